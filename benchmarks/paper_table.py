"""The paper's experiment on every model, checked with PrusaSlicer: a Markdown table.

For ../shared/data/bunny.obj and bb-bunny.obj (when present) and the built-in
3D figures, run ``optimize`` with the paper's settings (200 particles x 120
iterations), slice the rest and the posed mesh with PrusaSlicer at 60 mm tall,
and print one table row per model: support by the prism and column estimates
and by PrusaSlicer, before and after, the reductions, E_arap, self-intersection
and runtime.

    python benchmarks/paper_table.py [--out benchmarks/RESULTS.md] [--particles 200] [--iterations 120]
        [--models bunny bb-bunny tpose branch] [--joint-limit DEG] [--w-arap W] [--overhang-model prism|column] [--free all]
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import sys
import time
from pathlib import Path

from models import available, load

import supportless as sl
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.report.report import build_report, write_pictures
from supportless.slicing.prusaslicer import find_prusa_slicer, slice_check

ROOT = Path(__file__).resolve().parents[1]



def run(name: str, args) -> dict:
    rig = load(name)
    t0 = time.perf_counter()
    settings = sl.SearchSettings().replace(
        particles=args.particles, iterations=args.iterations, seed=args.seed, w_arap=args.w_arap,
        w_overhang=args.w_overhang, w_intersect=args.w_intersect, overhang_model=args.overhang_model,
        free=args.free, fix=args.fix, overhang_angle=args.overhang_angle, overhang_margin=args.overhang_margin,
        joint_limit=args.joint_limit)
    res = sl.optimize(rig, settings)
    runtime = time.perf_counter() - t0
    rep = build_report(rig, res)
    row = {"model": name, "runtime_s": runtime, "report": rep}
    if find_prusa_slicer() and rig.dim == 3:
        sc = slice_check((rig.vertices, rig.faces), (res.vertices, rig.faces), up=rig.up, height_mm=REFERENCE_HEIGHT_MM)
        row["slicer"] = sc.to_dict()
    if args.keep:
        out = Path(args.keep)
        out.mkdir(parents=True, exist_ok=True)
        sl.write_mesh(out / f"{name}-posed.stl", res.vertices, rig.faces)
        (out / f"{name}-report.json").write_text(json.dumps(rep, indent=1))
        write_pictures(out / name, rig, res, rep)
    return row


def fmt(x, spec=".3g"):
    return "–" if x is None else format(x, spec)


def table(rows: list[dict], args) -> str:
    head = ("| model | prism before → after | column before → after | PrusaSlicer support mm before → after "
            "| reduction prism / column / PrusaSlicer | E_arap / volume | self-intersection (vol / exact pairs) "
            "| search time |")
    lines = [head, "|" + "---|" * 8]
    for r in rows:
        b, a, red = r["report"]["before"], r["report"]["after"], r["report"]["reduction_percent"]
        s = r.get("slicer")
        slicer_cell = f"{s['before']['support_mm']:.0f} → {s['after']['support_mm']:.0f}" if s else "not run"
        slicer_red = fmt(s["reduction_percent"], ".1f") + " %" if s else "–"
        lines.append(
            f"| {r['model']} | {fmt(b['support_prism'])} → {fmt(a['support_prism'])} "
            f"| {fmt(b['support_column'])} → {fmt(a['support_column'])} | {slicer_cell} "
            f"| {fmt(red['support_prism'], '.1f')} % / {fmt(red['support_column'], '.1f')} % / {slicer_red} "
            f"| {a['terms']['arap']:.4f} | {a['self_intersection_volume']:.2g} / {a['intersecting_face_pairs']} "
            f"| {r['runtime_s']:.1f} s |")
    return "\n".join(lines)


def main(argv=None):
    # every option left out takes the tool's default (supportless.SearchSettings)
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=["bunny", "bb-bunny", "tpose", "branch"])
    p.add_argument("--particles", type=int, default=None)
    p.add_argument("--iterations", type=int, default=None)
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--joint-limit", type=float, default=None)
    p.add_argument("--w-arap", type=float, default=None)
    p.add_argument("--w-overhang", type=float, default=None)
    p.add_argument("--w-intersect", type=float, default=None)
    p.add_argument("--overhang-model", default=None, choices=["prism", "column"])
    p.add_argument("--overhang-angle", type=float, default=None)
    p.add_argument("--overhang-margin", type=float, default=None)
    p.add_argument("--free", nargs="*", default=None)
    p.add_argument("--fix", nargs="*", default=None)
    p.add_argument("--out", default=None, help="Write the Markdown table here (default: print only).")
    p.add_argument("--keep", default=None, help="Folder for posed meshes, reports and pictures.")
    args = p.parse_args(argv)
    models = [m for m in args.models if available(m)]
    skipped = sorted(set(args.models) - set(models))
    rows = []
    for m in models:
        print(f"running {m} ...", file=sys.stderr, flush=True)
        rows.append(run(m, args))
        print(table(rows[-1:], args).splitlines()[-1], file=sys.stderr, flush=True)
    settings = {k: v for k, v in vars(args).items() if k not in ("out", "keep", "models")}
    text = "\n".join([
        f"## Paper experiment — {dt.date.today().isoformat()}",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}. "
        f"Settings: {json.dumps(settings)}; defaults otherwise. "
        "PrusaSlicer: its own default print settings, 60 mm tall, support = the G-code's support features of one "
        "slice with supports. "
        + (f"Skipped (missing): {', '.join(skipped)}." if skipped else ""),
        "Command: `python benchmarks/paper_table.py " + " ".join(argv if argv is not None else sys.argv[1:]) + "`",
        "",
        table(rows, args),
        "",
    ])
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
