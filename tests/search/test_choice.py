"""The default answer: the search's best weighed against the simpler answers by predicted support."""

import json

import numpy as np
import pytest

import supportless as sl
from supportless.base.kinematics import euler_to_matrix
from supportless.report.report import build_report
from supportless.search.choice import KINDS, choose_by_model, print_distance_deg

SMALL = {"particles": 40, "iterations": 15, "seed": 1, "symmetric": False}  # one search: the choice alone


@pytest.fixture(scope="module")
def found(branch_rig):
    return sl.optimize(branch_rig, **SMALL)


def test_every_kind_of_answer_is_weighed_and_reported(branch_rig, found):
    choice = found.choice
    assert choice is not None and choice.by == "model"
    assert {c.kind for c in choice.candidates} == set(KINDS)
    assert choice.candidates[0].kind == "pose and turn"
    assert found.choice.chosen_kind == choice.candidates[choice.chosen].kind
    np.testing.assert_allclose(found.angles, choice.candidates[choice.chosen].result.angles)
    np.testing.assert_allclose(found.rotation, choice.candidates[choice.chosen].result.rotation)
    report = json.loads(json.dumps(build_report(branch_rig, found)))
    entries = report["choice"]["candidates"]
    assert [e["kind"] for e in entries] == [c.kind for c in choice.candidates]
    assert sum(e["chosen"] for e in entries) == 1 and entries[choice.chosen]["chosen"]
    assert report["choice"]["by"] == "model" and report["choice"]["reason"]
    assert all(e["sliced_mm"] is None for e in entries)
    # the chosen answer's predicted support is the report's prediction for the written pose (a second path)
    assert entries[choice.chosen]["predicted_mm"] == pytest.approx(report["predicted_slicer"]["after_mm"], abs=0.1)
    assert report["choice"]["rest_predicted_mm"] == pytest.approx(report["predicted_slicer"]["before_mm"], abs=0.1)


def test_the_simpler_answers_are_what_they_say(branch_rig, found):
    kinds = {}
    for c in found.choice.candidates:
        kinds.setdefault(c.kind, []).append(c.result)
    for r in kinds["pose"]:  # printed as the model stands
        np.testing.assert_allclose(r.rotation, np.eye(3), atol=1e-12)
    for r in kinds["turn"]:  # the rest pose, turned
        np.testing.assert_allclose(r.angles, 0.0, atol=1e-12)
    # the pose phase's best is the pose-only search's answer (same swarm, same seed)
    keep = sl.optimize(branch_rig, orient="keep", **SMALL)
    np.testing.assert_allclose(kinds["pose"][0].angles, keep.angles, atol=1e-9)
    assert kinds["pose"][0].value == pytest.approx(keep.value, rel=1e-9)


def test_choose_false_is_the_search_best(branch_rig, found):
    plain = sl.optimize(branch_rig, choose=False, **SMALL)
    assert plain.choice is None
    first = found.choice.candidates[0].result
    np.testing.assert_allclose(plain.angles, first.angles)
    np.testing.assert_allclose(plain.rotation, first.rotation)
    assert plain.value <= min(c.result.value for c in found.choice.candidates) + 1e-12


def test_keep_searches_weigh_nothing(branch_rig):
    assert sl.optimize(branch_rig, orient="keep", particles=10, iterations=3).choice is None


def test_model_choice_least_predicted_unless_a_tie_is_better_by_the_objective():
    predicted, values = np.array([100.0, 90.0, 95.0]), np.array([1.0, 3.0, 2.0])
    assert choose_by_model(predicted, values, 1000.0, 0.0)[0] == 1
    index, reason = choose_by_model(predicted, values, 1000.0, 0.006)  # a window of 6 mm: 90 and 95 tie
    assert index == 2 and "lower objective" in reason
    assert choose_by_model(predicted, values, 1000.0, 0.2)[0] == 0  # all tie: the least objective
    assert choose_by_model(predicted, values, 0.0, 0.2)[0] == 1  # no rest support: no window


def test_print_distance_ignores_a_spin_on_the_plate():
    up = np.array([0.0, 1.0, 0.0])
    A = np.zeros((2, 3))
    spin = euler_to_matrix(np.array([0.0, 0.7, 0.0]))  # about +Y, the up direction
    tilt = euler_to_matrix(np.array([np.radians(30.0), 0.0, 0.0]))
    assert print_distance_deg(A, np.eye(3), A, spin, up) == pytest.approx(0.0, abs=1e-6)
    assert print_distance_deg(A, np.eye(3), A, tilt, up) == pytest.approx(30.0, abs=1e-6)
    bent = A.copy()
    bent[1, 2] = np.radians(45.0)
    assert print_distance_deg(A, spin, bent, spin, up) == pytest.approx(45.0, abs=1e-6)


