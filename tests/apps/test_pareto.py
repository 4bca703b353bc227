"""The front of least support against least distortion (issue 16)."""

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import supportless as sl
from supportless.apps.pareto import SAME_DEGREES, non_dominated, pareto_front, spread, sweep_factors
from supportless.copyleft.cgal import self_intersects
from supportless.search.optimizer import pose_distance_deg


def test_non_dominated_on_known_points():
    s = np.array([1.0, 2.0, 3.0, 2.0, 1.0, 4.0])
    d = np.array([5.0, 3.0, 1.0, 4.0, 5.0, 1.0])
    # 3 (2, 4) is beaten by 1 (2, 3); 4 ties 0 exactly (the first kept); 5 (4, 1) is beaten by 2 (3, 1)
    assert non_dominated(s, d).tolist() == [True, True, True, False, False, False]
    # brute force on random points: kept points are beaten by none, dropped ones by some
    rng = np.random.default_rng(0)
    P = rng.random((60, 2))
    keep = non_dominated(P[:, 0], P[:, 1])
    for i in range(len(P)):
        beaten = np.any(np.all(P <= P[i], axis=1) & np.any(P < P[i], axis=1))
        assert keep[i] == (not beaten)


def test_spread_keeps_both_ends_and_fills_the_largest_gaps():
    P = np.array([[0.0, 10.0], [0.1, 9.9], [0.2, 9.8], [5.0, 5.0], [9.9, 0.1], [10.0, 0.0]])
    assert spread(P, 3) == [0, 3, 5]
    assert spread(P, 10) == list(range(6))
    assert spread(P, 2) == [0, 5]


def test_sweep_factors_are_symmetric_about_the_default():
    f = sweep_factors(5)
    np.testing.assert_allclose(f * f[::-1], 1.0)
    assert f[2] == pytest.approx(1.0) and f[0] == pytest.approx(0.25)
    assert sweep_factors(1).tolist() == [1.0]
    assert 1.0 in sweep_factors(4).tolist()  # the default weights are always among them
    with pytest.raises(ValueError):
        sweep_factors(0)


@pytest.fixture(scope="module", params=["nsga2", "sweep"])
def tpose_front(tpose_rig, request):
    settings = sl.SearchSettings(particles=40, iterations=16, seed=2)
    return tpose_rig, settings, pareto_front(tpose_rig, settings, 4, method=request.param)


def test_the_same_seed_gives_the_same_front(tpose_rig):
    settings = sl.SearchSettings(particles=16, iterations=4, seed=5)
    a, b = (pareto_front(tpose_rig, settings, 3) for _ in range(2))
    assert [p.support for p in a.poses] == [p.support for p in b.poses]


def test_the_front_is_spread_non_dominated_and_keeps_the_rules(tpose_front):
    rig, settings, front = tpose_front
    poses = front.poses
    assert 2 <= len(poses) <= 4
    s = np.array([p.support for p in poses])
    d = np.array([p.distortion for p in poses])
    assert np.all(np.diff(s) >= 0)  # least support first
    assert non_dominated(s, d).all()
    assert np.all(np.diff(d) < 0)  # so, along the front, distortion falls as support grows
    for i, p in enumerate(poses):
        r = p.result
        assert r.terms["violation"] == 0.0 and not self_intersects(rig.pose(r.angles), rig.faces)
        for q in poses[:i]:
            assert pose_distance_deg(r.angles, r.rotation, q.result.angles, q.result.rotation) >= SAME_DEGREES
        # the recorded measures are those of the pose, with the default weights
        assert p.distortion == pytest.approx(settings.w_arap * r.terms["arap"] + settings.w_prior * r.terms["prior"],
                                             rel=1e-9, abs=1e-12)
    # the default is the search at the settings' own weights
    assert front.default.settings.w_arap == settings.w_arap and front.default.settings.iterations == 16


def test_the_least_support_end_is_no_worse_than_the_single_search(tpose_front):
    rig, settings, front = tpose_front
    from supportless.report.report import predicted_slicer

    single = predicted_slicer(rig, front.default)["after_mm"]
    assert front.poses[0].support <= single + 1e-9


def test_cli_writes_the_front_beside_the_output(tmp_path, branch_files):
    from supportless.apps.cli import main

    out = tmp_path / "posed.stl"
    r = CliRunner().invoke(main, ["optimize", str(branch_files["mesh"]), "--cache-dir", str(branch_files["cache"]),
                                  "--particles", "12", "--iterations", "6", "--pareto", "3", "-q", "-o", str(out),
                                  "--report", str(tmp_path / "r.json")])
    assert r.exit_code == 0, r.output
    report = json.loads((tmp_path / "r.json").read_text())
    front = report["pareto"]
    assert 1 <= len(front) <= 3 and report["pareto_seconds"] > 0
    for k, entry in enumerate(front, 1):
        assert entry["mesh"] == str(tmp_path / f"posed-{k}.stl") and (tmp_path / f"posed-{k}.stl").is_file()
        angles = sl.read_pose(entry["pose"], branch_files["bones"])
        assert angles.shape == (3, 3)
    assert [e["support"] for e in front] == sorted(e["support"] for e in front)
    assert (tmp_path / "posed-front.png").stat().st_size > 0 and out.is_file()


def test_cli_refuses_pareto_with_slice_rank(tmp_path, branch_files):
    from supportless.apps.cli import main

    r = CliRunner().invoke(main, ["optimize", str(branch_files["mesh"]), "--pareto", "3", "--slice-rank", "2",
                                  "-o", str(tmp_path / "o.stl")])
    assert r.exit_code != 0 and "--pareto and --slice-rank" in r.output + (r.stderr if r.stderr_bytes else "")


def test_cli_front_of_a_gltf_character(tmp_path, shared_data):
    from supportless.apps.cli import main

    r = CliRunner().invoke(main, ["optimize", str(shared_data / "gltf" / "Fox.glb"), "--particles", "12",
                                  "--iterations", "3", "--pareto", "2", "-q", "-o", str(tmp_path / "fox.glb"),
                                  "--cache-dir", str(tmp_path / "cache"), "--report", str(tmp_path / "r.json")])
    assert r.exit_code == 0, r.output
    front = json.loads((tmp_path / "r.json").read_text())["pareto"]
    assert front and all(Path(e["mesh"]).is_file() and Path(e["pose"]).is_file() for e in front)
    assert (tmp_path / "fox.glb").is_file() and (tmp_path / "fox-front.png").is_file()
