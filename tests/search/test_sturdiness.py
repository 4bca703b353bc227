"""The strength of a pose as printed: the analysis of the body the slicer gets, asked once per pose."""

from __future__ import annotations

import numpy as np

from supportless.energies.materials import MATERIALS
from supportless.energies.strength import analyse_strength
from supportless.search import sturdiness
from supportless.search.sturdiness import (STRENGTH_CACHE_SIZE, face_bones, pose_strength, pose_strengths,
                                          printed_body)


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


def test_several_poses_are_analysed_half_in_a_child_and_equal_the_analyses_one_by_one(branch_rig, monkeypatch):
    """pose_strengths: the analyses not yet made, every other one in a forked child (run_beside), each equal to
    pose_strength's own; one asked twice or already made is not made again; a failed child's share is made here."""
    rig = branch_rig
    sturdiness._strength_cache(rig).clear()  # other tests' poses: none here
    poses = []
    for turn in (0.23, -0.37, 0.51, 0.66):
        angles = rig.rest_angles().copy()
        angles[1, 0] = turn
        poses.append((angles, np.eye(3)))
    bodies = [printed_body(rig, a, q, 60.0) for a, q in poses]
    expected = [analyse_strength(V, rig.faces, J, rig.bones, face_bones(rig)) for V, J in bodies]
    pose_strength(rig, *poses[3], 60.0)  # already made: not made again
    made = []  # the analyses made in this process
    monkeypatch.setattr(sturdiness, "analyse_strength", lambda *a, **k: made.append(1) or analyse_strength(*a, **k))
    beside, analysed = [], []
    run_beside, analyses = sturdiness.run_beside, sturdiness._analyses
    monkeypatch.setattr(sturdiness, "run_beside", lambda *a, **k: beside.append(a) or run_beside(*a, **k))
    monkeypatch.setattr(sturdiness, "_analyses", lambda bodies, *a: analysed.append(len(bodies)) or analyses(bodies, *a))
    got = pose_strengths(rig, poses + [poses[0]], 60.0)
    assert len(beside) == 1 and len(beside[0][1][0]) == 1 and len(beside[0][3][0]) == 2  # 1 there, 2 here
    assert analysed == [2] and len(made) == 2  # here two, the child's one kept from the child
    for strength, fresh in zip(got, expected + expected[:1]):
        assert strength.safety_factor == fresh.safety_factor
        np.testing.assert_array_equal(strength.face_safety, fresh.face_safety)
    assert got[4] is got[0] and got == [pose_strength(rig, a, q, 60.0) for a, q in poses + [poses[0]]]
    # a child that fails: every analysis is made here, one by one
    sturdiness._strength_cache(rig).clear()
    made.clear()

    def failing(*_args, **_kwargs):
        raise sturdiness.NativeFailure("the strength analysis crashed (SIGSEGV)", crashed=True)

    monkeypatch.setattr(sturdiness, "run_beside", failing)
    again = pose_strengths(rig, poses[:2], 60.0)
    assert len(made) == 2 and [s.safety_factor for s in again] == [e.safety_factor for e in expected[:2]]
    assert pose_strengths(rig, poses[:2], 60.0) == again and len(made) == 2  # kept: not made again
