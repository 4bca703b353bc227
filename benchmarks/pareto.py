"""The front of least support against least distortion (`--pareto N`), against the single default search.

For each model: the single default search (200 x 120) and its time; for
each method of ``pareto_front`` (the weight sweep, and the default search
followed by NSGA-II for the same extra time), the front (N poses) and its
time; the front's hypervolume (the area it dominates up to the reference
point: the rest pose's predicted support and the largest distortion of both
fronts, both axes scaled to 0..1); PrusaSlicer's support filament (60 mm
tall, default profile) of the rest pose, the single search's result and both
ends of each front. Prints a Markdown table.

    python benchmarks/pareto.py [--models bunny bb-bunny] [--count 5] [--gallery DIR] [--methods sweep nsga2]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import models
import numpy as np

import supportless as sl
from supportless.apps.pareto import pareto_front
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.report.report import predicted_slicer
from supportless.slicing.prusaslicer import find_prusa_slicer, scale_for_height, slice_support


def hypervolume(support, distortion, reference) -> float:
    """Area dominated by the points ``(support, distortion)`` (both minimised) up to ``reference``."""
    order = np.argsort(support)
    s, d = np.asarray(support, float)[order], np.asarray(distortion, float)[order]
    area, best = 0.0, reference[1]
    for i in range(len(s)):
        if d[i] < best and s[i] < reference[0]:
            area += (reference[0] - s[i]) * (best - d[i])
            best = d[i]
    return area


def run(name, count, gallery, methods):
    rig = models.load(name)
    settings = sl.SearchSettings()
    t0 = time.perf_counter()
    single = sl.optimize(rig, settings)
    single_s = time.perf_counter() - t0
    fronts = {m: pareto_front(rig, settings, count, method=m) for m in methods}
    rest_pred = predicted_slicer(rig, single)["before_mm"]
    d_max = max(max(p.distortion for p in f.poses) for f in fronts.values()) or 1e-12
    scale = scale_for_height(rig.vertices, rig.up, REFERENCE_HEIGHT_MM)
    meshes = [(rig.vertices, rig.faces), (single.print_vertices, rig.faces)]
    for f in fronts.values():
        meshes += [(f.poses[0].result.print_vertices, rig.faces), (f.poses[-1].result.print_vertices, rig.faces)]
    mm = slice_support(meshes, rig.up, scale, workers=2).support_mm
    for k, (method, front) in enumerate(fronts.items()):
        s = np.array([p.support for p in front.poses])
        d = np.array([p.distortion for p in front.poses])
        hv = hypervolume(s / rest_pred, d / d_max, (1.0, 1.0))
        low, high = mm[2 + 2 * k], mm[3 + 2 * k]
        if gallery:
            from supportless.apps.pareto import write_front

            write_front(rig, front, Path(gallery) / f"{name}-{method}.stl")
        print(f"| {name} | {method} | {single_s:.1f} s | {front.seconds:.1f} s ({front.seconds / single_s:.2f}x) "
              f"| {len(front.poses)} | {hv:.3f} | {mm[0]:.0f} | {mm[1]:.0f} | {low:.0f} ({100 * (low / mm[1] - 1):+.1f} %) "
              f"| {high:.0f} | {d[0]:.3g} → {d[-1]:.3g} |", flush=True)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=["bunny", "bb-bunny"])
    p.add_argument("--count", type=int, default=5)
    p.add_argument("--gallery", default=None, help="Write each front (meshes, poses, picture) into this folder.")
    p.add_argument("--methods", nargs="+", default=["sweep", "nsga2"], choices=["sweep", "nsga2"])
    args = p.parse_args(argv)
    if find_prusa_slicer() is None:
        sys.exit("PrusaSlicer not found: apt-get install prusa-slicer")
    print("| model | method | single search | front | poses | hypervolume | PrusaSlicer mm: rest | single search "
          "| least-support end (vs single) | least-distortion end | distortion along the front |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.models:
        if models.available(name):
            run(name, args.count, args.gallery, args.methods)


if __name__ == "__main__":
    main()
