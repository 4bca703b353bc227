"""Ctrl-C as a request to stop, read between steps, never an exception inside compiled code.

A ``KeyboardInterrupt`` raised while a parallel numba kernel runs comes out
as a ``SystemError`` (or is lost), and whatever the search had found is lost
with it. Inside :func:`deferred_interrupt` the first Ctrl-C only sets a flag;
long loops (the search's iterations) read it with :func:`requested` between
steps and stop cleanly, so their best result is still returned and written. A
second Ctrl-C raises ``KeyboardInterrupt`` as usual, for a user who does not
want to wait.
"""

from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["deferred_interrupt", "request", "requested"]

_state = {"requested": False, "depth": 0}


def requested() -> bool:
    """True once Ctrl-C was pressed inside :func:`deferred_interrupt` (until the outermost block is entered again)."""
    return _state["requested"]


def request() -> None:
    """Ask the running work to stop, as a first Ctrl-C does (for callers with their own stop button)."""
    _state["requested"] = True


def _on_sigint(signum, frame):
    if _state["requested"]:
        raise KeyboardInterrupt
    _state["requested"] = True


@contextlib.contextmanager
def deferred_interrupt():
    """Within the block, the first Ctrl-C sets :func:`requested` instead of raising.

    Blocks nest: only the outermost installs the handler (and clears the
    flag on entry); outside the main thread, where signal handlers cannot be
    set, the block does nothing and Ctrl-C behaves as usual.
    """
    outermost = _state["depth"] == 0
    install = outermost and threading.current_thread() is threading.main_thread()
    previous = None
    if outermost:
        _state["requested"] = False
    if install:
        previous = signal.signal(signal.SIGINT, _on_sigint)
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        if install:
            signal.signal(signal.SIGINT, previous)
