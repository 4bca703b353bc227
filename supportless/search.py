"""Global search over bone rotations: a batched particle swarm.

:func:`particle_swarm` is a plain bounded particle swarm optimizer with the
standard velocity update (inertia, cognitive and social terms, positions
clamped to the bounds) as in libigl's ``igl::pso``, except that the whole swarm
is evaluated in one batched call per iteration. :func:`optimize` searches the
Euler angles of a rig's free bones with it (and, with ``orient="free"``, the
print rotation: two more variables in 3D, one in 2D, in a second swarm, see
:data:`TURN_SHARE`) and returns a :class:`PoseResult`.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .copyleft.cgal import self_intersects
from .geometry import place_on_plate, print_pose
from .interrupt import deferred_interrupt, requested
from .choice import choose
from .candidates import CANDIDATE_TOLERANCE, DISTINCT_DEGREES, distinct_candidates, pose_distance_deg
from .objective import Objective
from .orientation import orientation_params, rotations_from_params, seed_params
from .result import PoseResult, as_written, measured_at, on_full_surface
from .rig import Rig
from .settings import PSO_PRESETS, SearchSettings
from .symmetry import PoseLayout, require_mirror

__all__ = ["CANDIDATE_TOLERANCE", "CMA_SHARE", "DISTINCT_DEGREES", "OPTIMIZERS", "PoseResult", "SwarmResult", "TURN_SHARE",
           "distinct_candidates", "evolution_strategy", "measured_at", "optimize", "pose_distance_deg",
           "particle_swarm"]

#: With ``orient="free"`` the search runs the pose-only swarm, then a swarm of
#: ``particles // TURN_SHARE`` over pose and turn together, started from the
#: best pose upright and at the candidate directions: never worse than the
#: pose-only search by the objective. Half the swarm since the self-intersection
#: is measured only for would-be bests (it was a third, when every personal best
#: was measured in full): over 5 seeds of the 15 zoo models the objective is
#: then 0.999x the one of the search before both changes (the dragon 1.20x, the
#: worst), in 0.56x its time (benchmarks/RESULTS.md, "Speed targets").
TURN_SHARE = 2

@dataclass
class SwarmResult:
    """Outcome of :func:`particle_swarm`.

    Attributes
    ----------
    x : (k,) float64
        Best position found.
    value : float
        Objective at ``x``.
    history : (iterations + 1,) float64
        Best value after initialisation and after each iteration.
    evaluations : int
    interrupted : bool
        True if the search was stopped early (Ctrl-C or the stop callback).
    candidates_x : (q, k) float64
        Other good positions, for a second opinion on the best (e.g. a
        slicer's): the swarm's personal bests, or the best samples CMA-ES
        computed exactly. Their values may not have passed ``feasible``.
    candidates_values : (q,) float64
        Their objective values.
    """

    x: np.ndarray
    value: float
    history: np.ndarray
    evaluations: int
    interrupted: bool = False
    candidates_x: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    candidates_values: np.ndarray = field(default_factory=lambda: np.zeros(0))


def particle_swarm(f: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, upper: np.ndarray, *,
                   particles: int = 200, iterations: int = 120, rng: np.random.Generator | None = None,
                   inertia: float = 0.7298, cognitive: float = 1.49618, social: float = 1.49618,
                   initial: np.ndarray | None = None,
                   callback: Callable[[int, np.ndarray, float], bool | None] | None = None,
                   feasible: Callable[[np.ndarray], bool] | None = None,
                   pass_bound: bool = False) -> SwarmResult:
    """Minimise ``f`` over a box with a particle swarm.

    Parameters
    ----------
    f : callable
        ``f(X)`` with ``X (P, k) float64`` returns ``(P,) float64``: the whole
        swarm is evaluated in one call per iteration.
    lower, upper : (k,) float64
        Bounds of each variable.
    particles : int
        Swarm size.
    iterations : int
        Number of velocity updates.
    rng : numpy.random.Generator
        Source of all randomness (default: ``default_rng(0)``).
    inertia, cognitive, social : float
        ``v <- inertia*v + cognitive*r_p*(p_best - x) + social*r_g*(g_best - x)``.
    initial : (q, k) float64, optional
        Positions used for the first ``q`` particles (e.g. the rest pose), the
        others start uniformly at random in the box.
    callback : callable, optional
        ``callback(iteration, best_x, best_value)`` after each iteration;
        returning ``False`` stops the search.
    feasible : callable, optional
        ``feasible(x) -> bool`` for a hard constraint too expensive to test on
        every particle: it is asked only about positions that would become the
        swarm's best (best first), and a rejected position counts as +inf. The
        initial particles given in ``initial`` are taken as feasible.
    pass_bound : bool
        Call ``f(X, bound)`` with each particle's best value so far (+inf at
        the start): where ``f`` cannot go below the bound it may return any
        value not below it, and skip the exact computation.

    Returns
    -------
    result : SwarmResult
        On Ctrl-C (KeyboardInterrupt) the best found so far, with
        ``interrupted=True``.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    lower = np.asarray(lower, np.float64)
    upper = np.asarray(upper, np.float64)
    k = lower.size
    span = upper - lower
    X = lower + rng.random((particles, k)) * span
    if initial is not None:
        initial = np.atleast_2d(np.asarray(initial, np.float64))[:particles]
        X[: len(initial)] = np.clip(initial, lower, upper)
    Vel = span * rng.uniform(-1.0, 1.0, (particles, k)) * 0.25
    def evaluate(X, bound):
        return np.asarray(f(X, bound) if pass_bound else f(X), np.float64)

    values = evaluate(X, np.full(particles, np.inf))
    evaluations = particles
    n_initial = 0 if initial is None else len(initial)
    if feasible is not None:
        g_f = values[:n_initial].min() if n_initial else np.inf
        _reject_infeasible(values, X, g_f, feasible, skip=n_initial)
    best_X, best_f = X.copy(), values.copy()
    g = int(np.argmin(best_f))
    g_x, g_f = best_X[g].copy(), float(best_f[g])
    history = [g_f]
    interrupted = requested()
    try:
        for it in range(0 if interrupted else iterations):
            r_p = rng.random((particles, k))
            r_g = rng.random((particles, k))
            Vel = inertia * Vel + cognitive * r_p * (best_X - X) + social * r_g * (g_x - X)
            X = np.clip(X + Vel, lower, upper)
            values = evaluate(X, best_f)
            evaluations += particles
            if feasible is not None:
                _reject_infeasible(values, X, g_f, feasible)
            improved = values < best_f
            best_X[improved] = X[improved]
            best_f[improved] = values[improved]
            g = int(np.argmin(best_f))
            if best_f[g] < g_f:
                g_x, g_f = best_X[g].copy(), float(best_f[g])
            history.append(g_f)
            if callback is not None and callback(it + 1, g_x, g_f) is False or requested():
                interrupted = True
                break
    except KeyboardInterrupt:
        interrupted = True
    return SwarmResult(g_x, g_f, np.asarray(history), evaluations, interrupted, best_X, best_f)


