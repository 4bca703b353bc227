"""Slice-ranking: the cheapest of the search's distinct good poses, by a slicer."""

import numpy as np
import pytest
from slicers import fake_exe, stand_in_slicer

import supportless as sl
from supportless.ranking import candidate_result, slice_rank


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
def searched(branch_rig):
    return sl.optimize(branch_rig, particles=40, iterations=15, seed=1, orient="keep")


def test_slice_rank_picks_the_cheapest_distinct_pose(branch_rig, searched):
    heights = []

    def support_of(V):  # pretend the slicer wants the lowest tip: support grows with x of the highest vertex
        heights.append(float(V[:, 0].max()))
        return 100.0 + 10.0 * float(V[np.argmax(V @ branch_rig.up), 0])

    fake, calls = _fake_slicer(support_of)
    ranked = slice_rank(branch_rig, searched, 4, slice_fn=fake, tolerance=10.0)
    assert len(calls) == 1 and calls[0]["workers"] == 2  # one batch, two at a time
    n = len(ranked.entries)
    assert 2 <= n <= 4
    support = [e["support_mm"] for e in ranked.entries]
    assert ranked.chosen == int(np.argmin(support))
    assert ranked.entries[ranked.chosen]["chosen"] and sum(e["chosen"] for e in ranked.entries) == 1
    assert ranked.entries[0]["rank"] == 1 and ranked.entries[0]["distance_deg"] == 0.0
    assert ranked.entries[0]["value"] == pytest.approx(searched.value)
    # the result is the chosen pose, and what was sliced is its print-frame surface
    chosen = ranked.result
    np.testing.assert_allclose(calls[0]["meshes"][ranked.chosen][0], chosen.print_vertices)
    assert ranked.entries[ranked.chosen]["value"] == pytest.approx(chosen.value)
    # the poses are distinct and none self-intersects
    from supportless.copyleft.cgal import self_intersects
    from supportless.search import DISTINCT_DEGREES
    for e in ranked.entries[1:]:
        assert e["distance_deg"] >= DISTINCT_DEGREES
    for V, F in calls[0]["meshes"]:
        assert not self_intersects(V, F)
    d = ranked.to_dict()
    assert d["chosen_rank"] == ranked.chosen + 1 and len(d["candidates"]) == n


def test_slice_rank_with_the_real_slicer_keeps_the_pose_it_measures_cheapest(branch_rig, searched, prusa_slicer):
    """Integration: PrusaSlicer slices the distinct poses; the chosen one has the least support it measured."""
    from supportless.slicer import scale_for_height, slice_support

    ranked = slice_rank(branch_rig, searched, 3, tolerance=10.0)
    support = [e["support_mm"] for e in ranked.entries]
    assert len(support) >= 2 and all(np.isfinite(x) and x >= 0 for x in support)
    assert ranked.chosen == int(np.argmin(support))
    # slicing the chosen pose again gives the figure the ranking recorded (to the slicer's own noise)
    again = slice_support([(ranked.result.print_vertices, branch_rig.faces)], branch_rig.up,
                          scale_for_height(branch_rig.vertices, branch_rig.up, 60.0)).support_mm[0]
    assert again == pytest.approx(support[ranked.chosen], rel=1e-3)


def test_slice_rank_keeps_the_search_result_when_the_slicer_agrees(branch_rig, searched):
    first = np.asarray(searched.print_vertices)

    def support_of(V):  # the search's own pose is the cheapest
        return 0.0 if np.allclose(V, first) else 50.0

    fake, _ = _fake_slicer(support_of)
    ranked = slice_rank(branch_rig, searched, 3, slice_fn=fake, tolerance=10.0)
    assert ranked.chosen == 0 and ranked.result is searched


def test_slice_rank_with_one_pose_slices_only_the_result(branch_rig, searched):
    fake, calls = _fake_slicer(lambda V: 7.0)
    ranked = slice_rank(branch_rig, searched, 1, slice_fn=fake)
    assert len(calls[0]["meshes"]) == 1 and ranked.result is searched and ranked.entries[0]["support_mm"] == 7.0
    with pytest.raises(ValueError):
        slice_rank(branch_rig, searched, 0, slice_fn=fake)


def test_candidate_result_measures_the_new_pose(branch_rig, searched):
    A = searched.candidates["angles"][-1]
    R = np.eye(3)
    res = candidate_result(branch_rig, searched, A, R)
    assert res.value == pytest.approx(float(searched.objective(A[None])[0]), rel=1e-9)
    np.testing.assert_allclose(res.angles, A)
    assert float((res.vertices @ branch_rig.up).min()) == pytest.approx(0.0, abs=1e-12)


def test_cli_slice_rank_with_a_stand_in_slicer(tmp_path, monkeypatch):
    """The command line slices the candidates with the executable it finds and reports them all."""
    import json

    from click.testing import CliRunner

    from supportless.cli import main

    exe = fake_exe(tmp_path, "stand-in-slicer", stand_in_slicer("float(np.ptp(rec['v'][..., 0]))"))
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", str(exe))
    out_stl, report = tmp_path / "out.stl", tmp_path / "report.json"
    r = CliRunner().invoke(main, ["optimize", "demo:branch", "--particles", "30", "--iterations", "10",
                                  "--orient", "keep", "--slice-rank", "3", "-o", str(out_stl),
                                  "--report", str(report), "-q", "--cache-dir", str(tmp_path / "cache")])
    assert r.exit_code == 0, r.output
    data = json.loads(report.read_text())
    cands = data["slice_rank"]["candidates"]
    assert 1 <= len(cands) <= 3 and cands[0]["rank"] == 1
    best = min(range(len(cands)), key=lambda i: cands[i]["support_mm"])
    assert data["slice_rank"]["chosen_rank"] == best + 1
    assert "PrusaSlicer support" in r.output and out_stl.is_file()


def test_cli_slice_rank_without_a_slicer_stops_before_the_search(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from supportless.cli import main

    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", str(tmp_path / "missing"))
    r = CliRunner().invoke(main, ["optimize", "demo:branch", "--slice-rank", "2", "-o", str(tmp_path / "o.stl")])
    assert r.exit_code == 3
    assert "--slice-rank needs PrusaSlicer" in r.output and not (tmp_path / "o.stl").exists()
