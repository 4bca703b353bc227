"""The default answer against the simpler ones: pose, print orientation and the choice, measured with PrusaSlicer.

For every built-in figure (3D), the shared models (bunny, bb-bunny), the
shared glTF characters (``gltf/*.glb``, ``gltf/quaternius/*.glb``) and the
planar woody, in one run:

1. **rest** — the rest pose, printed as it stands;
2. **turning only** — the rest pose turned: the candidate printing directions
   (:func:`supportless.search.orientation.seed_params`), the ``--slice-best`` best by
   the prism estimate sliced, the cheapest of them and upright kept (what a
   user with an auto-orienter gets, with the slicer as the judge);
3. **pose only** — ``optimize(orient="keep")``, printed as it stands;
4. **search's best** — ``optimize(choose=False)``: pose and orientation, the
   search's own best (the default before issue 32; the first answer the choice
   weighs, so its time is (5)'s less the choice's);
5. **model's choice** — ``optimize()`` without a slicer: the answer with the
   least predicted support (:func:`supportless.search.choice.choose`);
6. **default** — the same with PrusaSlicer found: the answers
   :func:`supportless.slicing.ranking.to_slice` picks are sliced and
   :func:`supportless.slicing.ranking.pick_sliced` chooses, as ``supportless optimize``
   does (every answer of the choice is sliced once here, so the table also
   shows what each would have cost).

Every mesh is sliced once with PrusaSlicer's defaults and supports, the
support read from the G-code's support features
(:func:`supportless.slicing.prusaslicer.slice_support` with ``by_feature``), the model 60 mm
tall as it stands (the turned meshes scaled by the same factor). A planar
figure is extruded to a slab 1/10 of its height thick. Prints a Markdown table
and writes it as the "## Pose and orientation" section of ``--out``.

    python benchmarks/orient.py [--models tpose bunny gltf:Fox woody ...] [--slice-best 4] [--out benchmarks/RESULTS.md]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np
from models import DATA, SHARED, available, load

import supportless as sl
from supportless.base.geometry import print_pose
from supportless.energies.surface import boundary_edges
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.report.report import reduction
from supportless.search.orientation import rotations_from_params, seed_params
from supportless.slicing.prusaslicer import scale_for_height, slice_support
from supportless.slicing.ranking import SLICE_RANK, SLICE_WINDOW, pick_sliced, to_slice

HEADING = "## Pose and orientation"
PLANAR = ("woody",)
GLTF = DATA / "gltf"


def load_any(name: str) -> sl.Rig:
    """A built-in figure, a shared 3D model, a shared glTF character (``gltf:Fox``) or the planar ``woody``."""
    if name in PLANAR:
        return sl.load_rig(DATA / f"{name}.obj", DATA / f"{name}.tgf", up="y")
    if name.startswith("gltf:"):
        stem = name[5:]
        path = next(p for p in (GLTF / f"{stem}.glb", GLTF / "quaternius" / f"{stem}.glb") if p.is_file())
        return sl.load_rig(path, height_mm=REFERENCE_HEIGHT_MM)
    return load(name)


def gltf_names() -> list[str]:
    """The shared glTF characters, as ``gltf:NAME``."""
    return [f"gltf:{p.stem}" for p in sorted([*GLTF.glob("*.glb"), *GLTF.glob("quaternius/*.glb")])]


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


def measure(name: str, slice_best: int) -> dict:
    """Every answer of one model, sliced in one batch (copies of a mesh once)."""
    rig = load_any(name)
    V, F, up = rig.vertices, rig.faces, rig.up
    row: dict = {"model": name, "bones": rig.bone_count}
    meshes = {"rest": V}
    for i, x in enumerate(seed_params(V, F, up, slice_best, overhang_angle=45.0)):
        meshes[f"turn{i}"] = print_pose(V, rotations_from_params(x[None], up)[0], up)
    t0 = time.perf_counter()
    pose = sl.optimize(rig, orient="keep")
    row["pose_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    default = sl.optimize(rig)
    row["default_s"] = time.perf_counter() - t0
    row["plain_s"] = row["default_s"] - (default.choice.seconds if default.choice is not None else 0.0)
    meshes["pose"] = pose.print_vertices
    choice = default.choice
    # the search's own best (optimize(choose=False)): the choice's first answer
    meshes["plain"] = default.print_vertices if choice is None else choice.candidates[0].result.print_vertices
    if choice is not None:
        for i, c in enumerate(choice.candidates):
            meshes[f"answer{i}"] = c.result.print_vertices
    else:
        meshes["answer0"] = default.print_vertices
    names, unique, index = list(meshes), [], {}
    for key in names:  # the same mesh twice (the pose phase's best is the pose-only answer) is sliced once
        same = next((j for j, W in enumerate(unique) if W.shape == meshes[key].shape and np.allclose(W, meshes[key])),
                    None)
        if same is None:
            unique.append(meshes[key])
            same = len(unique) - 1
        index[key] = same
    up3 = np.append(up, 0.0) if rig.dim == 2 else up
    t0 = time.perf_counter()
    sliced = slice_support([sliceable(rig, W) for W in unique], up3, scale_for_height(sliceable(rig, V)[0], up3, REFERENCE_HEIGHT_MM),
                           workers=2, by_feature=True).support_mm
    row["slice_s"] = time.perf_counter() - t0
    mm = {key: float(sliced[index[key]]) for key in names}
    row["rest"] = mm["rest"]
    row["turning"] = min(mm[k] for k in names if k == "rest" or k.startswith("turn"))
    row["pose"], row["plain"] = mm["pose"], mm["plain"]
    if choice is None:
        row["model_choice"] = row["default"] = mm["answer0"]
        row["kind"], row["candidates"] = "-", []
    else:
        answers = [mm[f"answer{i}"] for i in range(len(choice.candidates))]
        picked = to_slice(choice, SLICE_RANK, SLICE_WINDOW)
        chosen = picked[0] if len(picked) < 2 else pick_sliced(picked, [answers[i] for i in picked])[0]
        row["model_choice"], row["default"] = answers[choice.chosen], answers[chosen]
        row["kind"] = choice.candidates[chosen].kind
        row["candidates"] = [{"kind": c.kind, "predicted": c.predicted_mm, "sliced": answers[i],
                              "value": float(c.result.value)} for i, c in enumerate(choice.candidates)]
        row["rest_predicted"], row["model_chosen"] = choice.rest_mm, choice.chosen
        row["sliced_for_default"] = len(picked) if len(picked) > 1 else 0
    return row


def _pct(before: float, after: float) -> str:
    r = reduction(before, after)
    return "–" if r is None else f"{r:.1f} %"


def _vs(r: dict, key: str) -> float:
    """``r[key]`` against the better simple answer, percent (positive: more support)."""
    simple = min(r["turning"], r["pose"])
    return 100 * (r[key] / simple - 1) if simple > 0 else (0.0 if r[key] <= 0 else float("inf"))


def table(rows: list[dict]) -> str:
    head = ["model", "(1) rest mm", "(2) turning only", "(3) pose only", "(4) search's best", "(5) model's choice",
            "(6) default", "default vs best simple answer", "(6) kind", "answers sliced", "time (3)",
            "time (5)", "time (4)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["model"], f"{r['rest']:.0f}"]
        cells += [f"{r[k]:.0f} ({_pct(r['rest'], r[k])})" for k in ("turning", "pose", "plain", "model_choice",
                                                                     "default")]
        cells += [f"{_vs(r, 'default'):+.1f} %", r["kind"], str(r.get("sliced_for_default", 0)),
                  f"{r['pose_s']:.1f} s", f"{r['default_s']:.1f} s", f"{r['plain_s']:.1f} s"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def summary(rows: list[dict]) -> str:
    """Means over the models and how often each answer is within 2 % of the better simple answer."""
    def mean_red(key):
        return np.mean([reduction(r["rest"], r[key]) or 0.0 for r in rows])

    def within(key):
        return sum(r[key] <= 1.02 * min(r["turning"], r["pose"]) + 1.0 for r in rows)

    ratio = [r["default_s"] / r["pose_s"] for r in rows]
    return (f"Mean reduction against (1) over {len(rows)} models: turning only {mean_red('turning'):.1f} %, "
            f"pose only {mean_red('pose'):.1f} %, search's best {mean_red('plain'):.1f} %, model's choice "
            f"{mean_red('model_choice'):.1f} %, default {mean_red('default'):.1f} %. Within 2 % of min((2), (3)): "
            f"search's best on {within('plain')}, model's choice on {within('model_choice')}, default on "
            f"{within('default')} of {len(rows)}. Time (5) / (3): median {np.median(ratio):.2f}, largest "
            f"{max(ratio):.2f}.")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None)
    p.add_argument("--slice-best", type=int, default=4, help="Candidate directions sliced per model for (2).")
    p.add_argument("--rows", default=None, help="Append each model's figures (every answer's) to FILE as JSON lines.")
    p.add_argument("--out", default=None, help="Write the table as the '## Pose and orientation' section of FILE.")
    args = p.parse_args(argv)
    figures = [m for m in sl.DEMO_FIGURES if m != "woody2d"]
    models = args.models or figures + [m for m in SHARED if available(m)] + \
        gltf_names() + [m for m in PLANAR if (DATA / f"{m}.obj").is_file()]
    rows = []
    for name in models:
        t0 = time.perf_counter()
        rows.append(measure(name, args.slice_best))
        if args.rows:
            with open(args.rows, "a") as fh:
                fh.write(json.dumps(rows[-1]) + "\n")
        print(table(rows[-1:]).splitlines()[-1], f"({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    text = "\n".join([
        HEADING,
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores. PrusaSlicer default profile, each model 60 mm tall "
        "as it stands; support in mm of filament (reduction against (1)), each mesh sliced once with supports and "
        "the support read from the G-code's support features. Searches use the default settings (200 x 120). "
        f"(2) is the cheapest of upright and the {args.slice_best} best candidate directions. (6) slices up to "
        f"{SLICE_RANK} answers (those predicted within {100 * SLICE_WINDOW:g} % of the rest pose's support of the "
        "least); 'answers sliced' 0: the model's choice stood alone. Times: (3) `orient='keep'`, (5) the default "
        "search with the model's choice, (4) the same without the choice. woody is planar: extruded to a slab 1/10 "
        "of its height thick, no choice.",
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
