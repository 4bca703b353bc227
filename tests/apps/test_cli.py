"""The ``supportless`` command line: smoke tests and one-line errors with exit status 2.

Most commands run in-process with click's CliRunner (fast: the package and its
compiled kernels load once); one test runs the installed executable to check
what a user really sees on stderr.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import NO_SLICER

import supportless as sl
from supportless.apps.cli import main
from supportless.base.geometry import place_on_plate
from supportless.files.printframe import print_frame

EXE = Path(sys.executable).with_name("supportless")


def run(*args, env=None):
    """Run the CLI in-process; returns the click Result (stdout and stderr kept apart)."""
    return CliRunner().invoke(main, [str(a) for a in args], env=env, catch_exceptions=True)


def assert_user_error(result, *fragments):
    """Exit status 2 and exactly one line on stderr: 'supportless: error: ...'."""
    assert result.exit_code == 2, (result.exit_code, result.output, result.exception)
    assert isinstance(result.exception, SystemExit), repr(result.exception)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("supportless: error: "), lines[0]
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def optimized(tmp_path_factory, branch_files):
    """One tiny search of the branch figure with every output asked for (the slicer model chooses: no slicer)."""
    out = tmp_path_factory.mktemp("optimize")
    result = run("optimize", branch_files["mesh"], "--skeleton", branch_files["skeleton"],
                 "--cache-dir", branch_files["cache"], "--particles", 6, "--iterations", 3, "--seed", 5, "-q",
                 "-o", out / "posed.obj", "--pose", out / "pose.json", "--report", out / "report.json",
                 "--pictures", out / "pictures", env=NO_SLICER)
    return out, result


# ------------------------------------------------------------------------ smoke


def test_prepare_prints_the_rig(branch_files):
    args = ("prepare", branch_files["mesh"], "--skeleton", branch_files["skeleton"],
            "--cache-dir", branch_files["cache"])
    first = run(*args)
    assert first.exit_code == 0, first.output
    rig = sl.load_rig(branch_files["mesh"], branch_files["skeleton"], cache_dir=branch_files["cache"])
    assert (f"branch: {len(rig.vertices)} vertices, {len(rig.faces)} faces, {len(rig.tets)} tets, "
            f"3 bones, 3D") in first.stdout
    second = run(*args)
    assert second.exit_code == 0 and "from the cache" in second.stdout


def test_prepare_finds_the_skeleton_beside_the_model(branch_files):
    result = run("prepare", branch_files["mesh"], "--cache-dir", branch_files["cache"])
    assert result.exit_code == 0, result.output
    assert "3 bones" in result.stdout


@pytest.mark.slow
def test_optimize_writes_mesh_pose_report_and_pictures(optimized, branch_files):
    out, result = optimized
    assert result.exit_code == 0, (result.output, result.exception)
    V, F = sl.read_mesh(out / "posed.obj")
    assert F.shape == branch_files["F"].shape
    assert V[:, 2].min() == pytest.approx(0.0, abs=1e-6)  # placed on the build plate, +Z up
    angles = sl.read_pose(out / "pose.json", branch_files["bones"])
    from supportless.search.prior import joint_angles

    assert angles.shape == (3, 3)
    assert np.all(joint_angles(angles) <= np.radians(sl.SearchSettings().joint_limit) + 1e-9)
    report = json.loads((out / "report.json").read_text())
    for key in ("before", "after", "reduction_percent"):
        assert key in report
    for side in ("before", "after"):
        assert isinstance(report[side]["intersecting_face_pairs"], int)
        assert np.isfinite(report[side]["support_prism"])
    assert report["before"]["support_prism"] > 0  # the cantilevered arm of the rest pose needs support
    assert report["after"]["objective"] <= report["before"]["objective"] + 1e-12
    pictures = sorted(p.name for p in (out / "pictures").iterdir())
    assert pictures and all(name.endswith(".png") for name in pictures)
    assert all((out / "pictures" / name).stat().st_size > 1000 for name in pictures)
    # nothing else (no temporary files) in the output folder
    assert sorted(p.name for p in out.iterdir()) == ["pictures", "pose.json", "posed.obj", "report.json"]


@pytest.mark.slow
def test_optimize_is_reproducible_with_a_seed(optimized, branch_files, tmp_path, no_slicer):
    out, _ = optimized
    again = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 6,
                "--iterations", 3, "--seed", 5, "-q", "-o", tmp_path / "posed.stl", "--pose", tmp_path / "pose.json")
    assert again.exit_code == 0, again.output
    first = json.loads((out / "pose.json").read_text())
    second = json.loads((tmp_path / "pose.json").read_text())
    assert first["angles"] == second["angles"]


def test_apply_writes_the_posed_mesh(branch_files, tmp_path):
    B = branch_files["bones"]
    angles = np.zeros((len(B), 3))
    angles[1] = [0.0, 0.0, 0.6]  # lift the arm
    sl.write_pose(tmp_path / "pose.json", angles, B)
    result = run("apply", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--pose",
                 tmp_path / "pose.json", "-o", tmp_path / "posed.ply")
    assert result.exit_code == 0, result.output
    assert "posed.ply" in result.stdout
    V, F = sl.read_mesh(tmp_path / "posed.ply")
    rig = sl.load_rig(branch_files["mesh"], cache_dir=branch_files["cache"])
    expected = print_frame(rig.vertices, rig.up).place(rig.pose(angles))  # +Z up, 60 mm tall at rest, mm
    np.testing.assert_array_equal(F, rig.faces)
    np.testing.assert_allclose(V, expected, atol=1e-5)


def test_demo_2d(tmp_path):
    result = run("demo", "--figure", "woody2d", "--out", tmp_path / "demo", "--particles", 4, "--iterations", 2,
                 "-q", env={"SUPPORTLESS_CACHE": str(tmp_path / "cache")})
    assert result.exit_code == 0, (result.output, result.exception)
    names = {p.name for p in (tmp_path / "demo").iterdir()}
    assert {"woody2d-rest.obj", "woody2d.tgf", "woody2d-posed.obj", "woody2d-pose.json",
            "woody2d-report.json"} <= names
    V, F = sl.read_mesh(tmp_path / "demo" / "woody2d-posed.obj")
    assert np.all(V[:, 2] == 0)
    report = json.loads((tmp_path / "demo" / "woody2d-report.json").read_text())
    assert report["dimension"] == 2


@pytest.mark.slow
def test_demo_3d_writes_every_file(tmp_path, prusa_slicer):
    """The README's first command, on a small swarm: mesh, skeleton, pose, report, pictures, slicer figures."""
    out = tmp_path / "demo"
    result = run("demo", "--out", out, "--particles", 8, "--iterations", 3, "-q",
                 env={"SUPPORTLESS_CACHE": str(tmp_path / "cache")})
    assert result.exit_code == 0, (result.output, result.exception)
    names = {p.name for p in out.iterdir()}
    assert {"tpose-rest.stl", "tpose.tgf", "tpose-rest.png", "tpose-posed.stl", "tpose-pose.json",
            "tpose-report.json", "before_after.png", "convergence.png"} <= names
    report = json.loads((out / "tpose-report.json").read_text())
    assert report["dimension"] == 3 and report["after"]["intersecting_face_pairs"] == 0
    assert report["settings"]["particles"] == 8
    assert report["slice_check"]["before"]["support_mm"] > 0
    assert "(PrusaSlicer; printed 60 mm tall)" in " ".join(result.stdout.split())
    assert "60 particles" not in result.stdout and "8 particles x 3 iterations" in result.stdout
    V, _ = sl.read_mesh(out / "tpose-posed.stl")
    assert V[:, 2].min() == pytest.approx(0.0, abs=1e-6)
    R, _ = sl.read_mesh(out / "tpose-rest.stl")
    assert np.ptp(R[:, 2]) == pytest.approx(60.0, abs=1e-3)


