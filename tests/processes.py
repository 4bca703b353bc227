"""Processes seen from outside, through Linux's ``/proc``: who descends from whom, and who has ended."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

#: The tests that read ``/proc`` run on Linux only.
linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads Linux's /proc")


def _stat(pid: int) -> tuple[str, int] | None:
    """``pid``'s state letter and parent pid, or None when no such process is left."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # after "pid (name) ": the name may hold spaces
    return fields[0], int(fields[1])


def gone(pid: int) -> bool:
    """True when ``pid`` has ended (no longer there, or a zombie its new parent has not reaped yet)."""
    state = _stat(pid)
    return state is None or state[0] in ("Z", "X")


def descendants(pid: int) -> list[int]:
    """The live processes below ``pid``: its children, theirs, and so on."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (state := _stat(int(entry.name))) is not None and state[0] not in ("Z", "X"):
            parents[int(entry.name)] = state[1]
    found, todo = [], [pid]
    while todo:
        above = todo.pop()
        below = [p for p, parent in parents.items() if parent == above]
        found += below
        todo += below
    return found
