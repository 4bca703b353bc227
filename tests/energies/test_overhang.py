"""Tests for the prism overhang energy (supportless.energies.overhang)."""

import numpy as np
import pytest
import trimesh
from meshes import box, cells_mesh, t_shape, union

from supportless.energies.overhang import (
    overhang_energy,
    overhang_measures,
    projected_risky_area,
    risky_area,
    risky_faces,
)
from supportless.energies.surface import boundary_edges

UP = np.array([0.0, 0.0, 1.0])


def tilted_arm_shape(angle_deg):
    """Stem plus an arm rising outward at ``angle_deg`` from horizontal."""
    stem = box([-0.5, -0.5, 0], [0.5, 0.5, 3])
    v, f = box([0, -0.5, -0.5], [3, 0.5, 0.5])
    a = np.deg2rad(angle_deg)
    R = np.array([[np.cos(a), 0, -np.sin(a)], [0, 1, 0], [np.sin(a), 0, np.cos(a)]])
    return union(stem, (v @ R.T + [0, 0, 1.5], f))


def t_shape_2d():
    """Stem cell column x in [1,2], y in [0,3]; arm y in [2,3], x in [0,3]."""
    cells = [(1, 0), (1, 1), (1, 2), (0, 2), (2, 2)]
    return cells_mesh(cells)


