"""Tests for the column support estimator."""

import numpy as np
import pytest
import trimesh
from meshes import box_mesh as box
from meshes import cells_mesh, t_shape, union

from supportless.energies.overhang import overhang_energy
from supportless.energies.support import support_volume

UP = np.array([0.0, 0.0, 1.0])

#: Tolerance of the cases the grid measures exactly: axis-aligned shapes whose
#: features lie on cell edges (error 0.0 but for round-off).
EXACT = 1e-9


def arm_over_base():
    """Base slab on the plate, a stem, and an arm over the base.

    The arm underside (area 3, at z=3) hangs over the base top (z=1), so the
    columns are 2 long: support 6, while the prism energy counts 3*3 = 9.
    """
    return union(box([0, 0, 0], [4, 1, 1]), box([0, 0, 1], [1, 1, 3]), box([0, 0, 3], [4, 1, 4]))


def vertical_hits(mesh, x, y):
    """Heights and normal z of all triangles hit by the vertical line at (x, y).

    Plain barycentric point-in-triangle test (independent of the kernel).
    """
    T = mesh.triangles
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    ok = np.abs(det) > 1e-300
    det = np.where(ok, det, 1.0)
    l1 = ((x - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (y - a[:, 1])) / det
    l2 = ((b[:, 0] - a[:, 0]) * (y - a[:, 1]) - (x - a[:, 0]) * (b[:, 1] - a[:, 1])) / det
    l0 = 1.0 - l1 - l2
    hit = ok & (l0 >= 0) & (l1 >= 0) & (l2 >= 0)
    z = l0 * a[:, 2] + l1 * b[:, 2] + l2 * c[:, 2]
    return z[hit], mesh.face_normals[hit, 2]


def brute_force_columns(mesh, n, theta=45.0):
    """Independent reference: per-ray Python sweep along +z.

    Same ray set as the kernel: square cells, ``n`` along the longer side of
    the footprint, grid centred on the footprint.
    """
    lo, hi = mesh.bounds
    plate = lo[2]
    tau = np.cos(np.deg2rad(theta))
    ext = hi[:2] - lo[:2]
    cell = ext.max() / n
    cnt = np.maximum(1, np.ceil(ext / cell - 1e-9).astype(int))
    org = lo[:2] + 0.5 * (ext - cnt * cell)
    total = 0.0
    for x in org[0] + (np.arange(cnt[0]) + 0.5) * cell:
        for y in org[1] + (np.arange(cnt[1]) + 0.5) * cell:
            z, nz = vertical_hits(mesh, x, y)
            order = np.argsort(z)
            below, inside = plate, 0
            for k in order:
                if nz[k] < 0:
                    if inside == 0 and nz[k] < -tau:
                        total += z[k] - below
                    inside += 1
                else:
                    inside -= 1
                below = z[k]
    return total * cell * cell


def test_box_on_plate_zero():
    b = box([0, 0, 0], [1, 2, 3])
    assert support_volume(b.vertices, b.faces, UP) == 0.0
    R = trimesh.transformations.rotation_matrix(0.5, [0, 0, 1])
    b.apply_transform(R)
    assert support_volume(b.vertices, b.faces, UP) == 0.0


def test_t_shape():
    V, F = t_shape()
    # footprint 4 x 1 in 192 cells of 1/48: the arm undersides end on cell edges
    assert support_volume(V, F, UP) == pytest.approx(6.0, rel=EXACT)
    # same as the prism for a T standing on the plate
    assert overhang_energy(V, F, UP) == pytest.approx(6.0, rel=1e-12)
    # inverted winding
    assert support_volume(V, F[:, ::-1], UP) == pytest.approx(6.0, rel=EXACT)
    # upside down it stands on its bar
    assert support_volume(V, F, -UP) == 0.0
    # rigid motion about up: the undersides' outline now cuts cells
    # obliquely.  Grid error (here and below, first order): each cell cut by
    # the outline of the supported region is counted whole or not at all, so
    # |error| <= cell / 2 * outline length * column height = 0.011 * 10 * 2
    # = 0.21 (3.6 %); measured 0.05 %
    R = trimesh.transformations.rotation_matrix(0.7, [0.2, 0.1, 1.0])[:3, :3]
    up = R @ UP
    V2 = V @ R.T + [1.0, 2.0, 3.0]
    assert support_volume(V2, F, up) == pytest.approx(6.0, rel=0.02)
    # scaling by 2 scales the grid with it: the same rays, 8 times the volume
    assert support_volume(2 * V2, F, up) == pytest.approx(8 * support_volume(V2, F, up), rel=1e-12)


def test_arm_over_lower_body_stops_at_body_top():
    V, F = arm_over_base()
    # footprint 4 x 1: the arm's outline lies on cell edges
    assert support_volume(V, F, UP) == pytest.approx(6.0, rel=EXACT)
    assert overhang_energy(V, F, UP) == pytest.approx(9.0, rel=1e-12)


@pytest.mark.parametrize("angle,risky", [(30.0, True), (60.0, False)])
def test_tilted_arm_threshold(angle, risky):
    stem = box([-0.5, -0.5, 0], [0.5, 0.5, 3])
    arm = box([0, -0.5, -0.5], [3, 0.5, 0.5])
    arm.apply_transform(trimesh.transformations.rotation_matrix(-np.deg2rad(angle), [0, 1, 0]))
    arm.apply_translation([0, 0, 1.5])
    V, F = union(stem, arm)
    v = support_volume(V, F, UP)
    if risky:
        m = trimesh.Trimesh(V, F, process=False)
        v128 = support_volume(V, F, UP, resolution=128)
        assert v128 == pytest.approx(brute_force_columns(m, 128), rel=1e-9)
        # analytic: only the arm underside (width 1) is supported, down to
        # the plate, from where it leaves the stem (x = 0.5) to its tip
        a = np.deg2rad(angle)
        z0, x0 = 1.5 - 0.5 * np.cos(a), 0.5 * np.sin(a)
        xe = 3 * np.cos(a) + x0
        ref = z0 * (xe - 0.5) + np.tan(a) * ((xe - x0) ** 2 - (0.5 - x0) ** 2) / 2
        # grid error: centre sampling is exact for the linear underside;
        # the cells cut by the region's outline (length 6.7, columns <= 2.6
        # high) err: <= cell / 2 * 6.7 * 2.6 with cell = 3.35 / resolution,
        # 3.4 % at 192 and 0.6 % at 1024; measured 1.3 % and 0.04 %
        assert v == pytest.approx(ref, rel=0.02)
        assert support_volume(V, F, UP, resolution=1024) == pytest.approx(ref, rel=0.003)
        assert support_volume(V, F, UP, overhang_angle=25.0) == 0.0
    else:
        assert v == 0.0


def test_sphere_analytic():
    r = 1.0
    s = trimesh.creation.icosphere(subdivisions=5, radius=r)
    s.apply_translation([0, 0, r])
    a = r * np.sin(np.pi / 4)
    # integral over the disc rho < a of the lower-hemisphere height
    ref = np.pi * r * a**2 - 2 * np.pi / 3 * (r**3 - (r**2 - a**2) ** 1.5)
    # an approximation twice over: the icosphere (20 * 4**5 faces, edges
    # ~0.03) is not the sphere, so the rim of its risky region (where the
    # facets cross 45 degrees) is only known to a facet, and the grid adds
    # <= cell / 2 * rim length 4.4 * rim height 0.29 = 3 %; measured 0.9 %
    # (support) and 1.3 % (prism)
    assert support_volume(s.vertices, s.faces, UP, 45.0) == pytest.approx(ref, rel=0.03)
    assert overhang_energy(s.vertices, s.faces, UP, 45.0) == pytest.approx(ref, rel=0.03)


def test_bunny_matches_brute_force(shared_data):
    m = trimesh.load(shared_data / "bunny.obj", process=False)
    R = trimesh.transformations.rotation_matrix(2.0, [1.0, 0.3, 0.0])
    m.apply_transform(R)
    got = support_volume(m.vertices, m.faces, UP, 45.0, resolution=64)
    ref = brute_force_columns(m, 64)
    assert got > 0
    # the same rays; the reference's barycentric test may differ only on
    # rays within round-off of an edge (none here): equal up to summation order
    assert got == pytest.approx(ref, rel=1e-12)
    # the prism over-estimates (it also counts support resting on the model)
    assert overhang_energy(m.vertices, m.faces, UP, 45.0) > got


def test_batch_equals_single():
    V, F = arm_over_base()
    rng = np.random.default_rng(0)
    VV = np.stack(
        [V @ trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3].T for _ in range(4)]
    )
    batch = support_volume(VV, F, UP)
    assert batch.shape == (4,) and batch.dtype == np.float64
    single = [support_volume(v, F, UP) for v in VV]
    assert isinstance(single[0], float)
    np.testing.assert_array_equal(batch, single)


