"""Processes seen from outside, through Linux's ``/proc``: who descends from whom, and who has ended; and
``supportless optimize`` started so that a signal can be sent to it while its search runs (:func:`optimize_marked`,
also used by ``benchmarks/interrupt.py``)."""

from __future__ import annotations

import os
import subprocess
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


#: The ``supportless`` executable (:func:`supportless.apps.cli.run`), creating the file ``$MARKER`` at the
#: ``$AT``-th evaluation of the search: a signal sent once it is there comes while the search runs.
MARKED_TOOL = """
import os, sys
from pathlib import Path
from supportless.search.objective import Objective

calls, bounded = [0], Objective.bounded_overlap

def counted(self, *args, **options):
    calls[0] += 1
    if calls[0] == int(os.environ["AT"]):
        Path(os.environ["MARKER"]).touch()
    return bounded(self, *args, **options)

Objective.bounded_overlap = counted
sys.argv[0] = "supportless"
from supportless.apps.cli import run
run()
"""


def optimize_marked(model: list[str], out: Path, at: int, *options: str, **popen) -> tuple[subprocess.Popen, Path]:
    """Start ``supportless optimize MODEL OPTIONS`` (:data:`MARKED_TOOL`), quiet, not slicing its candidates.

    It writes ``posed.stl``, ``pose.json`` and ``report.json`` into ``out`` and creates ``out/searching`` at
    evaluation ``at`` of its search. ``popen`` goes to :class:`subprocess.Popen` (stderr is piped, as text).

    Returns
    -------
    proc : subprocess.Popen
    marker : Path
        The file that tells the search reached evaluation ``at``.
    """
    marker = out / "searching"
    proc = subprocess.Popen([sys.executable, "-c", MARKED_TOOL, "optimize", *model, "-q", "--slice-rank", "0",
                             "-o", str(out / "posed.stl"), "--pose", str(out / "pose.json"),
                             "--report", str(out / "report.json"), *options],
                            stderr=subprocess.PIPE, text=True, env=dict(os.environ, AT=str(at), MARKER=str(marker)),
                            **popen)
    return proc, marker
