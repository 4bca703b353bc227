"""The answer, stage by stage: what :func:`optimize` runs, from the search to the mesh that may be written.

Each stage is a function from the :class:`~supportless.search.result.PoseResult` the stage before made to
the next; a stage adds its own typed record to it (the arrow), in the order they run::

    optimize             the tool's search: one_answer, or mirrored_answer for a figure with a mirror plane
    mirrored_answer      one_answer with left/right pairs of bones as mirror images        -> symmetry
    one_answer           one search's answer, through the stages below:
      searched           the swarm on the rig (a dense surface: on its simplified proxy)   -> stats
      on_full_surface    a proxy's best poses measured and checked on the full surface     -> full_surface
      polished           CMA-ES with small steps from there, on the full surface           -> full_surface
      chosen             among the search's best and the simpler answers it met, by the
                         slicer model's predicted support                                  -> choice
      as_written         the mesh to write crosses itself no more than the rest pose, else
                         the next clear answer weighed, else the rest pose                 -> written

The stages after these are in later folders, since they need a slicer and the report: the slicer's
choice among the answers (:func:`supportless.slicing.ranking.slice_choice`, which ends in
:func:`as_written` again) and the report (:func:`supportless.report.report.build_report`, with the
command's guard, :mod:`supportless.apps.rest_guard`). The ``optimize`` command runs the whole list in
order; its module, :mod:`supportless.apps.cli_optimize`, lists it at the top.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..base.interrupt import deferred_interrupt
from ..base.progress import step
from ..base.threads import one_blas_thread
from ..copyleft.cgal import intersecting_faces
from ..energies.slicer_model import predicted_support_mm
from ..files.printframe import REFERENCE_HEIGHT_MM
from ..rig.rig import Rig
from .choice import choose
from .layout import find_mirror
from .naturalness import mirror_error_deg
from .objective import Objective
from .optimizer import _PoseSearch
from .result import FullSurface, PoseResult, WrittenCheck, at_full_resolution, measured_at, written_verdict
from .settings import SearchSettings

__all__ = ["FULL_CHECKS", "NEXT_ANSWERS", "PROXY_POLISH_BUDGET", "Request",
           "as_written", "chosen", "mirrored_answer", "on_full_surface", "one_answer", "optimize", "polished",
           "predicted_mm", "searched", "searched_on_proxy"]


def optimize(rig: Rig, settings: SearchSettings | None = None, *, objective: Objective | None = None,
             start: np.ndarray | None = None, start_rotation: np.ndarray | None = None,
             callback: Callable[[int, dict], bool | None] | None = None,
             intersects: Callable[[np.ndarray], bool] | None = None, **changes) -> PoseResult:
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
    intersects : callable, optional
        The exact self-intersection check of the search's gate,
        ``intersects(angles (m, 3) float64) -> bool`` (default:
        :meth:`Rig.self_intersects`), asked only about would-be bests.
    **changes
        Settings to change from ``settings`` (``particles=50``, ``seed=1``, ...).

    Returns
    -------
    result : PoseResult
        Never worse than the rest pose (the rest pose is one of the particles).
        With ``orient="free"`` in 3D and ``settings.choose`` (the default),
        the answer with the least predicted slicer support among the
        search's best, the best pose printed as it stands and the best turned
        start pose (:func:`supportless.search.choice.choose`; its ``choice`` says
        which and why). On Ctrl-C the search stops after the iteration under way and returns
        its best so far with ``interrupted=True``
        (:func:`supportless.base.interrupt.deferred_interrupt`).
    """
    settings = (settings or SearchSettings()).replace(**changes)
    request = Request(objective, start, start_rotation, callback, intersects)
    with one_blas_thread():
        if _as_mirror_images(rig, settings, start):
            return mirrored_answer(rig, settings, request)
        return one_answer(rig, settings.replace(symmetric=bool(settings.symmetric)), request)


