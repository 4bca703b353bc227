"""The tool's child lives and dies with it (issue 50): signals to the ``supportless`` process alone.

``supportless`` runs each command in a supervised child (:mod:`supportless.base.crash`). A SIGINT to the
tool's PID stops a search that keeps its best pose; ``kill -9`` leaves no process behind; a plain ``kill``
of ``supportless view`` closes its port. The moment a signal is sent is a step of the run (an evaluation
of the search, the page's address printed), not a delay.
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import until
from processes import descendants, gone, linux_only, optimize_marked

import supportless as sl

pytestmark = [pytest.mark.skipif(not hasattr(os, "fork"), reason="supervision forks; this platform cannot"),
              linux_only, pytest.mark.slow]


def optimize_until(model: list[str], out: Path, at: int, *options: str) -> subprocess.Popen:
    """``supportless optimize MODEL`` writing into ``out``, once its search reached evaluation ``at`` (else ended)."""
    proc, marker = optimize_marked(model, out, at, *options, stdout=subprocess.PIPE)
    assert until(lambda: marker.exists() or proc.poll() is not None, 600), "the search never started"
    assert marker.exists(), f"the tool ended before evaluation {at}: {proc.communicate()[1]}"
    return proc


def best_kept(out: Path, faces: int, bones) -> str | None:
    """Why the outputs in ``out`` are not a complete best-pose-so-far (None when they are)."""
    try:
        report = json.loads((out / "report.json").read_text())
        pose = sl.read_pose(out / "pose.json", bones)
        _, F = sl.read_mesh(out / "posed.stl")
    except (OSError, ValueError) as exc:
        return f"an output is missing or broken: {exc}"
    if report.get("interrupted") is not True:
        return "the report does not say interrupted"
    if len(F) != faces or pose.shape[0] != len(bones):
        return "the mesh or the pose is incomplete"
    if report["after"]["objective"] > report["before"]["objective"] + 1e-9:
        return "the pose written is worse than the rest pose"
    return None


@pytest.mark.parametrize("at", [1, 120])
def test_sigint_to_the_tools_pid_alone_writes_the_best_pose_and_exits_130(branch_files, tmp_path, at):
    """``kill -INT PID`` (not the group, as a terminal's Ctrl-C would be): the search stops, its best is written."""
    proc = optimize_until([str(branch_files["mesh"]), "--cache-dir", str(branch_files["cache"])], tmp_path, at,
                          "--particles", "6", "--iterations", "400")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "the best pose found so far is written" in err
    assert best_kept(tmp_path, len(branch_files["F"]), branch_files["bones"]) is None


def test_kill_9_of_the_tool_leaves_no_process(branch_files, tmp_path):
    proc = optimize_until([str(branch_files["mesh"]), "--cache-dir", str(branch_files["cache"])], tmp_path, 1,
                          "--particles", "6", "--iterations", "400")
    below = descendants(proc.pid)
    assert below, "the tool has no child"
    proc.kill()
    proc.communicate(timeout=60)
    assert until(lambda: all(gone(pid) for pid in below), 20), [pid for pid in below if not gone(pid)]
    assert not (tmp_path / "report.json").exists()  # nothing went on to write it


def _port_open(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(1.0)
        return s.connect_ex(("127.0.0.1", port)) == 0


def test_a_plain_kill_of_view_closes_its_port(tmp_path):
    """``kill PID`` (SIGTERM) of ``supportless view``: its server goes with it and the port closes."""
    exe = Path(sys.executable).with_name("supportless")
    proc = subprocess.Popen([str(exe), "view", "--workdir", str(tmp_path)], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True, cwd=tmp_path)
    try:
        lines = iter(proc.stdout.readline, "")  # up to "supportless: viewing ... at http://127.0.0.1:PORT/?token=..."
        said = next((line for line in lines if line.startswith("supportless: viewing")), "")
        found = re.search(r"http://127\.0\.0\.1:(\d+)/", said)
        assert found, f"no address in {said!r}"
        port = int(found.group(1))
        assert until(lambda: _port_open(port), 60)
        proc.terminate()
        assert proc.wait(timeout=60) == 128 + signal.SIGTERM
        assert until(lambda: not _port_open(port), 20), f"port {port} still open"
    finally:
        if proc.poll() is None:
            proc.kill()
