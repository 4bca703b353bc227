"""The naturalness figures: chain-end turns and the mirror error, against analytic cases."""

import numpy as np
import pytest

import supportless as sl
from supportless.base.kinematics import euler_to_matrix, matrix_to_euler
from supportless.search.objective import INFEASIBLE
from supportless.search.layout import find_mirror
from supportless.search.naturalness import (chain_ends, head_bones, mirror_error_deg, naturalness, rotation_angle_deg,
                                           world_turn_deg)


@pytest.fixture(scope="module")
def arm():
    return sl.load_rig("demo:arm")


def test_rotation_angle_of_known_rotations():
    for deg in (0.0, 30.0, 90.0, 179.0):
        a = np.radians(deg)
        Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])
        assert rotation_angle_deg(Rz) == pytest.approx(deg, abs=1e-6)
        assert rotation_angle_deg(Rz[:2, :2]) == pytest.approx(deg, abs=1e-9)
    R = euler_to_matrix(np.random.default_rng(0).uniform(-1, 1, (5, 3)))
    np.testing.assert_allclose(rotation_angle_deg(R), rotation_angle_deg(np.swapaxes(R, -1, -2)), atol=1e-9)


def test_three_joints_at_30_degrees_in_one_plane_turn_the_chain_end_90(arm):
    """The arm's chain root -> forearm -> hand: each joint turns 30 degrees about the plane's normal."""
    assert set(chain_ends(arm).tolist()) == {0, 3}  # the two bones nothing hangs from
    chain = [2, 1, 0]  # the root bone, its child, its grandchild (the end)
    assert arm.parents[0] == 1 and arm.parents[1] == 2 and arm.parents[2] == -1
    A = np.zeros((arm.bone_count, 3))
    A[chain, 2] = np.radians(30.0)
    turn = world_turn_deg(arm, A)
    np.testing.assert_allclose(turn[chain], [30.0, 60.0, 90.0], atol=1e-9)
    figures = naturalness(arm, A)
    assert figures["largest_chain_turn_deg"] == pytest.approx(90.0, abs=1e-9) and figures["chain_end"] == 1
    B = A.copy()
    B[1, 2] = -B[1, 2]  # the middle joint the other way: the end turns back to 30 degrees
    assert world_turn_deg(arm, B)[0] == pytest.approx(30.0, abs=1e-9)
    np.testing.assert_allclose(world_turn_deg(arm, np.stack([A, B]))[:, 0], [90.0, 30.0], atol=1e-9)  # a batch


def test_a_mirrored_pose_has_no_mirror_error_and_one_arm_alone_has(tpose_rig):
    mirror = find_mirror(tpose_rig)
    assert mirror is not None
    rest = np.zeros((tpose_rig.bone_count, 3))
    assert mirror_error_deg(tpose_rig, rest, mirror) == pytest.approx(0.0, abs=1e-9)
    pairs = [p for p in range(tpose_rig.bone_count) if mirror.partner[p] != p
             and tpose_rig.parents[p] >= 0 and mirror.partner[tpose_rig.parents[p]] == tpose_rig.parents[p]]
    p = pairs[0]  # a bone of a pair hanging from a bone in the plane (a shoulder or a hip)
    one = rest.copy()
    one[p] = np.radians([10.0, 20.0, 30.0])
    assert mirror_error_deg(tpose_rig, one, mirror) > 10.0
    both = one.copy()
    S = mirror.reflection
    both[mirror.partner[p]] = matrix_to_euler(S @ euler_to_matrix(one[p]) @ S)
    assert mirror_error_deg(tpose_rig, both, mirror) == pytest.approx(0.0, abs=1e-6)
    assert naturalness(tpose_rig, both)["mirror_error_deg"] == pytest.approx(0.0, abs=1e-6)


def test_the_chain_limit_rejects_a_chain_turned_past_it_and_the_search_keeps_it(arm):
    """Three joints at 30 degrees turn the end 90: feasible under no limit, infeasible under 60 degrees."""
    A = np.zeros((arm.bone_count, 3))
    A[[2, 1, 0], 2] = np.radians(30.0)
    free = sl.SearchSettings(joint_limit=45.0, keep_standing=False, free=("all",), chain_limit=None).objective(arm)
    limited = sl.SearchSettings(joint_limit=45.0, keep_standing=False, free=("all",), chain_limit=60.0).objective(arm)
    assert free.terms(A)["violation"] == pytest.approx(0.0)
    assert limited.terms(A)["violation"] == pytest.approx(np.radians(30.0))  # the end is 30 degrees past 60
    assert float(limited(A)) >= INFEASIBLE and float(free(A)) < INFEASIBLE
    found = sl.optimize(arm, particles=24, iterations=8, seed=0, orient="keep", free=("all",), chain_limit=20.0)
    assert world_turn_deg(arm, found.angles)[chain_ends(arm)].max() <= 20.0 + 1e-6
    with pytest.raises(sl.InputError, match="chain_limit"):
        sl.SearchSettings(chain_limit=200.0)


