"""Shared geometry helpers and the numba ray-grid kernel.

The self-intersection volume and the column support estimator both cast a
regular grid of rays along the printing direction ``up`` through the model's
footprint, collect every surface crossing along each ray, sort the crossings
by height and sweep upwards.  Both quantities come out of one sweep, so a
single kernel computes them together.

Coordinates
-----------
Vertices are first expressed in a right-handed orthonormal frame whose last
axis is ``up``: ``(u, w, z)`` in 3D and ``(u, z)`` in 2D.  Since the change of
frame is a rotation, orientations (triangle winding, signed areas) are kept.

Robust crossing rule
--------------------
A ray at pixel centre ``p`` crosses a triangle when ``p`` lies inside the
triangle's projection.  Each edge function is evaluated with the edge's end
points in a canonical (lexicographic) order, so two triangles sharing an edge
get bit-identical values of opposite sign, and ties (``p`` exactly on an edge
or a vertex) are broken by the symbolic perturbation ``p + (eps, eps**2)``.
Every ray therefore crosses a closed, consistently oriented surface an
even number of times, and a ray through a shared edge or vertex is counted
exactly once.  In 2D the same idea reduces to half-open intervals
``[min(u_a, u_b), max(u_a, u_b))``.

Backends
--------
``backend="fast"`` runs numba kernels parallel over poses; the 3D kernel
(:func:`_pose3_fast`) tests each triangle's bounding-box centres with float
edge functions and hands the few centres within ``_SPAN_EPS`` of an edge to
the exact test above, so it finds exactly the crossings of the reference
kernel :func:`_pose3` (kept as the fallback for poses overflowing the
buffers).  ``backend="numpy"`` is a plain numpy implementation of the same
rules (vectorised over (face, pixel) pairs, sorted with ``np.lexsort``),
slower, for reference and tests.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import njit, prange

#: Default number of square ray cells along the longer side of the footprint.
#: At 192 the relative error on the test shapes (rotated overlapping boxes,
#: overlapping spheres, a limb swung into a body, tilted-arm support) is at
#: most 1.8 %; in general it is about one cell over the feature width.
DEFAULT_RESOLUTION = 192

__all__ = [
    "DEFAULT_RESOLUTION",
    "prepare",
    "plane_basis",
    "to_frame",
    "orientation_sign",
    "boundary_edges",
    "ray_grid",
    "BACKENDS",
    "check_backend",
]


# ---------------------------------------------------------------------------
# numpy helpers
# ---------------------------------------------------------------------------


def prepare(vertices, faces, up):
    """Validate and normalise the common arguments.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Vertex positions of one pose or a batch of ``P`` poses, ``d`` in {2, 3}.
    faces : (f, 3) int
        Triangle indices.
    up : (d,) float
        Printing direction; any nonzero vector, normalised here.

    Returns
    -------
    V : (P, n, d) float64
        Batched vertices (``P = 1`` for a single pose).
    F : (f, 3) int64
        Faces as a contiguous int64 array.
    up : (d,) float64
        Unit printing direction.
    single : bool
        True when ``vertices`` was a single pose ``(n, d)``.
    """
    V = np.asarray(vertices, dtype=np.float64)
    single = V.ndim == 2
    if single:
        V = V[None]
    if V.ndim != 3 or V.shape[-1] not in (2, 3):
        raise ValueError("vertices must have shape (P, n, d) or (n, d) with d in {2, 3}")
    V = np.ascontiguousarray(V)
    F = np.ascontiguousarray(np.asarray(faces, dtype=np.int64).reshape(-1, 3))
    d = V.shape[-1]
    u = np.asarray(up, dtype=np.float64).reshape(-1)
    if u.shape != (d,):
        raise ValueError(f"up must be a vector of length {d}")
    nrm = np.linalg.norm(u)
    if not np.isfinite(nrm) or nrm == 0.0:
        raise ValueError("up must be a finite nonzero vector")
    return V, F, u / nrm, single


def plane_basis(up):
    """Orthonormal basis of the plane orthogonal to ``up``.

    Parameters
    ----------
    up : (d,) float64
        Unit vector, ``d`` in {2, 3}.

    Returns
    -------
    B : (d - 1, d) float64
        Rows span the plane orthogonal to ``up``; the frame
        ``(B[0], ..., up)`` is right-handed (determinant +1).
    """
    up = np.asarray(up, dtype=np.float64)
    if up.shape[0] == 2:
        return np.array([[up[1], -up[0]]])
    helper = np.zeros(3)
    helper[np.argmin(np.abs(up))] = 1.0
    e1 = np.cross(helper, up)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    return np.stack([e1, e2])


def to_frame(V, up):
    """Express vertices in the right-handed frame ``(plane basis, up)``.

    Parameters
    ----------
    V : (P, n, d) float64
        Batched vertices.
    up : (d,) float64
        Unit printing direction.

    Returns
    -------
    X : (P, n, d) float64
        Coordinates; the last one is the height along ``up``.
    """
    R = np.vstack([plane_basis(up), up[None]])  # (d, d), rows = new axes
    # written out (not V @ R.T) so the fast kernel's in-place transform is bit-identical
    d = V.shape[-1]
    X = np.empty(V.shape)
    for a in range(d):
        x = V[..., 0] * R[a, 0]
        for c in range(1, d):
            x = x + V[..., c] * R[a, c]
        X[..., a] = x
    return X


BACKENDS = ("fast", "numpy")


def check_backend(backend):
    """Raise ValueError unless ``backend`` is ``"fast"`` (numba) or ``"numpy"``."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, not {backend!r}")


