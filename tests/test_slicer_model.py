"""The slicer model's features on analytic shapes, and how they scale."""

import numpy as np
import pytest
import trimesh

from supportless.energies.slicer_model import (COEFFICIENTS, DELTA, INTERFACE_MM, predicted_support_mm,
                                               support_features)


def _shelf(height, width=10.0):
    """A 2 x 2 x 2 cube on the plate and a width x width x 1 slab whose underside is ``height`` above it (up +z)."""
    cube = trimesh.creation.box((2, 2, 2))
    cube.apply_translation((0, 0, 1))
    slab = trimesh.creation.box((width, width, 1))
    slab.apply_translation((20, 0, height + 0.5))
    m = trimesh.util.concatenate([cube, slab])
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


@pytest.mark.parametrize("height", [0.5, 1.0, 2.0, 7.5])
def test_a_flat_overhang_is_interface_then_base(height):
    V, F = _shelf(height)
    interface, base, tips = support_features(V, F, "z", 53.13)
    H = INTERFACE_MM
    assert interface == pytest.approx(100.0 * min(height, H) / H)
    assert base == pytest.approx(100.0 * max(height - H, 0.0))
    assert tips == 0.0  # the slab's lowest corners lie on its supported underside


def test_steep_faces_are_not_supported_and_a_hanging_tip_is():
    # a downward cone, 60 mm high over a 4 mm radius: its sides are ~86 degrees from the plate
    cone = trimesh.creation.cone(radius=4.0, height=60.0, sections=16)
    cone.apply_transform(trimesh.transformations.rotation_matrix(np.pi, (1, 0, 0)))  # apex down
    cone.apply_translation((0, 0, 80.0))  # apex at 20
    base = trimesh.creation.box((2, 2, 2))
    base.apply_translation((30, 0, 1))
    m = trimesh.util.concatenate([cone, base])
    V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    interface, base_volume, tips = support_features(V, F, "z", 53.13)
    assert interface == 0.0 and base_volume == 0.0
    assert tips == pytest.approx(20.0)


def _ramp(alpha_deg):
    """A triangular prism whose underside rises from the plate at ``alpha_deg`` from it (up +z)."""
    a = np.radians(alpha_deg)
    tri = [(0.0, 0.0), (10 * np.cos(a), 10 * np.sin(a)), (0.0, 20.0)]  # (x, z): ramp, top, wall
    P = np.array([(x, y, z) for y in (0.0, 1.0) for x, z in tri])
    hull = trimesh.convex.convex_hull(P)
    return np.asarray(hull.vertices, float), np.asarray(hull.faces, np.int64)


def test_the_threshold_is_the_profiles_plus_delta():
    # an underside 58 degrees from the plate counts at 53.13 + DELTA (> 58) but not at 45 + DELTA (< 58)
    assert 45.0 + DELTA < 58.0 < 53.13 + DELTA
    V, F = _ramp(58.0)
    a = np.radians(58.0)
    # area of the ramp 10 x 1, projected 10 cos(a); its height rises 0 .. 10 sin(a) = 8.5 mm over the face
    interface, base, _ = support_features(V, F, "z", 53.13)
    assert interface > 0 and base > 0
    h = 10 * np.sin(a) * np.array([1, 2]) / 3  # the two triangles' centroid heights
    proj = 10 * np.cos(a) / 2
    assert base == pytest.approx(sum(proj * max(x - INTERFACE_MM, 0) for x in h))
    assert np.all(support_features(V, F, "z", 45.0)[:2] == 0)


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
