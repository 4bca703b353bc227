"""As-rigid-as-possible (ARAP) distortion energy in the skinning subspace.

The energy measured on the rig's volumetric mesh (tets in 3D, triangles in
2D) is

    E(V') = 1/2 sum_e sum_{(i,j) in e} c_ije ||(v'_i - v'_j) - R_e (v_i - v_j)||^2

with cotangent weights ``c_ije`` (libigl convention: ``l_kl cot(theta_kl) / 6``
for tets, ``cot(alpha_k) / 2`` for triangles, i.e. the off-diagonal entries of
``igl.cotmatrix``) and best-fit rotations ``R_e`` in SO(d).

Because the deformed vertices are linear in the stacked bone transforms,
``V' = M T`` with ``M = igl.lbs_matrix(V, W)``, the energy can be evaluated in
the reduced space (Jacobson et al. 2012, "Fast automatic skinning
transformations").  Expanding the square and using ``||R e|| = ||e||``:

    E(T) = 1/2 tr(T^T Q T) - sum_g tr(R_g^T S_g(T)) + c0,

    Q   = -M^T L M                      (reduced quadratic term, L = cotmatrix)
    S_g = T^T K_g                       (covariance of rotation cluster g)
    K_g = sum_{e in g} sum_{(i,j) in e} c_ije (M_i - M_j)^T (v_i - v_j)^T
    c0  = 1/2 sum_e sum_{(i,j)} c_ije ||v_i - v_j||^2 = -1/2 tr(V^T L V).

Elements are grouped into ``g`` clusters sharing one rotation.  For the optimal
rotation ``R_g = U diag(1, .., det(U V^T)) V^T`` (from the SVD
``S_g = U Sigma V^T``) one has ``tr(R_g^T S_g) = sigma_1 + .. + sigma_{d-1} +
sign(det S_g) sigma_d``, so only singular values and a determinant sign are
needed.  One evaluation costs ``O(m^2 + g m)`` independently of the number of
elements.

Transform convention (project wide): ``transforms[..., j, :, :d]`` is the
linear part ``A_j`` and ``transforms[..., j, :, d]`` the translation ``b_j``
of bone ``j``; ``v'_i = sum_j w_ij (A_j v_i + b_j)``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import igl
import numpy as np
import scipy.sparse as sp
from numba import njit
from scipy.cluster.vq import kmeans2
from scipy.spatial.distance import cdist

from ..base.threads import one_blas_thread, over

__all__ = [
    "ArapData",
    "arap_precompute",
    "arap_energy",
    "arap_energy_direct",
    "element_edges",
]

# Local edge ordering of the columns of igl.cotmatrix_entries.
_TRI_EDGES = np.array([[1, 2], [2, 0], [0, 1]], dtype=np.int64)
_TET_EDGES = np.array([[1, 2], [2, 0], [0, 1], [3, 0], [3, 1], [3, 2]], dtype=np.int64)


def element_edges(simplex_size: int) -> np.ndarray:
    """Local edge list of a simplex, in ``igl.cotmatrix_entries`` column order.

    Parameters
    ----------
    simplex_size : int
        3 for triangles, 4 for tetrahedra.

    Returns
    -------
    edges : (3, 2) or (6, 2) int64
        Local vertex indices ``(i, j)`` of each unordered edge.
    """
    if simplex_size == 3:
        return _TRI_EDGES.copy()
    if simplex_size == 4:
        return _TET_EDGES.copy()
    raise ValueError(f"elements must be triangles or tets, got {simplex_size} vertices")


@dataclass(frozen=True)
class ArapData:
    """Precomputed reduced ARAP operators for one rig.

    Attributes
    ----------
    quad : (m*(d+1), m*(d+1)) float64
        Reduced quadratic term ``Q = -M^T L M`` (positive semi-definite).
    cov : (m*(d+1), g*d) float64
        Reduced covariance operators ``[K_1 | ... | K_g]``; the covariance of
        cluster ``g`` is ``S_g = T^T K_g`` (d x d).
    const : float
        Constant term ``1/2 sum c_ije ||v_i - v_j||^2``.
    labels : (k,) int64
        Rotation cluster of each element, in ``0 .. n_clusters-1``.
    n_clusters : int
        Number ``g`` of rotation clusters (all non-empty).
    n_bones : int
        Number ``m`` of bones.
    dim : int
        Spatial dimension ``d`` (2 or 3).
    """

    quad: np.ndarray
    cov: np.ndarray
    const: float
    labels: np.ndarray
    n_clusters: int
    n_bones: int
    dim: int


def _cluster_elements(mean_weights: np.ndarray, clusters, rng) -> np.ndarray:
    """Group elements by similar mean skinning weights.

    Parameters
    ----------
    mean_weights : (k, m) float64
        Per-element mean of its vertices' skinning weights.
    clusters : None, int or (k,) int array
        ``None``: one cluster per element; int: number of k-means clusters
        (capped at ``k``); array: explicit cluster labels.
    rng : numpy.random.Generator

    Returns
    -------
    labels : (k,) int64
        Compact labels in ``0 .. g-1``, every cluster non-empty.
    """
    k = mean_weights.shape[0]
    if clusters is None:
        return np.arange(k, dtype=np.int64)
    if not np.isscalar(clusters):
        labels = np.asarray(clusters)
        if labels.shape != (k,):
            raise ValueError(f"cluster labels must have shape ({k},), got {labels.shape}")
        return np.unique(labels, return_inverse=True)[1].astype(np.int64)
    g = int(clusters)
    if g < 1:
        raise ValueError("clusters must be >= 1")
    if g >= k:
        return np.arange(k, dtype=np.int64)
    uniq, inverse = np.unique(mean_weights, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    if uniq.shape[0] <= g:
        # Fewer distinct weight vectors than clusters: group exactly.
        return inverse.astype(np.int64)
    with warnings.catch_warnings():
        # Empty clusters are harmless: labels are compacted below.
        warnings.simplefilter("ignore")
        _, labels = kmeans2(mean_weights, _kmeans_pp(mean_weights, g, rng), minit="matrix")
    return np.unique(labels, return_inverse=True)[1].astype(np.int64)


def _kmeans_pp(data, g, rng):
    """k-means++ seeds, as ``scipy.cluster.vq.kmeans2(minit="++")`` picks them, in O(k g m) instead of O(k g² m).

    Each new seed's squared distances are folded into a running minimum
    instead of measuring every seed again: the same numbers, so the same seeds
    from the same ``rng`` (checked in the tests); with many bones (m = 68, 28k
    tets) this took 10 s of a 32 s search.

    Parameters
    ----------
    data : (k, m) float64
    g : int
        Number of seeds, ``g <= k``.
    rng : numpy.random.Generator

    Returns
    -------
    seeds : (g, m) float64
    """
    seeds = np.empty((g, data.shape[1]))
    seeds[0] = data[rng.integers(0, data.shape[0], dtype=np.int64)]
    d2 = None
    for i in range(1, g):
        new = cdist(seeds[i - 1:i], data, metric="sqeuclidean")[0]
        d2 = new if d2 is None else np.minimum(d2, new)
        cumulative = (d2 / d2.sum()).cumsum()
        seeds[i] = data[int(np.searchsorted(cumulative, rng.uniform()))]
    return seeds


def arap_precompute(vertices, elements, weights, clusters=100, rng=None) -> ArapData:
    """Precompute the reduced ARAP operators of a rig.

    Parameters
    ----------
    vertices : (t, d) float64
        Rest positions of the volumetric mesh vertices, ``d`` in {2, 3}.
    elements : (k, d+1) int
        Tetrahedra (3D) or triangles (2D) indexing ``vertices``.
    weights : (t, m) float64
        Skinning weights of the mesh vertices (rows should sum to 1 for the
        energy to be invariant to global translations).
    clusters : None, int or (k,) int array, optional
        Rotation clusters. An int asks for that many k-means clusters of the
        per-element mean weight vectors (default 100, capped at ``k``);
        ``None`` uses one rotation per element (the exact energy); an array
        gives explicit per-element labels.
    rng : numpy.random.Generator or int or None, optional
        Randomness for the k-means initialisation. An int is used as a seed;
        ``None`` means seed 0 so precomputation is reproducible.

    Returns
    -------
    data : ArapData
        Reduced operators; evaluation with :func:`arap_energy`.
    """
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    E = np.ascontiguousarray(elements, dtype=np.int64)
    W = np.ascontiguousarray(weights, dtype=np.float64)
    n, d = V.shape
    if d not in (2, 3):
        raise ValueError("vertices must be 2D or 3D")
    if E.ndim != 2 or E.shape[1] != d + 1:
        raise ValueError(f"elements must have shape (k, {d + 1})")
    if W.shape[0] != n:
        raise ValueError("weights must have one row per vertex")
    m = W.shape[1]
    if rng is None:
        rng = 0
    rng = np.random.default_rng(rng)

    # Skinning matrix: V' = M T, columns j*(d+1) + c, T = stacked transforms[j].T.
    M = np.asarray(igl.lbs_matrix(V, W), dtype=np.float64)
    L = igl.cotmatrix(V, E)
    quad = -(M.T @ (L @ M))
    quad = 0.5 * (quad + quad.T)

    C = np.asarray(igl.cotmatrix_entries(V, E), dtype=np.float64)  # (k, nE)
    edges = element_edges(d + 1)
    I = E[:, edges[:, 0]]  # (k, nE)
    J = E[:, edges[:, 1]]
    rest_edges = V[I] - V[J]  # (k, nE, d)
    const = 0.5 * float(np.einsum("ke,ked,ked->", C, rest_edges, rest_edges))

    labels = _cluster_elements(W[E].mean(axis=1), clusters, rng)
    g = int(labels.max()) + 1

    # G (n, g*d): G[i, g*d + b] = sum over cluster-g edges (i, j) of c (v_i - v_j)_b
    # (and minus for j), so that K = M^T G stacks the K_g.
    ce = C[:, :, None] * rest_edges  # (k, nE, d)
    cols = labels[:, None, None] * d + np.arange(d)[None, None, :]  # (k, 1, d)
    cols = np.broadcast_to(cols, ce.shape)
    rows_i = np.broadcast_to(I[:, :, None], ce.shape)
    rows_j = np.broadcast_to(J[:, :, None], ce.shape)
    G = sp.coo_matrix(
        (
            np.concatenate([ce.ravel(), -ce.ravel()]),
            (
                np.concatenate([rows_i.ravel(), rows_j.ravel()]),
                np.concatenate([cols.ravel(), cols.ravel()]),
            ),
        ),
        shape=(n, g * d),
    ).tocsr()
    cov = np.ascontiguousarray((G.T @ M).T)  # (m*(d+1), g*d)

    return ArapData(
        quad=np.ascontiguousarray(quad),
        cov=cov,
        const=const,
        labels=labels,
        n_clusters=g,
        n_bones=m,
        dim=d,
    )


def _stack_transforms(transforms: np.ndarray, m: int, d: int) -> np.ndarray:
    """(P, m, d, d+1) bone transforms -> (P, m*(d+1), d) ``T`` for ``V' = M T``."""
    P = transforms.shape[0]
    return np.ascontiguousarray(np.swapaxes(transforms, -1, -2)).reshape(P, m * (d + 1), d)