def rot_about(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return trimesh.transformations.rotation_matrix(angle, axis)[:3, :3]


def brute_force(V, F, up, theta=45.0):
    """Independent per-face Python loop using trimesh normals/areas."""
    up = np.asarray(up, float) / np.linalg.norm(up)
    m = trimesh.Trimesh(V, F, process=False)
    tau = np.cos(np.deg2rad(theta))
    plate = (V @ up).min()
    E = 0.0
    for fi in range(len(F)):
        nd = m.face_normals[fi] @ up
        if nd < -tau:
            E += m.area_faces[fi] * abs(nd) * (m.triangles_center[fi] @ up - plate)
    return E


def test_box_on_plate_is_zero():
    V, F = box([0, 0, 0], [1, 2, 3])
    assert overhang_energy(V, F, UP) == 0.0
    # lifted box: the plate is its lowest point, still zero
    assert overhang_energy(V + [0, 0, 7.0], F, UP) == 0.0
    # but the bottom is risky (area 2) even though it costs nothing
    assert risky_area(V, F, UP) == pytest.approx(2.0, rel=1e-12)


def test_t_shape_exact():
    V, F = t_shape()
    assert overhang_energy(V, F, UP) == pytest.approx(3.0 * 2.0, rel=1e-12)
    # risky: arm undersides (3) + stem bottom (1)
    assert risky_area(V, F, UP) == pytest.approx(4.0, rel=1e-12)
    mask = risky_faces(V, F, UP)
    normals = trimesh.Trimesh(V, F, process=False).face_normals
    assert mask.shape == (len(F),) and mask.dtype == bool
    np.testing.assert_array_equal(mask, normals[:, 2] < -0.5)
    # upside down the T stands on its bar: nothing overhangs
    assert overhang_energy(V, F, -UP) == pytest.approx(0.0, abs=1e-12)
    assert risky_area(V, F, -UP) == pytest.approx(4.0, rel=1e-12)


def test_inverted_winding_same_result():
    V, F = t_shape()
    assert overhang_energy(V, F[:, ::-1], UP) == pytest.approx(6.0, rel=1e-12)


@pytest.mark.parametrize("angle", [50.0, 60.0, 80.0])
def test_arm_tilted_beyond_threshold_is_zero(angle):
    V, F = tilted_arm_shape(angle)
    assert overhang_energy(V, F, UP, overhang_angle=45.0) == pytest.approx(0.0, abs=1e-12)


def test_arm_below_threshold_matches_brute_force():
    V, F = tilted_arm_shape(30.0)
    E = overhang_energy(V, F, UP)
    assert E > 0.1
    assert E == pytest.approx(brute_force(V, F, UP), rel=1e-10)


def test_threshold_angle_parameter():
    # arm underside slopes 40 deg from horizontal: risky at theta=45, not at 35
    V, F = tilted_arm_shape(40.0)
    assert overhang_energy(V, F, UP, overhang_angle=45.0) > 0.1
    assert overhang_energy(V, F, UP, overhang_angle=35.0) == pytest.approx(0.0, abs=1e-12)
    assert overhang_energy(V, F, UP, overhang_angle=35.0) == pytest.approx(
        brute_force(V, F, UP, 35.0), abs=1e-12
    )


def test_bunny_random_directions_brute_force(shared_data):
    m = trimesh.load(shared_data / "bunny.obj", process=False)
    V, F = np.asarray(m.vertices), np.asarray(m.faces)
    rng = np.random.default_rng(3)
    for _ in range(3):
        up = rng.normal(size=3)
        assert overhang_energy(V, F, up, overhang_angle=45.0) == pytest.approx(brute_force(V, F, up), rel=1e-9)


def test_batch_equals_single():
    V, F = t_shape()
    rng = np.random.default_rng(0)
    Rs = [rot_about(rng.normal(size=3), rng.uniform(0, np.pi)) for _ in range(5)]
    VV = np.stack([V @ R.T for R in Rs])
    for fn in (overhang_energy, risky_area):
        batch = fn(VV, F, UP)
        assert batch.shape == (5,) and batch.dtype == np.float64
        single = np.array([fn(v, F, UP) for v in VV])
        np.testing.assert_allclose(batch, single, rtol=1e-14)
        assert isinstance(fn(VV[0], F, UP), float)
    masks = risky_faces(VV, F, UP)
    assert masks.shape == (5, len(F))
    for p in range(5):
        np.testing.assert_array_equal(masks[p], risky_faces(VV[p], F, UP))
    assert len(np.unique(np.round(overhang_energy(VV, F, UP), 9))) > 1


def test_both_measures_in_one_pass_are_each_measures_value():
    V, F = t_shape()
    rng = np.random.default_rng(1)
    VV = np.stack([V @ rot_about(rng.normal(size=3), rng.uniform(0, np.pi)).T for _ in range(4)])
    energy, area = overhang_measures(VV, F, UP, 40.0)
    assert np.array_equal(energy, overhang_energy(VV, F, UP, 40.0)) and np.array_equal(area, risky_area(VV, F, UP, 40.0))
    one = overhang_measures(VV[2], F, UP, 40.0)
    assert one == (overhang_energy(VV[2], F, UP, 40.0), risky_area(VV[2], F, UP, 40.0)) and one[0] > 0 < one[1]


def test_scaling_cubic():
    V, F = tilted_arm_shape(30.0)
    up = np.array([0.2, -0.1, 1.0])
    E = overhang_energy(V, F, up)
    for s in (0.5, 3.0):
        assert overhang_energy(s * V, F, up) == pytest.approx(s**3 * E, rel=1e-12)


def test_rigid_motion_about_up_invariant():
    V, F = tilted_arm_shape(30.0)
    up = np.array([1.0, 2.0, 3.0])
    E = overhang_energy(V, F, up)
    R = rot_about(up, 1.1)
    V2 = V @ R.T + np.array([5.0, -3.0, 2.0])
    assert overhang_energy(V2, F, up) == pytest.approx(E, rel=1e-12)
    # non-normalised up gives the same value
    assert overhang_energy(V2, F, 7.0 * up) == pytest.approx(E, rel=1e-12)
    # a rotation NOT about up changes it
    assert abs(overhang_energy(V @ rot_about([1, 0, 0], 0.7).T, F, up) - E) > 1e-3


# ----------------------------------------------------------------------- 2D


def test_2d_t_shape_and_box():
    V, F = cells_mesh([(0, 0), (1, 0), (0, 1), (1, 1)])
    up = np.array([0.0, 1.0])
    assert overhang_energy(V, F, up) == 0.0
    V, F = t_shape_2d()
    # arm undersides: length 2 at height 2
    assert overhang_energy(V, F, up) == pytest.approx(4.0, rel=1e-12)
    assert overhang_energy(V, F[:, ::-1], up) == pytest.approx(4.0, rel=1e-12)
    assert risky_area(V, F, up) == pytest.approx(3.0, rel=1e-12)
    mask = risky_faces(V, F, up)
    assert mask.shape == (len(boundary_edges(F)),) and mask.sum() == 3
    # sideways printing: underside is the left column of the T (x=0, y 2..3)
    # and the stem's left side (x=1, y 0..2) -- plate at x=0
    assert overhang_energy(V, F, np.array([1.0, 0.0])) == pytest.approx(2.0 * 1.0, rel=1e-12)


def test_2d_tilt_threshold():
    # a parallelogram leaning at 60 deg -> underside edge is horizontal on the
    # plate (0) and the overhanging slanted side has slope 60 deg: not risky
    a = np.deg2rad(60.0)
    V = np.array([[0, 0], [1, 0], [1 + 2 * np.cos(a), 2 * np.sin(a)], [2 * np.cos(a), 2 * np.sin(a)]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    up = np.array([0.0, 1.0])
    assert overhang_energy(V, F, up) == 0.0
    a = np.deg2rad(30.0)
    V = np.array([[0, 0], [1, 0], [1 + 2 * np.cos(a), 2 * np.sin(a)], [2 * np.cos(a), 2 * np.sin(a)]])
    # slanted underside of length 2 with |n.d| = cos 30, centroid height sin30
    expect = 2.0 * np.cos(a) * np.sin(a)
    assert overhang_energy(V, F, up) == pytest.approx(expect, rel=1e-12)


def test_2d_scaling_rigid_and_batch():
    V, F = t_shape_2d()
    up = np.array([0.3, 1.0])
    E = overhang_energy(V, F, up)
    assert E > 0
    assert overhang_energy(2.5 * V, F, up) == pytest.approx(2.5**2 * E, rel=1e-12)
    # translation only (rotation about up in 2D is the identity or a mirror)
    assert overhang_energy(V + [4.0, -1.0], F, up) == pytest.approx(E, rel=1e-12)
    # mirror across the up axis (rotation by pi about up in 3D) keeps E
    u = up / np.linalg.norm(up)
    M = 2 * np.outer(u, u) - np.eye(2)
    assert overhang_energy(V @ M.T, F, up) == pytest.approx(E, rel=1e-12)
    rng = np.random.default_rng(1)
    VV = np.stack([V @ rot_about([0, 0, 1], t)[:2, :2].T for t in rng.uniform(0, 6, 4)])
    np.testing.assert_allclose(overhang_energy(VV, F, up), [overhang_energy(v, F, up) for v in VV], rtol=1e-14)


def test_bad_up_raises():
    V, F = t_shape()
    with pytest.raises(ValueError):
        overhang_energy(V, F, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError):
        overhang_energy(V, F, [0.0, 1.0])


def test_projected_risky_area_of_a_box_is_its_bottom():
    V, F = box([-1.0, -0.5, -1.5], [1.0, 0.5, 1.5])
    assert projected_risky_area(V, F, np.array([0.0, 1.0, 0.0])) == pytest.approx(2.0 * 3.0, rel=1e-12)
    assert projected_risky_area(V, F, np.array([0.0, 0.0, 1.0])) == pytest.approx(2.0 * 1.0, rel=1e-12)
    # a tilt of 30 degrees keeps the bottom risky at 45 degrees; its projection shrinks by cos 30
    R = rot_about([1, 0, 0], np.radians(30))
    batch = np.stack([V, V @ R.T])
    out = projected_risky_area(batch, F, np.array([0.0, 1.0, 0.0]))
    assert out.shape == (2,)
    np.testing.assert_allclose(out, [6.0, 6.0 * np.cos(np.radians(30))], rtol=1e-12)

    # either winding, and the 2D analogue: a unit-square grid's bottom edge has length 3
    assert projected_risky_area(V, F[:, ::-1], np.array([0.0, 1.0, 0.0])) == pytest.approx(6.0, rel=1e-12)
    V2, F2 = cells_mesh([(0, 0), (1, 0), (2, 0), (1, 1)])
    assert projected_risky_area(V2, F2, np.array([0.0, 1.0])) == pytest.approx(3.0, rel=1e-12)
    assert projected_risky_area(V2, F2[:, ::-1], np.array([0.0, 1.0])) == pytest.approx(3.0, rel=1e-12)


@pytest.mark.parametrize("backend", ["fast", "numpy"])
def test_floor_adds_a_fixed_height_under_every_risky_face(backend):
    """``floor`` raises every prism by the same height: + floor x the projected risky area (length in 2D)."""
    V, F = t_shape()
    rng = np.random.default_rng(4)
    for up in ([0, 1, 0], rng.normal(size=3)):
        up = np.asarray(up, float) / np.linalg.norm(up)
        plain = overhang_energy(V, F, up, 45.0, backend=backend)
        raised = overhang_energy(V, F, up, 45.0, backend=backend, floor=0.7)
        assert raised == pytest.approx(plain + 0.7 * projected_risky_area(V, F, up, 45.0), rel=1e-12)
    tri = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0], [0.0, 3.0], [-1.0, 3.0], [-1.0, 1.0]])
    T = np.array([[0, 1, 2], [0, 2, 3], [3, 4, 5], [3, 5, 6]])
    plain = overhang_energy(tri, T, [0.0, 1.0], 45.0, backend=backend)
    raised = overhang_energy(tri, T, [0.0, 1.0], 45.0, backend=backend, floor=0.5)
    assert raised == pytest.approx(plain + 0.5 * projected_risky_area(tri, T, [0.0, 1.0], 45.0), rel=1e-12)


