"""Strength of a pose: the rest pose's and the default answer's weakest sections, and what the floor costs.

For each model: the default search (``supportless.optimize(rig, SearchSettings())``, 60 mm tall) with the
strength rule on, then :func:`supportless.report.report.strength_summary` of the rest pose (as it stands) and the
answer (as printed), the choice's refused answers, and the slicer model's choice at other floors (from the same
candidates: the answers the choice weighed, each with its safety factor). With ``--slice`` PrusaSlicer measures
the rest pose and the answer. Also one analysis of the answer is timed (warm).

    python benchmarks/strength.py [--models tpose bunny gltf/Xbot ...] [--floors 0 0.5 1 2] [--slice]
        [--out benchmarks/RESULTS.md]

A model is a built-in figure, a shared model (``bunny``), ``libigl/NAME`` or ``gltf/NAME`` (under ../shared/data).
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import sys
import time
from pathlib import Path

import numpy as np
from models import DATA, write_section
from zoo import zoo_figures

import supportless as sl
from supportless.files.printframe import REFERENCE_HEIGHT_MM, rig_print_frame
from supportless.report.report import strength_summary
from supportless.search.choice import choose_by_model
from supportless.search.sturdiness import pose_strength

HEADING = "## Strength of a pose"
SHARED = ["bunny", "bb-bunny", "libigl/dinosaur", "libigl/elephant", "libigl/hand", "libigl/arm", "gltf/Fox",
          "gltf/CesiumMan", "gltf/Xbot", "gltf/quaternius/Wolf"]


def load(name: str) -> sl.Rig | None:
    if name in sl.DEMO_FIGURES:
        return sl.load_rig(f"demo:{name}")
    if name.startswith("gltf/"):
        path = DATA / f"{name}.glb"
        return sl.load_rig(path, height_mm=REFERENCE_HEIGHT_MM) if path.is_file() else None
    obj, tgf = DATA / f"{name}.obj", DATA / f"{name}.tgf"
    return sl.load_rig(obj, tgf, up="y") if obj.is_file() and tgf.is_file() else None


def floor_choice(choice, floor: float) -> tuple[float | None, float | None]:
    """``(predicted reduction, safety factor)`` of the slicer model's choice at another floor, from the choice's
    candidates and refused answers; None where strength was not weighed."""
    if choice is None or choice.strength is None:
        return None, None
    everyone = list(choice.candidates) + list(choice.refused)
    rest = choice.strength["rest_safety_factor"] or np.inf
    bound = min(rest, floor) if floor else -np.inf
    open_ = [c for c in everyone if c.safety_factor is None or c.safety_factor >= bound * (1 - 1e-9)] or everyone
    pick, _ = choose_by_model(np.array([c.predicted_mm for c in open_]), np.array([c.result.value for c in open_]),
                              choice.rest_mm)
    c = open_[pick]
    return 1.0 - c.predicted_mm / choice.rest_mm, c.safety_factor


def run(name: str, floors: list[float], slice_: bool) -> dict:
    rig = load(name)
    if rig is None:
        return {"model": name, "skipped": "files missing"}
    settings = sl.SearchSettings().replace(print_height_mm=REFERENCE_HEIGHT_MM)
    t0 = time.perf_counter()
    result = sl.optimize(rig, settings)
    seconds = time.perf_counter() - t0
    frame = rig_print_frame(rig)
    summary = strength_summary(rig, result, frame)
    pose_strength(rig, result.angles, result.rotation, frame.height_mm)  # warm
    t1 = time.perf_counter()
    pose_strength(rig, result.angles, result.rotation, frame.height_mm)
    analysis = time.perf_counter() - t1
    row = {"model": name, "faces": len(rig.faces), "seconds": seconds, "analysis_s": analysis, "strength": summary,
           "choice": result.choice.strength if result.choice else None}
    row["floors"] = {f: floor_choice(result.choice, f) for f in floors}
    if slice_:
        from supportless.slicing.prusaslicer import SlicerError, slice_check

        try:
            row["slicer"] = slice_check((rig.vertices, rig.faces), (result.print_vertices, rig.faces), up=rig.up,
                                        height_mm=REFERENCE_HEIGHT_MM).to_dict()
        except SlicerError as exc:
            row["slicer_error"] = str(exc).splitlines()[0]
    return row


def _sf(x) -> str:
    return "–" if x is None else f"{x:.2f}"


def _where(part: dict) -> str:
    w = part["weakest"]
    if not w:
        return "nothing pulls"
    breaks = "–" if w["breaks_at_n"] is None else f"{w['breaks_at_n']:.1f} N"
    return f"{(w['bone'] or '?').split(':')[-1]} {w['height_mm']:.0f} mm, {w['direction']}, {breaks}"


def table(rows: list[dict], floors: list[float]) -> str:
    head = ("| model | faces | rest: safety, weakest | answer: safety, weakest | refused | "
            + " | ".join(f"floor {f:g}: reduction / safety" for f in floors) + " | PrusaSlicer | analysis |")
    lines = [head, "|" + "---|" * (7 + len(floors))]
    for r in rows:
        if "skipped" in r:
            continue
        s, c = r["strength"], r["choice"] or {}
        floors_text = " | ".join(
            "–" if red is None else f"{100 * red:.1f} % / {_sf(sf)}" for red, sf in (r["floors"][f] for f in floors))
        sliced = r.get("slicer")
        sliced = f"{sliced['reduction_percent']:.1f} %" if sliced and sliced.get("reduction_percent") is not None \
            else "–"
        lines.append(f"| {r['model']} | {r['faces']} | {_sf(s['rest']['safety_factor'])}, {_where(s['rest'])} "
                     f"| {_sf(s['answer']['safety_factor'])}, {_where(s['answer'])} "
                     f"| {len(c.get('refused') or [])}{' (changed)' if c.get('changed_choice') else ''} "
                     f"| {floors_text} | {sliced} | {r['analysis_s']:.2f} s |")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--floors", nargs="+", type=float, default=[0.0, 0.5, 1.0, 2.0])
    p.add_argument("--slice", action="store_true", help="PrusaSlicer on the rest pose and the answer.")
    p.add_argument("--out", default=None, help="Write the table as the '## Strength of a pose' section of this file.")
    args = p.parse_args(argv)
    models = args.models or [*zoo_figures(), *SHARED]
    rows = []
    for name in models:
        print(f"running {name} ...", file=sys.stderr, flush=True)
        rows.append(run(name, args.floors, args.slice))
        if "skipped" not in rows[-1]:
            print(table(rows[-1:], args.floors).splitlines()[-1], flush=True)
    text = table(rows, args.floors)
    done = [r for r in rows if "skipped" not in r]
    weaker = [r["model"] for r in done if r["strength"]["answer"]["safety_factor"] is not None
              and r["strength"]["rest"]["safety_factor"] is not None
              and r["strength"]["answer"]["safety_factor"] < min(r["strength"]["rest"]["safety_factor"], 1.0) - 1e-9]
    command = "python benchmarks/strength.py " + " ".join(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    note = (f"{len(done)} models; answers weaker than both the rest pose and 1.0: {', '.join(weaker) or 'none'}. "
            f"Machine: {platform.machine()}, {os.cpu_count()} cores. Command: `{command}`.")
    print(text + "\n\n" + note)
    if args.out:
        write_section(Path(args.out), HEADING, f"{HEADING}\n\n{note}\n\n{text}\n")


if __name__ == "__main__":
    main()
