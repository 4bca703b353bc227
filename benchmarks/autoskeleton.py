"""Skeletons from the shape against hand-made ones, and figures that have none, checked with PrusaSlicer.

For every shared model with a TGF (the bunnies, woody, the libigl rigs, the
prototype's cantilever): the default search with its hand-made skeleton and
with one built from the shape (the TGF ignored), PrusaSlicer's support of
each (default profile, 60 mm tall). For every figure in
``../shared/data/unrigged/``: the built skeleton only. A model that fails is a
row with its one-line reason. Prints Markdown; ``--sheet`` draws every
before/after picture into one contact sheet; ``--out`` writes the section
"## Skeletons from the shape".

    python benchmarks/autoskeleton.py [--models bunny unrigged/lion ...] [--sheet docs/autoskeleton.png]
        [--out benchmarks/RESULTS.md] [--up auto]
    python benchmarks/autoskeleton.py --dense     # the skeleton of a 1.4M-triangle figure
"""

from __future__ import annotations

import argparse
import shlex
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from models import DATA, write_section
from zoo import contact_sheet

import supportless as sl
from supportless.copyleft.cgal import intersecting_face_pairs
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.report.report import build_report, write_pictures
from supportless.rig.autoskeleton import auto_skeleton
from supportless.slicing.prusaslicer import slice_check

HEADING = "## Skeletons from the shape"
#: The shared models with a hand-made skeleton (woody and the prototype's cantilever are planar: no slicer, the
#: estimate's reduction instead).
RIGGED = ("bunny", "bb-bunny", "libigl/elephant", "libigl/dinosaur", "libigl/hand", "libigl/arm", "woody",
          "prototype/cantilever_M")


def mesh_file(name: str) -> Path | None:
    for ext in (".obj", ".off", ".stl", ".ply"):
        if (DATA / f"{name}{ext}").is_file():
            return DATA / f"{name}{ext}"
    return None


def run(name: str, skeleton, pictures: Path, cache: str, up: str = "auto") -> dict:
    """One search and slicing; ``skeleton`` None builds one from the shape."""
    path = mesh_file(name)
    label = f"{name} ({'hand' if skeleton is not None else 'auto'})"
    if path is None:
        return {"model": label, "error": "missing"}
    t0 = time.perf_counter()
    try:
        if skeleton is None:
            V, F = sl.read_mesh(path)
            t = time.perf_counter()
            auto_skeleton(V, F, np.array([0.0, 1.0, 0.0]))
            skeleton_s = time.perf_counter() - t
            rig = sl.load_rig(path, "auto", up=up, cache_dir=cache, height_mm=REFERENCE_HEIGHT_MM)
        else:
            skeleton_s = None
            rig = sl.load_rig(path, skeleton, up=up, cache_dir=cache, height_mm=REFERENCE_HEIGHT_MM)
        prepare_s = time.perf_counter() - t0
        result = sl.optimize(rig)
        report = build_report(rig, result)
        if rig.dim == 2:  # no slicer for a planar figure: the estimate
            sliced = None
            before, after = (report[k]["support_prism"] for k in ("before", "after"))
            reduction = report["reduction_percent"]["support_prism"]
        else:
            sliced = slice_check((rig.vertices, rig.faces), (result.print_vertices, rig.faces), up=rig.up,
                                 height_mm=REFERENCE_HEIGHT_MM)
            before, after = sliced.support_mm_before, sliced.support_mm_after
            reduction = None if before <= 0 else 100 * (1 - after / before)
        written = dict(write_pictures(pictures / label.replace("/", "-"), rig, result, report))
    except Exception as exc:  # a row, not the end of the table
        return {"model": label, "error": f"{type(exc).__name__}: {str(exc).splitlines()[0]}"}
    return {"model": label, "bones": rig.bone_count, "faces": len(rig.faces), "skeleton_s": skeleton_s,
            "prepare_s": prepare_s, "search_s": result.runtime_seconds,
            "before": before, "after": after, "planar": sliced is None, "up": rig.info.get("up"),
            "reduction": reduction,  # PrusaSlicer's, or the estimate's for a planar figure
            "slicer": None if sliced is None else {"reduction_percent": reduction},  # the sheet's titles: slicer only
            "pairs": "2D" if rig.dim == 2 else intersecting_face_pairs(result.print_vertices, rig.faces),
            "stands": report["after"].get("stands"), "stood": report["before"].get("stands"),
            "chain": report["naturalness"]["largest_chain_turn_deg"],
            "picture": written["before/after picture"]}


