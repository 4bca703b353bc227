"""One search of a rig's pose: :class:`_PoseSearch`, its phases, the exact gate of would-be bests and the polish.

A search finds the Euler angles of a rig's free bones with an optimiser of
:mod:`supportless.search.swarm` (and, with ``orient="free"``, the print
rotation: two more variables in 3D, one in 2D, in a second swarm, see
:data:`TURN_SHARE`) and returns a :class:`PoseResult` with its
:class:`~supportless.search.result.SearchStats`. The answer's stages
(:mod:`supportless.search.answer`, whose :func:`~supportless.search.answer.optimize`
is the tool's search) run it on the rig, or on a dense surface's simplified
proxy and then once more as the polish on the full surface.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Callable

import numpy as np

from ..base.geometry import place_on_plate, print_pose
from ..rig.rig import Rig
from .candidates import CANDIDATE_TOLERANCE, DISTINCT_DEGREES, distinct_candidates, pose_distance_deg
from .layout import PoseLayout, require_mirror
from .objective import Objective
from .orientation import orientation_params, rotations_from_params, seed_params
from .relaxed import relaxed_poses
from .result import PoseResult, SearchStats, measured_at
from .settings import PSO_PRESETS, SearchSettings
from .swarm import CMA_SHARE, OPTIMIZERS, OptimizerResult, evolution_strategy, particle_swarm

__all__ = ["CANDIDATE_TOLERANCE", "CMA_SHARE", "DISTINCT_DEGREES", "OPTIMIZERS", "OptimizerResult", "PoseResult",
           "TURN_SHARE", "distinct_candidates", "evolution_strategy", "measured_at", "particle_swarm",
           "pose_distance_deg"]

#: With ``orient="free"`` the search runs the pose-only swarm, then a swarm of
#: ``particles // TURN_SHARE`` over pose and turn together, started from the
#: best pose upright and at the candidate directions: never worse than the
#: pose-only search by the objective. Half the swarm since the self-intersection
#: is measured only for would-be bests (it was a third, when every personal best
#: was measured in full): over 5 seeds of the 15 zoo models the objective is
#: then 0.999x the one of the search before both changes (the dragon 1.20x, the
#: worst), in 0.56x its time (benchmarks/RESULTS.md, "Speed targets").
TURN_SHARE = 2

#: The polish (``SearchSettings.polish``): CMA-ES with this many samples per generation, its initial step this
#: share of each variable's range (a joint's range of 180 degrees: 0.9 degrees).
POLISH_SAMPLES = 16
POLISH_SIGMA = 0.005

#: A ray-grid self-intersection volume above this share of the model's volume is taken as proof that a pose
#: intersects itself (an embedded closed surface is nowhere two layers deep); the exact gate then skips CGAL.
#: On the robot 767 of 1128 rejected candidates, on the tree 480 of 516, had such a volume; no accepted one had.
OVERLAP_CERTAIN = 1e-9

# --------------------------------------------------------------------------- #
# pose search
# --------------------------------------------------------------------------- #
class _Timed:
    """Wraps a callable and sums its calls and wall time into ``stats``' :class:`CallTime` named ``name``."""

    def __init__(self, fn: Callable, stats: SearchStats, name: str):
        self.fn, self.timing = fn, stats.timing(name)

    def __call__(self, *args):
        t = time.perf_counter()
        try:
            return self.fn(*args)
        finally:
            self.timing.seconds += time.perf_counter() - t
            self.timing.calls += 1


