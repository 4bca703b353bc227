"""The zoo as one `supportless batch` against `supportless optimize` run model after model.

Writes the built-in 3D figures and the shared models (OBJ + TGF) into a
scratch folder, warms the rig cache (so both runs find every rig prepared, as
a second pass over a catalogue would), then times
``supportless batch IN -o OUT`` (a LocalCluster, one single-threaded worker
per core) and a loop of ``supportless optimize X.obj -o X.stl`` (one process
per model, numba on every core), both with the default search. Prints the
times and how far the two runs' predicted reductions differ.

    python benchmarks/batch.py [--models tpose branch ...] [--workers 2]
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import models

import supportless as sl


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    figures = [n for n in sl.DEMO_FIGURES if n != "woody2d"]
    p.add_argument("--models", nargs="+", default=figures + list(models.SHARED))
    p.add_argument("--workers", type=int, default=None)
    args = p.parse_args(argv)
    exe = str(Path(sys.executable).with_name("supportless"))
    work = Path(tempfile.mkdtemp(prefix="supportless-batch-bench-"))
    try:
        src, cache = work / "in", work / "cache"
        src.mkdir()
        names = [n for n in args.models if models.available(n)]
        for name in names:
            rig = models.load(name)
            sl.write_mesh(src / f"{name}.obj", rig.vertices, rig.faces)
            sl.write_tgf(src / f"{name}.tgf", rig.joints, rig.bones)
            sl.load_rig(src / f"{name}.obj", src / f"{name}.tgf", up=rig.up.tolist(), cache_dir=cache)  # warm
        t0 = time.perf_counter()
        cmd = [exe, "batch", str(src), "-o", str(work / "batch"), "--cache-dir", str(cache), "-q"]
        if args.workers:
            cmd += ["--workers", str(args.workers)]
        subprocess.run(cmd, check=False, capture_output=True)
        batch_s = time.perf_counter() - t0
        with open(work / "batch" / "summary.csv", newline="") as fh:
            rows = {r["model"]: r for r in csv.DictReader(fh)}
        t0 = time.perf_counter()
        loop = {}
        for name in names:
            out = work / "loop" / name
            out.mkdir(parents=True)
            subprocess.run([exe, "optimize", str(src / f"{name}.obj"), "-o", str(out / f"{name}.stl"), "--report",
                            str(out / "report.json"), "--cache-dir", str(cache), "-q"], check=False,
                           capture_output=True)
            loop[name] = json.loads((out / "report.json").read_text())
        loop_s = time.perf_counter() - t0
        print("| model | batch: status, seconds | predicted reduction: batch / one by one |")
        print("|---|---|---|")
        for name in names:
            r = rows.get(name, {})
            red = loop[name].get("predicted_slicer_reduction")
            b = r.get("predicted_reduction")
            print(f"| {name} | {r.get('status')}, {float(r.get('seconds') or 0):.1f} s "
                  f"| {100 * float(b):.1f} / {100 * red:.1f} % |" if b and red is not None else
                  f"| {name} | {r.get('status')} | – |")
        print(f"\n{len(names)} models: batch {batch_s:.1f} s, one by one {loop_s:.1f} s "
              f"({loop_s / batch_s:.2f}x the batch's time).")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
