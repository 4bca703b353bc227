"""Print orientations: candidate directions, their support, and turning a model."""

import numpy as np
import pytest
import trimesh

import supportless as sl
from supportless.search.orientation import candidate_ups, rank_ups, rotation_between


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


def test_a_boxy_model_gets_its_candidates_without_a_warning():
    """Two boxes have six distinct normals, fewer than the twelve clusters asked: k-means is asked for six (no
    empty cluster, nothing printed on the user's terminal)."""
    import warnings

    boxes = trimesh.util.concatenate([trimesh.creation.box([1.0, 2.0, 3.0]),
                                      trimesh.creation.box([1.0, 1.0, 1.0]).apply_translation([0.0, 3.0, 0.0])])
    V, F = np.asarray(boxes.vertices), np.asarray(boxes.faces, np.int64)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ups = candidate_ups(V, F, clusters=12)
    np.testing.assert_allclose(np.linalg.norm(ups, axis=1), 1.0, atol=1e-12)
    assert np.allclose(ups[:6] @ ups[:6].T, [[1, -1, 0, 0, 0, 0], [-1, 1, 0, 0, 0, 0], [0, 0, 1, -1, 0, 0],
                                             [0, 0, -1, 1, 0, 0], [0, 0, 0, 0, 1, -1], [0, 0, 0, 0, -1, 1]])


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


# --------------------------------------------------------------------------- #
# the search's orientation variables
# --------------------------------------------------------------------------- #
from scipy.spatial.transform import Rotation  # noqa: E402

from supportless.search.orientation import (  # noqa: E402
    orientation_params,
    print_direction,
    rotation_axis_angle,
    rotations_from_params,
    seed_params,
    tangent_basis,
)


@pytest.mark.parametrize("up", [[0, 1, 0], [0, 0, 1], [1, -2, 0.5]])
def test_orientation_variables_are_a_rotation_vector_orthogonal_to_up(up):
    up = np.asarray(up, float) / np.linalg.norm(up)
    B = tangent_basis(up)
    np.testing.assert_allclose(B @ B.T, np.eye(2), atol=1e-12)
    np.testing.assert_allclose(B @ up, 0.0, atol=1e-12)
    X = np.random.default_rng(1).uniform(-np.pi, np.pi, (50, 2))
    R = rotations_from_params(X, up)
    np.testing.assert_allclose(R, Rotation.from_rotvec(X @ B).as_matrix(), atol=1e-12)  # scipy's exponential map
    np.testing.assert_allclose(rotations_from_params(np.zeros((1, 2)), up)[0], np.eye(3), atol=0)


@pytest.mark.parametrize("up", [[0, 1, 0], [0.3, 0.2, -1.0]])
def test_orientation_params_invert_the_smallest_rotation_to_up(up):
    up = np.asarray(up, float) / np.linalg.norm(up)
    rng = np.random.default_rng(2)
    for u in [*rng.normal(size=(20, 3)), -up, up]:
        u = u / np.linalg.norm(u)
        R = rotation_between(u, up)
        x = orientation_params(R, up)
        assert np.linalg.norm(x) <= np.pi + 1e-12
        back = rotations_from_params(x[None], up)[0]
        np.testing.assert_allclose(back @ u, up, atol=1e-9)
        np.testing.assert_allclose(print_direction(back, up), u, atol=1e-9)
    # a turn about up is dropped: the same printing direction, the same variables
    turn = Rotation.from_rotvec(0.7 * up).as_matrix()
    R = rotation_between(np.array([1.0, 0, 0]) - up * up[0], up) if abs(up[0]) < 0.99 else np.eye(3)
    np.testing.assert_allclose(orientation_params(turn @ R, up), orientation_params(R, up), atol=1e-9)


def test_planar_orientation_is_one_angle():
    up = np.array([0.0, 1.0])
    R = rotations_from_params(np.array([[0.5], [-2.0]]), up)
    np.testing.assert_allclose(R[0], [[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]])
    assert orientation_params(R[1], up)[0] == pytest.approx(-2.0)
    axis, degrees = rotation_axis_angle(R[0])
    assert axis is None and degrees == pytest.approx(np.degrees(0.5))
    axis, degrees = rotation_axis_angle(Rotation.from_rotvec([0, 0, -1.2]).as_matrix())
    np.testing.assert_allclose(axis, [0, 0, -1], atol=1e-12)
    assert degrees == pytest.approx(np.degrees(1.2))


def test_seeds_are_the_cheapest_candidates_and_never_upright():
    rod = trimesh.creation.cylinder(radius=1.0, height=10.0, sections=32)
    rod.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    V, F = np.asarray(rod.vertices), np.asarray(rod.faces, np.int64)
    up = np.array([0.0, 1.0, 0.0])
    X = seed_params(V, F, up, 3)
    assert X.shape == (3, 2) and np.all(np.linalg.norm(X, axis=1) > 1e-6)
    first = print_direction(rotations_from_params(X[:1], up)[0], up)
    assert abs(first[0]) > 0.999  # stood on a flat end
    ranks = [sl.overhang_energy(V @ rotations_from_params(x[None], up)[0].T, F, up) for x in X]
    assert ranks == sorted(ranks)
    assert len(seed_params(V, F, up, 0)) == 0