def test_slice_check_without_the_slicer_keeps_every_output(branch_files, tmp_path):
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 4,
                 "--iterations", 1, "-q", "-o", tmp_path / "posed.stl", "--pose", tmp_path / "pose.json",
                 "--report", tmp_path / "report.json", "--slice-check",
                 env={"SUPPORTLESS_PRUSA_SLICER": str(tmp_path / "no-such-slicer"),
                      "SUPPORTLESS_CURA_ENGINE": str(tmp_path / "no-such-engine")})
    assert result.exit_code == 3, (result.output, result.exception)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "PrusaSlicer not found" in lines[0] and "apt-get install prusa-slicer" in lines[0]
    assert "Traceback" not in result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pose.json", "posed.stl", "report.json"]
    assert "slice_check" not in json.loads((tmp_path / "report.json").read_text())


def _interrupt_at(monkeypatch, call, how):
    """Patch the swarm's objective so that Ctrl-C arrives at its ``call``-th evaluation.

    ``how``: ``"signal"`` sends SIGINT to this process just before the evaluation (a real Ctrl-C,
    handled between bytecodes), ``"during"`` sends it from another thread while the compiled kernels
    run, ``"raise"`` raises KeyboardInterrupt there (as a second Ctrl-C does).
    """
    import os
    import signal
    import threading

    from supportless.search.objective import Objective

    calls = {"n": 0}
    bounded = Objective.bounded_overlap  # what the swarm calls once per evaluation

    def patched(self, angles, bound, rotations=None, **options):
        calls["n"] += 1
        if calls["n"] == call:
            if how == "raise":
                raise KeyboardInterrupt
            if how == "signal":
                os.kill(os.getpid(), signal.SIGINT)
            else:
                threading.Timer(0.001, os.kill, (os.getpid(), signal.SIGINT)).start()
        return bounded(self, angles, bound, rotations, **options)

    monkeypatch.setattr(Objective, "bounded_overlap", patched)
    return calls


