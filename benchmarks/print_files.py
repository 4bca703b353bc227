"""Files that print as written: the tool's files opened in PrusaSlicer and CuraEngine exactly as written.

For each model, as a new user would: ``supportless optimize MODEL -o OUT.stl
--seed 0 --slice-check --report R --pose P`` and ``supportless apply MODEL
--pose P -o OUT.3mf``; the rest pose is written the same way (``apply`` with
an all-zero pose). Then each file is sliced by the slicers' own command lines,
with no help from the tool (no turning, no scaling; the slicer centres the
object on its bed and drops it to the plate as it does for any file):

* PrusaSlicer 2.5 with the tool's reference settings (PrusaSlicer's own
  defaults spelled out, automatic supports), support filament = with - without;
* CuraEngine 4.13 (Debian's ``cura-engine``; printer definitions from Debian's
  ``cura`` package, ``--cura-defs``), normal supports, ``Filament (mm^3)``
  with - without, as mm of 1.75 mm filament.

The table shows the report's figure (the tool's ``--slice-check``, which
slices the written file) beside the slicers' figures of the STL and the 3MF,
the written size and the lowest z.

    python benchmarks/print_files.py [--models bunny Fox elephant] [--cura-defs DIR] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from supportless.files.meshes import read_mesh
from supportless.files.posefile import write_pose
from supportless.slicing.prusaslicer import PRESETS, SUPPORT_OPTIONS, find_prusa_slicer

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("SUPPORTLESS_SHARED_DATA", ROOT.parent / "shared" / "data"))
MODELS = {"bunny": SHARED / "bunny.obj", "Fox": SHARED / "gltf" / "Fox.glb",
          "elephant": SHARED / "libigl" / "elephant.obj", "bb-bunny": SHARED / "bb-bunny.obj",
          "CesiumMan": SHARED / "gltf" / "CesiumMan.glb", "dinosaur": SHARED / "libigl" / "dinosaur.obj"}
CURA_DEFS = Path("/opt/cura-defs/x/usr/share/cura/resources/definitions")
FILAMENT_AREA = math.pi * (1.75 / 2) ** 2


def run(cmd: list[str]) -> subprocess.CompletedProcess:
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"failed: {' '.join(cmd)}\n{done.stderr[-2000:]}")
    return done


def prusa_support_mm(path: Path, work: Path) -> float:
    """PrusaSlicer's support filament of a file opened as it is (centred on a 250 x 210 bed, dropped to it)."""
    exe = find_prusa_slicer()
    cfg = [a for k, v in PRESETS["prusa-defaults"].items() for a in (f"--{k}", v)]
    used = []
    for support in (True, False):
        gcode = work / f"{path.stem}-{path.suffix[1:]}-{'s' if support else 'n'}.gcode"
        run([exe, "--export-gcode", "--loglevel=1", f"--datadir={work / 'datadir'}", *cfg,
             "--bed-shape", "0x0,250x0,250x210,0x210", "--center", "125,105",
             *(SUPPORT_OPTIONS if support else ("--no-support-material",)), "--output", str(gcode), str(path)])
        text = gcode.read_text()
        used.append(sum(float(x) for x in re.search(r"; filament used \[mm\] = (.+)", text).group(1).split(",")))
    return used[0] - used[1]


def cura_support_mm(path: Path, work: Path, defs: Path) -> float:
    """CuraEngine's support filament (normal supports) of an STL as it is, mm of 1.75 mm filament."""
    used = []
    for support in (True, False):
        out = work / f"{path.stem}-cura-{'s' if support else 'n'}.gcode"
        done = run(["CuraEngine", "slice", "-v", "-j", str(defs / "fdmprinter.def.json"),
                    "-s", f"support_enable={'true' if support else 'false'}", "-s", "support_structure=normal",
                    "-s", "machine_center_is_zero=false", "-s", "center_object=true",
                    "-s", "material_diameter=1.75", "-s", "roofing_layer_count=0",
                    "-e0", "-j", str(defs / "fdmextruder.def.json"), "-e0", "-l", str(path), "-o", str(out)])
        used.append(float(re.search(r"Filament \(mm\^3\): ([0-9.]+)", done.stderr).group(1)))
    return (used[0] - used[1]) / FILAMENT_AREA


