"""How long the finite-element strength reference takes on a rig's own tetrahedra (and on bigger meshes).

Each model's rest pose is printed 60 mm tall (:func:`supportless.rig.posed_volume.posed_tet_mesh`), held by its
first layer (:func:`~supportless.energies.strength_fem.plate_nodes`), loaded by its weight (PLA) and a 2 N
sideways push at its highest point, and solved with quadratic tetrahedra
(:func:`~supportless.energies.strength_fem.elastic_solution`). ``--refine 1`` splits every tetrahedron into
eight first (skfem's ``MeshTet.refined``: the bunny's 4 702 vertices become 29 000); ``--box N`` adds a cube of
about N vertices (the worst shape for a direct solver). Prints one line per mesh: vertices, tetrahedra,
unknowns, solver, iterations and seconds (assembly, solve, total).

    python benchmarks/strength_fem.py --models bunny.obj libigl/arm.obj --refine 0 1 --box 20000

On the 2-core development machine, shared (load average 6 to 8 while it ran), P2, to a relative residual of 1e-6:

| mesh | vertices | tetrahedra | unknowns | iterations | assembly | solve | total |
|---|---|---|---|---|---|---|---|
| bunny | 4 702 | 18 090 | 92 841 | 62 | 1.0 s | 13.3 s | 14.3 s |
| arm (libigl) | 10 492 | 37 444 | 199 911 | 57 | 2.9 s | 22.7 s | 25.6 s |
| cube | 19 683 | 105 456 | 438 204 | 23 | 7.7 s | 19.2 s | 26.9 s |
| bunny, refined once | 30 976 | 144 720 | 661 455 | 68 | 9.8 s | 58.4 s | 68.3 s |
| arm, refined once | 66 736 | 299 552 | 1 396 791 | 77 | 27.9 s | 139.6 s | 167.6 s |

A rig's TetGen mesh (slivers) takes about three times the iterations of the cube's regular tetrahedra.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import skfem
from models import DATA

import supportless as sl
from supportless.energies.strength_fem import PLA_GRAVITY, elastic_solution, plate_nodes, section_stress
from supportless.rig.posed_volume import posed_tet_mesh


def rig_mesh(model: str, refine: int) -> tuple[np.ndarray, np.ndarray]:
    """((t, 3) float64, (k, 4) int64): a shared model's rest tetrahedra in the print frame, 60 mm tall, refined."""
    rig = sl.load_rig(model if model.startswith("demo:") else DATA / model, up="y")
    nodes, tets = posed_tet_mesh(rig, np.zeros((rig.bone_count, 3)), None, height_mm=60.0)
    mesh = skfem.MeshTet(nodes.T.copy(), tets.T.copy())
    for _ in range(refine):
        mesh = mesh.refined()
    return mesh.p.T.copy(), mesh.t.T.astype(np.int64)


def cube_mesh(vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """((t, 3) float64, (k, 4) int64): a 30 mm cube of structured tetrahedra with about ``vertices`` vertices."""
    n = max(int(round(vertices ** (1 / 3))), 2)
    mesh = skfem.MeshTet.init_tensor(*[np.linspace(0.0, 30.0, n)] * 3)
    return mesh.p.T.copy(), mesh.t.T.astype(np.int64)


def run(name: str, nodes: np.ndarray, tets: np.ndarray, order: int) -> dict:
    """Solve one mesh under its weight and a 2 N push at its top; the timings and the largest stress at mid-height."""
    top = nodes[np.argmax(nodes[:, 2])]
    t0 = time.perf_counter()
    solution = elastic_solution(nodes, tets, plate_nodes(nodes), load_points=[top], load_forces=[[2.0, 0.0, 0.0]],
                                body_force=PLA_GRAVITY, order=order)
    seconds = time.perf_counter() - t0
    mid = section_stress(solution, [0.0, 0.0, 0.5 * nodes[:, 2].max()], [0, 0, 1])
    return {"name": name, "nodes": len(nodes), "tets": len(tets), "seconds": seconds, "mid_mpa": mid.max,
            **solution.info}


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=["bunny.obj"])
    p.add_argument("--refine", nargs="+", type=int, default=[0])
    p.add_argument("--box", nargs="*", type=int, default=[], help="also cubes of about this many vertices")
    p.add_argument("--order", type=int, default=2)
    args = p.parse_args()
    meshes = [(f"{m} x{r}" if r else m, lambda m=m, r=r: rig_mesh(m, r)) for m in args.models for r in args.refine]
    meshes += [(f"cube {n}", lambda n=n: cube_mesh(n)) for n in args.box]
    for name, make in meshes:
        r = run(name, *make(), args.order)
        print(f"{r['name']}: {r['nodes']} nodes, {r['tets']} tets, P{args.order}, {r['unknowns']} unknowns, "
              f"{r['solver']} {r['iterations']} it (levels {r['levels']}), assembly {r['assembly_seconds']:.1f} s, "
              f"solve {r['solve_seconds']:.1f} s, total {r['seconds']:.1f} s; mid-height max {r['mid_mpa']:.3f} MPa",
              flush=True)


if __name__ == "__main__":
    main()