def orientation_sign(V, F, backend="fast"):
    """Sign of the total signed volume (3D) or signed area (2D) per pose.

    Parameters
    ----------
    V : (P, n, d) float64
        Batched vertices.
    F : (f, 3) int64
        Triangles.
    backend : {"fast", "numpy"}
        numba kernel or plain numpy.

    Returns
    -------
    s : (P,) float64
        +1 when the faces are outward oriented (counter-clockwise in 2D),
        -1 when inverted; +1 when the total is exactly zero.
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if backend == "numpy":
        a, b, c = V[:, F[:, 0]], V[:, F[:, 1]], V[:, F[:, 2]]
        if V.shape[-1] == 3:
            tot = np.einsum("pfi,pfi->p", a, np.cross(b, c)) / 6.0
        else:
            e1, e2 = b - a, c - a
            tot = 0.5 * np.sum(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0], axis=-1)
    elif V.shape[-1] == 3:
        tot = _signed_volume3(V, F)
    else:
        tot = _signed_area2(V, F)
    return np.where(tot < 0.0, -1.0, 1.0)


@njit(cache=True, parallel=True)
def _signed_volume3(V, F):
    P = V.shape[0]
    out = np.zeros(P, np.float64)
    for p in prange(P):
        X = V[p]
        t = 0.0
        for f in range(F.shape[0]):
            a = F[f, 0]
            b = F[f, 1]
            c = F[f, 2]
            t += X[a, 0] * (X[b, 1] * X[c, 2] - X[b, 2] * X[c, 1])
            t += X[a, 1] * (X[b, 2] * X[c, 0] - X[b, 0] * X[c, 2])
            t += X[a, 2] * (X[b, 0] * X[c, 1] - X[b, 1] * X[c, 0])
        out[p] = t / 6.0
    return out


@njit(cache=True, parallel=True)
def _signed_area2(V, F):
    P = V.shape[0]
    out = np.zeros(P, np.float64)
    for p in prange(P):
        X = V[p]
        t = 0.0
        for f in range(F.shape[0]):
            a = F[f, 0]
            b = F[f, 1]
            c = F[f, 2]
            t += (X[b, 0] - X[a, 0]) * (X[c, 1] - X[a, 1]) - (X[b, 1] - X[a, 1]) * (X[c, 0] - X[a, 0])
        out[p] = 0.5 * t
    return out


def boundary_edges(faces, vertices=None):
    """Boundary edges of a 2D triangle mesh, oriented outward.

    A boundary edge is used by exactly one triangle.  Edges keep the
    direction in which they appear in their triangle, so for a
    counter-clockwise mesh the region lies to the left of each edge
    ``a -> b`` and the outward normal is ``(b - a)`` rotated clockwise,
    i.e. ``(dy, -dx) / |b - a|``.

    Parameters
    ----------
    faces : (f, 3) int
        Consistently oriented triangles.
    vertices : (n, 2) float, optional
        If given and the total signed area is negative (clockwise mesh), the
        edges are reversed so that the convention above holds.

    Returns
    -------
    edges : (e, 2) int64
        Directed boundary edges.
    """
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    edges = np.ascontiguousarray(E[cnt[inv.reshape(-1)] == 1])
    if vertices is not None:
        V = np.asarray(vertices, dtype=np.float64)
        if V.ndim == 3:
            V = V[0]
        if orientation_sign(V[None], F)[0] < 0:
            edges = np.ascontiguousarray(edges[:, ::-1])
    return edges


# ---------------------------------------------------------------------------
# numba kernels
# ---------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _edge(ax, ay, bx, by):
    """Canonical form of the directed edge a->b.

    Returns ``(ox, oy, dx, dy, flip, tie)``: the edge function of a point p
    is ``flip * (dx * (py - oy) - dy * (px - ox))`` (positive on the left of
    a->b), with the end points taken in lexicographic order so that both
    triangles sharing an edge evaluate bit-identical values; ``tie`` is the
    sign used when that value is exactly 0 (perturbation p + (eps, eps^2)).
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


