"""Welding a written sculpt's corners: :func:`supportless.base.geometry.row_groups` against a lexsort and ``np.unique``.

A binary STL stores every triangle's three corners; reading one back (``files.meshes.read_mesh``) groups the
corners at equal positions into vertices. For the bunny subdivided four times (``bunny4`` of
:mod:`supportless.apps.bench_targets`, 1 783 296 triangles) that is 5 349 888 float32 rows. Timed, best of
``--rounds``, in this process:

- ``row_groups``: the package's (rows hashed, one integer sort);
- ``lexsort``: the same groups by one lexsort of the columns (the package's way before, and its way still for rows
  with no bits to hash);
- ``np.unique(axis=0)`` with the first rows, the inverse and the counts;

each on the float32 corners and on the float64 vertices the OBJ reader welds, and checked to give the same first row
for every row.

    python benchmarks/weld.py [--rounds 3]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from supportless.apps.bench_targets import big_model
from supportless.base.geometry import _grouped_by_lexsort, row_groups
from supportless.files.meshes import read_mesh


def by_lexsort(X: np.ndarray) -> np.ndarray:
    """Each row's first equal row, by one lexsort."""
    order, starts = _grouped_by_lexsort(X)
    first = np.empty(len(X), np.int64)
    first[order] = order[starts][np.cumsum(starts) - 1]
    return first


def by_unique(X: np.ndarray) -> np.ndarray:
    _, first, inverse, _ = np.unique(X, axis=0, return_index=True, return_inverse=True, return_counts=True)
    return first[inverse.ravel()]


def by_row_groups(X: np.ndarray) -> np.ndarray:
    first, inverse, _ = row_groups(X)
    return first[inverse]


def best_of(f, X, rounds):
    times = []
    for _ in range(rounds):
        t = time.perf_counter()
        out = f(X)
        times.append(time.perf_counter() - t)
    return min(times), out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=3)
    args = p.parse_args(argv)
    mesh, _ = big_model("bunny4")
    V, F = read_mesh(mesh)
    corners = V[F].reshape(-1, 3).astype(np.float32)
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}; best of {args.rounds}")
    print("| rows | row_groups | lexsort | np.unique(axis=0) | same first rows |")
    print("|---|---:|---:|---:|---|")
    for label, X in ((f"{len(corners)} float32 corners", corners), (f"{len(V)} float64 vertices", V)):
        times, firsts = zip(*(best_of(f, X, args.rounds) for f in (by_row_groups, by_lexsort, by_unique)))
        same = all(np.array_equal(firsts[0], other) for other in firsts[1:])
        print(f"| {label} | {times[0]:.2f} s | {times[1]:.2f} s | {times[2]:.2f} s | {'yes' if same else 'NO'} |")


if __name__ == "__main__":
    main()
