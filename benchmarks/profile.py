"""Profile of the default answer: wall time per stage, against the bare skinning floor (issue 52, item 1).

    python benchmarks/profile.py [--models bunny,tpose,xbot] [--out benchmarks/RESULTS.md]

For each model, ``supportless optimize`` runs in this process with its defaults (the search's
``SearchSettings()``, PrusaSlicer's choice among the answers when it is installed, the report, the
pictures, the files written to a temporary folder) on a cold rig (``--no-cache``). The stages are
timed by wrapping the package's functions at run time (:class:`Profiler`; nothing in the package is
edited): each named function is replaced, in every ``supportless`` module that holds it, by a
wrapper that sums its wall seconds and calls, and restored afterwards. Stages nest (a search holds
its phases, the choice holds its strength checks): every row gives its time *inclusive* of the
stages it calls and *exclusive* of them (its own share); the exclusive times and the remainder
outside every stage add up to the total.

The floor, timed in the same process afterwards: the skinning of the poses the search evaluates,
``particles x iterations`` of the default ``SearchSettings`` (200 x 120 = 24 000), in batches of
one swarm iteration (``particles`` poses: 24 000 poses of a 40 000-triangle surface at once would
not fit in memory), on the surface the swarm evaluates (a dense model's simplified proxy, else the
surface itself): forward kinematics (``rig.transforms``) and linear blend skinning
(``supportless.base.kinematics.skin`` with ``rig.lbs``), as :mod:`supportless.apps.bench` does.

Numba is warmed first: a tiny search (8 particles x 2 iterations) on each model's rig, loaded
from the ordinary cache, before anything is timed.

Models: ``bunny`` (../shared/data/bunny.obj + bunny.tgf, up y), ``xbot`` (../shared/data/gltf/Xbot.glb,
its own skin, 60 mm high), ``tpose`` (the figure ``supportless demo`` poses, searched here at the
default 200 x 120 rather than the demo's quick 60 x 40).
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import os
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
from models import DATA, write_section

import supportless as sl
from supportless.search.settings import SearchSettings

HEADING = "## Profile of the default answer (issue 52)"

#: The model name -> (CLI arguments before the options, load_rig arguments, label).
MODELS = {
    "bunny": ([str(DATA / "bunny.obj"), "--skeleton", str(DATA / "bunny.tgf"), "--up", "y"],
              dict(model=DATA / "bunny.obj", skeleton=DATA / "bunny.tgf", up="y"), "bunny (shared, up y)"),
    "xbot": ([str(DATA / "gltf" / "Xbot.glb"), "--height-mm", "60"],
             dict(model=DATA / "gltf" / "Xbot.glb", height_mm=60), "Xbot.glb (glTF skin, 60 mm)"),
    "tpose": (["demo:tpose", "--up", "y"], dict(model="demo:tpose", up="y"), "tpose (the demo's figure)"),
}

#: The stages wrapped: (module, attribute path, label). A label may hold ``{phase}`` / ``{which}``,
#: filled from the call (see :func:`_label`).
STAGES = [
    ("supportless.rig.load", "load_rig", "load_rig (cold: tets, weights)"),
    ("supportless.search.answer", "optimize", "optimize (whole search, every search)"),
    ("supportless.search.answer", "mirrored_answer", "mirrored_answer (the search of a mirrored figure)"),
    ("supportless.search.answer", "one_answer", "one_answer [{which}] (one search + choose + as_written)"),
    ("supportless.search.answer", "predicted_mm", "predicted_mm (the mirrored answer's)"),
    ("supportless.search.answer", "_on_proxy_then_full", "_on_proxy_then_full (proxy search + full-surface stages)"),
    ("supportless.search.optimizer", "_PoseSearch.run", "_PoseSearch.run"),
    ("supportless.search.optimizer", "_PoseSearch.run_phase", "run_phase [{phase}]"),
    ("supportless.search.optimizer", "_PoseSearch.polish", "_PoseSearch.polish"),
    ("supportless.search.optimizer", "_PoseSearch.result", "_PoseSearch.result"),
    ("supportless.search.objective", "Objective.forbidden", "exact self-intersection check (Objective.forbidden)"),
    ("supportless.search.objective", "Objective.terms", "progress terms (Objective.terms)"),
    ("supportless.search.answer", "on_full_surface", "on_full_surface"),
    ("supportless.search.result", "at_full_resolution", "at_full_resolution"),
    ("supportless.search.answer", "as_written", "as_written"),
    ("supportless.search.result", "written_verdict", "written_verdict (CGAL pairs)"),
    ("supportless.search.choice", "choose", "choose (weighing the answers)"),
    ("supportless.search.choice", "candidate_answers", "candidate_answers"),
    ("supportless.search.choice", "strong_enough", "strong_enough (strength checks)"),
    ("supportless.search.choice", "crosses_as_written", "crosses_as_written"),
    ("supportless.slicing.ranking", "slice_choice", "slice_choice (PrusaSlicer's choice)"),
    ("supportless.slicing.prusaslicer", "slice_support", "slice_support (PrusaSlicer runs)"),
    ("supportless.report.report", "build_report", "build_report"),
    ("supportless.report.report", "write_pictures", "write_pictures"),
    ("supportless.report.outputs", "write_result", "write_result (files, incl. pictures)"),
]


def _label(template: str, args) -> str:
    if "{phase}" in template:  # run_phase(self, turns, initial, particles, offset, ..., label=...)
        return template.format(phase="pose and turn" if len(args) > 1 and args[1] else "pose")
    if "{which}" in template:  # one_answer(rig, settings, ...)
        symmetric = getattr(args[1], "symmetric", None) if len(args) > 1 else None
        return template.format(which="mirrored" if symmetric else "free")
    return template


class Profiler:
    """Wraps the :data:`STAGES` while active; ``rows()`` gives each stage's calls, inclusive and exclusive seconds."""

    def __init__(self, stages=STAGES):
        self.stages = stages
        self.inclusive = defaultdict(float)
        self.exclusive = defaultdict(float)
        self.calls = defaultdict(int)
        self.order: list[str] = []
        self.stack: list[list] = []  # [label, seconds spent in nested stages]
        self.returned: dict = {}
        self._undo: list = []

    def _wrap(self, fn, template):
        @functools.wraps(fn)
        def timed(*args, **kwargs):
            name = _label(template, args)
            if "{phase}" in template and kwargs.get("label") == "polish":
                name = "run_phase [polish]"
            if name not in self.order:
                self.order.append(name)
            frame = [name, 0.0]
            self.stack.append(frame)
            t = time.perf_counter()
            try:
                out = fn(*args, **kwargs)
                self.returned[template] = out
                return out
            finally:
                dt = time.perf_counter() - t
                self.stack.pop()
                self.inclusive[name] += dt
                self.exclusive[name] += dt - frame[1]
                self.calls[name] += 1
                if self.stack:
                    self.stack[-1][1] += dt
        timed.__wrapped_by_profile__ = True
        return timed

    def __enter__(self):
        for module_name, path, template in self.stages:
            module = importlib.import_module(module_name)
            owner_path, attr = path.rpartition(".")[::2]
            owner = module
            for part in filter(None, owner_path.split(".")):
                owner = getattr(owner, part)
            original = owner.__dict__[attr] if isinstance(owner, type) else getattr(owner, attr)
            wrapped = self._wrap(original, template)
            self._undo.append((owner, attr, original))
            setattr(owner, attr, wrapped)
            if not isinstance(owner, type):  # the same function imported by name into other modules
                for mod in list(sys.modules.values()):
                    if mod is not None and mod is not owner and getattr(mod, "__name__", "").startswith("supportless") \
                            and getattr(mod, attr, None) is original:
                        self._undo.append((mod, attr, original))
                        setattr(mod, attr, wrapped)
        return self

    def __exit__(self, *exc):
        for owner, attr, original in reversed(self._undo):
            setattr(owner, attr, original)
        self._undo.clear()
        return False

    def rows(self):
        return [(name, self.calls[name], self.inclusive[name], self.exclusive[name]) for name in self.order]


