"""Slice-ranking: let PrusaSlicer pick among the search's best distinct poses.

The search ranks poses by its estimate of the support. Near its optimum the
estimate and the slicer can disagree about which of several good poses needs
the least support. :func:`slice_rank` takes up to ``count`` distinct good poses
(:func:`supportless.search.distinct_candidates`: the search's result first,
then other local optima at least :data:`~supportless.search.DISTINCT_DEGREES`
apart, none self-intersecting), slices each with and without supports
(:func:`supportless.slicer.slice_support`, two at a time on two cores) and
returns the one with the least support filament. The search's result is
always one of them, so the choice is never worse by the slicer's measure.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .copyleft.cgal import self_intersects
from .profile import PrinterProfile
from .rig import Rig
from .search import (CANDIDATE_TOLERANCE, DISTINCT_DEGREES, PoseResult, distinct_candidates, measured_at,
                     pose_distance_deg)
from .slicer import DEFAULT_TIMEOUT_S, scale_for_height, slice_support

__all__ = ["RankedResult", "candidate_result", "distinct_poses", "slice_rank"]


@dataclass
class RankedResult:
    """Outcome of :func:`slice_rank`.

    Attributes
    ----------
    result : PoseResult
        The chosen pose (the search's own result when it needs the least support).
    chosen : int
        Its position in ``entries`` (0 = the search's result).
    entries : list of dict
        One per sliced pose, in the search's order: ``rank`` (1 = the
        search's best), ``value`` (objective), ``terms`` (normalised terms),
        ``support_mm`` (PrusaSlicer's support filament), ``chosen`` (bool),
        ``distance_deg`` (the largest rotation from the search's result).
    sliced_seconds : float
        Wall time of the slicing.
    """

    result: PoseResult
    chosen: int
    entries: list[dict]
    sliced_seconds: float = 0.0

    def to_dict(self) -> dict:
        """The entries and the choice as JSON values (for the report)."""
        return {"chosen_rank": self.chosen + 1, "sliced_seconds": round(self.sliced_seconds, 3),
                "candidates": [dict(e) for e in self.entries]}


def candidate_result(rig: Rig, result: PoseResult, angles: np.ndarray, rotation: np.ndarray) -> PoseResult:
    """``result`` with another pose and print rotation, measured with its objective.

    Parameters
    ----------
    rig : Rig
    result : PoseResult
        The search's result (its objective measures the new pose).
    angles : (m, 3) float64
        Relative Euler angles, radians.
    rotation : (d, d) float64
        Print rotation.

    Returns
    -------
    result : PoseResult
        With ``angles``, ``rotation``, ``vertices``, ``print_vertices``,
        ``value`` and ``terms`` of the new pose; the rest (history, settings,
        stats) unchanged.
    """
    return measured_at(rig, result, angles, rotation)


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
        As :func:`supportless.search.distinct_candidates`.

    Returns
    -------
    poses : list of PoseResult
        ``result`` itself first; the others none self-intersecting.
    """
    if count < 1:
        raise ValueError("count must be at least 1")
    cand = result.candidates or {}
    if not len(cand.get("values", ())):  # a result without alternatives: itself only
        cand = {"angles": result.angles[None], "rotations": result.rotation[None], "values": np.array([result.value])}
    elif not (np.allclose(cand["angles"][0], result.angles) and np.allclose(cand["rotations"][0], result.rotation)):
        cand = {"angles": np.concatenate([result.angles[None], cand["angles"]]),
                "rotations": np.concatenate([result.rotation[None], cand["rotations"]]),
                "values": np.concatenate([[result.value], cand["values"]])}

    def no_intersection(angles, _rotation):
        return rig.dim != 3 or not self_intersects(rig.pose(angles), rig.faces)

    picked = distinct_candidates(cand, count, min_degrees, tolerance, accept=no_intersection)
    return [result] + [candidate_result(rig, result, cand["angles"][i], cand["rotations"][i]) for i in picked[1:]]


def slice_rank(rig: Rig, result: PoseResult, count: int, *, height_mm: float = 60.0,
               profile: PrinterProfile | None = None, config: dict | str | None = None, workers: int = 2,
               slicer: str | None = None, timeout: float = DEFAULT_TIMEOUT_S,
               min_degrees: float = DISTINCT_DEGREES, tolerance: float = CANDIDATE_TOLERANCE,
               slice_fn: Callable[..., object] | None = None) -> RankedResult:
    """Slice up to ``count`` distinct good poses and keep the one with the least support.

    Parameters
    ----------
    rig : Rig
    result : PoseResult
        The search's result, with its :attr:`~PoseResult.candidates`.
    count : int
        How many poses to slice at most (the search's result included).
    height_mm : float
        The rest pose is scaled to this height; every pose by the same factor.
    profile, config, slicer, timeout
        As :func:`supportless.slicer.slice_check`.
    workers : int
        PrusaSlicer runs at a time (default 2: one per core here).
    min_degrees, tolerance
        As :func:`supportless.search.distinct_candidates`.
    slice_fn : callable, optional
        Replaces :func:`supportless.slicer.slice_support` (same arguments,
        returns an object with ``support_mm``: a list of floats), for tests.

    Returns
    -------
    ranked : RankedResult

    Raises
    ------
    SlicerNotFound, SlicerError
        As :func:`supportless.slicer.slice_support`.
    """
    poses = distinct_poses(rig, result, count, min_degrees, tolerance)
    t0 = time.perf_counter()
    scale = scale_for_height(rig.vertices, rig.up, height_mm)
    sliced = (slice_fn or slice_support)([(p.print_vertices, rig.faces) for p in poses], rig.up, scale, timeout,
                                         config=config, workers=workers, slicer=slicer, profile=profile,
                                         names=[f"candidate-{i + 1}" for i in range(len(poses))])
    seconds = time.perf_counter() - t0
    support = [float(x) for x in sliced.support_mm]
    chosen = int(np.argmin(support))  # the first of equals: the search's own order
    entries = [{"rank": i + 1, "value": float(p.value), "terms": dict(p.terms), "support_mm": support[i],
                "distance_deg": pose_distance_deg(p.angles, p.rotation, result.angles, result.rotation),
                "chosen": i == chosen} for i, p in enumerate(poses)]
    return RankedResult(result=poses[chosen], chosen=chosen, entries=entries, sliced_seconds=seconds)