@pytest.mark.parametrize("call, how", [(1, "signal"), (3, "signal"), (3, "during"), (20, "during"),
                                       (60, "signal"), (60, "during"), (5, "raise")])
def test_ctrl_c_during_the_search_writes_complete_outputs_and_exits_130(branch_files, tmp_path, monkeypatch,
                                                                         call, how):
    """Ctrl-C at several moments (the first evaluation, the pose phase, the turning phase from call 52 on):
    every output is complete, the report says interrupted, and the exit status is 130."""
    import signal

    calls = _interrupt_at(monkeypatch, call, how)
    handler = signal.getsignal(signal.SIGINT)
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 6,
                 "--iterations", 50, "-q", "-o", tmp_path / "posed.stl", "--pose", tmp_path / "pose.json",
                 "--report", tmp_path / "report.json", "--pictures", tmp_path / "pictures")
    assert calls["n"] >= call
    assert result.exit_code == 130, (result.output, result.exception)
    assert "Traceback" not in result.output and "interrupted" in result.stderr
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["interrupted"] is True
    assert len(report["history"]) < 101  # stopped before the end of both phases
    assert sl.read_pose(tmp_path / "pose.json", branch_files["bones"]).shape == (3, 3)
    V, F = sl.read_mesh(tmp_path / "posed.stl")
    assert len(F) == len(sl.read_mesh(branch_files["mesh"])[1])
    assert any(p.suffix == ".png" for p in (tmp_path / "pictures").iterdir())
    assert signal.getsignal(signal.SIGINT) is handler  # the usual Ctrl-C is back


@pytest.mark.slow
def test_search_options_reach_the_search(branch_files, tmp_path, no_slicer):
    """--overhang-model, --free all and the weights end up in the report's settings and change the search."""
    base = ("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 6,
            "--iterations", 2, "-q", "-o", tmp_path / "posed.stl")
    result = run(*base, "--overhang-model", "column", "--free", "all", "--w-arap", "3",
                 "--report", tmp_path / "column.json")
    assert result.exit_code == 0, (result.output, result.exception)
    settings = json.loads((tmp_path / "column.json").read_text())["settings"]
    assert settings["overhang_model"] == "column" and settings["free"] == ["all"] and settings["w_arap"] == 3.0
    assert settings["fixed_bones"] == []
    default = run(*base, "--report", tmp_path / "default.json")
    assert default.exit_code == 0, default.output
    settings = json.loads((tmp_path / "default.json").read_text())["settings"]
    assert settings["overhang_model"] == "prism" and settings["fixed_bones"] != []


