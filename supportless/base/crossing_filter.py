"""Which triangles of a surface might cross another: every other triangle is proven apart from all its neighbours.

An exact self-intersection test (CGAL's) converts every triangle to exact arithmetic and tests every pair whose
boxes meet: on the bunny subdivided four times (1.8 million triangles) that is 5.5 s on two cores, for a surface
that crosses itself nowhere. Almost every such pair is settled by one orientation test in floating point whose
sign is certain: the pairs of a closed surface whose boxes meet are mostly neighbours, and a neighbour's other
corners lie strictly to one side of a triangle's plane. :func:`possibly_crossing_faces` proves pairs apart that
way, with Shewchuk's error bound on the orientation determinant, so a pair it cannot prove apart goes to the
exact test and a pair it proves apart is apart: the exact test of the triangles it leaves finds the same pairs
as the exact test of the whole surface.

A pair is proven apart by a plane with one triangle on its closed side and the other's corners that do not lie on
it strictly on the other side (:func:`_apart`): either triangle's own plane; for two triangles sharing a corner, a
plane through it and a further corner of each; for two sharing none, a plane along an edge of one parallel to an
edge of the other. Triangles in one plane (a flat or subdivided patch, where every such determinant is zero) are
proven apart by the same argument seen along a coordinate axis (:func:`_apart_flat`). Then the two meet at most
in the corner or edge they share, which the exact test does not count either. Every sign is that of a
determinant whose value computed in doubles is farther from zero than Shewchuk's bound on its rounding error:
the sign the exact test would find. Pairs are found by a hashed grid of boxes, each pair tested once.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .threads import over

__all__ = ["MAX_ENTRIES_PER_FACE", "possibly_crossing_faces"]

#: Shewchuk's bound on the rounding error of the orientation determinant computed in doubles, relative to its
#: permanent (``o3derrboundA``, "Adaptive precision floating-point arithmetic and fast robust geometric
#: predicates", 1997), taken four times over.
ORIENT_BOUND = 4.0 * (7.0 + 56.0 * 2.0 ** -53) * 2.0 ** -53

#: Shewchuk's bound for the 2D orientation determinant (``ccwerrboundA``), taken four times over.
SIDE_BOUND = 4.0 * (3.0 + 16.0 * 2.0 ** -53) * 2.0 ** -53

#: The grid's cells, in the mean of the triangles' longest box sides.
CELL_SIZE = 1.5

#: When the grid would hold more than this many (cell, triangle) entries per triangle on average (triangles of
#: very different sizes), no pair is proven apart: every triangle is returned, and the exact test takes them all.
MAX_ENTRIES_PER_FACE = 64


def possibly_crossing_faces(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The triangles in some pair whose boxes meet and that floating-point orientation tests cannot prove apart.

    Every pair of triangles that intersect (other than in a shared corner or a shared edge) has both triangles
    marked; the exact test of the marked triangles alone (their shared corners kept shared) finds every such
    pair of the whole surface.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64

    Returns
    -------
    possibly : (f,) bool
        True for a triangle in a pair not proven apart (a degenerate triangle, a pair sharing all three
        corners, a pair close to crossing or crossing); all True when the grid would be too large
        (:data:`MAX_ENTRIES_PER_FACE`).
    """
    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    if V.ndim != 2 or V.shape[1] != 3 or F.ndim != 2 or F.shape[1] != 3:
        raise ValueError(f"need (n, 3) vertices and (f, 3) faces, not {V.shape} and {F.shape}")
    if len(F) < 2:
        return np.zeros(len(F), bool)
    lo, hi = _boxes(V, F)
    origin = lo.min(axis=0)
    extent = float(np.max(hi.max(axis=0) - origin))
    if not np.isfinite(extent):
        return np.ones(len(F), bool)
    cell = CELL_SIZE * float(np.mean(np.max(hi - lo, axis=1)))
    cell = max(cell, extent / 2.0 ** 20, 1e-300)  # cell coordinates fit 21 bits each
    first, last, entries = _cells(lo, hi, origin, cell)
    if entries > MAX_ENTRIES_PER_FACE * len(F):
        return np.ones(len(F), bool)
    return _possibly(V, F, lo, hi, first, last, int(entries))


def _boxes(V, F):
    """(f, 3) float64 twice: each triangle's lowest and highest coordinates."""
    lo, hi = np.empty((len(F), 3)), np.empty((len(F), 3))
    over(_boxes_of, len(F), V, F, lo, hi)
    return lo, hi