def test_2d():
    up = np.array([0.0, 1.0])
    V, F = cells_mesh([(1, 0), (1, 1), (1, 2), (0, 2), (2, 2)])
    # 192 or 300 rays over a footprint 3 wide: ray cells end on the unit cells' edges
    assert support_volume(V, F, up) == pytest.approx(4.0, rel=EXACT)
    assert support_volume(V, F, up, resolution=300) == pytest.approx(4.0, rel=EXACT)
    assert support_volume(V, F[:, ::-1], up, resolution=300) == pytest.approx(4.0, rel=EXACT)
    # arm over a base row: columns of height 2 over 2 cells (prism: 2 * 3)
    V, F = cells_mesh([(0, 0), (1, 0), (2, 0), (0, 1), (0, 2), (0, 3), (1, 3), (2, 3)])
    assert support_volume(V, F, up, resolution=300) == pytest.approx(4.0, rel=EXACT)
    assert overhang_energy(V, F, up) == pytest.approx(6.0, rel=1e-12)
    # a square on the plate
    V, F = cells_mesh([(0, 0)])
    assert support_volume(V, F, up) == 0.0
    VV = np.stack([V, 2 * V])
    np.testing.assert_array_equal(support_volume(VV, F, up), [0.0, 0.0])


def test_faces_inside_material_need_no_support():
    # two overlapping boxes given as one face list: the upper box's bottom
    # (z=1, x in [1,3]) lies inside the lower box for x < 2 -> only x in [2,3]
    # needs a column (length 1, area 1)
    a = box([0, 0, 0], [2, 1, 2])
    b = box([1, 0, 1], [3, 1, 3])
    V = np.vstack([a.vertices, b.vertices])
    F = np.vstack([a.faces, b.faces + len(a.vertices)])
    # footprint 3 x 1: x = 2 is a cell edge
    assert support_volume(V, F, UP) == pytest.approx(1.0, rel=EXACT)
    # the prism counts the whole bottom of b: area 2 at height 1
    assert overhang_energy(V, F, UP) == pytest.approx(2.0, rel=1e-12)


