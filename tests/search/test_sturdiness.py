"""The strength of a pose as printed: the analysis of the body the slicer gets, asked once per pose."""

from __future__ import annotations

import numpy as np

from supportless.energies.materials import MATERIALS
from supportless.energies.strength import analyse_strength
from supportless.search import sturdiness
from supportless.search.sturdiness import STRENGTH_CACHE_SIZE, face_bones, pose_strength, printed_body


def test_a_pose_asked_again_is_not_analysed_again_and_equals_a_fresh_analysis(branch_rig, monkeypatch):
    rig = branch_rig
    angles = rig.rest_angles().copy()
    angles[1, 0] = 0.4
    first = pose_strength(rig, angles, np.eye(3), 60.0, MATERIALS["PLA"])
    calls = []
    monkeypatch.setattr(sturdiness, "analyse_strength", lambda *a, **k: calls.append(a) or analyse_strength(*a, **k))
    again = pose_strength(rig, angles.copy(), np.eye(3), 60.0, MATERIALS["PLA"])
    assert again is first and not calls
    V, J = printed_body(rig, angles, np.eye(3), 60.0)
    fresh = analyse_strength(V, rig.faces, J, rig.bones, face_bones(rig), MATERIALS["PLA"])
    assert fresh.safety_factor == first.safety_factor
    np.testing.assert_array_equal(fresh.face_safety, first.face_safety)
    # another pose, height or material is a new analysis, and a different answer
    other = angles.copy()
    other[1, 0] = -0.4
    assert pose_strength(rig, other, np.eye(3), 60.0, MATERIALS["PLA"]) is not first
    taller = pose_strength(rig, angles, np.eye(3), 120.0, MATERIALS["PLA"])
    assert taller.safety_factor != first.safety_factor
    assert pose_strength(rig, angles, np.eye(3), 60.0, MATERIALS["PETG"]).material.name == "PETG"
    assert len(calls) == 3


def test_the_cache_keeps_a_bounded_number_of_poses(branch_rig):
    rig = branch_rig
    for i in range(STRENGTH_CACHE_SIZE + 3):
        angles = rig.rest_angles().copy()
        angles[1, 0] = 0.01 * i
        pose_strength(rig, angles, np.eye(3), 60.0)
    assert len(sturdiness._strength_cache(rig)) == STRENGTH_CACHE_SIZE
