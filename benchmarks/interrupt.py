"""SIGINT to the tool's PID at six moments of a search: is the best pose so far kept each time (issue 50)?

``supportless optimize`` runs in a supervised child (:mod:`supportless.base.crash`); a SIGINT sent to the
``supportless`` process alone (``kill -INT PID``, not a terminal's Ctrl-C to the whole group) must reach that
child, stop the search and write its best pose so far with exit status 130. For each moment, the tool is
started afresh and the signal sent once the search reached that evaluation (a patched
``Objective.bounded_overlap`` creates a file there: ``optimize_marked`` of ``tests/processes.py``, which
``tests/apps/test_cli_lifetime.py`` uses too); a moment counts as kept when the status is 130, the tool says
the best pose so far is written, the posed mesh, the pose and the report are complete and the pose written
is no worse than the rest pose. Prints one line per moment and ``k/6``.

    python benchmarks/interrupt.py [--model demo:tpose] [--at 1 40 120 220 320 420] [--group]

``--group`` sends the SIGINT to the tool's whole process group instead (as ``kill -INT -PGID`` does): it then
reaches the child twice, directly and passed on, and must still count as one request.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import supportless as sl

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from processes import optimize_marked  # noqa: E402 - the tests' helper: the tool that marks an evaluation


def interrupt_at(model: str, at: int, group: bool, folder: Path) -> tuple[str | None, float]:
    """One run stopped at evaluation ``at``: why the best pose was not kept (None when it was), and the seconds
    from the signal to the tool's end."""
    proc, marker = optimize_marked([model], folder, at, stdout=subprocess.DEVNULL, start_new_session=True)
    while not marker.exists() and proc.poll() is None:
        time.sleep(0.05)
    if not marker.exists():
        return f"the search ended before evaluation {at}", 0.0
    t0 = time.perf_counter()
    if group:
        os.killpg(proc.pid, signal.SIGINT)
    else:
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=1800)
    seconds = time.perf_counter() - t0
    if proc.returncode != 130:
        said = err.strip().splitlines()
        return f"exit status {proc.returncode}" + (f": {said[-1]}" if said else ""), seconds
    if "the best pose found so far is written" not in err:
        return "the tool does not say the best pose is written", seconds
    return _not_kept(folder), seconds


def _not_kept(folder: Path) -> str | None:
    """Why the outputs in ``folder`` are not a complete best pose so far (None when they are)."""
    try:
        report = json.loads((folder / "report.json").read_text())
        _, F = sl.read_mesh(folder / "posed.stl")
        json.loads((folder / "pose.json").read_text())
    except (OSError, ValueError) as exc:
        return f"an output is missing or broken: {exc}"
    if len(F) != report["faces"]:
        return "the posed mesh is incomplete"
    if report["after"]["objective"] > report["before"]["objective"] + 1e-9:
        return "the pose written is worse than the rest pose"
    return None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="demo:tpose", help="a model the tool reads (default: demo:tpose)")
    parser.add_argument("--at", type=int, nargs="+", default=[1, 40, 120, 220, 320, 420],
                        help="the evaluations at which the signal is sent (tpose's default search has ~480)")
    parser.add_argument("--group", action="store_true", help="signal the whole process group instead")
    args = parser.parse_args()
    kept = 0
    for at in args.at:
        with tempfile.TemporaryDirectory(prefix="supportless-interrupt-") as folder:
            why, seconds = interrupt_at(args.model, at, args.group, Path(folder))
        kept += why is None
        print(f"evaluation {at:5d}: {'kept' if why is None else 'LOST: ' + why} (ended {seconds:.1f} s after "
              f"the signal)", flush=True)
    whom = "the process group" if args.group else "the tool's PID"
    print(f"SIGINT to {whom}, {args.model}: best pose kept {kept}/{len(args.at)}")
    return 0 if kept == len(args.at) else 1


if __name__ == "__main__":
    sys.exit(main())
