"""The natural-pose prior: one angle per joint, limits, and the volume each joint turns."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import supportless as sl
from supportless.search.prior import PosePrior, joint_angles


def test_joint_angle_is_the_geodesic_angle_of_the_rotation():
    rng = np.random.default_rng(0)
    A = rng.uniform(-1.2, 1.2, (50, 4, 3))
    expected = Rotation.from_euler("XYZ", A.reshape(-1, 3)).magnitude().reshape(50, 4)
    np.testing.assert_allclose(joint_angles(A), expected, atol=1e-9)
    np.testing.assert_allclose(joint_angles(np.zeros((3, 3))), 0.0, atol=0)
    # 2D: only the angle about the plane normal counts, wrapped to [0, pi]
    np.testing.assert_allclose(joint_angles(np.array([[5.0, 5.0, -0.4], [0.0, 0.0, 2 * np.pi - 0.1]]), dim=2),
                               [0.4, 0.1], atol=1e-12)


def test_carried_volume_adds_up_down_the_tree(tpose_rig):
    prior = PosePrior(tpose_rig, np.full(tpose_rig.bone_count, 30.0))
    c = prior.carried
    assert np.all((c > 0) & (c <= 1 + 1e-12))
    roots = tpose_rig.parents < 0
    assert c[roots].sum() == pytest.approx(1.0, abs=1e-9)  # the roots carry the whole body
    for b, p in enumerate(tpose_rig.parents):
        if p >= 0:
            assert c[p] > c[b]  # a parent carries its children and its own region


def test_turning_the_head_costs_more_than_turning_a_hand(tpose_rig):
    rig = tpose_rig
    prior = PosePrior(rig, np.full(rig.bone_count, 180.0))
    head, hand = 2, 5  # tpose: bone 3 is the head (neck to crown), bone 6 the left forearm and hand
    assert rig.bones[head].tolist() == [2, 3] and rig.bones[hand].tolist() == [5, 6]
    A = np.zeros((2, rig.bone_count, 3))
    A[0, head] = np.radians([0.0, 0.0, 40.0])
    A[1, hand] = np.radians([0.0, 0.0, 40.0])
    cost = prior.cost(A)
    assert cost[0] > 2 * cost[1] > 0


def test_turning_the_bunnys_head_costs_more_than_an_ear(bunny_rig):
    rig = bunny_rig
    prior = PosePrior(rig, np.full(rig.bone_count, 180.0))
    ear = int(np.argmax(rig.joints[rig.bones[:, 1]] @ rig.up))  # the bone ending at the highest joint
    head = 0  # bunny.tgf: bone 1 runs from the neck into the head, and both ears hang from it
    assert rig.bones[head, 1] in rig.bones[rig.parents[ear]]
    A = np.zeros((2, rig.bone_count, 3))
    A[0, head] = np.radians([40.0, 0.0, 0.0])
    A[1, ear] = np.radians([40.0, 0.0, 0.0])
    cost = prior.cost(A)
    assert cost[0] > 5 * cost[1] > 0


def test_limits_hold_per_bone_in_the_search(branch_rig):
    settings = sl.SearchSettings(particles=24, iterations=8, seed=1, joint_limit=20.0,
                                 limits=("3=5",), free=("all",), keep_standing=False, orient="keep")
    result = sl.optimize(branch_rig, settings)
    turned = np.degrees(joint_angles(result.angles))
    assert np.all(turned <= settings.joint_limits(branch_rig) + 1e-9), turned
    assert turned.max() > 1.0  # the search did move
