"""The slicer's choice among the best answers (and the command line's default around it)."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from slicers import fake_exe, stand_in_slicer

import supportless as sl
from supportless.apps.cli import main
from supportless.search.choice import KINDS, print_distance_deg
from supportless.search.optimizer import DISTINCT_DEGREES
from supportless.slicing.ranking import SLICE_RANK, SLICER_NOISE, distinct_poses, pick_sliced, slice_choice, to_slice


class _FakeSlices:
    def __init__(self, support):
        self.support_mm = support


def _fake_slicer(support_of):
    """A stand-in for slice_support: the support of each mesh by ``support_of(V)``; records its calls."""
    calls = []

    def fake(meshes, up, scale, timeout, **options):
        calls.append({"meshes": meshes, "up": up, "scale": scale, **options})
        return _FakeSlices([support_of(V) for V, _ in meshes])

    return fake, calls


@pytest.fixture(scope="module")
def found(branch_rig):
    return sl.optimize(branch_rig, particles=40, iterations=15, seed=1)


def _index_of(choice, V):
    return next(i for i, c in enumerate(choice.candidates) if np.allclose(c.result.print_vertices, V))


def test_to_slice_takes_the_model_choice_then_one_of_each_kind_and_no_copies(found):
    choice = found.choice
    picked = to_slice(choice, 10, window=1e9)
    assert picked[0] == choice.model_chosen and len(set(picked)) == len(picked)
    kinds = [choice.candidates[i].kind for i in picked]
    assert set(kinds) == {c.kind for c in choice.candidates if c.same_as is None} | {kinds[0]}
    for a in picked:
        for b in picked:
            if a < b:
                ra, rb = choice.candidates[a].result, choice.candidates[b].result
                assert print_distance_deg(ra.angles, ra.rotation, rb.angles, rb.rotation, choice.up) >= \
                    DISTINCT_DEGREES
    assert to_slice(choice, 1) == [choice.model_chosen]
    # a window of nothing keeps only the answers with the least predicted support (and the model's choice)
    least = min(c.predicted_mm for c in choice.candidates)
    assert all(choice.candidates[i].predicted_mm == least for i in to_slice(choice, 10, window=0.0)[1:])
    with pytest.raises(ValueError):
        to_slice(choice, 0)


@pytest.mark.parametrize("kind", KINDS)
def test_the_answer_the_slicer_finds_cheapest_is_chosen(branch_rig, found, kind):
    choice = found.choice
    picked = to_slice(choice, 10, window=1e9)
    of_kind = [i for i, c in enumerate(choice.candidates) if c.kind == kind]
    # an answer that prints like an earlier one of another kind is that one (the search kept the rest pose, turned)
    target = next((i for i in picked if i in of_kind), choice.candidates[of_kind[0]].same_as)
    assert target in picked

    def support_of(V):
        return 10.0 if _index_of(choice, V) == target else 500.0 + _index_of(choice, V)

    fake, calls = _fake_slicer(support_of)
    chosen = slice_choice(branch_rig, found, 10, window=1e9, slice_fn=fake)
    assert len(calls) == 1 and calls[0]["workers"] == 2 and calls[0]["by_feature"]
    assert len(calls[0]["meshes"]) == len(picked)
    assert chosen.choice.by == "slicer" and chosen.choice.chosen == target
    assert chosen.choice.chosen_kind == chosen.choice.candidates[target].kind
    assert min(print_distance_deg(chosen.angles, chosen.rotation, choice.candidates[i].result.angles,
                                  choice.candidates[i].result.rotation, choice.up) for i in of_kind) < 0.5
    np.testing.assert_allclose(chosen.print_vertices, choice.candidates[target].result.print_vertices)
    report = chosen.choice.to_dict()
    assert [e["sliced_mm"] is not None for e in report["candidates"]] == \
        [i in picked for i in range(len(choice.candidates))]
    assert report["candidates"][target]["chosen"] and report["by"] == "slicer"


def test_the_model_choice_stays_within_the_slicer_noise(branch_rig, found):
    choice = found.choice
    picked = to_slice(choice, 10, window=1e9)
    assert len(picked) >= 2

    def support_of(V):
        return 100.0 if _index_of(choice, V) == choice.model_chosen else 100.0 * (1 - SLICER_NOISE / 2)

    fake, _ = _fake_slicer(support_of)
    chosen = slice_choice(branch_rig, found, 10, window=1e9, slice_fn=fake)
    assert chosen.choice.chosen == choice.model_chosen and "kept" in chosen.choice.reason
    assert pick_sliced([4, 2], [100.0, 50.0])[0] == 2
    assert pick_sliced([4, 2], [100.0, 100.0])[0] == 4


def test_nothing_is_sliced_when_one_answer_is_left(branch_rig, found):
    fake, calls = _fake_slicer(lambda V: 1.0)
    chosen = slice_choice(branch_rig, found, 1, slice_fn=fake)
    assert calls == [] and chosen.choice.by == "model" and "nothing to slice" in chosen.choice.reason
    np.testing.assert_allclose(chosen.angles, found.angles)


def test_a_keep_search_is_ranked_among_its_own_distinct_poses(branch_rig):
    kept = sl.optimize(branch_rig, particles=40, iterations=15, seed=1, orient="keep")
    poses = distinct_poses(branch_rig, kept, 4)
    fake, calls = _fake_slicer(lambda V: float(V[:, 0].max()))
    chosen = slice_choice(branch_rig, kept, 4, window=1e9, slice_fn=fake)
    assert {c.kind for c in chosen.choice.candidates} == {"pose"}
    assert len(calls[0]["meshes"]) <= len(poses)
    np.testing.assert_allclose(chosen.rotation, np.eye(3))


@pytest.mark.slow
def test_slice_choice_with_the_real_slicer_keeps_what_it_measures_cheapest(branch_rig, found, prusa_slicer):
    """Integration: PrusaSlicer slices the answers; the chosen one has the least support it measured (or the
    model's choice within the noise), and slicing it again gives the same figure."""
    from supportless.slicing.prusaslicer import scale_for_height, slice_support

    chosen = slice_choice(branch_rig, found, 3, window=1e9)
    sliced = [c.sliced_mm for c in chosen.choice.candidates if c.sliced_mm is not None]
    assert len(sliced) >= 2 and all(np.isfinite(x) and x >= 0 for x in sliced)
    mine = chosen.choice.candidates[chosen.choice.chosen].sliced_mm
    assert mine <= min(sliced) / (1 - SLICER_NOISE) + 1e-9
    again = slice_support([(chosen.print_vertices, branch_rig.faces)], branch_rig.up,
                          scale_for_height(branch_rig.vertices, branch_rig.up, 60.0), by_feature=True).support_mm[0]
    assert again == pytest.approx(mine, rel=1e-3, abs=0.5)


def _run(tmp_path, *extra):
    out_stl, report = tmp_path / "out.stl", tmp_path / "report.json"
    r = CliRunner().invoke(main, ["optimize", "demo:branch", "--particles", "30", "--iterations", "10",
                                  "-o", str(out_stl), "--report", str(report), "--cache-dir",
                                  str(tmp_path / "cache"), *extra])
    assert r.exit_code == 0, r.output
    return r, json.loads(report.read_text())


def test_cli_default_slices_the_answers_with_the_slicer_it_finds(tmp_path, monkeypatch):
    """The default: PrusaSlicer (here a stand-in) is found, so it chooses, and the report lists every answer."""
    exe = fake_exe(tmp_path, "stand-in-slicer", stand_in_slicer("float(np.ptp(rec['v'][..., 0]))"))
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", str(exe))
    r, data = _run(tmp_path)
    choice = data["choice"]
    assert choice["by"] == "slicer" and "chosen by PrusaSlicer" in r.output
    assert {e["kind"] for e in choice["candidates"]} == set(KINDS)
    sliced = [e for e in choice["candidates"] if e["sliced_mm"] is not None]
    assert 2 <= len(sliced) <= SLICE_RANK
    best = min(e["sliced_mm"] for e in sliced)
    mine = choice["candidates"][choice["chosen"] - 1]
    assert mine["chosen"] and mine["sliced_mm"] <= best / (1 - SLICER_NOISE) + 1e-9


def test_cli_without_a_slicer_the_model_chooses_and_says_so(tmp_path, monkeypatch):
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", str(tmp_path / "missing"))
    monkeypatch.setenv("SUPPORTLESS_CURA_ENGINE", str(tmp_path / "no-cura"))  # no slicer at all
    r, data = _run(tmp_path)
    assert data["choice"]["by"] == "model"
    assert "chosen by the slicer model (PrusaSlicer not found" in r.output
    assert all(e["sliced_mm"] is None for e in data["choice"]["candidates"])


def test_cli_slice_rank_0_is_the_plain_search_result(tmp_path, monkeypatch, branch_rig):
    exe = fake_exe(tmp_path, "stand-in-slicer", "raise SystemExit('must not be run')\n")
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", str(exe))
    r, data = _run(tmp_path, "--slice-rank", "0")
    assert data["choice"] is None and "chosen by" not in r.output
    plain = sl.optimize(branch_rig, particles=30, iterations=10, choose=False)
    np.testing.assert_allclose(np.radians(data["angles_deg"]), plain.angles, atol=1e-5)
    np.testing.assert_allclose(data["print_rotation"]["matrix"], plain.rotation, atol=1e-9)


def test_cli_slice_rank_without_a_slicer_stops_before_the_search(tmp_path, monkeypatch):
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", str(tmp_path / "missing"))
    monkeypatch.setenv("SUPPORTLESS_CURA_ENGINE", str(tmp_path / "no-cura"))  # no slicer at all
    r = CliRunner().invoke(main, ["optimize", "demo:branch", "--slice-rank", "2", "-o", str(tmp_path / "o.stl")])
    assert r.exit_code == 3
    assert "--slice-rank needs PrusaSlicer" in r.output and not (tmp_path / "o.stl").exists()
