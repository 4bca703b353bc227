"""Standing: no new contact with the plate, and the centre of mass over the support polygon."""

import numpy as np
import pytest
from meshes import box

import supportless as sl
from supportless.rig.balance import (
    centre_of_mass,
    centre_of_mass_operator,
    new_contact_depth,
    stability_margin,
    support_polygon,
)
from supportless.search.objective import INFEASIBLE
from supportless.search.standing import Standing

#: The objective's naturalness rules (the tool's defaults) left out: only standing judges these poses.
LOOSE = dict(joint_limits=180.0, chain_limit=None, head_limit=None, footprint_mm2=None, w_chain=0.0)


def test_support_polygon_and_margin_of_a_square():
    up = np.array([0.0, 0.0, 1.0])
    pts = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [1, 1, 0]], float)
    poly = support_polygon(pts, up)
    assert len(poly) == 4
    com = np.array([[1.0, 1.0, 5.0], [1.5, 1.0, 0.0], [3.0, 1.0, 2.0], [3.0, 3.0, 2.0]])
    np.testing.assert_allclose(stability_margin(com, poly, up), [1.0, 0.5, -1.0, -np.sqrt(2)], atol=1e-12)
    # a segment (collinear contacts) has no inside
    seg = support_polygon(np.array([[0, 0, 0], [1, 0, 0], [3, 0, 0]], float), up)
    assert stability_margin(np.array([1.0, 2.0, 1.0]), seg, up) == pytest.approx(-2.0, abs=1e-12)
    # 2D: an interval on the plate line
    interval = support_polygon(np.array([[-1.0, 0.0], [2.0, 0.0]]), np.array([0.0, 1.0]))
    assert stability_margin(np.array([0.5, 3.0]), interval, np.array([0.0, 1.0])) == pytest.approx(1.5)


def test_centre_of_mass_of_a_rigidly_moved_box():
    """A box's tets skinned to one bone: the centre of mass is the box centre, moved with the bone."""
    from supportless.rig.tetmesh import tetrahedralize_with_skeleton

    V, F = box((0, 0, 0), (2, 4, 6))
    TV, TT = tetrahedralize_with_skeleton(V, F, np.array([[1.0, 2.0, 1.0], [1.0, 2.0, 5.0]]), np.array([[0, 1]]))
    G = centre_of_mass_operator(TV, TT, np.ones((len(TV), 1)))
    T = np.zeros((1, 3, 4))
    T[0, :, :3] = np.eye(3)
    np.testing.assert_allclose(centre_of_mass(T, G), [1.0, 2.0, 3.0], atol=1e-12)
    T[0, :, 3] = [5.0, 0.0, -1.0]
    np.testing.assert_allclose(centre_of_mass(T[None], G)[0], [6.0, 2.0, 2.0], atol=1e-12)


def test_new_contact_depth():
    V = np.array([[[0, 0, 0], [0, 0, 3]], [[0, 0, 0], [0, 0, -0.5]]], float)
    clear = np.array([False, True])
    np.testing.assert_allclose(new_contact_depth(V, np.array([0, 0, 1.0]), clear, 0.1), [0.0, 0.6])


def test_new_contact_depth_of_a_batch_is_that_of_each_pose(branch_rig):
    """The batch's compiled pass against the heights of each pose alone (numpy's ``V @ up``), along an axis (the same
    bits) and a tilted direction; a pose whose clear vertices stay up is 0, one brought down by its depth."""
    rig = branch_rig
    rng = np.random.default_rng(3)
    V = rig.pose(rng.normal(scale=0.6, size=(12, rig.bone_count, 3)))
    clear = rng.random(len(rig.vertices)) > 0.3
    for up in (np.array([0.0, 1.0, 0.0]), np.array([0.3, 0.9, -0.2]) / np.linalg.norm([0.3, 0.9, -0.2])):
        heights = V @ up
        level = float(np.median(heights[:, clear].min(axis=1)))  # half the poses come down past it
        batch = new_contact_depth(V, up, clear, level)
        alone = np.array([new_contact_depth(v, up, clear, level) for v in V])
        np.testing.assert_allclose(batch, alone, rtol=0, atol=1e-12 if up[0] else 0.0)
        np.testing.assert_allclose(batch, np.maximum(0.0, level - heights[:, clear].min(axis=1)), rtol=0, atol=1e-12)
        assert 0 < np.count_nonzero(batch) < len(V)
    assert np.all(new_contact_depth(V, up, np.zeros(len(rig.vertices), bool), 0.0) == 0)  # nothing clear


