"""Mirror planes of skeletons and symmetric poses."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import supportless as sl
from supportless.base.errors import InputError
from supportless.base.kinematics import euler_to_matrix
from supportless.search.layout import PoseLayout, find_mirror, require_mirror


def test_the_tpose_mirrors_left_onto_right(tpose_rig):
    mirror = find_mirror(tpose_rig)
    np.testing.assert_allclose(np.abs(mirror.normal), [1.0, 0.0, 0.0], atol=1e-12)
    # arms (bones 4-6 and 7-9) and legs (10-12 and 13-15) swap; the spine, neck and head stay
    np.testing.assert_array_equal(mirror.partner + 1, [1, 2, 3, 7, 8, 9, 4, 5, 6, 13, 14, 15, 10, 11, 12])


def test_a_skeleton_without_a_mirror_image_has_none(bunny_rig):
    assert find_mirror(bunny_rig) is None  # the bunny's skeleton is one-sided
    with pytest.raises(InputError, match="no mirror plane"):
        require_mirror(bunny_rig)


def test_layout_round_trip_and_symmetric_angles(tpose_rig):
    rig = tpose_rig
    mirror = find_mirror(rig)
    layout = PoseLayout(rig, rig.anchored_bones, np.zeros((rig.bone_count, 3)), np.radians(60.0), mirror)
    X = np.random.default_rng(0).uniform(-0.5, 0.5, (4, layout.count)) / np.sqrt(3)  # inside the 60 degree ball
    A = layout.to_angles(X)
    np.testing.assert_allclose(layout.from_angles(A[1]), X[1], atol=1e-12)
    R = euler_to_matrix(A)
    S = mirror.reflection
    for b in range(rig.bone_count):
        np.testing.assert_allclose(S @ R[:, b] @ S, R[:, mirror.partner[b]], atol=1e-12)
    np.testing.assert_array_equal(layout.to_angles(np.zeros((1, layout.count)))[0], 0.0)  # X = 0 is the rest


def test_a_symmetric_search_finds_a_mirror_symmetric_pose(tpose_rig):
    rig = tpose_rig
    result = sl.optimize(rig, particles=20, iterations=5, seed=0, symmetric=True, orient="keep")  # bones, not turns
    mirror = find_mirror(rig)
    J = rig.posed_joints(result.angles)
    image = J - 2.0 * ((J - mirror.point) @ mirror.normal)[:, None] * mirror.normal
    assert cKDTree(J).query(image)[0].max() < 1e-9 * np.ptp(rig.vertices)
    assert np.abs(result.angles).max() > 0


def test_layout_keeps_every_point_of_the_box_within_the_limits(tpose_rig):
    """Rotation vectors longer than a joint's limit stand for the rotation at the limit."""
    from supportless.search.prior import joint_angles

    rig = tpose_rig
    limits = np.radians(np.linspace(10.0, 50.0, rig.bone_count))
    for mirror in (None, find_mirror(rig)):
        layout = PoseLayout(rig, rig.anchored_bones, np.zeros((rig.bone_count, 3)), limits, mirror)
        X = np.random.default_rng(1).uniform(layout.lower, layout.upper, (200, layout.count))
        turned = joint_angles(layout.to_angles(X))
        assert np.all(turned <= limits + 1e-9)
        assert np.any(turned > 0.99 * limits)  # the limit is reached, not just approached
        inside = X * 0.3  # well inside every ball: the variables come back
        np.testing.assert_allclose(layout.from_angles(layout.to_angles(inside[:1])[0]), inside[0], atol=1e-9)


def test_the_tool_searches_a_mirrored_figure_mirrored_in_one_search(tpose_rig, bunny_rig):
    """symmetric=None on a mirrored skeleton: the mirrored search alone, its answer and progress those of
    symmetric=True, and ``symmetry`` saying so."""
    from supportless.search.answer import predicted_mm
    from supportless.search.naturalness import mirror_error_deg

    rig = tpose_rig
    seen = []
    auto = sl.optimize(rig, particles=16, iterations=8, seed=0, callback=lambda it, info: seen.append((it, info)))
    mirrored = sl.optimize(rig, particles=16, iterations=8, seed=0, symmetric=True)
    assert auto.symmetry == {"mode": "auto", "kept": "mirrored", "mirrored_mm": pytest.approx(predicted_mm(rig, auto))}
    assert mirrored.symmetry is None  # forced: no choice to report
    np.testing.assert_array_equal(auto.angles, mirrored.angles)
    np.testing.assert_array_equal(auto.rotation, mirrored.rotation)
    assert mirror_error_deg(rig, auto.angles, find_mirror(rig)) == pytest.approx(0.0, abs=1e-6)
    # one search's progress: both swarm phases, counted to the end
    its = [it for it, _ in seen]
    assert its == list(range(1, 2 * 8 + 1)) and {i["iterations"] for _, i in seen} == {2 * 8}
    assert [i["phase"] for _, i in seen] == ["pose"] * 8 + ["pose and turn"] * 8
    # a skeleton without a mirror plane: one free search, nothing to report
    assert sl.optimize(bunny_rig, particles=8, iterations=2, seed=0, orient="keep").symmetry is None