@pytest.mark.parametrize("resolution", [7, 48, 64])
def test_compiled_crossings_are_the_numpy_paths_to_the_last_bit(tpose_rig, resolution):
    """support_columns' compiled crossings sweep to the numpy path's columns exactly (posed, tilted, coarse
    and fine grids), and their column volume is the numpy estimate's."""
    from supportless.base.geometry import print_pose
    from supportless.energies._grid_crossings import crossings3
    from supportless.energies._grid_numpy import columns3_numpy, sweep_crossings
    from supportless.energies.support import support_columns
    from supportless.energies.surface import orientation_sign, to_frame

    rig = tpose_rig
    angles = np.random.default_rng(resolution).uniform(-0.6, 0.6, (rig.bone_count, 3))
    c, s = np.cos(0.7), np.sin(0.7)
    for V in (rig.pose(angles), print_pose(rig.pose(angles), np.array([[1, 0, 0], [0, c, -s], [0, s, c]]), rig.up)):
        X = to_frame(V[None], rig.up)[0]
        orient = float(orientation_sign(V[None], rig.faces, "numpy")[0])
        tau = np.cos(np.radians(45.0))
        inter, sup, (cu, cw, bottom, top), cell = columns3_numpy(X, rig.faces, orient, resolution, tau)
        pix, z, code, (cell2, nx, _, u0, w0) = crossings3(X, rig.faces, orient, resolution, tau)
        inter2, sup2, (pix2, bottom2, top2) = sweep_crossings(pix, z, code, float(X[:, 2].min()))
        assert cell2 == cell and inter2 == inter and sup2 == sup and len(pix2) > 0
        np.testing.assert_array_equal(bottom2, bottom)
        np.testing.assert_array_equal(top2, top)
        np.testing.assert_array_equal(u0 + (pix2 % nx + 0.5) * cell, cu)
        np.testing.assert_array_equal(w0 + (pix2 // nx + 0.5) * cell, cw)
        _, heights, cell3, _ = support_columns(V, rig.faces, rig.up, 45.0, resolution)
        assert (heights * cell3**2).sum() == pytest.approx(support_volume(V, rig.faces, rig.up, 45.0, resolution,
                                                                          backend="numpy"), rel=1e-12)