def test_the_prior_pays_for_the_accumulated_turn_of_a_chain(arm):
    """Three joints at 30 degrees the same way cost more than the same joints turning different ways."""
    same = np.zeros((arm.bone_count, 3))
    same[[2, 1, 0], 2] = np.radians(30.0)
    mixed = same.copy()
    mixed[1, 2] = -mixed[1, 2]
    plain = sl.SearchSettings(keep_standing=False, free=("all",), w_chain=0.0).objective(arm)
    chained = sl.SearchSettings(keep_standing=False, free=("all",), w_chain=1.0).objective(arm)
    assert plain.terms(same)["prior"] == pytest.approx(plain.terms(mixed)["prior"])  # per joint: the same cost
    extra = chained.terms(same)["prior"] - plain.terms(same)["prior"]
    ends = world_turn_deg(arm, same)[chain_ends(arm)]
    assert extra == pytest.approx(float((np.radians(ends) ** 2).sum()), rel=1e-9)  # (pi/2)^2 for the hand
    assert chained.terms(same)["prior"] > chained.terms(mixed)["prior"]
    rest = np.zeros_like(same)
    assert chained.terms(rest)["prior"] == pytest.approx(0.0, abs=1e-12)


def test_an_unnamed_upright_figure_finds_its_head_and_a_chain_has_none(tpose_rig, arm):
    """The tpose's head (hips -> chest -> neck -> head, bone 3) ends the only chain at the top; the arm has no head."""
    assert tpose_rig.labels is None
    heads = head_bones(tpose_rig)
    assert heads.tolist() == [2] and heads[0] in chain_ends(tpose_rig)
    top = tpose_rig.joints @ tpose_rig.up
    assert top[tpose_rig.bones[2, 1]] == pytest.approx(top.max())  # its tip is the skeleton's highest joint
    assert head_bones(arm).size == 0


def test_a_head_turned_40_degrees_is_refused_and_a_hand_turned_40_allowed(tpose_rig):
    """The head limit (25 degrees by default) is tighter than the chain limit (60) that bounds a hand."""
    head, hand = 2, 5  # the tpose's head and left forearm, both chain ends
    assert hand in chain_ends(tpose_rig) and hand not in head_bones(tpose_rig)
    defaults = sl.SearchSettings()
    assert defaults.head_limit == 25.0 and defaults.head_limit < defaults.chain_limit
    objective = sl.SearchSettings(keep_standing=False, free=("all",)).objective(tpose_rig)
    nod, wave = np.zeros((2, tpose_rig.bone_count, 3))
    nod[head, 0] = wave[hand, 1] = np.radians(40.0)
    assert world_turn_deg(tpose_rig, nod)[head] == pytest.approx(40.0) == world_turn_deg(tpose_rig, wave)[hand]
    assert objective.terms(wave)["violation"] == pytest.approx(0.0) and float(objective(wave)) < INFEASIBLE
    assert objective.terms(nod)["violation"] == pytest.approx(np.radians(15.0))  # 15 degrees past 25
    assert float(objective(nod)) >= INFEASIBLE
    off = sl.SearchSettings(keep_standing=False, free=("all",), head_limit=None).objective(tpose_rig)
    assert off.terms(nod)["violation"] == pytest.approx(0.0)
    assert naturalness(tpose_rig, nod)["head_turn_deg"] == pytest.approx(40.0)
    with pytest.raises(sl.InputError, match="head_limit"):
        sl.SearchSettings(head_limit=200.0)


def test_the_head_limit_bounds_the_neck_chain_together(tpose_rig):
    """Chest, neck and head at 10 degrees each the same way: no joint is far, the head 30 degrees is."""
    objective = sl.SearchSettings(keep_standing=False, free=("all",)).objective(tpose_rig)
    bow = np.zeros((tpose_rig.bone_count, 3))
    bow[[0, 1, 2], 0] = np.radians(10.0)
    assert world_turn_deg(tpose_rig, bow)[2] == pytest.approx(30.0)
    assert objective.terms(bow)["violation"] == pytest.approx(np.radians(5.0))
    bow[1, 0] = -bow[1, 0]  # the neck back: the head stays up
    assert objective.terms(bow)["violation"] == pytest.approx(0.0)
