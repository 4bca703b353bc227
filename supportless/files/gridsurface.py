"""A closed surface remade on a grid: inside by winding number (counted along the grid's columns when the input is
closed), placed by distance, by marching cubes.

What a body whose shells cross each other is remade as when an exact union cannot make it one
(:func:`supportless.files.crossings.winding_surface`), and what a sculpt's proxy is collapsed from
(:func:`supportless.files.simplify.simplify_surface`): closed, never crossing itself, even triangles.
"""

from __future__ import annotations

import numpy as np

from .surfaceops import _components, _is_closed, _volume

__all__ = ["ISLAND_MIN_VOLUME", "grid_surface", "winding_by_columns"]

#: Solids still apart after bridging below this fraction of the volume are
#: dropped (eyes floating in front of a face would print in the air); larger
#: ones are kept as separate pieces, with a warning. Pockets and crumbs of a
#: winding-number surface below it go too.
ISLAND_MIN_VOLUME = 0.01


#: Grid points nearer the surface than this fraction of a cell get libigl's winding number, not the count along
#: their column: the columns run 3e-7 of a cell off the grid points (:func:`winding_by_columns`).
ON_SURFACE = 1e-6


def winding_by_columns(V: np.ndarray, F: np.ndarray, axes) -> np.ndarray:
    """The winding number of a closed surface at the points of a grid, counted along the grid's columns (parallel
    to z): each crossing below a point adds +1 where the surface faces down (the column enters) and -1 where it
    faces up.

    On a closed, consistently oriented surface (every edge shared by two faces in opposite directions) this is the
    winding number exactly, shells crossing or overlapping each other included, and a small fraction of the
    generalized winding number's time on a fine grid: each triangle meets only the columns under its shadow. The
    columns are moved by a hair (1e-7 of a cell) off the grid's lines, so that none runs exactly along a
    triangle's edge.

    Parameters
    ----------
    V : (n, 3) float64
    F : (f, 3) int64
        Closed and consistently oriented (outward: the winding number is 1 inside).
    axes : list of three (k_i,) float64
        The grid's x, y and z coordinates, evenly spaced.

    Returns
    -------
    winding : (k_z, k_y, k_x) int64
    """
    xs, ys, zs = (np.asarray(a, np.float64) for a in axes)
    step = [float(a[1] - a[0]) for a in (xs, ys, zs)]
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    corners = np.stack([A, B, C], axis=1)
    ox, oy = xs[0] + 1e-7 * np.pi * step[0], ys[0] + 1e-7 * np.e * step[1]  # the columns, off the lines
    i0 = np.ceil((corners[:, :, 0].min(1) - ox) / step[0]).astype(np.int64)
    i1 = np.floor((corners[:, :, 0].max(1) - ox) / step[0]).astype(np.int64)
    j0 = np.ceil((corners[:, :, 1].min(1) - oy) / step[1]).astype(np.int64)
    j1 = np.floor((corners[:, :, 1].max(1) - oy) / step[1]).astype(np.int64)
    wide, deep = np.maximum(i1 - i0 + 1, 0), np.maximum(j1 - j0 + 1, 0)
    count = wide * deep
    tri = np.repeat(np.arange(len(F)), count)
    k = np.arange(len(tri)) - np.repeat(np.cumsum(count) - count, count)  # index within each triangle's shadow
    i = i0[tri] + k % wide[tri]
    j = j0[tri] + k // wide[tri]
    px, py = ox + step[0] * i, oy + step[1] * j
    a, b, c = A[tri], B[tri], C[tri]
    d = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    u = ((b[:, 0] - px) * (c[:, 1] - py) - (c[:, 0] - px) * (b[:, 1] - py)) / np.where(d == 0, 1.0, d)
    v = ((c[:, 0] - px) * (a[:, 1] - py) - (a[:, 0] - px) * (c[:, 1] - py)) / np.where(d == 0, 1.0, d)
    w = 1.0 - u - v
    hit = (d != 0) & (u >= 0) & (v >= 0) & (w >= 0)
    z = u * a[:, 2] + v * b[:, 2] + w * c[:, 2]
    above = np.ceil((z[hit] - zs[0]) / step[2]).astype(np.int64)  # the first grid point over the crossing
    keep = above < len(zs)
    sign = np.where(d[hit][keep] < 0, 1, -1)  # d is twice the area seen from above: < 0 faces down
    crossings = np.zeros((len(zs) + 1, len(ys), len(xs)), np.int64)
    np.add.at(crossings, (np.maximum(above[keep], 0), j[hit][keep], i[hit][keep]), sign)
    return np.cumsum(crossings, axis=0)[:-1]