def _import_all():
    """Import the modules the CLI imports lazily, so the names imported from them are patched too."""
    for name in ("supportless.apps.cli_optimize", "supportless.apps.cli_common", "supportless.report.outputs",
                 "supportless.report.report", "supportless.slicing.ranking", "supportless.slicing.prusaslicer",
                 "supportless.search.answer", "supportless.search.optimizer", "supportless.search.choice",
                 "supportless.search.result",
                 "supportless.rig.load"):
        importlib.import_module(name)


def warm(model: str) -> None:
    """Compile numba's functions on this model's rig (ordinary cache) with a tiny search."""
    _, load_args, _ = MODELS[model]
    rig = sl.load_rig(**load_args)
    from supportless.search.answer import optimize

    optimize(rig, SearchSettings(particles=8, iterations=2))


def run_default(model: str, folder: Path) -> tuple[float, Profiler]:
    """``supportless optimize MODEL`` with its defaults, cold rig, in this process: (seconds, profiler)."""
    from supportless.apps.cli_optimize import optimize as command

    cli_args, _, _ = MODELS[model]
    args = [*cli_args, "--no-cache", "-q", "-o", str(folder / "posed.stl"), "--report", str(folder / "report.json"),
            "--pose", str(folder / "pose.json"), "--pictures", str(folder / "pictures")]
    with Profiler() as prof, contextlib.redirect_stdout(open(os.devnull, "w")):
        t = time.perf_counter()
        command.main(args, standalone_mode=False)
        total = time.perf_counter() - t
    return total, prof


def floor(model: str) -> dict:
    """The skinning of particles x iterations poses of the default search, in batches of one iteration."""
    from supportless.apps.bench import random_poses
    from supportless.base.kinematics import skin

    _, load_args, _ = MODELS[model]
    rig = sl.load_rig(**load_args)
    surface = rig.coarse_rig() or rig
    s = SearchSettings()
    A = random_poses(surface, s.particles, seed=3)
    M = surface.lbs
    skin(M, surface.transforms(A[:2]))  # warm
    fk = sk = 0.0
    for _ in range(s.iterations):
        t = time.perf_counter()
        T = surface.transforms(A)
        t1 = time.perf_counter()
        skin(M, T)
        t2 = time.perf_counter()
        fk += t1 - t
        sk += t2 - t1
    return {"poses": s.particles * s.iterations, "particles": s.particles, "iterations": s.iterations,
            "vertices": len(surface.vertices), "faces": len(surface.faces), "proxy": surface is not rig,
            "full_faces": len(rig.faces), "fk": fk, "skin": sk}


