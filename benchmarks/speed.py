"""Speed of the pipeline's stages, fast path against the plain numpy path (for RESULTS.md).

    python benchmarks/speed.py [MODEL --skeleton S] [--up y] [--particles 200] [--iterations 120]
        [--backend both|fast|numpy]

Without MODEL: the built-in tpose figure and, when ../shared/data exists, the
bunny. Prints the same table as ``supportless bench``.
"""

from __future__ import annotations

import argparse

from supportless.apps.bench import run_bench
from supportless.search.settings import SearchSettings


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model", nargs="?", default=None)
    ap.add_argument("--skeleton", "-s", default=None)
    ap.add_argument("--up", default="y")
    ap.add_argument("--particles", type=int, default=SearchSettings.particles)
    ap.add_argument("--iterations", type=int, default=SearchSettings.iterations)
    ap.add_argument("--backend", choices=["both", "fast", "numpy"], default="both")
    args = ap.parse_args()
    run_bench(args.model, args.skeleton, args.up, particles=args.particles, iterations=args.iterations,
              backend=args.backend, echo=print)


if __name__ == "__main__":
    main()
