"""Contact between jointed parts (supportless.rig.contact) on the built-in T-pose figure, where the answer is known.

The figure's bones (1-based in its TGF): 1 the torso from the hips to the chest, 2-3 neck and head, 4 the left
shoulder, 5 the left upper arm, 6 the left forearm, 10-12 the left leg, 13-15 the right leg.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import supportless as sl
from supportless.base.kinematics import matrix_to_euler
from supportless.copyleft.cgal import intersecting_faces
from supportless.files.printbody import united_surface
from supportless.rig.contact import (CONTACT_HOPS, BodyParts, ContactRules, RefusedCrossings, contact_verdict,
                                     refused_by_pairs)

SHOULDER, UPPER_ARM, FOREARM, HEAD, LEFT_THIGH, RIGHT_THIGH = 3, 4, 5, 2, 9, 12


def turned(rig, turns):
    """A pose: ``{bone: (axis, degrees)}``, each bone's rotation relative to its parent."""
    A = np.zeros((rig.bone_count, 3))
    for bone, (axis, degrees) in turns.items():
        axis = np.asarray(axis, np.float64)
        A[bone] = matrix_to_euler(Rotation.from_rotvec(axis / np.linalg.norm(axis) * np.radians(degrees)).as_matrix())
    return A


def verdict(rig, A, rules=ContactRules()):
    V = rig.pose(A)
    return rig.crossings(V, rig.posed_joints(A), rules, float(sl.self_intersection_volume(V, rig.faces, rig.up)))


ARM_DOWN = {UPPER_ARM: ((0, 0, -1), 70)}  # the left upper arm let down against the shoulder and chest
HAND_TO_HEAD = {UPPER_ARM: ((0, 0, 1), 40), FOREARM: ((0, 0, 1), 150)}  # the forearm folded up through the head


def test_parts_are_jointed_through_at_most_one_other_part(tpose_rig):
    parts = tpose_rig.body_parts
    assert parts.hops[UPPER_ARM, SHOULDER] == 1
    assert parts.hops[UPPER_ARM, 0] == 2  # through the shoulder to the torso
    assert parts.hops[LEFT_THIGH, RIGHT_THIGH] == 1  # at the hips
    assert parts.hops[FOREARM, HEAD] > CONTACT_HOPS
    assert parts.hops[LEFT_THIGH + 1, RIGHT_THIGH + 1] > CONTACT_HOPS  # the two shins
    assert np.all(parts.hops == parts.hops.T) and np.all(np.diag(parts.hops) == 0)
    # every face belongs to one bone, the one with the largest weight on its corners
    W = tpose_rig.weights
    expected = np.argmax(W[tpose_rig.faces].sum(axis=1), axis=1)
    assert np.array_equal(parts.face_bone, expected)


def test_an_arm_pressed_into_the_part_it_is_jointed_to_is_contact(tpose_rig):
    A = turned(tpose_rig, ARM_DOWN)
    assert len(intersecting_faces(tpose_rig.pose(A), tpose_rig.faces)) > 0  # it does cross itself
    found = verdict(tpose_rig, A)
    assert found.allowed, found.reason
    assert found.pairs > 0 and found.regions
    assert all(UPPER_ARM in r["bones"] for r in found.regions)
    assert all(0 <= r["depth"] <= ContactRules().depth for r in found.regions)


def test_the_same_press_is_refused_without_contact_or_past_the_depth_bound(tpose_rig):
    A = turned(tpose_rig, ARM_DOWN)
    assert not verdict(tpose_rig, A, ContactRules(hops=-1)).allowed
    deepest = max(r["depth"] for r in verdict(tpose_rig, A).regions)
    shallow = verdict(tpose_rig, A, ContactRules(depth=deepest / 2))
    assert not shallow.allowed and "thickness" in shallow.reason
    assert not verdict(tpose_rig, A, ContactRules(volume=1e-9)).allowed


def test_a_forearm_through_the_head_is_refused(tpose_rig):
    A = turned(tpose_rig, HAND_TO_HEAD)
    found = verdict(tpose_rig, A)
    assert found.pairs > 0
    assert not found.allowed and "not jointed" in found.reason