@njit(cache=True, inline="always")
def _inside(ox, oy, dx, dy, flip, tie, px, py):
    e = dx * (py - oy) - dy * (px - ox)
    if e == 0.0:
        e = tie
    return e * flip > 0.0


@njit(cache=True, inline="always")
def _clip_row(ox, oy, dx, dy, flip, tie, py, xl, xr, empty):
    """Narrow the span ``[xl, xr]`` of a pixel row to the inner side of one edge.

    A horizontal edge (``dy == 0``) does not depend on x: one exact test
    decides the whole row (``empty``). Returns ``(xl, xr, empty)``.
    """
    if dy == 0.0:
        empty = empty or not _inside(ox, oy, dx, dy, flip, tie, xl, py)
    elif flip * dy > 0.0:
        xr = min(xr, ox + dx * (py - oy) / dy)
    else:
        xl = max(xl, ox + dx * (py - oy) / dy)
    return xl, xr, empty


@njit(cache=True)
def _grow(pix, zz, cc):
    n = pix.shape[0] * 2
    p2 = np.empty(n, np.int64)
    z2 = np.empty(n, np.float64)
    c2 = np.empty(n, np.float64)
    p2[: pix.shape[0]] = pix
    z2[: pix.shape[0]] = zz
    c2[: pix.shape[0]] = cc
    return p2, z2, c2



@njit(cache=True, inline="always")
def _sort_segment(zs, cs, s0, s1):
    """Insertion sort of ``zs[s0:s1]`` (the crossings of one ray, few) with ``cs`` alongside."""
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
def _sweep(pix, zz, cc, m, npix, zplate, tau):
    """Sort crossings per pixel and sweep upwards.

    Returns (summed length inside >= 2 layers, summed support column length).
    """
    start = np.zeros(npix + 1, np.int64)
    for k in range(m):
        start[pix[k] + 1] += 1
    for q in range(npix):
        start[q + 1] += start[q]
    pos = start[:npix].copy()
    zs = np.empty(m, np.float64)
    cs = np.empty(m, np.float64)
    for k in range(m):
        q = pix[k]
        t = pos[q]
        zs[t] = zz[k]
        cs[t] = cc[k]
        pos[q] = t + 1
    inter = 0.0
    sup = 0.0
    for q in range(npix):
        s0 = start[q]
        s1 = start[q + 1]
        if s1 == s0:
            continue
        _sort_segment(zs, cs, s0, s1)
        count = 0
        zprev = zplate
        for k in range(s0, s1):
            z = zs[k]
            c = cs[k]
            if count >= 2:
                inter += z - zprev
            if c < 0.0:  # downward-facing: entering material
                if count <= 0 and c < -tau:
                    # column from this risky face down to the top of the
                    # material below (previous crossing) or the build plate
                    lo = zs[k - 1] if k > s0 else zplate
                    if z > lo:
                        sup += z - lo
                count += 1
            else:  # upward-facing: leaving material
                count -= 1
            zprev = z
    return inter, sup