def one_answer(rig: Rig, settings: SearchSettings, request: Request) -> PoseResult:
    """One search's answer through the stages (``settings.symmetric`` settled: True or False).

    Parameters
    ----------
    rig : Rig
        Full resolution.
    settings : SearchSettings
    request : Request

    Returns
    -------
    result : PoseResult
        As :func:`optimize`'s, its symmetry aside.
    """
    with deferred_interrupt():
        t0 = time.perf_counter()
        coarse = rig.coarse_rig() if request.objective is None else None
        if coarse is None:
            measure, found = rig, searched(rig, settings, request, t0)
        else:  # a dense surface: search its simplified proxy, then measure on the full one
            measure = rig.measure_rig() or rig  # (a sculpt: on its surface reduced for measuring)
            found = _on_proxy_then_full(measure, coarse, settings, request, t0)
        found = chosen(measure, found)
    with step("exact self-intersection check as written"):
        return as_written(rig, found)


# The stages' constants.

#: The polish on the full surface after a proxy search (``SearchSettings.polish=None``) runs this many
#: triangles x generations: its cost is about the same whatever the density (the 31 086-triangle character: 80
#: generations, 1281 evaluations; the bunny subdivided twice, 111 456 triangles: 22).
PROXY_POLISH_BUDGET = 2_500_000


#: How many of a proxy search's candidates are checked for exact intersections on the full surface at most.
FULL_CHECKS = 10

#: When the chosen answer crosses itself as written (a sculpt's, weighed on its reduced surface), this many of
#: the other answers weighed are checked at full resolution, the best predicted (or sliced) first, before the
#: rest pose is written instead.
NEXT_ANSWERS = 3


@dataclass(frozen=True)
class Request:
    """What a search is asked besides its settings (:func:`optimize`'s arguments of the same names).

    Attributes
    ----------
    objective : Objective or None
        Minimised instead of ``settings.objective(rig)``; then the rig itself is searched, never a proxy.
    start : (m, 3) float64 or None
        The pose to start from, radians.
    start_rotation : (d, d) float64 or None
        The print rotation to start from.
    callback : callable or None
        ``callback(iteration, info)``, as :func:`optimize`'s.
    intersects : callable or None
        The gate's exact check, ``intersects(angles (m, 3) float64) -> bool``.
    """

    objective: Objective | None = None
    start: np.ndarray | None = None
    start_rotation: np.ndarray | None = None
    callback: Callable[[int, dict], bool | None] | None = None
    intersects: Callable[[np.ndarray], bool] | None = None


def _as_mirror_images(rig: Rig, settings: SearchSettings, start: np.ndarray | None) -> bool:
    """Whether the tool poses a figure as mirror images: ``settings.symmetric`` None on a 3D figure
    with a mirror plane, from the rest pose or a start pose that keeps the mirror (one edited by hand that
    breaks it is searched freely: never worse than it)."""
    mirror = find_mirror(rig) if settings.symmetric is None and rig.dim == 3 else None
    return mirror is not None and (start is None or mirror_error_deg(
        rig, np.asarray(start, np.float64).reshape(-1, 3), mirror) < 1e-6)


def mirrored_answer(rig: Rig, settings: SearchSettings, request: Request) -> PoseResult:
    """The answer of a figure with a mirror plane (``settings.symmetric`` None): :func:`one_answer` with left/right
    pairs of bones as mirror images.

    A second, free search from the mirrored answer, kept only when it predicted 10 % less support, was kept on none
    of the 17 mirrored figures of the zoo and the shared glTF characters: it predicted the mirrored answer's support
    on 12, more on 3 and at most 3.7 % less on 2 (benchmarks/RESULTS.md, "One search for a mirrored figure"). It is
    no longer run. ``symmetry`` says so: ``mode`` ("auto"), ``kept`` ("mirrored") and ``mirrored_mm``, the answer's
    support filament as the slicer model predicts it (:func:`predicted_mm`).
    """
    answer = one_answer(rig, settings.replace(symmetric=True), request)
    return dataclasses.replace(answer, symmetry={"mode": "auto", "kept": "mirrored",
                                                 "mirrored_mm": predicted_mm(rig, answer)})


def predicted_mm(rig: Rig, result: PoseResult) -> float:
    """The slicer model's support filament of a result as printed, at the reference height, mm."""
    up = np.asarray(rig.up, np.float64)
    scale = REFERENCE_HEIGHT_MM / float(np.ptp(rig.vertices @ up))
    return float(predicted_support_mm(result.print_vertices, rig.faces, up, float(result.settings.overhang_angle),
                                      scale))