@njit(cache=True, nogil=True)
def _boxes_of(V, F, lo, hi, t_lo, t_hi):
    """Fill ``lo`` and ``hi`` (f, 3) at the triangles ``t_lo:t_hi``: their lowest and highest coordinates."""
    for t in range(t_lo, t_hi):
        for d in range(3):
            a, b, c = V[F[t, 0], d], V[F[t, 1], d], V[F[t, 2], d]
            lo[t, d] = min(a, min(b, c))
            hi[t, d] = max(a, max(b, c))


def _cells(lo, hi, origin, cell):
    """The first and last grid cell of each triangle's box along each axis, (f, 3) int64 twice, and how many
    cells all the boxes cover (a float: up to 2 ** 60 cells a triangle)."""
    f = len(lo)
    first, last, count = np.empty((f, 3), np.int64), np.empty((f, 3), np.int64), np.empty(f)
    over(_cells_of, f, lo, hi, origin, float(cell), first, last, count)
    return first, last, count.sum()


@njit(cache=True, nogil=True)
def _cells_of(lo, hi, origin, cell, first, last, count, t_lo, t_hi):
    """Fill ``first``, ``last`` and ``count`` at the triangles ``t_lo:t_hi`` (see :func:`_cells`)."""
    for t in range(t_lo, t_hi):
        n = 1.0
        for d in range(3):
            first[t, d] = np.int64(np.floor((lo[t, d] - origin[d]) / cell))
            last[t, d] = np.int64(np.floor((hi[t, d] - origin[d]) / cell))
            n *= last[t, d] - first[t, d] + 1
        count[t] = n


@njit(cache=True)
def _sign(ux, uy, uz, vx, vy, vz, wx, wy, wz):
    """+1 or -1: the certain sign of the determinant of the columns ``u, v, w`` (each the rounded difference of two
    corners, as in an orientation test); 0 when the value computed in doubles is within its error bound."""
    vw, wv = vx * wy, wx * vy
    wu, uw = wx * uy, ux * wy
    uv, vu = ux * vy, vx * uy
    det = uz * (vw - wv) + vz * (wu - uw) + wz * (uv - vu)
    permanent = (abs(vw) + abs(wv)) * abs(uz) + (abs(wu) + abs(uw)) * abs(vz) + (abs(uv) + abs(vu)) * abs(wz)
    return _certain(det, ORIENT_BOUND * permanent)


@njit(cache=True)
def _certain(det, bound):
    """+1 or -1, the sign of ``det`` when it is farther from 0 than ``bound``; else 0."""
    if det > bound:
        return 1
    if -det > bound:
        return -1
    return 0


@njit(cache=True)
def _orientation(V, a, b, c, d):
    """The certain sign of corner ``d`` against the plane of corners ``a, b, c`` (0: not certain)."""
    return _sign(V[a, 0] - V[d, 0], V[a, 1] - V[d, 1], V[a, 2] - V[d, 2], V[b, 0] - V[d, 0], V[b, 1] - V[d, 1],
                 V[b, 2] - V[d, 2], V[c, 0] - V[d, 0], V[c, 1] - V[d, 1], V[c, 2] - V[d, 2])


@njit(cache=True)
def _across(V, p0, p1, q0, q1, c):
    """The certain side of corner ``c`` of the plane through corner ``p0`` along the edges ``p0 p1`` and
    ``q0 q1`` (0: not certain)."""
    return _sign(V[p1, 0] - V[p0, 0], V[p1, 1] - V[p0, 1], V[p1, 2] - V[p0, 2], V[q1, 0] - V[q0, 0],
                 V[q1, 1] - V[q0, 1], V[q1, 2] - V[q0, 2], V[c, 0] - V[p0, 0], V[c, 1] - V[p0, 1],
                 V[c, 2] - V[p0, 2])


@njit(cache=True)
def _one_side(V, F, i, j):
    """Whether every corner of triangle ``j`` not shared with triangle ``i`` lies strictly on one side of ``i``'s
    plane (False when all three are shared)."""
    side = 0
    for k in range(3):
        c = F[j, k]
        if c == F[i, 0] or c == F[i, 1] or c == F[i, 2]:
            continue
        s = _orientation(V, F[i, 0], F[i, 1], F[i, 2], c)
        if s == 0 or (side != 0 and s != side):
            return False
        side = s
    return side != 0


