"""``supportless batch`` on Dask (issue 17): two small models and broken ones, resumable, on a local
cluster and on a real scheduler with a worker started here."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner
from processes import linux_only

import supportless as sl
from supportless.apps.batch import COLUMNS, find_models, run_model

EXE = Path(sys.executable).with_name("supportless")
FAST = ["--particles", "12", "--iterations", "3", "--orient", "keep"]


@pytest.fixture()
def folder(tmp_path):
    """branch and arm (OBJ + TGF), a broken OBJ with its TGF, and a mesh with no skeleton."""
    d = tmp_path / "in"
    d.mkdir()
    for name in ("branch", "arm"):
        V, F, J, B = sl.demo_figure(name)[:4]
        sl.write_mesh(d / f"{name}.obj", V, F)
        sl.write_tgf(d / f"{name}.tgf", J, B)
    (d / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
    (d / "broken.tgf").write_text("1 0 0 0\n2 0 1 0\n#\n1 2\n")
    (d / "lonely.stl").write_bytes(b"")
    return d


@pytest.fixture(scope="module")
def prepared_cache(tmp_path_factory):
    """A rig cache holding branch and arm as the batch prepares them (the cache is keyed by the files' content)."""
    cache = tmp_path_factory.mktemp("batch-rigs")
    d = tmp_path_factory.mktemp("batch-models")
    for name in ("branch", "arm"):
        V, F, J, B = sl.demo_figure(name)[:4]
        sl.write_mesh(d / f"{name}.obj", V, F)
        sl.write_tgf(d / f"{name}.tgf", J, B)
        sl.load_rig(d / f"{name}.obj", d / f"{name}.tgf", "auto", cache_dir=cache)
    return cache


@pytest.fixture()
def warm_cache(prepared_cache, tmp_path):
    """``tmp_path / "cache"`` holding branch and arm prepared, for a test whose subject is not the preparation."""
    shutil.copytree(prepared_cache, tmp_path / "cache")
    return tmp_path / "cache"


def _summary(out):
    with open(out / "summary.csv", newline="") as fh:
        return {row["model"]: row for row in csv.DictReader(fh)}


def _check_outputs(out, names):
    for name in names:
        files = {p.name for p in (out / name).iterdir()}
        assert {f"{name}.stl", f"{name}.pose.json", "report.json", "row.json", "before_after.png"} <= files
        assert json.loads((out / name / "report.json").read_text())["model"] == name


def test_find_models_pairs_meshes_and_skeletons(folder):
    specs = {s.name: s for s in find_models(folder)}
    assert set(specs) == {"arm", "branch", "broken", "lonely"}
    assert specs["branch"].skeleton.endswith("branch.tgf") and specs["branch"].problem is None
    assert "no skeleton lonely.tgf" in specs["lonely"].problem
    with pytest.raises(sl.InputError, match="no models here"):
        find_models(folder / "..")  # the test's folder holds only the 'in' folder


def test_meshes_sharing_a_name_are_one_failed_model(folder):
    """dup.obj + dup.glb: one row saying both files, so the count matches summary.csv."""
    V, F, J, B = sl.demo_figure("branch")[:4]
    sl.write_mesh(folder / "arm.stl", V, F)  # arm.obj is there too, both beside arm.tgf
    specs = [s for s in find_models(folder) if s.name == "arm"]
    assert len(specs) == 1 and "arm.obj" in specs[0].problem and "arm.stl" in specs[0].problem


@pytest.mark.slow
def test_local_cluster_two_ok_two_failed_then_a_rerun_skips_the_finished(folder, tmp_path, warm_cache, monkeypatch):
    from supportless.apps import cli_batch
    from supportless.apps.cli import main

    warm_up = []  # a local cluster's workers load the kernels the run compiled first (faked here: a cold cache)

    class Cold:
        active = True

        def finish(self):
            warm_up.append("finished")

    monkeypatch.setattr(cli_batch, "start_warm_up", lambda: warm_up.append("started") or Cold())
    out = tmp_path / "out"
    args = ["batch", str(folder), "-o", str(out), "--workers", "2", "--cache-dir", str(warm_cache), *FAST]
    first = CliRunner().invoke(main, args)
    assert first.exit_code == 1, first.output  # some models failed
    assert warm_up == ["started", "finished"] and "compiling the numerical kernels" in first.output
    rows = _summary(out)
    assert list(rows["arm"]) == list(COLUMNS)
    assert {m: r["status"] for m, r in rows.items()} == {"arm": "ok", "branch": "ok", "broken": "failed",
                                                        "lonely": "failed"}
    assert "cannot read as OBJ" in rows["broken"]["reason"] and "no skeleton" in rows["lonely"]["reason"]
    assert float(rows["branch"]["predicted_after_mm"]) < float(rows["branch"]["predicted_before_mm"])
    _check_outputs(out, ["arm", "branch"])
    assert not (out / "broken").exists() and (out / "contact_sheet.png").stat().st_size > 0
    stamp = (out / "arm" / "row.json").stat().st_mtime_ns
    again = CliRunner().invoke(main, args)
    assert "arm: already done" in again.output and "branch: already done" in again.output
    assert (out / "arm" / "row.json").stat().st_mtime_ns == stamp  # not posed again
    assert _summary(out)["arm"]["status"] == "ok"


def test_a_model_that_fails_midway_leaves_no_folder_that_looks_finished(folder, tmp_path, monkeypatch):
    import supportless.report.outputs as outputs

    def crash(*args, **kwargs):
        raise RuntimeError("disk went away")

    monkeypatch.setattr(outputs, "write_pictures", crash)  # after the mesh and the pose are written
    out = tmp_path / "out"
    out.mkdir()
    spec = next(s for s in find_models(folder) if s.name == "branch")
    row = run_model(spec, str(out), {"particles": 8, "iterations": 2, "orient": "keep"}, "y", None,
                    str(tmp_path / "cache"))
    assert row["status"] == "failed" and "RuntimeError: disk went away" in row["reason"]
    assert list(out.iterdir()) == []  # neither a half folder nor the temporary one


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_the_same_run_on_a_real_scheduler_and_worker(folder, tmp_path, warm_cache):
    dask = Path(sys.executable).with_name("dask")
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    scheduler = subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                  "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    worker = None
    try:
        worker = subprocess.Popen([str(dask), "worker", address, "--nthreads", "1", "--no-dashboard"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
        out = tmp_path / "out"
        run = subprocess.run([str(EXE), "batch", str(folder), "-o", str(out), "--scheduler", address,
                              "--cache-dir", str(warm_cache), "-q", *FAST],
                             capture_output=True, text=True, timeout=600, env=env)
        assert run.returncode == 1, run.stderr  # the two broken models
        rows = _summary(out)
        assert rows["arm"]["status"] == "ok" and rows["branch"]["status"] == "ok"
        assert rows["broken"]["status"] == "failed"
        _check_outputs(out, ["arm", "branch"])
    finally:
        for p in (worker, scheduler):
            if p is not None:
                p.terminate()
                try:
                    p.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    p.kill()


@pytest.mark.slow
@pytest.mark.parametrize("point", ["rename arm/", "rename branch/", "rename contact_sheet.png",
                                   "rename summary.csv"])
def test_killing_a_run_at_each_step_leaves_no_model_that_looks_finished(folder, tmp_path, point, warm_cache):
    """The run stops at a chosen step (``SUPPORTLESS_PAUSE_AT``), is killed there, and a rerun completes it.

    The steps: a model's scratch folder about to become its folder, the contact sheet and the summary about to
    be renamed into place. The kill lands at the step, not after a delay: the verdict never depends on timing.
    """
    from supportless.base.interrupt import PAUSE_ENV

    out, marker = tmp_path / "out", tmp_path / "paused"
    proc = subprocess.Popen([str(EXE), "batch", str(folder), "-o", str(out), "--workers", "1", "-q",
                             "--cache-dir", str(tmp_path / "cache"), *FAST],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
                            env=dict(os.environ, **{PAUSE_ENV: f"{point}={marker}"}))
    try:
        for _ in range(6000):  # the run reaches the step (or ends: then the test fails below)
            if marker.exists() or proc.poll() is not None:
                break
            time.sleep(0.1)
        assert marker.exists(), f"the run never reached {point!r}"
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the whole run, workers included, at once
        proc.wait(timeout=30)
    present = {p.name for p in out.iterdir() if p.is_dir() and not p.name.startswith(".")}
    assert present <= {"arm", "branch"}
    if point.startswith("rename ") and point.endswith("/"):  # the paused model has no folder yet
        assert point[len("rename "):-1] not in present
    if point == "rename contact_sheet.png":  # the sheet comes after every model
        assert present == {"arm", "branch"}
    _check_outputs(out, sorted(present))  # any model folder there is complete
    left = sorted(p.name for p in out.iterdir() if p.name.startswith("."))
    assert left, "the kill at the step leaves the step's scratch behind"
    rerun = subprocess.run([str(EXE), "batch", str(folder), "-o", str(out), "--workers", "1", "-q",
                            "--cache-dir", str(tmp_path / "cache"), *FAST], capture_output=True, text=True,
                           timeout=600)
    assert rerun.returncode == 1, rerun.stderr  # broken and lonely fail
    rows = _summary(out)
    assert rows["arm"]["status"] == rows["branch"]["status"] == "ok"
    _check_outputs(out, ["arm", "branch"])
    assert (out / "contact_sheet.png").is_file()
    assert not [p for p in out.iterdir() if p.name.startswith(".")], left  # the killed run's scratch is cleared
    mask = os.umask(0o022)
    os.umask(mask)
    assert (out / "arm").stat().st_mode & 0o777 == 0o777 & ~mask  # the umask's mode, not mkdtemp's 0700


def test_a_worker_uses_one_numba_thread_and_numba_accepts_its_environment_again():
    """A batch worker lowers numba's threads without changing what numba started with (a compilation
    re-reads NUMBA_NUM_THREADS and refuses a different value once its threads run)."""
    import numba

    from supportless.apps.batch import _one_numba_thread

    before, env = numba.get_num_threads(), os.environ.get("NUMBA_NUM_THREADS")
    try:
        os.environ["NUMBA_NUM_THREADS"] = str(numba.config.NUMBA_NUM_THREADS + 1)  # as a worker's env could say
        _one_numba_thread()
        assert numba.get_num_threads() == 1
        numba.core.config.reload_config()  # what each compilation does: no "Cannot set NUMBA_NUM_THREADS"
        numba.njit(lambda x: x + 1)(1)
    finally:
        numba.set_num_threads(before)
        if env is None:
            os.environ.pop("NUMBA_NUM_THREADS", None)
        else:
            os.environ["NUMBA_NUM_THREADS"] = env


def test_a_worker_that_dies_under_a_model_is_a_failed_row_not_a_traceback(tmp_path):
    from distributed.scheduler import KilledWorker

    from supportless.apps.batch import _row_of

    class Died:
        def result(self):
            raise KilledWorker("supportless-X-1", "tcp://127.0.0.1:1")

    class Done:
        def result(self):
            return {"model": "Y", "status": "ok"}

    (tmp_path / ".X.old").mkdir()
    (tmp_path / ".X.old" / "stage").write_text("preparing the rig\n")
    (tmp_path / ".X.new").mkdir()
    (tmp_path / ".X.new" / "stage").write_text("searching\n")
    os.utime(tmp_path / ".X.old" / "stage", (1, 1))  # the newest scratch is the stage of the last attempt
    row = _row_of(Died(), "X", tmp_path)
    assert row["model"] == "X" and row["status"] == "failed" and "died while searching" in row["reason"]
    assert "--backend numpy" in row["reason"] and not list(tmp_path.iterdir())  # what to try; the scratch is gone
    assert "died while starting" in _row_of(Died(), "X", tmp_path)["reason"]
    assert _row_of(Done(), "Y", tmp_path) == {"model": "Y", "status": "ok"}


@pytest.mark.parametrize("where", ["preparing the rig", "searching"])
def test_a_worker_that_aborts_in_native_code_is_a_failed_row_naming_the_stage(tmp_path, monkeypatch, where):
    """A real worker process calls os.abort() at a stage: the batch goes on, its row says where and what to try."""
    from supportless.apps.cli import main
    from supportless.base.crash import CRASH_ENV, advice

    d = tmp_path / "in"
    d.mkdir()
    V, F, J, B = sl.demo_figure("branch")[:4]
    sl.write_mesh(d / "branch.obj", V, F)
    sl.write_tgf(d / "branch.tgf", J, B)
    monkeypatch.setenv(CRASH_ENV, where)
    result = CliRunner().invoke(main, ["batch", str(d), "-o", str(tmp_path / "out"), "--workers", "1",
                                       "--particles", "4", "--iterations", "1", "--orient", "keep", "-q",
                                       "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code != 0 and "Traceback" not in result.output
    (row,) = list(csv.DictReader((tmp_path / "out" / "summary.csv").open()))
    assert row["status"] == "failed" and f"died while {where}" in row["reason"] and advice(where) in row["reason"]
    assert not [p for p in (tmp_path / "out").iterdir() if p.name.startswith(".")]  # no scratch left


def test_a_rerun_removes_what_a_killed_run_left_even_under_names_with_brackets(tmp_path):
    """``a[1].obj``: its scratch ``.a[1].x/`` is not a glob character class; the sheet's and summary's temporaries go."""
    from supportless.apps.cli import main

    d = tmp_path / "in"
    d.mkdir()
    V, F, J, B = sl.demo_figure("branch")[:4]
    sl.write_mesh(d / "a[1].obj", V, F)
    sl.write_tgf(d / "a[1].tgf", J, B)
    out = tmp_path / "out"
    out.mkdir()
    (out / ".a[1].k3j_x9ab").mkdir()  # what a killed run leaves
    (out / ".a[1].k3j_x9ab" / "a[1].stl").write_bytes(b"half")
    (out / ".contact_sheet.q1w2e3r4.png").write_bytes(b"half")
    (out / ".summary.z9y8x7w6.csv").write_text("half")
    result = CliRunner().invoke(main, ["batch", str(d), "-o", str(out), "--workers", "1",
                                       "--cache-dir", str(tmp_path / "cache"), *FAST])
    assert result.exit_code == 0, result.output
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]
    assert _summary(out)["a[1]"]["status"] == "ok"


@pytest.mark.slow
@linux_only
def test_kill_9_of_the_tool_ends_its_workers_too(folder, tmp_path, warm_cache):
    """``kill -9`` of the ``supportless batch`` process alone (not its group): its child and the Dask workers
    it started end with it, the worker paused at a model's last step included (none goes on to write it)."""
    from conftest import until
    from processes import descendants, gone

    from supportless.base.interrupt import PAUSE_ENV

    out, marker = tmp_path / "out", tmp_path / "paused"
    proc = subprocess.Popen([str(EXE), "batch", str(folder), "-o", str(out), "--workers", "1", "-q",
                             "--cache-dir", str(tmp_path / "cache"), *FAST],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env=dict(os.environ, **{PAUSE_ENV: f"rename arm/={marker}"}))
    try:
        assert until(lambda: marker.exists() or proc.poll() is not None, 600) and marker.exists()
        below = descendants(proc.pid)
        assert len(below) >= 2, below  # the supervised child and its worker at least
    finally:
        proc.kill()
        proc.wait(timeout=30)
    assert until(lambda: all(gone(pid) for pid in below), 20), [pid for pid in below if not gone(pid)]