@njit(cache=True)
def _pose3(X, F, orient, R, tau):
    n = X.shape[0]
    umin = np.inf
    umax = -np.inf
    wmin = np.inf
    wmax = -np.inf
    zplate = np.inf
    for i in range(n):
        u = X[i, 0]
        w = X[i, 1]
        umin = min(umin, u)
        umax = max(umax, u)
        wmin = min(wmin, w)
        wmax = max(wmax, w)
        zplate = min(zplate, X[i, 2])
    du = umax - umin
    dw = wmax - wmin
    L = max(du, dw)
    if not (L > 0.0) or F.shape[0] == 0:
        return 0.0, 0.0
    cell = L / R
    nx = max(1, int(np.ceil(du / cell - 1e-9)))
    ny = max(1, int(np.ceil(dw / cell - 1e-9)))
    u0 = umin + 0.5 * (du - nx * cell)
    w0 = wmin + 0.5 * (dw - ny * cell)
    cap = 4 * nx * ny + 64
    pix = np.empty(cap, np.int64)
    zz = np.empty(cap, np.float64)
    cc = np.empty(cap, np.float64)
    m = 0
    for f in range(F.shape[0]):
        i0 = F[f, 0]
        i1 = F[f, 1]
        i2 = F[f, 2]
        ax = X[i0, 0]
        ay = X[i0, 1]
        az = X[i0, 2]
        bx = X[i1, 0]
        by = X[i1, 1]
        bz = X[i1, 2]
        cx = X[i2, 0]
        cy = X[i2, 1]
        cz = X[i2, 2]
        e1x = bx - ax
        e1y = by - ay
        e1z = bz - az
        e2x = cx - ax
        e2y = cy - ay
        e2z = cz - az
        nxv = e1y * e2z - e1z * e2y
        nyv = e1z * e2x - e1x * e2z
        nzv = e1x * e2y - e1y * e2x  # = doubled signed projected area
        if nzv == 0.0:
            continue
        nlen = np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv)
        cosf = orient * nzv / nlen
        s = 1.0 if nzv > 0.0 else -1.0
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
        # orient the three edges so that the inside is on the left
        if s > 0.0:
            o1x, o1y, d1x, d1y, f1, t1 = _edge(ax, ay, bx, by)
            o2x, o2y, d2x, d2y, f2, t2 = _edge(bx, by, cx, cy)
            o3x, o3y, d3x, d3y, f3, t3 = _edge(cx, cy, ax, ay)
        else:
            o1x, o1y, d1x, d1y, f1, t1 = _edge(bx, by, ax, ay)
            o2x, o2y, d2x, d2y, f2, t2 = _edge(cx, cy, bx, by)
            o3x, o3y, d3x, d3y, f3, t3 = _edge(ax, ay, cx, cy)
        for j in range(j_lo, j_hi + 1):
            py = w0 + (j + 0.5) * cell
            # Approximate span of the row inside the triangle; pixels near
            # either end get the exact (tie-broken) test, pixels more than a
            # cell inside are accepted directly.  Edges with dy == 0 do not
            # depend on px: one exact test decides the whole row.
            xl, xr, empty = _clip_row(o1x, o1y, d1x, d1y, f1, t1, py, lo_u, hi_u, False)
            xl, xr, empty = _clip_row(o2x, o2y, d2x, d2y, f2, t2, py, xl, xr, empty)
            xl, xr, empty = _clip_row(o3x, o3y, d3x, d3y, f3, t3, py, xl, xr, empty)
            if empty:
                continue
            ia = int(np.ceil((xl - u0) / cell - 0.5))
            ib = int(np.floor((xr - u0) / cell - 0.5))
            k0 = max(i_lo, ia - 1)
            k1 = min(i_hi, ib + 1)
            for i in range(k0, k1 + 1):
                px = u0 + (i + 0.5) * cell
                if i <= ia or i >= ib:
                    if not _inside(o1x, o1y, d1x, d1y, f1, t1, px, py):
                        continue
                    if not _inside(o2x, o2y, d2x, d2y, f2, t2, px, py):
                        continue
                    if not _inside(o3x, o3y, d3x, d3y, f3, t3, px, py):
                        continue
                if m == pix.shape[0]:
                    pix, zz, cc = _grow(pix, zz, cc)
                pix[m] = j * nx + i
                zz[m] = az + gx * (px - ax) + gy * (py - ay)
                cc[m] = cosf
                m += 1
    inter, sup = _sweep(pix, zz, cc, m, nx * ny, zplate, tau)
    area = cell * cell
    return inter * area, sup * area


@njit(cache=True)
def _pose2(X, E, orient, R, tau):
    n = X.shape[0]
    umin = np.inf
    umax = -np.inf
    zplate = np.inf
    for i in range(n):
        umin = min(umin, X[i, 0])
        umax = max(umax, X[i, 0])
        zplate = min(zplate, X[i, 1])
    L = umax - umin
    if not (L > 0.0) or E.shape[0] == 0:
        return 0.0, 0.0
    cell = L / R
    nx = R
    u0 = umin
    cap = 4 * nx + 64
    pix = np.empty(cap, np.int64)
    zz = np.empty(cap, np.float64)
    cc = np.empty(cap, np.float64)
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
        cosf = -orient * ex / np.sqrt(ex * ex + ez * ez)
        lo = min(ax, bx)
        hi = max(ax, bx)
        slope = ez / ex
        i_lo = max(0, int(np.floor((lo - u0) / cell - 0.5)))
        i_hi = min(nx - 1, int(np.ceil((hi - u0) / cell - 0.5)))
        for i in range(i_lo, i_hi + 1):
            px = u0 + (i + 0.5) * cell
            if px < lo or px >= hi:
                continue
            if m == pix.shape[0]:
                pix, zz, cc = _grow(pix, zz, cc)
            pix[m] = i
            zz[m] = az + slope * (px - ax)
            cc[m] = cosf
            m += 1
    inter, sup = _sweep(pix, zz, cc, m, nx, zplate, tau)
    return inter * cell, sup * cell


@njit(cache=True, parallel=True)
def _grid3_batch(X, F, orient, R, tau):
    P = X.shape[0]
    out = np.zeros((P, 2), np.float64)
    for p in prange(P):
        a, b = _pose3(X[p], F, orient[p], R, tau)
        out[p, 0] = a
        out[p, 1] = b
    return out


@njit(cache=True, parallel=True)
def _grid2_batch(X, E, orient, R, tau):
    P = X.shape[0]
    out = np.zeros((P, 2), np.float64)
    for p in prange(P):
        a, b = _pose2(X[p], E, orient[p], R, tau)
        out[p, 0] = a
        out[p, 1] = b
    return out


# ---------------------------------------------------------------------------
# fast 3D kernel
# ---------------------------------------------------------------------------

