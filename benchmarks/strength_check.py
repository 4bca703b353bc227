"""The fast strength analysis against finite elements: the weakest section's stress, both ways.

For each model's rest pose as it stands, 60 mm tall in PLA: :func:`supportless.search.sturdiness.pose_strength`
finds the weakest section, its stress and the grip that loads it worst (a chain end, a direction). The same
loads — the body's weight and that grip, 2 N at that chain end in that direction — are then put on the rig's own
tetrahedra, posed by the same skinning and held where the fast path holds them (the part within 5 % of the height
of the plate), and solved as linear elasticity with quadratic tetrahedra (scikit-fem,
:func:`supportless.energies.strength_fem.elastic_solution`). The finite element stress is the largest normal stress
over the same plane section, in the connected piece through the section's centroid
(:func:`~supportless.energies.strength_fem.section_normal_stress`). ``--refine 1`` splits each tetrahedron into
eight first (the rigs' own tetrahedra are coarse: a thin ankle is a few elements across).

    python benchmarks/strength_check.py [--models tpose bunny gltf/Fox ...] [--refine 0] [--out benchmarks/RESULTS.md]
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import sys
import time
from pathlib import Path

import numpy as np
from models import write_section
from strength import load

from supportless.energies.materials import MATERIALS
from supportless.energies.strength import HELD_SHARE
from supportless.energies.strength_fem import elastic_solution, section_normal_stress
from supportless.rig.posed_volume import posed_tet_mesh
from supportless.search.sturdiness import pose_strength, printed_body

HEADING = "## Strength: beam theory against finite elements"
MODELS = ["tpose", "staff", "bb-bunny", "libigl/dinosaur", "libigl/hand", "gltf/Fox", "gltf/CesiumMan"]


def refined(nodes: np.ndarray, tets: np.ndarray, times: int) -> tuple[np.ndarray, np.ndarray]:
    import skfem

    mesh = skfem.MeshTet(nodes.T, tets.T)
    for _ in range(times):
        mesh = mesh.refined()
    return mesh.p.T.copy(), mesh.t.T.astype(np.int64)


def check(name: str, refine: int, height_mm: float = 60.0) -> dict:
    rig = load(name)
    if rig is None:
        return {"model": name, "skipped": "files missing"}
    angles, R = rig.rest_angles(), np.eye(3)
    material = MATERIALS["PLA"]
    fast = pose_strength(rig, angles, R, height_mm, material)
    w = fast.weakest
    V, J = printed_body(rig, angles, R, height_mm)
    nodes, tets = posed_tet_mesh(rig, angles, R, height_mm)
    nodes = nodes + (V[0] - nodes[0])  # the same frame as the surface the fast path cut
    nodes, tets = refined(nodes, tets, refine)
    z0 = V[:, 2].min()
    held = nodes[:, 2] < z0 + HELD_SHARE * np.ptp(V[:, 2])
    gravity = np.array([0.0, 0.0, -material.density * 9.81e-6])
    t0 = time.perf_counter()
    solution = elastic_solution(nodes, tets, held, J[[w.chain_end]], 2.0 * w.grip[None], gravity,
                                young_mpa=material.young_mpa, poisson=material.poisson)
    fem = section_normal_stress(solution, w.centre, w.normal, near=w.centre)
    seconds = time.perf_counter() - t0
    return {"model": name, "section": w.kind, "bone": rig.bone_names()[w.bone], "height": w.height_mm,
            "area": w.area_mm2, "fast": w.stress_mpa, "fem": fem, "ratio": w.stress_mpa / fem if fem > 0 else None,
            "nodes": len(nodes), "tets": len(tets), "seconds": seconds}


def table(rows: list[dict]) -> str:
    lines = ["| model | weakest section | area | beam theory | finite elements | beam / FE | FE mesh | FE time |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "skipped" in r:
            continue
        ratio = "–" if r["ratio"] is None else f"{r['ratio']:.2f}"
        lines.append(f"| {r['model']} | {r['section']}, {r['bone'].split(':')[-1]} {r['height']:.1f} mm up "
                     f"| {r['area']:.1f} mm² | {r['fast']:.2f} MPa | {r['fem']:.2f} MPa | {ratio} "
                     f"| {r['nodes']} nodes, {r['tets']} tets | {r['seconds']:.1f} s |")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=MODELS)
    p.add_argument("--refine", type=int, default=0)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    rows = []
    for name in args.models:
        print(f"checking {name} ...", file=sys.stderr, flush=True)
        rows.append(check(name, args.refine))
        if "skipped" not in rows[-1]:
            print(table(rows[-1:]).splitlines()[-1], flush=True)
    ratios = np.array([r["ratio"] for r in rows if "skipped" not in r and r["ratio"] is not None])
    within = int(np.sum(np.abs(ratios - 1.0) <= 0.25))
    command = "python benchmarks/strength_check.py " + " ".join(
        shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    note = (f"{within} of {len(ratios)} within 25 % (beam / FE from {ratios.min():.2f} to {ratios.max():.2f}). "
            f"Machine: {platform.machine()}, {os.cpu_count()} cores. Command: `{command}`.")
    text = table(rows)
    print(text + "\n\n" + note)
    if args.out:
        write_section(Path(args.out), HEADING, f"{HEADING}\n\n{note}\n\n{text}\n")


if __name__ == "__main__":
    main()
