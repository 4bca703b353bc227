"""Nearest triangle of a set, by brute force: exact and fast for a few points against a surface.

:func:`nearest_other_face` finds, for each query point, the nearest triangle that does not belong to the point's
own group (a body part's own triangles are always at distance 0 from its own vertices). It is the contact depth's
question (:mod:`supportless.rig.contact`): a few dozen vertices found inside another part, against a surface of some
ten thousand triangles, where building a tree per part costs more than the whole scan.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .threads import over

__all__ = ["nearest_other_face", "point_triangle_distance2"]


@njit(cache=True, inline="always")
def _dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


@njit(cache=True)
def point_triangle_distance2(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """Squared distance from the point p to the triangle abc (the closest point by the triangle's Voronoi regions:
    a vertex, an edge or the inside), float64."""
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = _dot(abx, aby, abz, apx, apy, apz)
    d2 = _dot(acx, acy, acz, apx, apy, apz)
    if d1 <= 0.0 and d2 <= 0.0:  # vertex a
        return _dot(apx, apy, apz, apx, apy, apz)
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = _dot(abx, aby, abz, bpx, bpy, bpz)
    d4 = _dot(acx, acy, acz, bpx, bpy, bpz)
    if d3 >= 0.0 and d4 <= d3:  # vertex b
        return _dot(bpx, bpy, bpz, bpx, bpy, bpz)
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:  # edge ab
        t = d1 / (d1 - d3)
        qx, qy, qz = apx - t * abx, apy - t * aby, apz - t * abz
        return _dot(qx, qy, qz, qx, qy, qz)
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = _dot(abx, aby, abz, cpx, cpy, cpz)
    d6 = _dot(acx, acy, acz, cpx, cpy, cpz)
    if d6 >= 0.0 and d5 <= d6:  # vertex c
        return _dot(cpx, cpy, cpz, cpx, cpy, cpz)
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:  # edge ac
        t = d2 / (d2 - d6)
        qx, qy, qz = apx - t * acx, apy - t * acy, apz - t * acz
        return _dot(qx, qy, qz, qx, qy, qz)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:  # edge bc
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        qx, qy, qz = bpx - t * (cx - bx), bpy - t * (cy - by), bpz - t * (cz - bz)
        return _dot(qx, qy, qz, qx, qy, qz)
    denom = 1.0 / (va + vb + vc)  # inside: along the normal
    v = vb * denom
    w = vc * denom
    qx, qy, qz = apx - abx * v - acx * w, apy - aby * v - acy * w, apz - abz * v - acz * w
    return _dot(qx, qy, qz, qx, qy, qz)


def _nearest(P, group, V, F, face_group):
    """(k,) float64 and (k,) int64: see :func:`nearest_other_face`."""
    d2 = np.full(len(P), np.inf)
    nearest = np.full(len(P), -1, np.int64)
    over(_nearest_of, len(P), P, group, V, F, face_group, d2, nearest)
    return d2, nearest


@njit(cache=True, nogil=True)
def _nearest_of(P, group, V, F, face_group, d2, nearest, lo, hi):
    """Fill ``d2`` and ``nearest`` at the points ``lo:hi`` (see :func:`nearest_other_face`)."""
    for i in range(lo, hi):
        px, py, pz = P[i, 0], P[i, 1], P[i, 2]
        best, at = np.inf, -1
        for f in range(F.shape[0]):
            if face_group[f] == group[i]:
                continue
            a, b, c = F[f, 0], F[f, 1], F[f, 2]
            d = point_triangle_distance2(px, py, pz, V[a, 0], V[a, 1], V[a, 2], V[b, 0], V[b, 1], V[b, 2],
                                         V[c, 0], V[c, 1], V[c, 2])
            if d < best:
                best, at = d, f
        d2[i] = best
        nearest[i] = at


def nearest_other_face(points: np.ndarray, group: np.ndarray, vertices: np.ndarray, faces: np.ndarray,
                       face_group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each point, the nearest triangle of another group, and its squared distance.

    Parameters
    ----------
    points : (k, 3) float64
    group : (k,) int64
        Each point's group: its own group's triangles are left out.
    vertices : (n, 3) float64
    faces : (f, 3) int64
    face_group : (f,) int64
        Each triangle's group.

    Returns
    -------
    d2 : (k,) float64
        Squared distances; inf where every triangle is of the point's own group.
    nearest : (k,) int64
        The nearest triangle of another group (the first in ``faces`` at a tie), -1 where there is none.
    """
    return _nearest(np.ascontiguousarray(points, np.float64), np.ascontiguousarray(group, np.int64),
                    np.ascontiguousarray(vertices, np.float64), np.ascontiguousarray(faces, np.int64),
                    np.ascontiguousarray(face_group, np.int64))
