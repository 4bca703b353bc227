"""Figures printed standing: what the pose alone saves, sliced by PrusaSlicer and Cura (normal and tree).

For each model, the command a user runs to print a figure as it is displayed::

    supportless optimize MODEL -o MODEL.stl --orient keep --seed 0 --height-mm 60 --slice-check --report R.json

then the same written file and the rest pose sliced with Cura's normal and tree supports
(``supportless slice-check``). Each row: PrusaSlicer's support filament at rest and for the file, the
reduction, Cura's two reductions, the contact merged as written (mm³ and the parts), the skinning, the largest
joint turn, whether the written STL is closed, on the plate and free of crossing triangle pairs, and the
search's time. Pictures (the found pose standing, before and after) are copied to ``docs/standing-NAME.png``
with ``--pictures``.

    python benchmarks/standing.py [--models gltf/Xbot.glb ...] [--cura] [--pictures] [--out benchmarks/RESULTS.md]

Each model runs in its own process (the command itself); a model that fails is a row with its reason.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from models import DATA, write_section

HEADING = "## Figures printed standing (issue 49)"
ROOT = Path(__file__).resolve().parents[1]

#: The shared humanoids the issue names first, then every other shared glTF character, then rigs with a TGF.
HUMANOIDS = ["gltf/Xbot.glb", "gltf/Mannequin.glb", "gltf/quaternius/Adventurer.glb", "gltf/Soldier.glb"]
OTHERS = ["gltf/CesiumMan.glb", "gltf/quaternius/Character_HumanoidRig.glb", "gltf/RobotExpressive.glb",
          "gltf/Fox.glb", "gltf/quaternius/Horse.glb", "gltf/quaternius/Wolf.glb", "gltf/quaternius/Stegosaurus.glb",
          "gltf/quaternius/Frog.glb", "gltf/quaternius/Wasp.glb", "bunny.obj", "bb-bunny.obj"]


def _cli(*args, timeout=1800) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "supportless.apps.cli", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, env=dict(os.environ, COLUMNS="200"))


def _cura(rest: Path, posed: Path, support: str) -> float | None:
    """Cura's reduction (%) of support filament from ``rest`` to ``posed`` (both print files), or None."""
    out = _cli("slice-check", rest, posed, "--slicer", "cura", "--support", support, "--json", "--up", "z",
               "--height-mm", "60")
    if out.returncode != 0:
        return None
    data = json.loads(out.stdout)
    before, after = data["before"]["support_mm"], data["after"]["support_mm"]
    return 100.0 * (1.0 - after / before) if before else None


def _write_rest(model: Path, out: Path) -> None:
    """The rest pose as the command prints it (+Z up, 60 mm tall, on the plate)."""
    import supportless as sl
    from supportless.files.meshes import write_mesh
    from supportless.files.printframe import rig_print_frame

    skeleton = model.with_suffix(".tgf") if model.suffix == ".obj" else None
    rig = sl.load_rig(model, skeleton, height_mm=60.0)
    write_mesh(out, rig_print_frame(rig, 60.0).place(rig.vertices), rig.faces)


def _written_checks(path: Path) -> str:
    """closed / on the plate / crossing pairs of a written STL, as one cell."""
    import trimesh

    from supportless.copyleft.cgal import intersecting_faces

    mesh = trimesh.load(path, force="mesh")
    pairs = len(intersecting_faces(np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)))
    on_plate = abs(float(mesh.bounds[0, 2])) < 1e-3
    return f"{'closed' if mesh.is_watertight else 'OPEN'}, {'on plate' if on_plate else 'OFF PLATE'}, {pairs} pairs"


