"""Reference numba kernels of the ray grid (:mod:`supportless.energies.raygrid`).

One pose at a time, the plain way: every triangle (3D) or boundary edge (2D)
is rasterised row by row over the ray cells of its bounding box, each ray
that crosses it records a crossing (pixel, height, code) in growable
buffers, and :func:`._grid_common.sweep_rays` sorts and sweeps them.  The 2D
grid always runs here; the 3D one serves as the fallback of the fast kernel
(:mod:`._grid_fast`) for poses whose crossings overflow its buffers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..base.threads import over

from ._grid_common import (
    face_normal,
    frame_bbox3,
    grid_layout,
    inside,
    inside_triangle,
    risk_code,
    sweep_rays,
    triangle,
    triangle_edges,
)

__all__ = ["grid_batch"]


@njit(cache=True)
def _grow(pix, zz, cc):
    """Twice as long copies of the crossing buffers ``pix`` (k,) int64, ``zz`` (k,) float64, ``cc`` (k,) int8."""
    n = pix.shape[0] * 2
    p2 = np.empty(n, np.int64)
    z2 = np.empty(n, np.float64)
    c2 = np.empty(n, np.int8)
    p2[: pix.shape[0]] = pix
    z2[: pix.shape[0]] = zz
    c2[: pix.shape[0]] = cc
    return p2, z2, c2


@njit(cache=True)
def _sweep(pix, zz, cc, cnt, m, npix, zplate):
    """:func:`._grid_common.sweep_rays` over every ray with a crossing, with its work space.

    ``pix`` (>= m,) int64, ``zz`` (>= m,) float64 and ``cc`` (>= m,) int8:
    the ``m`` crossings; ``cnt`` (npix,) int64: crossings per ray.
    """
    start = np.empty(npix, np.int64)
    zs = np.empty(m, np.float64)
    cs = np.empty(m, np.int8)
    return sweep_rays(pix, zz, cc, m, cnt, npix, 1, zplate, start, zs, cs)


@njit(cache=True, inline="always")
def _clip_row(e, py, xl, xr, empty):
    """Narrow the span ``[xl, xr]`` of the pixel row at height ``py`` to the inner side of one edge.

    ``e`` is a canonical edge (:func:`._grid_common.edge`, 6 floats).

    A horizontal edge (``dy == 0``) does not depend on x: one exact test
    decides the whole row (``empty``). Returns ``(xl, xr, empty)``.
    """
    ox, oy, dx, dy, flip, tie = e
    if dy == 0.0:
        empty = empty or not inside(e, xl, py)
    elif flip * dy > 0.0:
        xr = min(xr, ox + dx * (py - oy) / dy)
    else:
        xl = max(xl, ox + dx * (py - oy) / dy)
    return xl, xr, empty


@njit(cache=True)
def _pose3(X, F, orient, R, tau):
    """Ray grid of one 3D pose.

    Parameters
    ----------
    X : (n, 3) float64
        Vertices in the frame of ``up`` (:func:`supportless.energies.surface.to_frame`).
    F : (f, 3) int64
        Triangles.
    orient : float
        +1 for outward-oriented faces, -1 for inverted ones.
    R : int
        Cells along the longer side of the footprint.
    tau : float
        Risk threshold (``n . up < -tau``).

    Returns
    -------
    inter, sup : float
        Volume inside two or more layers; support column volume.
    """
    umin, umax, wmin, wmax, zplate = frame_bbox3(X)
    cell, nx, ny, u0, w0 = grid_layout(umin, umax, wmin, wmax, R)
    if nx == 0 or F.shape[0] == 0:
        return 0.0, 0.0
    cap = 4 * nx * ny + 64
    pix = np.empty(cap, np.int64)
    zz = np.empty(cap, np.float64)
    cc = np.empty(cap, np.int8)
    cnt = np.zeros(nx * ny, np.int64)
    m = 0
    for f in range(F.shape[0]):
        ax, ay, az, bx, by, bz, cx, cy, cz = triangle(X, F, f)
        nxv, nyv, nzv = face_normal(ax, ay, az, bx, by, bz, cx, cy, cz)
        if nzv == 0.0:  # vertical: no ray crosses it
            continue
        nlen = np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv)
        code = risk_code(orient * nzv / nlen, tau)
        gx = -nxv / nzv
        gy = -nyv / nzv
        lo_u = min(ax, min(bx, cx))
        hi_u = max(ax, max(bx, cx))
        lo_w = min(ay, min(by, cy))
        hi_w = max(ay, max(by, cy))
        i_lo = max(0, int(np.floor((lo_u - u0) / cell - 0.5)))
        i_hi = min(nx - 1, int(np.ceil((hi_u - u0) / cell - 0.5)))
        j_lo = max(0, int(np.floor((lo_w - w0) / cell - 0.5)))
        j_hi = min(ny - 1, int(np.ceil((hi_w - w0) / cell - 0.5)))
        edges = triangle_edges(ax, ay, bx, by, cx, cy, nzv > 0.0)
        e1, e2, e3 = edges
        for j in range(j_lo, j_hi + 1):
            py = w0 + (j + 0.5) * cell
            # Approximate span of the row inside the triangle; pixels near
            # either end get the exact (tie-broken) test, pixels more than a
            # cell inside are accepted directly.  Edges with dy == 0 do not
            # depend on px: one exact test decides the whole row.
            xl, xr, empty = _clip_row(e1, py, lo_u, hi_u, False)
            xl, xr, empty = _clip_row(e2, py, xl, xr, empty)
            xl, xr, empty = _clip_row(e3, py, xl, xr, empty)
            if empty:
                continue
            ia = int(np.ceil((xl - u0) / cell - 0.5))
            ib = int(np.floor((xr - u0) / cell - 0.5))
            k0 = max(i_lo, ia - 1)
            k1 = min(i_hi, ib + 1)
            for i in range(k0, k1 + 1):
                px = u0 + (i + 0.5) * cell
                if (i <= ia or i >= ib) and not inside_triangle(edges, px, py):
                    continue
                if m == pix.shape[0]:
                    pix, zz, cc = _grow(pix, zz, cc)
                q = j * nx + i
                pix[m] = q
                zz[m] = az + gx * (px - ax) + gy * (py - ay)
                cc[m] = code
                cnt[q] += 1
                m += 1
    inter, sup = _sweep(pix, zz, cc, cnt, m, nx * ny, zplate)
    area = cell * cell
    return inter * area, sup * area


@njit(cache=True)
def _pose2(X, E, orient, R, tau):
    """Ray grid of one 2D pose.

    Parameters
    ----------
    X : (n, 2) float64
        Vertices in the frame of ``up``.
    E : (e, 2) int64
        Boundary edges (:func:`supportless.energies.surface.boundary_edges`).
    orient : float
        +1 for a counter-clockwise mesh, -1 for a clockwise one.
    R : int
        Number of rays; the cells (intervals) split the footprint.
    tau : float
        Risk threshold.

    Returns
    -------
    inter, sup : float
        Area inside two or more layers; support column area.  A ray at ``px``
        crosses the edge ``a b`` when ``min(ua, ub) <= px < max(ua, ub)``.
    """
    umin = np.inf
    umax = -np.inf
    zplate = np.inf
    for i in range(X.shape[0]):
        umin = min(umin, X[i, 0])
        umax = max(umax, X[i, 0])
        zplate = min(zplate, X[i, 1])
    L = umax - umin
    if not (L > 0.0) or E.shape[0] == 0:
        return 0.0, 0.0
    cell = L / R
    cap = 4 * R + 64
    pix = np.empty(cap, np.int64)
    zz = np.empty(cap, np.float64)
    cc = np.empty(cap, np.int8)
    cnt = np.zeros(R, np.int64)
    m = 0
    for e in range(E.shape[0]):
        a = E[e, 0]
        b = E[e, 1]
        ax = X[a, 0]
        az = X[a, 1]
        bx = X[b, 0]
        bz = X[b, 1]
        ex = bx - ax
        if ex == 0.0:
            continue
        ez = bz - az
        code = risk_code(-orient * ex / np.sqrt(ex * ex + ez * ez), tau)  # outward normal (ez, -ex) / length
        lo = min(ax, bx)
        hi = max(ax, bx)
        slope = ez / ex
        i_lo = max(0, int(np.floor((lo - umin) / cell - 0.5)))
        i_hi = min(R - 1, int(np.ceil((hi - umin) / cell - 0.5)))
        for i in range(i_lo, i_hi + 1):
            px = umin + (i + 0.5) * cell
            if px < lo or px >= hi:
                continue
            if m == pix.shape[0]:
                pix, zz, cc = _grow(pix, zz, cc)
            pix[m] = i
            zz[m] = az + slope * (px - ax)
            cc[m] = code
            cnt[i] += 1
            m += 1
    inter, sup = _sweep(pix, zz, cc, cnt, m, R, zplate)
    return inter * cell, sup * cell


def grid_batch(X, S, orient, R, tau):
    """The reference ray grid over a batch, parallel over poses.

    Parameters
    ----------
    X : (P, n, d) float64
        Vertices in the frame of ``up``, ``d`` in {2, 3}.
    S : (f, 3) or (e, 2) int64
        The surface: triangles in 3D, boundary edges in 2D.
    orient : (P,) float64
        Orientation sign per pose.
    R : int
        Cells along the longer side of the footprint (3D), rays (2D).
    tau : float
        Risk threshold.

    Returns
    -------
    out : (P, 2) float64
        Self-intersection volume (area) and support column volume (area) per
        pose: :func:`_pose3` or :func:`_pose2`, each compiled only for the
        dimension it serves (a 2D figure's first run does not compile the 3D
        rasteriser).
    """
    return _batch(_batch3 if X.shape[2] == 3 else _batch2, X, S, orient, R, tau)


def _batch(kernel, X, S, orient, R, tau):
    """``kernel`` (:func:`_batch3` or :func:`_batch2`) over the poses of ``X``, split over threads."""
    out = np.zeros((X.shape[0], 2), np.float64)
    over(kernel, X.shape[0], X, S, orient, int(R), float(tau), out)
    return out


@njit(cache=True, nogil=True)
def _batch3(X, S, orient, R, tau, out, lo, hi):
    """:func:`grid_batch` of the 3D poses ``lo:hi``, into ``out`` (P, 2)."""
    for p in range(lo, hi):
        a, b = _pose3(X[p], S, orient[p], R, tau)
        out[p, 0] = a
        out[p, 1] = b


@njit(cache=True, nogil=True)
def _batch2(X, S, orient, R, tau, out, lo, hi):
    """:func:`grid_batch` of the 2D poses ``lo:hi``, into ``out`` (P, 2)."""
    for p in range(lo, hi):
        a, b = _pose2(X[p], S, orient[p], R, tau)
        out[p, 0] = a
        out[p, 1] = b
