"""A first run after install: ``supportless demo`` (and ``optimize`` of a model) with numba's and the rig's caches
empty, with and without the warm-up that compiles the kernels on both cores (:mod:`supportless.apps.warmup`).

    python benchmarks/first_run.py [--rounds 2] [--model ../shared/data/gltf/Xbot.glb] [--warm]

Each run is a fresh ``python -m supportless.apps.cli`` process with an empty ``NUMBA_CACHE_DIR`` and
``SUPPORTLESS_CACHE``; the two variants alternate (``SUPPORTLESS_WARMUP=0`` turns the warm-up off), so both see
the machine alike. The table gives each run's wall time and the support figure it printed (the same answer both
ways: the warm-up only moves where the kernels are compiled). ``--warm`` adds a run of each command with the
caches kept, the time after the first run.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def run(args: list[str], cache: Path, warm_up: bool, keep: bool = False) -> tuple[float, str]:
    """Wall seconds of ``supportless ARGS`` with the caches under ``cache`` (emptied first unless ``keep``),
    and the support line it printed."""
    if not keep:
        shutil.rmtree(cache, ignore_errors=True)
    cache.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache / "numba"), SUPPORTLESS_CACHE=str(cache / "rigs"),
               SUPPORTLESS_WARMUP="1" if warm_up else "0")
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "supportless.apps.cli", *args], capture_output=True, text=True,
                         env=env)
    seconds = time.perf_counter() - t
    if out.returncode != 0:
        sys.exit(f"first_run.py: supportless {' '.join(args)} failed: {(out.stderr.strip().splitlines() or ['?'])[-1]}")
    found = re.search(r"support [^\n]*? less", out.stdout.replace("\n", " "))
    return seconds, found.group(0) if found else "(no support line)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--model", help="also time `supportless optimize MODEL` (defaults)")
    parser.add_argument("--warm", action="store_true", help="also time each command with the caches kept")
    options = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="supportless-first-run-"))
    commands = {"demo": ["demo", "--out", str(work / "demo")]}
    if options.model:
        commands[f"optimize {Path(options.model).name}"] = ["optimize", options.model, "-o", str(work / "out.stl")]
    print(f"Machine: {platform.machine()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the "
          f"start. Command: `python benchmarks/{Path(__file__).name} {' '.join(sys.argv[1:])}`.\n")
    print("| command | round | without warm-up (s) | with warm-up (s) | support (both) |")
    print("|---|---:|---:|---:|---|")
    for name, args in commands.items():
        for r in range(options.rounds):
            off, said_off = run(args, work / "cache", warm_up=False)
            on, said_on = run(args, work / "cache", warm_up=True)
            said = said_on if said_on == said_off else f"differ: {said_off} / {said_on}"
            print(f"| `{name}` | {r + 1} | {off:.1f} | {on:.1f} | {said} |", flush=True)
        if options.warm:
            warm, _ = run(args, work / "cache", warm_up=True, keep=True)
            print(f"| `{name}` | caches kept | – | {warm:.1f} | |", flush=True)
    print(f"\nload average {os.getloadavg()[0]:.2f} at the end.")
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