def measure(name: str, model: Path, work: Path, cura_defs: Path | None) -> dict:
    out = work / name
    out.mkdir()
    stl, mf, rest = out / f"{name}.stl", out / f"{name}.3mf", out / f"{name}-rest.stl"
    report, pose = out / "report.json", out / "pose.json"
    run(["supportless", "optimize", str(model), "-o", str(stl), "--seed", "0", "--slice-check", "-q",
         "--report", str(report), "--pose", str(pose)])
    run(["supportless", "apply", str(model), "--pose", str(pose), "-o", str(mf)])
    data = json.loads(pose.read_text())
    zero = out / "rest-pose.json"
    write_pose(zero, np.zeros_like(np.asarray(data["angles"])), np.asarray(data["bones"]),
               extra={"print_frame": data["print_frame"]}, tree=(data["tree"]["parents"], data["tree"]["pivots"]))
    run(["supportless", "apply", str(model), "--pose", str(zero), "-o", str(rest)])
    r = json.loads(report.read_text())
    V, _ = read_mesh(stl)
    row = {"model": name, "report_before": r["slice_check"]["before"]["support_mm"],
           "report_after": r["slice_check"]["after"]["support_mm"],
           "size_mm": np.ptp(V, axis=0).round(1).tolist(), "min_z": float(V[:, 2].min()),
           "prusa_rest": prusa_support_mm(rest, out), "prusa_stl": prusa_support_mm(stl, out),
           "prusa_3mf": prusa_support_mm(mf, out)}
    if cura_defs is not None:
        row |= {"cura_rest": cura_support_mm(rest, out, cura_defs), "cura_stl": cura_support_mm(stl, out, cura_defs)}
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", nargs="+", default=["bunny", "Fox", "elephant"], choices=list(MODELS))
    ap.add_argument("--cura-defs", type=Path, default=CURA_DEFS)
    ap.add_argument("--out", type=Path, default=None, help="Also write the table to this file.")
    args = ap.parse_args()
    if find_prusa_slicer() is None:
        raise SystemExit("PrusaSlicer not found: apt-get install prusa-slicer")
    defs = args.cura_defs if (args.cura_defs / "fdmprinter.def.json").is_file() else None
    if defs is None:
        print(f"no Cura definitions in {args.cura_defs}: CuraEngine columns left out "
              "(apt-get download cura; dpkg-deb -x cura_*.deb DIR)", file=sys.stderr)
    lines = ["| model | report: rest -> written (PrusaSlicer) | PrusaSlicer: rest file | STL as written | "
             "3MF as written | Cura: rest file | STL as written | written size (mm) | min z |",
             "|---|---|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory(prefix="supportless-print-files-") as tmp:
        for name in args.models:
            r = measure(name, MODELS[name], Path(tmp), defs)
            cura = (f"{r['cura_rest']:.0f} mm | {r['cura_stl']:.0f} mm" if "cura_rest" in r else "- | -")
            lines.append(f"| {name} | {r['report_before']:.0f} -> {r['report_after']:.0f} mm | "
                         f"{r['prusa_rest']:.0f} mm | {r['prusa_stl']:.0f} mm | {r['prusa_3mf']:.0f} mm | {cura} | "
                         f"{' x '.join(f'{x:g}' for x in r['size_mm'])} | {r['min_z']:.3f} |")
            print(lines[-1], flush=True)
    text = "\n".join(lines) + f"\n\n{platform.machine()}, {os.cpu_count()} cores; `python benchmarks/print_files.py`\n"
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