def searched(rig: Rig, settings: SearchSettings, request: Request, t0: float) -> PoseResult:
    """The search on ``rig`` itself (:class:`~supportless.search.optimizer._PoseSearch`): its phases and polish.

    ``t0`` (:func:`time.perf_counter`) is when the answer's stages began: the result's ``runtime_seconds``
    counts from it. The result's ``stats`` say where the time went.
    """
    objective = request.objective or settings.objective(rig)
    return _PoseSearch(rig, settings, objective, request.start, request.start_rotation, request.callback,
                       request.intersects).run(t0)


def _on_proxy_then_full(rig: Rig, coarse: Rig, settings: SearchSettings, request: Request, t0: float) -> PoseResult:
    """A dense surface's three stages: :func:`searched_on_proxy`, :func:`on_full_surface`, :func:`polished`.

    The proxy's iterations and the polish's are reported as one search's; the polish runs for about
    :data:`PROXY_POLISH_BUDGET` triangles x generations (or ``settings.polish``).
    """
    full = settings.objective(rig)
    generations = max(1, round(PROXY_POLISH_BUDGET / len(rig.faces))) if settings.polish is None else settings.polish
    count = _OneSearchCount(request.callback)
    found = searched_on_proxy(coarse, full, settings, request, count.reporter(0, generations), t0)
    with step(f"measuring the best poses on {len(rig.faces)} triangles"):
        found = on_full_surface(rig, found, full, t0)
    if not generations or found.interrupted:
        return found
    return polished(rig, found, full, settings.replace(polish=generations), dataclasses.replace(
        request, callback=count.reporter(count.seen, count.seen)), t0)


class _OneSearchCount:
    """The proxy search's iterations, then the polish's, reported to ``callback`` as one search's."""

    def __init__(self, callback):
        self.callback, self.seen = callback, 0

    def reporter(self, offset: int, more: int):
        """A callback counting from ``offset``, the whole count ``more`` iterations longer (None without one)."""
        def report(it, info):
            self.seen = offset + it
            return self.callback(offset + it, info | {"iterations": info["iterations"] + more})
        return None if self.callback is None else report


def searched_on_proxy(coarse: Rig, full: Objective, settings: SearchSettings, request: Request, callback,
                      t0: float) -> PoseResult:
    """The search on a dense surface's simplified proxy (:meth:`Rig.coarse_rig`), without a polish.

    The proxy shares the full rig's volume mesh, so its ARAP operators and its volume (``full``'s), and its
    turns rest on the plate as the full surface does.
    """
    proxy = settings.objective(coarse, full.arap_data, full.volume)
    with step("searching on the proxy"):
        return _PoseSearch(coarse, settings.replace(polish=0), proxy, request.start, request.start_rotation,
                           callback, request.intersects, rests=full.rests).run(t0)


def on_full_surface(rig: Rig, found: PoseResult, objective: Objective, t0: float) -> PoseResult:
    """A result found on a rig's simplified proxy (:meth:`Rig.coarse_rig`), measured on the full surface.

    The proxy's best and other good poses are re-scored on the full surface; with exact intersection checks the
    best of the first :data:`FULL_CHECKS` whose full surface is clear is taken, the rest pose last. The result's
    ``full_surface`` (:class:`~supportless.search.result.FullSurface`) says how.
    """
    A = np.concatenate([found.angles[None], found.candidates.get("angles", np.zeros((0,) + found.angles.shape))])
    Q = np.concatenate([found.rotation[None], found.candidates.get("rotations", np.zeros((0,) + found.rotation.shape))])
    first = np.sort(np.unique(np.hstack([A.reshape(len(A), -1), Q.reshape(len(Q), -1)]), axis=0,
                              return_index=True)[1])  # copies of a pose once
    A, Q = A[first], Q[first]
    order = np.argsort(np.asarray(objective(A, Q)), kind="stable")
    A, Q = A[order], Q[order]
    angles, rotation, checks = A[0], Q[0], 0
    if found.settings.exact_intersections and rig.dim == 3:
        for a, q in [*zip(A[:FULL_CHECKS], Q[:FULL_CHECKS]), (np.zeros_like(angles), Q[0])]:
            checks += 1
            if not objective.forbidden(a):
                angles, rotation = a, q
                break
    measured = measured_at(rig, found, angles, rotation, objective)
    record = FullSurface(proxy_faces=len(found.objective.rig.faces), proxy_value=found.value, full_rescored=len(A),
                         full_exact_calls=checks)
    return dataclasses.replace(measured, full_surface=record, runtime_seconds=time.perf_counter() - t0)


