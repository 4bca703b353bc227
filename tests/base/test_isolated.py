"""Native calls in a child process (:mod:`supportless.base.isolated`): a crash is an error, not the end."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np
import pytest
from processes import gone, linux_only

from supportless.base.isolated import NativeFailure, run_beside, run_isolated


def _double(a):
    return a * 2


def _raise(message):
    raise RuntimeError(message)


def _segfault():
    print("noise on stdout")
    os.kill(os.getpid(), signal.SIGSEGV)


def _exit_quietly():
    os._exit(3)


def _write_a_file(name):
    with open(name, "w") as f:
        f.write("scratch")
    return os.path.exists(name)


def test_the_value_comes_back_through_the_pipe():
    a = np.random.default_rng(0).normal(size=(1000, 3))
    np.testing.assert_array_equal(run_isolated(_double, a), a * 2)


def test_an_exception_in_the_child_is_one_failure_naming_the_call():
    with pytest.raises(NativeFailure, match="TetGen failed: bad surface") as info:
        run_isolated(_raise, "bad surface", what="TetGen")
    assert not info.value.crashed


def test_a_crash_is_a_failure_and_the_parent_goes_on(capfd):
    with pytest.raises(NativeFailure, match=r"CGAL crashed \(SIGSEGV\)") as info:
        run_isolated(_segfault, what="CGAL")
    assert info.value.crashed
    out, err = capfd.readouterr()
    assert "noise" not in out and err == ""
    assert run_isolated(_double, 2) == 4


def test_an_exit_without_a_result_is_a_failure():
    with pytest.raises(NativeFailure, match="exited with status 3") as info:
        run_isolated(_exit_quietly, what="fTetWild")
    assert info.value.crashed


def test_files_the_child_writes_stay_in_its_scratch_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert run_isolated(_write_a_file, "tetgen-tmpfile_skipped.node")
    assert list(tmp_path.iterdir()) == []


def _pid_and_double(a):
    return os.getpid(), 2 * a


def test_run_beside_runs_one_call_in_a_child_and_one_here_and_returns_both():
    (theirs_pid, theirs), (mine_pid, mine) = run_beside(_pid_and_double, (np.arange(3),), _pid_and_double,
                                                        (np.arange(4),))
    assert theirs_pid != os.getpid() and mine_pid == os.getpid()
    np.testing.assert_array_equal(theirs, [0, 2, 4])
    np.testing.assert_array_equal(mine, [0, 2, 4, 6])
    with pytest.raises(NativeFailure, match="crashed"):  # the child's crash is the one failure, after here's part
        run_beside(_segfault, (), _double, (np.arange(2),), what="the slab check")


_KILLED_TOOL = """
import os, sys, time
from pathlib import Path
from supportless.base.isolated import run_isolated

def native(marker):
    Path(marker + ".tmp").write_text(str(os.getpid()))
    os.replace(marker + ".tmp", marker)
    while True:  # a native call that takes its time
        time.sleep(60)

run_isolated(native, sys.argv[1], what="TetGen")
"""


@linux_only
def test_the_child_ends_when_the_tool_is_killed(tmp_path):
    """``kill -9`` of the process that waits for a native call: the call's process ends too."""
    from conftest import until

    marker = tmp_path / "native"
    proc = subprocess.Popen([sys.executable, "-c", _KILLED_TOOL, str(marker)])
    try:
        assert until(lambda: marker.exists() or proc.poll() is not None, 120) and marker.exists()
    finally:
        proc.kill()
        proc.wait(timeout=60)
    assert until(lambda: gone(int(marker.read_text())), 20), "the native call goes on without the tool"