def test_precomputed_tets_and_weights(branch_files, branch_rig, tmp_path):
    from supportless.files.meshes import write_dmat, write_tet_mesh

    write_tet_mesh(tmp_path / "b.mesh", branch_rig.tet_vertices, branch_rig.tets)
    W = branch_rig.tet_weights.copy()
    W[:, 0], W[:, 1:] = 1.0, 0.0  # every vertex follows the first bone: a visibly different rig
    write_dmat(tmp_path / "b.dmat", W)
    result = run("prepare", branch_files["mesh"], "--no-cache", "--tets", tmp_path / "b.mesh",
                 "--weights", tmp_path / "b.dmat")
    assert result.exit_code == 0, (result.output, result.exception)
    assert f"{len(branch_rig.tets)} tets" in result.stdout
    angles = np.zeros((3, 3))
    angles[1] = [0.0, 0.0, 0.6]
    sl.write_pose(tmp_path / "pose.json", angles, branch_files["bones"])
    result = run("apply", branch_files["mesh"], "--no-cache", "--tets", tmp_path / "b.mesh", "--weights",
                 tmp_path / "b.dmat", "--pose", tmp_path / "pose.json", "-o", tmp_path / "posed.stl")
    assert result.exit_code == 0, (result.output, result.exception)
    V, _ = sl.read_mesh(tmp_path / "posed.stl")
    surface = sl.load_rig(branch_files["mesh"], cache_dir=branch_files["cache"])  # same file, same vertex order
    frame = print_frame(surface.vertices, surface.up)
    np.testing.assert_allclose(V, frame.place(surface.vertices), atol=1e-4)  # nothing follows bone 2


# ----------------------------------------------------------------------- errors


def test_bad_input_is_one_line_and_exit_2(bad_case):
    model, kwargs, culprit, fragments = bad_case
    args = ["prepare", model, "--no-cache"]
    for option in ("skeleton", "tets", "weights"):
        if option in kwargs:
            args += [f"--{option}", kwargs[option]]
    line = assert_user_error(run(*args), str(culprit), *fragments)
    assert line.startswith(f"supportless: error: {culprit}: "), line  # the file at fault comes first


def test_optimize_with_a_bad_output_extension_writes_nothing(branch_files, tmp_path):
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 2,
                 "--iterations", 0, "-q", "-o", tmp_path / "out.xyz", "--pose", tmp_path / "pose.json",
                 "--report", tmp_path / "report.json")
    assert_user_error(result, "out.xyz", "unknown output format")
    assert list(tmp_path.iterdir()) == []


def test_apply_rejects_a_pose_for_another_skeleton(branch_files, tmp_path):
    tpose_bones = sl.demo_figure("tpose")[3]
    sl.write_pose(tmp_path / "pose.json", np.zeros((len(tpose_bones), 3)), tpose_bones)
    result = run("apply", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--pose",
                 tmp_path / "pose.json", "-o", tmp_path / "posed.stl")
    assert_user_error(result, "pose.json", "15 bones", "with 3;")
    assert not (tmp_path / "posed.stl").exists()


def test_bad_up_option(branch_files):
    result = run("prepare", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--up", "sideways")
    assert_user_error(result, "up direction")


def test_bad_fix_option(branch_files, tmp_path):
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 2,
                 "--iterations", 0, "-q", "--fix", "99", "-o", tmp_path / "out.stl")
    assert_user_error(result)
    assert not (tmp_path / "out.stl").exists()


def test_real_executable_prints_one_line(tmp_path):
    """What a user sees: a missing file gives one line on stderr, status 2, no traceback."""
    assert EXE.exists(), EXE
    proc = subprocess.run([str(EXE), "prepare", str(tmp_path / "missing.stl"), "--no-cache"],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "SUPPORTLESS_CACHE": str(tmp_path / "cache")})
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"supportless: error: {tmp_path / 'missing.stl'}: no such file"
    assert "Traceback" not in proc.stderr + proc.stdout
    assert proc.stdout == ""


