"""Global search over bone rotations: a batched particle swarm.

:func:`particle_swarm` is a plain bounded particle swarm optimiser with the
standard velocity update (inertia, cognitive and social terms, positions
clamped to the bounds) as in libigl's ``igl::pso``, except that the whole swarm
is evaluated in one batched call per iteration. :func:`optimize` searches the
Euler angles of a rig's free bones with it and returns a :class:`PoseResult`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .kinematics import descendants
from .objective import Objective
from .rig import Rig

#: Velocity-update coefficients. ``standard`` is the constriction-factor swarm
#: (Clerc & Kennedy); ``libigl`` reproduces igl::pso's constants.
PSO_PRESETS = {
    "standard": {"inertia": 0.7298, "cognitive": 1.49618, "social": 1.49618},
    "libigl": {"inertia": 0.98, "cognitive": 0.01, "social": 0.01},
}


#: Degrees added to the overhang threshold during the search. A search that
#: counts faces as risky only up to the printer's threshold parks them just
#: past it, where a slicer (whose own threshold depends on layer height and
#: extrusion width: PrusaSlicer's automatic one is about 53 degrees at its
#: default 0.3 mm layers) still supports them. With a 10 degree margin the
#: support PrusaSlicer lays down falls 53 % on the bunny instead of 20 %
#: (benchmarks/RESULTS.md).
OVERHANG_MARGIN = 10.0


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
    """

    x: np.ndarray
    value: float
    history: np.ndarray
    evaluations: int
    interrupted: bool = False


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
    interrupted = False
    try:
        for it in range(iterations):
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
            if callback is not None and callback(it + 1, g_x, g_f) is False:
                interrupted = True
                break
    except KeyboardInterrupt:
        interrupted = True
    return SwarmResult(g_x, g_f, np.asarray(history), evaluations, interrupted)


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
def plate_bones(rig: Rig, tolerance: float = 0.01) -> np.ndarray:
    """Bones whose skin touches the build plate in the rest pose.

    Parameters
    ----------
    rig : Rig
    tolerance : float
        Vertices within ``tolerance`` × the model's height of the lowest point
        count as touching.

    Returns
    -------
    mask : (m,) bool
        The bones that dominate (largest weight on) a touching vertex.
    """
    h = rig.vertices @ rig.up
    touching = h <= h.min() + tolerance * (h.max() - h.min())
    mask = np.zeros(rig.bone_count, bool)
    mask[np.unique(np.argmax(rig.weights[touching], axis=1))] = True
    return mask


def resolve_fixed_bones(rig: Rig, fix: list | None = None, free: list | None = None) -> np.ndarray:
    """Which bones keep their rest rotation during the search.

    By default the bones touching the build plate and every bone above them
    in the hierarchy (so the parts on the plate stay where they are).

    Parameters
    ----------
    rig : Rig
    fix, free : list of int or str, optional
        Bones to fix or free in addition to (or against) the default: 1-based
        bone numbers as in the TGF file (ints or digit strings), or
        ``"all"``.

    Returns
    -------
    fixed : (m,) bool
    """
    m = rig.bone_count
    fixed = plate_bones(rig)
    for b in np.flatnonzero(fixed.copy()):
        p = rig.parents[b]
        while p >= 0:
            fixed[p] = True
            p = rig.parents[p]
    for names, value in ((fix, True), (free, False)):
        for name in names or []:
            if str(name).lower() == "all":
                fixed[:] = value
                continue
            try:
                b = int(name) - 1
            except ValueError:
                raise ValueError(f"bone {name!r} is not a bone number 1..{m} or 'all'") from None
            if not 0 <= b < m:
                raise ValueError(f"bone {name} is out of range 1..{m}")
            fixed[b] = value
    return fixed


@dataclass
class PoseResult:
    """Outcome of :func:`optimize`.

    Attributes
    ----------
    angles : (m, 3) float64
        Best pose, radians.
    vertices : (n, d) float64
        Posed full-resolution surface, placed on the build plate (lowest point
        at 0 along up).
    value : float
        Objective of the best pose.
    history : (iterations + 1,) float64
        Best objective per iteration.
    terms : dict
        Normalised terms of the best pose.
    report : dict
        The JSON report (see :func:`supportless.report.build_report`).
    """

    angles: np.ndarray
    vertices: np.ndarray
    value: float
    history: np.ndarray
    terms: dict
    report: dict = field(default_factory=dict)
    interrupted: bool = False
    fixed: np.ndarray | None = None
    term_history: dict = field(default_factory=dict)


def angle_layout(rig: Rig, fixed: np.ndarray) -> np.ndarray:
    """Which Euler angles the search varies.

    Returns
    -------
    free : (m, 3) bool
        In 2D only the angle about the plane normal (index 2) of free bones.
    """
    free = np.zeros((rig.bone_count, 3), bool)
    if rig.dim == 2:
        free[~fixed, 2] = True
    else:
        free[~fixed] = True
    return free


