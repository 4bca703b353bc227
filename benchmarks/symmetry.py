"""Mirrored or free: both searches on every figure with a mirror plane, checked with PrusaSlicer.

For each model whose rest skeleton has a mirror plane (the built-in 3D figures
and the shared models, and with ``--gltf`` the shared glTF characters): the
default search with ``symmetric=True`` and with ``symmetric=False``, each
answer's predicted support (the slicer model, what the tool decides by) and
PrusaSlicer's (60 mm tall, default profile). Then, for each candidate share
``s``, the rule of ``SearchSettings(symmetric=None)`` — keep the free answer
only when its predicted support is below ``(1 - s)`` times the mirrored one's —
and the mean PrusaSlicer reduction it gives over the built-in figures. Prints
Markdown; ``--out`` writes it as the "## Symmetry" section of that file.

    python benchmarks/symmetry.py [--models tpose bird ...] [--gltf] [--out benchmarks/RESULTS.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import sys
from pathlib import Path

import models
import numpy as np
from models import DATA, SHARED, available, write_section

import supportless as sl
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.search.layout import find_mirror
from supportless.search.naturalness import mirror_error_deg
from supportless.search.answer import predicted_mm
from supportless.slicing.prusaslicer import slice_check

HEADING = "## Symmetry"
SHARES = (0.0, 0.05, 0.10, 0.15, 0.20, 0.30, 1.0)


def load(name: str):
    """A built-in figure, a shared model or (``gltf/NAME``) a shared glTF character, 60 mm tall for glTF."""
    if name.startswith("gltf/"):
        return sl.load_rig(DATA / f"{name}.glb", height_mm=REFERENCE_HEIGHT_MM)
    return models.load(name) if available(name) else None


def run(name: str) -> dict | None:
    """Both searches and both slicings of one model; None when it has no mirror plane."""
    rig = load(name)
    if rig is None or rig.dim != 3 or (mirror := find_mirror(rig)) is None:
        return None
    row = {"model": name.split("/")[-1], "gltf": name.startswith("gltf/")}
    for label, mirrored in (("mirrored", True), ("free", False)):
        result = sl.optimize(rig, sl.SearchSettings(symmetric=mirrored))
        sliced = slice_check((rig.vertices, rig.faces), (result.print_vertices, rig.faces), up=rig.up,
                             height_mm=REFERENCE_HEIGHT_MM)
        row["rest_mm"] = sliced.support_mm_before
        row[label] = {"predicted_mm": predicted_mm(rig, result), "sliced_mm": sliced.support_mm_after,
                      "mirror_error_deg": float(mirror_error_deg(rig, result.angles, mirror)),
                      "seconds": result.runtime_seconds}
    return row


def reduction(row: dict, kept: str) -> float:
    """PrusaSlicer's reduction of the kept answer, percent of the rest pose's support."""
    rest = row["rest_mm"]
    return 100.0 * (1.0 - row[kept]["sliced_mm"] / rest) if rest > 0 else 0.0


def kept_at(row: dict, share: float) -> str:
    """The answer the rule keeps at ``share``."""
    return "free" if row["free"]["predicted_mm"] < (1.0 - share) * row["mirrored"]["predicted_mm"] else "mirrored"


def section(rows: list[dict], command: str) -> str:
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    lines = [HEADING, "",
             f"Machine: {platform.machine()}, {cores} cores. The default search with `symmetric=True` (mirrored) "
             "and `symmetric=False` (free) on every model whose rest skeleton has a mirror plane; predicted = the "
             "slicer model's support filament (what the tool decides by), PrusaSlicer = its default profile, 60 mm "
             "tall, against the rest pose standing.", f"Command: `{command}`", "",
             "| model | rest mm | mirrored: predicted / PrusaSlicer mm (reduction) | free: predicted / PrusaSlicer mm "
             "(reduction), mirror error | free saves (predicted / PrusaSlicer) |",
             "|---|---|---|---|---|"]
    for r in rows:
        m, f = r["mirrored"], r["free"]
        saves_p = 100 * (1 - f["predicted_mm"] / m["predicted_mm"]) if m["predicted_mm"] > 0 else 0.0
        saves_s = 100 * (1 - f["sliced_mm"] / m["sliced_mm"]) if m["sliced_mm"] > 0 else 0.0
        lines.append(f"| {r['model']} | {r['rest_mm']:.0f} | {m['predicted_mm']:.0f} / {m['sliced_mm']:.0f} "
                     f"({reduction(r, 'mirrored'):.1f} %) | {f['predicted_mm']:.0f} / {f['sliced_mm']:.0f} "
                     f"({reduction(r, 'free'):.1f} %), {f['mirror_error_deg']:.0f}° | {saves_p:+.1f} % / "
                     f"{saves_s:+.1f} % |")
    lines += ["", "The rule at each share (keep the free answer when its predicted support is below (1 - share) x "
                  "the mirrored one's): mean PrusaSlicer reduction and how many models keep the free pose.", "",
              "| share | " + " | ".join(f"{s:g}" for s in SHARES) + " |", "|---|" + "---|" * len(SHARES)]
    for group, label in ((False, "built-in and shared models"), (True, "glTF characters")):
        chosen = [r for r in rows if r["gltf"] == group]
        if not chosen:
            continue
        cells = []
        for s in SHARES:
            kept = [kept_at(r, s) for r in chosen]
            cells.append(f"{np.mean([reduction(r, k) for r, k in zip(chosen, kept)]):.1f} % "
                         f"({kept.count('free')} free)")
        lines.append(f"| {label} ({len(chosen)}) | " + " | ".join(cells) + " |")
    lines += ["", "The tool searches a mirrored figure mirrored only (`supportless.search.answer.mirrored_answer`)."]
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--gltf", action="store_true", help="Also the shared glTF characters.")
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    figures = [n for n in sl.DEMO_FIGURES if sl.demo_figure(n)[0].shape[1] == 3]
    names = args.models or [*figures, *SHARED]
    if args.gltf:
        folder = DATA / "gltf"
        names += sorted("gltf/" + str(f.relative_to(folder).with_suffix(""))
                        for f in [*folder.glob("*.glb"), *folder.glob("quaternius/*.glb")])
    rows = []
    for name in names:
        row = run(name)
        if row is None:
            print(f"{name}: no mirror plane", file=sys.stderr, flush=True)
            continue
        rows.append(row)
        print(f"{name}: rest {row['rest_mm']:.0f}, mirrored {row['mirrored']['sliced_mm']:.0f} "
              f"(pred {row['mirrored']['predicted_mm']:.0f}), free {row['free']['sliced_mm']:.0f} "
              f"(pred {row['free']['predicted_mm']:.0f})", file=sys.stderr, flush=True)
    text = section(rows, "python benchmarks/symmetry.py " + " ".join(shlex.quote(a) for a in argv))
    print(text)
    if args.out:
        write_section(Path(args.out), HEADING, text + "\n")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
