"""A child process lives and dies with the tool: it gets the tool's stop signals and ends when the tool ends.

Two halves, one for each side of a fork:

* in a child, :func:`end_with_parent` makes the kernel end it when its
  parent ends, however the parent ends (a ``kill -9`` included): Linux's
  ``prctl(PR_SET_PDEATHSIG)``, elsewhere a thread that watches
  :func:`os.getppid`. The command's supervised child (:mod:`.crash`), the
  native calls' children (:mod:`.isolated`) and the batch's local Dask
  workers call it, so none goes on working (and writing files) for a tool
  that is gone;
* in a supervising parent, :func:`wait_passing_on` waits for its child
  and passes on the SIGINT and SIGTERM sent to the parent's PID alone
  (``kill -INT PID``, ``Popen.send_signal``), which would not reach the
  child otherwise. A Ctrl-C typed at the terminal reaches the parent and
  the child together (the terminal signals its whole foreground process
  group); the kernel marks it (``si_code`` ``SI_KERNEL``) and it is not
  passed on, so the child gets it once. A signal sent by a process to
  the whole group (``kill -INT -PGID``) reaches both too and cannot be told
  from one sent to the parent alone: the child gets it twice, within
  moments, and :mod:`.interrupt` counts the two as one request (as it does
  for the terminal's Ctrl-C where signals cannot be waited for, macOS: there
  the parent passes every one on).

The parent blocks those signals from before the fork (:func:`held`) to the
end of the wait, so that none is lost or handled by the wrong side in
between; the child unblocks them first thing (:func:`release`).
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time

__all__ = ["PASSED_ON", "end_with_parent", "held", "release", "wait_passing_on"]

#: The signals a supervising parent passes on to its child.
PASSED_ON = (signal.SIGINT, signal.SIGTERM)

#: ``prctl``'s option that names the signal a process gets when its parent ends (linux/prctl.h).
_PR_SET_PDEATHSIG = 1

#: ``si_code`` of a signal the kernel sent itself, as the terminal's Ctrl-C to its foreground group.
_SI_KERNEL = 0x80

#: Seconds between two looks at the parent by the watcher thread (where ``prctl`` does not exist).
_WATCH_S = 0.5


def end_with_parent(parent: int | None = None, sig: int = signal.SIGKILL) -> None:
    """End this process with ``sig`` when its parent process ends, however the parent ends.

    Call it in a child, first thing after the fork (or at the start of a
    spawned program). On Linux the kernel sends ``sig`` when the thread that
    started this process ends: start it from a thread that waits for it (or
    from a main thread).

    Parameters
    ----------
    parent : int, optional
        The parent's pid as the parent knew it before the fork. When the
        process's parent is already another one (the parent died before this
        call), ``sig`` comes at once. Default: the parent now (that race open).
    sig : int
        The signal that ends this process (default SIGKILL: nothing of a
        gone tool's work is worth finishing).
    """
    expected = os.getppid() if parent is None else parent
    if not _kernel_ends_with_parent(sig):
        _watch_parent(expected, sig)
    if os.getppid() != expected:  # the parent was gone before the kernel was asked
        os.kill(os.getpid(), sig)


def _kernel_ends_with_parent(sig: int) -> bool:
    """Ask the kernel for ``sig`` when the parent ends (Linux); False where it cannot be asked."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(sig), 0, 0, 0) == 0
    except (OSError, AttributeError):  # no C library to ask, or no prctl in it
        return False


def _watch_parent(parent: int, sig: int) -> None:
    """Send ``sig`` to this process from a daemon thread once its parent is no longer ``parent``."""
    def watch():
        while os.getppid() == parent:
            time.sleep(_WATCH_S)
        os.kill(os.getpid(), sig)

    threading.Thread(target=watch, name="supportless-end-with-parent", daemon=True).start()


#: What :func:`held` blocks: the signals passed on, and SIGCHLD (the child's end, waited for with them).
_HELD = {*PASSED_ON, signal.SIGCHLD}


def held() -> set[int]:
    """Block the signals a parent passes on (and SIGCHLD) in this thread; returns the mask to :func:`release` to.

    Called before the fork: the child starts with them blocked, pending
    rather than lost, until it calls :func:`release`. The parent has no
    other thread (one that did not block them could take them instead).
    """
    return signal.pthread_sigmask(signal.SIG_BLOCK, _HELD)


def release(mask: set[int]) -> None:
    """Restore the signal mask :func:`held` returned (the child, first thing; the parent, after the wait)."""
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def wait_passing_on(pid: int, mask: set[int]) -> int:
    """Wait for the child ``pid``, passing on to it the SIGINT and SIGTERM sent to this process.

    Call it with :func:`held`'s signals blocked since before the fork; it
    restores ``mask`` (what :func:`held` returned) on its way out.

    Parameters
    ----------
    pid : int
        The child.
    mask : set of int
        The signal mask to restore.

    Returns
    -------
    status : int
        The child's wait status (:func:`os.waitpid`'s).
    """
    if not hasattr(signal, "sigtimedwait"):  # macOS: handlers, without the terminal's mark
        return _wait_forwarding(pid, mask)
    try:
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                return status
            info = signal.sigtimedwait(_HELD, 1.0)  # the timeout: a look at the child even if SIGCHLD was missed
            if info is not None and info.si_signo in PASSED_ON:
                _pass_on(pid, info)
    finally:
        _drain()
        release(mask)


def _pass_on(pid: int, info) -> None:
    """Send the signal ``info`` describes on to ``pid`` unless the terminal sent it to the child already."""
    if info.si_signo == signal.SIGINT and info.si_code == _SI_KERNEL:  # Ctrl-C: the whole group has it
        return
    try:
        os.kill(pid, info.si_signo)
    except ProcessLookupError:  # ended meanwhile: its status is next
        pass


def _drain() -> None:
    """Take the signals :func:`held` blocked that came after the child's end: the tool ends with its child."""
    while signal.sigtimedwait(PASSED_ON, 0) is not None:
        pass


def _wait_forwarding(pid: int, mask: set[int]) -> int:
    """:func:`wait_passing_on` where signals cannot be waited for: handlers that pass every one on."""
    def forward(signum, frame):
        try:
            os.kill(pid, signum)
        except ProcessLookupError:
            pass

    previous = {sig: signal.signal(sig, forward) for sig in PASSED_ON}
    release(mask)
    try:
        _, status = os.waitpid(pid, 0)  # interrupted by a handler, then waited for again (PEP 475)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return status
