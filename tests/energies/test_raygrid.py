"""Tests of the ray grid (supportless.energies.raygrid) and its shared pieces."""

import numpy as np
import pytest
import trimesh
from meshes import box, cells_mesh

from supportless.energies import _grid_fast, _grid_numpy, _grid_reference
from supportless.energies._grid_common import (
    ENTERING,
    LEAVING,
    RISKY,
    grid_layout,
    inside_triangle,
    sweep_rays,
    triangle_edges,
)
from supportless.energies.raygrid import ray_grid
from supportless.energies.surface import orientation_sign, prepare, to_frame


def cat(*meshes):
    """``(V, F)`` pairs concatenated into one face list (no boolean)."""
    V = np.vstack([v for v, _ in meshes])
    offsets = np.cumsum([0] + [len(v) for v, _ in meshes[:-1]])
    return V, np.vstack([f + o for (_, f), o in zip(meshes, offsets)])


# ------------------------------------------------------------------ layout


def test_grid_layout_square_cells_centred_on_the_footprint():
    cell, nx, ny, u0, w0 = grid_layout(0.0, 4.0, 0.0, 1.0, 192)
    assert (cell, nx, ny, u0, w0) == (4.0 / 192, 192, 48, 0.0, 0.0)
    # the shorter side is rounded up to whole cells, the grid centred on it
    cell, nx, ny, u0, w0 = grid_layout(-1.0, 2.0, 0.0, 1.5, 3)
    assert (cell, nx, ny, u0, w0) == (1.0, 3, 2, -1.0, -0.25)
    # a side a hair over a whole number of cells is not given an extra cell
    assert grid_layout(0.0, 1.0, 0.0, 0.5 + 1e-12, 2)[1:3] == (2, 1)
    # no extent: no rays
    assert grid_layout(1.0, 1.0, 2.0, 2.0, 8)[1] == 0


# ------------------------------------------------------------ crossing rule


def _triangulated_square(n, flip_every=3):
    """Unit square split into n x n cells, two triangles each, alternating
    diagonals and, every ``flip_every``-th triangle, reversed winding."""
    V = np.array([(i / n, j / n) for j in range(n + 1) for i in range(n + 1)])
    F = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            F += [(a, b, c), (a, c, d)] if (i + j) % 2 else [(a, b, d), (b, c, d)]
    F = np.array(F)
    F[::flip_every] = F[::flip_every, ::-1]
    return V, F


def test_a_point_on_shared_edges_or_vertices_is_in_exactly_one_triangle():
    V, F = _triangulated_square(4)
    # every multiple of 1/8 strictly inside: the vertices, the midpoints of
    # all edges (diagonals included) and the cell centres
    pts = [(i / 8, j / 8) for i in range(1, 8) for j in range(1, 8)]
    ccw = [(V[b, 0] - V[a, 0]) * (V[c, 1] - V[a, 1]) - (V[b, 1] - V[a, 1]) * (V[c, 0] - V[a, 0]) > 0 for a, b, c in F]
    assert 0 < sum(ccw) < len(F)
    for px, py in pts:
        hits = [inside_triangle(triangle_edges(*V[a], *V[b], *V[c], o), px, py) for (a, b, c), o in zip(F, ccw)]
        assert sum(hits) == 1, (px, py)


def test_numpy_crossing_rule_is_the_kernels():
    V, F = _triangulated_square(4)
    rng = np.random.default_rng(0)
    P = np.concatenate([rng.integers(0, 9, (200, 2)) / 8, rng.random((200, 2))])
    for a, b, c in F:
        if (V[b, 0] - V[a, 0]) * (V[c, 1] - V[a, 1]) - (V[b, 1] - V[a, 1]) * (V[c, 0] - V[a, 0]) < 0:
            a, b = b, a  # numpy path: counter-clockwise a, b, c
        got = np.ones(len(P), bool)
        for s, t in ((a, b), (b, c), (c, a)):
            ex, ey = np.full(len(P), V[s, 0]), np.full(len(P), V[s, 1])
            got &= _grid_numpy._inside(_grid_numpy._edges(ex, ey, np.full(len(P), V[t, 0]),
                                                          np.full(len(P), V[t, 1])), P[:, 0], P[:, 1])
        want = [inside_triangle(triangle_edges(*V[a], *V[b], *V[c], True), x, y) for x, y in P]
        np.testing.assert_array_equal(got, want)


# ------------------------------------------------------------------- sweep


def brute_force_sweep(pix, z, code, zplate, npix, kmin=1):
    """Per-ray Python sweep: sort each ray's kept crossings by height (stable)
    and count layers; returns (length inside >= 2 layers, support column length)."""
    inter = sup = 0.0
    for q in range(npix):
        ks = [k for k in range(len(pix)) if pix[k] == q and code[k] >= 0]
        if len(ks) < kmin:
            continue
        ks.sort(key=lambda k: z[k])
        inside, below = 0, zplate
        for n, k in enumerate(ks):
            if inside >= 2:
                inter += z[k] - below
            if code[k] != LEAVING:
                lo = z[ks[n - 1]] if n else zplate
                if inside <= 0 and code[k] == RISKY and z[k] > lo:
                    sup += z[k] - lo
                inside += 1
            else:
                inside -= 1
            below = z[k]
    return inter, sup


