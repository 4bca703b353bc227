"""Time per pose of each energy when 200 poses are evaluated at once.

For the built-in ``tpose`` figure and for ../shared/data/bunny.obj (when
present): random poses (±30° on every bone, seed 0), one batched call per term,
best of ``--repeat`` runs after a warm-up (numba compilation excluded). Prints
the face, tet and cluster counts with the times.

    python benchmarks/energies.py [--poses 200] [--repeat 3] [--backend fast|numpy]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numba
import numpy as np
from models import DATA

import supportless as sl
from supportless.base.kinematics import skin
from supportless.energies.arap import arap_energy


def best_of(fn, repeat):
    fn()  # warm-up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def bench(name, rig, poses, repeat, backend):
    obj = sl.SearchSettings(backend=backend).objective(rig)  # what the search minimises
    data = obj.arap_data
    A = np.random.default_rng(0).uniform(-1, 1, (poses, rig.bone_count, 3)) * np.radians(30)
    T = rig.transforms(A)
    V = skin(rig.lbs, T)
    F, up = rig.faces, rig.up
    rows = [
        ("forward kinematics", best_of(lambda: rig.transforms(A), repeat)),
        ("skinning", best_of(lambda: skin(rig.lbs, T), repeat)),
        ("ARAP (reduced)", best_of(lambda: arap_energy(data, T, backend=backend), repeat)),
        ("overhang (prism)", best_of(lambda: sl.overhang_energy(V, F, up, backend=backend), repeat)),
        ("support (column)", best_of(lambda: sl.support_volume(V, F, up, backend=backend), repeat)),
        ("self-intersection", best_of(lambda: sl.self_intersection_volume(V, F, up, backend=backend), repeat)),
        ("whole objective", best_of(lambda: obj(A), repeat)),
    ]
    print(f"\n{name}: {len(rig.vertices)} vertices, {len(F)} faces, {len(rig.tets)} tets, {rig.bone_count} bones, "
          f"{data.n_clusters} rotation clusters; {poses} poses per call, backend {backend}")
    print(f"  {'term':<22}{'per call':>12}{'per pose':>12}")
    for label, t in rows:
        print(f"  {label:<22}{t * 1e3:>9.2f} ms{t / poses * 1e3:>9.3f} ms")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--poses", type=int, default=200)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--backend", choices=["fast", "numpy"], default="fast")
    args = p.parse_args(argv)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, numba threads {numba.get_num_threads()}, "
          f"Python {platform.python_version()}")
    bench("tpose", sl.load_rig("demo:tpose"), args.poses, args.repeat, args.backend)
    if (DATA / "bunny.obj").is_file():
        bench("bunny", sl.load_rig(DATA / "bunny.obj", DATA / "bunny.tgf", up="y"), args.poses, args.repeat,
              args.backend)
    else:
        print(f"\nbunny: skipped, {DATA} not found")


if __name__ == "__main__":
    main()
