"""Pieces of the ray grid (:mod:`supportless.energies.raygrid`) shared by its implementations.

Numba helpers used by both the reference kernels (:mod:`._grid_reference`)
and the fast kernel (:mod:`._grid_fast`), and the grid layout that the numpy
path (:mod:`._grid_numpy`) uses too:

* :func:`grid_layout`: where the rays of a 3D footprint are;
* :func:`edge`, :func:`inside`, :func:`triangle_edges`,
  :func:`inside_triangle`: the exact, tie-broken test of a ray against a
  projected triangle (see "Robust crossing rule" in :mod:`.raygrid`);
* :func:`face_normal`, :func:`risk_code`: what a crossing means;
* :func:`sweep_rays`: sorting the crossings of every ray by height and
  sweeping upwards, which gives both measured quantities.

Crossing codes: 0 the ray leaves material (upward-facing face), 1 it enters
material, 2 it enters through a risky face (``n . up < -tau``).

Numba caches each file's kernels on their own: a kernel in another file that
calls a helper from here keeps its cached machine code after this file
changes.  After editing this file, delete the numba cache files
(``supportless/energies/__pycache__/*.nb[ci]``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "LEAVING",
    "ENTERING",
    "RISKY",
    "frame_bbox3",
    "grid_layout",
    "edge",
    "inside",
    "triangle_edges",
    "inside_triangle",
    "triangle",
    "face_normal",
    "risk_code",
    "sweep_rays",
]

#: Crossing codes stored per crossing (int8 in the kernels).
LEAVING, ENTERING, RISKY = 0, 1, 2


@njit(cache=True)
def frame_bbox3(X):
    """Footprint and build plate of one pose in the frame of ``up``.

    Parameters
    ----------
    X : (n, 3) float64
        Vertices in the frame ``(u, w, z)``, ``z`` along ``up``.

    Returns
    -------
    umin, umax, wmin, wmax, zplate : float
        Bounding rectangle of the projection and the lowest height.
    """
    umin = np.inf
    umax = -np.inf
    wmin = np.inf
    wmax = -np.inf
    zplate = np.inf
    for i in range(X.shape[0]):
        u = X[i, 0]
        w = X[i, 1]
        umin = min(umin, u)
        umax = max(umax, u)
        wmin = min(wmin, w)
        wmax = max(wmax, w)
        zplate = min(zplate, X[i, 2])
    return umin, umax, wmin, wmax, zplate


@njit(cache=True)
def grid_layout(umin, umax, wmin, wmax, R):
    """Square ray cells over a 3D footprint.

    ``R`` cells span the longer side; the ``nx x ny`` cells cover the
    footprint and are centred on it.  Ray ``(i, j)`` (pixel ``j * nx + i``)
    starts at the cell centre ``(u0 + (i + 0.5) * cell, w0 + (j + 0.5) * cell)``.

    Parameters
    ----------
    umin, umax, wmin, wmax : float
        Footprint rectangle (:func:`frame_bbox3`).
    R : int
        Cells along the longer side, >= 1.

    Returns
    -------
    cell : float
        Side of a cell.
    nx, ny : int
        Cells along ``u`` and ``w``; ``nx = 0`` when the footprint has no
        extent (no rays).
    u0, w0 : float
        Lower corner of the grid.
    """
    du = umax - umin
    dw = wmax - wmin
    L = max(du, dw)
    if not (L > 0.0):
        return 0.0, 0, 0, 0.0, 0.0
    cell = L / R
    nx = max(1, int(np.ceil(du / cell - 1e-9)))
    ny = max(1, int(np.ceil(dw / cell - 1e-9)))
    u0 = umin + 0.5 * (du - nx * cell)
    w0 = wmin + 0.5 * (dw - ny * cell)
    return cell, nx, ny, u0, w0


# ---------------------------------------------------------------------------
# exact, tie-broken point-in-triangle test
# ---------------------------------------------------------------------------


@njit(cache=True)
def edge(ax, ay, bx, by):
    """Canonical form of the directed edge a->b.

    Parameters
    ----------
    ax, ay, bx, by : float
        End points in the plane of the footprint.

    Returns
    -------
    e : tuple of 6 float
        ``(ox, oy, dx, dy, flip, tie)``: the edge function of a point p is
        ``flip * (dx * (py - oy) - dy * (px - ox))`` (positive on the left of
        a->b), with the end points taken in lexicographic order so that both
        triangles sharing an edge evaluate bit-identical values; ``tie`` is
        the sign used when that value is exactly 0 (perturbation
        ``p + (eps, eps**2)``).
    """
    flip = 1.0
    if bx < ax or (bx == ax and by < ay):
        ax, ay, bx, by = bx, by, ax, ay
        flip = -1.0
    dx = bx - ax
    dy = by - ay
    if dy != 0.0:
        tie = -dy
    else:
        tie = dx
    return ax, ay, dx, dy, flip, tie


@njit(cache=True)
def inside(e, px, py):
    """True when ``(px, py)`` is on the left of the canonical edge ``e`` (6 floats, :func:`edge`), ties broken."""
    ox, oy, dx, dy, flip, tie = e
    v = dx * (py - oy) - dy * (px - ox)
    if v == 0.0:
        v = tie
    return v * flip > 0.0


@njit(cache=True)
def triangle_edges(ax, ay, bx, by, cx, cy, ccw):
    """The three canonical edges of a projected triangle, inside on their left.

    Parameters
    ----------
    ax, ay, bx, by, cx, cy : float
        Projected vertices.
    ccw : bool
        True when ``a, b, c`` run counter-clockwise; otherwise the triangle is
        walked the other way.

    Returns
    -------
    edges : tuple of 3 edges
        :func:`edge` of ``a->b, b->c, c->a`` (``b->a, c->b, a->c`` when clockwise).
    """
    if ccw:
        return edge(ax, ay, bx, by), edge(bx, by, cx, cy), edge(cx, cy, ax, ay)
    return edge(bx, by, ax, ay), edge(cx, cy, bx, by), edge(ax, ay, cx, cy)


@njit(cache=True)
def inside_triangle(edges, px, py):
    """Exact, tie-broken test of a ray at ``(px, py)`` against a projected triangle (:func:`triangle_edges`)."""
    e1, e2, e3 = edges
    return inside(e1, px, py) and inside(e2, px, py) and inside(e3, px, py)


# ---------------------------------------------------------------------------
# crossings
# ---------------------------------------------------------------------------


@njit(cache=True)
def triangle(X, F, f):
    """The corners of triangle ``f``: ``(ax, ay, az, bx, by, bz, cx, cy, cz)``
    from ``X`` (n, 3) float64 and ``F`` (f, 3) int64."""
    i0 = F[f, 0]
    i1 = F[f, 1]
    i2 = F[f, 2]
    return X[i0, 0], X[i0, 1], X[i0, 2], X[i1, 0], X[i1, 1], X[i1, 2], X[i2, 0], X[i2, 1], X[i2, 2]


@njit(cache=True)
def face_normal(ax, ay, az, bx, by, bz, cx, cy, cz):
    """``(b - a) x (c - a)`` of a triangle in the frame of ``up``.

    Returns
    -------
    nx, ny, nz : float
        Twice the area times the unit normal; ``nz`` is twice the signed
        projected area (positive when the projection is counter-clockwise).
    """
    e1x = bx - ax
    e1y = by - ay
    e1z = bz - az
    e2x = cx - ax
    e2y = cy - ay
    e2z = cz - az
    return e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x


@njit(cache=True)
def risk_code(cosf, tau):
    """Crossing code of a face with ``cosf = n . up`` (outward unit normal).

    Returns
    -------
    code : int
        :data:`LEAVING` when ``cosf >= 0``, :data:`RISKY` when
        ``cosf < -tau``, else :data:`ENTERING`.
    """
    if cosf < 0.0:
        if cosf < -tau:
            return RISKY
        return ENTERING
    return LEAVING


@njit(cache=True)
def _sort_segment(zs, cs, s0, s1):
    """Stable insertion sort of ``zs[s0:s1]`` (float64 heights of one ray's few
    crossings), with ``cs`` (int8 codes) alongside."""
    for i in range(s0 + 1, s1):
        zk = zs[i]
        ck = cs[i]
        j = i - 1
        while j >= s0 and zs[j] > zk:
            zs[j + 1] = zs[j]
            cs[j + 1] = cs[j]
            j -= 1
        zs[j + 1] = zk
        cs[j + 1] = ck


@njit(cache=True)
def _sweep_ray(zs, cs, s0, s1, zplate, inter, sup):
    """Sweep the sorted crossings ``zs[s0:s1]`` (float64, codes ``cs`` int8) of one ray upwards.

    Adds to ``inter`` the length inside two or more layers of material, and
    to ``sup`` the support column under every risky face met from air: down
    to the crossing below it (top of the material underneath) or to the build
    plate ``zplate``.  Returns the updated ``(inter, sup)``.
    """
    count = 0
    zprev = zplate
    for k in range(s0, s1):
        z = zs[k]
        c = cs[k]
        if count >= 2:
            inter += z - zprev
        if c > 0:  # entering material
            if count <= 0 and c == RISKY:
                lo = zs[k - 1] if k > s0 else zplate
                if z > lo:
                    sup += z - lo
            count += 1
        else:
            count -= 1
        zprev = z
    return inter, sup


@njit(cache=True)
def sweep_rays(pix, zz, cc, m, cnt, npix, kmin, zplate, start, zs, cs):
    """Sort the crossings ray by ray and sweep every ray upwards.

    Parameters
    ----------
    pix : (>= m,) int32 or int64
        Pixel (ray) of each crossing.
    zz : (>= m,) float64
        Height of each crossing.
    cc : (>= m,) int8
        Code of each crossing (:data:`LEAVING`, :data:`ENTERING`,
        :data:`RISKY`); a negative code drops the crossing.
    m : int
        Number of crossings.
    cnt : (>= npix,) int32 or int64
        Number of kept crossings per pixel.
    npix : int
        Number of pixels.
    kmin : int
        Only rays with at least ``kmin`` crossings are swept.
    zplate : float
        Height of the build plate.
    start : (>= npix,) int64
        Work space.
    zs : (>= kept crossings,) float64
        Work space.
    cs : (>= kept crossings,) int8
        Work space.

    Returns
    -------
    inter, sup : float
        Summed length inside >= 2 layers and summed support column length,
        over rays in pixel order (multiply by the cell area or length).
    """
    # counting sort by pixel; within a ray the crossings keep their order
    total = 0
    for q in range(npix):
        start[q] = total
        if cnt[q] >= kmin:
            total += cnt[q]
    for k in range(m):
        q = pix[k]
        if cnt[q] >= kmin and cc[k] >= 0:
            t = start[q]
            zs[t] = zz[k]
            cs[t] = cc[k]
            start[q] = t + 1
    inter = 0.0
    sup = 0.0
    for q in range(npix):
        n = cnt[q]
        if n < kmin:
            continue
        s1 = start[q]
        s0 = s1 - n
        _sort_segment(zs, cs, s0, s1)
        inter, sup = _sweep_ray(zs, cs, s0, s1, zplate, inter, sup)
    return inter, sup
