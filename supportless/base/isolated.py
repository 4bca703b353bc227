"""Run native code that can crash in a child process, and say so when it does.

TetGen, fTetWild and CGAL are C++ libraries that abort or segfault on some
inputs (a surface that cuts itself, coincident points); in the same process
that would end the program with no message. :func:`run_isolated` forks,
runs the call in the child with its output silenced and its working folder
a scratch folder (TetGen writes files there; the parent removes it even when
the child dies, :mod:`supportless.base.scratch`), and sends the result back
through a pipe. A crash, an exception or an exit in the child becomes one
:class:`NativeFailure` in the parent. The child ends with its parent
(:func:`supportless.base.lifetime.end_with_parent`): a killed tool leaves no
native call running.

Where ``fork`` does not exist the call runs in the process itself.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import warnings

from .lifetime import end_with_parent
from .scratch import scratch_dir

__all__ = ["NativeFailure", "run_beside", "run_isolated"]


class NativeFailure(RuntimeError):
    """A native call failed (``crashed`` says whether the child process died)."""

    def __init__(self, message: str, crashed: bool = False):
        super().__init__(message)
        self.crashed = crashed


def run_isolated(fn, *args, what: str = "native code"):
    """``fn(*args)`` in a forked child; its return value, pickled back.

    Parameters
    ----------
    fn : callable
        A module-level function; its result must pickle.
    *args
        Passed as they are (the child is a copy of this process).
    what : str
        Names the call in the error message ("TetGen").

    Returns
    -------
    The value ``fn`` returned.

    Raises
    ------
    NativeFailure
        When ``fn`` raised (message: the exception's) or the child died
        (``crashed=True``, message: the signal).
    """
    if not hasattr(os, "fork"):
        try:
            return fn(*args)
        except Exception as exc:  # the same contract as the child's
            raise NativeFailure(f"{what} failed: {exc}") from None
    with scratch_dir("supportless-native-") as scratch:  # the parent removes it, whatever became of the child
        data, status, _ = _fork_and_wait(fn, args, scratch)
    return _outcome(data, status, what)


def run_beside(fn, args: tuple, here, here_args: tuple, what: str = "native code"):
    """``fn(*args)`` in a forked child (as :func:`run_isolated`) while ``here(*here_args)`` runs in this process:
    both results, ``(fn's, here's)``. Two cores at work on one long native job split in two.

    Raises
    ------
    NativeFailure
        As :func:`run_isolated`, for the child's part (after ``here`` is done).
    """
    if not hasattr(os, "fork"):
        return run_isolated(fn, *args, what=what), here(*here_args)
    with scratch_dir("supportless-native-") as scratch:
        data, status, mine = _fork_and_wait(fn, args, scratch, here, here_args)
    return _outcome(data, status, what), mine


def _outcome(data: bytes, status: int, what: str):
    """The child's value from its pickled outcome and wait status, or :class:`NativeFailure`."""
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        name = signal.Signals(sig).name if sig in signal.Signals._value2member_map_ else f"signal {sig}"
        raise NativeFailure(f"{what} crashed ({name})", crashed=True)
    if not data:
        raise NativeFailure(f"{what} exited with status {os.waitstatus_to_exitcode(status)} and no result",
                            crashed=True)
    kind, value = pickle.loads(data)
    if kind == "error":
        raise NativeFailure(f"{what} failed: {value}")
    return value


def _fork_and_wait(fn, args, scratch, here=None, here_args=()):
    """Run ``fn(*args)`` in a forked child working in ``scratch``, and ``here(*here_args)`` here meanwhile
    when ``here`` is given: (the child's pickled outcome, its wait status, here's value or None)."""
    read_end, write_end = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    parent = os.getpid()
    with warnings.catch_warnings():  # Python 3.12+ warns about fork with threads; the child only runs fn
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:  # the child: never returns
        code = 0
        try:
            end_with_parent(parent)  # this thread waits for the child: the kernel's "parent" lives as long
            os.close(read_end)
            _silence_and_run(fn, args, write_end, scratch)
        except BaseException:
            code = 1
        finally:
            os._exit(code)
    os.close(write_end)
    try:
        mine = here(*here_args) if here is not None else None
        with os.fdopen(read_end, "rb") as source:
            data = source.read()
        _, status = os.waitpid(pid, 0)
    except BaseException:  # Ctrl-C while waiting: the child goes too
        try:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        except OSError:
            pass
        raise
    return data, status, mine


def _silence_and_run(fn, args, write_end: int, scratch) -> None:
    """In the child: quiet stdout/stderr, ``scratch`` as working folder, the pickled outcome to ``write_end``."""
    import faulthandler

    faulthandler.disable()  # a crash is the parent's to report, not a traceback on the parent's terminal
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.dup2(null, 2)
    sys.stdout = sys.stderr = open(os.devnull, "w")  # noqa: SIM115  (the child ends with os._exit)
    os.chdir(scratch)
    try:
        outcome = ("ok", fn(*args))
    except Exception as exc:
        outcome = ("error", str(exc) or type(exc).__name__)
    finally:
        os.chdir("/")
    payload = pickle.dumps(outcome, protocol=pickle.HIGHEST_PROTOCOL)
    with os.fdopen(write_end, "wb") as sink:
        sink.write(payload)
