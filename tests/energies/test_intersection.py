"""Tests for the ray-cast self-intersection volume."""

import numpy as np
import pytest
import trimesh

from supportless.energies.intersection import DEFAULT_RESOLUTION, self_intersection_volume

UP = np.array([0.0, 0.0, 1.0])

#: Tolerance of the cases the grid measures exactly: axis-aligned overlaps
#: whose sides lie on cell edges (error 0.0 but for round-off).
EXACT = 1e-9

# The other cases measure an approximation.  Grid error, first order: a cell
# cut by the outline of the overlap's footprint is counted whole or not at
# all, so |error| <= cell / 2 * outline length * overlap height, with cell =
# (longer footprint side) / resolution (in 2D: cell * height).  Along straight
# sides the errors of the cut cells mostly cancel, so measured errors are far
# below the bound.


def cat(*meshes):
    """Concatenate trimesh meshes into one face list (no boolean)."""
    V, F, o = [], [], 0
    for m in meshes:
        V.append(np.asarray(m.vertices, float))
        F.append(np.asarray(m.faces, np.int64) + o)
        o += len(m.vertices)
    return np.vstack(V), np.vstack(F)


def exact_overlap(a, b):
    """Independent reference: volume of the boolean intersection (manifold)."""
    return trimesh.boolean.intersection([a, b], engine="manifold").volume


def body_and_arm(angle_deg):
    """Box body with a box limb hinged at its side, swung ``angle`` into it."""
    body = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 3]])
    limb = trimesh.creation.box(bounds=[[0, 0.2, -0.3], [2, 0.8, 0.3]])
    limb.apply_transform(trimesh.transformations.rotation_matrix(np.deg2rad(angle_deg), [0, 1, 0]))
    limb.apply_translation([1.0, 0.0, 2.5])
    return body, limb


def squares_2d(offsets_and_sizes):
    """2D mesh of several (possibly overlapping) axis-aligned rectangles."""
    V, F = [], []
    for (x, y), (w, h) in offsets_and_sizes:
        o = len(V)
        V += [(x, y), (x + w, y), (x + w, y + h), (x, y + h)]
        F += [(o, o + 1, o + 2), (o, o + 2, o + 3)]
    return np.array(V, float), np.array(F, np.int64)


def test_default_resolution_documented():
    assert DEFAULT_RESOLUTION == 192
    assert "192" in self_intersection_volume.__doc__


def test_two_axis_aligned_boxes_exact():
    a = trimesh.creation.box(bounds=[[0, 0, 0], [2, 1, 1]])
    b = trimesh.creation.box(bounds=[[1.5, 0.25, 0.5], [3, 2, 2]])
    V, F = cat(a, b)
    # overlap 0.5 x 0.75 x 0.5; footprint 3 x 2 in cells of 1/64: exact
    assert self_intersection_volume(V, F, UP) == pytest.approx(0.1875, rel=EXACT)
    # inverted winding of the whole mesh
    assert self_intersection_volume(V, F[:, ::-1], UP) == pytest.approx(0.1875, rel=EXACT)
    # the union (one clean surface) has no self-intersection
    u = trimesh.boolean.union([a, b], engine="manifold")
    assert self_intersection_volume(u.vertices, u.faces, UP) == 0.0


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_two_rotated_boxes_match_boolean(seed):
    rng = np.random.default_rng(seed)
    a = trimesh.creation.box(extents=[2.0, 1.0, 1.5])
    b = trimesh.creation.box(extents=[1.0, 2.0, 1.0])
    b.apply_translation(rng.uniform(-0.6, 0.6, 3))
    T = trimesh.transformations.random_rotation_matrix(rng.random(3))
    a.apply_transform(T)
    b.apply_transform(T)
    ref = exact_overlap(a, b)
    assert ref > 0.1
    V, F = cat(a, b)
    up = rng.normal(size=3)
    # overlap <= 1 x 1 x 1 seen from anywhere (outline <= 6, height <= 1.7),
    # cell <= 3.2 / 192: bound 0.07 (loose against ref > 0.1); measured <= 3e-5
    assert self_intersection_volume(V, F, up) == pytest.approx(ref, rel=0.02)


