"""Ctrl-C as a request to stop, read between steps, never an exception inside compiled code.

A ``KeyboardInterrupt`` raised while a parallel numba kernel runs comes out
as a ``SystemError`` (or is lost), and whatever the search had found is lost
with it. Inside :func:`deferred_interrupt` the first Ctrl-C only sets a flag;
long loops (the search's iterations) read it with :func:`requested` between
steps and stop cleanly, so their best result is still returned and written. A
second Ctrl-C raises ``KeyboardInterrupt`` as usual, for a user who does not
want to wait. A SIGINT that comes within :data:`SAME_REQUEST_S` of the last one
is the same request reaching the process twice (sent to the whole process
group, it also comes passed on by the supervising parent,
:mod:`supportless.base.lifetime`) and is let go, inside the block and outside
it (:func:`interrupt_once`, the supervised command's usual Ctrl-C). For the
tests, :func:`pause_point` stops a run at a named step so that it can be
killed exactly there.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
from pathlib import Path

__all__ = ["PAUSE_ENV", "SAME_REQUEST_S", "deferred_interrupt", "interrupt_once", "pause_point", "requested"]

#: Seconds within which a SIGINT repeats the last one instead of making a request of its own.
SAME_REQUEST_S = 1.0

_state = {"requested": False, "depth": 0, "last": float("-inf")}


def requested() -> bool:
    """True once Ctrl-C was pressed inside :func:`deferred_interrupt` (until the outermost block is entered again)."""
    return _state["requested"]


def _new_request() -> bool:
    """True when the SIGINT being handled is a request of its own, not the last one's repeat."""
    now = time.monotonic()
    if now - _state["last"] < SAME_REQUEST_S:
        return False
    _state["last"] = now
    return True


def _on_sigint(signum, frame):
    if not _new_request():
        return
    if _state["requested"]:
        raise KeyboardInterrupt
    _state["requested"] = True


def interrupt_once(signum, frame):
    """A SIGINT handler: Python's usual ``KeyboardInterrupt``, once for a SIGINT and its repeats
    (:data:`SAME_REQUEST_S`)."""
    if _new_request():
        raise KeyboardInterrupt


@contextlib.contextmanager
def deferred_interrupt():
    """Within the block, the first Ctrl-C sets :func:`requested` instead of raising.

    Blocks nest: only the outermost installs the handler (and clears the
    flag, and the time of the last SIGINT, on entry); outside the main
    thread, where signal handlers cannot be set, the block does nothing and
    Ctrl-C behaves as usual.
    """
    outermost = _state["depth"] == 0
    install = outermost and threading.current_thread() is threading.main_thread()
    previous = None
    if outermost:
        _state["requested"] = False
        _state["last"] = float("-inf")
    if install:
        previous = signal.signal(signal.SIGINT, _on_sigint)
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        if install:
            signal.signal(signal.SIGINT, previous)


#: Names a point where a run stops for a test to kill it there: ``POINT=FILE`` (:func:`pause_point`).
PAUSE_ENV = "SUPPORTLESS_PAUSE_AT"


def pause_point(name: str) -> None:
    """Block here for good when ``$SUPPORTLESS_PAUSE_AT`` is ``name=FILE``, after creating FILE.

    A test kills a run at a known step (a model's folder or the contact
    sheet about to be renamed into place) instead of after a delay, so its
    verdict never depends on timing. Unset, as it always is outside the
    tests, it costs one environment lookup.
    """
    point, _, marker = os.environ.get(PAUSE_ENV, "").partition("=")
    if point != name or not marker:
        return
    Path(marker).touch()
    while True:
        time.sleep(3600)
