"""Plain numpy implementation of the ray grid (:mod:`supportless.energies.raygrid`, ``backend="numpy"``).

The same grid (:func:`._grid_common.grid_layout`), crossing rule and sweep as
the numba kernels, vectorised: every (face, ray centre of its bounding box)
pair at once, sorted with ``np.lexsort`` and swept with cumulative sums.
Slower; a reference for the kernels and for tests.  Same crossings as the
kernels; the sums run in another order, so they agree to round-off.
"""

from __future__ import annotations

import numpy as np

from ._grid_common import ENTERING, LEAVING, RISKY, grid_layout

__all__ = ["columns3_numpy", "pose2_numpy", "pose3_numpy", "sweep_crossings"]


def _edges(ax, ay, bx, by):
    """Vectorised :func:`._grid_common.edge`: canonical ``(ox, oy, dx, dy, flip, tie)``, each (k,) float64."""
    swap = (bx < ax) | ((bx == ax) & (by < ay))
    ox = np.where(swap, bx, ax)
    oy = np.where(swap, by, ay)
    dx = np.where(swap, ax, bx) - ox
    dy = np.where(swap, ay, by) - oy
    flip = np.where(swap, -1.0, 1.0)
    tie = np.where(dy != 0.0, -dy, dx)
    return ox, oy, dx, dy, flip, tie


def _inside(edge, px, py):
    """Vectorised :func:`._grid_common.inside`: (k,) bool."""
    ox, oy, dx, dy, flip, tie = edge
    e = dx * (py - oy) - dy * (px - ox)
    e = np.where(e == 0.0, tie, e)
    return e * flip > 0.0


def _pairs(count):
    """Every (element, index) pair with index in ``range(count[element])``.

    Parameters
    ----------
    count : (k,) int64
        Non-negative counts.

    Returns
    -------
    elem : (N,) int64
        Element of each pair, ``N = count.sum()``.
    off : (N,) int64
        Index of each pair within its element.
    """
    elem = np.repeat(np.arange(len(count)), count)
    off = np.arange(elem.size) - np.repeat(np.cumsum(count) - count, count)
    return elem, off


def sweep_crossings(pix, z, code, zplate):
    """Sort crossings by (pixel, height) and sweep every ray at once.

    Parameters
    ----------
    pix : (k,) int64
        Pixel (ray) of each crossing.
    z : (k,) float64
        Height of each crossing.
    code : (k,) int8
        :data:`._grid_common.LEAVING`, ``ENTERING`` or ``RISKY``.
    zplate : float
        Height of the build plate.

    Returns
    -------
    inter, sup : float
        Summed length inside >= 2 layers, summed support column length.
    columns : tuple of (c,) int64, (c,) float64, (c,) float64
        The support columns: pixel, bottom and top height of each.
    """
    if pix.size == 0:
        return 0.0, 0.0, (pix, z, z)
    order = np.lexsort((z, pix))  # stable: ties keep face order, like the kernels
    pix, z, code = pix[order], z[order], code[order]
    step = np.where(code != LEAVING, 1, -1)
    first = np.ones(pix.size, bool)
    first[1:] = pix[1:] != pix[:-1]
    group = np.cumsum(first) - 1
    before = np.cumsum(step) - step  # running count before each crossing, all rays
    before = before - before[first][group]  # ... restarted at each ray
    zprev = np.empty_like(z)
    zprev[0] = zplate
    zprev[1:] = z[:-1]
    zprev[first] = zplate
    inter = float(np.sum(np.where(before >= 2, z - zprev, 0.0)))
    col = (code == RISKY) & (before <= 0) & (z > zprev)
    sup = float(np.sum(z[col] - zprev[col]))
    return inter, sup, (pix[col], zprev[col], z[col])


def pose3_numpy(X, F, orient, R, tau, support=True):
    """The ray grid of one 3D pose (:func:`._grid_reference._pose3` in numpy).

    Parameters
    ----------
    X : (n, 3) float64
    F : (f, 3) int64
    orient, R, tau
        As :func:`._grid_reference._pose3`.
    support : bool
        False: skip the risky test (the support volume is then meaningless).

    Returns
    -------
    inter, sup : float
        As :func:`._grid_reference._pose3`.
    """
    inter, sup, _, cell = columns3_numpy(X, F, orient, R, tau, support)
    area = cell * cell
    return inter * area, sup * area