def test_two_spheres_and_convergence():
    s1 = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    s2 = s1.copy()
    s2.apply_translation([0.8, 0.3, 0.2])
    ref = exact_overlap(s1, s2)
    V, F = cat(s1, s2)
    vals = [self_intersection_volume(V, F, UP, resolution=r) for r in (16, 32, 64, 128, 256)]
    # the lens-shaped overlap (1.6) thins to nothing at its outline, so the
    # cut cells err to second order in the cell (2.8 / 192); measured 0.01 %
    assert self_intersection_volume(V, F, UP) == pytest.approx(ref, rel=0.02)
    diffs = np.abs(np.diff(vals))
    assert diffs[-1] < diffs[0]
    assert diffs[-1] < 1e-3 * ref
    err = np.abs(np.array(vals) - ref)
    assert err[-1] < err[0] and err[-1] < 2e-3 * ref


@pytest.mark.parametrize("up", [[0, 0, 1], [0.3, 0.5, 1.0], [1, 0, 0], [0.1, -1.0, 0.2]])
def test_clean_torus_and_sphere_zero(up):
    t = trimesh.creation.torus(1.0, 0.3)
    s = trimesh.creation.icosphere(subdivisions=3)
    for m in (t, s):
        # every ray crosses a clean closed surface alternately in and out:
        # never two layers, exactly
        assert self_intersection_volume(m.vertices, m.faces, up) == 0.0
    # the same at a resolution where many rays hit edges/vertices exactly
    # (grid-aligned box: pixel centres on the diagonal edges of the faces)
    b = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    for r in (1, 2, 4, 7, 8):
        assert self_intersection_volume(b.vertices, b.faces, UP, resolution=r) == 0.0


def test_edge_and_vertex_hits_counted_once():
    # a closed surface whose vertices sit exactly on pixel centres: an
    # octahedron with apexes on the grid; with resolution 2 the pixel
    # centres are (+-0.5, +-0.5), choose vertices there.
    V = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0], [-0.5, -0.5, 1], [0.5, 0.5, -1]], float)
    hull = trimesh.convex.convex_hull(V)
    for r in (1, 2, 3, 4, 8, 16):
        assert self_intersection_volume(hull.vertices, hull.faces, UP, resolution=r) == 0.0
        # two copies -> the whole volume is doubled
        VV, FF = cat(hull, hull)
        got = self_intersection_volume(VV, FF, UP, resolution=r)
        one = self_intersection_volume(VV, FF[: len(hull.faces)], UP, resolution=r)
        assert one == 0.0
        if r >= 8:
            # the grid's measure of the whole octahedron (2.67): its height
            # vanishes on the footprint's outline, so only cells on its ridges
            # err, O(cell**2) with cell = 2 / r; measured 3 % (r = 8) and
            # 0.8 % (r = 16): the error is O(cell**2), a quarter at twice the resolution
            assert got == pytest.approx(hull.volume, rel={8: 0.04, 16: 0.01}[r])


def test_arm_rotated_into_body_grows():
    angles = [0.0, 30.0, 60.0, 90.0, 120.0]  # 30 deg: a thin sliver, not checked
    vals = []
    for ang in angles:
        body, limb = body_and_arm(ang)
        V, F = cat(body, limb)
        vals.append(self_intersection_volume(V, F, UP))
        if ang >= 60:
            # overlaps 0.047, 0.36, 0.63 at 60, 90, 120 degrees: bounds 13 %,
            # 3.4 %, 4 %; measured 0.4 %, 0.9 %, 1.2 %
            assert vals[-1] == pytest.approx(exact_overlap(body, limb), rel=0.02)
    assert vals[0] == 0.0
    assert all(b > a for a, b in zip(vals, vals[1:]))


