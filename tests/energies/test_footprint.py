"""The first layer's contact: sections of closed surfaces against their areas in closed form."""

import numpy as np
import pytest
import trimesh

from supportless.energies.footprint import FIRST_LAYER_MM, footprint_area, section_area


def _rotation(seed):
    q = np.random.default_rng(seed).normal(size=4)
    return trimesh.transformations.quaternion_matrix(q / np.linalg.norm(q))[:3, :3]


def test_a_box_rests_on_its_whole_base_however_it_is_turned():
    box = trimesh.creation.box([2.0, 3.0, 4.0])
    assert section_area(box.vertices, box.faces, [0, 0, 1], 0.5) == pytest.approx(6.0)
    R = _rotation(1)  # the same box turned, heights measured along the turned up
    assert section_area(box.vertices @ R.T, box.faces, R @ [0, 0, 1], 0.5) == pytest.approx(6.0)


def test_a_sphere_rests_on_the_cap_of_its_first_layer():
    """A sphere of radius r cut h over its lowest point: a disc of area pi (2 r h - h^2)."""
    sphere = trimesh.creation.icosphere(6, radius=30.0)
    h = 2.0
    assert section_area(sphere.vertices, sphere.faces, [0, 0, 1], h) == pytest.approx(np.pi * (2 * 30 * h - h * h), rel=0.01)


def test_a_ring_subtracts_its_hole():
    ring = trimesh.creation.annulus(1.0, 2.0, 1.0)
    assert section_area(ring.vertices, ring.faces, [0, 0, 1], 0.3) == pytest.approx(np.pi * (4 - 1), rel=0.01)


def test_a_cone_on_its_tip_rests_on_almost_nothing():
    """Tip down, a cone of base radius 5 and height 10 is cut 0.1 over its tip in a disc of radius 0.05."""
    cone = trimesh.creation.cone(5.0, 10.0, sections=64)
    V, F = cone.vertices * [1, 1, -1], cone.faces[:, ::-1]  # mirrored: tip down, still outward
    assert section_area(V, F, [0, 0, 1], 0.1) == pytest.approx(np.pi * 0.05 ** 2, rel=0.02)


def test_a_batch_equals_its_single_calls_and_the_scale_goes_squared():
    box = trimesh.creation.box([2.0, 3.0, 4.0])
    R = _rotation(2)
    batch = np.stack([box.vertices, box.vertices @ R.T, 2 * box.vertices])
    one = [footprint_area(V, box.faces, [0, 0, 1], 10.0) for V in batch]
    assert np.allclose(footprint_area(batch, box.faces, [0, 0, 1], 10.0), one)
    # 10 mm a unit: the first layer's half (0.1 mm) is 0.01 units over the lowest point
    assert one[0] == pytest.approx(6.0 * 100.0)
    assert one[2] == pytest.approx(4 * 6.0 * 100.0)
    assert FIRST_LAYER_MM == 0.2


def test_a_plane_past_the_surface_gives_zero():
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    assert section_area(box.vertices, box.faces, [0, 0, 1], 5.0) == 0.0


def test_a_turned_pose_measured_along_the_turned_up_is_the_pose_turned_and_manifolds_slice():
    """Per-pose directions: ``V`` along ``R.T @ up`` equals ``V @ R.T`` along ``up``, and both equal the area of
    manifold3d's slice of the turned surface (an independent method)."""
    import manifold3d
    blob = trimesh.creation.icosphere(3, radius=10.0)
    blob.vertices *= [1.0, 0.6, 1.4]  # an ellipsoid: every turn rests on a different cap
    up = np.array([0.0, 0.0, 1.0])
    Rs = np.stack([_rotation(s) for s in range(6)])
    above = np.linspace(0.5, 3.0, 6)
    along = section_area(np.broadcast_to(blob.vertices, (6, *blob.vertices.shape)), blob.faces, Rs.transpose(0, 2, 1) @ up,
                         above)
    turned = blob.vertices @ Rs.transpose(0, 2, 1)  # (6, n, 3): each pose turned by its R
    np.testing.assert_allclose(along, section_area(turned, blob.faces, up, above), rtol=1e-9)
    for V, h, area in zip(turned, above, along):
        solid = manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(V, np.float32),
                                                    tri_verts=np.asarray(blob.faces, np.uint32)))
        assert area == pytest.approx(solid.slice(float(V[:, 2].min() + h)).area(), rel=1e-4)  # float32 there