@njit(cache=True)
def _rotation_term_jacobi(S, g, det):
    """:func:`_rotation_term` of a 3 x 3 block by one-sided Jacobi (Hestenes) orthogonalisation.

    The singular values of the columns come to high relative accuracy; the
    sign of the smallest is that of ``det`` (``det S_g``). Slower (an
    allocation and a few sweeps per block), robust where the fast form is not.
    """
    d = 3
    a = np.empty((3, 3))
    for r in range(d):
        for c in range(d):
            a[r, c] = S[r, g, c]
    for sweep in range(30):
        rotated = False
        for p in range(d - 1):
            for q in range(p + 1, d):
                alpha = 0.0
                beta = 0.0
                gamma = 0.0
                for r in range(d):
                    alpha += a[r, p] * a[r, p]
                    beta += a[r, q] * a[r, q]
                    gamma += a[r, p] * a[r, q]
                if gamma == 0.0 or abs(gamma) <= 1e-15 * np.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = (1.0 if zeta >= 0.0 else -1.0) / (abs(zeta) + np.sqrt(1.0 + zeta * zeta))
                c = 1.0 / np.sqrt(1.0 + t * t)
                s = c * t
                for r in range(d):
                    ap = a[r, p]
                    aq = a[r, q]
                    a[r, p] = c * ap - s * aq
                    a[r, q] = s * ap + c * aq
        if not rotated:
            break
    total = 0.0
    smallest = np.inf
    for c in range(d):
        n2 = 0.0
        for r in range(d):
            n2 += a[r, c] * a[r, c]
        sv = np.sqrt(n2)
        total += sv
        smallest = min(smallest, sv)
    if det < 0.0:
        total -= 2.0 * smallest
    return total