#: CMA-ES samples ``particles // CMA_SHARE`` poses per generation for
#: ``iterations`` generations: a fifth of the swarm's evaluations. Measured on
#: the zoo and the shared models (``benchmarks/optimizers.py``) it takes
#: about 0.8x the swarm's time but ends worse on some figures (a local search
#: from the rest pose), so the swarm stays the default.
CMA_SHARE = 5


def evolution_strategy(f: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, upper: np.ndarray, *,
                       particles: int = 200, iterations: int = 120, rng: np.random.Generator | None = None,
                       initial: np.ndarray | None = None, sigma: float = 0.1,
                       callback: Callable[[int, np.ndarray, float], bool | None] | None = None,
                       feasible: Callable[[np.ndarray], bool] | None = None,
                       pass_bound: bool = False) -> SwarmResult:
    """Minimise ``f`` over a box with CMA-ES (the ``cma`` package), one batched call per generation.

    The search runs in the box scaled to the unit cube, from the best of the
    ``initial`` positions, with ``particles // CMA_SHARE`` samples per
    generation (at least 8) for ``iterations`` generations; when the strategy
    converges early it restarts from the best position found.

    Parameters
    ----------
    f : callable
        ``f(X)`` (or ``f(X, bound)`` with ``pass_bound``), ``X (P, k) float64``
        -> ``(P,) float64``.
    lower, upper : (k,) float64
        Bounds of each variable.
    particles, iterations : int
        The swarm's budget words: see above.
    rng : numpy.random.Generator
        Source of all randomness (default: ``default_rng(0)``).
    initial : (q, k) float64, optional
        Positions evaluated first (taken as feasible); the search starts at
        the best of them (default: the centre of the box).
    sigma : float
        Initial step size as a share of each variable's range.
    callback, feasible
        As :func:`particle_swarm`.
    pass_bound : bool
        Call ``f(X, bound)`` with the previous generation's median as the
        bound: only the better half of a generation steers the strategy, so
        samples that cannot beat the median need not be computed exactly.

    Returns
    -------
    result : SwarmResult
        The best feasible position seen; ``history`` per generation.
    """
    import cma

    rng = np.random.default_rng(0) if rng is None else rng
    lower = np.asarray(lower, np.float64)
    upper = np.asarray(upper, np.float64)
    span = np.where(upper > lower, upper - lower, 1.0)
    popsize = max(8, particles // CMA_SHARE)
    bound = np.inf

    def evaluate(Z):
        X = lower + np.clip(Z, 0.0, 1.0) * span
        values = f(X, np.full(len(X), bound)) if pass_bound else f(X)
        return np.array(values, np.float64), X

    initial = np.full((1, lower.size), 0.5) * span + lower if initial is None else np.atleast_2d(initial)
    values, X = evaluate((np.asarray(initial, np.float64) - lower) / span)
    evaluations = len(values)
    i = int(np.argmin(values))
    g_x, g_f = X[i].copy(), float(values[i])
    history = [g_f]

    def strategy(x0):
        options = {"bounds": [0.0, 1.0], "popsize": popsize, "verbose": -9,
                   "seed": int(rng.integers(1, 2**31 - 1)), "CMA_active": False}
        return cma.CMAEvolutionStrategy(np.clip((x0 - lower) / span, 0.0, 1.0), sigma, options)

    es = strategy(g_x)
    archive_x, archive_f = [X], [values]
    interrupted = requested()
    try:
        for it in range(0 if interrupted else iterations):
            if es.stop():
                es, bound = strategy(g_x), np.inf
            Z = np.asarray(es.ask(), np.float64)
            values, X = evaluate(Z)
            evaluations += len(values)
            if feasible is not None:
                _reject_infeasible(values, X, g_f, feasible)
            i = int(np.argmin(values))
            if values[i] < g_f:
                g_x, g_f = X[i].copy(), float(values[i])
            exact = np.isfinite(values) & (values < bound)
            archive_x.append(X[exact])
            archive_f.append(values[exact])
            finite = np.isfinite(values)
            ranked = np.where(finite, values, values[finite].max() + 1.0 if finite.any() else 0.0)
            es.tell(list(Z), ranked.tolist())
            bound = float(np.median(ranked))
            history.append(g_f)
            if callback is not None and callback(it + 1, g_x, g_f) is False or requested():
                interrupted = True
                break
    except KeyboardInterrupt:
        interrupted = True
    cand_x, cand_f = np.concatenate(archive_x), np.concatenate(archive_f)
    keep = np.argsort(cand_f, kind="stable")[:particles]
    return SwarmResult(g_x, g_f, np.asarray(history), evaluations, interrupted, cand_x[keep], cand_f[keep])


#: The polish (``SearchSettings.polish``): CMA-ES with this many samples per generation, its initial step this
#: share of each variable's range (a joint's range of 180 degrees: 0.9 degrees).
POLISH_SAMPLES = 16
POLISH_SIGMA = 0.005

#: The polish on the full surface after a proxy search (``SearchSettings.polish=None``) runs this many
#: triangles x generations: its cost is about the same whatever the density (the 31 086-triangle character: 80
#: generations, 1281 evaluations; the bunny subdivided twice, 111 456 triangles: 22).
PROXY_POLISH_BUDGET = 2_500_000

#: A ray-grid self-intersection volume above this share of the model's volume is taken as proof that a pose
#: intersects itself (an embedded closed surface is nowhere two layers deep); the exact gate then skips CGAL.
#: On the robot 767 of 1128 rejected candidates, on the tree 480 of 516, had such a volume; no accepted one had.
OVERLAP_CERTAIN = 1e-9

#: The searches :func:`optimize` can run (``SearchSettings.optimizer``).
OPTIMIZERS = {"cma": evolution_strategy, "pso": particle_swarm}


def _reject_infeasible(values, X, threshold, feasible, skip=0):
    """Set to +inf the values of infeasible positions that would beat ``threshold``.

    Candidates are tested best first and testing stops at the first feasible
    one: only it can become the swarm's best in this round.
    """
    order = np.argsort(values, kind="stable")
    for i in order:
        if values[i] >= threshold:
            break
        if i < skip or feasible(X[i]):
            return
        values[i] = np.inf


# --------------------------------------------------------------------------- #
# pose search
# --------------------------------------------------------------------------- #
class _Timed:
    """Wraps a callable and sums its calls and wall time into ``stats``."""

    def __init__(self, fn: Callable, stats: dict, name: str):
        self.fn, self.stats, self.name = fn, stats, name
        stats.setdefault(f"{name}_calls", 0)
        stats.setdefault(f"{name}_seconds", 0.0)

    def __call__(self, *args):
        t = time.perf_counter()
        try:
            return self.fn(*args)
        finally:
            self.stats[f"{self.name}_seconds"] += time.perf_counter() - t
            self.stats[f"{self.name}_calls"] += 1


def optimize(rig: Rig, settings: SearchSettings | None = None, *, objective: Objective | None = None,
             start: np.ndarray | None = None, start_rotation: np.ndarray | None = None,
             callback: Callable[[int, dict], bool | None] | None = None, **changes) -> PoseResult:
    """Find a pose of ``rig`` that needs less support, with a particle swarm.

    Parameters
    ----------
    rig : Rig
    settings : SearchSettings, optional
        What to search (default: ``SearchSettings()``, the tool's defaults).
    objective : Objective, optional
        Use this objective instead of ``settings.objective(rig)`` (e.g. one
        whose ARAP operators are already computed).
    start : (m, 3) float64, optional
        A pose to start from (radians), e.g. one edited by hand: fixed bones
        keep its angles, and it is one of the initial particles (with the
        free bones' rest rotations as another), so the result is never worse
        than the start pose.
    start_rotation : (d, d) float64, optional
        A print rotation to start from (with ``orient="free"``): the start
        pose turned by it is one more initial particle, so a repeated search
        is never worse than the pose and turn it starts from.
    callback : callable, optional
        ``callback(iteration, info)`` with ``info`` holding ``value``, ``terms``
        (normalised terms of the best pose), ``angles``, ``rotation`` (the
        print rotation), ``iterations`` (of the whole search, every phase and
        the polish; it does not change) and ``phase`` ("pose", "pose and
        turn" or "polish"); return ``False`` to stop.
    **changes
        Settings to change from ``settings`` (``particles=50``, ``seed=1``, ...).

    Returns
    -------
    result : PoseResult
        Never worse than the rest pose (the rest pose is one of the particles).
        With ``orient="free"`` in 3D and ``settings.choose`` (the default),
        the answer with the least predicted slicer support among the
        search's best, the best pose printed as it stands and the best turned
        start pose (:func:`supportless.choice.choose`; its ``choice`` says
        which and why). On Ctrl-C the search stops after the iteration under way and returns
        its best so far with ``interrupted=True``
        (:func:`supportless.interrupt.deferred_interrupt`).
    """
    with deferred_interrupt():
        found = _optimize(rig, settings, objective=objective, start=start, start_rotation=start_rotation,
                          callback=callback, **changes)
        if found.alternatives and found.settings.choose and rig.dim == 3 and not found.interrupted:
            found = choose(rig, found)
    return as_written(rig, found)


def _optimize(rig: Rig, settings: SearchSettings | None = None, *, objective: Objective | None = None,
              start: np.ndarray | None = None, start_rotation: np.ndarray | None = None,
              callback: Callable[[int, dict], bool | None] | None = None, _polish_only: bool = False,
              **changes) -> PoseResult:
    """:func:`optimize` without the Ctrl-C handling (``_polish_only``: no swarm, the polish from the start)."""
    t0 = time.perf_counter()
    settings = (settings or SearchSettings()).replace(**changes)
    coarse = rig.coarse_rig() if objective is None else None
    if coarse is not None:  # a dense surface: search its simplified proxy, then measure on the full one
        full = settings.objective(rig)  # the proxy shares its volume mesh, so its ARAP operators, and its volume
        polish = max(1, round(PROXY_POLISH_BUDGET / len(rig.faces))) if settings.polish is None else settings.polish
        seen = {"iterations": 0}

        def progress(offset, more):  # the proxy's iterations, then the polish's, counted as one search
            def report(it, info):
                seen["iterations"] = offset + it
                return callback(offset + it, info | {"iterations": info["iterations"] + more})
            return None if callback is None else report

        found = _optimize(coarse, settings.replace(polish=0),
                          objective=settings.objective(coarse, full.arap_data, full.volume),
                          start=start, start_rotation=start_rotation, callback=progress(0, polish))
        chosen = on_full_surface(rig, found, full, t0)
        if not polish or chosen.interrupted:
            return chosen
        polished = _optimize(rig, settings.replace(polish=polish), objective=full, start=chosen.angles,
                             start_rotation=chosen.rotation,
                             callback=progress(seen["iterations"], seen["iterations"]), _polish_only=True)
        stats = dict(chosen.stats, full_polish_value=polished.value,
                     full_polish_evaluations=polished.stats["polish_evaluations"],
                     full_exact_calls=chosen.stats["full_exact_calls"] + polished.stats.get("exact_calls", 0))
        better = polished.value < chosen.value
        return dataclasses.replace(measured_at(rig, chosen, polished.angles, polished.rotation, full) if better
                                   else chosen, stats=stats, interrupted=polished.interrupted,
                                   history=np.concatenate([chosen.history, polished.history[1:]]),
                                   runtime_seconds=time.perf_counter() - t0)
    if objective is None:
        objective = settings.objective(rig)
    base = np.zeros((rig.bone_count, 3)) if start is None else np.asarray(start, np.float64).reshape(-1, 3)
    if base.shape != (rig.bone_count, 3):
        raise ValueError(f"start pose has {len(base)} bones, the rig {rig.bone_count}")
    mirror = require_mirror(rig) if settings.symmetric else None
    layout = PoseLayout(rig, settings.fixed_bones(rig), base, np.radians(settings.joint_limits(rig)), mirror)
    fixed, k = layout.fixed, layout.count
    stats: dict = {}
    term_history = {"arap": [], "overhang": [], "intersection": []}
    turning = settings.orient == "free"
    # orient="free": the pose alone first (the whole swarm, as "keep"), then pose and turn together with
    # part of the swarm (TURN_SHARE), started from the first phase's best pose upright and at the candidate directions
    phases = [] if _polish_only else ([False] if k else []) + ([True] if turning else [])
    polishing = (settings.polish or 0) if k or turning else 0
    total = settings.iterations * len(phases) + polishing

    def variables(turns):
        o = rig.dim - 1 if turns else 0

        def to_angles(X):
            return layout.to_angles(X[:, :k])

        def to_rotation(x):
            return rotations_from_params(x[None, k:], rig.up)[0] if turns else np.eye(rig.dim)

        return o, to_angles, to_rotation

    feasible = None
    overlapping: set = set()  # positions of the last batch whose ray grid saw two layers: they intersect
    stats["overlap_rejections"] = 0
    if settings.exact_intersections and rig.dim == 3:
        cgal = _Timed(lambda x: self_intersects(rig.pose(layout.to_angles(x[None, :k])[0]), rig.faces), stats, "exact")

        def no_intersection(x):
            if x.tobytes() in overlapping:  # no need to ask CGAL
                stats["overlap_rejections"] += 1
                return False
            return not cgal(x)

        feasible = no_intersection

    def run_phase(turns, initial, particles, offset, optimizer=settings.optimizer, iterations=settings.iterations,
                  label=None, **options):
        o, to_angles, to_rotation = variables(turns)

        def f(X, bound):
            R = rotations_from_params(X[:, k:], rig.up) if turns else None
            # the self-intersection only for poses that could become the swarm's best (the least of the personal
            # bests): a particle's own best is judged by the other terms, the swarm's by all, then exactly
            values, overlap = objective.bounded_overlap(to_angles(X), bound, R, intersection_bound=np.min(bound))
            overlapping.clear()
            overlapping.update(X[i].tobytes() for i in np.flatnonzero(overlap > OVERLAP_CERTAIN * objective.volume))
            return values

        def terms_of(x):
            return objective.terms(to_angles(x[None]), to_rotation(x)[None] if turns else None)

        best_terms = _Timed(terms_of, stats, "progress")
        last = {}

        def on_iteration(it, x, value):
            if last.get("x") is None or not np.array_equal(last["x"], x):  # the best changed
                last["x"], last["terms"] = x.copy(), {key: float(v[0]) for key, v in best_terms(x).items()}
            terms = last["terms"]
            for key in term_history:
                term_history[key].append(terms[key])
            if callback is not None:
                return callback(offset + it, {"value": value, "terms": terms, "angles": to_angles(x[None])[0],
                                              "rotation": to_rotation(x), "iterations": total,
                                              "phase": label or ("pose and turn" if turns else "pose")})
            return None

        lower = np.concatenate([layout.lower, np.full(o, -np.pi)])
        upper = np.concatenate([layout.upper, np.full(o, np.pi)])
        options = (PSO_PRESETS[settings.preset] if optimizer == "pso" else {}) | options
        return OPTIMIZERS[optimizer](f, lower, upper, particles=particles, iterations=iterations,
                                     rng=np.random.default_rng(settings.seed), initial=initial,
                                     callback=on_iteration, feasible=feasible, pass_bound=True, **options)

    initial = np.zeros((1, k)) if start is None else np.stack([np.zeros(k), layout.from_angles(base)])
    swarm, history, turned, pose_swarm = None, [], False, None
    seeds = seed_params(rig.vertices, rig.faces, rig.up, settings.orient_seeds, objective.overhang_angle) \
        if turning and not _polish_only else None
    for phase, turns in enumerate(phases):
        if turns:
            o = variables(True)[0]
            # the best pose so far first (upright, then at each candidate direction): the swarm keeps it, so
            # this phase never ends worse than the last
            poses = ([swarm.x] if swarm is not None else []) + [*initial]
            starts = [np.concatenate([x, t]) for x in poses for t in np.vstack([np.zeros((1, o)), seeds])]
            if start_rotation is not None:
                starts.insert(0, np.concatenate([layout.from_angles(base), orientation_params(
                    np.asarray(start_rotation, np.float64), rig.up)]))
            initial = np.array(starts, np.float64)
            particles = max(2, settings.particles // TURN_SHARE) if phase else settings.particles
        else:
            particles = settings.particles
        swarm_now = run_phase(turns, initial, particles, phase * settings.iterations)
        history += list(swarm_now.history if not history else swarm_now.history[1:])
        pose_swarm = pose_swarm if turns else swarm_now
        swarm, turned = swarm_now, turns
        if swarm.interrupted:
            break
    stats["polish_evaluations"] = 0
    if polishing and not (swarm is not None and swarm.interrupted):
        turned = turning if swarm is None else turned
        x0 = swarm.x if swarm is not None else np.concatenate([layout.from_angles(base), orientation_params(
            np.eye(rig.dim) if start_rotation is None else np.asarray(start_rotation, np.float64), rig.up)
            if turned else np.zeros(0)])
        polished = run_phase(turned, x0[None], POLISH_SAMPLES * CMA_SHARE, settings.iterations * len(phases),
                             optimizer="cma", iterations=polishing, sigma=POLISH_SIGMA, label="polish")
        stats["polish_evaluations"] = polished.evaluations
        history += list(polished.history if not history else polished.history[1:])
        if swarm is None or polished.value < swarm.value:
            keep = swarm if swarm is not None else polished  # the swarm's other good positions, if any
            swarm = dataclasses.replace(polished, candidates_x=keep.candidates_x,
                                        candidates_values=keep.candidates_values)
        swarm.interrupted = polished.interrupted
    if swarm is None:  # nothing to move and nothing to turn
        swarm = SwarmResult(np.zeros(0), float(objective(base[None])[0]), np.zeros(1), 1)
        history = [swarm.value]
    _, to_angles, to_rotation = variables(turned)
    angles = to_angles(swarm.x[None])[0]
    rotation = to_rotation(swarm.x)
    candidates = _candidates(swarm, to_angles, to_rotation)
    alternatives = {}
    if seeds is not None:  # the simpler answers met on the way, for supportless.choice
        if pose_swarm is not None and turned:
            alternatives["pose"] = _candidates(pose_swarm, *variables(False)[1:])
        # the start pose turned: the search's directions and those ranked at the printer's own threshold
        at_threshold = seed_params(rig.vertices, rig.faces, rig.up, settings.orient_seeds, settings.overhang_angle)
        alternatives["turn"] = _turned(objective, base, np.concatenate([seeds, at_threshold]), rig.up)
    posed = place_on_plate(rig.pose(angles), rig.up)
    value, terms, _ = objective.evaluate(angles, rotation if turned else None)  # the rig's own weights
    terms = {key: float(v) for key, v in terms.items()}
    return PoseResult(angles=angles, vertices=posed, value=float(value), history=np.asarray(history),
                      terms=terms, settings=settings, objective=objective, interrupted=swarm.interrupted,
                      fixed=fixed, term_history=term_history, runtime_seconds=time.perf_counter() - t0,
                      stats=stats, rotation=rotation,
                      print_vertices=print_pose(posed, rotation, rig.up) if turned else posed,
                      candidates=candidates, alternatives=alternatives)


def _turned(objective: Objective, angles: np.ndarray, seeds: np.ndarray, up: np.ndarray) -> dict:
    """A pose upright and turned to each printing direction of ``seeds``, best first (as :func:`_candidates`)."""
    d = len(up)
    rotations = np.concatenate([np.eye(d)[None], rotations_from_params(seeds, up)]) if len(seeds) else np.eye(d)[None]
    A = np.repeat(angles[None], len(rotations), axis=0)
    values = np.asarray(objective(A, rotations), np.float64)
    order = np.argsort(values, kind="stable")
    return {"angles": A[order], "rotations": rotations[order], "values": values[order]}


def _candidates(swarm: SwarmResult, to_angles, to_rotation) -> dict:
    """The best position and the optimiser's other good positions as poses, best first (see PoseResult)."""
    X = np.vstack([swarm.x[None], swarm.candidates_x]) if len(swarm.candidates_x) else swarm.x[None]
    values = np.concatenate([[swarm.value], swarm.candidates_values])
    finite = np.isfinite(values)
    X, values = X[finite], values[finite]
    order = np.argsort(values, kind="stable")
    X, values = X[order], values[order]
    rotations = np.stack([to_rotation(x) for x in X]) if len(X) else np.zeros((0, 3, 3))
    return {"angles": to_angles(X), "rotations": rotations, "values": values}
