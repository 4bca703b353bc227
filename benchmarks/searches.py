"""Default searches timed, and their answers fingerprinted, at this checkout or at several commits in turn (issue 52).

    python benchmarks/searches.py [--models bunny Xbot Soldier] [--rounds 1]
    python benchmarks/searches.py --commits fac88c0 HEAD [--models ...] [--rounds 2]

Each model's rig is loaded cold (an empty rig cache), a second copy from that cache runs a tiny search first so
numba's kernels are compiled or loaded, then ``sl.optimize(rig, SearchSettings(seed=0))`` is timed on the cold
copy. Each line gives the seconds, the objective value (``repr``: its last bits) and the first 12 hex digits of
the SHA-1 of the written vertices (``print_vertices``): two commits whose answers print the same file give the
same fingerprint.

With ``--commits``, each commit is checked out in a temporary git worktree and the rounds run the commits in
turn, each in a fresh process (this machine's speed drifts by 10-25 % from hour to hour: only runs taken
alternately compare).

Models: ``bunny`` (../shared/data/bunny.obj + .tgf, up y) and any glTF file name under ../shared/data/gltf
(``Xbot``, ``Soldier``, ``quaternius/Wolf`` ...).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from models import DATA


def load(model: str, cache_dir: str):
    """The model's rig, prepared into (or read from) ``cache_dir``."""
    import supportless as sl

    if model == "bunny":
        return sl.load_rig(DATA / "bunny.obj", DATA / "bunny.tgf", up="y", cache_dir=cache_dir)
    return sl.load_rig(DATA / "gltf" / f"{model}.glb", cache_dir=cache_dir)


def timed(model: str) -> str:
    """One line: the default search's seconds, value and written-vertices fingerprint."""
    import supportless as sl
    from supportless.search.settings import SearchSettings

    with tempfile.TemporaryDirectory() as cache:
        rig = load(model, cache)
        sl.optimize(load(model, cache), SearchSettings(particles=8, iterations=2))
        t = time.perf_counter()
        result = sl.optimize(rig, SearchSettings(seed=0))
        seconds = time.perf_counter() - t
    sha = hashlib.sha1(np.ascontiguousarray(result.print_vertices).tobytes()).hexdigest()[:12]
    return f"{model}: {seconds:.2f} s, value {result.value!r}, written vertices {sha}"


def at_commits(commits: list[str], models: list[str], rounds: int) -> None:
    """Run this script's timing at each commit in turn, ``rounds`` times, each in a fresh process."""
    root = Path(subprocess.run(["git", "rev-parse", "--show-toplevel"], capture_output=True, text=True,
                               check=True).stdout.strip())
    with tempfile.TemporaryDirectory() as scratch:
        trees = {}
        for commit in commits:
            tree = Path(scratch) / commit.replace("/", "_")
            subprocess.run(["git", "-C", str(root), "worktree", "add", "--detach", "-f", str(tree), commit],
                           check=True, capture_output=True)
            trees[commit] = tree
        try:
            for r in range(rounds):
                for commit, tree in trees.items():
                    env = {**os.environ, "PYTHONPATH": str(tree)}
                    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--models", *models],
                                         cwd=tree, env=env, capture_output=True, text=True)
                    for line in out.stdout.splitlines():
                        print(f"round {r + 1}, {commit}: {line}", flush=True)
                    if out.returncode:
                        why = (out.stderr.strip().splitlines() or ["no message"])[-1]
                        print(f"round {r + 1}, {commit}: failed: {why}", flush=True)
        finally:
            for tree in trees.values():
                subprocess.run(["git", "-C", str(root), "worktree", "remove", "--force", str(tree)], capture_output=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", nargs="+", default=["bunny", "Xbot", "Soldier"])
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--commits", nargs="+", default=None, help="compare these commits, run alternately")
    args = ap.parse_args()
    if args.commits:
        at_commits(args.commits, args.models, args.rounds)
        return
    for _ in range(args.rounds):
        for model in args.models:
            print(timed(model), flush=True)


if __name__ == "__main__":
    main()
