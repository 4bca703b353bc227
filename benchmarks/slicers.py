"""Three kinds of support: PrusaSlicer's grid, Cura's normal and Cura's tree supports, rest pose -> found pose.

For each model (the zoo's built-in 3D figures, the shared rigged models, the
shared glTF characters): the default search (``supportless.optimize``, as the
zoo runs it), then the rest pose and the found pose as printed, both 60 mm
tall, sliced by PrusaSlicer (its default profile, grid supports), by Cura
(CuraEngine with ``fdmprinter``'s defaults, normal supports) and by Cura with
tree supports. Support = the support extrusions of one slice with supports (the
G-code's support features; Cura's leave out the brim the supports add), mm of
1.75 mm filament. A model or slicer that fails is a cell with its one-line reason.
Prints Markdown; ``--out`` writes it as the "## Three kinds of support"
section.

    python benchmarks/slicers.py [--models bunny Fox ...] [--out benchmarks/RESULTS.md] [--threshold prusa|cura]
"""

from __future__ import annotations

import argparse
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import models
import numpy as np
from models import DATA, available, write_section

import supportless as sl
from supportless.base.errors import SupportlessError
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.slicing.choice import SlicerChoice
from supportless.slicing.prusaslicer import slice_check

HEADING = "## Three kinds of support"
ROOT = Path(__file__).resolve().parents[1]
SLICERS = (SlicerChoice("prusa", "grid"), SlicerChoice("cura", "grid"), SlicerChoice("cura", "tree"))
RIGGED = ("bunny", "bb-bunny", "libigl/elephant", "libigl/dinosaur", "libigl/hand", "libigl/arm")


def all_models() -> list[str]:
    figures = [n for n in sl.DEMO_FIGURES if sl.demo_figure(n)[0].shape[1] == 3]
    characters = sorted(str(p.relative_to(DATA / "gltf").with_suffix("")) for p in (DATA / "gltf").rglob("*.glb")
                        if "reference" not in p.parts)
    return [*figures, *RIGGED, *(f"gltf/{c}" for c in characters)]


def load(name: str, cache: str) -> sl.Rig:
    if name.startswith("gltf/"):
        return sl.load_rig(DATA / f"{name}.glb", cache_dir=cache, height_mm=REFERENCE_HEIGHT_MM)
    if not available(name):
        raise FileNotFoundError(f"missing {DATA / name}.obj or .tgf")
    return models.load(name)


def run(name: str, cache: str, settings=None) -> dict:
    """Search one model and slice its rest and found poses with each slicer."""
    row = {"model": name}
    try:
        rig = load(name, cache)
        t0 = time.perf_counter()
        result = sl.optimize(rig, settings)
        row["search_s"] = time.perf_counter() - t0
    except (SupportlessError, OSError) as exc:
        row["error"] = str(exc).splitlines()[0]
        return row
    for choice in SLICERS:
        t0 = time.perf_counter()
        try:
            s = slice_check((rig.vertices, rig.faces), (result.print_vertices, rig.faces), up=rig.up,
                            height_mm=REFERENCE_HEIGHT_MM, choice=choice).to_dict()
            row[choice.label] = {"before": s["before"]["support_mm"], "after": s["after"]["support_mm"],
                                 "reduction": s["reduction_percent"], "seconds": time.perf_counter() - t0,
                                 "before_print_s": s["before"]["total_time_s"],
                                 "after_print_s": s["after"]["total_time_s"]}
        except SupportlessError as exc:
            row[choice.label] = {"error": str(exc).splitlines()[0]}
    return row


def _cell(c: dict | None) -> str:
    if c is None:
        return "–"
    if "error" in c:
        return f"failed: {c['error']}"
    red = "–" if c["reduction"] is None else f"{c['reduction']:.1f} %"
    return f"{c['before']:.0f} → {c['after']:.0f} mm ({red})"


def table(rows: list[dict]) -> str:
    lines = ["| model | " + " | ".join(c.label for c in SLICERS) + " | search |", "|---|" + "---|" * (len(SLICERS) + 1)]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['model']} | failed: {r['error']} |" + " |" * len(SLICERS))
            continue
        lines.append(f"| {r['model']} | " + " | ".join(_cell(r.get(c.label)) for c in SLICERS)
                     + f" | {r['search_s']:.0f} s |")
    return "\n".join(lines)


def summary(rows: list[dict]) -> str:
    """Mean reduction of each slicer over the models every slicer measured, and how often the pose saved support."""
    ok = [r for r in rows if "error" not in r and all(
        "error" not in r.get(c.label, {"error": 1}) and r[c.label]["reduction"] is not None for c in SLICERS)]
    if not ok:
        return "No model was measured by every slicer."
    parts = []
    for c in SLICERS:
        reds = np.array([r[c.label]["reduction"] for r in ok])
        before = sum(r[c.label]["before"] for r in ok)
        after = sum(r[c.label]["after"] for r in ok)
        parts.append(f"{c.label}: mean reduction {reds.mean():.1f} % (median {np.median(reds):.1f} %, worst "
                     f"{reds.min():.1f} %, less support on {int((reds > 0).sum())} of {len(ok)}); all models together "
                     f"{before:.0f} → {after:.0f} mm ({100 * (1 - after / before):.1f} %)")
    return f"Over the {len(ok)} models every slicer measured:\n\n" + "\n".join(f"- {p}" for p in parts)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--out", default=None)
    p.add_argument("--threshold", choices=["prusa", "cura"], default="prusa",
                   help="Whose overhang threshold the search uses: PrusaSlicer's default (as the tool's default) or "
                        "Cura's (as with --slicer cura).")
    args = p.parse_args(argv)
    settings = None
    if args.threshold == "cura":
        from supportless.files.printer import cura_default_profile

        settings = sl.SearchSettings(overhang_angle=cura_default_profile().overhang_angle)
    names = args.models or all_models()
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        for name in names:
            rows.append(run(name, cache, settings))
            print(table(rows[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    heading = HEADING + (", searched at Cura's threshold" if settings else "")
    text = "\n".join([
        heading, "",
        f"Command: `python benchmarks/slicers.py {' '.join(shlex.quote(a) for a in argv)}` at {commit} "
        f"({platform.machine()}, 2 cores). The default search"
        + (" with Cura's overhang threshold (40° from the plate, as `--slicer cura` searches)" if settings else "")
        + "; the rest pose and the found pose as printed, 60 mm "
        "tall. PrusaSlicer 2.5: its default profile, grid supports. Cura: CuraEngine 4.13 with fdmprinter's "
        "defaults (0.1 mm layers, supports from 50° off the vertical), normal or tree supports. Support = the support "
        "extrusions of one slice with supports (the G-code's support features), mm of 1.75 mm filament.", "",
        table(rows), "", summary(rows), ""])
    print(text)
    if args.out:
        write_section(Path(args.out), heading, text)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
