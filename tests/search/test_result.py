"""The last gate (:func:`supportless.search.answer.as_written`): what goes to the file never intersects itself more than rest."""

from __future__ import annotations

import dataclasses

import numpy as np

import supportless as sl
from supportless.base.geometry import place_on_plate, print_pose
from supportless.copyleft.cgal import intersecting_face_pairs, self_intersects
from supportless.search.answer import as_written
from supportless.search.result import measured_at


def intersecting_pose(rig, rng):
    """A pose of ``rig`` whose surface crosses itself (large random turns until one does)."""
    for _ in range(200):
        angles = rng.uniform(-2.5, 2.5, (rig.bone_count, 3))
        if self_intersects(rig.pose(angles), rig.faces):
            return angles
    raise AssertionError("no intersecting pose found")


def test_a_found_pose_that_intersects_as_written_gives_way_to_the_rest_pose(tpose_rig):
    rig = tpose_rig
    found = sl.optimize(rig, particles=6, iterations=2, seed=0)
    assert found.written.written_pairs == 0 and found.written.fell_back_to_rest is None
    bad_angles = intersecting_pose(rig, np.random.default_rng(1))
    bad = dataclasses.replace(measured_at(rig, found, bad_angles, found.rotation), choice=None)  # no other answers
    gated = as_written(rig, bad)
    assert gated.written.fell_back_to_rest == intersecting_face_pairs(bad.print_vertices, rig.faces) > 0
    np.testing.assert_array_equal(gated.angles, 0.0)
    assert gated.written.written_pairs == intersecting_face_pairs(gated.print_vertices, rig.faces) == 0
    # the rest pose as written: turned only when turning lowers the objective
    upright = measured_at(rig, found, np.zeros_like(bad_angles), np.eye(3))
    turned = measured_at(rig, found, np.zeros_like(bad_angles), bad.rotation)
    assert gated.value == min(upright.value, turned.value)


def test_the_gate_judges_the_written_mesh_not_the_pose_it_came_from(tpose_rig):
    """A result whose pose is clean but whose mesh as written (here: a proxy's, moved) crosses itself is refused."""
    rig = tpose_rig
    found = sl.optimize(rig, particles=6, iterations=2, seed=0)
    crossing = place_on_plate(rig.pose(intersecting_pose(rig, np.random.default_rng(2))), rig.up)
    assert not self_intersects(rig.pose(found.angles), rig.faces)
    written = dataclasses.replace(found, print_vertices=print_pose(crossing, found.rotation, rig.up), choice=None)
    gated = as_written(rig, written)
    assert gated.written.fell_back_to_rest > 0 and np.all(gated.angles == 0.0)


def test_without_exact_checks_the_result_is_left_as_it_is(tpose_rig):
    found = sl.optimize(tpose_rig, particles=6, iterations=2, seed=0, exact_intersections=False)
    assert found.written is None


def test_a_chosen_answer_crossing_itself_as_written_gives_way_to_the_next_clear_answer(branch_rig, monkeypatch):
    """A sculpt's answers are weighed on its reduced surface: the one chosen may cross itself at full resolution.
    The gate then takes the best predicted of the other answers that does not, not the rest pose. (No contact
    allowed: the stand-in pairs below are not placed anywhere a contact could be judged.)"""
    from supportless.search import answer as answer_mod
    from supportless.search import result as result_mod

    found = sl.optimize(branch_rig, particles=8, iterations=3, seed=0, contact=False)
    assert found.choice is not None and len(found.choice.candidates) >= 2
    chosen = found.choice.chosen
    bad = found.print_vertices.copy()
    real = result_mod.intersecting_faces

    def pairs(V, F):  # the chosen answer's file crosses itself in 4 places; every other is what CGAL says
        return np.zeros((4, 2), np.int64) if np.array_equal(V, bad) else real(V, F)

    for module in (answer_mod, result_mod):  # the gate's own counts and the verdict's
        monkeypatch.setattr(module, "intersecting_faces", pairs)
    gated = as_written(branch_rig, found)
    assert gated.written.fell_back_to_rest is None
    assert gated.written.passed_over_as_written == chosen + 1 and gated.choice.chosen != chosen
    assert f"#{chosen + 1} crossed itself at full resolution" in gated.choice.reason
    others = [c.predicted_mm for i, c in enumerate(found.choice.candidates) if i != chosen]
    assert gated.choice.candidates[gated.choice.chosen].predicted_mm == min(others)
    assert gated.written.written_pairs == 0
    np.testing.assert_array_equal(gated.angles, found.choice.candidates[gated.choice.chosen].result.angles)
    # no clear answer among those tried: the rest pose, as before
    for module in (answer_mod, result_mod):
        monkeypatch.setattr(module, "intersecting_faces",
                            lambda V, F: np.zeros((4, 2), np.int64) if not np.array_equal(V, branch_rig.vertices) and
                            not np.allclose(V, place_on_plate(branch_rig.vertices, branch_rig.up)) else real(V, F))
    assert as_written(branch_rig, found).written.fell_back_to_rest == 4
