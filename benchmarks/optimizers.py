"""CMA-ES against the particle swarm: objective against time on the zoo and the shared models.

For each model and seed, :func:`supportless.optimize` runs with the tool's
defaults and ``optimizer="pso"`` and ``optimizer="cma"`` (same particles and
iterations words: CMA-ES samples a fifth of the swarm's poses, see
:data:`supportless.search.optimizer.CMA_SHARE`). Each iteration's best value is recorded
with its wall time (``--curves`` draws them). Prints a Markdown table: the final
objective, support and distortion terms, exact intersecting pairs of the result
and the time, per optimizer, and the mean over seeds.

    python benchmarks/optimizers.py [--models tpose bunny ...] [--seeds 0 1] [--orient free|keep]
        [--curves docs/optimizers.png]
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import sys
import time
from pathlib import Path

import models
import numpy as np
from models import SHARED, available

import supportless as sl
from supportless.copyleft.cgal import intersecting_face_pairs

OPTIMIZERS = ("pso", "cma")


def run(rig, settings):
    """One search; returns (result, seconds, curve (iterations, 2): wall time and best value)."""
    curve = []
    t0 = time.perf_counter()

    def on_iteration(it, info):
        curve.append((time.perf_counter() - t0, info["value"]))

    result = sl.optimize(rig, settings, callback=on_iteration)
    return result, time.perf_counter() - t0, np.asarray(curve)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    figures = [n for n in sl.DEMO_FIGURES if sl.demo_figure(n)[0].shape[1] == 3]
    p.add_argument("--models", nargs="+", default=[*figures, *SHARED])
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1])
    p.add_argument("--orient", default=None, choices=["free", "keep"])
    p.add_argument("--curves", default=None, help="PNG of objective against time per model.")
    args = p.parse_args(argv)
    base = sl.SearchSettings().replace(orient=args.orient)
    command = "python benchmarks/optimizers.py " + " ".join(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    rows, curves = [], {}
    for name in args.models:
        if not available(name):
            print(f"skipped {name}: its files are missing", file=sys.stderr)
            continue
        rig = models.load(name)
        sl.optimize(rig, base.replace(particles=8, iterations=1))  # compile the kernels
        for opt in OPTIMIZERS:
            for seed in args.seeds:
                result, seconds, curve = run(rig, base.replace(optimizer=opt, seed=seed))
                pairs = intersecting_face_pairs(result.vertices, rig.faces) if rig.dim == 3 else 0
                rows.append(dict(model=name, optimizer=opt, seed=seed, value=result.value, seconds=seconds,
                                 overhang=result.terms["overhang"], arap=result.terms["arap"], pairs=pairs))
                curves.setdefault(name, []).append((opt, seed, curve))
                r = rows[-1]
                print(f"{name} {opt} seed {seed}: objective {r['value']:.4f}  support {r['overhang']:.4f}  "
                      f"distortion {r['arap']:.4f}  pairs {pairs}  {seconds:.1f} s", file=sys.stderr, flush=True)
    lines = [f"Machine: {platform.machine()}, {len(os.sched_getaffinity(0))} cores. Command: `{command}`", "",
             "| model | PSO objective | CMA-ES objective | PSO support | CMA-ES support | PSO time | CMA-ES time | "
             "exact pairs (PSO / CMA-ES) |", "|---|---|---|---|---|---|---|---|"]
    names = list(dict.fromkeys(r["model"] for r in rows))
    ratio_v, ratio_t = [], []
    for name in names:
        by = {o: [r for r in rows if r["model"] == name and r["optimizer"] == o] for o in OPTIMIZERS}
        mean = {o: {k: np.mean([r[k] for r in by[o]]) for k in ("value", "overhang", "seconds")} for o in OPTIMIZERS}
        pairs = {o: max(r["pairs"] for r in by[o]) for o in OPTIMIZERS}
        ratio_v.append(mean["cma"]["value"] / mean["pso"]["value"])
        ratio_t.append(mean["cma"]["seconds"] / mean["pso"]["seconds"])
        lines.append(f"| {name} | {mean['pso']['value']:.4f} | {mean['cma']['value']:.4f} | "
                     f"{mean['pso']['overhang']:.4f} | {mean['cma']['overhang']:.4f} | {mean['pso']['seconds']:.1f} s | "
                     f"{mean['cma']['seconds']:.1f} s | {pairs['pso']} / {pairs['cma']} |")
    lines += ["", f"Means over {len(args.seeds)} seed(s). CMA-ES objective / PSO objective: mean "
              f"{np.mean(ratio_v):.3f}, worst {np.max(ratio_v):.3f}; time ratio: mean {np.mean(ratio_t):.2f}, "
              f"worst {np.max(ratio_t):.2f}."]
    print("\n".join(lines))
    if args.curves:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        cols = 4
        rows_n = -(-len(curves) // cols)
        fig, axes = plt.subplots(rows_n, cols, figsize=(4 * cols, 3 * rows_n), squeeze=False)
        for ax, (name, runs) in zip(axes.flat, curves.items()):
            for opt, seed, curve in runs:
                if len(curve):
                    ax.plot(curve[:, 0], curve[:, 1], color="C0" if opt == "pso" else "C3",
                            label=f"{opt} seed {seed}", alpha=0.8)
            ax.set_title(name)
            ax.set_xlabel("s")
            ax.set_ylabel("objective")
            ax.set_yscale("log")
        for ax in list(axes.flat)[len(curves):]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(args.curves, dpi=80)


if __name__ == "__main__":
    main()