@pytest.mark.parametrize("seed", range(4))
def test_sweep_rays_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    npix = 30
    pix, z, code = [], [], []
    for q in range(npix):
        for _ in range(rng.integers(0, 4)):  # material intervals on this ray, may overlap
            lo, hi = np.sort(rng.integers(0, 16, 2) / 4)  # quarter heights: ties happen
            pix += [q, q]
            z += [lo, hi]
            code += [rng.choice([ENTERING, RISKY]), LEAVING]
    order = rng.permutation(len(pix))
    pix = np.array(pix, np.int64)[order]
    z = np.array(z, np.float64)[order]
    code = np.array(code, np.int8)[order]
    code[rng.random(len(code)) < 0.1] = -1  # dropped crossings
    zplate = -0.5
    for kmin in (1, 2, 4):
        cnt = np.bincount(pix[code >= 0], minlength=npix)
        m = len(pix)
        work = np.empty(npix, np.int64), np.empty(m), np.empty(m, np.int8)
        got = sweep_rays(pix, z, code, m, cnt, npix, kmin, zplate, *work)
        want = brute_force_sweep(pix, z, code, zplate, npix, kmin)
        assert got == want
    assert want[0] > 0 and want[1] > 0


# ---------------------------------------------------------------- ray_grid


def overlapping_boxes():
    """Lower box [0,2]x[0,2]x[0,2] and upper box [1,3]x[0,2]x[1,3] in one face list.

    Overlap 1 x 2 x 1 = 2; the upper box's bottom over x in [2, 3] needs
    columns of length 1 (2 in all; over [1, 2] it lies inside the lower box).
    """
    return cat(box([0, 0, 0], [2, 2, 2]), box([1, 0, 1], [3, 2, 3]))


def test_ray_grid_both_columns_exact_on_a_grid_aligned_shape():
    # 192 cells over the 3 long footprint: cell edges on x = 1, 2 (exact
    # areas), and many ray centres on the faces' diagonals (ties)
    V, F = overlapping_boxes()
    V, F, up, _ = prepare(np.stack([V, V + [5.0, -1.0, 2.0]]), F, [0.0, 0.0, 1.0])
    tau = np.cos(np.pi / 4)
    for backend in ("fast", "numpy"):
        out = ray_grid(V, F, up, 192, tau, backend=backend)
        np.testing.assert_allclose(out, [[2.0, 2.0], [2.0, 2.0]], rtol=1e-12)
        assert ray_grid(V, F, up, 192, tau, backend=backend, support=False)[0, 0] == out[0, 0]
    # 2D: unit squares [0,2]x[0,2] and [1,3]x[1,3] overlap in a unit square;
    # the upper one's bottom over x in [2, 3] needs a column of length 1
    V2, F2 = cat(cells_mesh([(0, 0), (1, 0), (0, 1), (1, 1)]), cells_mesh([(1, 1), (2, 1), (1, 2), (2, 2)]))
    V2, F2, up2, _ = prepare(V2, F2, "y")
    for backend in ("fast", "numpy"):
        np.testing.assert_allclose(ray_grid(V2, F2, up2, 192, tau, backend=backend), [[1.0, 1.0]], rtol=1e-12)


def test_ray_grid_rejects_a_bad_resolution():
    V, F, up, _ = prepare(*box(), "z")
    with pytest.raises(ValueError, match="resolution"):
        ray_grid(V, F, up, 0, 0.5)


@pytest.fixture(scope="module")
def two_bunnies(shared_data):
    """Two overlapping copies of the bunny, in 4 random orientations: (P, n, 3), (f, 3)."""
    m = trimesh.load(shared_data / "bunny.obj", process=False)
    V, F = np.asarray(m.vertices), np.asarray(m.faces, np.int64)
    R = trimesh.transformations.rotation_matrix(0.9, [0.2, 1.0, 0.3])[:3, :3]
    V2, F2 = cat((V, F), (V @ R.T + 0.02 * np.ptp(V, axis=0), F))
    rng = np.random.default_rng(7)
    poses = [V2 @ trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3].T for _ in range(4)]
    return np.ascontiguousarray(np.stack(poses)), F2


def assert_fast_is_reference(V, F, up, resolution, tau):
    """The fast 3D kernel returns the reference kernel's bits; returns the reference (P, 2)."""
    ref = _grid_reference.grid_batch(to_frame(V, up), F, np.ascontiguousarray(orientation_sign(V, F)), resolution, tau)
    np.testing.assert_array_equal(_grid_fast.ray_grid3_fast(V, F, up, resolution, tau, True), ref)
    np.testing.assert_array_equal(_grid_fast.ray_grid3_fast(V, F, up, resolution, tau, False)[:, 0], ref[:, 0])
    return ref


@pytest.mark.parametrize("resolution", [1, 2, 3, 4, 5, 7, 8, 11, 64])
def test_fast_kernel_is_the_reference_where_rays_hit_edges(resolution):
    V, F = overlapping_boxes()
    V, F, up, _ = prepare(V, F, "z")
    assert_fast_is_reference(V, F, up, resolution, 0.5)


def test_fast_kernel_is_the_reference_on_a_symmetric_mesh():
    # a torus about the z axis: many ray centres within round-off of its edges
    t = trimesh.creation.torus(1.0, 0.3)
    V, F, up, _ = prepare(t.vertices, t.faces, "z")
    ref = assert_fast_is_reference(V, F, up, 192, 0.5)
    assert ref[0, 0] == 0.0 and ref[0, 1] > 0


@pytest.mark.parametrize("resolution", [48, 192])
def test_fast_kernel_is_bit_identical_to_the_reference(two_bunnies, resolution):
    V, F = two_bunnies
    up = np.array([0.0, 1.0, 0.0])
    tau = np.cos(np.pi / 4)
    ref = assert_fast_is_reference(V, F, up, resolution, tau)
    assert np.all(ref > 0)
    # the numpy path: same crossings, sums in another order
    np.testing.assert_allclose(ray_grid(V, F, up, resolution, tau, backend="numpy"), ref, rtol=1e-9)
