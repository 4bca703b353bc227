"""A search's result, measured on the full surface and checked as it will be written.

* :class:`PoseResult`: what :func:`supportless.search.optimizer.optimize` returns;
* :func:`measured_at`: a result moved to another pose and print rotation;
* :func:`on_full_surface`: a result found on a simplified proxy, measured
  and checked for exact self-intersection on the full surface;
* :func:`at_full_resolution`: a result measured on a sculpt's reduced surface
  (:meth:`Rig.measure_rig`), posed on the full one;
* :func:`as_written`: the last gate. The mesh that goes to the file (full
  resolution, in the print frame) must not have more intersecting triangle
  pairs than the rest pose; if it does, the rest pose is written instead
  (turned, if turning alone lowers the objective), and ``stats`` says so.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from ..base.geometry import place_on_plate, print_pose
from ..copyleft.cgal import intersecting_faces
from ..rig.contact import ContactRules, ContactVerdict, contact_verdict
from ..rig.rig import Rig
from .objective import Objective
from .settings import SearchSettings

__all__ = ["FULL_CHECKS", "PoseResult", "as_written", "at_full_resolution", "faces_of", "measured_at",
           "on_full_surface", "written_verdict"]


@dataclass
class PoseResult:
    """Outcome of :func:`optimize`.

    Attributes
    ----------
    angles : (m, 3) float64
        Best pose, radians.
    vertices : (n, d) float64
        Posed full-resolution surface standing as the input stood (the
        display frame), placed on the build plate (lowest point at 0 along up).
    value : float
        Objective of the best pose.
    history : (iterations + 1,) float64
        Best objective per iteration.
    terms : dict of str -> float
        Normalised terms of the best pose.
    settings : SearchSettings
        What the search was asked to do.
    objective : Objective
        What it minimised (for measuring poses afterwards).
    interrupted : bool
        True when the search stopped early (Ctrl-C or the callback).
    fixed : (m,) bool
        The bones that kept their rotation.
    term_history : dict of str -> list of float
        Normalised terms of the best pose after each iteration.
    runtime_seconds : float
        Wall time of the search.
    stats : dict
        Where the time went: ``exact_calls``/``exact_seconds`` (CGAL checks
        of candidates for the swarm's best), ``overlap_rejections``
        (candidates rejected without CGAL, :data:`OVERLAP_CERTAIN`) and
        ``progress_calls``/``progress_seconds`` (terms of the best pose per
        iteration). A search on a proxy adds ``proxy_faces``, ``proxy_value``
        (its best value on the proxy), ``full_rescored`` (candidates measured
        on the full surface) and ``full_exact_calls`` (CGAL checks there).
    rotation : (d, d) float64
        The print rotation R (the identity with ``orient="keep"``).
    print_vertices : (n, d) float64
        The posed surface in the print frame: ``vertices`` turned by R
        (:func:`supportless.base.geometry.print_pose`), on the plate. This is
        the mesh to slice.
    candidates : dict
        Other good poses the last phase of the search reached, best first:
        ``angles`` (q, m, 3) float64, ``rotations`` (q, d, d) float64 and
        ``values`` (q,) float64 (objective values as the search measured them, :meth:`Objective.bounded`;
        not checked for exact self-intersection). See :func:`distinct_candidates`.
    alternatives : dict of str -> dict
        With ``orient="free"``, the simpler answers the search met on its
        way, each in the form of ``candidates``: ``"pose"``, the pose phase's
        best and other good poses, printed as they stand, and ``"turn"``,
        the start pose upright and turned to each candidate printing direction
        (:func:`supportless.search.orientation.seed_params`). Empty otherwise.
    choice : supportless.search.choice.Choice or None
        How the result was chosen among the search's best and the simpler
        answers (:func:`supportless.search.choice.choose`), or None when it was not.
    symmetry : dict or None
        When the tool chose between a mirrored and a free pose
        (``settings.symmetric`` None on a figure with a mirror plane):
        ``mirrored_mm`` and ``free_mm`` (each answer's predicted support
        filament at the reference height), ``share`` (what the free answer had
        to save), ``kept`` (``"mirrored"`` or ``"free"``) and
        ``runtime_seconds`` (both searches). None otherwise.

    The JSON report of a result is built by its caller
    (:func:`supportless.report.report.build_report`): it measures the rest pose and
    the found pose, which the search itself does not need.
    """

    angles: np.ndarray
    vertices: np.ndarray
    value: float
    history: np.ndarray
    terms: dict
    settings: SearchSettings
    objective: Objective
    interrupted: bool = False
    fixed: np.ndarray | None = None
    term_history: dict = field(default_factory=dict)
    runtime_seconds: float = 0.0
    stats: dict = field(default_factory=dict)
    rotation: np.ndarray | None = None
    print_vertices: np.ndarray | None = None
    candidates: dict = field(default_factory=dict)
    alternatives: dict = field(default_factory=dict)
    choice: object = None
    symmetry: dict | None = None

    def __post_init__(self):
        if self.rotation is None:
            self.rotation = np.eye(self.vertices.shape[1])
        if self.print_vertices is None:
            self.print_vertices = self.vertices


def measured_at(rig: Rig, result: PoseResult, angles: np.ndarray, rotation: np.ndarray,
                objective: Objective | None = None) -> PoseResult:
    """``result`` with another pose and print rotation, measured with an objective.

    Parameters
    ----------
    rig : Rig
        The rig the pose is for (full resolution).
    result : PoseResult
        The result to take the rest from (history, settings, stats, candidates).
    angles : (m, 3) float64
        Relative Euler angles, radians.
    rotation : (d, d) float64
        Print rotation.
    objective : Objective, optional
        What measures the pose (default: ``result.objective``).

    Returns
    -------
    result : PoseResult
        With ``angles``, ``rotation``, ``vertices``, ``print_vertices``,
        ``value``, ``terms`` and ``objective`` of the new measurement.
    """
    objective = result.objective if objective is None else objective
    angles = np.asarray(angles, np.float64)
    rotation = np.asarray(rotation, np.float64)
    turned = not np.allclose(rotation, np.eye(rig.dim))
    posed = place_on_plate(rig.pose(angles), rig.up)
    value, terms, _ = objective.evaluate(angles, rotation if turned else None)
    return dataclasses.replace(result, angles=angles, rotation=rotation, vertices=posed, value=float(value),
                               terms={k: float(v) for k, v in terms.items()}, objective=objective,
                               print_vertices=print_pose(posed, rotation, rig.up) if turned else posed)


#: How many of a proxy search's candidates are checked for exact intersections on the full surface at most.
FULL_CHECKS = 10


def on_full_surface(rig: Rig, found: PoseResult, objective: Objective, t0: float) -> PoseResult:
    """A result found on a rig's simplified proxy (:meth:`Rig.coarse_rig`), measured on the full surface.

    The proxy's best and other good poses are re-scored on the full surface; with exact intersection checks the
    best of the first :data:`FULL_CHECKS` whose full surface is clear is taken, the rest pose last.
    """
    stats = dict(found.stats, proxy_faces=len(found.objective.rig.faces), proxy_value=found.value, full_exact_calls=0)
    A = np.concatenate([found.angles[None], found.candidates.get("angles", np.zeros((0,) + found.angles.shape))])
    Q = np.concatenate([found.rotation[None], found.candidates.get("rotations", np.zeros((0,) + found.rotation.shape))])
    first = np.sort(np.unique(np.hstack([A.reshape(len(A), -1), Q.reshape(len(Q), -1)]), axis=0,
                              return_index=True)[1])  # copies of a pose once
    A, Q = A[first], Q[first]
    order = np.argsort(np.asarray(objective(A, Q)), kind="stable")
    A, Q = A[order], Q[order]
    stats["full_rescored"] = len(A)
    angles, rotation = A[0], Q[0]
    if found.settings.exact_intersections and rig.dim == 3:
        for a, q in [*zip(A[:FULL_CHECKS], Q[:FULL_CHECKS]), (np.zeros_like(angles), Q[0])]:
            stats["full_exact_calls"] += 1
            if not objective.forbidden(a):
                angles, rotation = a, q
                break
    measured = measured_at(rig, found, angles, rotation, objective)
    return dataclasses.replace(measured, stats=stats, runtime_seconds=time.perf_counter() - t0)


def at_full_resolution(rig: Rig, result: PoseResult) -> PoseResult:
    """``result`` posed on ``rig``'s surface, when it was measured on another (:meth:`Rig.measure_rig`).

    The pose, the print rotation, the value and the terms stay those measured; the surfaces
    (``vertices``, ``print_vertices``) become ``rig``'s, and ``stats`` gains ``measured_faces``, the
    triangles it was measured on. A result of ``rig``'s own surface is returned as it is.

    Parameters
    ----------
    rig : Rig
        Full resolution.
    result : PoseResult

    Returns
    -------
    result : PoseResult
    """
    if result.vertices.shape == rig.vertices.shape:
        return result
    posed = place_on_plate(rig.pose(result.angles), rig.up)
    turned = not np.allclose(result.rotation, np.eye(rig.dim))
    measured = len(result.objective.rig.faces) if result.objective is not None else None
    return dataclasses.replace(result, vertices=posed, stats=dict(result.stats, measured_faces=measured),
                               print_vertices=print_pose(posed, result.rotation, rig.up) if turned else posed)


#: When the chosen answer crosses itself as written (a sculpt's, weighed on its reduced surface), this many of
#: the other answers weighed are checked at full resolution, the best predicted (or sliced) first, before the
#: rest pose is written instead.
NEXT_ANSWERS = 3


def written_verdict(rig: Rig, result: PoseResult, rest_pairs: int) -> ContactVerdict:
    """Whether ``result``'s mesh as written (``print_vertices`` with ``rig``'s faces) may be written.

    Allowed when it has no more intersecting triangle pairs (CGAL) than the rest pose's ``rest_pairs``, or when
    every crossing is contact between jointed parts within the search's rules (``settings.contact``,
    :meth:`Rig.crossings`, the ray grid's overlap in the print frame). Its ``regions`` name the contacts.
    """
    from ..energies.intersection import self_intersection_volume

    P = result.print_vertices
    pairs = intersecting_faces(P, rig.faces)
    if len(pairs) <= rest_pairs:
        return ContactVerdict(True, len(pairs))
    rules = ContactRules() if getattr(result.settings, "contact", False) else None
    if rules is None:
        return ContactVerdict(False, len(pairs), f"{len(pairs)} pairs of triangles cross")
    X = rig.pose(result.angles)  # the same surface before its rigid placement in the print frame
    R = np.asarray(result.rotation, np.float64)
    offset = P[0] - X[0] @ R.T
    joints = rig.posed_joints(result.angles) @ R.T + offset
    overlap = float(self_intersection_volume(P, rig.faces, rig.up))
    return contact_verdict(rig.body_parts, P, joints, pairs, rules, overlap, rig.rest_volume)


def _next_clear_answer(rig: Rig, result: PoseResult, rest_pairs: int) -> PoseResult | None:
    """The best of ``result.choice``'s other answers whose file crosses itself no more than the rest pose's
    (:data:`NEXT_ANSWERS` at most, by the slicer's support when it chose, else the predicted), or None."""
    choice = result.choice
    if choice is None:
        return None
    sliced = choice.by == "slicer"

    def support(c):
        return c.sliced_mm if sliced else c.predicted_mm

    others = sorted((i for i, c in enumerate(choice.candidates) if i != choice.chosen and support(c) is not None),
                    key=lambda i: support(choice.candidates[i]))
    for i in others[:NEXT_ANSWERS]:
        answer = at_full_resolution(rig, choice.candidates[i].result)
        verdict = written_verdict(rig, answer, rest_pairs)
        written = verdict.pairs
        if verdict.allowed:
            why = (f"{choice.reason}; #{choice.chosen + 1} crossed itself at full resolution as written, "
                   f"so #{i + 1}")
            return dataclasses.replace(answer, choice=dataclasses.replace(choice, chosen=i, reason=why),
                                       symmetry=result.symmetry, interrupted=result.interrupted,
                                       stats=dict(answer.stats, written_pairs=written, rest_pairs=rest_pairs,
                                                  contacts=verdict.regions, chosen_kind=choice.candidates[i].kind,
                                                  passed_over_as_written=choice.chosen + 1))
    return None


def faces_of(rig: Rig, result: PoseResult) -> np.ndarray:
    """(f, 3) int64: the triangles of ``result``'s surfaces: ``rig``'s, or those of the surface it was
    measured on when that is not ``rig``'s (an answer a sculpt's choice weighed, :meth:`Rig.measure_rig`)."""
    if result.print_vertices.shape == rig.vertices.shape or result.objective is None:
        return rig.faces
    return result.objective.rig.faces


def as_written(rig: Rig, result: PoseResult) -> PoseResult:
    """``result`` if its mesh as written intersects itself no more than the rest pose, else the rest pose.

    The exact count (CGAL) is taken on ``result.print_vertices`` with the
    full-resolution faces: after any proxy, and after the print rotation,
    whose rounding can turn a touch into a crossing. With exact intersection
    checks off (``settings.exact_intersections``) or in 2D the result is
    returned as it is.

    Parameters
    ----------
    rig : Rig
        Full resolution.
    result : PoseResult
        At full resolution or measured on the sculpt's reduced surface (posed at full resolution first,
        :func:`at_full_resolution`).

    Returns
    -------
    result : PoseResult
        When it crosses itself more than the rest pose and was chosen among answers, the best of the other
        answers that does not (:data:`NEXT_ANSWERS` tried; ``stats["passed_over_as_written"]`` names the
        answer passed over). ``stats`` gains ``written_pairs`` and ``rest_pairs``; when the rest
        pose replaced the result, ``fell_back_to_rest`` (the pairs the found
        pose had) as well.
    """
    result = at_full_resolution(rig, result)
    if rig.dim != 3 or not result.settings.exact_intersections:
        return result
    rest_pairs = len(intersecting_faces(rig.vertices, rig.faces))
    verdict = written_verdict(rig, result, rest_pairs)
    written = verdict.pairs
    if verdict.allowed:
        return dataclasses.replace(result, stats=dict(result.stats, written_pairs=written, rest_pairs=rest_pairs,
                                                      contacts=verdict.regions))
    if (other := _next_clear_answer(rig, result, rest_pairs)) is not None:
        return other
    rest = np.zeros_like(result.angles)
    turned = measured_at(rig, result, rest, result.rotation)
    upright = measured_at(rig, result, rest, np.eye(rig.dim))
    chosen = turned if turned.value < upright.value else upright
    pairs = len(intersecting_faces(chosen.print_vertices, rig.faces))
    return dataclasses.replace(chosen, stats=dict(result.stats, written_pairs=pairs, rest_pairs=rest_pairs,
                                                  fell_back_to_rest=written, refused_as_written=verdict.reason,
                                                  contacts=[]))
