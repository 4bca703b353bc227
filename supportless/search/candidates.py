"""Good poses that differ: how far apart two poses are, and a greedy choice of distinct candidates.

A search ends with many good poses, most of them near-copies of its best.
:func:`distinct_candidates` keeps the ones that differ by at least
:data:`DISTINCT_DEGREES` (:func:`pose_distance_deg`) and cost at most
:data:`CANDIDATE_TOLERANCE` more than the best: the alternatives a slicer or a
person may prefer (:mod:`supportless.slicing.ranking`, :mod:`supportless.apps.pareto`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..base.kinematics import euler_to_matrix

__all__ = ["CANDIDATE_TOLERANCE", "DISTINCT_DEGREES", "distinct_candidates", "pose_distance_deg"]

#: Two poses closer than this (degrees, the largest rotation of a bone or of
#: the print rotation between them) are near-copies for
#: :func:`distinct_candidates`.
DISTINCT_DEGREES = 10.0

#: :func:`distinct_candidates` keeps alternatives whose objective is at most
#: this share above the best's: they distort the model about as little.
CANDIDATE_TOLERANCE = 0.25


def pose_distance_deg(angles_a: np.ndarray, rotation_a: np.ndarray, angles_b: np.ndarray,
                      rotation_b: np.ndarray) -> float:
    """How far apart two poses are: the largest rotation between them, of one bone or of the print rotation.

    Parameters
    ----------
    angles_a, angles_b : (m, 3) float64
        Relative XYZ Euler angles, radians.
    rotation_a, rotation_b : (d, d) float64
        Print rotations.

    Returns
    -------
    degrees : float
        ``max(max_i angle(R_a,i^T R_b,i), angle(Q_a^T Q_b))``, each the
        geodesic angle of a rotation, in degrees.
    """
    def geodesic(R):
        return np.degrees(np.arccos(np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)))

    Ra = euler_to_matrix(np.asarray(angles_a, np.float64))
    Rb = euler_to_matrix(np.asarray(angles_b, np.float64))
    bones = geodesic(np.swapaxes(Ra, -1, -2) @ Rb)
    Qa, Qb = np.asarray(rotation_a, np.float64), np.asarray(rotation_b, np.float64)
    if Qa.shape[0] == 2:  # planar: embed the 2D turn in 3D
        Qa, Qb = np.pad(Qa, (0, 1)), np.pad(Qb, (0, 1))
        Qa[2, 2] = Qb[2, 2] = 1.0
    turn = geodesic(Qa.T @ Qb)
    return float(max(bones.max(initial=0.0), turn))


def distinct_candidates(candidates: dict, count: int, min_degrees: float = DISTINCT_DEGREES,
                        tolerance: float = CANDIDATE_TOLERANCE,
                        accept: Callable[[np.ndarray, np.ndarray], bool] | None = None) -> list[int]:
    """Up to ``count`` good poses that differ: greedy, best first.

    Parameters
    ----------
    candidates : dict
        :attr:`PoseResult.candidates` (sorted best first).
    count : int
        How many poses at most.
    min_degrees : float
        A pose is kept only if it is at least this far (:func:`pose_distance_deg`)
        from every pose kept before it: near-copies of one local optimum count once.
    tolerance : float
        Only poses with an objective value at most ``(1 + tolerance)`` times
        the best's (the least distorted alternatives; the best is always kept).
    accept : callable, optional
        ``accept(angles (m, 3), rotation (d, d)) -> bool``, a hard rule to
        pass (e.g. no exact self-intersection), asked only about poses that
        would be kept otherwise; the first pose (the search's result) is
        kept without asking.

    Returns
    -------
    indices : list of int
        Indices into the candidates, the first one 0.
    """
    A, Q, values = candidates["angles"], candidates["rotations"], candidates["values"]
    if len(values) == 0 or count < 1:
        return []
    limit = values[0] + abs(values[0]) * float(tolerance)
    kept = [0]
    for i in range(1, len(values)):
        if len(kept) >= count or values[i] > limit:
            break
        if all(pose_distance_deg(A[i], Q[i], A[j], Q[j]) >= min_degrees for j in kept) and \
                (accept is None or accept(A[i], Q[i])):
            kept.append(i)
    return kept
