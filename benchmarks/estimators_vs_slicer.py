"""How well do the support estimates track PrusaSlicer? Random poses, least squares, R².

For each model, slice the rest pose and a few random poses (free bones within
±max-angle, self-intersecting poses skipped) with PrusaSlicer at 60 mm tall and
compare the support filament with

* the prism estimate (the paper's energy),
* the column estimate,
* the projected risky footprint (area needing support, seen from above),

all scaled to the same 60 mm model. It fits, over all samples, filament ≈ a·x
and filament ≈ a·x + b·footprint for x = prism or column, and prints R² of
each, and the footprint weight b/a as a height (mm) and as a fraction of the
model height (how much a per-area term would add, if it helped).

    python benchmarks/estimators_vs_slicer.py [--models bunny bb-bunny tpose] [--poses 8] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

import supportless as sl
from supportless.energies.overhang import projected_risky_area
from models import available, load
from supportless.energies.exact import intersecting_face_pairs
from supportless.slicer import find_prusa_slicer, slice_check




def samples(name, poses, max_angle, rng):
    rig = load(name)
    height = float(np.ptp(rig.vertices @ rig.up))
    s = 60.0 / height
    rows = []
    angle_sets = [rig.rest_angles()]
    while len(angle_sets) < poses + 1:
        A = rng.uniform(-1, 1, (rig.bone_count, 3)) * np.radians(max_angle)
        if intersecting_face_pairs(rig.pose(A), rig.faces) == 0:
            angle_sets.append(A)
    for A in angle_sets:
        V = rig.pose(A)
        rep = slice_check((rig.vertices, rig.faces), (V, rig.faces), up=rig.up, height_mm=60.0).to_dict()
        rows.append({
            "model": name,
            "slicer_mm": rep["after"]["support_mm"],
            "prism": float(sl.overhang_energy(V, rig.faces, rig.up)) * s ** 3,
            "column": float(sl.support_volume(V, rig.faces, rig.up)) * s ** 3,
            "footprint": float(projected_risky_area(V, rig.faces, rig.up)) * s ** 2,
        })
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    return rows


def r2(X, y):
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    res = y - X @ coef
    return 1.0 - res @ res / ((y - y.mean()) @ (y - y.mean())), coef


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=["bunny", "bb-bunny", "tpose"])
    p.add_argument("--poses", type=int, default=8)
    p.add_argument("--max-angle", type=float, default=30.0)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    if find_prusa_slicer() is None:
        sys.exit("PrusaSlicer not found: apt-get install prusa-slicer")
    rng = np.random.default_rng(args.seed)
    rows = []
    for m in args.models:
        if available(m):
            rows += samples(m, args.poses, args.max_angle, rng)
    y = np.array([r["slicer_mm"] for r in rows])
    print(f"{len(rows)} poses of {', '.join(args.models)}; PrusaSlicer support filament vs estimates (60 mm tall)")
    print("| estimate | R² (filament ≈ a·x) | R² (filament ≈ a·x + b·footprint) | b/a (mm of height) |")
    print("|---|---|---|---|")
    for key in ("prism", "column"):
        x = np.array([r[key] for r in rows])
        f = np.array([r["footprint"] for r in rows])
        r_a, _ = r2(x[:, None], y)
        r_b, coef = r2(np.column_stack([x, f]), y)
        print(f"| {key} | {r_a:.3f} | {r_b:.3f} | {coef[1] / coef[0]:.2f} mm ({coef[1] / coef[0] / 60:.3f} of height) |")
    f = np.array([r["footprint"] for r in rows])
    r_f, _ = r2(f[:, None], y)
    print(f"| footprint alone | {r_f:.3f} | | |")


if __name__ == "__main__":
    main()
