"""Tests for the reduced (skinning-subspace) ARAP energy."""

import igl
import igl.copyleft.tetgen
import numpy as np
import pytest
from meshes import box
from scipy.spatial.transform import Rotation

from supportless.energies.arap import (
    ArapData,
    _rotation_terms,
    arap_energy,
    arap_energy_direct,
    arap_precompute,
    element_edges,
)

# ---------------------------------------------------------------- fixtures


def _sigmoid_weights(x, joints, tau=0.15):
    """Smooth partition of unity along x with bone boundaries at ``joints``."""
    s = 1.0 / (1.0 + np.exp(-(x[:, None] - np.asarray(joints)[None, :]) / tau))
    cum = np.concatenate([np.ones((x.size, 1)), s, np.zeros((x.size, 1))], axis=1)
    return cum[:, :-1] - cum[:, 1:]


def _bar_tets(n_bones=3, max_vol=0.01):
    Vs, Fs = box([0, 0, 0], [n_bones, 1, 1])
    TV, TT, *_ = igl.copyleft.tetgen.tetrahedralize(Vs, Fs, flags=f"pq1.414a{max_vol}Q")
    W = _sigmoid_weights(TV[:, 0], np.arange(1, n_bones))
    return TV, TT, W


def _rectangle_tris(nx=24, ny=8, length=3.0, rng=None):
    x, y = np.meshgrid(np.linspace(0, length, nx + 1), np.linspace(0, 1, ny + 1), indexing="ij")
    V = np.stack([x.ravel(), y.ravel()], axis=1)
    if rng is not None:  # jitter interior vertices so cot weights vary
        interior = (V[:, 0] > 0) & (V[:, 0] < length) & (V[:, 1] > 0) & (V[:, 1] < 1)
        V[interior] += rng.uniform(-0.3, 0.3, (interior.sum(), 2)) * [length / nx, 1 / ny]
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    F = np.concatenate(
        [np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)]
    )
    return V, F


@pytest.fixture(scope="module")
def bar():
    return _bar_tets()


@pytest.fixture(scope="module")
def rect():
    V, F = _rectangle_tris(rng=np.random.default_rng(3))
    W = _sigmoid_weights(V[:, 0], [1.0, 2.0])
    return V, F, W


# ---------------------------------------------------------------- helpers


def _identity(m, d):
    X = np.zeros((m, d, d + 1))
    X[:, :, :d] = np.eye(d)
    return X


def _rot_about(R, p):
    """Affine (d, d+1) rotation ``R`` about point ``p``."""
    return np.concatenate([R, (p - R @ p)[:, None]], axis=1)


def _rot_z(theta, d):
    c, s = np.cos(theta), np.sin(theta)
    R = np.array([[c, -s], [s, c]])
    if d == 3:
        R = np.block([[R, np.zeros((2, 1))], [np.zeros((1, 2)), np.ones((1, 1))]])
    return R


def _bend(theta, m, d, joint_x=1.0):
    """Bones 1.. rigidly rotated by theta about z around the first joint."""
    X = _identity(m, d)
    p = np.full(d, 0.5)
    p[0] = joint_x
    X[1:] = _rot_about(_rot_z(theta, d), p)
    return X


def _skin(V, W, X):
    """Deformed vertices by plain LBS. X: (..., m, d, d+1) -> (..., t, d)."""
    Vh = np.concatenate([V, np.ones((V.shape[0], 1))], axis=1)
    per_bone = np.einsum("...jab,tb->...tja", X, Vh)
    return np.einsum("tj,...tja->...ta", W, per_bone)


def _random_affine(rng, P, m, d, noise=0.2, trans=1.0):
    R = Rotation.random(P * m, random_state=rng).as_matrix().reshape(P, m, 3, 3)[..., :d, :d]
    if d == 2:
        th = rng.uniform(-np.pi, np.pi, (P, m))
        R = np.stack(
            [np.stack([np.cos(th), -np.sin(th)], -1), np.stack([np.sin(th), np.cos(th)], -1)], -2
        )
    A = R + noise * rng.standard_normal((P, m, d, d))
    b = trans * rng.standard_normal((P, m, d, 1))
    return np.concatenate([A, b], axis=-1)


# ---------------------------------------------------------------- tests


@pytest.mark.parametrize("which", ["bar", "rect"])
def test_cotmatrix_entries_convention(which, bar, rect):
    """Assembling cotmatrix_entries with our edge order reproduces cotmatrix."""
    V, F = (bar[0], bar[1]) if which == "bar" else (rect[0], rect[1])
    C = igl.cotmatrix_entries(V, F)
    edges = element_edges(F.shape[1])
    I, J = F[:, edges[:, 0]].ravel(), F[:, edges[:, 1]].ravel()
    n = V.shape[0]
    L = np.zeros((n, n))
    np.add.at(L, (I, J), C.ravel())
    np.add.at(L, (J, I), C.ravel())
    L -= np.diag(L.sum(axis=1))
    assert np.allclose(L, igl.cotmatrix(V, F).toarray(), atol=1e-12)