def test_the_rest_pose_stands(tpose_rig):
    standing = Standing(tpose_rig)
    rest = standing.measures(tpose_rig.transforms(tpose_rig.rest_angles()), tpose_rig.vertices)
    assert rest["stands"] and rest["new_contact_vertices"] == 0 and rest["stability_margin"] > 0


def test_a_pose_that_puts_a_new_part_on_the_plate_is_rejected(branch_rig):
    """The stem of the branch figure laid down flat: its side touches the plate."""
    rig = branch_rig
    obj = sl.Objective(rig, **LOOSE)
    A = np.zeros((2, rig.bone_count, 3))
    A[1, 0] = np.radians([0.0, 0.0, -85.0])  # bone 1, the stem, turned about its foot
    V = rig.pose(A[1])
    assert (V @ rig.up)[obj.standing.clear].min() < obj.standing.touch_level
    t = obj.terms(A)
    assert t["violation"][0] == 0 and t["violation"][1] > 0
    assert obj(A)[1] > INFEASIBLE
    assert obj.standing.measures(rig.transforms(A[1]), V)["new_contact_vertices"] > 0


def test_a_pose_that_falls_over_is_rejected(tpose_rig):
    """The whole upper body leant 80 degrees backwards: the centre of mass leaves the feet."""
    rig = tpose_rig
    obj = sl.Objective(rig, **LOOSE)
    A = np.zeros((2, rig.bone_count, 3))
    A[1, 0] = np.radians([-80.0, 0.0, 0.0])  # bone 1: the spine, carrying the torso, arms and head
    transforms = rig.transforms(A)
    margins = obj.standing.margin(transforms)
    assert margins[0] > 0 > margins[1]
    assert obj.terms(A)["violation"][1] > 0
    assert not obj.standing.measures(transforms[1], rig.pose(A[1]))["stands"]
    relaxed = sl.Objective(rig, **LOOSE, keep_standing=False)
    assert relaxed.terms(A)["violation"][1] == 0


def test_found_poses_stand_and_touch_nothing_new(tpose_rig):
    result = sl.optimize(tpose_rig, particles=30, iterations=10, seed=0)
    m = result.objective.standing.measures(tpose_rig.transforms(result.angles), tpose_rig.pose(result.angles))
    assert m["stands"] and m["new_contact_vertices"] == 0


def test_a_pose_never_stands_with_a_negative_margin_even_when_rest_falls_over(tpose_rig):
    """A rest pose tipped past its feet: poses as steady as it are allowed, but none is said to stand."""
    rig = tpose_rig
    obj = sl.Objective(rig)
    tipped = obj.standing
    tipped.__dict__["rest_margin"] = -0.1 * tipped.height  # as if the rest pose leaned out of its feet
    tipped.__dict__.pop("required_margin", None)
    A = rig.rest_angles()[None].repeat(2, 0)
    A[1, 0] = np.radians([-60.0, 0.0, 0.0])  # the spine bent far forward: the centre of mass past the toes
    transforms = rig.transforms(A)
    upright, bent = (tipped.measures(transforms[k], rig.pose(A[k])) for k in range(2))
    assert upright["stands"] and upright["stability_margin"] > 0
    assert bent["stability_margin"] < 0 and bent["as_steady_as_rest"] and not bent["stands"]
    from supportless.apps.cli import _standing_word

    falls = {"stands": False, "stability_margin": -0.05, "as_steady_as_rest": True}
    assert "nor does the rest pose" in _standing_word({"stands": False}, falls)
    assert _standing_word({"stands": True}, falls | {"as_steady_as_rest": False}) == "FALLS OVER"