@pytest.mark.slow
def test_print_rotation_round_trips_through_apply(branch_files, tmp_path):
    """`optimize -o` writes the pose as printed, `--upright-out` standing; `apply` reproduces both from the pose file."""
    common = [branch_files["mesh"], "--cache-dir", branch_files["cache"]]
    result = run("optimize", *common, "--particles", 10, "--iterations", 4, "--seed", 2, "-q", "--slice-rank", 0,
                 "--min-footprint", 0,  # the turn this short search finds rests on an edge: not the subject here
                 "-o", tmp_path / "printed.obj", "--upright-out", tmp_path / "standing.obj",
                 "--pose", tmp_path / "pose.json", "--report", tmp_path / "report.json")
    assert result.exit_code == 0, result.output
    rig = sl.load_rig(branch_files["mesh"], cache_dir=branch_files["cache"])
    R = sl.files.posefile.read_print_rotation(tmp_path / "pose.json", 3)
    assert not np.allclose(R, np.eye(3))  # the branch is turned to print
    report = json.loads((tmp_path / "report.json").read_text())
    np.testing.assert_allclose(report["print_rotation"]["matrix"], R, atol=1e-12)
    printed, _ = sl.read_mesh(tmp_path / "printed.obj")
    standing, _ = sl.read_mesh(tmp_path / "standing.obj")
    angles = sl.read_pose(tmp_path / "pose.json", rig.bones)
    frame = print_frame(rig.vertices, rig.up)  # the files: +Z up, mm, the rest pose 60 mm tall
    upright = place_on_plate(rig.pose(angles), rig.up)
    np.testing.assert_allclose(standing, frame.place(upright), atol=1e-5)
    np.testing.assert_allclose(printed, frame.place(sl.base.geometry.print_pose(upright, R, rig.up)), atol=1e-4)
    assert printed[:, 2].min() == pytest.approx(0.0, abs=1e-5)
    again = run("apply", *common, "--pose", tmp_path / "pose.json", "-o", tmp_path / "a-printed.obj",
                "--upright-out", tmp_path / "a-standing.obj")
    assert again.exit_code == 0, again.output
    np.testing.assert_array_equal(sl.read_mesh(tmp_path / "a-printed.obj")[0], printed)
    np.testing.assert_array_equal(sl.read_mesh(tmp_path / "a-standing.obj")[0], standing)


def test_orient_keep_writes_the_pose_standing(branch_files, tmp_path):
    common = [branch_files["mesh"], "--cache-dir", branch_files["cache"]]
    result = run("optimize", *common, "--particles", 6, "--iterations", 2, "-q", "--orient", "keep",
                 "-o", tmp_path / "printed.obj", "--upright-out", tmp_path / "standing.obj",
                 "--pose", tmp_path / "pose.json")
    assert result.exit_code == 0, result.output
    np.testing.assert_array_equal(sl.read_mesh(tmp_path / "printed.obj")[0], sl.read_mesh(tmp_path / "standing.obj")[0])
    np.testing.assert_array_equal(sl.files.posefile.read_print_rotation(tmp_path / "pose.json", 3), np.eye(3))


def test_a_bad_print_rotation_is_one_line(branch_files, tmp_path):
    rig = sl.load_rig(branch_files["mesh"], cache_dir=branch_files["cache"])
    sl.write_pose(tmp_path / "pose.json", np.zeros((rig.bone_count, 3)), rig.bones, rotation=2 * np.eye(3))
    result = run("apply", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--pose",
                 tmp_path / "pose.json", "-o", tmp_path / "posed.obj")
    assert result.exit_code == 2
    assert "print_rotation" in result.output and "rotation matrix" in result.output
    assert not (tmp_path / "posed.obj").exists()


def test_turning_only_needs_no_free_bone(branch_files, tmp_path, no_slicer):
    """`--joint-limit 0` holds every joint: with `--orient free` the model is only turned."""
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 8,
                 "--iterations", 3, "-q", "--joint-limit", 0, "-o", tmp_path / "turned.obj",
                 "--pose", tmp_path / "pose.json")
    assert result.exit_code == 0, result.output
    assert np.all(np.asarray(json.loads((tmp_path / "pose.json").read_text())["angles"]) == 0)
    keep = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "-q", "--joint-limit", 0,
               "--orient", "keep", "-o", tmp_path / "kept.obj")
    assert keep.exit_code == 2 and "--orient free" in keep.output


# ------------------------------------------------------------- issue 18: robustness


def test_a_skeleton_with_a_cycle_is_one_line_not_a_hang(tmp_path, branch_files):
    tgf = tmp_path / "cycle.tgf"
    tgf.write_text("1 0 0 0\n2 0 1 0\n3 1 1 0\n#\n1 2\n2 3\n3 1\n")
    for command in ("optimize", "prepare"):
        extra = ("-o", tmp_path / "out.stl") if command == "optimize" else ()
        result = run(command, branch_files["mesh"], "--skeleton", tgf, "--cache-dir", tmp_path / "cache", *extra)
        assert_user_error(result, "cycle.tgf", "form a cycle")
    assert not (tmp_path / "out.stl").exists()


