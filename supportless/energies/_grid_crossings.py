"""The crossings of one 3D pose's rays, compiled: what :func:`._grid_numpy.columns3_numpy` finds before its sweep.

:func:`crossings3` lists the same crossings as the numpy path, in the same order (faces in order, each face's
ray centres row by row), with the same exact, tie-broken inside test (:mod:`._grid_common`), so the numpy sweep
(:func:`._grid_numpy.sweep_crossings`) of either gives the same columns to the last bit. The numpy path builds every
(face, ray) candidate as arrays; this loops over them once, in two passes (count, then fill) over the faces.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..base.threads import over

from ._grid_common import ENTERING, LEAVING, RISKY, grid_layout, inside_triangle, triangle_edges

__all__ = ["crossings3"]


@njit(cache=True, inline="always")
def _pixel_range(lo, hi, origin, cell, n):
    """The first and last ray index whose centre may lie in ``[lo, hi]`` (as the numpy path rounds them)."""
    first = max(0, int(np.floor((lo - origin) / cell - 0.5)))
    last = min(n - 1, int(np.ceil((hi - origin) / cell - 0.5)))
    return first, last


@njit(cache=True, nogil=True)
def _count(X, F, cell, nx, ny, u0, w0, counts, lo, hi):
    # counts[f]: the ray centres inside triangle f, for the triangles lo:hi
    for f in range(lo, hi):
        a, b, c = F[f, 0], F[f, 1], F[f, 2]
        ax, ay, bx, by, cx, cy = X[a, 0], X[a, 1], X[b, 0], X[b, 1], X[c, 0], X[c, 1]
        nz = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        counts[f] = 0
        if nz == 0.0:
            continue
        edges = triangle_edges(ax, ay, bx, by, cx, cy, nz > 0.0)
        i0, i1 = _pixel_range(min(ax, bx, cx), max(ax, bx, cx), u0, cell, nx)
        j0, j1 = _pixel_range(min(ay, by, cy), max(ay, by, cy), w0, cell, ny)
        k = 0
        for j in range(j0, j1 + 1):
            py = w0 + (j + 0.5) * cell
            for i in range(i0, i1 + 1):
                if inside_triangle(edges, u0 + (i + 0.5) * cell, py):
                    k += 1
        counts[f] = k


@njit(cache=True, nogil=True)
def _fill(X, F, orient, tau, cell, nx, ny, u0, w0, start, pix, z, code, lo, hi):
    # the crossings of the triangles lo:hi, from start[f] on
    for f in range(lo, hi):
        if start[f + 1] == start[f]:
            continue
        a, b, c = F[f, 0], F[f, 1], F[f, 2]
        ax, ay, az = X[a, 0], X[a, 1], X[a, 2]
        bx, by, bz = X[b, 0], X[b, 1], X[b, 2]
        cx, cy, cz = X[c, 0], X[c, 1], X[c, 2]
        e1x, e1y, e1z = bx - ax, by - ay, bz - az
        e2x, e2y, e2z = cx - ax, cy - ay, cz - az
        nzv = e1x * e2y - e1y * e2x
        nxv = e1y * e2z - e1z * e2y
        nyv = e1z * e2x - e1x * e2z
        kind = ENTERING if orient * nzv < 0.0 else LEAVING
        if kind == ENTERING and orient * nzv / np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv) < -tau:
            kind = RISKY
        gx, gy = -nxv / nzv, -nyv / nzv
        edges = triangle_edges(ax, ay, bx, by, cx, cy, nzv > 0.0)
        i0, i1 = _pixel_range(min(ax, bx, cx), max(ax, bx, cx), u0, cell, nx)
        j0, j1 = _pixel_range(min(ay, by, cy), max(ay, by, cy), w0, cell, ny)
        k = start[f]
        for j in range(j0, j1 + 1):
            py = w0 + (j + 0.5) * cell
            for i in range(i0, i1 + 1):
                px = u0 + (i + 0.5) * cell
                if inside_triangle(edges, px, py):
                    pix[k] = j * nx + i
                    z[k] = az + gx * (px - ax) + gy * (py - ay)
                    code[k] = kind
                    k += 1


def crossings3(X: np.ndarray, F: np.ndarray, orient: float, R: int, tau: float):
    """Every crossing of the rays of one 3D pose with its surface.

    Parameters
    ----------
    X : (n, 3) float64
        Vertices in the frame ``(u, w, z)``, ``z`` along up.
    F : (f, 3) int64
    orient : float
        +1 for an outward-oriented surface, -1 for an inward one.
    R : int
        Ray cells along the longer side of the footprint.
    tau : float
        Cosine of the overhang angle: a face entering the material with ``n . up < -tau`` is risky.

    Returns
    -------
    pix : (k,) int64
        The ray of each crossing (``j * nx + i``).
    z : (k,) float64
        Its height.
    code : (k,) int8
        LEAVING, ENTERING or RISKY.
    layout : tuple
        ``(cell, nx, ny, u0, w0)`` (:func:`._grid_common.grid_layout`).
    """
    X = np.ascontiguousarray(X, np.float64)
    F = np.ascontiguousarray(F, np.int64)
    umin, wmin, _ = X.min(axis=0)
    umax, wmax, _ = X.max(axis=0)
    cell, nx, ny, u0, w0 = grid_layout(umin, umax, wmin, wmax, int(R))
    if nx == 0 or len(F) == 0:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int8), (cell, nx, ny, u0, w0)
    counts = np.empty(len(F), np.int64)
    over(_count, len(F), X, F, cell, nx, ny, u0, w0, counts)
    start = np.concatenate([[0], np.cumsum(counts)])
    pix, z, code = np.empty(start[-1], np.int64), np.empty(start[-1]), np.empty(start[-1], np.int8)
    orient, tau = float(orient), float(tau)
    over(_fill, len(F), X, F, orient, tau, cell, nx, ny, u0, w0, start, pix, z, code)
    return pix, z, code, (cell, nx, ny, u0, w0)
