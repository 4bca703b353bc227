"""``supportless bench --targets``: the speed cases, their table and what happens without the shared data."""

import pytest

import supportless as sl
from supportless.apps import bench_targets as bt


@pytest.mark.slow
def test_a_case_is_measured_against_its_full_resolution_reference(dense_branch, monkeypatch):
    rig = dense_branch[0]  # a rig with a proxy (conftest.py)
    monkeypatch.setattr(bt, "_prepare", lambda case, cache: rig)
    row = bt.measure_case("character", reference=True, settings=sl.SearchSettings(particles=16, iterations=6, polish=4))  # a short polish: the search's length is not the subject
    assert row["faces"] == len(rig.faces) and row["proxy_faces"] == len(rig.coarse_faces)
    assert row["bones"] == 3 and row["free_bones"] >= 1
    assert row["pairs"] == 0 and row["ref_pairs"] == 0
    assert 0 < row["reduction"] <= 100 and 0 < row["ref_reduction"] <= 100
    # the reference searches the full surface: another (slower) search, measured the same way
    assert row["ref_search_s"] > 0 and row["value"] > 0 and row["ref_value"] > 0
    assert row["peak_mb"] > 0
    line = bt.format_table([row]).splitlines()[-1]
    assert line.startswith("| character |") and f"({row['proxy_faces']})" in line and "search ≤ 20 s" in line
    assert f"{row['ref_reduction']:.1f} %" in line


def test_missing_shared_data_skips_its_cases_with_the_reason(tmp_path, monkeypatch):
    monkeypatch.setattr(bt, "SHARED_DATA", tmp_path)
    said = []
    rows = bt.run_targets(cases=("bunny", "robot"), echo=said.append)
    assert [r["case"] for r in rows] == ["bunny", "robot"] and all(r["missing"] for r in rows)
    assert "bunny.obj" in rows[0]["error"] and "RobotExpressive.glb" in rows[1]["error"]
    assert any(line.startswith("robot: skipped:") for line in said)
    table = said[-1]
    assert "| bunny | skipped:" in table and "search ≤ 4 s" in table and "cores" in table


def test_a_case_without_a_proxy_is_its_own_reference():
    row = {"case": "bunny", "faces": 6966, "proxy_faces": None, "bones": 11, "free_bones": 7, "prepare_s": 3.0,
           "search_s": 10.0, "peak_mb": 300.0, "reduction": 60.0, "distortion": 0.01, "value": 0.4, "pairs": 0}
    line = bt.format_table([row]).splitlines()[-1]
    assert "the same search" in line and "| 6966 |" in line and "11 (7)" in line


def test_a_sculpt_is_reported_end_to_end_against_its_target(tmp_path, monkeypatch):
    row = {"case": "bunny4", "faces": 1783296, "bones": 11, "end_to_end_s": 50.0, "peak_mb": 2900.0,
           "reduction": 40.0, "distortion": 0.01, "value": 0.4, "pairs": 0}
    table = bt.format_table([row])
    assert "| bunny4 | 1783296 | 11 | 50.0 s | 2900 MB |" in table and "end to end ≤ 60 s, ≤ 3 GB" in table
    monkeypatch.setattr(bt, "SHARED_DATA", tmp_path)  # no bunny: skipped, nothing made
    rows = bt.run_targets(cases=("bunny5m",), echo=lambda s: None)
    assert rows[0]["missing"] and "bunny.obj" in rows[0]["error"]
