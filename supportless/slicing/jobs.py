"""Slicer runs as jobs: several at once, each with its logs beside its G-code, a timeout, and one line on failure."""

from __future__ import annotations

import math
import re
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..base.errors import SlicerError

__all__ = ["Job", "build_volume", "mesh_jobs", "run_jobs"]


def _last_line(stderr: str, stdout: str = "") -> str:
    """The last non-empty line of a log (stderr first)."""
    for text in (stderr, stdout):
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        if lines:
            return lines[-1]
    return "no error message"


@dataclass
class Job:
    """One slicer run: its command, its G-code file and, beside it, its ``.out.log`` / ``.err.log``."""

    label: str
    cmd: list[str]
    gcode: Path
    proc: subprocess.Popen | None = None
    started: float = 0.0
    elapsed: float = 0.0

    def log(self, stream: str) -> Path:
        """The log file of ``stream`` (``"out"`` or ``"err"``)."""
        return self.gcode.with_suffix(f".{stream}.log")


def run_jobs(jobs: list[Job], workers: int, timeout: float, name: str = "PrusaSlicer",
             last_line=None) -> None:
    """Run slicer jobs in parallel.

    Parameters
    ----------
    jobs : list of _Job
        Their ``proc``, ``started`` and ``elapsed`` are filled in.
    workers : int
        Jobs running at a time.
    timeout : float
        Seconds allowed for each job.
    name : str
        The slicer, in messages.
    last_line : callable(stderr, stdout) -> str, optional
        The line of a failed job's logs that says why.

    Raises
    ------
    SlicerError
        On the first failure or timeout, after every running job is killed.
    """
    pending, running = list(jobs), []
    try:
        while pending or running:
            while pending and len(running) < workers:
                j = pending.pop(0)
                with open(j.log("out"), "wb") as out, open(j.log("err"), "wb") as err:
                    try:
                        j.proc = subprocess.Popen(j.cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL)
                    except OSError as e:
                        raise SlicerError(f"cannot run {name} ({j.cmd[0]}): {e}") from None
                j.started = time.monotonic()
                running.append(j)
            time.sleep(0.02)
            now = time.monotonic()
            for j in list(running):
                rc = j.proc.poll()
                if rc is None:
                    if now - j.started > timeout:
                        raise SlicerError(f"{name} timed out after {timeout:g} s slicing {j.label} "
                                          "(raise the timeout, or use a coarser config / smaller mesh)")
                    continue
                j.elapsed = now - j.started
                running.remove(j)
                if rc != 0 or not j.gcode.is_file():
                    line = (last_line or _last_line)(j.log("err").read_text(errors="replace"),
                                                     j.log("out").read_text(errors="replace"))
                    hint = " (needs a display? see supportless.slicing.prusaslicer: xvfb-run)" \
                        if re.search(r"display|gtk|x11", line, re.I) else ""
                    raise SlicerError(f"{name} failed slicing {j.label} (exit {rc}): {line}{hint}")
    finally:
        for j in running:
            if j.proc.poll() is None:
                j.proc.kill()
        for j in running:
            try:
                j.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass


def build_volume(extents) -> tuple[float, float, float]:
    """A build volume holding meshes of ``extents`` (3,) mm with room around, at least a common 250 x 210 x 210 mm
    printer's (a Prusa MK3's)."""
    ext = np.asarray(extents, np.float64).reshape(3)
    return (float(max(250.0, math.ceil(ext[0] + 20.0))), float(max(210.0, math.ceil(ext[1] + 20.0))),
            float(max(210.0, math.ceil(ext[2] + 10.0))))


def mesh_jobs(placed, names, work: Path, command, by_feature: bool = False) -> list[Job]:
    """Each placed mesh written as ``work/NAME.stl`` and its slices with supports (and, unless ``by_feature``,
    without): ``command(stl, gcode, support) -> list[str]`` gives each run's command line."""
    from ..files.meshes import write_mesh

    jobs = []
    for label, (V, F) in zip(names, placed):
        stl = work / f"{label}.stl"
        write_mesh(stl, V, F)
        for support in (True,) if by_feature else (True, False):
            gcode = work / f"{label}-{'support' if support else 'nosupport'}.gcode"
            jobs.append(Job(f"{label} mesh ({'with' if support else 'without'} supports)",
                            command(stl, gcode, support), gcode))
    return jobs
