"""Slice-ranking: PrusaSlicer makes the final choice among the answers the slicer model ranks best.

:func:`supportless.search.choice.choose` weighs the search's best against the
simpler answers it met (the best pose printed as it stands, the best turned
start pose) with the slicer model. :func:`slice_choice` takes the model's
choice and the next answers by predicted support, up to ``count``, leaving
out those predicted to need more than :data:`SLICE_WINDOW` of the rest pose's
support beyond the least; slices them, two at a time on two cores, each once
with supports (the support read from the G-code's support features,
:func:`supportless.slicing.prusaslicer.slice_support` with ``by_feature``), and returns the
one PrusaSlicer lays the least support under. The model's choice is one of
them, and it keeps the choice unless another answer is cheaper by more than
:data:`SLICER_NOISE`.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Callable

import numpy as np

from ..base.progress import step
from ..files.printer import PrinterProfile
from ..files.printframe import REFERENCE_HEIGHT_MM
from ..files.simplify import SLICE_FACES, reduced_alike
from ..rig.rig import Rig
from ..search.choice import KINDS, PER_KIND, Choice, choose, pool_of, print_distance_deg, with_choice
from ..search.optimizer import CANDIDATE_TOLERANCE, DISTINCT_DEGREES, PoseResult, distinct_candidates, measured_at
from ..search.answer import as_written
from ..search.result import faces_of
from .choice import SlicerChoice
from .prusaslicer import DEFAULT_TIMEOUT_S, scale_for_height, slice_support

__all__ = ["SLICER_NOISE", "SLICE_RANK", "SLICE_WINDOW", "distinct_poses", "pick_sliced", "slice_choice",
           "slice_choice_if_found", "to_slice"]

#: Answers sliced at most by default when PrusaSlicer is found (``--slice-rank``): two rounds of two. Chosen on
#: the 27 models of benchmarks/RESULTS.md, "Pose and orientation": with 2 the default printed with more support
#: than the better simple answer on 4 of them, with 3 on 2, with 4 (and the window 0.3) on 1.
SLICE_RANK = 4

#: Answers predicted to need more support than the least by more than this
#: share of the rest pose's predicted support are not sliced (the model is off by
#: 30 % and more on some game characters: Soldier's rest pose 3334 mm predicted, 2302 mm sliced).
SLICE_WINDOW = 0.3

#: Another answer replaces the model's choice only when PrusaSlicer measures
#: it cheaper by more than this share (its run-to-run and skirt noise).
SLICER_NOISE = 0.01


def to_slice(choice: Choice, count: int, window: float = SLICE_WINDOW) -> list[int]:
    """Which answers of ``choice`` to slice: the model's choice, then the kinds in turn.

    The slicer model misranks answers of different kinds more than answers
    of one kind, so after the model's choice come the first answer of each
    kind (the search's best of that kind; for turns, the one with the least
    predicted support), then the second of each, and so on. Answers
    predicted above the least by more than ``window * choice.rest_mm``, and
    answers that print like one already taken (:func:`print_distance_deg`
    below :data:`DISTINCT_DEGREES`), are left out.

    Parameters
    ----------
    choice : Choice
    count : int
        How many at most (at least 1).
    window : float

    Returns
    -------
    indices : list of int
        Positions in ``choice.candidates``, the model's choice first.
    """
    if count < 1:
        raise ValueError("count must be at least 1")
    cands = choice.candidates
    predicted = np.array([c.predicted_mm for c in cands])
    limit = predicted.min() + float(window) * max(choice.rest_mm, 0.0)
    by_support = [int(i) for i in np.argsort(predicted, kind="stable")]
    members = {kind: [i for i in range(len(cands)) if cands[i].kind == kind] for kind in KINDS}
    members["turn"] = [i for i in by_support if i in members["turn"]]
    # the kinds in turn: each one's first, then each one's second, ...
    interleaved = [m[rank] for rank in range(len(cands)) for m in members.values() if rank < len(m)]
    up = np.asarray(choice.up, np.float64)
    picked = [choice.model_chosen]
    for i in [*interleaved, *by_support]:
        if len(picked) >= count:
            break
        a = cands[i].result
        if predicted[i] <= limit and all(print_distance_deg(a.angles, a.rotation, cands[j].result.angles,
                                                            cands[j].result.rotation, up) >= DISTINCT_DEGREES
                                         for j in picked):
            picked.append(i)
    return picked


def slice_choice(rig: Rig, result: PoseResult, count: int = SLICE_RANK, *, height_mm: float = REFERENCE_HEIGHT_MM,
                 profile: PrinterProfile | None = None, config: dict | str | None = None, workers: int = 2,
                 slicer: str | None = None, timeout: float = DEFAULT_TIMEOUT_S, window: float = SLICE_WINDOW,
                 per_kind: int = PER_KIND, slice_fn: Callable[..., object] | None = None,
                 choice: SlicerChoice | None = None) -> PoseResult:
    """Slice the best few answers and return the one with the least support by the slicer (PrusaSlicer's default).

    A sculpt's answers (over :data:`~supportless.files.simplify.SLICE_FACES` triangles) are sliced from copies
    reduced by the same collapses (:func:`~supportless.files.simplify.reduced_alike`); what is written stays whole.

    Parameters
    ----------
    rig : Rig
        3D.
    result : PoseResult
        A search's result; its :attr:`~PoseResult.choice` when it has one
        (``orient="free"``), else its own distinct good poses are the answers.
    count : int
        How many answers to slice at most (:func:`to_slice`).
    height_mm : float
        The rest pose is scaled to this height; every answer by the same factor.
    profile, config, slicer, timeout
        As :func:`supportless.slicing.prusaslicer.slice_check`.
    workers : int
        PrusaSlicer runs at a time (default 2: one per core here).
    window : float
        As :func:`to_slice`.
    per_kind : int
        As :func:`supportless.search.choice.candidate_answers`, when ``result`` has no choice yet.
    slice_fn : callable, optional
        Replaces :func:`supportless.slicing.prusaslicer.slice_support` (same arguments,
        returns an object with ``support_mm``: a list of floats), for tests.
    choice : SlicerChoice, optional
        The slicer and support to measure with (default PrusaSlicer's grid).

    Returns
    -------
    chosen : PoseResult
        With a :class:`~supportless.search.choice.Choice` by ``"slicer"`` (by
        ``"model"`` when only one answer was worth slicing: then nothing is
        sliced), through :func:`supportless.search.answer.as_written`.

    Raises
    ------
    SlicerNotFound, SlicerError
        As :func:`supportless.slicing.prusaslicer.slice_support`.
    """
    slicer_choice, choice = choice, result.choice or choose(rig, result, per_kind, height_mm=height_mm).choice
    picked = to_slice(choice, count, window)
    if len(picked) < 2:
        reason = (f"{choice.reason}; no other answer is predicted within {100 * window:g} % of the rest pose's "
                  "support: nothing to slice")
        return as_written(rig, dataclasses.replace(with_choice(choice.candidates[choice.chosen].result,
                                                               dataclasses.replace(choice, reason=reason)),
                                                   symmetry=result.symmetry))
    t0 = time.perf_counter()
    scale = scale_for_height(rig.vertices, rig.up, height_mm)
    poses = [choice.candidates[i].result for i in picked]
    posed, faces = reduced_alike([p.print_vertices for p in poses], faces_of(rig, poses[0]), SLICE_FACES)  # lighter
    with step("slicing the answers"):
        sliced = (slice_fn or slice_support)([(V, faces) for V in posed], rig.up, scale, timeout,
                                             config=config, workers=workers, slicer=slicer, profile=profile,
                                             names=[f"answer-{i + 1}" for i in picked], by_feature=True,
                                             choice=slicer_choice)
    candidates = [dataclasses.replace(c) for c in choice.candidates]
    for i, mm in zip(picked, sliced.support_mm):
        candidates[i].sliced_mm = float(mm)
    chosen, reason = pick_sliced(picked, [candidates[i].sliced_mm for i in picked])
    new = dataclasses.replace(choice, candidates=candidates, chosen=chosen, by="slicer", reason=reason,
                              sliced_seconds=time.perf_counter() - t0, slicer_height_mm=float(height_mm))
    return as_written(rig, dataclasses.replace(with_choice(candidates[chosen].result, new), symmetry=result.symmetry))


def pick_sliced(picked: list[int], support_mm: list[float], noise: float = SLICER_NOISE) -> tuple[int, str]:
    """The slicer's choice among sliced answers.

    Parameters
    ----------
    picked : list of int
        The answers sliced (:func:`to_slice`), the model's choice first.
    support_mm : list of float
        PrusaSlicer's support filament of each, mm.
    noise : float
        The model's choice stays unless another is cheaper by more than this share.

    Returns
    -------
    chosen : int
        An entry of ``picked``.
    reason : str
    """
    support = np.asarray(support_mm, np.float64)
    best = int(np.argmin(support))
    if support[best] < (1.0 - noise) * support[0]:
        return picked[best], f"least PrusaSlicer support of {len(picked)} answers sliced ({support[best]:.0f} mm)"
    if best == 0:
        return picked[0], f"least PrusaSlicer support of {len(picked)} answers sliced ({support[0]:.0f} mm)"
    return picked[0], (f"PrusaSlicer support {support[0]:.0f} mm, within {100 * noise:g} % of the least sliced "
                       f"({support[best]:.0f} mm): the slicer model's choice kept")


def distinct_poses(rig: Rig, result: PoseResult, count: int, min_degrees: float = DISTINCT_DEGREES,
                   tolerance: float = CANDIDATE_TOLERANCE) -> list[PoseResult]:
    """The poses :func:`slice_rank` slices: the search's result, then distinct good alternatives.

    Parameters
    ----------
    rig : Rig
    result : PoseResult
        The search's result, with its :attr:`~PoseResult.candidates`.
    count : int
        How many poses at most (at least 1).
    min_degrees, tolerance
        As :func:`supportless.search.optimizer.distinct_candidates`.

    Returns
    -------
    poses : list of PoseResult
        ``result`` itself first; the others none self-intersecting.
    """
    if count < 1:
        raise ValueError("count must be at least 1")
    cand = pool_of(result, "pose and turn")

    def no_intersection(angles, _rotation):
        return not rig.self_intersects(angles)

    picked = distinct_candidates(cand, count, min_degrees, tolerance, accept=no_intersection)
    return [result] + [measured_at(rig, result, cand["angles"][i], cand["rotations"][i]) for i in picked[1:]]


def slice_choice_if_found(rig: Rig, result: PoseResult, height_mm: float = REFERENCE_HEIGHT_MM,
                          on_failure: Callable[[str], None] | None = None) -> PoseResult:
    """:func:`slice_choice` with :data:`SLICE_RANK` answers when PrusaSlicer is found, as the default makes it.

    Parameters
    ----------
    rig : Rig
    result : PoseResult
        Returned as it is when it weighed no answers (``choice`` None), was
        interrupted, or PrusaSlicer is not found.
    height_mm : float
        As :func:`slice_choice`.
    on_failure : callable, optional
        ``on_failure(message)`` when PrusaSlicer fails: the model's choice
        stands. Without it the :class:`~supportless.base.errors.SlicerError` is raised.

    Returns
    -------
    chosen : PoseResult
    """
    from ..base.errors import SlicerError
    from .prusaslicer import find_prusa_slicer

    if result.choice is None or result.interrupted or not find_prusa_slicer():
        return result
    try:
        return slice_choice(rig, result, SLICE_RANK, height_mm=height_mm)
    except SlicerError as exc:
        if on_failure is None:
            raise
        on_failure(str(exc))
        return result