def _fmt_s(x: float) -> str:
    return f"{x:.2f}" if x >= 0.01 else f"{x:.3f}"


def section(model: str, total: float, prof: Profiler, fl: dict) -> str:
    label = MODELS[model][2]
    lines = [f"### {label}", "",
             f"Whole `supportless optimize` (cold rig, defaults): **{total:.1f} s**.", "",
             "| stage | calls | inclusive s | share | exclusive s | share |", "|---|---:|---:|---:|---:|---:|"]
    inside = 0.0
    for name, calls, inc, exc in prof.rows():
        inside += exc
        lines.append(f"| {name} | {calls} | {_fmt_s(inc)} | {100 * inc / total:.1f} % | {_fmt_s(exc)} | "
                     f"{100 * exc / total:.1f} % |")
    rest = total - inside
    lines.append(f"| (outside every stage: CLI, printing, files) | | | | {_fmt_s(rest)} | {100 * rest / total:.1f} % |")
    lines.append(f"| **total** | | {_fmt_s(total)} | 100 % | | |")
    result = prof.returned.get("as_written") or prof.returned.get("optimize (whole search, every search)")
    stats = {} if result is None else result.flat_stats()
    own = {k: v for k, v in sorted(stats.items()) if k.endswith("_seconds") or k.endswith("_calls")}
    if own:
        lines += ["", "The package's own `result.stats` (of the answer kept): " + ", ".join(
            f"`{k}` {v:.2f}" if isinstance(v, float) else f"`{k}` {v}" for k, v in own.items()) + "."]
    bare = fl["fk"] + fl["skin"]
    where = (f"the {fl['faces']}-triangle proxy the swarm searches ({fl['full_faces']} triangles in full)"
             if fl["proxy"] else f"its {fl['faces']}-triangle surface")
    lines += ["", f"Floor: skinning {fl['poses']} poses ({fl['particles']} x {fl['iterations']}, in batches of "
                  f"{fl['particles']}) on {where}, {fl['vertices']} vertices: forward kinematics {fl['fk']:.2f} s + "
                  f"skinning {fl['skin']:.2f} s = **{bare:.2f} s**; the whole answer is **{total / bare:.0f}x** the "
                  f"floor (the search alone, `optimize`, "
                  f"{prof.inclusive.get('optimize (whole search, every search)', 0.0) / bare:.0f}x).", ""]
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", default="bunny,tpose", help="comma-separated: " + ", ".join(MODELS))
    ap.add_argument("--out", default=None, help="write the section into this Markdown file (benchmarks/RESULTS.md)")
    args = ap.parse_args()
    models = [m.strip() for m in args.models.split(",") if m.strip()]
    for m in models:
        if m not in MODELS:
            ap.error(f"unknown model {m!r}; choose among {', '.join(MODELS)}")
    _import_all()
    import shutil

    import numba

    start_load = os.getloadavg()
    parts = []
    for m in models:
        warm(m)
        with tempfile.TemporaryDirectory(prefix="supportless-profile-") as tmp:
            total, prof = run_default(m, Path(tmp))
        fl = floor(m)
        text = section(m, total, prof, fl)
        print(text, flush=True)
        parts.append(text)
    load = os.getloadavg()
    slicer = shutil.which("prusa-slicer") or shutil.which("PrusaSlicer")
    head = [HEADING, "",
            "Wall time per stage of `supportless optimize MODEL` with its defaults (search "
            f"{SearchSettings().particles} x {SearchSettings().iterations}, the choice among the answers, "
            "PrusaSlicer's ranking " + ("(installed)" if slicer else "(not installed: skipped)") +
            ", the report, the pictures and files), on a cold rig (`--no-cache`) after numba is warmed, measured by "
            "wrapping the package's functions at run time (`benchmarks/profile.py`, nothing edited). Stages nest: "
            "*inclusive* counts the stages a stage calls, *exclusive* does not; the exclusive column and the "
            "remainder add up to the total. The floor is the bare skinning of the poses the search evaluates "
            "(particles x iterations of the default settings), timed in the same process.", "",
            f"Machine: {os.cpu_count()} cores, numba threads {numba.get_num_threads()}, load average (1/5/15 min) "
            f"{start_load[0]:.2f} / {start_load[1]:.2f} / {start_load[2]:.2f} at the start, "
            f"{load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} at the end. "
            f"Command: `python benchmarks/profile.py --models {','.join(models)}"
            f"{' --out ' + args.out if args.out else ''}`.", ""]
    text = "\n".join(head + parts)
    print("\n".join(head[-2:]))
    if args.out:
        write_section(Path(args.out), HEADING, text)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