class _PoseSearch:
    """One search of a rig's pose (and print rotation) for :mod:`supportless.search.answer`, in named steps.

    :meth:`run` runs the phases (:meth:`phases`: the pose alone, then pose and
    turn with ``orient="free"``), the polish (:meth:`polish`) and assembles
    the :class:`PoseResult` (:meth:`result`); :meth:`run_phase` is one
    optimiser run over the variables of :meth:`variables`, gated by
    :meth:`feasible` (the exact self-intersection check of would-be bests).
    """

    def __init__(self, rig: Rig, settings: SearchSettings, objective: Objective, start, start_rotation, callback,
                 intersects=None, polish_only: bool = False, rests=None):
        self.rig, self.settings, self.objective, self.callback = rig, settings, objective, callback
        self.start, self.start_rotation = start, start_rotation
        self.base = np.zeros((rig.bone_count, 3)) if start is None else np.asarray(start, np.float64).reshape(-1, 3)
        if self.base.shape != (rig.bone_count, 3):
            raise ValueError(f"start pose has {len(self.base)} bones, the rig {rig.bone_count}")
        mirror = require_mirror(rig) if settings.symmetric else None
        self.layout = PoseLayout(rig, settings.fixed_bones(rig), self.base, np.radians(settings.joint_limits(rig)),
                                 mirror)
        self.k = self.layout.count
        self.stats = SearchStats()
        self.term_history: dict = {"arap": [], "overhang": [], "intersection": []}
        self.turning = settings.orient == "free"
        # orient="free": the pose alone first (the whole swarm, as "keep"), then pose and turn together with part
        # of the swarm (TURN_SHARE), started from the first phase's best pose upright and at the candidate directions
        self.turns = [] if polish_only else ([False] if self.k else []) + ([True] if self.turning else [])
        self.polishing = (settings.polish or 0) if self.k or self.turning else 0
        self.total = settings.iterations * len(self.turns) + self.polishing
        self.overlapping: set = set()  # positions of the last batch whose ray grid saw two layers: they intersect
        self.intersects = intersects if intersects is not None else objective.forbidden
        self.rests = rests if rests is not None else objective.rests  # the plate contact, on the full surface
        self.seeds = seed_params(rig.vertices, rig.faces, rig.up, settings.orient_seeds, objective.overhang_angle) \
            if self.turning and not polish_only else None

    def variables(self, turns: bool):
        """``(o, to_angles, to_rotation)``: the rotation's variable count and the maps from positions."""
        k, rig, layout = self.k, self.rig, self.layout
        o = rig.dim - 1 if turns else 0

        def to_angles(X):
            return layout.to_angles(X[:, :k])

        def to_rotation(x):
            return rotations_from_params(x[None, k:], rig.up)[0] if turns else np.eye(rig.dim)

        return o, to_angles, to_rotation

    def feasible(self):
        """The gate of would-be bests (None when off): False for a position whose pose intersects itself, or
        whose turn rests on less plate than the footprint rule's bound (judged on the full surface)."""
        exact_on = bool(self.settings.exact_intersections and self.rig.dim == 3)
        footprint_on = bool(self.turning and self.objective.footprint_mm2 and self.rig.dim == 3)
        if not (exact_on or footprint_on):
            return None
        k, layout, up = self.k, self.layout, self.rig.up
        exact = _Timed(lambda x: self.intersects(layout.to_angles(x[None, :k])[0]), self.stats, "exact")
        rests = _Timed(lambda x: self.rests(layout.to_angles(x[None, :k])[0], rotations_from_params(x[None, k:], up)[0]),
                       self.stats, "footprint")

        def gate(x):
            if footprint_on and len(x) > k and not rests(x):
                self.stats.footprint_rejections += 1
                return False
            if not exact_on:
                return True
            if x.tobytes() in self.overlapping:  # the ray grid saw two layers: no need to ask CGAL
                self.stats.overlap_rejections += 1
                return False
            return not exact(x)

        return gate

    def run_phase(self, turns, initial, particles, offset, optimizer=None, iterations=None, label=None, **options):
        """One optimiser run from the positions ``initial``, its iterations counted from ``offset``."""
        rig, k, objective, settings = self.rig, self.k, self.objective, self.settings
        optimizer = settings.optimizer if optimizer is None else optimizer
        iterations = settings.iterations if iterations is None else iterations
        o, to_angles, to_rotation = self.variables(turns)

        measured: dict = {}  # the terms of the poses of this iteration measured in full, by position

        def f(X, bound):
            R = rotations_from_params(X[:, k:], rig.up) if turns else None
            # the self-intersection only for poses that could become the swarm's best (the least of the personal
            # bests): a particle's own best is judged by the other terms, the swarm's by all, then exactly
            batch: dict = {}
            values, overlap = objective.bounded_overlap(to_angles(X), bound, R, intersection_bound=np.min(bound),
                                                        measured=batch)
            self.overlapping.clear()
            certain = max(OVERLAP_CERTAIN, objective.overlap_allowed) * objective.volume  # past any allowed contact
            self.overlapping.update(X[i].tobytes() for i in np.flatnonzero(overlap > certain))
            measured.update({X[i].tobytes(): {key: float(batch[key][j]) for key in batch if key != "index"}
                             for j, i in enumerate(batch["index"])})
            return values

        def terms_of(x):  # a new best was measured in full in the batch that found it; else it is measured here
            known = measured.get(x.tobytes())
            return known if known is not None else \
                {key: float(v[0]) for key, v in objective.terms(to_angles(x[None]), to_rotation(x)[None]
                                                                if turns else None).items()}

        best_terms = _Timed(terms_of, self.stats, "progress")
        last = {}

        def on_iteration(it, x, value):
            if last.get("x") is None or not np.array_equal(last["x"], x):  # the best changed
                last["x"], last["terms"] = x.copy(), best_terms(x)
            measured.clear()  # the next iteration's best is this one or one of its poses
            terms = last["terms"]
            for key in self.term_history:
                self.term_history[key].append(terms[key])
            if self.callback is not None:
                return self.callback(offset + it, {"value": value, "terms": terms, "angles": to_angles(x[None])[0],
                                                   "rotation": to_rotation(x), "iterations": self.total,
                                                   "phases": len(self.turns),
                                                   "phase": label or ("pose and turn" if turns else "pose")})
            return None

        lower = np.concatenate([self.layout.lower, np.full(o, -np.pi)])
        upper = np.concatenate([self.layout.upper, np.full(o, np.pi)])
        options = (PSO_PRESETS[settings.preset] if optimizer == "pso" else {}) | options
        return OPTIMIZERS[optimizer](f, lower, upper, particles=particles, iterations=iterations,
                                     rng=np.random.default_rng(settings.seed), initial=initial,
                                     callback=on_iteration, feasible=self._gate, pass_bound=True, **options)

    def turn_starts(self, best, initial) -> np.ndarray:
        """The pose-and-turn phase's first positions: the best pose so far first, upright and at each direction.

        The swarm keeps them, so this phase never ends worse than the last;
        a given start rotation turns the start pose in front of them.
        """
        o = self.variables(True)[0]
        poses = ([best.x] if best is not None else []) + [*initial]
        starts = [np.concatenate([x, t]) for x in poses for t in np.vstack([np.zeros((1, o)), self.seeds])]
        if self.start_rotation is not None:
            starts.insert(0, np.concatenate([self.layout.from_angles(self.base), orientation_params(
                np.asarray(self.start_rotation, np.float64), self.rig.up)]))
        return np.array(starts, np.float64)

    def relaxed_starts(self) -> np.ndarray:
        """(s, k) float64: positions of :func:`~supportless.search.relaxed.relaxed_poses` (limbs let down),
        after the start pose's own turns; none with a start pose or when nothing can be let down."""
        if self.start is not None or not self.k or not self.settings.relaxed:
            return np.zeros((0, self.k))
        rig = self.rig
        free = ~self.settings.fixed_bones(rig)
        poses = relaxed_poses(rig, free, self.settings.joint_limits(rig))
        if not len(poses):
            return np.zeros((0, self.k))
        X = np.stack([self.layout.from_angles(a) for a in poses])
        return np.clip(X, self.layout.lower, self.layout.upper)

    def phases(self):
        """Run the phases: ``(best, history, turned, pose_best)`` (``best`` None when there is none)."""
        k, settings = self.k, self.settings
        initial = np.zeros((1, k)) if self.start is None else np.stack([np.zeros(k), self.layout.from_angles(self.base)])
        initial = np.vstack([initial, self.relaxed_starts()])
        best, history, turned, pose_best = None, [], False, None
        for phase, turns in enumerate(self.turns):
            if turns:
                initial = self.turn_starts(best, initial)
                particles = max(2, settings.particles // TURN_SHARE) if phase else settings.particles
            else:
                particles = settings.particles
            now = self.run_phase(turns, initial, particles, phase * settings.iterations)
            history += list(now.history if not history else now.history[1:])
            pose_best = pose_best if turns else now
            best, turned = now, turns
            if best.interrupted:
                break
        return best, history, turned, pose_best

    def polish(self, best, history, turned):
        """CMA-ES with small steps from the best position (or the start): ``(best, history, turned)``."""
        settings, rig = self.settings, self.rig
        turned = self.turning if best is None else turned
        x0 = best.x if best is not None else np.concatenate([self.layout.from_angles(self.base), orientation_params(
            np.eye(rig.dim) if self.start_rotation is None else np.asarray(self.start_rotation, np.float64), rig.up)
            if turned else np.zeros(0)])
        polished = self.run_phase(turned, x0[None], POLISH_SAMPLES * CMA_SHARE, settings.iterations * len(self.turns),
                                  optimizer="cma", iterations=self.polishing, sigma=POLISH_SIGMA, label="polish")
        self.stats.polish_evaluations = polished.evaluations
        history += list(polished.history if not history else polished.history[1:])
        if best is None or polished.value < best.value:
            keep = best if best is not None else polished  # the swarm's other good positions, if any
            best = dataclasses.replace(polished, candidates_x=keep.candidates_x,
                                       candidates_values=keep.candidates_values)
        best.interrupted = polished.interrupted
        return best, history, turned

    def run(self, t0: float) -> PoseResult:
        """The whole search: phases, polish, result."""
        self._gate = self.feasible()
        best, history, turned, pose_best = self.phases()
        if self.polishing and not (best is not None and best.interrupted):
            best, history, turned = self.polish(best, history, turned)
        if best is None:  # nothing to move and nothing to turn
            best = OptimizerResult(np.zeros(0), float(self.objective(self.base[None])[0]), np.zeros(1), 1)
            history = [best.value]
        return self.result(best, history, turned, pose_best, t0)

    def result(self, best, history, turned, pose_best, t0: float) -> PoseResult:
        """The :class:`PoseResult` of the best position, with the other good ones and the simpler answers."""
        rig, objective, settings = self.rig, self.objective, self.settings
        _, to_angles, to_rotation = self.variables(turned)
        angles = to_angles(best.x[None])[0]
        rotation = to_rotation(best.x)
        candidates = _candidates(best, to_angles, to_rotation)
        alternatives = {}
        if self.seeds is not None:  # the simpler answers met on the way, for supportless.search.choice
            if pose_best is not None and turned:
                alternatives["pose"] = _candidates(pose_best, *self.variables(False)[1:])
            # the start pose turned: the search's directions and those ranked at the printer's own threshold
            at_threshold = seed_params(rig.vertices, rig.faces, rig.up, settings.orient_seeds, settings.overhang_angle)
            alternatives["turn"] = _turned(objective, self.base, np.concatenate([self.seeds, at_threshold]), rig.up)
        posed = place_on_plate(rig.pose(angles), rig.up)
        value, terms, _ = objective.evaluate(angles, rotation if turned else None)  # the rig's own weights
        terms = {key: float(v) for key, v in terms.items()}
        return PoseResult(angles=angles, vertices=posed, value=float(value), history=np.asarray(history),
                          terms=terms, settings=settings, objective=objective, interrupted=best.interrupted,
                          fixed=self.layout.fixed, term_history=self.term_history,
                          runtime_seconds=time.perf_counter() - t0, stats=self.stats, rotation=rotation,
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


def _candidates(swarm: OptimizerResult, to_angles, to_rotation) -> dict:
    """The best position and the optimiser's other good positions as poses, best first (see PoseResult)."""
    X = np.vstack([swarm.x[None], swarm.candidates_x]) if len(swarm.candidates_x) else swarm.x[None]
    values = np.concatenate([[swarm.value], swarm.candidates_values])
    finite = np.isfinite(values)
    X, values = X[finite], values[finite]
    order = np.argsort(values, kind="stable")
    X, values = X[order], values[order]
    rotations = np.stack([to_rotation(x) for x in X]) if len(X) else np.zeros((0, 3, 3))
    return {"angles": to_angles(X), "rotations": rotations, "values": values}
