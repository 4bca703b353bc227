"""The long steps of a run, announced: what the command line shows while a sculpt of millions of triangles waits.

A stage that takes long on a dense surface (reading it, simplifying it, the weights' transfer, the exact
self-intersection check, the report's measures, writing) runs inside :func:`step`; whoever listens
(:func:`listening`: the command line prints a line per step, the benchmarks time and measure each) is told
when it starts and when it ends. With no one listening a step costs a function call.
"""

from __future__ import annotations

import contextlib
import time
from typing import Callable, Iterator

__all__ = ["Listener", "listening", "step"]

#: ``listener(event, name, seconds)``: ``event`` is ``"start"`` (``seconds`` None) or ``"done"`` (the step's
#: wall time; also after an error inside it).
Listener = Callable[[str, str, "float | None"], None]

_listeners: list[Listener] = []


@contextlib.contextmanager
def listening(listener: Listener) -> Iterator[None]:
    """Inside, ``listener`` hears every :func:`step` (nested ones too, innermost last to start, first to end)."""
    _listeners.append(listener)
    try:
        yield
    finally:
        _listeners.remove(listener)


@contextlib.contextmanager
def step(name: str) -> Iterator[None]:
    """Announce the step ``name`` (e.g. ``"exact self-intersection check"``) to the listeners, and its end."""
    for listener in list(_listeners):
        listener("start", name, None)
    t = time.perf_counter()
    try:
        yield
    finally:
        seconds = time.perf_counter() - t
        for listener in list(_listeners):
            listener("done", name, seconds)