@njit(cache=True, inline="always")
def _rotation_term(S, g, d):
    """``max_R tr(R^T S_g)`` over SO(d) for the d x d block ``S_g = S[:, g, :]``.

    In 2D the closed form ``hypot(s00 + s11, s10 - s01)``. In 3D the largest
    eigenvalue of Horn's traceless symmetric 4 x 4 quaternion matrix of
    ``S`` (whose eigenvalues are ``+-s1 +- s2 +- s3`` with an even number of
    minus signs, ``s`` the singular values signed by ``det S``), found as the
    largest root of its characteristic polynomial
    ``x^4 - 2 |S|_F^2 x^2 - 8 det(S) x + det(N)`` by Newton's method from
    ``sqrt(3) |S|_F``: above the largest root a polynomial with only real
    roots is increasing and convex, so the iterates decrease to it
    monotonically (and a near-rotation block, whose singular values are
    equal, starts at its root). Where that root is (nearly) multiple, which
    Newton's method finds only to about the square root of the rounding
    (blocks of rank one, or reflections with equal singular values, never
    met in a search), the block is left to :func:`_rotation_term_jacobi`.
    """
    if d == 2:
        return np.hypot(S[0, g, 0] + S[1, g, 1], S[1, g, 0] - S[0, g, 1])
    sxx, sxy, sxz = S[0, g, 0], S[0, g, 1], S[0, g, 2]
    syx, syy, syz = S[1, g, 0], S[1, g, 1], S[1, g, 2]
    szx, szy, szz = S[2, g, 0], S[2, g, 1], S[2, g, 2]
    f2 = sxx * sxx + sxy * sxy + sxz * sxz + syx * syx + syy * syy + syz * syz + szx * szx + szy * szy + szz * szz
    if f2 == 0.0:
        return 0.0
    det = sxx * (syy * szz - syz * szy) - sxy * (syx * szz - syz * szx) + sxz * (syx * szy - syy * szx)
    # Horn's matrix N (symmetric, traceless)
    a00 = sxx + syy + szz
    a01 = syz - szy
    a02 = szx - sxz
    a03 = sxy - syx
    a11 = sxx - syy - szz
    a12 = sxy + syx
    a13 = szx + sxz
    a22 = syy - sxx - szz
    a23 = syz + szy
    a33 = szz - sxx - syy
    # det(N) by 2 x 2 minors of the first two and the last two rows
    m01 = a00 * a11 - a01 * a01
    m02 = a00 * a12 - a02 * a01
    m03 = a00 * a13 - a03 * a01
    m12 = a01 * a12 - a02 * a11
    m13 = a01 * a13 - a03 * a11
    m23 = a02 * a13 - a03 * a12
    n01 = a02 * a13 - a12 * a03
    n02 = a02 * a23 - a22 * a03
    n03 = a02 * a33 - a23 * a03
    n12 = a12 * a23 - a22 * a13
    n13 = a12 * a33 - a23 * a13
    n23 = a22 * a33 - a23 * a23
    c0 = m01 * n23 - m02 * n13 + m03 * n12 + m12 * n03 - m13 * n02 + m23 * n01
    c1 = -8.0 * det
    c2 = -2.0 * f2
    x = np.sqrt(3.0 * f2)
    for _ in range(60):
        x2 = x * x
        p = (x2 + c2) * x2 + c1 * x + c0
        dp = (4.0 * x2 + 2.0 * c2) * x + c1
        if not (p > 0.0 and dp > 0.0):  # at the root (to rounding)
            break
        step = p / dp
        x -= step
        if step <= 1e-15 * x:
            break
    x2 = x * x
    if (4.0 * x2 + 2.0 * c2) * x + c1 < 1e-2 * x2 * x:  # p'(x) = prod(x - other roots): one is within ~x/10
        return _rotation_term_jacobi(S, g, det)
    return x


