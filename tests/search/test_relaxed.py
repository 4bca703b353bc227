"""Relaxed seeds (supportless.search.relaxed): limbs let down toward gravity, on the built-in T-pose figure."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import supportless as sl
from supportless.search.layout import find_mirror
from supportless.search.relaxed import ARM_DROPS, relaxed_poses
from supportless.search.naturalness import mirror_error_deg

MIXAMO_TPOSE = ["mixamorig:Spine", "mixamorig:Neck", "mixamorig:Head",
                "mixamorig:LeftShoulder", "mixamorig:LeftArm", "mixamorig:LeftForeArm",
                "mixamorig:RightShoulder", "mixamorig:RightArm", "mixamorig:RightForeArm",
                "mixamorig:Hips", "mixamorig:LeftUpLeg", "mixamorig:LeftLeg",
                "mixamorig:RightHips", "mixamorig:RightUpLeg", "mixamorig:RightLeg"]
UPPER_ARMS = (4, 7)
HANDS = (6, 9)  # the tips of the forearms: joints 7 and 10 (1-based), 0-based 6 and 9


def _seeds(rig):
    settings = sl.SearchSettings()
    free = ~settings.fixed_bones(rig)
    limits = settings.joint_limits(rig)
    return relaxed_poses(rig, free, limits), free, limits


@pytest.fixture(scope="module")
def named(tpose_rig):
    rig = copy.copy(tpose_rig)
    rig.labels = list(MIXAMO_TPOSE)
    return rig


@pytest.mark.parametrize("which", ["unnamed", "named"])
def test_seeds_let_the_arms_down_within_the_rules(tpose_rig, named, which):
    rig = tpose_rig if which == "unnamed" else named
    seeds, free, limits = _seeds(rig)
    assert len(seeds) >= 1
    rest_hands = rig.joints[list(HANDS)] @ rig.up
    mirror = find_mirror(rig)
    for A in seeds:
        assert np.all(A[~free] == 0)  # anchored bones (the legs standing on the plate) stay
        assert np.all(np.degrees(sl.SearchSettings().objective(rig).prior.angles(A)) <= limits + 1e-6)
        hands = rig.posed_joints(A)[list(HANDS)] @ rig.up
        assert np.all(hands < rest_hands - 1.0)  # both hands lower than at rest
        assert mirror_error_deg(rig, A, mirror) < 1e-6  # each side turned toward its own down
    assert not np.any(np.all(seeds == 0, axis=(1, 2)))  # the rest pose is not repeated


def test_a_named_rig_turns_its_upper_arms_by_each_drop(named):
    seeds, _, limits = _seeds(named)
    assert len(seeds) == len(ARM_DROPS)
    turned = np.degrees(sl.SearchSettings().objective(named).prior.angles(seeds))  # (s, m)
    moved = np.flatnonzero(turned.max(axis=0) > 1e-6)
    assert set(moved.tolist()) == set(UPPER_ARMS)
    for drop, row in zip(ARM_DROPS, turned):
        assert row[list(UPPER_ARMS)] == pytest.approx(min(drop, limits[UPPER_ARMS[0]] * 0.98), abs=1e-6)


def test_a_named_upper_arm_may_swing_as_far_as_its_range(tpose_rig, named):
    assert sl.SearchSettings().joint_limits(named)[list(UPPER_ARMS)].tolist() == [90.0, 90.0]
    assert sl.SearchSettings().joint_limits(tpose_rig)[list(UPPER_ARMS)].tolist() == [45.0, 45.0]
    assert sl.SearchSettings(anatomy=False).joint_limits(named)[list(UPPER_ARMS)].tolist() == [45.0, 45.0]


def test_a_planar_figure_gets_no_seeds(rig_cache_dir):
    rig = sl.load_rig("demo:woody2d", cache_dir=rig_cache_dir)
    assert relaxed_poses(rig, np.ones(rig.bone_count, bool), np.full(rig.bone_count, 45.0)).shape[0] == 0