@pytest.mark.parametrize("which", ["bar", "rect"])
def test_lbs_matrix_layout(which, bar, rect):
    V, _, W = bar if which == "bar" else rect
    d, m = V.shape[1], W.shape[1]
    X = _random_affine(np.random.default_rng(0), 1, m, d)[0]
    M = igl.lbs_matrix(V, W)
    T = np.swapaxes(X, -1, -2).reshape(m * (d + 1), d)
    assert np.allclose(M @ T, _skin(V, W, X))


def test_identity_and_rigid_motion_zero(bar):
    V, T, W = bar
    m = W.shape[1]
    data = arap_precompute(V, T, W, clusters=20, rng=0)
    assert isinstance(data, ArapData)
    bent = arap_energy(data, _bend(0.6, m, 3))
    assert bent > 0
    assert arap_energy(data, _identity(m, 3)) <= 1e-8 * bent
    rng = np.random.default_rng(1)
    for _ in range(5):
        R = Rotation.random(random_state=rng).as_matrix()
        b = rng.uniform(-5, 5, 3)
        X = np.broadcast_to(np.concatenate([R, b[:, None]], 1), (m, 3, 4))
        assert arap_energy(data, X) <= 1e-8 * bent
        assert arap_energy_direct(V, T, _skin(V, W, X)) <= 1e-8 * bent


def test_bend_positive_and_increasing(bar):
    V, T, W = bar
    m = W.shape[1]
    data = arap_precompute(V, T, W, rng=0)
    thetas = np.linspace(0.0, 1.2, 7)
    X = np.stack([_bend(t, m, 3) for t in thetas])
    E = arap_energy(data, X)
    assert E[0] <= 1e-10 * E[-1]
    assert np.all(E[1:] > 0)
    assert np.all(np.diff(E) > 0)


@pytest.mark.parametrize("which", ["bar", "rect"])
def test_reduced_equals_direct_per_element(which, bar, rect):
    V, F, W = bar if which == "bar" else rect
    d, m = V.shape[1], W.shape[1]
    data = arap_precompute(V, F, W, clusters=None)
    assert data.n_clusters == F.shape[0]
    X = _random_affine(np.random.default_rng(2), 4, m, d)
    X[0] = _bend(0.8, m, d)
    E = arap_energy(data, X)
    E_direct = arap_energy_direct(V, F, _skin(V, W, X))
    assert np.all(E > 0)
    assert np.allclose(E, E_direct, rtol=1e-8, atol=0)


def test_clusters_upper_bound_and_labels(bar):
    """Sharing rotations can only increase the energy; clusters are configurable."""
    V, T, W = bar
    m = W.shape[1]
    X = _random_affine(np.random.default_rng(4), 6, m, 3, noise=0.1)
    full = arap_energy(arap_precompute(V, T, W, clusters=None), X)
    coarse = arap_precompute(V, T, W, clusters=10, rng=np.random.default_rng(5))
    assert 1 <= coarse.n_clusters <= 10
    assert np.all(arap_energy(coarse, X) >= full * (1 - 1e-10))
    # default: min(100, #elements) clusters, reproducible for a given seed
    d1 = arap_precompute(V, T, W, rng=7)
    d2 = arap_precompute(V, T, W, rng=7)
    assert d1.n_clusters <= 100
    assert np.array_equal(d1.labels, d2.labels)
    # explicit labels: one cluster for everything
    one = arap_precompute(V, T, W, clusters=np.zeros(T.shape[0], int))
    assert one.n_clusters == 1
    # more clusters than elements -> one per element
    tiny = arap_precompute(V, T[:5], W, clusters=100)
    assert tiny.n_clusters == 5


@pytest.mark.parametrize("which", ["bar", "rect"])
def test_uniform_scaling_analytic(which, bar, rect):
    """A uniform stretch by s gives 1/2 * volume * d * (s - 1)^2."""
    V, F, W = bar if which == "bar" else rect
    d, m = V.shape[1], W.shape[1]
    measure = 3.0  # bar 3x1x1, rectangle 3x1
    data = arap_precompute(V, F, W, clusters=5, rng=0)
    for s in (0.7, 1.3):
        X = _identity(m, d)
        X[:, :, :d] *= s
        expected = 0.5 * measure * d * (s - 1) ** 2
        assert arap_energy(data, X) == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("which", ["bar", "rect"])
def test_scale_model(which, bar, rect):
    V, F, W = bar if which == "bar" else rect
    d, m = V.shape[1], W.shape[1]
    X = _random_affine(np.random.default_rng(6), 3, m, d)
    E1 = arap_energy(arap_precompute(V, F, W, clusters=30, rng=1), X)
    for s in (0.5, 2.5):
        Xs = X.copy()
        Xs[..., d] *= s
        Es = arap_energy(arap_precompute(s * V, F, W, clusters=30, rng=1), Xs)
        assert np.allclose(Es, s**d * E1, rtol=1e-8)


