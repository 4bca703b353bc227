"""The speed targets (``supportless bench --targets``), written into RESULTS.md.

Runs :func:`supportless.apps.bench_targets.run_targets` (each case in its own
process, empty rig cache, numba warmed up) and, with ``--out FILE``, replaces
the "## Speed targets" section of FILE with the table.

    python benchmarks/targets.py [--cases bunny bb-bunny character robot bunny111k] [--reference] [--choice]
                                 [--out benchmarks/RESULTS.md]
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from supportless.apps.bench_targets import CASES, format_table, run_targets

HEADING = "## Speed targets"


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    p.add_argument("--reference", action="store_true", help="also search the full surface of proxy cases")
    p.add_argument("--choice", action="store_true",
                   help="also time the pose-only search and the choice among the answers (model, PrusaSlicer)")
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    rows = run_targets(args.cases, reference=args.reference, echo=lambda s: print(s, file=sys.stderr, flush=True),
                       choice=args.choice)
    text = "\n".join([HEADING, "", "Command: `python benchmarks/targets.py " + " ".join(argv) + "`", "",
                      format_table(rows)]) + "\n"
    print(text)
    if args.out:
        path = Path(args.out)
        old = path.read_text() if path.is_file() else ""
        # up to the next heading of any level: the hand-written subsections after the table stay
        pattern = re.compile(rf"^{re.escape(HEADING)}\n.*?(?=^##|\Z)", re.S | re.M)
        path.write_text(pattern.sub(lambda _: text + "\n", old) if pattern.search(old)
                        else old.rstrip() + "\n\n" + text)


if __name__ == "__main__":
    main()