def test_an_answer_that_crosses_itself_as_written_is_passed_over_for_the_next(branch_rig, monkeypatch):
    """The model's first pick crossing itself on the full surface (a proxy's pose can): the next is chosen,
    not the rest pose that the written-file check would fall back to."""
    from supportless.search import choice as choice_mod

    search = sl.optimize(branch_rig, **SMALL, choose=False)
    plain = choice_mod.choose(branch_rig, search)
    first = plain.choice.chosen
    asked = []

    def crosses(rig, result, rest_pairs):
        asked.append(rest_pairs)
        return result is plain.choice.candidates[first].result or np.array_equal(
            result.print_vertices, plain.choice.candidates[first].result.print_vertices)

    monkeypatch.setattr(choice_mod, "crosses_as_written", crosses)
    again = choice_mod.choose(branch_rig, search)
    assert again.choice.chosen != first and f"#{first + 1}" in again.choice.reason
    assert asked and asked[0] == 0  # the branch's rest pose crosses itself nowhere
    predicted = [c.predicted_mm for i, c in enumerate(again.choice.candidates) if i != first]
    assert again.choice.candidates[again.choice.chosen].predicted_mm <= min(predicted) + \
        choice_mod.PREDICTION_TOLERANCE * again.choice.rest_mm + 1e-9


def test_the_choice_refuses_turns_resting_on_less_than_the_bound():
    from types import SimpleNamespace

    from supportless.search.choice import Candidate, resting_on_area

    turn = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])

    def answer(rotation, footprint, same_as=None):
        return Candidate("turn", SimpleNamespace(rotation=rotation), 100.0, same_as=same_as, footprint_mm2=footprint)

    standing, tip, flat = answer(np.eye(3), 0.5), answer(turn, 1.0), answer(turn, 40.0, same_as=1)
    kept = resting_on_area([standing, tip, flat], 3.0)
    assert kept == [standing, flat]  # as it stands it rests as made; the tip is refused
    assert flat.same_as is None  # it pointed at the refused one
    assert resting_on_area([tip], 3.0) == [tip]  # nothing rests on enough: the one resting on the most is kept
    assert resting_on_area([standing, tip], 0.0) == [standing, tip]  # the rule off


def test_the_choice_refuses_answers_weaker_than_both_the_rest_pose_and_the_floor(monkeypatch):
    """A weak answer is refused only when it is below both; the strongest stays when every one is; the record says
    when strength changed the slicer model's choice."""
    from types import SimpleNamespace

    import supportless.search.choice as choice_mod
    from supportless.search.choice import Candidate, strength_record, strong_enough

    def answer(factor, predicted, value=1.0):
        result = SimpleNamespace(angles=np.full((1, 3), factor), rotation=np.eye(3), value=value)
        return Candidate("pose", result, predicted)

    def strength(_rig, angles, _rotation, _height, _material):  # the safety factor rides on the angles
        factor = float(angles[0, 0])
        return SimpleNamespace(safety_factor=factor, weakest=SimpleNamespace(breaks_at_n=2.0 * factor))

    monkeypatch.setattr(choice_mod, "pose_strength", strength)
    monkeypatch.setattr(choice_mod, "pose_strengths", lambda *_args: None)  # the analyses on two cores: none here
    rig = SimpleNamespace(dim=3, rest_angles=lambda: np.full((1, 3), 0.5))  # the rest pose's factor: 0.5
    settings = sl.SearchSettings().replace(min_safety=1.0)
    weak, under_floor, strong = answer(0.2, 10.0), answer(0.6, 50.0), answer(3.0, 80.0)
    kept, record = strong_enough(rig, [weak, under_floor, strong], settings)
    assert kept == [under_floor, strong]  # 0.6 is under the floor but over the rest pose's 0.5: kept
    assert record["refused"] == [weak] and weak.safety_factor == 0.2 and weak.breaks_at_n == 0.4
    summary = strength_record(record, kept, 0, rest_mm=100.0)
    assert summary["changed_choice"] and "0.4 N" in summary["changed_reason"]  # the least support was the weak one
    # as strong as the rest pose within REST_STRENGTH_TOLERANCE counts as strong as it (the analysis moves that
    # much when the rest pose is turned a degree or two); below that, refused
    tolerance = choice_mod.REST_STRENGTH_TOLERANCE
    near, under = answer(0.5 * (1 - 0.9 * tolerance), 20.0), answer(0.5 * (1 - 1.1 * tolerance), 15.0)
    kept, record = strong_enough(rig, [under, near, strong], settings)
    assert kept == [near, strong] and record["refused"] == [under]
    # a stronger rest pose: the floor decides
    rig_strong = SimpleNamespace(dim=3, rest_angles=lambda: np.full((1, 3), 5.0))
    kept, _ = strong_enough(rig_strong, [answer(0.2, 10.0), answer(1.5, 50.0)], settings)
    assert [c.safety_factor for c in kept] == [1.5]
    # every answer weak: the strongest is kept
    kept, record = strong_enough(rig_strong, [answer(0.2, 10.0), answer(0.3, 50.0)], settings)
    assert [c.safety_factor for c in kept] == [0.3]
    # strength not weighed
    off = [answer(0.2, 10.0)]
    assert strong_enough(rig, off, settings.replace(min_safety=0.0)) == (off, None) and off[0].safety_factor is None