def _rotation_terms(S):
    """Sum over clusters of :func:`_rotation_term`; ``S`` is (P, d, g, d) (block ``g`` of pose ``p``: ``S[p, :, g]``)."""
    out = np.zeros(S.shape[0])
    over(_rotation_terms_of, S.shape[0], S, out)
    return out


@njit(cache=True, nogil=True)
def _rotation_terms_of(S, out, lo, hi):
    """Fill ``out`` (P,) at the poses ``lo:hi`` (see :func:`_rotation_terms`)."""
    g, d = S.shape[2], S.shape[1]
    for p in range(lo, hi):
        t = 0.0
        for k in range(g):
            t += _rotation_term(S[p], k, d)
        out[p] = t


def arap_energy(data: ArapData, transforms, backend="fast"):
    """Reduced ARAP energy of one or many poses.

    Parameters
    ----------
    data : ArapData
        From :func:`arap_precompute`.
    transforms : (P, m, d, d+1) or (m, d, d+1) float64
        Bone transforms (linear part ``[..., :d]``, translation ``[..., d]``).
    backend : {"fast", "numpy"}
        How the per-cluster rotation terms are found: ``fast`` by a numba
        kernel (Horn's quaternion matrix, :func:`_rotation_term`), ``numpy``
        by ``numpy.linalg.svd`` (agree to ~1e-12 relative).

    Returns
    -------
    energy : (P,) float64 or float
        ARAP energy per pose (a float for a single pose).

    Notes
    -----
    The true energy is a sum of squares, hence >= 0, but the reduced form is
    a difference of terms of similar size (quadratic term + constant minus the
    rotation term). For (near-)rigid poses the result can come out as a tiny
    negative number from round-off; it is therefore clamped at 0.
    """
    if backend not in ("fast", "numpy"):
        raise ValueError(f"backend must be 'fast' or 'numpy', not {backend!r}")
    X = np.asarray(transforms, dtype=np.float64)
    single = X.ndim == 3
    if single:
        X = X[None]
    m, d = data.n_bones, data.dim
    if X.shape[1:] != (m, d, d + 1):
        raise ValueError(f"transforms must have shape (P, {m}, {d}, {d + 1}), got {X.shape}")
    P = X.shape[0]
    g = data.n_clusters

    T = _stack_transforms(X, m, d)  # (P, n_dof, d)
    rows = np.ascontiguousarray(np.swapaxes(T, 1, 2)).reshape(P * d, -1)  # T^T of every pose, stacked
    # one product for every pose, not one per pose (which reads the whole operator again for 3 rows); on one
    # BLAS thread (:func:`~supportless.base.threads.one_blas_thread`)
    with one_blas_thread():
        quad = 0.5 * np.einsum("rk,rk->r", rows, rows @ data.quad).reshape(P, d).sum(axis=1)
        # cluster covariances S_g = T^T K_g: (P, d, g*d) -> (P, d, g, d), block g of pose p is S[p, :, g]
        S = (rows @ data.cov).reshape(P, d, g, d)
    if backend == "numpy":
        S = S.transpose(0, 2, 1, 3)  # (P, g, d, d)
        sig = np.linalg.svd(S, compute_uv=False)  # (P, g, d), descending
        sign = np.where(np.linalg.det(S) < 0.0, -1.0, 1.0)
        rot = (sig[..., :-1].sum(axis=-1) + sign * sig[..., -1]).sum(axis=-1)  # sum_g max_R tr(R^T S_g)
    else:
        rot = _rotation_terms(S)
    energy = quad - rot + data.const
    energy = np.maximum(energy, 0.0)
    return float(energy[0]) if single else energy


