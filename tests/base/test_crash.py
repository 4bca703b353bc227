"""A command that dies in native code: one line naming the signal and the stage, and a status of its own."""

import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="supervision forks; this platform cannot")

_CHILD = """
import os, signal, sys
from supportless.base.crash import stage, supervised

def command():
    stage("preparing the rig")
    stage("searching")
    print("half a progress bar", flush=True)
    {how}

sys.exit(supervised(command))
"""


def _run(how: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", _CHILD.format(how=how)], capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("how, signame", [("os.abort()", "SIGABRT"),
                                          ("os.kill(os.getpid(), signal.SIGSEGV)", "SIGSEGV")])
def test_a_native_crash_is_one_line_with_the_stage_and_what_to_try(how, signame):
    from supportless.base.crash import EXIT_CRASHED

    done = _run(how)
    assert done.returncode == EXIT_CRASHED
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, done.stderr
    assert f"crashed in native code ({signame}) while searching" in lines[0] and "--backend numpy" in lines[0]
    assert "half a progress bar" in done.stdout  # the terminal was the command's


def test_the_out_of_memory_killer_is_said_as_such():
    done = _run("os.kill(os.getpid(), signal.SIGKILL)")
    assert "killed (SIGKILL: out of memory?)" in done.stderr


@pytest.mark.parametrize("how, code", [("sys.exit(3)", 3), ("pass", 0), ("raise SystemExit('no')", 1)])
def test_a_command_that_ends_on_its_own_keeps_its_status(how, code):
    done = _run(how)
    assert done.returncode == code and "crashed" not in done.stderr


def test_the_executable_is_the_supervised_command():
    """The console script runs cli.run (supervised); an ordinary error still gets its own status and line."""
    from importlib.metadata import entry_points

    (script,) = [e for e in entry_points(group="console_scripts") if e.name == "supportless"]
    assert script.value == "supportless.apps.cli:run"
    done = subprocess.run([sys.executable, "-c", "import sys; sys.argv[0] = 'supportless'; "
                           "from supportless.apps.cli import run; run()", "optimize", "missing.obj", "-o", "x.stl"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stderr.startswith("supportless: error:"), done.stderr