#: Margin, in cells, around the floating-point row spans of a triangle within
#: which pixel centres get the exact (tie-broken) inside test; rounding of the
#: spans is ~1e-13 cells, so every decision is the exact test's.
_SPAN_EPS = 1e-6

#: Buffer size of the fast kernel, crossings per ray on average (the bunny
#: has ~1.6); a pose with more is recomputed by the general kernel.
_CROSSINGS_PER_PIXEL = 8


@njit(cache=True, inline="always")
def _frame_bbox3(X):
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
def _inside_tri(ax, ay, bx, by, cx, cy, ccw, px, py):
    """Exact, tie-broken test of a pixel centre against a projected triangle
    (the same edge functions as :func:`_pose3`)."""
    if ccw:
        o1x, o1y, d1x, d1y, f1, t1 = _edge(ax, ay, bx, by)
        o2x, o2y, d2x, d2y, f2, t2 = _edge(bx, by, cx, cy)
        o3x, o3y, d3x, d3y, f3, t3 = _edge(cx, cy, ax, ay)
    else:
        o1x, o1y, d1x, d1y, f1, t1 = _edge(bx, by, ax, ay)
        o2x, o2y, d2x, d2y, f2, t2 = _edge(cx, cy, bx, by)
        o3x, o3y, d3x, d3y, f3, t3 = _edge(ax, ay, cx, cy)
    return (_inside(o1x, o1y, d1x, d1y, f1, t1, px, py) and _inside(o2x, o2y, d2x, d2y, f2, t2, px, py)
            and _inside(o3x, o3y, d3x, d3y, f3, t3, px, py))


@njit(cache=True, inline="always")
def _slope(px, py, qx, qy, ccw):
    """Row-span bound of the directed edge p->q of a triangle: ``(x at y=0 of
    the edge line, dx/dy, kind)``, kind +1 for an upper bound of x, -1 for a
    lower bound, 0 for an edge parallel to the rows."""
    dy = qy - py
    if dy == 0.0:
        return 0.0, 0.0, 0
    sl = (qx - px) / dy
    kind = 1 if (dy > 0.0) == ccw else -1
    return px - py * sl, sl, kind