@pytest.mark.parametrize("which", ["bar", "rect"])
def test_batch_equals_single(which, bar, rect):
    V, F, W = bar if which == "bar" else rect
    d, m = V.shape[1], W.shape[1]
    data = arap_precompute(V, F, W, clusters=25, rng=0)
    X = _random_affine(np.random.default_rng(8), 7, m, d)
    E = arap_energy(data, X)
    assert E.shape == (7,)
    singles = [arap_energy(data, x) for x in X]
    assert all(isinstance(e, float) for e in singles)
    assert np.allclose(E, singles, rtol=1e-12, atol=0)
    Ed = arap_energy_direct(V, F, _skin(V, W, X))
    assert Ed.shape == (7,)
    assert isinstance(arap_energy_direct(V, F, _skin(V, W, X[0])), float)


def test_2d_rectangle(rect):
    V, F, W = rect
    m = W.shape[1]
    data = arap_precompute(V, F, W, clusters=50, rng=0)
    assert data.dim == 2 and data.cov.shape == (m * 3, data.n_clusters * 2)
    thetas = np.linspace(0, 1.0, 5)
    E = arap_energy(data, np.stack([_bend(t, m, 2) for t in thetas]))
    assert E[0] <= 1e-10 * E[-1]
    assert np.all(np.diff(E) > 0)
    th = 0.9
    X = np.broadcast_to(_rot_about(_rot_z(th, 2), np.array([4.0, -2.0])), (m, 2, 3))
    assert arap_energy(data, X) <= 1e-8 * E[-1]


def test_bad_shapes(bar):
    V, T, W = bar
    data = arap_precompute(V, T, W, clusters=4, rng=0)
    with pytest.raises(ValueError):
        arap_energy(data, np.zeros((2, W.shape[1] + 1, 3, 4)))
    with pytest.raises(ValueError):
        arap_precompute(V, T[:, :3], W)


@pytest.mark.parametrize("seed", [0, 1, 7])
def test_the_fast_kmeans_seeds_are_scipys(seed):
    """The running-minimum k-means++ picks scipy's seeds from the same generator: the same clusters, faster."""
    import warnings

    from scipy.cluster.vq import kmeans2

    from supportless.energies.arap import _kmeans_pp

    data = np.random.default_rng(seed).dirichlet(np.full(9, 0.3), size=700)  # mean weight vectors
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        codes, labels = kmeans2(data, 40, minit="++", rng=np.random.default_rng(seed))
        fast_codes, fast_labels = kmeans2(data, _kmeans_pp(data, 40, np.random.default_rng(seed)), minit="matrix")
    np.testing.assert_array_equal(fast_labels, labels)
    np.testing.assert_array_equal(fast_codes, codes)


def _signed_nuclear_norm(S):
    """``max_R tr(R^T S)`` over rotations by the SVD: (..., d, d) -> (...)."""
    sig = np.linalg.svd(S, compute_uv=False)
    sign = np.where(np.linalg.det(S) < 0.0, -1.0, 1.0)
    return sig[..., :-1].sum(axis=-1) + sign * sig[..., -1]


@pytest.mark.parametrize("kind", ["gaussian", "scaled rotations", "near rotations", "rank one", "rank two",
                                  "reflections", "near reflections", "2d"])
def test_the_rotation_term_is_the_signed_sum_of_singular_values(kind):
    """The fast per-cluster kernel against the SVD, on general blocks and on the degenerate ones
    (multiple roots of its quartic) where it hands over to Jacobi."""
    rng = np.random.default_rng(3)
    P, g = 40, 25
    R = Rotation.random(P * g, random_state=4).as_matrix().reshape(P, g, 3, 3)
    S = {"gaussian": lambda: rng.normal(size=(P, g, 3, 3)),
         "scaled rotations": lambda: R * rng.uniform(0.01, 100.0, (P, g, 1, 1)),
         "near rotations": lambda: R + 1e-7 * rng.normal(size=R.shape),
         "rank one": lambda: rng.normal(size=(P, g, 3, 1)) * rng.normal(size=(P, g, 1, 3)),
         "rank two": lambda: R @ np.diag([2.0, 1.0, 0.0]),
         "reflections": lambda: R @ np.diag([1.0, 1.0, -1.0]),
         "near reflections": lambda: R @ np.diag([1.0, 1.0, -1.0]) + 1e-5 * rng.normal(size=R.shape),
         "2d": lambda: rng.normal(size=(P, g, 2, 2))}[kind]()
    got = _rotation_terms(np.ascontiguousarray(np.swapaxes(S, 1, 2)))  # the kernel's (P, d, g, d) layout
    scale = np.linalg.norm(S, axis=(2, 3)).sum(axis=1)
    np.testing.assert_allclose(got / scale, _signed_nuclear_norm(S).sum(axis=1) / scale, rtol=0, atol=1e-13)
