"""Turning only: how much support a user saves by choosing the print orientation, without posing.

For every built-in 3D figure and the shared models: the candidate printing
directions of :func:`supportless.orientation.candidate_ups`, ranked by the
prism estimate at the rest pose; the best few are sliced with PrusaSlicer
(60 mm tall, measured as the upright model) and the cheapest kept. Prints a
Markdown table: upright support, the best turned support, its direction and
the reduction. This is the baseline the pose-and-orientation search must beat.

    python benchmarks/orient.py [--models tpose bunny ...] [--slice-best 4] [--out FILE]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import supportless as sl
from models import SHARED, available, load
from supportless.orientation import candidate_ups, rank_ups, rotation_between
from supportless.report import reduction
from supportless.slicer import slice_check




def turn(rig, slice_best: int) -> dict:
    """Upright and best-turned support of one rig's rest pose (PrusaSlicer)."""
    V, F, up = rig.vertices, rig.faces, rig.up
    ups = candidate_ups(V, F)
    estimate = rank_ups(V, F, ups)
    tried = []
    for i in np.argsort(estimate)[:slice_best]:
        turned = V @ rotation_between(ups[i], up).T
        report = slice_check((V, F), (turned, F), up=up, height_mm=60.0).to_dict()
        tried.append((report["after"]["support_mm"], ups[i], report["before"]["support_mm"]))
    best = min(tried, key=lambda t: t[0])
    return {"upright_mm": best[2], "turned_mm": best[0], "direction": best[1], "candidates": len(ups)}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--slice-best", type=int, default=4, help="Candidates sliced per model (best estimates first).")
    p.add_argument("--out", default=None, help="Also write the table to this file.")
    args = p.parse_args(argv)
    models = args.models or [m for m in sl.DEMO_FIGURES if m != "woody2d"] + [m for m in SHARED if available(m)]
    lines = ["| model | candidates | upright support mm | best turned support mm | printing direction (input frame) "
             "| reduction by turning |", "|---|---|---|---|---|---|"]
    for name in models:
        t0 = time.perf_counter()
        r = turn(load(name), args.slice_best)
        red = reduction(r["upright_mm"], r["turned_mm"])
        d = np.round(r["direction"], 2).tolist()
        lines.append(f"| {name} | {r['candidates']} | {r['upright_mm']:.0f} | {r['turned_mm']:.0f} | {d} "
                     f"| {'–' if red is None else f'{red:.1f} %'} |")
        print(lines[-1], f"({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    text = "\n".join([
        "## Turning only (rest pose, best of the candidate directions)",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores. PrusaSlicer default profile, the model 60 mm tall "
        f"upright; the {args.slice_best} best candidates by the prism estimate are sliced, the cheapest kept.",
        "Command: `python benchmarks/orient.py " + " ".join(argv if argv is not None else sys.argv[1:]) + "`",
        "",
        *lines,
        "",
    ])
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
