"""Pose and print orientation: four ways to print each model, measured with PrusaSlicer.

For every built-in figure (3D), the shared models (bunny, bb-bunny) and the
planar woody, in one run:

1. **rest** — the rest pose, printed as it stands;
2. **turning only** — the rest pose turned: the candidate printing directions
   (:func:`supportless.orientation.seed_params`), the ``--slice-best`` best by
   the prism estimate sliced, the cheapest of them and upright kept (what a
   user with an auto-orienter gets, with the slicer as the judge);
3. **pose only** — ``optimize(orient="keep")``, printed as it stands;
4. **pose and orientation** — ``optimize(orient="free")`` (the default), printed
   in the found orientation; and the same with ``orient_seeds=0`` (the swarm
   alone finds the orientation, no candidate directions) to compare the two
   schemes.

Every mesh is sliced with PrusaSlicer's defaults, the model 60 mm tall as it
stands (the turned meshes scaled by the same factor). A planar figure is
extruded to a slab 1/10 of its height thick to be sliced. Prints a Markdown
table with the search times and writes it as the "## Pose and orientation"
section of ``--out``.

    python benchmarks/orient.py [--models tpose bunny woody ...] [--slice-best 4] [--out benchmarks/RESULTS.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np

import supportless as sl
from models import DATA, SHARED, available, load
from supportless.energies.surface import boundary_edges
from supportless.geometry import print_pose
from supportless.orientation import rotations_from_params, seed_params
from supportless.report import reduction
from supportless.slicer import slice_check

HEADING = "## Pose and orientation"
PLANAR = ("woody",)


def load_any(name: str) -> sl.Rig:
    """A built-in figure, a shared 3D model, or the shared planar ``woody``."""
    if name in PLANAR:
        return sl.load_rig(DATA / f"{name}.obj", DATA / f"{name}.tgf", up="y")
    return load(name)


def slab(V: np.ndarray, F: np.ndarray, thickness: float) -> tuple[np.ndarray, np.ndarray]:
    """A planar triangle mesh extruded along z into a closed slab.

    Parameters
    ----------
    V : (n, 2) float64
    F : (f, 3) int64
        Counter-clockwise triangles.
    thickness : float

    Returns
    -------
    V3 : (2n, 3) float64
    F3 : (2f + 2e, 3) int64
        Outward-oriented closed surface (e boundary edges).
    """
    n = len(V)
    top = np.column_stack([V, np.full(n, thickness / 2)])
    bottom = np.column_stack([V, np.full(n, -thickness / 2)])
    E = boundary_edges(F, V)
    a, b = E[:, 0], E[:, 1]
    sides = np.vstack([np.column_stack([a, b, b + n]), np.column_stack([a, b + n, a + n])])
    return np.vstack([top, bottom]), np.vstack([F, F[:, ::-1] + n, sides[:, [0, 2, 1]]])


def sliceable(rig, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mesh PrusaSlicer gets for vertices ``V`` of ``rig`` (a slab for a planar rig)."""
    if rig.dim == 3:
        return V, rig.faces
    return slab(V, rig.faces, 0.1 * float(np.ptp(rig.vertices @ rig.up)))


def slicer_mm(rig, V: np.ndarray) -> tuple[float, float]:
    """PrusaSlicer support of the rest pose and of ``V`` (mm of filament), scaled as the rest pose stands."""
    up3 = np.append(rig.up, 0.0) if rig.dim == 2 else rig.up
    report = slice_check(sliceable(rig, rig.vertices), sliceable(rig, V), up=up3, height_mm=60.0).to_dict()
    return report["before"]["support_mm"], report["after"]["support_mm"]


def four_ways(name: str, slice_best: int, unseeded: bool = False) -> dict:
    """The four (five) measurements of one model."""
    rig = load_any(name)
    V, F, up = rig.vertices, rig.faces, rig.up
    row: dict = {"model": name, "bones": rig.bone_count}
    turned = []
    for x in seed_params(V, F, up, slice_best, overhang_angle=45.0):
        R = rotations_from_params(x[None], up)[0]
        row["rest"], mm = slicer_mm(rig, print_pose(V, R, up))
        turned.append(mm)
    if not turned:
        row["rest"], _ = slicer_mm(rig, V)
    row["turning"] = min([row["rest"], *turned])
    variants = [("pose", {"orient": "keep"}), ("both", {})] + ([("both_unseeded", {"orient_seeds": 0})]
                                                               if unseeded else [])
    for key, changes in variants:
        t0 = time.perf_counter()
        result = sl.optimize(rig, **changes)
        seconds = time.perf_counter() - t0
        _, mm = slicer_mm(rig, result.print_vertices)
        measures = result.objective.standing.measures(rig.transforms(result.angles), rig.pose(result.angles))
        row[key] = {"mm": mm, "seconds": seconds, "stands": bool(measures["stands"]),
                    "new_contacts": int(measures["new_contact_vertices"]),
                    "up": np.round(result.rotation.T @ up, 2).tolist()}
    return row