def test_batch_equals_single():
    body = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 3]])
    poses = []
    for ang in (0.0, 45.0, 100.0):
        _, limb = body_and_arm(ang)
        V, F = cat(body, limb)
        poses.append(V)
    VV = np.stack(poses)
    up = np.array([0.1, 0.2, 1.0])
    batch = self_intersection_volume(VV, F, up)
    assert batch.shape == (3,) and batch.dtype == np.float64
    single = [self_intersection_volume(v, F, up) for v in VV]
    assert isinstance(single[0], float)
    np.testing.assert_array_equal(batch, single)
    # pose 0 only touches the body (coincident faces): zero up to round-off
    assert abs(batch[0]) < 1e-12 and batch[2] > batch[1] > 1e-3


def test_rigid_motion_and_scaling():
    a = trimesh.creation.box(extents=[2.0, 1.0, 1.5])
    b = trimesh.creation.box(extents=[1.0, 2.0, 1.0])
    b.apply_translation([0.3, 0.2, 0.4])
    V, F = cat(a, b)
    ref = exact_overlap(a, b)
    rng = np.random.default_rng(5)
    R = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
    V2 = V @ R.T + [3.0, -2.0, 1.0]
    up = R @ UP
    # the boxes are turned about up against the grid: overlap 1 x 1 x 0.85,
    # cell <= 2.5 / 192, bound 0.022 (2.6 %); measured 3e-5
    assert self_intersection_volume(V2, F, up) == pytest.approx(ref, rel=0.02)
    # scaling scales the grid with it: the same rays, 27 times the volume
    assert self_intersection_volume(3.0 * V2, F, up) == pytest.approx(
        27 * self_intersection_volume(V2, F, up), rel=1e-12)


# ----------------------------------------------------------------------- 2D


def test_2d_two_overlapping_squares():
    V, F = squares_2d([((0, 0), (2, 2)), ((1.0, 0.5), (2, 2))])
    up2 = np.array([0.0, 1.0])
    ov = 1.0 * 1.5
    # footprint 3 wide in 192 rays: the overlap's sides x = 1, 2 are cell edges
    assert self_intersection_volume(V, F, up2) == pytest.approx(ov, rel=EXACT)
    assert self_intersection_volume(V, F[:, ::-1], up2) == pytest.approx(ov, rel=EXACT)
    # narrower overlap (width 0.5), sides off the cell edges: bound
    # cell * height = 3.5 / 2000 * 1.5 (0.35 %); measured 0.1 %
    V3, F3 = squares_2d([((0, 0), (2, 2)), ((1.5, 0.5), (2, 2))])
    assert self_intersection_volume(V3, F3, up2, resolution=2000) == pytest.approx(0.75, rel=2e-3)
    # rotating the whole configuration does not change the overlap area; the
    # grid's error <= cell * height <= 3.9 / 192 * 1.8 (2.4 %); measured <= 0.01 %
    for t in (0.3, 1.0, 2.5):
        c, s = np.cos(t), np.sin(t)
        R = np.array([[c, -s], [s, c]])
        assert self_intersection_volume(V @ R.T, F, up2) == pytest.approx(ov, rel=0.02)
    # disjoint squares: 0; a single square: 0
    V2, F2 = squares_2d([((0, 0), (1, 1)), ((1.5, 0), (1, 1))])
    assert self_intersection_volume(V2, F2, up2) == 0.0
    # batch; translated and scaled by 2 the sides stay on cell edges
    VV = np.stack([V, V + [1.0, 2.0], 2 * V])
    np.testing.assert_allclose(self_intersection_volume(VV, F, up2), [ov, ov, 4 * ov], rtol=EXACT)


def test_2d_three_layers_counted_once():
    # region covered by >= 2 layers is the union of pairwise overlaps
    V, F = squares_2d([((0, 0), (2, 1)), ((1, 0), (2, 1)), ((1.5, 0), (2, 1))])
    # coverage: [0,1):1, [1,1.5):2, [1.5,2):3, [2,3):2, [3,3.5):1 -> >=2 on [1,3)
    assert self_intersection_volume(V, F, [0.0, 1.0], resolution=350) == pytest.approx(2.0, rel=EXACT)
