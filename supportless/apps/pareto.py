"""A front of poses from least support to least distortion, instead of one weighted guess.

The weights of distortion and support are a trade-off with no right value: a
print farm wants the least plastic, an artist the pose barely touched.
:func:`pareto_front` gives the choice. Two methods, measured against each
other on the zoo (benchmarks/RESULTS.md, "A front of poses"):

``nsga2`` (the default)
    The single search at the default weights first (so the front is never
    worse at its least-support end than the single search), then pymoo's
    NSGA-II on the same variables (pose and print turn), seeded with that
    search's poses, minimising support (the search's estimate) and
    distortion, with the hard rules (joint limits, standing,
    self-intersection) as constraints, for :data:`NSGA_SHARE` times the
    search's evaluations.
``sweep``
    The weight of the distortion terms swept over :data:`SPAN` ``** [-1, 1]``
    times its default, one search per weight, each started from its
    neighbour's pose: the default weight's search with the full iterations,
    the others ``SHORT_SHARE / (N - 1)`` of them each.

Either way, the searches' results and other good positions (the particles'
bests, :data:`CANDIDATES_PER_SEARCH` each, and NSGA-II's last population)
make a pool, each pose measured with one yardstick: *support* as the slicer
model predicts PrusaSlicer's filament (mm, 60 mm tall; the prism estimate
for planar figures) and *distortion* as the default objective's distortion
part (``w_arap * arap + w_prior * prior`` at the default weights). Poses
that break a rule, poses another pose beats on both measures, and
near-copies (every joint and the turn within :data:`SAME_DEGREES`) are
dropped; of the rest, the front's two ends and the poses farthest from those
already chosen are returned, least support first, each checked exactly for
self-intersection. The whole front costs about 2.5 single searches.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..base.geometry import place_on_plate, print_pose
from ..base.interrupt import requested
from ..energies.slicer_model import predicted_support_mm
from ..files.printframe import REFERENCE_HEIGHT_MM, PrintFrame, rig_print_frame
from ..rig.rig import Rig
from ..search.layout import PoseLayout, require_mirror
from ..search.answer import optimize
from ..search.optimizer import TURN_SHARE, PoseResult, measured_at, pose_distance_deg
from ..search.orientation import orientation_params, rotations_from_params
from ..search.settings import SearchSettings

__all__ = ["CANDIDATES_PER_SEARCH", "NSGA_SHARE", "NSGA_TIME_SHARE", "SAME_DEGREES", "SHORT_SHARE", "SPAN", "Front",
           "FrontPose", "front_paths", "non_dominated", "pareto_front", "spread", "sweep_factors", "write_front"]

#: The distortion weights are swept from 1/SPAN to SPAN times the default.
SPAN = 4.0

#: The searches beside the default weights' share this many times its iterations (they start from a
#: neighbour's pose): with the default's own, the front costs about 1 + SHORT_SHARE single searches.
SHORT_SHARE = 1.5

#: Population of the NSGA-II front (``method="nsga2"``).
NSGA_POPULATION = 100

#: NSGA-II evaluates this many times the single search's poses (each costs more than a swarm's
#: evaluation, which may skip the intersection term) ...
NSGA_SHARE = 0.6

#: ... and stops early when it has run this many times the single search's time (or 5 s, if longer), so
#: the front costs at most about 2.5 single searches. Only a run that reaches this cap depends on the
#: machine's speed; otherwise the same seed gives the same front.
NSGA_TIME_SHARE = 1.4

#: How many of each search's other good positions join the pool the front is chosen from.
CANDIDATES_PER_SEARCH = 60

#: Two poses of the front closer than this (every joint and the print turn, degrees) are one pose.
SAME_DEGREES = 1.0


@dataclass
class FrontPose:
    """One pose of the front.

    Attributes
    ----------
    result : PoseResult
        The search's result (its settings carry the swept weights).
    factor : float
        The distortion weights' factor over the default.
    support : float
        Predicted PrusaSlicer support filament, mm at 60 mm tall (3D), or the
        normalised prism estimate (planar figures; 1 = the rest pose).
    distortion : float
        ``w_arap * arap + w_prior * prior`` at the default weights.
    """

    result: PoseResult
    factor: float
    support: float
    distortion: float

    def to_dict(self) -> dict:
        """JSON-ready: ``support``, ``distortion``, ``factor``, ``objective`` and the swept weights."""
        s = self.result.settings
        return {"support": float(self.support), "distortion": float(self.distortion), "factor": float(self.factor),
                "w_arap": float(s.w_arap), "w_prior": float(s.w_prior), "objective": float(self.result.value)}


@dataclass
class Front:
    """What :func:`pareto_front` returns.

    Attributes
    ----------
    poses : list of FrontPose
        Least support first.
    default : PoseResult
        The search at the settings' own weights (the sweep's middle): what a
        single search would have returned.
    seconds : float
        Wall time of the whole front.
    """

    poses: list
    default: PoseResult
    seconds: float

    def summary(self) -> list[str]:
        """One line per pose and one for the time."""
        return [f"front pose {k}: support {p.support:.4g}, distortion {p.distortion:.3g}"
                for k, p in enumerate(self.poses, 1)] + [
            f"the front took {self.seconds:.1f} s ({len(self.poses)} poses)"]


def sweep_factors(count: int) -> np.ndarray:
    """The distortion weights' factors, ``SPAN ** linspace(-1, 1, count)`` with the one nearest 1 set to 1.

    So the default weights are always searched (the middle for an odd
    ``count``). Returns (count,) float64.
    """
    if count < 1:
        raise ValueError(f"a front needs at least one pose, not {count}")
    f = SPAN ** np.linspace(-1.0, 1.0, count)
    f[int(np.argmin(np.abs(np.log(f))))] = 1.0
    return f


def non_dominated(support: np.ndarray, distortion: np.ndarray) -> np.ndarray:
    """Which points no other point beats on both measures (ties on both keep the first).

    Parameters
    ----------
    support, distortion : (n,) float64

    Returns
    -------
    keep : (n,) bool
    """
    s, d = np.asarray(support, float), np.asarray(distortion, float)
    keep = np.ones(len(s), bool)
    for i in range(len(s)):
        no_worse = (s <= s[i]) & (d <= d[i])
        better = no_worse & ((s < s[i]) | (d < d[i]))
        same = no_worse & (s == s[i]) & (d == d[i])
        if better.any() or same[:i].any():
            keep[i] = False
    return keep


def spread(points: np.ndarray, count: int) -> list[int]:
    """Up to ``count`` indices spread along a front: both ends, then farthest-point picks.

    Parameters
    ----------
    points : (n, 2) float64
        ``(support, distortion)``, least support first; each axis is scaled to
        0..1 before distances are taken.
    count : int

    Returns
    -------
    chosen : list of int
        Sorted (least support first).
    """
    P = np.asarray(points, float)
    if len(P) <= count:
        return list(range(len(P)))
    span = np.ptp(P, axis=0)
    Q = (P - P.min(axis=0)) / np.where(span > 0, span, 1.0)
    chosen = [0, len(P) - 1][:count]
    while len(chosen) < count:
        d = np.min(np.linalg.norm(Q[:, None] - Q[chosen][None], axis=-1), axis=1)
        chosen.append(int(np.argmax(d)))
    return sorted(chosen)


def _pool(results: list[tuple[float, PoseResult]], per_search: int):
    """Every search's result and its best other positions: (angles (q, m, 3), rotations (q, d, d), factor (q,))."""
    A, R, f = [], [], []
    for factor, r in results:
        A.append(r.angles[None])
        R.append(r.rotation[None])
        f.append(factor)
        c = r.candidates
        if c and len(c["angles"]):
            A.append(c["angles"][:per_search])
            R.append(c["rotations"][:per_search])
            f += [factor] * len(c["angles"][:per_search])
    return np.concatenate(A), np.concatenate(R), np.array(f)


