"""A command that dies in native code says so in one line: which stage, and what to try.

Most native code that can crash runs in a child process already
(:mod:`supportless.base.isolated`: TetGen, fTetWild, CGAL, the weight solve). The
rest (numba's compiled kernels, NumPy and SciPy's libraries) runs in the
command's own process, where a segmentation fault would end it with no word.
The ``supportless`` executable therefore runs each command under
:func:`supervised`: a forked child does the work with the terminal as it is
(progress bars, messages), reporting the stage it is in (:func:`stage`)
through a pipe; the parent only waits. When the child dies of a signal the
parent prints one line naming the signal and the last stage, and exits with
:data:`EXIT_CRASHED` (the out-of-memory killer's SIGKILL is said as such).
The child lives and dies with the parent (:mod:`supportless.base.lifetime`):
a Ctrl-C at the terminal reaches both and the parent leaves it to the
child; a SIGINT or SIGTERM sent to the parent's PID alone is passed on; and
when the parent ends, even of a ``kill -9``, the kernel ends the child.

A batch worker has no supervising parent of its own: there :func:`stage` also
writes the stage into a file (:func:`recording_stages`) that the batch reads
when the worker dies (:func:`last_stage`). For the tests, ``$SUPPORTLESS_CRASH_AT``
naming a stage makes :func:`stage` abort the process there, as native code would.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
from pathlib import Path
from typing import Callable, Iterator

from .interrupt import interrupt_once
from .lifetime import end_with_parent, held, release, wait_passing_on

__all__ = ["CRASH_ENV", "EXIT_CRASHED", "STAGE_ENV", "advice", "last_stage", "recording_stages", "stage",
           "supervised"]

#: Exit status of a command whose process died in native code (sysexits' EX_SOFTWARE).
EXIT_CRASHED = 70

#: The file descriptor :func:`stage` writes to, set by :func:`supervised` for its child.
STAGE_ENV = "SUPPORTLESS_STAGE_FD"

#: A stage named here aborts the process when reached (the tests' stand-in for a crash in native code).
CRASH_ENV = "SUPPORTLESS_CRASH_AT"

#: The file :func:`stage` also writes to, inside :func:`recording_stages`.
_record: dict[str, Path | None] = {"file": None}

#: What to try, by the last stage the command reached.
_ADVICE = {
    "preparing the rig": "repair the mesh (closed, no parts cutting each other) or try --tets/--weights",
    "searching": "try --backend numpy (the reference kernels), or fewer --particles",
    "slicing": "slice without the choice: --slice-rank 0",
    "writing": "check the output folder",
}


def stage(name: str) -> None:
    """Tell the supervising parent (if any), and the stage file (if any), that the command now does ``name``."""
    line = name.replace("\n", " ")
    fd = os.environ.get(STAGE_ENV)
    if fd:
        try:
            os.write(int(fd), (line + "\n").encode())
        except (OSError, ValueError):  # no parent listening: nothing to tell
            pass
    if _record["file"] is not None:
        try:
            _record["file"].write_text(line + "\n")
        except OSError:  # the stage is a courtesy: never the reason a run fails
            pass
    if os.environ.get(CRASH_ENV) == name:
        os.abort()


@contextlib.contextmanager
def recording_stages(path: str | os.PathLike) -> Iterator[None]:
    """Inside, :func:`stage` also writes the current stage into ``path`` (read by :func:`last_stage`)."""
    before = _record["file"]
    _record["file"] = Path(path)
    try:
        yield
    finally:
        _record["file"] = before


def last_stage(path: str | os.PathLike) -> str:
    """The stage a process recorded in ``path`` before it died, or ``"starting"`` when it recorded none."""
    try:
        return Path(path).read_text().strip() or "starting"
    except OSError:
        return "starting"


def advice(where: str) -> str:
    """What to try when native code crashed while ``where`` (a :func:`stage` name)."""
    return _ADVICE.get(where, "run it again with -v and report the model")


def supervised(command: Callable[[], object]) -> int:
    """Run ``command`` in a forked child and turn a crash of that child into one line.

    Parameters
    ----------
    command : callable
        The command (a click group's ``main`` in standalone mode: it exits
        with the command's status).

    Returns
    -------
    status : int
        The child's exit status, or :data:`EXIT_CRASHED` when it died of a
        signal other than SIGINT (130, as the child would have said) and
        SIGTERM (143).

    Notes
    -----
    SIGINT and SIGTERM sent to this process alone are passed on to the
    child, and the child ends when this process ends, even of a SIGKILL
    (:mod:`supportless.base.lifetime`).
    """
    if not hasattr(os, "fork") or os.environ.get(STAGE_ENV):  # nowhere to fork, or supervised already
        return _run(command)
    read_end, write_end = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    parent, mask = os.getpid(), held()  # until the wait, SIGINT and SIGTERM wait blocked (none lost)
    pid = os.fork()
    if pid == 0:  # the child: the command, with the terminal as it is; it never returns
        _child(command, parent, mask, read_end, write_end)
    os.close(write_end)
    chunks = []
    try:
        status = wait_passing_on(pid, mask)  # not the pipe's end: a process the child started may hold it
        os.set_blocking(read_end, False)
        while chunk := os.read(read_end, 4096):  # the few stage lines (far below a pipe's buffer)
            chunks.append(chunk)
    except BlockingIOError:  # all read
        pass
    finally:
        os.close(read_end)
    if not os.WIFSIGNALED(status):
        return os.waitstatus_to_exitcode(status)
    sig = os.WTERMSIG(status)
    if sig in _STOPPED:
        return _STOPPED[sig]
    last = b"".join(chunks).decode(errors="replace").strip().splitlines()
    where = last[-1] if last else "starting"
    name = signal.Signals(sig).name if sig in signal.Signals._value2member_map_ else f"signal {sig}"
    why = "killed (SIGKILL: out of memory?)" if sig == signal.SIGKILL else f"crashed in native code ({name})"
    sys.stderr.write(f"supportless: error: the command {why} while {where}; {advice(where)}\n")
    sys.stderr.flush()
    return EXIT_CRASHED


#: The exit status of a command whose child ended of a stop signal, not of a crash: as a shell says it (128 + N).
_STOPPED = {signal.SIGINT: 128 + signal.SIGINT, signal.SIGTERM: 128 + signal.SIGTERM}


def _child(command: Callable[[], object], parent: int, mask: set[int], read_end: int, write_end: int) -> None:
    """The forked child of :func:`supervised`: ``command`` run to its exit status, ending with the parent."""
    code = 1
    try:
        release(mask)
        end_with_parent(parent)
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, interrupt_once)  # a Ctrl-C that reaches it twice is one
        os.close(read_end)
        os.environ[STAGE_ENV] = str(write_end)
        code = _run(command)
    except BaseException:  # noqa: BLE001 - said as Python would, then the child ends
        import traceback

        traceback.print_exc()
    finally:
        os._exit(code)


def _run(command: Callable[[], object]) -> int:
    """``command()``'s exit status (0 when it returns, its SystemExit's code otherwise)."""
    try:
        command()
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        if not isinstance(exc.code, (int, type(None))):
            sys.stderr.write(f"{exc.code}\n")
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more to say
            pass
    return code