def test_an_output_that_is_an_input_is_refused_before_any_work(branch_files, tmp_path):
    mesh, skeleton = Path(branch_files["mesh"]), Path(branch_files["skeleton"])
    before = mesh.read_bytes(), skeleton.read_bytes()
    link = tmp_path / "link.obj"
    link.symlink_to(mesh)
    base = ("optimize", mesh, "--skeleton", skeleton, "--cache-dir", tmp_path / "cache", "-q")
    assert_user_error(run(*base, "-o", mesh), "-o would overwrite the input")
    assert_user_error(run(*base, "-o", tmp_path / "a.stl", "--report", skeleton), "--report would overwrite")
    assert_user_error(run(*base, "-o", tmp_path / "a.stl", "--pose", link), "--pose would overwrite")
    assert_user_error(run(*base, "-o", tmp_path / "a.stl", "--upright-out", tmp_path / "a.stl"),
                      "--upright-out and -o are the same path")
    pose = tmp_path / "pose.json"
    pose.write_text("{}")
    assert_user_error(run("apply", mesh, "--skeleton", skeleton, "--pose", pose, "-o", mesh), "-o would overwrite")
    assert (mesh.read_bytes(), skeleton.read_bytes()) == before
    assert not (tmp_path / "cache").exists()  # refused before the rig was prepared


def test_impossible_output_locations_are_refused_before_the_search(branch_files, tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    base = ("optimize", branch_files["mesh"], "--cache-dir", tmp_path / "cache", "-q")
    assert_user_error(run(*base, "-o", blocker / "out.stl"), "a-file is a file, not a folder")
    assert_user_error(run(*base, "-o", tmp_path / "ok.stl", "--report", blocker / "deep" / "r.json"), "--report")
    # click itself refuses a file given for a folder and a folder for a file (its usage error, status 2)
    for args, words in (((*base, "-o", tmp_path / "ok.stl", "--pictures", blocker), "is a file"),
                        ((*base, "-o", tmp_path), "is a directory"), (("demo", "--out", blocker, "-q"), "is a file")):
        result = run(*args)
        assert result.exit_code == 2 and words in result.stderr and "Traceback" not in result.output
    assert not (tmp_path / "ok.stl").exists() and not (tmp_path / "cache").exists()


def test_a_file_that_cannot_be_written_is_one_line_and_the_others_are_written(branch_files, tmp_path,
                                                                               monkeypatch, no_slicer):
    import supportless.report.outputs as outputs

    def full_disk(path, *args, **kwargs):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(outputs, "write_pose", full_disk)  # the one writer of a result's files
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 4,
                 "--iterations", 1, "-q", "-o", tmp_path / "posed.stl", "--pose", tmp_path / "pose.json",
                 "--report", tmp_path / "report.json")
    assert result.exit_code == 1, (result.output, result.exception)
    lines = result.stderr.strip().splitlines()
    assert lines == [f"supportless: error: {tmp_path / 'pose.json'}: cannot write: No space left on device"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["posed.stl", "report.json"]


@pytest.mark.slow
def test_a_closed_stdout_loses_nothing(branch_files, tmp_path, no_slicer):
    """``supportless optimize ... | head -1``: the files are written and the exit status is 0."""
    import subprocess

    out = tmp_path / "posed.stl"
    proc = subprocess.Popen([str(EXE), "optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"],
                             "--particles", "4", "--iterations", "2", "-o", str(out), "--report",
                             str(tmp_path / "r.json")], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.readline()
    proc.stdout.close()  # as `head -1` does
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert out.stat().st_size > 0 and json.loads((tmp_path / "r.json").read_text())["model"]


@pytest.mark.parametrize("option, value, words", [
    ("--w-arap", "nan", "w_arap (--w-arap) must be a finite number"),
    ("--w-overhang", "inf", "w_overhang (--w-overhang) must be a finite number"),
    ("--w-intersect", "-1", "w_intersect (--w-intersect) must be 0 or more"),
    ("--fix", "99", "bone 99 is out of range 1..3"),
    ("--limit", "7=10", "bone 7 is out of range 1..3"),
    ("--up", "0,1", "has 2 numbers; give three"),
])
def test_bad_options_are_one_line_before_the_rig_is_prepared(branch_files, tmp_path, option, value, words):
    result = run("optimize", branch_files["mesh"], "--skeleton", branch_files["skeleton"], "--cache-dir",
                 tmp_path / "cache", "-o", tmp_path / "out.stl", option, value)
    assert_user_error(result, words)
    assert not (tmp_path / "cache").exists() and not (tmp_path / "out.stl").exists()


def test_a_negative_seed_names_the_option(branch_files, tmp_path):
    result = run("optimize", branch_files["mesh"], "-o", tmp_path / "out.stl", "--seed", "-1")
    assert result.exit_code == 2 and "'--seed'" in result.stderr and "Traceback" not in result.output


def test_when_every_bone_is_fixed_the_user_is_told_why_only_the_turn_changes(branch_files, tmp_path, no_slicer):
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--fix", "all",
                 "--particles", 4, "--iterations", 1, "-q", "-o", tmp_path / "out.stl")
    assert result.exit_code == 0, result.output
    assert "every bone of" in result.stderr and "the search only turns it" in result.stderr


