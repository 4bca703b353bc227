"""The footprint rule's bound, chosen on figures of the zoo and the shared models.

For each bound (mm² at 60 mm tall; 0 is no rule) and each model, the default search (200 x 120, orientation free,
the slicer model's choice): the predicted support filament of the rest pose and of the answer, and the area the
answer's first layer rests on (:func:`supportless.energies.footprint.footprint_area`). Prints one line per run and
a Markdown table.

    python benchmarks/footprint.py --bounds 0 3 10 --models bunny.obj gltf/Fox.glb demo:tpose
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from models import DATA

import supportless as sl
from supportless.energies.footprint import footprint_area

MODELS = ["bunny.obj", "gltf/Fox.glb", "gltf/CesiumMan.glb", "gltf/quaternius/Stegosaurus.glb", "demo:tpose",
          "demo:quadruped", "demo:dragon", "demo:bird"]


def run(model: str, bound: float) -> dict:
    rig = sl.load_rig(model if model.startswith("demo:") else DATA / model, height_mm=60)
    t0 = time.perf_counter()
    result = sl.optimize(rig, sl.SearchSettings(footprint_mm2=bound))
    chosen = result.choice.candidates[result.choice.chosen]
    scale = 60.0 / float(np.ptp(rig.vertices @ rig.up))
    return {"model": model, "bound": bound, "rest_mm": result.choice.rest_mm, "mm": chosen.predicted_mm,
            "footprint": float(footprint_area(result.print_vertices, rig.faces, rig.up, scale)),
            "turned": bool(not np.allclose(result.rotation, np.eye(3))), "seconds": time.perf_counter() - t0}


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--bounds", nargs="+", type=float, default=[0.0, 3.0, 10.0])
    p.add_argument("--models", nargs="+", default=MODELS)
    args = p.parse_args()
    rows = []
    for bound in args.bounds:
        for model in args.models:
            r = run(model, bound)
            rows.append(r)
            print(f"{model} bound {bound:g}: {r['rest_mm']:.0f} -> {r['mm']:.0f} mm, rests on {r['footprint']:.1f} mm², "
                  f"{'turned' if r['turned'] else 'standing'}, {r['seconds']:.0f} s", flush=True)
    print("\n| model | " + " | ".join(f"bound {b:g} mm²" for b in args.bounds) + " |")
    print("|---|" + "---|" * len(args.bounds))
    for model in args.models:
        cells = [next(r for r in rows if r["model"] == model and r["bound"] == b) for b in args.bounds]
        print(f"| {model} | " + " | ".join(f"{(1 - c['mm'] / c['rest_mm']) * 100:.1f} % less, rests on "
                                           f"{c['footprint']:.1f} mm²{'' if c['turned'] else ' (standing)'}"
                                           for c in cells) + " |")
    means = [np.mean([1 - r["mm"] / r["rest_mm"] for r in rows if r["bound"] == b]) * 100 for b in args.bounds]
    print("| mean | " + " | ".join(f"{m:.1f} % less" for m in means) + " |")


if __name__ == "__main__":
    main()
