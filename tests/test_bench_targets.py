"""``supportless bench --targets``: the speed cases, their table and what happens without the shared data."""

import igl
import numpy as np
import pytest

import supportless as sl
from supportless import bench_targets as bt
from supportless import rig as rig_mod


@pytest.fixture(scope="module")
def dense_branch():
    """The branch subdivided twice, prepared with a proxy (the thresholds lowered to its size)."""
    V, F, J, B = sl.demo_figure("branch")
    V2, F2 = igl.upsample(V, F.astype(np.int64), 2)
    mp = pytest.MonkeyPatch()
    mp.setattr(rig_mod, "PROXY_FACES", len(F2) - 1)
    mp.setattr(rig_mod, "PROXY_TARGET", len(F2) // 8)
    try:
        return sl.prepare_rig(V2, F2, J, B, "y", name="dense")
    finally:
        mp.undo()


def test_a_case_is_measured_against_its_full_resolution_reference(dense_branch, monkeypatch):
    monkeypatch.setattr(bt, "_prepare", lambda case, cache: dense_branch)
    row = bt.measure_case("character", reference=True, settings=sl.SearchSettings(particles=16, iterations=6))
    assert row["faces"] == len(dense_branch.faces) and row["proxy_faces"] == len(dense_branch.coarse_faces)
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
