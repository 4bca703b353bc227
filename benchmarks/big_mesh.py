"""Where a sculpt's minute goes: ``supportless optimize`` on a dense model, timed and measured per stage (issue 39).

The inputs are made from the shared bunny (``../shared/data/bunny.obj`` and ``bunny.tgf``), nothing downloaded,
and kept in a cache folder (:func:`supportless.apps.bench_targets.big_model`): ``bunny4``, the bunny subdivided
four times by trimesh (1 783 296 triangles), and ``bunny5m``, each of the bunny's triangles split in three at
its centroid and then subdivided four times (5 349 888 triangles).

The run is the command line's, in this process, from an empty rig cache, with a JSON report and pictures, so
every stage runs: each stage's wall time and the largest resident memory sampled during it (every 10 ms), then
the whole run's peak (``ru_maxrss``). Stages are the steps the command announces
(:func:`supportless.base.progress.step`); a stage inside another is indented.

    python benchmarks/big_mesh.py [--case bunny4] [--proxy-cells N] [--out FILE.md]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import tempfile
import threading
import time

import psutil

from supportless.apps.bench_targets import big_model


class Sampler:
    """Resident memory sampled in a thread; :meth:`peak_since` is the largest sample since a mark."""

    def __init__(self, interval: float = 0.01):
        self.process, self.interval = psutil.Process(), interval
        self.samples: list[tuple[float, int]] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stop.is_set():
            self.samples.append((time.perf_counter(), self.process.memory_info().rss))
            time.sleep(self.interval)

    def peak(self, start: float, end: float) -> int:
        inside = [rss for t, rss in self.samples if start <= t <= end]
        return max(inside, default=self.process.memory_info().rss)


def profile(case: str) -> tuple[list[dict], dict]:
    """Run ``supportless optimize`` on ``case`` here, per stage; returns (stages, whole run)."""
    from supportless.apps.cli import main
    from supportless.base.progress import listening

    mesh, skeleton = big_model(case)
    sampler = Sampler()
    rows, open_ = [], []

    def listen(event, name, seconds=None):
        now = time.perf_counter()
        if event == "start":
            open_.append((name, now))
            return
        while open_:
            what, t0 = open_.pop()
            if what == name:
                rows.append({"stage": name, "depth": len(open_), "seconds": now - t0, "t0": t0,
                             "peak_mb": sampler.peak(t0, now) / 2**20})
                break

    with tempfile.TemporaryDirectory() as out:
        argv = ["optimize", str(mesh), "--skeleton", str(skeleton), "--up", "y", "-o", f"{out}/out.stl",
                "--report", f"{out}/report.json", "--pictures", f"{out}/pictures", "--seed", "0",
                "--cache-dir", f"{out}/cache"]
        t = time.perf_counter()
        with listening(listen):
            try:
                main.main(argv, standalone_mode=False)
            except SystemExit:
                pass
        total = time.perf_counter() - t
        try:
            with open(f"{out}/report.json") as fh:
                reduction = json.load(fh)["reduction_percent"]["support_prism"]
        except (OSError, KeyError, ValueError):
            reduction = None
    sampler.stop.set()
    rows.sort(key=lambda r: r["t0"])
    return rows, {"seconds": total, "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "command": "supportless " + " ".join(argv), "reduction": reduction}


def table(case: str, rows: list[dict], whole: dict) -> str:
    lines = [f"`{case}`, {os.cpu_count()} cores, load average before {os.getloadavg()[0]:.2f}: "
             f"{whole['seconds']:.1f} s end to end, peak {whole['peak_mb']:.0f} MB"
             + (f", support (prism) {whole['reduction']:.1f} % less" if whole.get("reduction") is not None else ""),
             "",
             "| stage | seconds | largest resident memory during it |", "|---|---|---|"]
    for r in rows:
        lines.append(f"| {'&nbsp;' * 4 * r['depth']}{r['stage']} | {r['seconds']:.1f} | {r['peak_mb']:.0f} MB |")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="bunny4", choices=["bunny4", "bunny5m"])
    p.add_argument("--out", default=None, help="also append the table to this file")
    p.add_argument("--proxy-cells", type=int, default=None,
                   help="the proxy's grid (supportless.files.simplify.PROXY_CELLS) for this run")
    args = p.parse_args(argv)
    if args.proxy_cells is not None:
        from supportless.files import simplify

        simplify.PROXY_CELLS = args.proxy_cells
    rows, whole = profile(args.case)
    text = table(args.case, rows, whole)
    print(text)
    print(f"command: {whole['command']}", file=sys.stderr)
    if args.out:
        with open(args.out, "a") as fh:
            fh.write(text + "\n")


if __name__ == "__main__":
    main()
