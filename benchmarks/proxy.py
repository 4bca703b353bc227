"""How far a dense model's simplified proxy reads the search's terms from the full surface.

For the 68-bone character (31 086 triangles) and the bunny subdivided twice (111 456), each searched on a
10 000-triangle proxy: 30 random poses of the free bones within 20° of rest and 30 within 45°, the
normalised terms on the proxy (as the search measures it) against the full surface. Prints a Markdown table.

    python benchmarks/proxy.py
"""

from __future__ import annotations

import igl
import numpy as np
from models import DATA

from supportless.apps.bench import random_poses
from supportless.files.meshes import read_mesh, read_tgf
from supportless.rig.rig import prepare_rig
from supportless.search.settings import SearchSettings
from supportless.shapes.character import character


def rigs():
    V, F, J, B = character()
    yield "character", prepare_rig(V, F, J, B, up="y", name="character")
    V, F = read_mesh(DATA / "bunny.obj")
    V, F = igl.upsample(V, F.astype(np.int64), 2)
    J, B = read_tgf(DATA / "bunny.tgf")
    yield "bunny111k", prepare_rig(V, F, J, B, up="y", name="bunny111k")


def main():
    settings = SearchSettings()
    print("| model | overhang term, largest difference (20° / 45°) | distortion term, largest relative difference "
          "| self-intersection term, largest difference | standing rule judged differently |")
    print("|---|---|---|---|---|")
    for name, rig in rigs():
        full = settings.objective(rig)
        proxy = settings.objective(rig.coarse_rig(), full.arap_data, full.volume)  # as the search measures it
        overhang, arap, inter, rule = [], 0.0, 0.0, 0
        for degrees in (20.0, 45.0):
            A = random_poses(rig, 30, max_angle=degrees, seed=3)
            tf, tc = full.terms(A), proxy.terms(A)
            overhang.append(float(np.abs(tc["overhang"] - tf["overhang"]).max()))
            arap = max(arap, float(np.max(np.abs(tc["arap"] / tf["arap"] - 1.0))))
            inter = max(inter, float(np.abs(tc["intersection"] - tf["intersection"]).max()))
            rule += int(np.sum((tc["violation"] > 0) != (tf["violation"] > 0)))
        print(f"| {name} ({len(rig.coarse_faces)} of {len(rig.faces)} triangles) | {overhang[0]:.3f} / "
              f"{overhang[1]:.3f} | {arap:.1e} | {inter:.1e} of the volume | {rule} of 60 poses |", flush=True)


if __name__ == "__main__":
    main()