@njit(cache=True)
def _apart(V, F, i, j):
    """Whether triangles ``i`` and ``j`` are proven to meet at most in the corners or the edge they share.

    A plane that has one triangle on its closed side and the other's corners that are not on it strictly on the
    other side proves it: either triangle's own plane; for a pair sharing one corner, a plane through it and a
    further corner of each (the two meet only where their wedges at that corner do); for a pair sharing none,
    a plane along an edge of one and parallel to an edge of the other (with the triangles' planes, the axes
    that separate any two triangles that neither meet nor lie in one plane).
    """
    if _one_side(V, F, i, j) or _one_side(V, F, j, i):
        return True
    shared = np.int64(0)  # (not the literal 0: _apart_flat is compiled for one type of count, not two)
    for a in range(3):
        for b in range(3):
            if F[i, a] == F[j, b]:
                shared += 1
                ia, jb = a, b
    if shared == 1:
        v = F[i, ia]
        for a in range(1, 3):
            p, p_other = F[i, (ia + a) % 3], F[i, (ia + 3 - a) % 3]
            for b in range(1, 3):
                q, q_other = F[j, (jb + b) % 3], F[j, (jb + 3 - b) % 3]
                sp = _orientation(V, v, p, q, p_other)
                if sp != 0 and _orientation(V, v, p, q, q_other) == -sp:
                    return True
    if shared == 0:
        for a in range(3):
            p0, p1, p2 = F[i, a], F[i, (a + 1) % 3], F[i, (a + 2) % 3]
            for b in range(3):
                q0, q1 = F[j, b], F[j, (b + 1) % 3]
                side = _across(V, p0, p1, q0, q1, p2)
                if side == 0:
                    continue
                if (_across(V, p0, p1, q0, q1, F[j, 0]) == -side and _across(V, p0, p1, q0, q1, F[j, 1]) == -side
                        and _across(V, p0, p1, q0, q1, F[j, 2]) == -side):
                    return True
    return _apart_flat(V, F, i, j, shared)


@njit(cache=True)
def _side(V, a, b, c, x, y):
    """The certain side of corner ``c`` of the line through corners ``a, b`` in the coordinates ``x, y`` (0: not
    certain)."""
    left = (V[a, x] - V[c, x]) * (V[b, y] - V[c, y])
    right = (V[a, y] - V[c, y]) * (V[b, x] - V[c, x])
    return _certain(left - right, SIDE_BOUND * (abs(left) + abs(right)))


@njit(cache=True)
def _line_apart(V, F, i, j, a, b, x, y):
    """Whether, seen along the dropped coordinate, the line through corners ``a, b`` of triangle ``i`` has ``i``'s
    other corners strictly on one side and ``j``'s corners other than ``a`` and ``b`` strictly on the other."""
    side = 0
    for k in range(3):
        c = F[i, k]
        if c != a and c != b:
            side = _side(V, a, b, c, x, y)
    if side == 0:
        return False
    for k in range(3):
        c = F[j, k]
        if c != a and c != b and _side(V, a, b, c, x, y) != -side:
            return False
    return True


@njit(cache=True)
def _apart_flat(V, F, i, j, shared):
    """:func:`_apart` for pairs in (or close to) one plane, seen along the coordinate axis nearest ``i``'s normal:
    a line along an edge of one triangle (or, for a shared corner, through it and a further corner) with the
    triangles strictly on either side, in that view, proves the two apart but for what they share (the view of
    a triangle with a corner strictly off such a line is one to one)."""
    ex, ey, ez = V[F[i, 1], 0] - V[F[i, 0], 0], V[F[i, 1], 1] - V[F[i, 0], 1], V[F[i, 1], 2] - V[F[i, 0], 2]
    fx, fy, fz = V[F[i, 2], 0] - V[F[i, 0], 0], V[F[i, 2], 1] - V[F[i, 0], 1], V[F[i, 2], 2] - V[F[i, 0], 2]
    nx, ny, nz = abs(ey * fz - ez * fy), abs(ez * fx - ex * fz), abs(ex * fy - ey * fx)
    if nz >= nx and nz >= ny:
        x, y = 0, 1
    elif ny >= nx:
        x, y = 2, 0
    else:
        x, y = 1, 2
    if shared == 1:
        return _wedges_apart(V, F, i, j, x, y)
    for first, second in ((i, j), (j, i)):  # the lines of the edges (the shared edge's, for a shared edge)
        for k in range(3):
            if _line_apart(V, F, first, second, F[first, k], F[first, (k + 1) % 3], x, y):
                return True
    return False


