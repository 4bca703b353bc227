"""Timing of the pipeline's stages, fast (numba) path against the plain numpy path.

:func:`run_bench` is what ``supportless bench`` and ``benchmarks/speed.py``
call. For each model it times

* ``prepare cold``: tet mesh + bounded biharmonic weights, in a temporary
  (empty) cache folder;
* ``prepare cached``: loading the same rig from that cache;
* ``one pose``: one call of the :class:`~supportless.search.objective.Objective` on a
  single pose (what the viewer does per edit);
* ``one swarm iteration``: the objective on ``particles`` poses in one batch;
* ``whole search``: :func:`supportless.search.answer.optimize` with the given swarm
  size and iterations, including its exact (CGAL) intersection checks and the
  per-iteration terms of the best pose for the progress callback (their
  shares are printed below the table).

Both paths run in the same process on the same poses. The numpy path is
slow: its whole search is extrapolated from its swarm-iteration and
one-pose times, and the table says so. Numba compilation is excluded (a
warm-up call runs first). Times are the best of a few runs.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..search.settings import SearchSettings

__all__ = ["bench_model", "default_models", "random_poses", "run_bench", "timed_search"]

#: Folder of the shared test models (``../shared/data`` beside the repository
#: root, which is ``parents[2]`` of this file).
SHARED_DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data"


def default_models() -> list[tuple[str, str | None, str]]:
    """The built-in ``tpose`` and, when ``../shared/data`` exists, the bunny: (model, skeleton, up)."""
    models = [("demo:tpose", None, "y")]
    bunny = SHARED_DATA / "bunny.obj"
    if bunny.is_file():
        models.append((str(bunny), str(SHARED_DATA / "bunny.tgf"), "y"))
    return models


def _best(fn: Callable, repeat: int) -> float:
    best = np.inf
    for _ in range(max(1, repeat)):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def _fmt(seconds: float | None) -> str:
    if seconds is None or not np.isfinite(seconds):
        return "-"
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e6:.0f} us"


def random_poses(rig, count: int, max_angle: float = 30.0, seed: int = 0) -> np.ndarray:
    """Random poses of the search's free bones.

    Parameters
    ----------
    rig : Rig
    count : int
    max_angle : float
        Every free angle is uniform in ±``max_angle`` degrees.
    seed : int

    Returns
    -------
    angles : (count, m, 3) float64
    """
    from ..search.settings import angle_layout

    free = angle_layout(rig, SearchSettings().fixed_bones(rig))
    rng = np.random.default_rng(seed)
    A = np.zeros((count, rig.bone_count, 3))
    lim = np.radians(max_angle)
    A[:, free] = rng.uniform(-lim, lim, (count, int(free.sum())))
    return A


def timed_search(rig, objective, settings) -> dict:
    """Run :func:`supportless.search.answer.optimize` and split its wall time.

    Parameters
    ----------
    rig : Rig
    objective : Objective
        Already set up (its precomputation is timed elsewhere).
    settings : SearchSettings

    Returns
    -------
    timing : dict
        ``seconds``, ``result`` (the PoseResult) and the search's own
        ``stats``: the exact check's ``exact_seconds``/``exact_calls`` and the
        progress terms' ``progress_seconds``/``progress_calls``.
    """
    from ..search.answer import optimize

    t = time.perf_counter()
    result = optimize(rig, settings, objective=objective)
    return {"seconds": time.perf_counter() - t, "result": result, **result.stats.to_dict()}


def bench_model(model, skeleton=None, up="auto", *, particles: int = SearchSettings.particles, iterations: int = SearchSettings.iterations,
                backend: str = "both", echo: Callable[[str], None] = print, repeat: int = 3) -> dict:
    """Time one model's stages on the chosen backends and print the table.

    Returns the measured times: ``{"rows": [(stage, {backend: seconds}, per_pose_count, note)], ...}``.
    """
    from ..rig.load import load_rig

    backends = ["fast", "numpy"] if backend == "both" else [backend]
    with tempfile.TemporaryDirectory(prefix="supportless-bench-") as tmp:
        t = time.perf_counter()
        rig = load_rig(model, skeleton, up, cache_dir=tmp)
        cold = time.perf_counter() - t
        cached = _best(lambda: load_rig(model, skeleton, up, cache_dir=tmp), repeat)
    echo(f"\n{rig!r}")
    info = rig.info
    echo(f"  cold preparation: tets {_fmt(info.get('tet_seconds'))}, weights {_fmt(info.get('weights_seconds'))}")

    one = random_poses(rig, 1, seed=1)[0]
    swarm = random_poses(rig, particles, seed=2)
    times: dict[str, dict] = {}
    search_info = {}
    for b in backends:
        settings = SearchSettings(particles=particles, iterations=iterations, backend=b)
        obj = settings.objective(rig)  # what the search minimises by default
        t = time.perf_counter()
        obj.arap_data, obj.rest_overhang  # noqa: B018 -- precompute (once per rig)
        obj(swarm[:2])  # warm-up: numba compilation / caches
        setup = time.perf_counter() - t
        slow = b == "numpy"
        pose_t = _best(lambda: obj(one), 2 if slow else 5 * repeat)
        iter_t = _best(lambda: obj(swarm), 1 if slow else repeat)
        times[b] = {"setup": setup, "pose": pose_t, "iteration": iter_t}
        if slow:
            # (iterations + 1) swarm evaluations and one progress pose per iteration
            times[b]["search"] = (iterations + 1) * iter_t + iterations * pose_t
            times[b]["search_note"] = "extrapolated"
        else:
            s = timed_search(rig, obj, settings)
            times[b]["search"] = s["seconds"]
            search_info[b] = s
    rows = [
        ("prepare cold (empty cache)", {b: cold for b in backends}, None),
        ("prepare cached", {b: cached for b in backends}, None),
        ("objective setup (once per rig)", {b: times[b]["setup"] for b in backends}, None),
        ("one pose", {b: times[b]["pose"] for b in backends}, 1),
        (f"one swarm iteration ({particles} poses)", {b: times[b]["iteration"] for b in backends}, particles),
        (f"whole search {particles}x{iterations}", {b: times[b]["search"] for b in backends},
         particles * (iterations + 1)),
    ]
    head = f"  {'stage':<34}" + "".join(f"{b + ' time':>14}{b + ' /pose':>14}" for b in backends)
    if len(backends) == 2:
        head += f"{'speed-up':>10}"
    echo(head)
    for stage, vals, per in rows:
        line = f"  {stage:<34}"
        for b in backends:
            v = vals[b]
            note = "*" if stage.startswith("whole") and times[b].get("search_note") else ""
            line += f"{_fmt(v) + note:>14}{(_fmt(v / per) if per else '-'):>14}"
        if len(backends) == 2:
            shared = stage.startswith("prepare")
            line += f"{'-' if shared else format(vals['numpy'] / vals['fast'], '.0f') + 'x':>10}"
        echo(line)
    if "numpy" in backends:
        echo("  * numpy whole search extrapolated: (iterations + 1) x swarm iteration + iterations x one pose")
    for b, s in search_info.items():
        r = s["result"]
        echo(f"  {b} search: overhang {100 * (1 - r.terms['overhang']):.1f} % below the rest pose, "
             f"self-intersection {100 * r.terms['intersection']:.3f} % of the volume, "
             f"E_arap/vol {r.terms['arap']:.4f}, objective {r.value:.4f}")
        echo(f"  {b} search time: exact CGAL checks {_fmt(s.get('exact_seconds', 0.0))} "
             f"({s.get('exact_calls', 0)} calls, {100 * s.get('exact_seconds', 0.0) / s['seconds']:.0f} %), progress terms {_fmt(s['progress_seconds'])} "
             f"({s['progress_calls']} calls, {100 * s['progress_seconds'] / s['seconds']:.0f} %)")
    return {"rig": repr(rig), "cold": cold, "cached": cached, "times": times,
            "search": {b: {k: v for k, v in s.items() if k != "result"} | {"terms": s["result"].terms}
                       for b, s in search_info.items()}}


def run_bench(model=None, skeleton=None, up="auto", *, particles: int = SearchSettings.particles, iterations: int = SearchSettings.iterations,
              backend: str = "both", echo: Callable[[str], None] = print) -> list[dict]:
    """Print the timing table of each model (see the module docstring).

    Parameters
    ----------
    model : str or None
        A mesh file (with ``skeleton``) or ``demo:NAME``; None: the built-in
        ``tpose`` and, when ``../shared/data`` exists, the bunny.
    skeleton : str, optional
    up : str
    particles, iterations : int
        The swarm (default: :class:`~supportless.search.settings.SearchSettings`', the paper's 200 x 120).
    backend : {"both", "fast", "numpy"}
    echo : callable(str)

    Returns
    -------
    results : list of dict
        One per model, as :func:`bench_model`.
    """
    import numba

    if backend not in ("both", "fast", "numpy"):
        raise ValueError(f"backend must be 'both', 'fast' or 'numpy', not {backend!r}")
    models = default_models() if model is None else [(str(model), skeleton, up)]
    echo(f"supportless bench: {particles} particles x {iterations} iterations, backend {backend}, "
         f"numba threads {numba.get_num_threads()}")
    return [bench_model(m, s, u, particles=particles, iterations=iterations, backend=backend, echo=echo)
            for m, s, u in models]
