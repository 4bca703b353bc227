"""The front of least support against least distortion (`--pareto N`), against the single default search.

For each model: the single default search (200 x 120) and its time; the
front (``pareto_front``, N poses) and its time; the front's hypervolume (the
area the front dominates up to the reference point: the rest pose's predicted
support and the largest distortion on the front, both axes scaled to 0..1);
PrusaSlicer's support filament (60 mm tall, default profile) of the rest pose,
the single search's result and both ends of the front. Prints a Markdown table.

With ``--nsga``, pymoo's NSGA-II (population 100, the same variables,
objectives and constraints, for the front's wall time) is measured the same
way, for the comparison the issue asks for.

    python benchmarks/pareto.py [--models bunny bb-bunny] [--count 5] [--gallery DIR] [--nsga]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import models
import supportless as sl
from supportless.pareto import pareto_front
from supportless.report import predicted_slicer
from supportless.slicer import find_prusa_slicer, scale_for_height, slice_support


def hypervolume(support, distortion, reference) -> float:
    """Area dominated by the points ``(support, distortion)`` (both minimised) up to ``reference``."""
    order = np.argsort(support)
    s, d = np.asarray(support, float)[order], np.asarray(distortion, float)[order]
    area, best = 0.0, reference[1]
    for i in range(len(s)):
        if d[i] < best and s[i] < reference[0]:
            area += (reference[0] - s[i]) * (best - d[i])
            best = d[i]
    return area


def nsga2_front(rig, settings, seconds, population=100, seed=0):
    """pymoo's NSGA-II on the same variables (pose and print turn), for ``seconds``; the front as FrontPose-like rows.

    Objectives: the search's support estimate (the normalised prism term) and
    the distortion; constraints: the hard rules' violation and the ray-grid
    self-intersection volume. Returns (support mm (q,), distortion (q,)) of
    its final non-dominated poses that pass the exact self-intersection check,
    measured as :mod:`supportless.pareto` measures the sweep's.
    """
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize
    from pymoo.termination import get_termination

    from supportless.energies.exact import self_intersects
    from supportless.orientation import rotations_from_params
    from supportless.pareto import _measure, non_dominated
    from supportless.symmetry import PoseLayout

    base = np.zeros((rig.bone_count, 3))
    layout = PoseLayout(rig, settings.fixed_bones(rig), base, np.radians(settings.joint_limits(rig)))
    k, o = layout.count, rig.dim - 1
    objective = settings.objective(rig)
    lower = np.concatenate([layout.lower, np.full(o, -np.pi)])
    upper = np.concatenate([layout.upper, np.full(o, np.pi)])

    class Posing(Problem):
        def __init__(self):
            super().__init__(n_var=k + o, n_obj=2, n_ieq_constr=2, xl=lower, xu=upper)

        def _evaluate(self, X, out, *args, **kwargs):
            t = objective.terms(layout.to_angles(X[:, :k]), rotations_from_params(X[:, k:], rig.up))
            out["F"] = np.column_stack([t["overhang"], settings.w_arap * t["arap"] + settings.w_prior * t["prior"]])
            out["G"] = np.column_stack([t["violation"], t["intersection"]])

    rng = np.random.default_rng(seed)
    X0 = lower + rng.random((population, k + o)) * (upper - lower)
    X0[0] = 0.0  # the rest pose, upright
    res = minimize(Posing(), NSGA2(pop_size=population, sampling=X0), get_termination("time", seconds),
                   seed=seed, verbose=False)
    X = np.atleast_2d(res.X)
    A, R = layout.to_angles(X[:, :k]), rotations_from_params(X[:, k:], rig.up)
    support, distortion, ok = _measure(rig, objective, A, R, settings)
    ok &= np.array([not self_intersects(rig.pose(a), rig.faces) for a in A])
    keep = np.flatnonzero(ok)
    keep = keep[non_dominated(support[keep], distortion[keep])]
    return support[keep], distortion[keep]


def run(name, count, gallery, nsga):
    rig = models.load(name)
    settings = sl.SearchSettings()
    t0 = time.perf_counter()
    single = sl.optimize(rig, settings)
    single_s = time.perf_counter() - t0
    front = pareto_front(rig, settings, count)
    rest_pred = predicted_slicer(rig, single)["before_mm"]
    s = np.array([p.support for p in front.poses])
    d = np.array([p.distortion for p in front.poses])
    ref = (rest_pred, max(float(d.max()), 1e-12))
    hv = hypervolume(s / ref[0], d / ref[1], (1.0, 1.0))
    scale = scale_for_height(rig.vertices, rig.up, 60.0)
    meshes = [(rig.vertices, rig.faces), (single.print_vertices, rig.faces),
              (front.poses[0].result.print_vertices, rig.faces), (front.poses[-1].result.print_vertices, rig.faces)]
    mm = slice_support(meshes, rig.up, scale, workers=2).support_mm
    if gallery:
        from supportless.pareto import write_front

        write_front(rig, front, Path(gallery) / f"{name}.stl")
    nsga_hv = "–"
    if nsga:
        ns, nd = nsga2_front(rig, settings, front.seconds)
        nsga_hv = f"{hypervolume(ns / ref[0], nd / ref[1], (1.0, 1.0)):.3f} ({len(ns)} poses)" if len(ns) else "0"
    print(f"| {name} | {single_s:.1f} s | {front.seconds:.1f} s ({front.seconds / single_s:.2f}x) | {len(front.poses)} "
          f"| {hv:.3f} | {nsga_hv} | {mm[0]:.0f} | {mm[1]:.0f} | {mm[2]:.0f} ({100 * (mm[2] / mm[1] - 1):+.1f} %) "
          f"| {mm[3]:.0f} | {d[0]:.3g} → {d[-1]:.3g} |", flush=True)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=["bunny", "bb-bunny"])
    p.add_argument("--count", type=int, default=5)
    p.add_argument("--gallery", default=None, help="Write each front (meshes, poses, picture) into this folder.")
    p.add_argument("--nsga", action="store_true",
                   help="Also run pymoo's NSGA-II for the front's time and give its hypervolume (needs pymoo).")
    args = p.parse_args(argv)
    if find_prusa_slicer() is None:
        sys.exit("PrusaSlicer not found: apt-get install prusa-slicer")
    print("| model | single search | front | poses | hypervolume | NSGA-II hypervolume, same time "
          "| PrusaSlicer mm: rest | single search | least-support end (vs single) | least-distortion end "
          "| distortion along the front |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.models:
        if models.available(name):
            run(name, args.count, args.gallery, args.nsga)


if __name__ == "__main__":
    main()