def _near_and_distance(inside: np.ndarray, grid: np.ndarray, V: np.ndarray, F: np.ndarray):
    """The grid points with a neighbour across the surface, (k_z, k_y, k_x) bool, and their squared distances to
    (V, F), (k,) float64 in the grid's order."""
    import igl

    near = np.zeros_like(inside)
    for axis in range(3):
        change = np.diff(inside, axis=axis)
        lower = [slice(None)] * 3
        upper = [slice(None)] * 3
        lower[axis], upper[axis] = slice(0, -1), slice(1, None)
        near[tuple(lower)] |= change
        near[tuple(upper)] |= change
    return near, igl.point_mesh_squared_distance(np.ascontiguousarray(grid[near.ravel()]), V, F)[0]


def grid_surface(V, F, cells: int, closed: bool | None = None):
    """The outer surface of (V, F) remade by marching cubes: inside by winding number, placed by distance.

    Inside is where the shells wind around a point at least once, so
    overlapping and crossing shells are one solid; the field marching cubes
    meets is that sign times the distance to the surface (computed at the
    grid points next to a change of sign: the others only need their sign),
    so the surface is as smooth as the input, not a staircase of cells. On a
    grid of ``cells`` along the longest side; closed, manifold, never crossing
    itself. Deterministic. The winding number is counted along the grid's
    columns (:func:`winding_by_columns`) when (V, F) is closed and
    consistently oriented, and is libigl's fast winding number (at least half
    a turn) otherwise: the two agree on a closed surface, and counting is a
    small fraction of the time.

    Parameters
    ----------
    V : (n, 3) float64
    F : (f, 3) int64
    cells : int
        Grid cells along the longest side.
    closed : bool, optional
        Whether (V, F) is known to be closed and consistently oriented; checked when not given.

    Returns
    -------
    vertices : (k, 3) float64
    faces : (g, 3) int64
        Outward.
    """
    import igl

    lo, hi = V.min(0), V.max(0)
    h = float((hi - lo).max()) / cells
    lo, hi = lo - 2 * h, hi + 2 * h
    nx, ny, nz = (np.ceil((hi - lo) / h).astype(np.int64) + 1).tolist()
    axes = [lo[i] + h * np.arange(n) for i, n in enumerate((nx, ny, nz))]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).transpose(2, 1, 0, 3).reshape(-1, 3)  # x fastest
    if closed if closed is not None else _is_closed(F):
        outward = 1 if _volume(V, F) >= 0 else -1
        inside = winding_by_columns(V, F, axes) * outward > 0
        near, d2 = _near_and_distance(inside, grid, V, F)
        # a point within a hair of the surface may be on the other side of it from its column, moved by that hair:
        # libigl's winding number decides those few, as it decides every point of an open surface
        on = np.flatnonzero(near.ravel())[d2 <= (ON_SURFACE * h) ** 2]
        decided = igl.fast_winding_number(V, F, np.ascontiguousarray(grid[on])) > 0.5
        if np.any(decided != inside.ravel()[on]):
            inside = inside.ravel()
            inside[on] = decided
            inside = inside.reshape(nz, ny, nx)
            near, d2 = _near_and_distance(inside, grid, V, F)
    else:
        inside = (igl.fast_winding_number(V, F, np.ascontiguousarray(grid)) > 0.5).reshape(nz, ny, nx)
        near, d2 = _near_and_distance(inside, grid, V, F)
    field = np.full(inside.shape, 2.0 * h)
    field[near] = np.minimum(np.sqrt(d2), 2.0 * h)
    # no grid point exactly on the surface: marching cubes would put a vertex on it, shared by needle triangles
    field = np.maximum(field, 1e-2 * h)
    field = np.where(inside, -field, field).ravel()
    out = igl.marching_cubes(np.ascontiguousarray(field), grid, nx, ny, nz, 0.0)
    Vs, Fs = np.asarray(out[0], np.float64), np.asarray(out[1], np.int64)
    if len(Fs) and _volume(Vs, Fs) < 0:
        Fs = Fs[:, ::-1]
    # pockets the winding number left inside (closed voids) and crumbs go: a print body is solid
    comp = _components(Fs, len(Vs))
    vols = np.array([_volume(Vs, Fs[comp == c]) for c in range(comp.max() + 1)]) if len(Fs) else np.zeros(0)
    Fs = Fs[vols[comp] >= ISLAND_MIN_VOLUME * vols[vols > 0].sum()] if len(Fs) else Fs
    used = np.unique(Fs)
    remap = np.full(len(Vs), -1, np.int64)
    remap[used] = np.arange(len(used))
    Vs, Fs = Vs[used], remap[Fs]
    return Vs, Fs