def polished(rig: Rig, found: PoseResult, full: Objective, settings: SearchSettings, request: Request,
             t0: float) -> PoseResult:
    """``found`` polished on the full surface: CMA-ES with small steps, its pose kept only when better.

    Parameters
    ----------
    rig : Rig
        Full resolution (or a sculpt's reduced surface).
    found : PoseResult
        Measured on the full surface (:func:`on_full_surface`).
    full : Objective
        The full surface's.
    settings : SearchSettings
        The search's, with ``polish`` the polish's generations.
    request : Request
        Its ``callback`` and ``intersects`` (the start is ``found``).
    t0 : float
        When the answer's stages began (:func:`time.perf_counter`).

    Returns
    -------
    result : PoseResult
        Its ``full_surface`` with the polish's value and evaluations, and its exact checks added.
    """
    with step(f"polishing on {len(rig.faces)} triangles"):
        polish = _PoseSearch(rig, settings, full, found.angles, found.rotation,
                             request.callback, request.intersects, polish_only=True).run(time.perf_counter())
    exact_calls = polish.stats.exact.calls if polish.stats.exact is not None else 0
    record = dataclasses.replace(found.full_surface, full_polish_value=polish.value,
                                 full_polish_evaluations=polish.stats.polish_evaluations,
                                 full_exact_calls=found.full_surface.full_exact_calls + exact_calls)
    better = polish.value < found.value
    return dataclasses.replace(measured_at(rig, found, polish.angles, polish.rotation, full) if better else found,
                               full_surface=record, interrupted=polish.interrupted,
                               history=np.concatenate([found.history, polish.history[1:]]),
                               runtime_seconds=time.perf_counter() - t0)


def chosen(rig: Rig, found: PoseResult) -> PoseResult:
    """The answer with the least predicted support among the search's best and the simpler answers it met
    (:func:`supportless.search.choice.choose`: its ``choice`` says which and why); ``found`` as it is when it
    met none (``orient="keep"``), was interrupted, in 2D or with ``settings.choose`` off."""
    if not (found.alternatives and found.settings.choose and rig.dim == 3 and not found.interrupted):
        return found
    with step("weighing the answers"):
        return choose(rig, found)


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
        answers that does not (:data:`NEXT_ANSWERS` tried; ``written.passed_over_as_written`` names the
        answer passed over). Its ``written`` (:class:`~supportless.search.result.WrittenCheck`) holds the
        counts; when the rest pose replaced the result, ``written.fell_back_to_rest`` (the pairs the found
        pose had) and why as well.
    """
    result = at_full_resolution(rig, result)
    if rig.dim != 3 or not result.settings.exact_intersections:
        return result
    rest_pairs = len(intersecting_faces(rig.vertices, rig.faces))
    verdict = written_verdict(rig, result, rest_pairs)
    if verdict.allowed:
        return dataclasses.replace(result, written=WrittenCheck(verdict.pairs, rest_pairs, verdict.regions))
    if (other := _next_clear_answer(rig, result, rest_pairs)) is not None:
        return other
    rest = np.zeros_like(result.angles)
    turned = measured_at(rig, result, rest, result.rotation)
    upright = measured_at(rig, result, rest, np.eye(rig.dim))
    rest_pose = turned if turned.value < upright.value else upright
    pairs = len(intersecting_faces(rest_pose.print_vertices, rig.faces))
    return dataclasses.replace(rest_pose, written=WrittenCheck(pairs, rest_pairs, [], fell_back_to_rest=verdict.pairs,
                                                               refused_as_written=verdict.reason))


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
        if verdict.allowed:
            why = (f"{choice.reason}; #{choice.chosen + 1} crossed itself at full resolution as written, "
                   f"so #{i + 1}")
            return dataclasses.replace(answer, choice=dataclasses.replace(choice, chosen=i, reason=why),
                                       symmetry=result.symmetry, interrupted=result.interrupted,
                                       written=WrittenCheck(verdict.pairs, rest_pairs, verdict.regions,
                                                            passed_over_as_written=choice.chosen + 1))
    return None
