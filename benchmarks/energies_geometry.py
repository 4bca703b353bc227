"""Time the geometric energies per pose on a closed mesh.

Usage::

    python benchmarks/energies_geometry.py [mesh.obj] [--poses 200] [--threads N]
                                           [--resolution R]

Poses are random rotations of the mesh (explicit numpy Generator, seed 0);
all poses are evaluated in one batched call.  Numba compilation is excluded
(a warm-up call on two poses runs first).
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from supportless.energies._raycast import DEFAULT_RESOLUTION
from supportless.energies.intersection import self_intersection_volume
from supportless.energies.overhang import overhang_energy
from supportless.energies.support import support_volume


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh", nargs="?", default="/work/shared/data/bunny.obj")
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--resolution", type=int, default=DEFAULT_RESOLUTION)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if args.threads:
        numba.set_num_threads(args.threads)

    m = trimesh.load(args.mesh, process=False)
    V = np.asarray(m.vertices, np.float64)
    F = np.asarray(m.faces, np.int64)
    rng = np.random.default_rng(0)
    R = Rotation.random(args.poses, random_state=rng).as_matrix()
    VV = np.ascontiguousarray(np.einsum("pij,nj->pni", R, V))
    up = np.array([0.0, 0.0, 1.0])
    print(f"{args.mesh}: {len(V)} vertices, {len(F)} faces, {args.poses} poses, "
          f"resolution {args.resolution}, numba threads {numba.get_num_threads()}")

    fns = {
        "overhang_energy": lambda X: overhang_energy(X, F, up),
        "self_intersection_volume": lambda X: self_intersection_volume(X, F, up, resolution=args.resolution),
        "support_volume": lambda X: support_volume(X, F, up, resolution=args.resolution),
    }
    for name, fn in fns.items():
        fn(VV[:2])  # compile / load cache
        best = np.inf
        for _ in range(args.repeat):
            t = time.perf_counter()
            out = fn(VV)
            best = min(best, time.perf_counter() - t)
        print(f"  {name:26s} {1e3 * best / args.poses:8.3f} ms/pose   (mean value {np.mean(out):.4g})")


if __name__ == "__main__":
    main()