def columns3_numpy(X, F, orient, R, tau, support=True):
    """The ray grid of one 3D pose and the support columns it finds.

    Parameters
    ----------
    X, F, orient, R, tau, support
        As :func:`pose3_numpy`.

    Returns
    -------
    inter, sup : float
        Summed lengths (not yet times the cell area).
    columns : tuple of (c,) float64, (c,) float64, (c,) float64, (c,) float64
        ``u``, ``w`` (the ray's centre in the frame's plane), ``bottom`` and
        ``top`` (heights) of each support column.
    cell : float
        Side of a ray cell (0 when the footprint is empty).
    """
    umin, wmin, zplate = X.min(axis=0)
    umax, wmax, _ = X.max(axis=0)
    cell, nx, ny, u0, w0 = grid_layout(umin, umax, wmin, wmax, R)
    empty = np.zeros(0)
    if nx == 0 or F.shape[0] == 0:
        return 0.0, 0.0, (empty, empty, empty, empty), cell
    A, B, C = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    e1 = B - A
    e2 = C - A
    nzv = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    keep = nzv != 0.0
    A, B, C, e1, e2, nzv = A[keep], B[keep], C[keep], e1[keep], e2[keep], nzv[keep]
    nxv = e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1]
    nyv = e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2]
    code = np.where(orient * nzv < 0.0, ENTERING, LEAVING).astype(np.int8)
    if support:
        cosf = orient * nzv / np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv)
        code[(code == ENTERING) & (cosf < -tau)] = RISKY
    gx = -nxv / nzv
    gy = -nyv / nzv
    lo = np.minimum(np.minimum(A, B), C)
    hi = np.maximum(np.maximum(A, B), C)
    i_lo = np.maximum(0, np.floor((lo[:, 0] - u0) / cell - 0.5).astype(np.int64))
    i_hi = np.minimum(nx - 1, np.ceil((hi[:, 0] - u0) / cell - 0.5).astype(np.int64))
    j_lo = np.maximum(0, np.floor((lo[:, 1] - w0) / cell - 0.5).astype(np.int64))
    j_hi = np.minimum(ny - 1, np.ceil((hi[:, 1] - w0) / cell - 0.5).astype(np.int64))
    # candidate (face, pixel) pairs: the pixel centres in each face's bounding box
    ni = np.maximum(i_hi - i_lo + 1, 0)
    nj = np.maximum(j_hi - j_lo + 1, 0)
    f, off = _pairs(ni * nj)
    i = i_lo[f] + off % ni[f]
    j = j_lo[f] + off // ni[f]
    px = u0 + (i + 0.5) * cell
    py = w0 + (j + 0.5) * cell
    # edges with the inside on the left (reverse the triangle when clockwise)
    pos = nzv[f] > 0.0
    a = np.where(pos[:, None], A[f], B[f])
    b = np.where(pos[:, None], B[f], A[f])
    c = C[f]
    inside = (_inside(_edges(a[:, 0], a[:, 1], b[:, 0], b[:, 1]), px, py)
              & _inside(_edges(b[:, 0], b[:, 1], c[:, 0], c[:, 1]), px, py)
              & _inside(_edges(c[:, 0], c[:, 1], a[:, 0], a[:, 1]), px, py))
    f, px, py, i, j = f[inside], px[inside], py[inside], i[inside], j[inside]
    z = A[f, 2] + gx[f] * (px - A[f, 0]) + gy[f] * (py - A[f, 1])
    inter, sup, (pix, bottom, top) = sweep_crossings(j * nx + i, z, code[f], zplate)
    return inter, sup, (u0 + (pix % nx + 0.5) * cell, w0 + (pix // nx + 0.5) * cell, bottom, top), cell


def pose2_numpy(X, E, orient, R, tau):
    """The ray grid of one 2D pose (:func:`._grid_reference._pose2` in numpy).

    Parameters
    ----------
    X : (n, 2) float64
    E : (e, 2) int64
    orient, R, tau
        As :func:`._grid_reference._pose2`.

    Returns
    -------
    inter, sup : float
        As :func:`._grid_reference._pose2`.
    """
    umin, zplate = X.min(axis=0)
    umax = X[:, 0].max()
    L = umax - umin
    if not (L > 0.0) or E.shape[0] == 0:
        return 0.0, 0.0
    cell = L / R
    a, b = X[E[:, 0]], X[E[:, 1]]
    ex = b[:, 0] - a[:, 0]
    keep = ex != 0.0
    a, b, ex = a[keep], b[keep], ex[keep]
    ez = b[:, 1] - a[:, 1]
    cosf = -orient * ex / np.sqrt(ex * ex + ez * ez)
    code = np.where(cosf < 0.0, np.where(cosf < -tau, RISKY, ENTERING), LEAVING).astype(np.int8)
    lo = np.minimum(a[:, 0], b[:, 0])
    hi = np.maximum(a[:, 0], b[:, 0])
    slope = ez / ex
    i_lo = np.maximum(0, np.floor((lo - umin) / cell - 0.5).astype(np.int64))
    i_hi = np.minimum(R - 1, np.ceil((hi - umin) / cell - 0.5).astype(np.int64))
    e, off = _pairs(np.maximum(i_hi - i_lo + 1, 0))
    i = i_lo[e] + off
    px = umin + (i + 0.5) * cell
    ok = (px >= lo[e]) & (px < hi[e])
    e, i, px = e[ok], i[ok], px[ok]
    z = a[e, 1] + slope[e] * (px - a[e, 0])
    inter, sup, _ = sweep_crossings(i, z, code[e], zplate)
    return inter * cell, sup * cell