def _pct(before: float, after: float) -> str:
    r = reduction(before, after)
    return "–" if r is None else f"{r:.1f} %"


def table(rows: list[dict]) -> str:
    unseeded = any("both_unseeded" in r for r in rows)
    head = ["model", "(1) rest mm", "(2) turning only mm", "(3) pose only mm", "(4) pose + orientation mm",
            "(4) vs min((2),(3))"] + (["(4) unseeded mm"] if unseeded else []) + \
        ["time (3)", "time (4)"] + (["time (4) unseeded"] if unseeded else []) + \
        ["printing direction (4)", "(4) stands / new contacts"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        p, b = r["pose"], r["both"]
        u = r.get("both_unseeded") or {"mm": float("nan"), "seconds": float("nan")}
        best_other = min(r["turning"], p["mm"])
        cells = [r["model"], f"{r['rest']:.0f}", f"{r['turning']:.0f} ({_pct(r['rest'], r['turning'])})",
                 f"{p['mm']:.0f} ({_pct(r['rest'], p['mm'])})", f"{b['mm']:.0f} ({_pct(r['rest'], b['mm'])})",
                 f"{100 * (b['mm'] / best_other - 1) if best_other > 0 else 0:+.1f} %"]
        cells += [f"{u['mm']:.0f} ({_pct(r['rest'], u['mm'])})"] if unseeded else []
        cells += [f"{p['seconds']:.1f} s", f"{b['seconds']:.1f} s"]
        cells += [f"{u['seconds']:.1f} s"] if unseeded else []
        cells += [str(b["up"]), f"{'yes' if b['stands'] else 'NO'} / {b['new_contacts']}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def summary(rows: list[dict]) -> str:
    """Means over the models and how often (4) is at least as good as the others."""
    def mean_red(key):
        return np.mean([reduction(r["rest"], r[key]["mm"] if isinstance(r[key], dict) else r[key]) or 0.0
                        for r in rows])
    tol = 1.01  # PrusaSlicer's noise
    ok = sum(r["both"]["mm"] <= tol * min(r["turning"], r["pose"]["mm"]) + 1.0 for r in rows)
    beats_turning = sum(r["both"]["mm"] < r["turning"] for r in rows)
    seeded_better = sum(r["both"]["mm"] <= r["both_unseeded"]["mm"] for r in rows if "both_unseeded" in r)
    ratio = [r["both"]["seconds"] / r["pose"]["seconds"] for r in rows]
    compared = [r for r in rows if "both_unseeded" in r]
    unseeded = (f" (unseeded {np.mean([reduction(r['rest'], r['both_unseeded']['mm']) or 0.0 for r in compared]):.1f} "
                f"% on {len(compared)})") if compared else ""
    return (f"Mean reduction against (1) over {len(rows)} models: turning only {mean_red('turning'):.1f} %, "
            f"pose only {mean_red('pose'):.1f} %, pose + orientation {mean_red('both'):.1f} % "
            f"{unseeded}. (4) within 1 % of min((2), (3)) on {ok} of {len(rows)}; "
            f"below (2) on {beats_turning}"
            + (f"; seeded at least as good as unseeded on {seeded_better} of {len(compared)}" if compared else "")
            + ". "
            f"Time (4) / (3): median {np.median(ratio):.2f}, largest {max(ratio):.2f}.")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--slice-best", type=int, default=4, help="Candidate directions sliced per model for (2).")
    p.add_argument("--unseeded", action="store_true",
                   help="Also search with orient_seeds=0 (no candidate directions) to compare the schemes.")
    p.add_argument("--out", default=None, help="Write the table as the '## Pose and orientation' section of FILE.")
    args = p.parse_args(argv)
    figures = [m for m in sl.DEMO_FIGURES if m != "woody2d"]
    models = args.models or figures + [m for m in SHARED if available(m)] + \
        [m for m in PLANAR if (DATA / f"{m}.obj").is_file()]
    rows = []
    for name in models:
        t0 = time.perf_counter()
        rows.append(four_ways(name, args.slice_best, args.unseeded))
        print(table(rows[-1:]).splitlines()[-1], f"({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    text = "\n".join([
        HEADING,
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores. PrusaSlicer default profile, each model 60 mm tall "
        "as it stands; support in mm of filament (reduction against (1)). Searches use the default settings "
        f"(200 x 120). (2) is the cheapest of upright and the {args.slice_best} best candidate directions, sliced. "
        "woody is planar: extruded to a slab 1/10 of its height thick for slicing.",
        "Command: `python benchmarks/orient.py " + " ".join(argv if argv is not None else sys.argv[1:]) + "`",
        "",
        table(rows),
        "",
        summary(rows),
        "",
    ])
    print(text)
    if args.out:
        path = Path(args.out)
        old = path.read_text() if path.is_file() else ""
        pattern = re.compile(rf"^{re.escape(HEADING)}\n.*?(?=^## |\Z)", re.S | re.M)
        new = pattern.sub(lambda _: text + "\n", old) if pattern.search(old) else old.rstrip() + "\n\n" + text
        path.write_text(new)


if __name__ == "__main__":
    main()
