"""Issue 52's ratios in one process: each default search against the bunny's, and the bunny's against its floor.

    python benchmarks/ratios.py [--rounds 1] [--cases bunny bb-bunny mannequin bunny111k]

Everything runs in this one process, as the issue asks (warm numba, cold rig caches):

* each case's rig is prepared cold (an empty rig cache, or built in memory for ``bunny111k``); a second copy of
  it, loaded from that cache (or prepared again), runs a tiny search first so numba's kernels are compiled or
  loaded, and the timed search then runs on the first copy, whose own caches (ARAP operators, proxy) are cold;
* the timed search is the default one, ``sl.optimize(rig, SearchSettings(seed=0))`` (200 x 120, the print
  orientation free, the choice among the answers by the slicer model: no slicer is run);
* the floor is the bare skinning of the 24 000 poses (200 x 120) the bunny's swarm evaluates, in batches of 200
  (forward kinematics and ``kinematics.skin`` with the rig's LBS matrix), timed in the same process after the
  searches of its round.

Cases: ``bunny`` and ``bb-bunny`` (``../shared/data``, up y), ``mannequin`` (the 29k-triangle
``gltf/reference/Mannequin.obj`` + ``.tgf``, up y), ``bunny111k`` (the bunny subdivided twice with
``igl.upsample``). With ``--rounds N`` the cases run N times in turn; every ratio is taken within its round and
the table gives each round's figures and the median of the ratios.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time

import numpy as np
from models import DATA

import supportless as sl
from supportless.search.settings import SearchSettings

HEADING = "### The targets' ratios in one process (issue 52)"

#: case -> (the issue's target: the case's search within this many times the bunny's, or None for the bunny).
TARGETS = {"bunny": None, "bb-bunny": 2.0, "mannequin": 3.0, "bunny111k": 3.0}

#: The bunny's search within this many times its floor.
FLOOR_TARGET = 3.0


def prepare(case: str, cache_dir: str) -> sl.Rig:
    """The case's rig, prepared into (or read from) ``cache_dir``; ``bunny111k`` is built in memory."""
    if case in ("bunny", "bb-bunny"):
        return sl.load_rig(DATA / f"{case}.obj", DATA / f"{case}.tgf", up="y", cache_dir=cache_dir)
    if case == "mannequin":
        folder = DATA / "gltf" / "reference"
        return sl.load_rig(folder / "Mannequin.obj", folder / "Mannequin.tgf", up="y", cache_dir=cache_dir)
    if case == "bunny111k":
        import igl

        from supportless.files.meshes import read_mesh, read_tgf
        from supportless.rig.rig import prepare_rig

        V, F = read_mesh(DATA / "bunny.obj")
        V, F = igl.upsample(V, F.astype(np.int64), 2)
        J, B = read_tgf(DATA / "bunny.tgf")
        return prepare_rig(V, F, J, B, up="y", name="bunny111k")
    raise ValueError(f"unknown case {case!r}")


def timed_search(case: str) -> dict:
    """Prepare cold, warm numba on a second copy, then time the default search on the cold copy."""
    with tempfile.TemporaryDirectory() as cache:
        t = time.perf_counter()
        rig = prepare(case, cache)
        prepare_s = time.perf_counter() - t
        warm = prepare(case, cache)
        sl.optimize(warm, SearchSettings(particles=8, iterations=2))
        del warm
        t = time.perf_counter()
        result = sl.optimize(rig, SearchSettings(seed=0))
        search_s = time.perf_counter() - t
    proxy = rig.coarse_rig()
    return {"case": case, "faces": len(rig.faces), "searched_faces": len((proxy or rig).faces),
            "prepare_s": prepare_s, "search_s": search_s, "value": float(result.value)}