def test_apply_on_a_full_disk_is_one_line_and_no_file(branch_files, tmp_path, monkeypatch):
    import errno

    import supportless.report.outputs as sio
    from supportless.apps.cli_common import EXIT_WRITE_FAILED

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    sl.write_pose(tmp_path / "pose.json", np.zeros((len(branch_files["bones"]), 3)), branch_files["bones"])
    monkeypatch.setattr(sio, "write_mesh", full)
    result = run("apply", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--pose",
                 tmp_path / "pose.json", "-o", tmp_path / "posed.stl")
    assert result.exit_code == EXIT_WRITE_FAILED
    errors = [line for line in result.stderr.splitlines() if line.startswith("supportless: error")]
    assert len(errors) == 1 and "No space left on device" in errors[0] and "Traceback" not in result.output
    assert not (tmp_path / "posed.stl").exists()


@pytest.mark.parametrize("command", ["demo", "batch"])
def test_a_full_disk_in_demo_and_the_batch_contact_sheet_is_one_line(tmp_path, monkeypatch, command, no_slicer):
    """Disk full while demo writes its files, or while batch writes its contact sheet: one line, no traceback."""
    import errno

    import supportless.apps.batch as batch
    import supportless.files.meshes as sio
    from supportless.apps.cli_common import EXIT_WRITE_FAILED

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp_path / "out" / "file"))

    if command == "demo":
        monkeypatch.setattr(sio, "write_mesh", full)
        result = run("demo", "--figure", "branch", "--out", tmp_path / "out", "--particles", 4, "--iterations", 1,
                     "-q")
    else:
        d = tmp_path / "in"
        d.mkdir()
        V, F, J, B = sl.demo_figure("branch")[:4]
        sl.write_mesh(d / "branch.obj", V, F)
        sl.write_tgf(d / "branch.tgf", J, B)
        monkeypatch.setattr(batch, "write_contact_sheet", full)
        result = run("batch", d, "-o", tmp_path / "out", "--workers", 1, "--particles", 4, "--iterations", 1,
                     "--orient", "keep", "-q", "--cache-dir", tmp_path / "cache")
    assert result.exit_code == EXIT_WRITE_FAILED, result.output
    errors = [line for line in result.stderr.splitlines() if line.startswith("supportless: error")]
    assert len(errors) == 1 and "No space left on device" in errors[0] and "free some space" in errors[0]
    assert "Traceback" not in result.output


def test_the_chain_options_reach_the_search(branch_files, tmp_path, no_slicer):
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 4,
                 "--iterations", 1, "-q", "-o", tmp_path / "p.stl", "--report", tmp_path / "r.json",
                 "--chain-limit", 50, "--w-chain", 0.25)
    assert result.exit_code == 0, (result.output, result.exception)
    settings = json.loads((tmp_path / "r.json").read_text())["settings"]
    assert settings["chain_limit"] == 50.0 and settings["w_chain"] == 0.25
    bad = run("optimize", branch_files["mesh"], "--chain-limit", 200, "-o", tmp_path / "q.stl")
    assert bad.exit_code == 2 and "0<=x<=180" in bad.stderr