def test_a_crossing_far_from_the_shared_joint_is_refused():
    # two bones sharing one joint, and a crossing placed ten bone lengths away from it
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    W = np.array([[1.0, 0], [1, 0], [0, 1], [0, 1]])
    joints = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0, 0]])
    parts = BodyParts(V, F, W, joints, np.array([[0, 1], [1, 2]]))
    pair = np.array([[0, 2]])
    face_bones = parts.face_bone[pair[0]]
    assert parts.hops[face_bones[0], face_bones[1]] <= CONTACT_HOPS
    near = contact_verdict(parts, V, joints, pair, ContactRules(reach=1e6))
    far = contact_verdict(parts, V, joints, pair, ContactRules(reach=1.0))
    assert near.allowed and not far.allowed and "farther" in far.reason


def test_no_crossing_is_always_allowed(tpose_rig):
    rest = np.zeros((tpose_rig.bone_count, 3))
    found = verdict(tpose_rig, rest, ContactRules(hops=-1))
    assert found.allowed and found.pairs == 0


def test_a_posed_body_with_contact_is_written_as_one_clean_solid(tpose_rig):
    A = turned(tpose_rig, ARM_DOWN)
    V = tpose_rig.pose(A)
    U, G, merged = united_surface(V, tpose_rig.faces)
    assert merged["pairs"] == len(intersecting_faces(V, tpose_rig.faces)) > 0
    assert len(intersecting_faces(U, G)) == 0
    assert len(intersecting_faces(U.astype(np.float32).astype(np.float64), G)) == 0  # as an STL stores it
    edges = np.sort(G[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)  # closed and manifold
    # the shared volume is counted once: less than the posed surface's, by about the overlap the ray grid sees
    overlap = float(sl.self_intersection_volume(V, tpose_rig.faces, tpose_rig.up))
    assert merged["volume"] < merged["volume_before"]
    assert merged["merged_volume"] == pytest.approx(overlap, rel=0.5)


def test_a_surface_that_does_not_cross_itself_is_written_as_it_is(tpose_rig):
    U, G, merged = united_surface(tpose_rig.vertices, tpose_rig.faces)
    assert merged["pairs"] == 0 and merged["how"] == "none"
    assert np.array_equal(U, tpose_rig.vertices) and np.array_equal(G, tpose_rig.faces)


def test_a_united_file_is_written_on_the_plate(tpose_rig, tmp_path, monkeypatch):
    """The written file of a pose with contact is one solid; a remeshed one (lifted here) is put back on the plate."""
    from supportless.base.geometry import place_on_plate
    from supportless.files.printframe import rig_print_frame
    from supportless.report import outputs

    A = turned(tpose_rig, ARM_DOWN)
    V = place_on_plate(tpose_rig.pose(A), tpose_rig.up)
    real = outputs.united_surface

    def lifted(P, F):
        U, G, merged = real(P, F)
        return U + np.array([0.0, 0.0, 0.5]), G, merged

    monkeypatch.setattr(outputs, "united_surface", lifted)
    kind = outputs.write_posed(tmp_path / "posed.stl", tpose_rig, A, V, V, rig_print_frame(tpose_rig))
    assert "one solid (exact self-union" in kind
    W, G = sl.read_mesh(tmp_path / "posed.stl")
    assert W[:, 2].min() == pytest.approx(0.0, abs=1e-6)
    assert len(intersecting_faces(W, G)) == 0


@pytest.mark.parametrize("pose", [ARM_DOWN, HAND_TO_HEAD])
def test_the_depth_scan_finds_the_depths_a_tree_per_part_finds(tpose_rig, pose, monkeypatch):
    """The compiled scan of every triangle (a few vertices inside) against libigl's distance tree per part."""
    from supportless.rig import contact

    A = turned(tpose_rig, pose)
    V, parts = tpose_rig.pose(A), tpose_rig.body_parts
    bones = np.arange(tpose_rig.bone_count)
    scanned = contact._deepest(parts, V, bones)
    monkeypatch.setattr(contact, "SCAN_BUDGET", 0)
    tree = contact._deepest(parts, V, bones)
    assert scanned and scanned.keys() == tree.keys()
    for key in tree:
        assert scanned[key] == pytest.approx(tree[key], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("rules", [ContactRules(), ContactRules(volume=1e-9), ContactRules(depth=0.01)])
def test_the_search_gate_is_the_verdict_with_its_overlap(tpose_rig, rules):
    """Objective.forbidden judges the pairs first and measures the overlap only for a pose the other rules allow:
    the same yes or no as the whole verdict with the overlap, the volume rule included."""
    objective = sl.SearchSettings().objective(tpose_rig)
    objective.contact = rules
    for turns in ({}, ARM_DOWN, HAND_TO_HEAD):
        A = turned(tpose_rig, turns)
        assert objective.forbidden(A) == (not verdict(tpose_rig, A, rules).allowed)
    # the three rules decide differently on the arm let down: allowed, too much volume, too deep
    assert [objective.forbidden(turned(tpose_rig, ARM_DOWN))] == [rules != ContactRules()]


@pytest.mark.parametrize("pose", [HAND_TO_HEAD, ARM_DOWN])
def test_pairs_that_refuse_by_themselves_refuse_any_set_holding_them(tpose_rig, pose):
    """The rules :func:`refused_by_pairs` applies judge each pair alone: random subsets of a pose's crossing pairs
    refuse only when the verdict of all of them refuses (the forearm through the head), and never when it allows
    (the arm let down against the chest)."""
    A = turned(tpose_rig, pose)
    V, J, parts = tpose_rig.pose(A), tpose_rig.posed_joints(A), tpose_rig.body_parts
    pairs = intersecting_faces(V, tpose_rig.faces)
    whole = contact_verdict(parts, V, J, pairs, ContactRules())
    assert len(pairs) > 1
    assert refused_by_pairs(parts, V, J, pairs, ContactRules()) == (not whole.allowed)
    rng = np.random.default_rng(3)
    verdicts = [refused_by_pairs(parts, V, J, pairs[rng.random(len(pairs)) < share], ContactRules())
                for share in (0.1, 0.3, 0.5, 0.8) for _ in range(5)]
    if whole.allowed:
        assert not any(verdicts)
    else:
        assert any(verdicts)  # some subsets hold a pair through the head
    assert not refused_by_pairs(parts, V, J, np.zeros((0, 2), np.int64), ContactRules())
    assert refused_by_pairs(parts, V, J, pairs[:1], ContactRules(hops=-1))  # no contact allowed: any pair refuses


def test_the_last_refused_crossings_are_asked_first(tpose_rig, monkeypatch):
    """After the forearm through the head is refused, a pose near it is refused from its remembered triangles
    alone (no exact test of the whole surface); a pose whose crossings lie elsewhere is tested whole."""
    from supportless.search import objective as objective_module

    whole = []
    exact = objective_module.intersecting_faces

    def counted(V, F):
        whole.append(len(F))
        return exact(V, F)

    monkeypatch.setattr(objective_module, "intersecting_faces", counted)
    objective = sl.SearchSettings().objective(tpose_rig)
    assert objective.forbidden(turned(tpose_rig, HAND_TO_HEAD)) and whole == [len(tpose_rig.faces)]
    remembered = objective._refused.faces
    assert remembered is not None and 0 < len(remembered) < len(tpose_rig.faces)
    near = {UPPER_ARM: ((0, 0, 1), 42), FOREARM: ((0, 0, 1), 148)}
    assert objective.forbidden(turned(tpose_rig, near)) and len(whole) == 1
    assert not objective.forbidden(turned(tpose_rig, ARM_DOWN)) and len(whole) == 2
    assert np.array_equal(objective._refused.faces, remembered)  # an allowed pose is not remembered
    memory = RefusedCrossings()
    assert not memory.refuse(tpose_rig.body_parts, tpose_rig.vertices, tpose_rig.joints, ContactRules())


def test_a_search_gate_with_a_memory_says_what_a_fresh_one_says(tpose_rig):
    """One objective judging a sequence of random poses (each asked first about the last refused pose's
    triangles) gives the verdicts of a fresh objective per pose."""
    rng = np.random.default_rng(11)
    poses = [np.radians(rng.uniform(-100, 100, (tpose_rig.bone_count, 3))) * (rng.random((tpose_rig.bone_count, 1))
                                                                             < 0.4) for _ in range(14)]
    poses = [p for pair in zip(poses, poses) for p in pair]  # each twice: the second is asked from the memory
    kept = sl.SearchSettings().objective(tpose_rig)
    mine = [kept.forbidden(A) for A in poses]
    fresh = [sl.SearchSettings().objective(tpose_rig).forbidden(A) for A in poses]
    assert mine == fresh
    assert 0 < sum(mine) < len(mine)  # both verdicts occur