def skinning_floor(case: str = "bunny") -> dict:
    """The bare skinning of the default search's poses (particles x iterations) on the case's searched surface."""
    from supportless.apps.bench import random_poses
    from supportless.base.kinematics import skin

    with tempfile.TemporaryDirectory() as cache:
        rig = prepare(case, cache)
    surface = rig.coarse_rig() or rig
    s = SearchSettings()
    A = random_poses(surface, s.particles, seed=3)
    M = surface.lbs
    skin(M, surface.transforms(A[:2]))
    t = time.perf_counter()
    for _ in range(s.iterations):
        skin(M, surface.transforms(A))
    return {"poses": s.particles * s.iterations, "seconds": time.perf_counter() - t,
            "vertices": len(surface.vertices)}


def section(rounds: list[dict], argv: list[str]) -> str:
    """The Markdown table: per round the seconds and ratios, then the median ratios against the targets."""
    load = os.getloadavg()
    cases = [c for c in TARGETS if c in rounds[0]["cases"]]
    lines = [HEADING, "",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores; load average at the end "
             f"{load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} (1 / 5 / 15 min). "
             "Command: `python benchmarks/ratios.py " + " ".join(argv) + "`.", "",
             "| round | floor (bunny, 24 000 poses) | " + " | ".join(f"{c} search" for c in cases)
             + " | bunny / floor | " + " | ".join(f"{c} / bunny" for c in cases if TARGETS[c]) + " |",
             "|" + "---|" * (3 + len(cases) + sum(1 for c in cases if TARGETS[c]))]
    ratios = {"floor": []} | {c: [] for c in cases if TARGETS[c]}
    for i, r in enumerate(rounds, 1):
        bunny = r["cases"]["bunny"]["search_s"]
        ratios["floor"].append(bunny / r["floor"]["seconds"])
        row = [str(i), f"{r['floor']['seconds']:.2f} s"]
        row += [f"{r['cases'][c]['search_s']:.2f} s" for c in cases]
        row.append(f"{ratios['floor'][-1]:.2f}x")
        for c in cases:
            if TARGETS[c]:
                ratios[c].append(r["cases"][c]["search_s"] / bunny)
                row.append(f"{ratios[c][-1]:.2f}x")
        lines.append("| " + " | ".join(row) + " |")
    lines.append("")
    verdict = [f"bunny / floor median {np.median(ratios['floor']):.2f}x (target {FLOOR_TARGET:g}x: "
               f"{'met' if np.median(ratios['floor']) <= FLOOR_TARGET else 'not met'})"]
    for c in cases:
        if TARGETS[c]:
            m = float(np.median(ratios[c]))
            verdict.append(f"{c} / bunny {m:.2f}x (target {TARGETS[c]:g}x: {'met' if m <= TARGETS[c] else 'not met'})")
    lines.append("Median over the rounds: " + "; ".join(verdict) + ".")
    first = rounds[0]["cases"]
    lines.append("")
    lines.append("Triangles (searched): " + ", ".join(
        f"{c} {first[c]['faces']} ({first[c]['searched_faces']})" for c in cases)
        + "; cold preparation in the first round: " + ", ".join(f"{c} {first[c]['prepare_s']:.1f} s" for c in cases)
        + "; objective values: " + ", ".join(f"{c} {first[c]['value']:.4f}" for c in cases) + ".")
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=1)
    p.add_argument("--cases", nargs="+", default=list(TARGETS), choices=list(TARGETS))
    args = p.parse_args(argv)
    cases = ["bunny", *[c for c in args.cases if c != "bunny"]]
    missing = [c for c in cases if c != "bunny111k" and not (DATA / ("gltf/reference/Mannequin.obj" if c == "mannequin"
                                                                      else f"{c}.obj")).is_file()]
    if missing:
        sys.exit(f"ratios: the shared models of {', '.join(missing)} are not in {DATA}")
    rounds = []
    for i in range(args.rounds):
        got = {}
        for case in cases:
            got[case] = timed_search(case)
            print(f"round {i + 1}: {case} search {got[case]['search_s']:.2f} s", file=sys.stderr, flush=True)
        floor = skinning_floor()
        print(f"round {i + 1}: floor {floor['seconds']:.2f} s", file=sys.stderr, flush=True)
        rounds.append({"cases": got, "floor": floor})
    text = section(rounds, argv)
    print(text)


if __name__ == "__main__":
    main()