def run(model: str, folder: Path, cura: bool, pictures: bool) -> dict:
    """One model: the command, its report, Cura's figures and the written file's checks."""
    path = DATA / model
    name = Path(model).stem
    out, report = folder / f"{name}.stl", folder / f"{name}.json"
    pics = folder / f"{name}-pictures"
    args = [path, "-o", out, "--orient", "keep", "--seed", 0, "--height-mm", 60, "--slice-check", "--report",
            report, "--pictures", pics]
    if path.suffix == ".obj":
        args += ["--skeleton", path.with_suffix(".tgf")]
    done = _cli("optimize", *args)
    if done.returncode != 0 or not report.exists():
        return {"model": model, "error": (done.stderr.strip().splitlines() or ["failed"])[-1][:160]}
    data = json.loads(report.read_text())
    sliced = data["slice_check"]
    row = {"model": model, "rest_mm": sliced["before"]["support_mm"], "after_mm": sliced["after"]["support_mm"],
           "reduction": sliced["support"]["reduction_percent"] if isinstance(sliced.get("support"), dict)
           else 100.0 * (1 - sliced["after"]["support_mm"] / sliced["before"]["support_mm"]),
           "contact_mm3": (data.get("contacts") or [{}])[0].get("overlap_mm3") or 0.0,
           "contacts": ", ".join(f"{c['parts'][0].split(':')[-1]}–{c['parts'][1].split(':')[-1]}"
                                 for c in data.get("contacts") or [] if c["parts"][0] != c["parts"][1])[:90],
           "skinning": data.get("skinning", ""), "largest": data["largest_rotation_deg"],
           "written": _written_checks(out), "seconds": data["runtime_seconds"],
           "fell_back": bool(data.get("rest_instead"))}  # why the rest pose was written, when it was
    if cura:
        rest = folder / f"{name}-rest.stl"
        _write_rest(path, rest)
        row["cura"] = _cura(rest, out, "grid") if rest.exists() else None
        row["cura_tree"] = _cura(rest, out, "tree") if rest.exists() else None
    if pictures and (pics / "before_after.png").exists():
        shutil.copy(pics / "before_after.png", ROOT / "docs" / f"standing-{name}.png")
    return row


def table(rows: list[dict], command: str) -> str:
    head = ("| model | PrusaSlicer rest → pose (mm) | less | Cura normal | Cura tree | contact merged | "
            "largest turn | written STL | skinning | search |\n|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['model']} | failed: {r['error']} |||||||||")
            continue
        pct = lambda v: "—" if v is None else f"{v:.1f} %"  # noqa: E731
        lines.append(f"| {r['model']} | {r['rest_mm']:,.0f} → {r['after_mm']:,.0f} | **{r['reduction']:.1f} %** | "
                     f"{pct(r.get('cura'))} | {pct(r.get('cura_tree'))} | {r['contact_mm3']:,.0f} mm³ "
                     f"({r['contacts'] or 'none'}) | {r['largest']:.0f}° | {r['written']} | "
                     f"{r['skinning'].replace('linear blend skinning with ', 'LBS, ')} | {r['seconds']:.0f} s |")
    ok = [r["reduction"] for r in rows if "error" not in r]
    summary = (f"\nMean PrusaSlicer reduction {np.mean(ok):.1f} % over {len(ok)} models, worst {min(ok):.1f} %."
               if ok else "")
    return (f"`{command}` on {platform.machine()}, {os.cpu_count()} cores. Each row is `supportless optimize MODEL "
            f"-o MODEL.stl --orient keep --seed 0 --height-mm 60 --slice-check` (PrusaSlicer's default profile), "
            f"then the written STL against the rest pose with Cura.\n\n" + head + "\n".join(lines) + summary + "\n")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="*", default=HUMANOIDS + OTHERS)
    parser.add_argument("--cura", action="store_true", help="also slice with Cura (normal and tree supports)")
    parser.add_argument("--pictures", action="store_true", help="copy each before/after to docs/standing-NAME.png")
    parser.add_argument("--out", type=Path, help="write the table as this file's section")
    parser.add_argument("--keep", type=Path, help="keep the written files in this folder")
    args = parser.parse_args(argv)
    folder = args.keep or Path(tempfile.mkdtemp(prefix="standing-"))
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for model in args.models:
        rows.append(run(model, folder, args.cura, args.pictures))
        print(json.dumps(rows[-1]), flush=True)
    text = table(rows, "python benchmarks/" + " ".join([Path(__file__).name, *(argv or sys.argv[1:])]))
    print(text)
    if args.out:
        write_section(args.out, HEADING, f"{HEADING}\n\n{text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
