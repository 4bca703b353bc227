"""Fast numba kernel of the 3D ray grid (:mod:`supportless.energies.raygrid`).

It finds exactly the crossings of the reference kernel
(:func:`._grid_reference._pose3`) and sweeps them with the same code
(:func:`._grid_common.sweep_rays`), so the results are bit-identical; it is
faster because

* the batch runs in one call per thread (:func:`supportless.base.threads.split`)
  that computes each pose's orientation and frame coordinates itself, into
  per-thread buffers allocated once;
* every triangle scans the ray centres of its bounding box in one flat loop
  with incremental floating-point edge functions: centres surely inside are
  kept, surely outside dropped, and the few within ``_SPAN_EPS`` cells of an
  edge are decided afterwards by the exact, tie-broken test;
* for the self-intersection volume alone (``support=False``) it rasterises
  the entering (downward) faces first, then the leaving ones only where a ray
  has two or more entering crossings, and sweeps only rays with four or more
  crossings (a ray crossing a closed surface twice is never inside two layers).

A pose whose crossings overflow the buffers is recomputed by the reference kernel.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..base import threads
from . import _grid_reference
from ._grid_common import (
    ENTERING,
    LEAVING,
    RISKY,
    face_normal,
    frame_bbox3,
    grid_layout,
    inside_triangle,
    sweep_rays,
    triangle,
    triangle_edges,
)
from .surface import frame_matrix, orientation_sign, signed_volume3, to_frame

__all__ = ["ray_grid3_fast"]

#: Margin, in cells, around a triangle's floating-point edge functions within
#: which ray centres get the exact (tie-broken) inside test; rounding of the
#: edge functions is ~1e-13 cells, so every decision is the exact test's.
_SPAN_EPS = 1e-6

#: Buffer size of the fast kernel, crossings per ray on average (the bunny
#: has ~1.6); a pose with more is recomputed by the reference kernel.
_CROSSINGS_PER_PIXEL = 8

#: Count given to rays left out of the second pass (``support=False``).
_NOT_FLAGGED = -(1 << 30)


@njit(cache=True)
def _face_code(orient, nxv, nyv, nzv, tau, support):
    """Crossing code of a face from its normal ``(nxv, nyv, nzv)`` (frame of ``up``, ``nzv != 0``).

    The same decisions as :func:`._grid_common.risk_code` of ``n . up``;
    the risky test (a square root) only when ``support`` is wanted.
    """
    if orient * nzv < 0.0:
        if support:
            nlen = np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv)
            if orient * nzv / nlen < -tau:
                return RISKY
        return ENTERING
    return LEAVING


@njit(cache=True)
def _flag_rays(cnt, sat, nx, ny):
    """Between the two passes: keep the rays with two or more entering crossings.

    Parameters
    ----------
    cnt : (>= nx * ny,) int32
        Crossings per ray after the first pass; the rays not kept get
        ``_NOT_FLAGGED``, far below any count.
    sat : (>= (ny + 1) * (nx + 1),) int32
        Filled with the summed-area table of the kept rays: ``sat[j * (nx +
        1) + i]`` counts those in ``[0, j) x [0, i)``.
    nx, ny : int
        Grid size.
    """
    w = nx + 1
    for i in range(w):
        sat[i] = 0
    for j in range(ny):
        acc = 0
        sat[(j + 1) * w] = 0
        for i in range(nx):
            q = j * nx + i
            if cnt[q] >= 2:
                acc += 1
            else:
                cnt[q] = _NOT_FLAGGED
            sat[(j + 1) * w + i + 1] = sat[j * w + i + 1] + acc


@njit(cache=True)
def _flagged_in_box(sat, nx, i_lo, i_hi, j_lo, j_hi):
    """Number of flagged rays in the pixel box ``[i_lo, i_hi] x [j_lo, j_hi]`` (``sat`` of :func:`_flag_rays`)."""
    w = nx + 1
    return (sat[(j_hi + 1) * w + i_hi + 1] - sat[j_lo * w + i_hi + 1] - sat[(j_hi + 1) * w + i_lo]
            + sat[j_lo * w + i_lo])


@njit(cache=True)
def _decide_near_edges(X, F, ubuf, ufac, nu, pix, cc, cnt, nx, u0, w0, cell):
    """Exact, tie-broken test of the crossings kept near an edge of their triangle.

    Parameters
    ----------
    X : (n, 3) float64
        Frame coordinates.
    F : (f, 3) int64
        Triangles.
    ubuf, ufac : (>= nu,) int64
        The crossings to test (indices into ``pix``/``cc``) and their faces.
    nu : int
        Number of crossings to test.
    pix : (m,) int32
        Pixel of each crossing.
    cc : (m,) int8
        Code of each crossing; set to -1 (dropped by the sweep) when the test fails.
    cnt : (npix,) int32
        Crossings per ray; decremented for each dropped crossing.
    nx : int
        Grid width.
    u0, w0, cell : float
        Grid origin and cell (:func:`._grid_common.grid_layout`).
    """
    for k in range(nu):
        t = ubuf[k]
        q = pix[t]
        ax, ay, _, bx, by, _, cx, cy, _ = triangle(X, F, ufac[k])
        ccw = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) > 0.0
        px = u0 + (q % nx + 0.5) * cell
        py = w0 + (q // nx + 0.5) * cell
        if not inside_triangle(triangle_edges(ax, ay, bx, by, cx, cy, ccw), px, py):
            cc[t] = -1
            cnt[q] -= 1


@njit(cache=True)
def _pose3_fast(X, F, orient, R, tau, support, pix, zz, cc, cnt, start, zs, cs, ubuf, ufac, sat):
    """One 3D pose of the ray grid, into the caller's buffers.

    Parameters
    ----------
    X, F, orient, R, tau
        As :func:`._grid_reference._pose3`: frame coordinates (n, 3) float64,
        triangles (f, 3) int64, orientation sign, cells along the longer
        side, risk threshold.
    support : bool
        False: only the self-intersection volume is wanted (two passes).
    pix, zz, cc : (cap,) int32, float64, int8
        Crossings: pixel, height, code (-1: dropped).
    cnt, start : (>= R * R,) int32, int64
        Crossings per ray; work space of the sweep.
    zs, cs : (cap,) float64, int8
        Work space of the sweep.
    ubuf, ufac : (ucap,) int64
        Crossings (and their faces) waiting for the exact test.
    sat : ((R + 1) ** 2,) int32
        Summed-area table of the second pass.

    Returns
    -------
    inter, sup : float
        As :func:`._grid_reference._pose3` (``sup`` is meaningless when
        ``support`` is False).
    ok : bool
        False when the crossings do not fit in the buffers (the caller then
        uses the reference kernel).
    """
    eps = _SPAN_EPS
    umin, umax, wmin, wmax, zplate = frame_bbox3(X)
    cell, nx, ny, u0, w0 = grid_layout(umin, umax, wmin, wmax, R)
    if nx == 0 or F.shape[0] == 0:
        return 0.0, 0.0, True
    inv = 1.0 / cell
    npix = nx * ny
    cap = pix.shape[0]
    ucap = ubuf.shape[0]
    for q in range(npix):
        cnt[q] = 0
    m = np.int64(0)  # (not the literal 0: the callees below are compiled for one type of count, not two)
    nu = np.int64(0)
    two_pass = not support
    for pss in range(2 if two_pass else 1):
        if pss == 1:
            _flag_rays(cnt, sat, nx, ny)
        for f in range(F.shape[0]):
            ax, ay, az, bx, by, bz, cx, cy, cz = triangle(X, F, f)
            # ray centres of the bounding box, with a margin of eps cells
            sj_lo = (min(ay, min(by, cy)) - w0) * inv - 0.5
            sj_hi = (max(ay, max(by, cy)) - w0) * inv - 0.5
            j_lo = max(0, int(np.ceil(sj_lo - eps)))
            j_hi = min(ny - 1, int(np.floor(sj_hi + eps)))
            if j_hi < j_lo:
                continue
            lo_u = min(ax, min(bx, cx))
            hi_u = max(ax, max(bx, cx))
            i_lo = max(0, int(np.ceil((lo_u - u0) * inv - 0.5 - eps)))
            i_hi = min(nx - 1, int(np.floor((hi_u - u0) * inv - 0.5 + eps)))
            if i_hi < i_lo:
                continue
            nxv, nyv, nzv = face_normal(ax, ay, az, bx, by, bz, cx, cy, cz)
            if nzv == 0.0:  # vertical: no ray crosses it
                continue
            code = _face_code(orient, nxv, nyv, nzv, tau, support)
            if two_pass:
                if pss == 0 and code == LEAVING:
                    continue
                # second pass: leaving faces over flagged rays only
                if pss == 1 and (code != LEAVING or _flagged_in_box(sat, nx, i_lo, i_hi, j_lo, j_hi) == 0):
                    continue
            gx = -nxv / nzv
            gy = -nyv / nzv
            ccw = nzv > 0.0
            # float edge functions in cell units, inside > 0 (vertices taken
            # counter-clockwise); a centre within `tol` of an edge gets the exact test
            pa_u = (ax - u0) * inv - 0.5
            pa_w = (ay - w0) * inv - 0.5
            if ccw:
                pb_u = (bx - u0) * inv - 0.5
                pb_w = (by - w0) * inv - 0.5
                pc_u = (cx - u0) * inv - 0.5
                pc_w = (cy - w0) * inv - 0.5
            else:
                pc_u = (bx - u0) * inv - 0.5
                pc_w = (by - w0) * inv - 0.5
                pb_u = (cx - u0) * inv - 0.5
                pb_w = (cy - w0) * inv - 0.5
            d1u = pb_u - pa_u
            d1w = pb_w - pa_w
            d2u = pc_u - pb_u
            d2w = pc_w - pb_w
            d3u = pa_u - pc_u
            d3w = pa_w - pc_w
            tol1 = eps * (abs(d1u) + abs(d1w)) + 1e-9
            tol2 = eps * (abs(d2u) + abs(d2w)) + 1e-9
            tol3 = eps * (abs(d3u) + abs(d3w)) + 1e-9
            # one flat, branch-free loop over the bounding box's centres (short
            # nested loops cost a mispredicted exit per row)
            if m + (i_hi - i_lo + 1) * (j_hi - j_lo + 1) > cap:
                return 0.0, 0.0, False
            r1 = d1u * (j_lo - pa_w) - d1w * (i_lo - pa_u)
            r2 = d2u * (j_lo - pb_w) - d2w * (i_lo - pb_u)
            r3 = d3u * (j_lo - pc_w) - d3w * (i_lo - pc_u)
            e1 = r1
            e2 = r2
            e3 = r3
            i = i_lo
            j = j_lo
            for _ in range((i_hi - i_lo + 1) * (j_hi - j_lo + 1)):
                # keep the candidate when it is not surely outside, remember
                # it when it is not surely inside either
                sure = (e1 > tol1) * (e2 > tol2) * (e3 > tol3)
                maybe = (e1 >= -tol1) * (e2 >= -tol2) * (e3 >= -tol3)
                q = j * nx + i
                pix[m] = q
                zz[m] = az + gx * (u0 + (i + 0.5) * cell - ax) + gy * (w0 + (j + 0.5) * cell - ay)
                cc[m] = code
                if maybe != sure:  # rare
                    if nu == ucap:
                        return 0.0, 0.0, False
                    ubuf[nu] = m
                    ufac[nu] = f
                    nu += 1
                cnt[q] += maybe
                m += maybe
                wrap = i == i_hi
                i = i_lo if wrap else i + 1
                j = j + 1 if wrap else j
                r1 = r1 + d1u if wrap else r1
                r2 = r2 + d2u if wrap else r2
                r3 = r3 + d3u if wrap else r3
                e1 = r1 if wrap else e1 - d1w
                e2 = r2 if wrap else e2 - d2w
                e3 = r3 if wrap else e3 - d3w
    _decide_near_edges(X, F, ubuf, ufac, nu, pix, cc, cnt, nx, u0, w0, cell)
    # with two passes a ray's entering crossings come before its leaving ones,
    # not in face order: only tied heights sort differently, and between them
    # the sweep adds zero lengths
    inter, sup = sweep_rays(pix, zz, cc, m, cnt, npix, 2 if support else 4, zplate, start, zs, cs)
    area = cell * cell
    return inter * area, sup * area, True


@njit(cache=True, nogil=True)
def _grid3_fast(V, F, Rm, R, tau, support, X, pix, zz, cc, cnt, start, zs, cs, ubuf, ufac, sat, lo, hi, out, ok):
    """:func:`_pose3_fast` over the poses ``lo:hi`` of a batch (one thread's range of :func:`.threads.split`).

    Each pose's orientation and frame coordinates are computed here, bit for
    bit as :func:`.surface.orientation_sign` and :func:`.surface.to_frame`.

    Parameters
    ----------
    V : (P, n, 3) float64
        World-space poses.
    F : (f, 3) int64
        Triangles.
    Rm : (3, 3) float64
        The frame of ``up`` (:func:`.surface.frame_matrix`).
    R, tau, support
        As :func:`_pose3_fast`.
    X : (n, 3) float64
        Scratch: frame coordinates.
    pix, zz, cc, cnt, start, zs, cs, ubuf, ufac, sat
        The scratch buffers of :func:`_pose3_fast` (this thread's).
    lo, hi : int
        The poses computed here.
    out : (P, 2) float64
        Filled at ``lo:hi``: self-intersection and support column volume per pose.
    ok : (P,) bool
        Filled at ``lo:hi``: False for the poses whose crossings did not fit in the buffers.
    """
    n = V.shape[1]
    for p in range(lo, hi):
        Y = V[p]
        orient = -1.0 if signed_volume3(Y, F) < 0.0 else 1.0
        for i in range(n):
            for a in range(3):
                X[i, a] = Y[i, 0] * Rm[a, 0] + Y[i, 1] * Rm[a, 1] + Y[i, 2] * Rm[a, 2]
        r0, r1, good = _pose3_fast(X, F, orient, R, tau, support, pix, zz, cc, cnt, start, zs, cs, ubuf, ufac, sat)
        out[p, 0] = r0
        out[p, 1] = r1
        ok[p] = good


def ray_grid3_fast(V, F, up, R, tau, support):
    """The 3D ray grid of a batch of world-space poses with the fast kernel.

    Parameters
    ----------
    V : (P, n, 3) float64
        C-contiguous poses.
    F : (f, 3) int64
        Triangles.
    up : (3,) float64
        Unit printing direction.
    R : int
        Cells along the longer side of the footprint.
    tau : float
        Risk threshold.
    support : bool
        False when only column 0 is wanted.

    Returns
    -------
    out : (P, 2) float64
        As :func:`supportless.energies.raygrid.ray_grid`; poses overflowing
        the buffers come from :func:`._grid_reference.grid_batch`.
    """
    rows = min(threads.thread_count(), max(len(V), 1))
    npix = R * R
    cap = _CROSSINGS_PER_PIXEL * npix + 1024
    xbuf = np.empty((rows, V.shape[1], 3), np.float64)
    pix = np.empty((rows, cap), np.int32)
    zz = np.empty((rows, cap), np.float64)
    cc = np.empty((rows, cap), np.int8)
    zs = np.empty((rows, cap), np.float64)
    cs = np.empty((rows, cap), np.int8)
    cnt = np.empty((rows, npix), np.int32)
    start = np.empty((rows, npix), np.int64)
    ubuf = np.empty((rows, npix), np.int64)
    ufac = np.empty((rows, npix), np.int64)
    sat = np.empty((rows, (R + 1) * (R + 1)), np.int32)
    out, ok = np.zeros((len(V), 2), np.float64), np.ones(len(V), np.bool_)
    Rm, R, tau, support = frame_matrix(up), int(R), float(tau), bool(support)
    threads.split(lambda lo, hi, t: _grid3_fast(V, F, Rm, R, tau, support, xbuf[t], pix[t], zz[t], cc[t], cnt[t],
                                                start[t], zs[t], cs[t], ubuf[t], ufac[t], sat[t], lo, hi, out, ok),
                  len(V), rows)
    if not ok.all():
        bad = np.flatnonzero(~ok)
        Vb = np.ascontiguousarray(V[bad])
        orient = np.ascontiguousarray(orientation_sign(Vb, F))
        out[bad] = _grid_reference.grid_batch(to_frame(Vb, up), F, orient, R, float(tau))
    return out
