"""The slicer model's features on analytic shapes, and how they scale."""

import numpy as np
import pytest
import trimesh

from supportless.energies.slicer_model import COEFFICIENTS, DELTA, INTERFACE_MM, predicted_support_mm, support_features


def _shelf(height, width=10.0):
    """A 2 x 2 x 2 cube on the plate and a width x width x 1 slab whose underside is ``height`` above it (up +z)."""
    cube = trimesh.creation.box((2, 2, 2))
    cube.apply_translation((0, 0, 1))
    slab = trimesh.creation.box((width, width, 1))
    slab.apply_translation((20, 0, height + 0.5))
    m = trimesh.util.concatenate([cube, slab])
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


@pytest.mark.parametrize("height", [0.5, 1.0, 2.0, 7.5])
def test_a_flat_overhang_is_interface_then_base_with_its_outline(height):
    V, F = _shelf(height)
    interface, base, rim = support_features(V, F, "z", 53.13)
    H = INTERFACE_MM
    assert interface == pytest.approx(100.0 * min(height, H) / H)
    assert base == pytest.approx(100.0 * max(height - H, 0.0))
    # the 10 x 10 underside's outline (40 mm) at its height; the cube's bottom lies on the plate and costs nothing
    assert rim == pytest.approx(40.0 * min(height, H) / H)


def test_the_outline_is_seen_from_above():
    # the slab turned 20 degrees about x: its underside is still supported, its walls (70 degrees) are not;
    # seen from above, the outline's edges along y shorten by cos(20), those along x do not
    V, F = _shelf(20.0)
    slab = V[:, 0] > 5
    c, s = np.cos(np.radians(20)), np.sin(np.radians(20))
    centre = V[slab].mean(axis=0)
    V[slab] = (V[slab] - centre) @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]]).T + centre
    _, _, rim = support_features(V, F, "z", 53.13)
    assert rim == pytest.approx(2 * 10.0 + 2 * 10.0 * c)  # every outline edge is above H


def test_steep_faces_are_not_supported():
    # a downward cone, 60 mm high over a 4 mm radius: its sides are ~86 degrees from the plate
    cone = trimesh.creation.cone(radius=4.0, height=60.0, sections=16)
    cone.apply_transform(trimesh.transformations.rotation_matrix(np.pi, (1, 0, 0)))  # apex down
    cone.apply_translation((0, 0, 80.0))  # apex at 20
    base = trimesh.creation.box((2, 2, 2))
    base.apply_translation((30, 0, 1))
    m = trimesh.util.concatenate([cone, base])
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    assert np.all(support_features(V, F, "z", 53.13) == 0.0)
    assert np.all(support_features(V, F, "z", 87.0) > 0)  # past the cone's slope its sides are supported


def _ramp(alpha_deg, length=10.0):
    """A triangular prism whose underside, ``length`` long, rises from the plate at ``alpha_deg`` (up +z)."""
    a = np.radians(alpha_deg)
    tri = [(0.0, 0.0), (length * np.cos(a), length * np.sin(a)), (0.0, 2 * length)]  # (x, z): ramp, top, wall
    P = np.array([(x, y, z) for y in (0.0, 1.0) for x, z in tri])
    hull = trimesh.convex.convex_hull(P)
    return np.asarray(hull.vertices, float), np.asarray(hull.faces, np.int64)


def test_the_threshold_is_the_profiles_plus_delta():
    # an underside alpha degrees from the plate counts at 53.13 + DELTA (> alpha) but not at 45 + DELTA (< alpha)
    alpha = 49.0 + DELTA
    V, F = _ramp(alpha, length=20.0)
    a = np.radians(alpha)
    # the ramp 20 x 1, projected 20 cos(a); its height rises 0 .. 20 sin(a) over the face
    interface, base, rim = support_features(V, F, "z", 53.13)
    assert interface > 0 and base > 0 and rim > 0
    h = 20 * np.sin(a) * np.array([1, 2]) / 3  # the two triangles' centroid heights
    proj = 20 * np.cos(a) / 2
    assert base == pytest.approx(sum(proj * max(x - INTERFACE_MM, 0) for x in h))
    assert np.all(support_features(V, F, "z", 45.0) == 0)


def test_features_scale_as_area_volume_and_length():
    V, F = _shelf(7.5)
    # keep the interface height fixed relative to the model: compare at scale 1 and 3 with H scaled too
    f1 = support_features(V, F, "z", 53.13, scale=1.0, interface_mm=INTERFACE_MM)
    f3 = support_features(V, F, "z", 53.13, scale=3.0, interface_mm=3 * INTERFACE_MM)
    np.testing.assert_allclose(f3, f1 * [9.0, 27.0, 3.0], rtol=1e-12)


def test_batched_equals_single_and_rigid_moves_in_the_plate_cost_nothing():
    V, F = _shelf(5.0)
    c, s = np.cos(0.7), np.sin(0.7)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    moved = V @ Rz.T + [3.0, -2.0, 11.0]
    batch = predicted_support_mm(np.stack([V, moved]), F, "z", 53.13, scale=2.0)
    single = predicted_support_mm(V, F, "z", 53.13, scale=2.0)
    assert batch[0] == pytest.approx(single) and batch[1] == pytest.approx(single, rel=1e-12)
    assert single == pytest.approx(np.dot(COEFFICIENTS, support_features(V, F, "z", 53.13, scale=2.0)))


def _rim_by_edges(V, F, up, overhang_angle):
    """The rim feature edge by edge: every edge between a risky face and one that is not, its length seen along
    ``up`` times its midpoint's height over the plate, capped at :data:`INTERFACE_MM`, over the cap."""
    u = np.asarray(up, float) / np.linalg.norm(up)
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    tau = np.cos(np.radians(overhang_angle + DELTA))
    risky = n @ u < -tau * np.linalg.norm(n, axis=1)
    faces_of: dict = {}
    for f, tri in enumerate(F):
        for k in range(3):
            faces_of.setdefault(tuple(sorted((int(tri[k]), int(tri[(k + 1) % 3])))), []).append(f)
    plate = (V @ u).min()
    rim = 0.0
    for (i, j), (f, g) in faces_of.items():
        if risky[f] != risky[g]:
            d = V[j] - V[i]
            rim += np.linalg.norm(d - (d @ u) * u) * min((V[i] + V[j]) @ u / 2 - plate, INTERFACE_MM)
    return rim / INTERFACE_MM


def test_the_rim_is_the_outline_edges_alone_pose_by_pose():
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=5.0)
    V0, F = np.asarray(sphere.vertices), np.asarray(sphere.faces, np.int64)
    rng = np.random.default_rng(3)
    poses = []
    for _ in range(4):  # lumpy spheres, each turned its own way: outlines of different edges
        V = V0 * (1.0 + 0.3 * rng.random((len(V0), 1)))
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        poses.append(V @ q.T)
    poses = np.stack(poses)
    rims = support_features(poses, F, "z", 45.0)[:, 2]
    expected = [_rim_by_edges(V, F, (0, 0, 1.0), 45.0) for V in poses]
    assert rims == pytest.approx(expected, rel=1e-12)
    assert len(set(np.round(rims, 6))) == len(poses) and min(rims) > 0
