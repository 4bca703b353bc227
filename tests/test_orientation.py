"""Print orientations: candidate directions, their support, and turning a model."""

import numpy as np
import pytest
import trimesh

import supportless as sl
from supportless.orientation import candidate_ups, rank_ups, rotation_between


def test_rotation_between_takes_a_to_b():
    rng = np.random.default_rng(0)
    for _ in range(20):
        a, b = rng.normal(size=(2, 3))
        a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
        R = rotation_between(a, b)
        np.testing.assert_allclose(R @ a, b, atol=1e-12)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    a = np.array([0.0, 1.0, 0.0])
    np.testing.assert_allclose(rotation_between(a, -a) @ a, -a, atol=1e-12)
    np.testing.assert_allclose(rotation_between(a, a), np.eye(3), atol=1e-15)


def test_a_rod_lying_flat_is_cheapest_printed_upright():
    """A cylinder lying along x needs support under its lower half; standing on its flat end, none."""
    rod = trimesh.creation.cylinder(radius=1.0, height=10.0, sections=32)
    rod.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))  # axis z -> x
    V, F = np.asarray(rod.vertices), np.asarray(rod.faces, np.int64)
    ups = candidate_ups(V, F)
    assert np.allclose(ups[0], [0, 1, 0])  # the upright direction is always a candidate
    np.testing.assert_allclose(np.linalg.norm(ups, axis=1), 1.0, atol=1e-12)
    support = rank_ups(V, F, ups)
    best = ups[np.argmin(support)]
    assert abs(best[0]) > 0.999  # along the rod's axis
    assert support.min() < 1e-9 * rank_ups(V, F, [[0.0, 1.0, 0.0]])[0]  # a flat end on the plate: none


def test_candidates_are_at_least_min_angle_apart(tpose_rig):
    ups = candidate_ups(tpose_rig.vertices, tpose_rig.faces, min_angle_deg=15.0)
    cos = ups @ ups.T
    np.fill_diagonal(cos, -1.0)
    assert cos.max() < np.cos(np.radians(15.0)) + 1e-12
    assert 6 <= len(ups) <= 6 + 24 + 12


def test_ranking_matches_the_energy_of_the_turned_mesh(tpose_rig):
    """Scoring a direction equals turning the mesh so that direction points up and scoring it upright."""
    V, F = tpose_rig.vertices, tpose_rig.faces
    ups = candidate_ups(V, F)[:8]
    support = rank_ups(V, F, ups)
    for u, s in zip(ups, support):
        turned = V @ rotation_between(u, np.array([0.0, 1.0, 0.0])).T
        assert sl.overhang_energy(turned, F, "y") == pytest.approx(s, rel=1e-9)
