"""The app's Slice button: a real slicer on the rest pose and the current one, in the background.

:class:`SliceRun` writes both meshes (as printed, millimetres) to a private
folder and runs :func:`supportless.slicing.prusaslicer.slice_check` with the
chosen slicer in a child process of its own session, so Cancel stops it and
every slicer it started at once, and a slicer that crashes takes only that
process down. The figures come back as the CLI's ``--slice-check`` report
(``before`` is the rest pose, ``after`` the pose).

Run as a module, it is that child: ``python -m supportless.apps.ui.slicerun
FOLDER`` reads ``FOLDER/meshes.npz`` and ``FOLDER/choice.json`` and writes
``FOLDER/report.json`` (or ``FOLDER/error.txt``, one line).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path
from typing import Callable

import numpy as np

__all__ = ["SliceRun", "slice_markdown"]


def _duration(seconds: float | None) -> str:
    if seconds is None:
        return "n/a"
    seconds = float(seconds)
    return f"{seconds / 60:.0f} min" if abs(seconds) >= 90 else f"{seconds:.0f} s"


def slice_markdown(report: dict) -> str:
    """The slicer's figures of the rest pose and the pose, for the panel.

    Parameters
    ----------
    report : dict
        :meth:`supportless.slicing.prusaslicer.SliceReport.to_dict` (``before``: rest pose, ``after``: the pose).
    """
    from ...report.report import slicer_label

    b, a = report["before"], report["after"]

    def row(label: str, key: str, fmt) -> str:
        return f"| {label} | {fmt(b.get(key))} | {fmt(a.get(key))} |"

    def mm(x):
        return "n/a" if x is None else f"{x:,.0f} mm"

    def g(x):
        return "n/a" if x is None else f"{x:.2f} g"

    red = report.get("reduction_percent")
    headline = ("the rest pose needs no support" if red is None else
                f"**{red:.1f} % less support** than the rest pose" if red >= 0 else
                f"**{-red:.1f} % more support** than the rest pose")
    return "\n".join([
        f"{slicer_label(report)} ({report.get('slicer_version') or 'version unknown'}): {headline}",
        "",
        "| | rest pose | this pose |",
        "|---|---|---|",
        row("support filament", "support_mm", mm),
        row("support", "support_g", g),
        row("whole print time, with supports", "total_time_s", _duration),
        row("whole print filament", "total_mm", mm),
    ])


class SliceRun:
    """One slice of the rest pose and the pose at a time, in the background.

    Parameters
    ----------
    on_done : callable
        ``on_done(report, error)``: the report dict (as :func:`slice_markdown`
        takes it) and None, or None and a one-line error; not called after
        :meth:`cancel`.
    """

    def __init__(self, on_done: Callable[[dict | None, str | None], None]):
        self.on_done = on_done
        self._proc: subprocess.Popen | None = None
        self._thread: threading.Thread | None = None
        self._cancelled = threading.Event()
        self._lock = threading.Lock()

    @property
    def running(self) -> bool:
        """True while a slice runs."""
        t = self._thread
        return t is not None and t.is_alive()

    def start(self, rest: tuple[np.ndarray, np.ndarray], posed: tuple[np.ndarray, np.ndarray], choice,
              timeout: float | None = None, pose=None) -> bool:
        """Slice both meshes, each with and without supports, with ``choice``'s slicer.

        Parameters
        ----------
        rest, posed : tuple of ((n, 3) float64, (f, 3) int64)
            The meshes as printed: +Z up, millimetres, on the plate.
        choice : supportless.slicing.choice.SlicerChoice
        timeout : float, optional
            Seconds for each slicer run (default: the slicer's own).
        pose : object, optional
            What ``posed`` is of (the app gives the pose and print rotation): handed back as the
            report's ``pose``, so a figure is shown only with the pose it was measured on.

        Returns
        -------
        started : bool
            False when a slice already runs.
        """
        with self._lock:
            if self.running:
                return False
            self._cancelled.clear()
            folder = Path(tempfile.mkdtemp(prefix="supportless-slice-"))
            np.savez(folder / "meshes.npz", rest_v=rest[0], rest_f=rest[1], posed_v=posed[0], posed_f=posed[1])
            (folder / "choice.json").write_text(json.dumps(
                {"engine": choice.engine, "support": choice.support, "cura_definitions": choice.cura_definitions,
                 "timeout": timeout}))
            self._thread = threading.Thread(target=self._run, args=(folder, pose), name="supportless-ui-slice",
                                            daemon=True)
            self._thread.start()
            return True

    def _run(self, folder: Path, pose=None) -> None:
        try:
            self._proc = subprocess.Popen([sys.executable, "-m", "supportless.apps.ui.slicerun", str(folder),
                                           str(os.getpid())],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                          start_new_session=True)
            _, err = self._proc.communicate()
            if self._cancelled.is_set():
                return
            report_file, error_file = folder / "report.json", folder / "error.txt"
            if report_file.is_file():
                self.on_done(json.loads(report_file.read_text()) | ({} if pose is None else {"pose": pose}), None)
            elif error_file.is_file():
                self.on_done(None, error_file.read_text().strip())
            else:
                tail = err.decode(errors="replace").strip().splitlines()
                self.on_done(None, f"the slicing process stopped (exit {self._proc.returncode})"
                             + (f": {tail[-1]}" if tail else ""))
        except Exception as exc:  # noqa: BLE001 - said in the page, the app keeps running
            if not self._cancelled.is_set():
                self.on_done(None, str(exc))
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    def cancel(self) -> bool:
        """Stop the running slice and every slicer it started; False when none runs."""
        if not self.running:
            return False
        self._cancelled.set()
        proc = self._proc
        if proc is not None and proc.poll() is None:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        return True

    def wait(self, timeout: float | None = None) -> bool:
        """Wait for the slice thread; True when none runs."""
        t = self._thread
        if t is not None:
            t.join(timeout)
        return not self.running


def _child(folder: Path) -> int:
    """The child process: slice the two meshes of ``folder`` and write the report (or one error line)."""
    from ...base.errors import SupportlessError
    from ...slicing.choice import SlicerChoice
    from ...slicing.prusaslicer import slice_check

    try:
        asked = json.loads((folder / "choice.json").read_text())
        meshes = np.load(folder / "meshes.npz")
        choice = SlicerChoice(asked["engine"], asked["support"], asked["cura_definitions"])
        extra = {} if asked.get("timeout") is None else {"timeout": float(asked["timeout"])}
        report = slice_check((meshes["rest_v"], meshes["rest_f"]), (meshes["posed_v"], meshes["posed_f"]),
                             up=(0.0, 0.0, 1.0), height_mm=None, choice=choice, **extra)
    except (SupportlessError, OSError, ValueError) as exc:
        (folder / "error.txt").write_text(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
        return 1
    (folder / "report.json").write_text(json.dumps(report.to_dict()))
    return 0


if __name__ == "__main__":  # pragma: no cover - run by SliceRun
    from ...base.lifetime import end_with_parent

    if len(sys.argv) > 2:  # the app's server: when it ends, however it ends, so does its slice
        end_with_parent(int(sys.argv[2]))
    sys.exit(_child(Path(sys.argv[1])))