def place_on_plate(vertices: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Translate so the lowest point along ``up`` is at 0, (n, d) float64."""
    return vertices - (vertices @ up).min() * up


def optimize(rig: Rig, *, particles: int = 200, iterations: int = 120, seed: int = 0, max_angle: float = 30.0,
             overhang_angle: float = 45.0, overhang_margin: float = OVERHANG_MARGIN,
             w_arap: float | None = None, w_overhang: float | None = None,
             w_intersect: float | None = None, overhang_model: str = "prism", fix=None, free=None,
             preset: str = "standard", objective: Objective | None = None, exact_intersections: bool = True,
             start: np.ndarray | None = None,
             callback: Callable[[int, dict], bool | None] | None = None) -> PoseResult:
    """Find a pose of ``rig`` that needs less support, with a particle swarm.

    Parameters
    ----------
    rig : Rig
    particles, iterations : int
        Swarm size and number of iterations (the paper: 200 × 120).
    seed : int
        Same seed, same result.
    max_angle : float
        Bound of every free Euler angle, degrees (±).
    overhang_angle : float
        Overhang threshold, degrees from the build plate: what the report
        counts as needing support.
    overhang_margin : float
        The search counts faces up to ``overhang_angle + overhang_margin`` as
        needing support (degrees; see :data:`OVERHANG_MARGIN`).
    w_arap, w_overhang, w_intersect : float, optional
        Weights of the normalised terms (defaults in :mod:`supportless.objective`).
    overhang_model : {"prism", "column"}
    fix, free : list, optional
        Bones to fix / free (1-based numbers), see :func:`resolve_fixed_bones`.
    preset : {"standard", "libigl"}
        Swarm coefficients, see :data:`PSO_PRESETS`.
    objective : Objective, optional
        Use this objective instead of building one from the weights.
    exact_intersections : bool
        Reject any pose whose surface has intersecting triangle pairs by
        CGAL's exact test (3D), checked on every candidate for the swarm's
        best. The ray-cast intersection energy steers the search away from
        overlaps; this makes sure thin ones it cannot see never reach the
        output.
    start : (m, 3) float64, optional
        A pose to start from (radians), e.g. one edited by hand: fixed bones
        keep its angles, and it is one of the initial particles (with the
        free bones' rest rotations as another), so the result is never worse
        than the start pose.
    callback : callable, optional
        ``callback(iteration, info)`` with ``info`` holding ``value``, ``terms``
        (normalised terms of the best pose) and ``angles``; return ``False`` to
        stop.

    Returns
    -------
    result : PoseResult
        Never worse than the rest pose (the rest pose is one of the particles).
    """
    from .report import build_report

    t0 = time.perf_counter()
    if objective is None:
        kw = {k: v for k, v in dict(w_arap=w_arap, w_overhang=w_overhang, w_intersect=w_intersect).items()
              if v is not None}
        objective = Objective(rig, overhang_angle=min(overhang_angle + overhang_margin, 89.0),
                              overhang_model=overhang_model, **kw)
    fixed = resolve_fixed_bones(rig, fix, free)
    free_mask = angle_layout(rig, fixed)
    k = int(free_mask.sum())
    limit = np.radians(max_angle)

    base = np.zeros((rig.bone_count, 3)) if start is None else np.asarray(start, np.float64).reshape(-1, 3)
    if base.shape != (rig.bone_count, 3):
        raise ValueError(f"start pose has {len(base)} bones, the rig {rig.bone_count}")

    def to_angles(X):
        A = np.repeat(base[None], len(X), axis=0)
        A[:, free_mask] = X
        return A

    def f(X, bound):
        return objective.bounded(to_angles(X), bound)

    term_history = {"arap": [], "overhang": [], "intersection": []}

    def on_iteration(it, x, value):
        terms = {key: float(v[0]) for key, v in objective.terms(to_angles(x[None])).items()}
        for key in term_history:
            term_history[key].append(terms[key])
        if callback is not None:
            return callback(it, {"value": value, "terms": terms, "angles": to_angles(x[None])[0],
                                 "iterations": iterations})
        return None

    feasible = None
    if exact_intersections and rig.dim == 3:
        from .report import intersecting_face_pairs

        def feasible(x):
            return intersecting_face_pairs(rig.pose(to_angles(x[None])[0]), rig.faces) == 0

    initial = np.zeros((1, k)) if start is None else np.stack([np.zeros(k), base[free_mask]])
    if k == 0:
        swarm = SwarmResult(np.zeros(0), float(objective(base[None])[0]), np.zeros(1), 1)
    else:
        swarm = particle_swarm(f, -limit * np.ones(k), limit * np.ones(k), particles=particles,
                               iterations=iterations, rng=np.random.default_rng(seed),
                               initial=initial, callback=on_iteration, feasible=feasible,
                               pass_bound=True, **PSO_PRESETS[preset])
    angles = to_angles(swarm.x[None])[0]
    posed = place_on_plate(rig.pose(angles), rig.up)
    terms = {key: float(v) for key, v in objective.terms(angles).items()}
    result = PoseResult(angles=angles, vertices=posed, value=float(swarm.value), history=swarm.history,
                        terms=terms, interrupted=swarm.interrupted, fixed=fixed, term_history=term_history)
    settings = dict(particles=particles, iterations=iterations, seed=seed, max_angle=max_angle, preset=preset,
                    report_overhang_angle=overhang_angle,
                    fixed_bones=[int(b) + 1 for b in np.flatnonzero(fixed)], **objective.settings())
    result.report = build_report(rig, objective, result, settings, runtime=time.perf_counter() - t0,
                                 overhang_angle=overhang_angle)
    return result
