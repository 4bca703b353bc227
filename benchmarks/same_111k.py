"""The 111k bunny's answer, to compare two versions of the code (issue 39: the same pose, the same verdict).

Prepares the ``bunny111k`` case of :mod:`supportless.apps.bench_targets` (the bunny subdivided twice), runs the
default search (seed 0) and writes the answer's print vertices to ``OUT.npy`` and its pose, rotation, value and
exact-check figures as JSON on stdout. Run it with each version on ``PYTHONPATH`` and compare:

    PYTHONPATH=OLD python benchmarks/same_111k.py before > before.json
    PYTHONPATH=NEW python benchmarks/same_111k.py after > after.json
"""

from __future__ import annotations

import json
import sys
import tempfile

import numpy as np

from supportless.apps.bench_targets import _prepare
from supportless.search.answer import optimize


def main(out: str) -> None:
    with tempfile.TemporaryDirectory() as cache:
        rig = _prepare("bunny111k", cache)
    result = optimize(rig)
    np.save(out, result.print_vertices)
    stats = {k: v for k, v in result.flat_stats().items() if isinstance(v, (int, float, str))}
    print(json.dumps({"angles": result.angles.tolist(), "rotation": result.rotation.tolist(), "value": result.value,
                      "stats": stats}))


if __name__ == "__main__":
    main(sys.argv[1])