@njit(cache=True)
def _wedges_apart(V, F, i, j, x, y):
    """Whether triangles ``i`` and ``j``, which share one corner, meet only there, seen in the coordinates
    ``x, y``: their wedges at the shared corner (each under half a turn) overlap exactly when one holds a side of
    the other, so each side of either must lie strictly outside the other's wedge."""
    for first, second in ((i, j), (j, i)):
        v, a1, a2 = F[first, 0], F[first, 1], F[first, 2]
        for k in range(3):
            c = F[first, k]
            if c == F[second, 0] or c == F[second, 1] or c == F[second, 2]:
                v, a1, a2 = c, F[first, (k + 1) % 3], F[first, (k + 2) % 3]
        turn = _side(V, v, a1, a2, x, y)
        back = _side(V, v, a2, a1, x, y)
        if turn == 0 or back == 0:
            return False
        for k in range(3):
            r = F[second, k]
            if r != v and _side(V, v, a1, r, x, y) != -turn and _side(V, v, a2, r, x, y) != -back:
                return False  # the side towards r may lie in the wedge
    return True


@njit(cache=True)
def _key(x, y, z):
    """A cell's coordinates (21 bits each) in one integer."""
    return (x << 42) | (y << 21) | z


@njit(cache=True)
def _bucket(key, bits, mask):
    """A cell's bucket of ``mask + 1 = 2 ** bits``: the top bits of its key times a large odd number (Fibonacci
    hashing: every bit of the key moves them)."""
    return ((key * 0x5851F42D4C957F2D) >> (64 - bits)) & mask


def _possibly(V, F, lo, hi, first, last, entries):
    """(f,) bool: the triangles of some pair in a common grid cell not proven apart (:func:`_apart`)."""
    f = len(F)
    size, bits = 1, 0
    while 2 * size < entries:
        size, bits = 2 * size, bits + 1
    counts = np.prod(last - first + 1, axis=1)
    offset = np.zeros(f + 1, np.int64)
    np.cumsum(counts, out=offset[1:])
    key = np.empty(entries, np.int64)
    owner = np.empty(entries, np.int32)
    over(_entries, f, first, last, offset, key, owner)
    start, grouped_key, grouped_owner = _grouped(key, owner, bits, size - 1)
    possibly = np.zeros(f, np.bool_)
    over(_pairs, size, V, F, lo, hi, first, start, grouped_key, grouped_owner, possibly)
    return possibly


@njit(cache=True, nogil=True)
def _entries(first, last, offset, key, owner, lo, hi):
    """Every (cell, triangle) entry of the triangles ``lo:hi``: ``key`` (the cell) and ``owner`` (the triangle)
    from ``offset[t]`` on."""
    for t in range(lo, hi):
        at = offset[t]
        for x in range(first[t, 0], last[t, 0] + 1):
            for y in range(first[t, 1], last[t, 1] + 1):
                for z in range(first[t, 2], last[t, 2] + 1):
                    key[at] = _key(x, y, z)
                    owner[at] = t
                    at += 1


@njit(cache=True, nogil=True)
def _grouped(key, owner, bits, mask):
    """The entries grouped by their cell's bucket (a counting sort): each bucket's first entry, ``(mask + 2,)``
    int64, then the keys and owners in that order."""
    entries = len(key)
    start = np.zeros(mask + 2, np.int64)
    for e in range(entries):
        start[_bucket(key[e], bits, mask)] += 1
    total = 0
    for b in range(mask + 2):
        total, start[b] = total + start[b], total
    grouped_key = np.empty(entries, np.int64)
    grouped_owner = np.empty(entries, np.int32)
    fill = start.copy()
    for e in range(entries):
        b = _bucket(key[e], bits, mask)
        grouped_key[fill[b]], grouped_owner[fill[b]] = key[e], owner[e]
        fill[b] += 1
    return start, grouped_key, grouped_owner


@njit(cache=True, nogil=True)
def _pairs(V, F, lo, hi, first, start, grouped_key, grouped_owner, possibly, b_lo, b_hi):
    """Mark in ``possibly`` both triangles of each pair of the buckets ``b_lo:b_hi`` not proven apart, each pair
    once (in the cell of its boxes' common lowest corner)."""
    for b in range(b_lo, b_hi):
        for p in range(start[b], start[b + 1]):
            i, k = grouped_owner[p], grouped_key[p]
            for q in range(p + 1, start[b + 1]):
                if grouped_key[q] != k:
                    continue
                j = grouped_owner[q]
                if _key(max(first[i, 0], first[j, 0]), max(first[i, 1], first[j, 1]),
                        max(first[i, 2], first[j, 2])) != k:
                    continue
                if (lo[i, 0] > hi[j, 0] or lo[j, 0] > hi[i, 0] or lo[i, 1] > hi[j, 1] or lo[j, 1] > hi[i, 1]
                        or lo[i, 2] > hi[j, 2] or lo[j, 2] > hi[i, 2]):
                    continue
                if not _apart(V, F, i, j):
                    possibly[i] = True
                    possibly[j] = True