def _measure(rig: Rig, objective, angles: np.ndarray, rotations: np.ndarray, base: SearchSettings):
    """Support and distortion of poses (see the module's description), and whether they keep the rules.

    Returns ``support (q,)``, ``distortion (q,)``, ``ok (q,) bool``.
    """
    turned = not np.allclose(rotations, np.eye(rig.dim))
    terms = objective.terms(angles, rotations if turned else None)
    distortion = base.distortion(terms)
    ok = (terms["violation"] <= 0) & (terms["intersection"] <= 0)
    support = np.asarray(terms["overhang"], float)
    if rig.dim == 3:
        up = np.asarray(rig.up, float)
        height = float(np.ptp(rig.vertices @ up))
        V = np.stack([print_pose(place_on_plate(rig.pose(a), up), r, up) for a, r in zip(angles, rotations)])
        support = predicted_support_mm(V, rig.faces, up, base.overhang_angle, REFERENCE_HEIGHT_MM / height)
    return np.asarray(support, float), np.asarray(distortion, float), ok


def _nsga2_pool(rig: Rig, base: SearchSettings, default: PoseResult, stop=None):
    """NSGA-II (pymoo) on the pose (and turn) variables, seeded with the default search's poses.

    It runs for ``NSGA_SHARE`` times the default search's evaluations (a
    fixed number of generations), or :data:`NSGA_TIME_SHARE` times its time
    if that comes first.

    Objectives: the search's support estimate (the normalised overhang term)
    and the distortion; constraints: the hard rules' violation and the
    self-intersection volume. Returns the final population's
    ``angles (q, m, 3)`` and ``rotations (q, d, d)``.
    """
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.callback import Callback
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize

    mirror = require_mirror(rig) if base.symmetric else None
    layout = PoseLayout(rig, base.fixed_bones(rig), np.zeros((rig.bone_count, 3)),
                        np.radians(base.joint_limits(rig)), mirror)
    k = layout.count
    o = rig.dim - 1 if base.orient == "free" else 0
    objective = base.objective(rig)
    lower = np.concatenate([layout.lower, np.full(o, -np.pi)])
    upper = np.concatenate([layout.upper, np.full(o, np.pi)])

    def decode(X):
        R = rotations_from_params(X[:, k:], rig.up) if o else np.broadcast_to(np.eye(rig.dim), (len(X), rig.dim,
                                                                                                 rig.dim))
        return layout.to_angles(X[:, :k]), np.ascontiguousarray(R)

    class Posing(Problem):
        def __init__(self):
            super().__init__(n_var=k + o, n_obj=2, n_ieq_constr=2, xl=lower, xu=upper)

        def _evaluate(self, X, out, *args, **kwargs):
            A, R = decode(X)
            t = objective.terms(A, R if o else None)
            out["F"] = np.column_stack([t["overhang"], base.distortion(t)])
            out["G"] = np.column_stack([t["violation"], t["intersection"]])

    rng = np.random.default_rng(base.seed)
    c = default.candidates or {"angles": default.angles[None], "rotations": default.rotation[None]}
    seeds = [np.concatenate([layout.from_angles(a), orientation_params(r, rig.up) if o else []])
             for a, r in zip(c["angles"][:NSGA_POPULATION // 2], c["rotations"][:NSGA_POPULATION // 2])]
    X0 = lower + rng.random((NSGA_POPULATION, k + o)) * (upper - lower)
    X0[0] = 0.0  # the rest pose, upright
    X0[1:1 + len(seeds)] = np.clip(seeds, lower, upper)[:NSGA_POPULATION - 1]
    evaluations = base.particles * base.iterations * (1.0 + (1.0 / TURN_SHARE if o else 0.0))
    generations = max(1, int(round(NSGA_SHARE * evaluations / NSGA_POPULATION)))

    deadline = time.perf_counter() + max(NSGA_TIME_SHARE * default.runtime_seconds, 5.0)

    class Stop(Callback):
        def notify(self, algorithm):
            if stop is not None and stop() or requested() or time.perf_counter() > deadline:
                algorithm.termination.force_termination = True

    res = minimize(Posing(), NSGA2(pop_size=NSGA_POPULATION, sampling=X0), ("n_gen", generations), seed=base.seed,
                   verbose=False, callback=Stop())
    return decode(np.atleast_2d(res.pop.get("X")))


def pareto_front(rig: Rig, settings: SearchSettings | None = None, count: int = 5,
                 callback: Callable[[int, int, PoseResult], None] | None = None,
                 per_search: int = CANDIDATES_PER_SEARCH, stop: Callable[[], bool] | None = None,
                 method: str = "nsga2") -> Front:
    """Poses along the front of least support against least distortion.

    Parameters
    ----------
    rig : Rig
    settings : SearchSettings, optional
        The single search's settings (default: the tool's defaults); its
        distortion weights are the sweep's middle.
    count : int
        At most how many poses come back (and, for ``sweep``, how many searches).
    callback : callable, optional
        ``callback(done, count, result)`` after each search.
    per_search : int
        How many of each search's other good positions (its particles' bests)
        join the pool the front is chosen from, besides its result.
    stop : callable, optional
        ``stop() -> bool``, asked after each iteration: True ends the search
        under way and the sweep (a stop button).
    method : {"nsga2", "sweep"}
        ``nsga2`` (the default): the default weights' search, then pymoo's
        NSGA-II seeded with its poses for :data:`NSGA_SHARE` times its
        evaluations (at most :data:`NSGA_TIME_SHARE` times its time); its
        final population joins the pool. ``sweep``: the
        weight sweep above. On the zoo the NSGA-II front has the larger
        hypervolume in less time (benchmarks/RESULTS.md, "A front of poses").

    Returns
    -------
    front : Front
        Its ``poses`` least support first, spread along the front (its two
        ends, then the poses farthest from those chosen); no pose is beaten
        on both measures by another, none self-intersects, and no two are
        near-copies. Stops early (fewer searches) on Ctrl-C.
    """
    t0 = time.perf_counter()
    base = settings or SearchSettings()
    if method not in ("sweep", "nsga2"):
        raise ValueError(f"method must be 'sweep' or 'nsga2', not {method!r}")
    searches = count if method == "sweep" else 1
    factors = sweep_factors(searches)
    middle = int(np.argmin(np.abs(np.log(factors))))
    short = max(1, int(round(base.iterations * SHORT_SHARE / (searches - 1)))) if searches > 1 else base.iterations
    # the middle first, then outwards, each search started from its inner neighbour's pose
    order = [middle] + [i for k in range(1, searches) for i in (middle - k, middle + k) if 0 <= i < searches]
    found: dict[int, PoseResult] = {}
    for done, i in enumerate(order, 1):
        start = found.get(i + 1 if i < middle else i - 1)
        f = float(factors[i])
        run = base.replace(w_arap=base.w_arap * f, w_prior=base.w_prior * f,
                           iterations=base.iterations if i == middle else short)
        found[i] = optimize(rig, run, start=None if start is None else start.angles,
                            start_rotation=None if start is None or base.orient != "free" else start.rotation,
                            callback=None if stop is None else lambda *_: False if stop() else None)
        if callback is not None:
            callback(done, searches, found[i])
        if found[i].interrupted:
            break
    objective = base.objective(rig)
    A, R, F = _pool([(float(factors[i]), found[i]) for i in sorted(found)], per_search)
    if method == "nsga2" and not found[middle].interrupted:
        An, Rn = _nsga2_pool(rig, base, found[middle], stop)
        A, R, F = np.concatenate([A, An]), np.concatenate([R, Rn]), np.concatenate([F, np.ones(len(An))])
    support, distortion, ok = _measure(rig, objective, A, R, base)
    idx = np.flatnonzero(ok)
    idx = idx[non_dominated(support[idx], distortion[idx])]
    idx = idx[np.lexsort((distortion[idx], support[idx]))]
    distinct: list[int] = []
    for k in idx:
        if all(pose_distance_deg(A[k], R[k], A[j], R[j]) >= SAME_DEGREES for j in distinct):
            distinct.append(int(k))
    if rig.dim == 3:  # the exact check, only on the poses that could be chosen, each once
        clean: dict[int, bool] = {}

        def intersects(k):
            if k not in clean:
                clean[k] = not rig.self_intersects(A[k])
            return not clean[k]
    else:
        def intersects(k):
            return False
    pick = []
    while distinct:
        pick = [distinct[j] for j in spread(np.column_stack([support[distinct], distortion[distinct]]), count)]
        bad = [k for k in pick if intersects(k)]
        if not bad:
            break
        distinct = [k for k in distinct if k not in bad]  # drop them and choose again
    front = []
    for k in pick:
        source = found[min(found, key=lambda i: abs(np.log(factors[i] / F[k])))]  # the search it came from
        front.append(FrontPose(measured_at(rig, source, A[k], R[k], objective), float(F[k]), float(support[k]),
                               float(distortion[k])))
    return Front(front, found[middle], time.perf_counter() - t0)


def front_paths(output: str | os.PathLike, count: int) -> tuple[list[Path], list[Path], Path]:
    """Where the front of ``-o OUT.ext`` goes: ``OUT-k.ext`` meshes, ``OUT-k.pose.json`` poses, ``OUT-front.png``."""
    out = Path(output)
    stem = out.with_suffix("")
    meshes = [Path(f"{stem}-{k}{out.suffix}") for k in range(1, count + 1)]
    poses = [Path(f"{stem}-{k}.pose.json") for k in range(1, count + 1)]
    return meshes, poses, Path(f"{stem}-front.png")


def write_front(rig: Rig, front: Front, output: str | os.PathLike,
                frame: PrintFrame | None = None) -> tuple[list[dict], list[tuple[str, str]]]:
    """Write the front's meshes (print orientation), poses and gallery beside ``output``.

    The meshes are print files in ``frame`` (default: the rig's, 60 mm tall):
    +Z up, millimetres, on the plate; a ``.glb`` is glTF's +Y up, metres.

    Returns
    -------
    entries : list of dict
        Per pose (least support first): ``support``, ``distortion``,
        ``factor``, ``objective``, the swept weights, ``mesh`` and ``pose`` paths.
    written : list of (str, str)
        ``(label, path)`` of each file.
    """
    from ..files.meshes import write_mesh
    from ..files.posefile import write_pose
    from ..report.render import render_front

    frame = rig_print_frame(rig) if frame is None else frame
    meshes, poses, gallery = front_paths(output, len(front.poses))
    entries, written = [], []
    for p, mesh, pose in zip(front.poses, meshes, poses):
        r = p.result
        glb = Path(mesh).suffix.lower() in (".glb", ".gltf") and rig.dim == 3
        write_mesh(mesh, frame.to_gltf(r.print_vertices) if glb else frame.place(r.print_vertices), rig.faces)
        write_pose(pose, r.angles, rig.bones, rig.joints, rotation=r.rotation, tree=rig.tree,
                   extra={"objective": r.value, "support": p.support, "distortion": p.distortion,
                          "print_frame": frame.to_dict()})
        entries.append(p.to_dict() | {"mesh": str(mesh), "pose": str(pose)})
        written += [(f"front pose {len(entries)} mesh", str(mesh)), (f"front pose {len(entries)} pose", str(pose))]
    if front.poses:
        label = "predicted PrusaSlicer support, mm (60 mm tall)" if rig.dim == 3 else "support (prism, rest = 1)"
        render_front(gallery, [(p.result.print_vertices, rig.faces) for p in front.poses], rig.up,
                     [p.support for p in front.poses], [p.distortion for p in front.poses], label)
        written.append(("front gallery", str(gallery)))
    return entries, written