def test_a_given_winding_equals_the_measured_one():
    """``orient`` saves measuring the winding per pose; it must give what the measurement gives."""
    from meshes import box

    V, F = box((0, 0, 0), (1, 2, 1))
    rng = np.random.default_rng(3)
    Q = [np.linalg.qr(rng.normal(size=(3, 3)))[0] * s for s in (1, -1, 1, -1)]  # rotations and reflections
    batch = np.stack([V @ q for q in Q])
    measured = overhang_energy(batch, F, "y")
    winding = np.array([np.sign(np.linalg.det(q)) for q in Q])  # a reflection turns the faces inward
    assert (winding < 0).any() and (winding > 0).any()
    np.testing.assert_allclose(overhang_energy(batch, F, "y", orient=winding), measured, rtol=1e-12)
    np.testing.assert_allclose(overhang_energy(batch, F[:, ::-1], "y", orient=-winding),
                               overhang_energy(batch, F[:, ::-1], "y"), rtol=1e-12)
    assert not np.allclose(overhang_energy(batch, F, "y", orient=-1.0), measured)


@pytest.mark.parametrize("backend", ["fast", "numpy"])
def test_one_direction_per_pose_measures_each_pose_as_if_turned(backend):
    """``V`` along ``R.T @ up`` is ``V @ R.T`` along ``up`` (the search's turned poses), in 3D and 2D."""
    V, F = tilted_arm_shape(30.0)
    Rs = np.stack([rot_about(np.random.default_rng(s).normal(size=3), 0.4 * s) for s in range(5)])
    batch = np.broadcast_to(V, (5, *V.shape))
    along = overhang_energy(batch, F, Rs.transpose(0, 2, 1) @ UP, 50.0, backend=backend, floor=0.1)
    turned = overhang_energy(V @ Rs.transpose(0, 2, 1), F, UP, 50.0, backend=backend, floor=0.1)
    assert np.all(turned > 0) and np.ptp(turned) > 0
    np.testing.assert_allclose(along, turned, rtol=1e-10)
    V2, F2 = t_shape_2d()
    turns = [np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]) for a in (0.0, 0.3, -0.5)]
    up2 = np.array([0.0, 1.0])
    along2 = overhang_energy(np.broadcast_to(V2, (3, *V2.shape)), F2, np.stack([R.T @ up2 for R in turns]), 50.0,
                             backend=backend)
    np.testing.assert_allclose(along2, [overhang_energy(V2 @ R.T, F2, up2, 50.0, backend=backend) for R in turns],
                               rtol=1e-10)
