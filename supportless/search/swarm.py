"""The two optimisers of a box-bounded search, each evaluating a whole generation in one batched call.

:func:`particle_swarm` is a plain bounded particle swarm with the standard
velocity update (inertia, cognitive and social terms, positions clamped to the
bounds) as in libigl's ``igl::pso``; :func:`evolution_strategy` is CMA-ES (the
``cma`` package) in the box scaled to the unit cube. Both take the same
arguments, return an :class:`OptimizerResult` and share their generation loop
(:func:`_generations`: the callback, Ctrl-C, the history). Neither knows of
rigs: :mod:`supportless.search.optimizer` searches poses with them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..base.interrupt import requested
from .settings import SearchSettings

__all__ = ["CMA_SHARE", "OPTIMIZERS", "OptimizerResult", "evolution_strategy", "particle_swarm"]


@dataclass
class OptimizerResult:
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
                   particles: int = SearchSettings.particles, iterations: int = SearchSettings.iterations, rng: np.random.Generator | None = None,
                   inertia: float = 0.7298, cognitive: float = 1.49618, social: float = 1.49618,
                   initial: np.ndarray | None = None,
                   callback: Callable[[int, np.ndarray, float], bool | None] | None = None,
                   feasible: Callable[[np.ndarray], bool] | None = None,
                   pass_bound: bool = False) -> OptimizerResult:
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
    result : OptimizerResult
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

    def step():
        nonlocal X, Vel, g_x, g_f, evaluations
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
        return g_x, g_f

    interrupted = _generations(iterations, step, history, callback)
    return OptimizerResult(g_x, g_f, np.asarray(history), evaluations, interrupted, best_X, best_f)


#: CMA-ES samples ``particles // CMA_SHARE`` poses per generation for
#: ``iterations`` generations: a fifth of the swarm's evaluations. Measured on
#: the zoo and the shared models (``benchmarks/optimizers.py``) it takes
#: about 0.8x the swarm's time but ends worse on some figures (a local search
#: from the rest pose), so the swarm stays the default.
CMA_SHARE = 5


def evolution_strategy(f: Callable[[np.ndarray], np.ndarray], lower: np.ndarray, upper: np.ndarray, *,
                       particles: int = SearchSettings.particles, iterations: int = SearchSettings.iterations, rng: np.random.Generator | None = None,
                       initial: np.ndarray | None = None, sigma: float = 0.1,
                       callback: Callable[[int, np.ndarray, float], bool | None] | None = None,
                       feasible: Callable[[np.ndarray], bool] | None = None,
                       pass_bound: bool = False) -> OptimizerResult:
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
    result : OptimizerResult
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

    def step():
        nonlocal es, bound, g_x, g_f, evaluations
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
        return g_x, g_f

    interrupted = _generations(iterations, step, history, callback)
    cand_x, cand_f = np.concatenate(archive_x), np.concatenate(archive_f)
    keep = np.argsort(cand_f, kind="stable")[:particles]
    return OptimizerResult(g_x, g_f, np.asarray(history), evaluations, interrupted, cand_x[keep], cand_f[keep])


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


def _generations(iterations: int, step: Callable[[], tuple[np.ndarray, float]], history: list,
                 callback: Callable[[int, np.ndarray, float], bool | None] | None) -> bool:
    """Run up to ``iterations`` generations of an optimiser; True when it was stopped early.

    ``step()`` runs one generation and returns the best position and value so
    far, which is appended to ``history``. The loop stops after a generation
    when ``callback(generation, best_x, best_value)`` returns ``False`` or
    Ctrl-C was requested (:func:`supportless.base.interrupt.requested`), and
    at a ``KeyboardInterrupt`` inside one.
    """
    if requested():
        return True
    try:
        for it in range(iterations):
            x, value = step()
            history.append(value)
            if callback is not None and callback(it + 1, x, value) is False or requested():
                return True
    except KeyboardInterrupt:
        return True
    return False


#: The optimisers by name (``SearchSettings.optimizer``).
OPTIMIZERS = {"cma": evolution_strategy, "pso": particle_swarm}