@njit(cache=True)
def _pose3_fast(X, F, orient, R, tau, support, pix, zz, cc, cnt, start, zs, cs, ubuf, ufac, sat):
    """One pose of the ray grid: same grid, crossings and sweep as :func:`_pose3`.

    Differences (none changes the result): candidate pixels are the centres in
    each triangle's row spans, found in floating point with a margin of
    ``_SPAN_EPS`` cells, the exact tie-broken test deciding every centre within
    the margin (rounding of the spans is ~1e-13 cells, so all decisions are
    the exact test's); buffers come from the caller; and when ``support`` is
    False only rays with 4 or more crossings are swept (a ray crossing a
    closed surface twice is never inside two layers).

    Returns ``(intersection, support, ok)``; ``ok`` is False when the crossings
    do not fit in the buffers (the caller then uses :func:`_pose3`).
    """
    eps = _SPAN_EPS
    umin, umax, wmin, wmax, zplate = _frame_bbox3(X)
    du = umax - umin
    dw = wmax - wmin
    L = max(du, dw)
    if not (L > 0.0) or F.shape[0] == 0:
        return 0.0, 0.0, True
    cell = L / R
    inv = 1.0 / cell
    nx = max(1, int(np.ceil(du / cell - 1e-9)))
    ny = max(1, int(np.ceil(dw / cell - 1e-9)))
    u0 = umin + 0.5 * (du - nx * cell)
    w0 = wmin + 0.5 * (dw - ny * cell)
    npix = nx * ny
    cap = pix.shape[0]
    ucap = ubuf.shape[0]
    for q in range(npix):
        cnt[q] = 0
    m = 0
    nu = 0
    two_pass = not support
    for pss in range(2 if two_pass else 1):
        if pss == 1:
            # rays with two or more entering crossings (the only ones that can be
            # inside two layers) keep their count; the others get a large
            # negative one; `sat` counts flagged rays in [0, j) x [0, i)
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
                        cnt[q] = -(1 << 30)
                    sat[(j + 1) * w + i + 1] = sat[j * w + i + 1] + acc
        for f in range(F.shape[0]):
            i0 = F[f, 0]
            i1 = F[f, 1]
            i2 = F[f, 2]
            ay = X[i0, 1]
            by = X[i1, 1]
            cy = X[i2, 1]
            sj_lo = (min(ay, min(by, cy)) - w0) * inv - 0.5
            sj_hi = (max(ay, max(by, cy)) - w0) * inv - 0.5
            j_lo = max(0, int(np.ceil(sj_lo - eps)))
            j_hi = min(ny - 1, int(np.floor(sj_hi + eps)))
            if j_hi < j_lo:
                continue
            ax = X[i0, 0]
            bx = X[i1, 0]
            cx = X[i2, 0]
            lo_u = min(ax, min(bx, cx))
            hi_u = max(ax, max(bx, cx))
            i_lo = max(0, int(np.ceil((lo_u - u0) * inv - 0.5 - eps)))
            i_hi = min(nx - 1, int(np.floor((hi_u - u0) * inv - 0.5 + eps)))
            if i_hi < i_lo:
                continue
            az = X[i0, 2]
            e1x = bx - ax
            e1y = by - ay
            e1z = X[i1, 2] - az
            e2x = cx - ax
            e2y = cy - ay
            e2z = X[i2, 2] - az
            nzv = e1x * e2y - e1y * e2x  # = doubled signed projected area
            if nzv == 0.0:
                continue
            nxv = e1y * e2z - e1z * e2y
            nyv = e1z * e2x - e1x * e2z
            # 0: leaving material, 1: entering, 2: entering through a risky face
            code = 0
            if orient * nzv < 0.0:
                code = 1
                if support:
                    nlen = np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv)
                    if orient * nzv / nlen < -tau:
                        code = 2
            if two_pass:
                if pss == 0 and code == 0:
                    continue
                if pss == 1:
                    if code != 0:
                        continue
                    # skip leaving faces whose bounding box holds no flagged ray
                    w = nx + 1
                    if (sat[(j_hi + 1) * w + i_hi + 1] - sat[j_lo * w + i_hi + 1] - sat[(j_hi + 1) * w + i_lo]
                            + sat[j_lo * w + i_lo]) == 0:
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
    # exact, tie-broken test of the centres close to an edge
    for k in range(nu):
        t = ubuf[k]
        f = ufac[k]
        q = pix[t]
        i0 = F[f, 0]
        i1 = F[f, 1]
        i2 = F[f, 2]
        ax = X[i0, 0]
        ay = X[i0, 1]
        bx = X[i1, 0]
        by = X[i1, 1]
        cx = X[i2, 0]
        cy = X[i2, 1]
        ccw = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) > 0.0
        px = u0 + (q % nx + 0.5) * cell
        py = w0 + (q // nx + 0.5) * cell
        if not _inside_tri(ax, ay, bx, by, cx, cy, ccw, px, py):
            cc[t] = -1
            cnt[q] -= 1
    # bucket the crossings of the rays that need a sweep (counting sort; the
    # order within a ray stays the face order, as in _sweep)
    kmin = 2 if support else 4
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
        count = 0
        zprev = zplate
        for k in range(s0, s1):
            z = zs[k]
            c = cs[k]
            if count >= 2:
                inter += z - zprev
            if c > 0:  # entering material
                if count <= 0 and c == 2:
                    lo = zs[k - 1] if k > s0 else zplate
                    if z > lo:
                        sup += z - lo
                count += 1
            else:
                count -= 1
            zprev = z
    area = cell * cell
    return inter * area, sup * area, True


@njit(cache=True, parallel=True)
def _grid3_fast(V, F, Rm, R, tau, support, xbuf, pix, zz, cc, cnt, start, zs, cs, ubuf, ufac, sat):
    """Per pose: orientation, frame coordinates (as :func:`orientation_sign` and
    :func:`to_frame`, bit for bit) and :func:`_pose3_fast`."""
    P = V.shape[0]
    n = V.shape[1]
    out = np.zeros((P, 2), np.float64)
    ok = np.ones(P, np.bool_)
    for p in prange(P):
        t = numba.get_thread_id()
        Y = V[p]
        vol = 0.0
        for f in range(F.shape[0]):
            a = F[f, 0]
            b = F[f, 1]
            c = F[f, 2]
            vol += Y[a, 0] * (Y[b, 1] * Y[c, 2] - Y[b, 2] * Y[c, 1])
            vol += Y[a, 1] * (Y[b, 2] * Y[c, 0] - Y[b, 0] * Y[c, 2])
            vol += Y[a, 2] * (Y[b, 0] * Y[c, 1] - Y[b, 1] * Y[c, 0])
        orient = -1.0 if vol / 6.0 < 0.0 else 1.0
        X = xbuf[t]
        for i in range(n):
            for a in range(3):
                X[i, a] = Y[i, 0] * Rm[a, 0] + Y[i, 1] * Rm[a, 1] + Y[i, 2] * Rm[a, 2]
        r0, r1, good = _pose3_fast(X[:n], F, orient, R, tau, support, pix[t], zz[t], cc[t], cnt[t], start[t],
                                   zs[t], cs[t], ubuf[t], ufac[t], sat[t])
        out[p, 0] = r0
        out[p, 1] = r1
        ok[p] = good
    return out, ok


def _ray_grid3_fast(V, F, up, R, tau, support):
    """Fast kernel over a batch of world-space poses; poses overflowing its
    buffers go to :func:`_grid3_batch`."""
    threads = numba.config.NUMBA_NUM_THREADS
    npix = R * R
    cap = _CROSSINGS_PER_PIXEL * npix + 1024
    Rm = np.ascontiguousarray(np.vstack([plane_basis(up), up[None]]))
    xbuf = np.empty((threads, V.shape[1], 3), np.float64)
    pix = np.empty((threads, cap), np.int32)
    zz = np.empty((threads, cap), np.float64)
    cc = np.empty((threads, cap), np.int8)
    zs = np.empty((threads, cap), np.float64)
    cs = np.empty((threads, cap), np.int8)
    cnt = np.empty((threads, npix), np.int32)
    start = np.empty((threads, npix), np.int64)
    ubuf = np.empty((threads, npix), np.int64)
    ufac = np.empty((threads, npix), np.int64)
    sat = np.empty((threads, (R + 1) * (R + 1)), np.int32)
    out, ok = _grid3_fast(V, F, Rm, R, float(tau), bool(support), xbuf, pix, zz, cc, cnt, start, zs, cs, ubuf,
                          ufac, sat)
    if not ok.all():
        bad = np.flatnonzero(~ok)
        Vb = np.ascontiguousarray(V[bad])
        out[bad] = _grid3_batch(to_frame(Vb, up), F, np.ascontiguousarray(orientation_sign(Vb, F)), R, float(tau))
    return out


def ray_grid(V, F, up, resolution, tau, backend="fast", support=True):
    """Cast the ray grid for a batch of poses.

    Parameters
    ----------
    V : (P, n, d) float64
        Batched vertices, ``d`` in {2, 3}.
    F : (f, 3) int64
        Triangles (in 2D: a triangle mesh whose boundary is the surface).
    up : (d,) float64
        Unit printing direction.
    resolution : int
        Number of ray cells along the longer side of the footprint (square
        cells).  In 2D the footprint is an interval split into
        ``resolution`` cells.
    tau : float
        Risk threshold: a crossing face with ``n . up < -tau`` is risky.
    backend : {"fast", "numpy"}
        ``fast``: numba kernels, parallel over poses (3D: per-thread buffers,
        orientation and frame computed in the kernel); ``numpy``: the plain
        numpy reference, one pose at a time.  Both find the same crossings
        and agree to round-off in the sums.
    support : bool
        When False only column 0 is wanted: the fast 3D kernel then
        rasterises the entering (downward) faces first and the leaving ones
        only over rays with two or more entering crossings, and column 1 is
        not meaningful.

    Returns
    -------
    out : (P, 2) float64
        Column 0: volume (area in 2D) covered by at least two layers of
        material.  Column 1: column support volume (area in 2D).
    """
    R = int(resolution)
    if R < 1:
        raise ValueError("resolution must be a positive integer")
    check_backend(backend)
    if backend == "fast" and V.shape[-1] == 3:
        return _ray_grid3_fast(V, F, up, R, tau, support)
    orient = np.ascontiguousarray(orientation_sign(V, F, backend))
    X = to_frame(V, up)
    if backend == "numpy":
        if V.shape[-1] == 3:
            return np.array([_pose3_numpy(x, F, o, R, float(tau), support) for x, o in zip(X, orient)]).reshape(-1, 2)
        E = boundary_edges(F)
        return np.array([_pose2_numpy(x, E, o, R, float(tau)) for x, o in zip(X, orient)]).reshape(-1, 2)
    E = boundary_edges(F)
    return _grid2_batch(X, E, orient, R, float(tau))


# ---------------------------------------------------------------------------
# plain numpy reference implementation (backend="numpy")
# ---------------------------------------------------------------------------


def _edges_numpy(ax, ay, bx, by):
    """Vectorised :func:`_edge`: canonical (ox, oy, dx, dy, flip, tie) per edge."""
    swap = (bx < ax) | ((bx == ax) & (by < ay))
    ox = np.where(swap, bx, ax)
    oy = np.where(swap, by, ay)
    dx = np.where(swap, ax, bx) - ox
    dy = np.where(swap, ay, by) - oy
    flip = np.where(swap, -1.0, 1.0)
    tie = np.where(dy != 0.0, -dy, dx)
    return ox, oy, dx, dy, flip, tie


def _inside_numpy(edge, px, py):
    ox, oy, dx, dy, flip, tie = edge
    e = dx * (py - oy) - dy * (px - ox)
    e = np.where(e == 0.0, tie, e)
    return e * flip > 0.0


def _sweep_numpy(pix, z, code, zplate):
    """Sort crossings by (pixel, height) and sweep every ray at once.

    ``code``: 0 leaving, 1 entering, 2 entering through a risky face.
    Returns (summed length inside >= 2 layers, summed support column length).
    """
    if pix.size == 0:
        return 0.0, 0.0
    order = np.lexsort((z, pix))  # stable: ties keep face order, like the kernels
    pix, z, code = pix[order], z[order], code[order]
    step = np.where(code > 0, 1, -1)
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
    col = (code == 2) & (before <= 0) & (z > zprev)
    sup = float(np.sum(z[col] - zprev[col]))
    return inter, sup


def _pose3_numpy(X, F, orient, R, tau, support=True):
    """:func:`_pose3` in numpy: every (face, pixel of its bounding box) pair at once."""
    umin, wmin, zplate = X.min(axis=0)
    umax, wmax, _ = X.max(axis=0)
    du = umax - umin
    dw = wmax - wmin
    L = max(du, dw)
    if not (L > 0.0) or F.shape[0] == 0:
        return 0.0, 0.0
    cell = L / R
    nx = max(1, int(np.ceil(du / cell - 1e-9)))
    ny = max(1, int(np.ceil(dw / cell - 1e-9)))
    u0 = umin + 0.5 * (du - nx * cell)
    w0 = wmin + 0.5 * (dw - ny * cell)
    A, B, C = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    e1 = B - A
    e2 = C - A
    nzv = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    keep = nzv != 0.0
    A, B, C, e1, e2, nzv = A[keep], B[keep], C[keep], e1[keep], e2[keep], nzv[keep]
    nxv = e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1]
    nyv = e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2]
    code = np.where(orient * nzv < 0.0, 1, 0).astype(np.int8)
    if support:
        cosf = orient * nzv / np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv)
        code[(code == 1) & (cosf < -tau)] = 2
    gx = -nxv / nzv
    gy = -nyv / nzv
    lo = np.minimum(np.minimum(A, B), C)
    hi = np.maximum(np.maximum(A, B), C)
    i_lo = np.maximum(0, np.floor((lo[:, 0] - u0) / cell - 0.5).astype(np.int64))
    i_hi = np.minimum(nx - 1, np.ceil((hi[:, 0] - u0) / cell - 0.5).astype(np.int64))
    j_lo = np.maximum(0, np.floor((lo[:, 1] - w0) / cell - 0.5).astype(np.int64))
    j_hi = np.minimum(ny - 1, np.ceil((hi[:, 1] - w0) / cell - 0.5).astype(np.int64))
    ni = np.maximum(i_hi - i_lo + 1, 0)
    nj = np.maximum(j_hi - j_lo + 1, 0)
    count = ni * nj
    # candidate (face, pixel) pairs: the pixel centres in each face's bounding box
    f = np.repeat(np.arange(len(count)), count)
    off = np.arange(f.size) - np.repeat(np.cumsum(count) - count, count)
    i = i_lo[f] + off % ni[f]
    j = j_lo[f] + off // ni[f]
    px = u0 + (i + 0.5) * cell
    py = w0 + (j + 0.5) * cell
    # edges with the inside on the left (reverse the triangle when clockwise)
    pos = nzv[f] > 0.0
    a = np.where(pos[:, None], A[f], B[f])
    b = np.where(pos[:, None], B[f], A[f])
    c = C[f]
    inside = (_inside_numpy(_edges_numpy(a[:, 0], a[:, 1], b[:, 0], b[:, 1]), px, py)
              & _inside_numpy(_edges_numpy(b[:, 0], b[:, 1], c[:, 0], c[:, 1]), px, py)
              & _inside_numpy(_edges_numpy(c[:, 0], c[:, 1], a[:, 0], a[:, 1]), px, py))
    f, px, py, i, j = f[inside], px[inside], py[inside], i[inside], j[inside]
    z = A[f, 2] + gx[f] * (px - A[f, 0]) + gy[f] * (py - A[f, 1])
    inter, sup = _sweep_numpy(j * nx + i, z, code[f], zplate)
    area = cell * cell
    return inter * area, sup * area


def _pose2_numpy(X, E, orient, R, tau):
    """:func:`_pose2` in numpy."""
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
    code = np.where(cosf < 0.0, np.where(cosf < -tau, 2, 1), 0).astype(np.int8)
    lo = np.minimum(a[:, 0], b[:, 0])
    hi = np.maximum(a[:, 0], b[:, 0])
    slope = ez / ex
    i_lo = np.maximum(0, np.floor((lo - umin) / cell - 0.5).astype(np.int64))
    i_hi = np.minimum(R - 1, np.ceil((hi - umin) / cell - 0.5).astype(np.int64))
    count = np.maximum(i_hi - i_lo + 1, 0)
    e = np.repeat(np.arange(len(count)), count)
    i = i_lo[e] + np.arange(e.size) - np.repeat(np.cumsum(count) - count, count)
    px = umin + (i + 0.5) * cell
    ok = (px >= lo[e]) & (px < hi[e])
    e, i, px = e[ok], i[ok], px[ok]
    z = a[e, 1] + slope[e] * (px - a[e, 0])
    inter, sup = _sweep_numpy(i, z, code[e], zplate)
    return inter * cell, sup * cell