@pytest.mark.parametrize("flags, symmetric, anatomy", [((), None, True), (("--symmetric",), True, True),
                                                       (("--no-symmetric", "--no-anatomy"), False, False)])
def test_the_symmetry_and_anatomy_options_reach_the_search(branch_files, tmp_path, flags, symmetric, anatomy,
                                                           no_slicer):
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 4,
                 "--iterations", 1, "-q", "-o", tmp_path / "p.stl", "--report", tmp_path / "r.json", *flags)
    assert result.exit_code == 0, (result.output, result.exception)
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["settings"]["anatomy"] is anatomy
    # the branch has a mirror plane (its arm lies in it): the tool's choice searches it mirrored, and the
    # settings reported are that search's
    assert (report["symmetry"] is not None) == (symmetric is None)
    if symmetric is None:
        assert report["symmetry"]["kept"] == "mirrored" and report["symmetry"]["mirrored_mm"] >= 0
        symmetric = True
    assert report["settings"]["symmetric"] is symmetric


def test_an_answer_the_slicer_finds_worse_than_the_rest_pose_is_replaced_by_it(branch_files, tmp_path):
    """A stand-in PrusaSlicer that supports anything but the rest pose (exactly 60 mm tall) with 1000 mm more."""
    from slicers import fake_exe, stand_in_slicer

    exe = fake_exe(tmp_path, "prusa-slicer", stand_in_slicer(
        "10.0 if abs(float(rec['v'][:, :, 2].max()) - 60.0) < 1e-3 else 1010.0"))
    out = tmp_path / "posed.stl"
    result = run("optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 8,
                 "--iterations", 3, "--orient", "keep", "-o", out, "--report", tmp_path / "report.json",
                 "--slice-check", env={"SUPPORTLESS_PRUSA_SLICER": exe})
    assert result.exit_code == 0, (result.output, result.exception)
    assert "needs more support than the rest pose; the rest pose is written instead" in result.stderr
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["rest_instead"] and report["largest_rotation_deg"] == 0.0
    assert report["slice_check"]["after"]["support_mm"] == report["slice_check"]["before"]["support_mm"]
    V, _ = sl.read_mesh(out)
    assert np.ptp(V[:, 2]) == pytest.approx(60.0, abs=1e-3)


def test_the_rest_guard_reads_the_slicer_and_the_prediction():
    from supportless.apps.rest_guard import predicted_worse, sliced_worse

    assert predicted_worse({"predicted_slicer": {"before_mm": 10.0, "after_mm": 11.0}})
    assert not predicted_worse({"predicted_slicer": {"before_mm": 10.0, "after_mm": 9.0}})
    assert not predicted_worse({"predicted_slicer": None})
    assert sliced_worse({"slice_check": {"before": {"support_mm": 5.0}, "after": {"support_mm": 6.0}}})
    assert not sliced_worse({"slice_check": {"before": {"support_mm": 5.0}, "after": {"support_mm": 5.0}}})
    assert not sliced_worse({})


def test_every_height_mm_option_takes_the_settings_print_height_range():
    """--height-mm of every command is bounded by one range: the search settings' print_height_mm."""
    from supportless.search.settings import RANGES

    low, high = RANGES["print_height_mm"]
    heights = {name: p for name, command in main.commands.items() for p in command.params if p.name == "height_mm"}
    assert {"optimize", "prepare", "apply", "slice-check", "batch"} <= set(heights)
    for name, param in heights.items():
        assert (param.type.min, param.type.max, param.type.min_open, param.type.max_open) == (low, high, False, False), name
    assert "0.01" in run("slice-check", "a.stl", "b.stl", "--height-mm", "0.001").output
    assert "0.01" in run("optimize", "a.stl", "--height-mm", "0").output


def test_the_contact_line_names_the_parts_that_touch_or_the_one_that_touches_itself():
    from supportless.apps.cli_summary import _contact_line

    def line(*parts):
        return _contact_line({"contacts": [{"parts": p, "pairs": 3, "overlap_mm3": 12.0} for p in parts]})

    assert line(("bone:arm", "bone:torso")).endswith("(arm with torso)")
    assert line(("bone:ear", "bone:ear")).endswith("(ear against itself)")
    assert "()" not in line(("bone:ear", "bone:ear"))