def _cot_entries_direct(rest: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """Cotangent weights per element edge, computed from geometry.

    Parameters
    ----------
    rest : (t, d) float64
    elements : (k, d+1) int64

    Returns
    -------
    c : (k, nE) float64
        For triangles ``cot(angle opposite the edge) / 2``, for tets
        ``l_kl cot(theta_kl) / 6`` with ``kl`` the opposite edge and
        ``theta_kl`` the interior dihedral angle there. Edge order as in
        :func:`element_edges`.
    """
    d = rest.shape[1]
    edges = element_edges(d + 1)
    X = rest[elements]  # (k, d+1, d)
    out = np.empty((elements.shape[0], edges.shape[0]))
    for col, (i, j) in enumerate(edges):
        others = [v for v in range(d + 1) if v not in (i, j)]
        if d == 2:
            (o,) = others
            a = X[:, i] - X[:, o]
            b = X[:, j] - X[:, o]
            cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
            out[:, col] = 0.5 * np.einsum("kd,kd->k", a, b) / np.abs(cross)
        else:
            p, q = others
            t = X[:, q] - X[:, p]
            length = np.linalg.norm(t, axis=1)
            t = t / length[:, None]
            u = X[:, i] - X[:, p]
            w = X[:, j] - X[:, p]
            u = u - np.einsum("kd,kd->k", u, t)[:, None] * t
            w = w - np.einsum("kd,kd->k", w, t)[:, None] * t
            cot = np.einsum("kd,kd->k", u, w) / np.linalg.norm(np.cross(u, w), axis=1)
            out[:, col] = length * cot / 6.0
    return out


def arap_energy_direct(rest_vertices, elements, deformed_vertices):
    """Per-element ARAP energy computed directly on deformed vertices.

    Reference implementation independent of the reduced operators: cotangent
    weights from element geometry, one best-fit rotation per element from a
    full SVD (sign fixed so ``det R = +1``) and the explicit sum of squared
    residuals.

    Parameters
    ----------
    rest_vertices : (t, d) float64
        Rest positions, ``d`` in {2, 3}.
    elements : (k, d+1) int
        Tets (3D) or triangles (2D).
    deformed_vertices : (t, d) or (P, t, d) float64
        Deformed positions of the same vertices.

    Returns
    -------
    energy : float or (P,) float64
        ``1/2 sum_e sum_(i,j) c_ije ||(v'_i - v'_j) - R_e (v_i - v_j)||^2``.
    """
    V = np.asarray(rest_vertices, dtype=np.float64)
    E = np.asarray(elements, dtype=np.int64)
    U = np.asarray(deformed_vertices, dtype=np.float64)
    single = U.ndim == 2
    if single:
        U = U[None]
    d = V.shape[1]
    edges = element_edges(d + 1)
    c = _cot_entries_direct(V, E)  # (k, nE)
    I = E[:, edges[:, 0]]
    J = E[:, edges[:, 1]]
    e = V[I] - V[J]  # (k, nE, d)
    ep = U[:, I] - U[:, J]  # (P, k, nE, d)
    S = np.einsum("ke,pkea,keb->pkab", c, ep, e)  # (P, k, d, d)
    Us, _, Vt = np.linalg.svd(S)
    D = np.ones(S.shape[:-1])
    D[..., -1] = np.sign(np.linalg.det(Us @ Vt))
    R = (Us * D[..., None, :]) @ Vt  # (P, k, d, d)
    res = ep - np.einsum("pkab,keb->pkea", R, e)
    energy = 0.5 * np.einsum("ke,pkea,pkea->p", c, res, res)
    return float(energy[0]) if single else energy