def dense_timing(subdivisions: int = 2) -> str:
    """Building the skeleton (and guessing the up direction) of the armadillo subdivided to over a million triangles."""
    import trimesh

    from supportless.files.upaxis import guess_up

    V, F = sl.read_mesh(DATA / "unrigged/armadillo.obj")
    mesh = trimesh.Trimesh(V, F, process=False)
    for _ in range(subdivisions):
        mesh = mesh.subdivide()
    V, F = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    t = time.perf_counter()
    up, _ = guess_up(V, F, "armadillo.obj")
    t_up = time.perf_counter() - t
    t = time.perf_counter()
    _, B = auto_skeleton(V, F, up)
    return (f"The armadillo subdivided {subdivisions} times ({len(F)} triangles): up direction guessed in {t_up:.1f} s, "
            f"skeleton of {len(B)} bones built in {time.perf_counter() - t:.1f} s.")


def table(rows: list[dict]) -> str:
    lines = ["| model (skeleton) | bones | faces | skeleton built | prepare | search | PrusaSlicer support | "
             "exact pairs | stands (rest / found) | largest chain-end turn |", "|" + "---|" * 10]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['model']} | failed: {r['error']} |" + " |" * 8)
            continue
        red = r["reduction"]
        built = "–" if r["skeleton_s"] is None else f"{r['skeleton_s']:.1f} s"
        lines.append(f"| {r['model']} | {r['bones']} | {r['faces']} | {built} | {r['prepare_s']:.1f} s | "
                     f"{r['search_s']:.1f} s | "
                     + (f"2D, estimate {r['before']:.3g} → {r['after']:.3g} ({'–' if red is None else format(red, '.1f') + ' %'})"
                        if r.get("planar") else f"{r['before']:.0f} → {r['after']:.0f} mm "
                        f"({'–' if red is None else format(red, '.1f') + ' %'})") + f" | {r['pairs']} | "
                     f"{'yes' if r['stood'] else 'no'} / {'yes' if r['stands'] else 'no'} | {r['chain']:.0f}° |")
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--sheet", default=None)
    p.add_argument("--out", default=None)
    p.add_argument("--auto-only", action="store_true", help="Only the built skeletons (not the hand-made ones).")
    p.add_argument("--dense", action="store_true", help="Only time the skeleton of a million-triangle armadillo.")
    p.add_argument("--up", default="auto", help="Printing direction of every model [default: auto, as a new user].")
    args = p.parse_args(argv)
    if args.dense:
        print(dense_timing())
        return
    unrigged = sorted(f"unrigged/{f.stem}" for f in (DATA / "unrigged").glob("*.*"))
    names = args.models or [*RIGGED, *unrigged]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        pictures, cache = Path(tmp) / "pictures", str(Path(tmp) / "cache")
        for name in names:
            tgf = DATA / f"{name}.tgf"
            for skeleton in ((tgf, None) if tgf.is_file() and not args.auto_only else (None,)):
                rows.append(run(name, skeleton, pictures, cache, args.up))
                print(table(rows[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
        if args.sheet:
            contact_sheet([r for r in rows if "error" not in r], Path(args.sheet))
            shutil.rmtree(pictures, ignore_errors=True)
    pairs = {}
    for r in rows:
        if "error" not in r and r["reduction"] is not None and not r.get("planar"):
            base, kind = r["model"].rsplit(" (", 1)
            pairs.setdefault(base, {})[kind.rstrip(")")] = r["reduction"]
    both = [v for v in pairs.values() if "hand" in v and "auto" in v]
    only = [v["auto"] for k, v in pairs.items() if k.startswith("unrigged/") and "auto" in v]
    text = "\n".join([HEADING, "", "Command: `python benchmarks/autoskeleton.py " + " ".join(shlex.quote(a) for a in argv)
                      + f"` (2 cores; default search, PrusaSlicer default profile, 60 mm tall, up {args.up}).", "",
                      table(rows), "",
                      (f"Hand against built skeleton over {len(both)} models: mean PrusaSlicer reduction "
                       f"{np.mean([v['hand'] for v in both]):.1f} % against {np.mean([v['auto'] for v in both]):.1f} %."
                       if both else ""),
                      (f"Unrigged figures ({len(only)} of {len(unrigged)} ran): mean {np.mean(only):.1f} %." if only
                       else "")])
    print(text)
    if args.out:
        write_section(Path(args.out), HEADING, text + "\n")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
