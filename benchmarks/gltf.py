"""Real rigged glTF characters end to end, measured with PrusaSlicer.

For each shared glTF asset (``../shared/data/gltf/*.glb`` and
``../shared/data/gltf/quaternius/*.glb``): what each repair
step did to make the print body, the preparation time (cold cache), the
default search (200 x 120, print orientation free) and PrusaSlicer's support
filament for the rest print body standing against the result as printed, both
60 mm tall (PrusaSlicer's default profile). Pictures of each result go to
``docs/gltf-NAME.png`` (the found pose standing and as printed), or with
``--sheet docs/gltf.png`` one contact sheet of every before/after. Prints a
Markdown section and, with ``--out``, writes it as the "## glTF characters"
section of that file.

A model that fails is a row with its one-line reason; the run goes on. The
section ends with the mean and the worst PrusaSlicer reduction.

    python benchmarks/gltf.py [--models Fox quaternius/Wolf] [--particles N] [--iterations N] [--seed S] [--out benchmarks/RESULTS.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from models import DATA, write_section
from zoo import contact_sheet

import supportless as sl
import trimesh

from supportless.copyleft.cgal import intersecting_face_pairs
from supportless.energies.footprint import footprint_area
from supportless.files.meshes import read_mesh
from supportless.files.printframe import REFERENCE_HEIGHT_MM, rig_print_frame
from supportless.report.outputs import write_posed
from supportless.report.report import build_report, write_pictures
from supportless.slicing.prusaslicer import slice_check

HEADING = "## glTF characters"
ROOT = Path(__file__).resolve().parents[1]


def run(path: Path, cache_dir: str, settings=None, pictures: Path | None = None) -> dict:
    """Prepare, search and slice one asset; returns the figures of one table row."""
    t0 = time.perf_counter()
    from supportless.copyleft.cgal import intersecting_face_pairs
    from supportless.files.gltf import read_gltf_skin

    rest = read_gltf_skin(path).vertices
    height_m = float(np.ptp(rest[:, 1]))
    rig = sl.load_rig(path, cache_dir=cache_dir, height_mm=REFERENCE_HEIGHT_MM)
    prepare_s = time.perf_counter() - t0
    rest_pairs = intersecting_face_pairs(rig.vertices, rig.faces)
    result = sl.optimize(rig, settings or sl.SearchSettings())
    report = build_report(rig, result)
    frame = rig_print_frame(rig, REFERENCE_HEIGHT_MM)
    footprint = float(footprint_area(result.print_vertices, rig.faces, rig.up, frame.scale))
    with tempfile.TemporaryDirectory() as tmp:
        written = Path(tmp) / "posed.stl"  # the file as the command line writes it, sliced as it reads it
        write_posed(written, rig, result.angles, result.vertices, result.print_vertices, frame)
        Vw, Fw = read_mesh(written)
        closed = bool(trimesh.Trimesh(Vw, Fw).is_watertight)
        written_pairs = intersecting_face_pairs(Vw, Fw)
        sliced = slice_check((frame.place(rig.vertices), rig.faces), str(written), up=(0.0, 0.0, 1.0),
                             height_mm=None).to_dict()
        for label, file in write_pictures(tmp, rig, result, report):
            if Path(file).name == "print.png" and pictures is None:
                shutil.copy(file, ROOT / "docs" / f"gltf-{path.stem}.png")
            if label == "before/after picture" and pictures is not None:
                pictures.mkdir(parents=True, exist_ok=True)
                shutil.copy(file, pictures / f"{path.stem}.png")
    before = report["before"]
    after = report["after"]
    return {
        "name": path.stem, "height_m": height_m, "rest_pairs": rest_pairs, "log": rig.info["gltf"]["log"], "faces": len(rig.faces), "bones": rig.bone_count,
        "free": int((~sl.SearchSettings().fixed_bones(rig)).sum()), "tets": len(rig.tets),
        "prepare_s": prepare_s, "search_s": result.runtime_seconds,
        "prism": (before["support_prism"], after["support_prism"]),
        "slicer": (sliced["before"]["support_mm"], sliced["after"]["support_mm"]),
        "pairs": after.get("intersecting_face_pairs"), "stands": after.get("stands"),
        "footprint": footprint, "closed": closed, "written_pairs": written_pairs,
        "turn": report["print_rotation"]["angle_deg"], "largest": report["largest_rotation_deg"],
        "natural": report["naturalness"],
        "picture": None if pictures is None else str(pictures / f"{path.stem}.png"),
    }


def _deg(x) -> str:
    return "–" if x is None else f"{x:.0f}°"


def _chain(natural: dict) -> str:
    """The largest chain-end turn and the bone, short."""
    name = (natural.get("chain_end_name") or f"bone {natural['chain_end']}").split(":")[-1]
    return f"{natural['largest_chain_turn_deg']:.0f}° ({name})"


def _range(natural: dict) -> str:
    """The named joint nearest its range: ``LeftLeg bend 40°/140°``, or – without a table."""
    use = natural.get("joint_range")
    if not use:
        return "–"
    return (f"{use['joint'].split(':')[-1]} {use['measure']} {abs(use['angle_deg']):.0f}°/{abs(use['limit_deg']):.0f}°"
            + (f", {use['outside_deg']:.0f}° out" if use["outside_deg"] >= 0.5 else ""))


def section(rows: list[dict], argv: list[str]) -> str:
    lines = [
        HEADING, "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores. Default settings (200 x 120, `--orient free`), "
        "skin weights from the file, the print body scaled to 60 mm tall; PrusaSlicer default profile, support "
        "filament of the rest print body standing against the result as printed, written as the command line "
        "writes it (`-o posed.stl`) and sliced from that file. Preparation with a cold cache. \"Rests on\": the "
        "first layer's contact with the plate (the section 0.1 mm over the lowest point, mm² at 60 mm tall); "
        "\"file closed\": trimesh reads the written STL watertight, and its intersecting triangle pairs (CGAL).",
        "Command: `python benchmarks/gltf.py " + " ".join(argv) + "`", "",
        "| model | height in the file | faces / tets | bones (free) | prepare | search | prism estimate | "
        "PrusaSlicer support | turned | largest joint turn | largest chain-end turn | named joint nearest its "
        "range | mirror error | exact pairs rest / result | stands | rests on | file closed, pairs |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['name']} | failed: {r['error']} |" + " |" * 15)
            continue
        (pb, pa), (sb, sa) = r["prism"], r["slicer"]
        lines.append(
            f"| {r['name']} | {r['height_m']:.2f} m | {r['faces']} / {r['tets']} | {r['bones']} ({r['free']}) | {r['prepare_s']:.1f} s | "
            f"{r['search_s']:.1f} s | {pb:.0f} → {pa:.0f} ({(1 - pa / pb) * 100:.1f} % less) | "
            f"{sb:.0f} → {sa:.0f} mm ({(1 - sa / sb) * 100:.1f} % less) | {r['turn']:.0f}° | "
            f"{r['largest']:.0f}° | {_chain(r['natural'])} | {_range(r['natural'])} | "
            f"{_deg(r['natural']['mirror_error_deg'])} | {r['rest_pairs']} / {r['pairs']} | "
            f"{'yes' if r['stands'] else 'no'} | {r['footprint']:.1f} mm² | "
            f"{'yes' if r['closed'] else 'NO'}, {r['written_pairs']} |")
    done = [1 - r["slicer"][1] / r["slicer"][0] for r in rows if "error" not in r and r["slicer"][0] > 0]
    lines.append("")
    if done:
        lines.append(f"{len(done)} of {len(rows)} ran; PrusaSlicer support reduction mean {np.mean(done) * 100:.1f} %, "
                     f"worst {np.min(done) * 100:.1f} %.")
        lines.append("")
    for r in rows:
        if "error" in r:
            continue
        lines.append(f"What was done to {r['name']} (one line per step):")
        lines.append("")
        lines += [f"- {line}" for line in r["log"]]
        lines.append("")
        if "--sheet" not in argv:  # with a contact sheet the per-model pictures are not redrawn
            lines.append(f"![{r['name']}](../docs/gltf-{r['name']}.png)")
            lines.append("")
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--out", default=None, help="Write the section into this Markdown file.")
    p.add_argument("--sheet", default=None,
                   help="Draw a contact sheet of every character's before/after picture to this PNG "
                        "(e.g. docs/gltf.png); the per-model print pictures in docs/ are then left alone.")
    p.add_argument("--no-anatomy", action="store_true", help="SearchSettings.anatomy=False.")
    p.add_argument("--chain-limit", type=float, default=None, help="SearchSettings.chain_limit, degrees.")
    p.add_argument("--w-chain", type=float, default=None, help="SearchSettings.w_chain.")
    p.add_argument("--symmetric", choices=("auto", "on", "off"), default="auto",
                   help="SearchSettings.symmetric: None (the tool's choice), True or False.")
    p.add_argument("--particles", type=int, default=None, help="SearchSettings.particles.")
    p.add_argument("--iterations", type=int, default=None, help="SearchSettings.iterations.")
    p.add_argument("--seed", type=int, default=None, help="SearchSettings.seed.")
    args = p.parse_args(argv)
    settings = sl.SearchSettings().replace(chain_limit=args.chain_limit, w_chain=args.w_chain,
                                           particles=args.particles, iterations=args.iterations, seed=args.seed)
    if args.no_anatomy:
        settings = settings.replace(anatomy=False)
    settings = settings.replace(symmetric={"auto": None, "on": True, "off": False}[args.symmetric])
    folder = DATA / "gltf"
    names = args.models or sorted(str(f.relative_to(folder).with_suffix("")) for f in
                                  [*folder.glob("*.glb"), *folder.glob("quaternius/*.glb")])
    rows = []
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as tmp:
        pictures = Path(tmp) if args.sheet else None
        for name in names:
            t0 = time.perf_counter()
            try:
                rows.append(run(folder / f"{name}.glb", cache, settings, pictures))
            except Exception as exc:  # a benchmark row, not the end of the table
                rows.append({"name": Path(name).name, "error": f"{type(exc).__name__}: {exc}"})
                print(f"{name}: failed: {rows[-1]['error']}", file=sys.stderr, flush=True)
                continue
            r = rows[-1]
            print(f"{name}: slicer {r['slicer'][0]:.0f} -> {r['slicer'][1]:.0f} mm, pairs {r['rest_pairs']} -> "
                  f"{r['pairs']}, search {r['search_s']:.1f} s ({time.perf_counter() - t0:.0f} s)",
                  file=sys.stderr, flush=True)
        if args.sheet:
            contact_sheet([{**r, "model": r["name"], "slicer": {"reduction_percent": 100 * (1 - r["slicer"][1] / r["slicer"][0])
                                                               if r["slicer"][0] > 0 else None}}
                           for r in rows if "error" not in r], Path(args.sheet))
    text = section(rows, argv)
    print(text)
    if args.out:
        write_section(Path(args.out), HEADING, text + "\n")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
