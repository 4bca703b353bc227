"""The answer a user gets: the search's best against the simpler answers it met, judged by predicted support.

The default search turns the model as well as posing it, and its objective
(the prism estimate) ranks turned poses differently from a slicer: on some
models the best pose printed as it stands, or the rest pose turned, needs
less support in PrusaSlicer than the search's own best. :func:`choose` keeps
a few distinct answers of each kind (:data:`KINDS`), predicts each one's
support filament with the slicer model (:mod:`supportless.energies.slicer_model`)
and returns the one with the least; when another is within
:data:`PREDICTION_TOLERANCE` of that least support (inside the model's error)
and better by the search's objective, that one. With PrusaSlicer installed the
final choice among the best of them is the slicer's
(:func:`supportless.slicing.ranking.slice_choice`): that is what makes the difference.
On 29 models the model's choice alone is about as good as the search's own
best (54.1 % against 54.5 % less support on average), PrusaSlicer's 55.5 %,
never worse than the search's best (benchmarks/RESULTS.md, "Pose and
orientation"): the model is off by 30 % and more on some game characters.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from ..base.geometry import place_on_plate
from ..copyleft.cgal import intersecting_faces
from ..energies.slicer_model import predicted_support_mm
from ..energies.footprint import footprint_area
from ..energies.materials import MATERIALS
from ..files.printframe import REFERENCE_HEIGHT_MM
from ..rig.rig import Rig
from .candidates import CANDIDATE_TOLERANCE, DISTINCT_DEGREES, distinct_candidates, pose_distance_deg
from .objective import POSED_VERTICES
from .result import PoseResult, measured_at, written_verdict
from .sturdiness import pose_strength, pose_strengths

__all__ = ["CHECKS_PER_KIND", "KINDS", "PER_KIND", "PREDICTION_TOLERANCE", "REST_STRENGTH_TOLERANCE", "Candidate", "Choice", "candidate_answers", "choose", "pool_of", "print_distance_deg",
           "choose_by_model", "strong_enough"]

#: The kinds of answer, the search's own first: ``"pose and turn"`` (the
#: search's best and its other good poses), ``"pose"`` (the pose phase's,
#: printed as the model stands) and ``"turn"`` (the start pose, upright or
#: turned to a candidate printing direction).
KINDS = ("pose and turn", "pose", "turn")

#: Distinct good answers kept of each kind (:func:`supportless.search.candidates.distinct_candidates`).
PER_KIND = 2

#: Candidates whose predicted support is within this share of the rest pose's
#: predicted support of the least are a tie for the slicer model (it is within
#: 7 points of PrusaSlicer's reduction, benchmarks/RESULTS.md, "The slicer
#: model"): among them the search's objective decides.
PREDICTION_TOLERANCE = 0.02

#: Exact self-intersection checks (CGAL) of alternatives per kind at most: a model whose every pose
#: crosses itself (its rest pose does) would otherwise have each of the swarm's good poses checked.
CHECKS_PER_KIND = 6

#: Two answers closer than this (degrees, :func:`pose_distance_deg`) are one.
SAME_DEGREES = 0.5

#: An answer as strong as the rest pose within this share counts as strong as it (:func:`strong_enough`): the
#: strength analysis moves by that much when the rest pose itself is turned by one or two degrees (its layers cut
#: the weakest part elsewhere; at 1 degree 0.2-3 % on 13 of 14 zoo figures and characters, 7.5 % on the Fox:
#: benchmarks/RESULTS.md, "Ratios in one process, ..., a weak rest pose"). Without it a figure weak at rest (the
#: glTF Mannequin's ankles, 0.25) had every answer refused for reading 0.25 as well, and got its rest pose back.
REST_STRENGTH_TOLERANCE = 0.05


@dataclass
class Candidate:
    """One answer the choice weighs.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    result : PoseResult
        The answer measured with the search's objective (``value``, ``terms``,
        ``print_vertices``).
    predicted_mm : float
        The slicer model's support filament at ``Choice.height_mm``, mm.
    sliced_mm : float or None
        PrusaSlicer's support filament, mm, once sliced.
    same_as : int or None
        The earlier answer (of another kind) this one prints like (within
        :data:`SAME_DEGREES`, :func:`print_distance_deg`), e.g. the pose
        phase's best when the search kept it upright.
    footprint_mm2 : float or None
        The first layer's contact with the plate at ``Choice.height_mm``, mm²
        (:func:`~supportless.energies.footprint.footprint_area`).
    """

    kind: str
    result: PoseResult
    predicted_mm: float
    sliced_mm: float | None = None
    same_as: int | None = None
    footprint_mm2: float | None = None
    safety_factor: float | None = None
    breaks_at_n: float | None = None

    @property
    def turned(self) -> bool:
        """Whether the answer prints turned from how the model stands."""
        return bool(not np.allclose(self.result.rotation, np.eye(len(self.result.rotation))))


@dataclass
class Choice:
    """How :func:`choose` (and the slicer, :func:`supportless.slicing.ranking.slice_choice`) chose the answer.

    Attributes
    ----------
    candidates : list of Candidate
        In :data:`KINDS` order, best by the objective first within a kind.
    chosen : int
        The answer's position in ``candidates``.
    by : {"model", "slicer"}
        Who made the final choice.
    reason : str
        Why, in a sentence.
    rest_mm : float
        The rest pose's predicted support filament, as it stands, mm.
    height_mm : float
        The printed height of the rest pose the predictions are for, mm.
    sliced_seconds : float
        Wall time spent slicing (0 when the model chose).
    slicer_height_mm : float or None
        The printed height the slices were made at.
    up : (3,) float64
        The rig's up direction (a candidate's ``up`` in the report is the
        model's direction that prints upward).
    model_chosen : int
        The slicer model's choice (``chosen`` until a slicer chooses).
    strength : dict or None
        How strength weighed (:func:`strong_enough`): ``rest_safety_factor``, ``floor``, ``refused`` (the
        answers left out, each a dict of ``kind``, ``predicted_mm``, ``safety_factor``, ``breaks_at_n``) and
        ``changed_choice`` (the slicer model would have chosen one of them); None when strength was not weighed.
    refused : list of Candidate
        The answers left out for strength, with their safety factors.
    seconds : float
        Wall time the slicer model's choice took (:func:`choose`), s.
    """

    candidates: list[Candidate]
    chosen: int
    by: str
    reason: str
    rest_mm: float
    height_mm: float
    sliced_seconds: float = 0.0
    slicer_height_mm: float | None = None
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    model_chosen: int = -1
    strength: dict | None = None
    refused: list = field(default_factory=list)
    seconds: float = 0.0

    def __post_init__(self):
        if self.model_chosen < 0:
            self.model_chosen = self.chosen

    @property
    def chosen_kind(self) -> str:
        """The kind of the answer chosen, one of :data:`KINDS`."""
        return self.candidates[self.chosen].kind

    def to_dict(self) -> dict:
        """The candidates and the choice as JSON values (for the report)."""
        chosen = self.candidates[self.chosen].result
        return {
            "by": self.by, "reason": self.reason, "chosen": self.chosen + 1,
            "predicted_height_mm": self.height_mm, "rest_predicted_mm": round(self.rest_mm, 1),
            "sliced_seconds": round(self.sliced_seconds, 3), "sliced_height_mm": self.slicer_height_mm,
            "candidates": [{
                "number": i + 1, "kind": c.kind, "value": float(c.result.value),
                "terms": {k: float(v) for k, v in c.result.terms.items()},
                "predicted_mm": round(c.predicted_mm, 1),
                "sliced_mm": None if c.sliced_mm is None else round(c.sliced_mm, 1),
                "turned": c.turned,
                "footprint_mm2": None if c.footprint_mm2 is None else round(c.footprint_mm2, 1),
                "safety_factor": _rounded(c.safety_factor, 2), "breaks_at_n": _rounded(c.breaks_at_n, 2),
                "up": np.round(c.result.rotation.T @ self.up, 3).tolist(),
                "same_as": None if c.same_as is None else c.same_as + 1,
                "distance_deg": round(pose_distance_deg(c.result.angles, c.result.rotation, chosen.angles,
                                                        chosen.rotation), 1),
                "chosen": i == self.chosen, "model_choice": i == self.model_chosen,
            } for i, c in enumerate(self.candidates)],
            "strength": self.strength,
        }


def _rounded(x: float | None, digits: int) -> float | None:
    """``x`` rounded for JSON; None stays None, infinity (nothing pulls) becomes None."""
    return None if x is None or not np.isfinite(x) else round(float(x), digits)


def print_distance_deg(angles_a: np.ndarray, rotation_a: np.ndarray, angles_b: np.ndarray, rotation_b: np.ndarray,
                       up: np.ndarray) -> float:
    """How far apart two answers print: :func:`pose_distance_deg` with a turn about the vertical left out.

    Parameters
    ----------
    angles_a, angles_b : (m, 3) float64
    rotation_a, rotation_b : (3, 3) float64
    up : (3,) float64

    Returns
    -------
    degrees : float
        The largest of the bones' rotations between the poses and the angle
        between the two directions that print upward (``R^T up``): two
        answers turned alike but for a spin on the plate are one print.
    """
    bones = pose_distance_deg(angles_a, np.eye(3), angles_b, np.eye(3))
    u = np.asarray(rotation_a, np.float64).T @ up
    v = np.asarray(rotation_b, np.float64).T @ up
    tilt = np.degrees(np.arccos(np.clip(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)), -1.0, 1.0)))
    return float(max(bones, tilt))


def pool_of(result: PoseResult, kind: str) -> dict:
    """The poses of one kind of :data:`KINDS`, best first, as :attr:`PoseResult.candidates`.

    ``"pose and turn"``: ``result`` itself, then its ``candidates``; the other
    kinds: its ``alternatives``.
    """
    if kind == "pose and turn":
        cand = result.candidates or {}
        head = {"angles": result.angles[None], "rotations": result.rotation[None], "values": np.array([result.value])}
        if not len(cand.get("values", ())):
            return head
        if np.allclose(cand["angles"][0], result.angles) and np.allclose(cand["rotations"][0], result.rotation):
            return cand
        return {key: np.concatenate([head[key], cand[key]]) for key in head}
    return result.alternatives.get(kind) or {}


def candidate_answers(rig: Rig, result: PoseResult, per_kind: int = PER_KIND,
                      height_mm: float = REFERENCE_HEIGHT_MM) -> tuple[list[Candidate], float]:
    """The distinct answers of each kind, measured with the objective and the slicer model.

    Parameters
    ----------
    rig : Rig
        3D.
    result : PoseResult
        The search's result, with its ``candidates`` and ``alternatives``.
    per_kind : int
        Distinct answers kept of each kind at most (:func:`distinct_candidates`,
        self-intersecting ones left out, at most :data:`CHECKS_PER_KIND` asked).
        Of the turns of the start pose (never left out for crossing itself: it
        crosses itself as the start pose does) the ``per_kind`` with the least
        predicted support are kept, and the one the search's objective likes best.
    height_mm : float
        The rest pose is printed this tall; the predictions are at this scale.

    Returns
    -------
    candidates : list of Candidate
        :data:`KINDS` in order, the search's result first; a copy of an
        answer of the same kind is left out, of another kind marked ``same_as``;
        turns resting on a tip (:func:`resting_on_area`) and answers too weak (:func:`strong_enough`) left out.
    rest_mm : float
        Predicted support of the rest pose as it stands, mm.
    strength : dict or None
        As :attr:`Choice.strength`, with ``refused`` a list of the Candidates left out.
    """
    picked: list[tuple[str, PoseResult, int | None]] = []  # (kind, answer, the answer it copies)
    for kind in KINDS:
        checks = {"left": CHECKS_PER_KIND}

        def clear(angles, _rotation, checks=checks):
            checks["left"] -= 1  # where every pose crosses itself (so does the rest pose) stop asking soon
            return checks["left"] >= 0 and not result.objective.forbidden(angles)

        label = kind if kind != "pose and turn" or result.settings.orient == "free" else "pose"
        pool = pool_of(result, kind)
        if not len(pool.get("values", ())):
            continue
        # one pose turned: every direction (the least predicted support is kept below); else the best (checked
        # by the search) and other good poses clear of self-intersection
        keep = range(len(pool["values"])) if kind == "turn" else \
            distinct_candidates(pool, per_kind, DISTINCT_DEGREES, CANDIDATE_TOLERANCE, accept=clear)
        for i in keep:
            a, q = pool["angles"][i], pool["rotations"][i]
            same = [j for j, (_, r, _) in enumerate(picked)
                    if print_distance_deg(a, q, r.angles, r.rotation, rig.up) < SAME_DEGREES]
            if any(picked[j][0] == label for j in same):  # a copy within its kind (a spin on the plate) adds nothing
                continue
            picked.append((label, result if (kind == "pose and turn" and i == 0) else measured_at(rig, result, a, q),
                           same[0] if same else None))
    up = np.asarray(rig.up, np.float64)
    scale = float(height_mm) / float(np.ptp(rig.vertices @ up))
    # a few answers at a time on a sculpt (its answers stacked took gigabytes), else all at once
    surfaces = [place_on_plate(rig.vertices, up)] + [r.print_vertices for _, r, _ in picked]
    chunk = max(1, POSED_VERTICES // len(rig.vertices))
    predicted = np.concatenate([np.atleast_1d(predicted_support_mm(np.stack(surfaces[i:i + chunk]), rig.faces, up,
                                                                   float(result.settings.overhang_angle), scale))
                                for i in range(0, len(surfaces), chunk)])
    candidates = [Candidate(kind, r, float(p), same_as=j, footprint_mm2=float(footprint_area(
        r.print_vertices, rig.faces, up, scale)) if rig.dim == 3 else None) for (kind, r, j), p in zip(picked, predicted[1:])]
    candidates = resting_on_area(candidates, result.settings.footprint_mm2)
    candidates, strength = strong_enough(rig, candidates, result.settings, per_turn=per_kind)
    # the turns with the least predicted support, and the one the search's objective likes best (the first)
    turns = [c for c in candidates if c.kind == "turn"]
    kept_turns = {id(c) for c in sorted(turns, key=lambda c: c.predicted_mm)[:per_kind]} | {id(c) for c in turns[:1]}
    dropped = {id(c) for c in turns if id(c) not in kept_turns}
    kept = [c for c in candidates if id(c) not in dropped]
    position = {id(c): i for i, c in enumerate(kept)}
    for c in kept:  # same_as pointed into the list before the extra turns were dropped
        if c.same_as is not None:
            c.same_as = position.get(id(candidates[c.same_as]))
    return kept, float(predicted[0]), strength


def resting_on_area(candidates: list[Candidate], bound_mm2: float) -> list[Candidate]:
    """The candidates that rest on at least ``bound_mm2`` of plate, or print as the model stands.

    A turn onto a tip or an edge is refused, as in the search
    (:meth:`~supportless.search.objective.Objective.footprint_shortfall`): the search judged it on its proxy,
    this on the full surface. When every candidate is such a turn, the one resting on the most is kept.
    ``same_as`` is renumbered.
    """
    if not bound_mm2 or not candidates or candidates[0].footprint_mm2 is None:
        return candidates
    kept = [c for c in candidates if not c.turned or c.footprint_mm2 >= bound_mm2]
    if not kept:
        kept = [max(candidates, key=lambda c: c.footprint_mm2)]
    position = {id(c): i for i, c in enumerate(kept)}
    for c in kept:
        if c.same_as is not None:
            c.same_as = position.get(id(candidates[c.same_as]))
    return kept


def strong_enough(rig: Rig, candidates: list[Candidate], settings, per_turn: int | None = None
                  ) -> tuple[list[Candidate], dict | None]:
    """The candidates at least as strong as the rest pose as it stands, or as ``settings.min_safety``.

    Each candidate weighed gets its ``safety_factor`` and ``breaks_at_n`` (:func:`~supportless.search.sturdiness.
    pose_strength` at ``settings.print_height_mm`` in ``settings.material``). An answer is refused when its
    safety factor is below both the rest pose's (less :data:`REST_STRENGTH_TOLERANCE`) and the floor; when every
    one is, the strongest is kept.
    ``same_as`` is renumbered.

    With ``per_turn``, of the turns of the start pose only those :func:`candidate_answers` keeps are weighed and
    returned: the first strong one in the search's order and the ``per_turn`` strong ones with the least predicted
    support (the others are never analysed: a turn is weighed only until enough strong ones are found).

    Returns
    -------
    kept : list of Candidate
    strength : dict or None
        ``rest_safety_factor``, ``floor``, ``material`` and ``refused`` (list of Candidate); None in 2D or with
        ``min_safety`` 0.
    """
    floor = float(getattr(settings, "min_safety", 0.0) or 0.0)
    if rig.dim != 3 or not floor or not candidates:
        return candidates, None
    material = MATERIALS[settings.material]
    height = float(settings.print_height_mm)
    lazy = [c for c in candidates if c.kind == "turn"] if per_turn is not None else []
    wanted = {id(c) for c in candidates if all(c is not t for t in lazy)}
    # the rest pose and the answers weighed whatever the others weigh (of the turns, the first and the one with the
    # least predicted support): analysed on two cores at once
    surely = wanted | ({id(lazy[0]), id(min(lazy, key=lambda c: c.predicted_mm))} if lazy and per_turn else set())
    pose_strengths(rig, [(rig.rest_angles(), np.eye(3))] + [(c.result.angles, c.result.rotation) for c in candidates
                                                             if id(c) in surely and c.same_as is None
                                                             and c.safety_factor is None], height, material)
    rest = pose_strength(rig, rig.rest_angles(), np.eye(3), height, material)
    bound = min(rest.safety_factor * (1.0 - REST_STRENGTH_TOLERANCE), floor) * (1.0 - 1e-9)

    def weigh(c):  # one analysis per print: a copy of another kind prints alike
        if c.safety_factor is None:
            twin = candidates[c.same_as] if c.same_as is not None and c.same_as < len(candidates) else None
            if twin is not None and twin.safety_factor is not None:
                c.safety_factor, c.breaks_at_n = twin.safety_factor, twin.breaks_at_n
            else:
                s = pose_strength(rig, c.result.angles, c.result.rotation, height, material)
                c.safety_factor = s.safety_factor
                c.breaks_at_n = s.weakest.breaks_at_n if s.weakest is not None else float("inf")
        return c.safety_factor >= bound

    for c in candidates:
        if id(c) in wanted:
            weigh(c)
    first = next((c for c in lazy if weigh(c)), None)
    wanted |= {id(first)} if first is not None else set()
    cheapest = []
    for c in sorted(lazy, key=lambda c: c.predicted_mm):
        if len(cheapest) >= per_turn:
            break
        if weigh(c):
            cheapest.append(id(c))
    wanted |= set(cheapest)
    weighed = [c for c in candidates if c.safety_factor is not None]
    kept = [c for c in weighed if id(c) in wanted and c.safety_factor >= bound]
    if not kept:
        kept = [max(weighed, key=lambda c: c.safety_factor)]
    refused = [c for c in weighed if c.safety_factor < bound and all(c is not k for k in kept)]
    position = {id(c): i for i, c in enumerate(kept)}
    for c in kept:
        if c.same_as is not None:
            c.same_as = position.get(id(candidates[c.same_as]))
    return kept, {"rest_safety_factor": rest.safety_factor, "floor": floor, "material": material.name,
                  "refused": refused}


def choose_by_model(predicted_mm: np.ndarray, values: np.ndarray, rest_mm: float,
                    tolerance: float = PREDICTION_TOLERANCE) -> tuple[int, str]:
    """The slicer model's choice among answers.

    Parameters
    ----------
    predicted_mm : (c,) float64
        Predicted support filament of each answer.
    values : (c,) float64
        Their objective values.
    rest_mm : float
        The rest pose's predicted support (the scale of the tolerance).
    tolerance : float
        Answers within ``tolerance * rest_mm`` of the least predicted support
        tie; the least objective value among them is chosen.

    Returns
    -------
    index : int
    reason : str
    """
    predicted_mm, values = np.asarray(predicted_mm, np.float64), np.asarray(values, np.float64)
    least = int(np.argmin(predicted_mm))
    window = float(tolerance) * max(float(rest_mm), 0.0)
    ties = np.flatnonzero(predicted_mm <= predicted_mm[least] + window)
    best = int(ties[np.argmin(values[ties])])
    if best == least:
        return least, f"least predicted support ({predicted_mm[least]:.0f} mm)"
    return best, (f"predicted support {predicted_mm[best]:.0f} mm, within {100 * tolerance:g} % of the rest pose's "
                  f"of the least ({predicted_mm[least]:.0f} mm), and a lower objective")


def choose(rig: Rig, result: PoseResult, per_kind: int = PER_KIND, tolerance: float = PREDICTION_TOLERANCE,
           height_mm: float = REFERENCE_HEIGHT_MM) -> PoseResult:
    """The answer with the least predicted support among the search's best and the simpler answers.

    Parameters
    ----------
    rig : Rig
        3D, full resolution.
    result : PoseResult
        The search's result with its ``alternatives`` (``orient="free"``).
    per_kind, height_mm
        As :func:`candidate_answers`.
    tolerance : float
        As :func:`choose_by_model`.

    Returns
    -------
    chosen : PoseResult
        One of the candidates, with :attr:`PoseResult.choice` saying how it
        was chosen (and how long that took, ``choice.seconds``); the search's history, stats and time are kept.
    """
    t0 = time.perf_counter()
    candidates, rest_mm, strength = candidate_answers(rig, result, per_kind, height_mm)
    crossing: list[int] = []  # answers that cross themselves as written (checked only when they would be chosen)
    rest_pairs = None
    while True:
        open_ = [i for i in range(len(candidates)) if i not in crossing]
        pick, reason = choose_by_model(np.array([candidates[i].predicted_mm for i in open_]),
                                       np.array([candidates[i].result.value for i in open_]), rest_mm, tolerance)
        index = open_[pick]
        if len(open_) == 1:
            break
        if rest_pairs is None:
            rest_pairs = len(intersecting_faces(rig.vertices, rig.faces)) if rig.dim == 3 else 0
        if not crosses_as_written(rig, candidates[index].result, rest_pairs):
            break
        crossing.append(index)
    if crossing:
        reason += "; passed over for crossing themselves as written: " + ", ".join(f"#{i + 1}" for i in crossing)
    weighed = strength_record(strength, candidates, index, rest_mm, tolerance)
    if weighed and weighed["changed_choice"]:
        reason += f"; {weighed['changed_reason']}"
    seconds = time.perf_counter() - t0
    choice = Choice(candidates, index, "model", reason, rest_mm, float(height_mm), up=np.asarray(rig.up, np.float64),
                    strength=weighed, refused=list(strength["refused"]) if strength else [], seconds=seconds)
    return dataclasses.replace(with_choice(candidates[index].result, choice),
                               runtime_seconds=result.runtime_seconds + seconds)


def strength_record(strength: dict | None, candidates: list[Candidate], index: int, rest_mm: float,
                    tolerance: float = PREDICTION_TOLERANCE) -> dict | None:
    """:attr:`Choice.strength` from :func:`strong_enough`'s record: whether the slicer model would have chosen a
    refused answer over ``candidates[index]``, and why not, in a sentence."""
    if strength is None:
        return None
    refused = strength["refused"]
    record = {"rest_safety_factor": _rounded(strength["rest_safety_factor"], 2), "floor": strength["floor"],
              "material": strength["material"],
              "refused": [{"kind": c.kind, "predicted_mm": round(c.predicted_mm, 1),
                           "safety_factor": _rounded(c.safety_factor, 2), "breaks_at_n": _rounded(c.breaks_at_n, 2)}
                          for c in refused],
              "changed_choice": False, "changed_reason": None}
    if refused:
        everyone = candidates + refused
        pick, _ = choose_by_model(np.array([c.predicted_mm for c in everyone]),
                                  np.array([c.result.value for c in everyone]), rest_mm, tolerance)
        if pick >= len(candidates):
            weak = everyone[pick]
            record["changed_choice"] = True
            record["changed_reason"] = (
                f"strength changed the choice: the answer with the least predicted support "
                f"({weak.predicted_mm:.0f} mm) would break at {weak.breaks_at_n:.1f} N "
                f"(safety factor {weak.safety_factor:.2f}, below the rest pose's "
                f"{strength['rest_safety_factor']:.2f} less {100 * REST_STRENGTH_TOLERANCE:g} % and the floor "
                f"{strength['floor']:g})")
    return record


def crosses_as_written(rig: Rig, result: PoseResult, rest_pairs: int) -> bool:
    """Whether an answer's mesh as written (:attr:`PoseResult.print_vertices`, full resolution) has more
    intersecting triangle pairs than ``rest_pairs``, the rest pose's (CGAL's exact test; False with the
    checks off).

    A pose the search checked on a simplified proxy can cross itself on the full surface; so can a turn's
    rounding turn a touch into a crossing. :func:`supportless.search.answer.as_written` would replace such an
    answer by the rest pose, so the choice passes it over for the next best instead.
    """
    if rig.dim != 3 or not result.settings.exact_intersections:
        return False
    return not written_verdict(rig, result, rest_pairs).allowed


def best_standing(choice: Choice) -> int | None:
    """The position in ``choice.candidates`` of the best answer printed as it stands (a ``"pose"`` answer, or the
    chosen one when the search kept it upright): least sliced support when every such answer was sliced, else
    least predicted; None when there is none."""
    standing = [i for i, c in enumerate(choice.candidates)
                if c.kind == "pose" or (i == choice.chosen and np.allclose(c.result.rotation, np.eye(len(c.result.rotation))))]
    if not standing:
        return None
    sliced = all(choice.candidates[i].sliced_mm is not None for i in standing)
    return min(standing, key=lambda i: choice.candidates[i].sliced_mm if sliced else choice.candidates[i].predicted_mm)


def with_choice(result: PoseResult, choice: Choice) -> PoseResult:
    """``result`` carrying ``choice``."""
    return dataclasses.replace(result, choice=choice)
