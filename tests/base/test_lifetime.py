"""A supervised command's child lives and dies with the tool (:mod:`supportless.base.lifetime`).

Each test runs a small supervised command in a real process, sends the tool
a signal the way a user or a program would (its PID alone, its whole group,
the terminal's Ctrl-C, ``kill -9``) and reads what the child got from its
exit status, or whether the child is still there. No verdict waits for a
fixed delay except a generous limit.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import until
from processes import gone, linux_only

pytestmark = [pytest.mark.skipif(not hasattr(os, "fork"), reason="supervision forks; this platform cannot"),
              linux_only]

#: A supervised command that writes its pid to argv[1]; ``{body}`` then runs in the child. ``{prelude}`` may
#: take ``signal.sigtimedwait`` away, as macOS has none: the parent then passes signals on from handlers.
_TOOL = """
import os, signal, sys, time
from pathlib import Path
{prelude}
from supportless.base.crash import supervised
from supportless.base.interrupt import deferred_interrupt, requested

def ready():
    Path(sys.argv[1] + ".tmp").write_text(str(os.getpid()))
    os.replace(sys.argv[1] + ".tmp", sys.argv[1])

def command():
{body}

sys.exit(supervised(command))
"""

#: Counts every SIGINT the child receives; exits 10 + the count once the first has come and a repeat would have.
_COUNTING = """
    got = []
    signal.signal(signal.SIGINT, lambda *a: got.append(1))
    ready()
    while not got:
        time.sleep(0.01)
    time.sleep(2)  # a repeat of it would come meanwhile
    sys.exit(10 + len(got))
"""

#: Waits for good.
_WAITING = """
    ready()
    while True:
        time.sleep(60)
"""

#: The search's way: the first Ctrl-C a request to stop, read between steps; a second one a KeyboardInterrupt.
_DEFERRED = """
    with deferred_interrupt():
        ready()
        while not requested():
            time.sleep(0.01)
        time.sleep(2)  # the last step; a repeat of the request comes meanwhile
    sys.exit(130)
"""


#: How the parent waits: for signals (``sigtimedwait``), or with handlers where that does not exist.
_WAITS = {"sigtimedwait": "", "handlers": "del signal.sigtimedwait"}


def _start(body: str, marker: Path, prelude: str = "", **popen) -> tuple[subprocess.Popen, int]:
    """The tool running ``body`` in its child; returns the tool's process and, once it is ready, the child's pid."""
    proc = subprocess.Popen([sys.executable, "-c", _TOOL.format(body=body, prelude=prelude), str(marker)], **popen)
    assert until(lambda: marker.exists() or proc.poll() is not None, 120), "the child never started"
    assert marker.exists(), f"the tool ended first (status {proc.returncode})"
    return proc, int(marker.read_text())


def _ended(proc: subprocess.Popen) -> int:
    try:
        return proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()


@pytest.mark.parametrize("wait", _WAITS)
def test_a_sigint_to_the_tools_pid_alone_reaches_the_child_once(tmp_path, wait):
    proc, _ = _start(_COUNTING, tmp_path / "child", _WAITS[wait])
    proc.send_signal(signal.SIGINT)
    assert _ended(proc) == 11


def test_ctrl_c_at_the_terminal_reaches_the_child_once(tmp_path):
    """The terminal signals the whole foreground group: the parent sees it came from there and leaves it."""
    import fcntl
    import termios

    main, side = os.openpty()

    def take_the_terminal():
        fcntl.ioctl(0, termios.TIOCSCTTY, 0)

    try:
        proc, _ = _start(_COUNTING, tmp_path / "child", stdin=side, stdout=side, stderr=side, start_new_session=True,
                         preexec_fn=take_the_terminal)
        os.close(side)
        os.write(main, b"\x03")  # Ctrl-C typed at the terminal
        assert _ended(proc) == 11
    finally:
        os.close(main)


def test_a_sigint_to_the_whole_group_is_one_request(tmp_path):
    """Sent to the group, SIGINT reaches the child and comes passed on too (unless the two merge on the way):
    one request to stop, not a second Ctrl-C that would cut the search's last step short."""
    proc, _ = _start(_DEFERRED, tmp_path / "child", start_new_session=True, stderr=subprocess.PIPE, text=True)
    os.killpg(proc.pid, signal.SIGINT)
    status, err = _ended(proc), proc.stderr.read()
    assert status == 130 and "Traceback" not in err, err


@pytest.mark.parametrize("wait", _WAITS)
def test_sigterm_to_the_tool_ends_the_child_and_the_tool_with_143(tmp_path, wait):
    proc, child = _start(_WAITING, tmp_path / "child", _WAITS[wait], stderr=subprocess.PIPE, text=True)
    proc.terminate()
    assert _ended(proc) == 128 + signal.SIGTERM
    assert proc.stderr.read() == ""  # a stop asked for, not a crash to report
    assert until(lambda: gone(child), 20)


def test_kill_9_of_the_tool_ends_the_child(tmp_path):
    proc, child = _start(_WAITING, tmp_path / "child")
    proc.kill()
    _ended(proc)
    assert until(lambda: gone(child), 20), "the child goes on without the tool"


_ORPHAN = """
import os, signal, sys, time
from pathlib import Path
from supportless.base import lifetime

parent = os.getpid()
if os.fork() == 0:
    {how}
    Path(sys.argv[1] + ".tmp").write_text(str(os.getpid()))
    os.replace(sys.argv[1] + ".tmp", sys.argv[1])
    while True:
        time.sleep(60)
while True:
    time.sleep(60)
"""


@pytest.mark.parametrize("how", ["lifetime.end_with_parent(parent)",
                                 "lifetime._watch_parent(parent, signal.SIGKILL)"],  # where prctl is missing
                         ids=["kernel", "watcher"])
def test_a_child_ends_when_its_parent_is_killed(tmp_path, how):
    marker = tmp_path / "child"
    proc = subprocess.Popen([sys.executable, "-c", _ORPHAN.format(how=how), str(marker)])
    try:
        assert until(lambda: marker.exists() or proc.poll() is not None, 120) and marker.exists()
    finally:
        proc.kill()
        proc.wait(timeout=60)
    assert until(lambda: gone(int(marker.read_text())), 20)


def test_a_child_whose_parent_is_gone_already_ends_at_once():
    """The parent died before the child asked the kernel: the child's parent is another one, and it ends."""
    done = subprocess.run([sys.executable, "-c", "import os; from supportless.base.lifetime import end_with_parent; "
                           "end_with_parent(os.getppid() + 1); print('still here')"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == -signal.SIGKILL and "still here" not in done.stdout
