"""Peak memory of the search against the swarm size, with and without measuring the swarm in chunks.

Each run is its own Python process (the bunny, ``--orient keep``, 3 iterations: memory, not time): the
peak resident memory with :data:`supportless.search.objective.POSE_CHUNK` as it is and with chunking switched off.

    python benchmarks/memory.py [--particles 200 1000 5000]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

from models import DATA

CHILD = r"""
import json, resource, sys
import supportless as sl
import supportless.search.objective as ob
particles, chunk, mesh, skeleton = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4]
if chunk == 0:
    ob.POSE_CHUNK = 10 ** 9
rig = sl.load_rig(mesh, skeleton)
result = sl.optimize(rig, particles=particles, iterations=3, orient="keep")
print(json.dumps({"peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "value": result.value}))
"""


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--particles", nargs="+", type=int, default=[200, 1000, 5000])
    args = p.parse_args(argv)
    print("| particles | peak memory, in chunks | peak memory, one batch | same value |")
    print("|---|---|---|---|")
    for n in args.particles:
        out = []
        for chunk in (1, 0):
            run = subprocess.run([sys.executable, "-c", CHILD, str(n), str(chunk), str(DATA / "bunny.obj"),
                                  str(DATA / "bunny.tgf")], capture_output=True, text=True, check=True)
            out.append(json.loads(run.stdout.strip().splitlines()[-1]))
        print(f"| {n} | {out[0]['peak_mb']:.0f} MB | {out[1]['peak_mb']:.0f} MB | "
              f"{'yes' if out[0]['value'] == out[1]['value'] else 'no'} |", flush=True)


if __name__ == "__main__":
    main()
