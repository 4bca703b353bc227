"""The support preview's columns as triangles: one box per column, or the outer surface of their union.

The ray grid's support columns (:func:`supportless.energies.support.support_columns`) stand side by side on a
square grid. Drawn as closed boxes, every pair of neighbours adds two walls inside the support's body; seen
through a translucent material those stacked inner walls are most of what a browser has to blend (a 40 000-triangle
character's preview took a software renderer 2-3 s a frame). :func:`column_shell` keeps only the outside: each
column's top and foot, and of each side wall the part no neighbour covers.
"""

from __future__ import annotations

import numpy as np

__all__ = ["column_boxes", "column_shell"]

# the four sides of a column: outward direction in the section's (u, w) coordinates
_SIDES = np.array([[1, 0], [-1, 0], [0, 1], [0, -1]], np.int64)


def column_boxes(bottoms: np.ndarray, heights: np.ndarray, cell: float, basis: np.ndarray):
    """Square columns as one triangle mesh (outward faces).

    Parameters
    ----------
    bottoms : (c, 3) float64
        The centre of each column's foot.
    heights : (c,) float64
    cell : float
        The side of each column's square section.
    basis : (3, 3) float64
        Rows: the section's two sides and the columns' direction, orthonormal and right-handed.

    Returns
    -------
    V : (8c, 3) float64
    F : (12c, 3) int64
    """
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0],
                        [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], np.float64)
    box = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                    [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]], np.int64)
    c = len(heights)
    local = np.broadcast_to(corners, (c, 8, 3)).copy()
    local[..., :2] *= cell / 2
    local[..., 2] *= np.asarray(heights, np.float64)[:, None]
    V = (np.asarray(bottoms, np.float64)[:, None, :] + local @ basis).reshape(-1, 3)
    F = (box[None] + 8 * np.arange(c)[:, None, None]).reshape(-1, 3)
    return V, F


def _quads(corners: np.ndarray):
    """Quads ``(q, 4, 3)`` (counter-clockwise seen from outside) as triangles: V (4q, 3), F (2q, 3)."""
    q = len(corners)
    F = (np.array([[0, 1, 2], [0, 2, 3]], np.int64)[None] + 4 * np.arange(q)[:, None, None]).reshape(-1, 3)
    return corners.reshape(-1, 3), F


def column_shell(bottoms: np.ndarray, heights: np.ndarray, cell: float, basis: np.ndarray):
    """The outer surface of a grid of columns: the walls between neighbours left out.

    Every column keeps its top and its foot. A side wall facing a neighbouring cell keeps the part of the column's
    span that no column of that cell covers: the whole wall toward an empty cell, the part above or below the
    neighbour's column toward a cell of one column. Where either cell holds more than one column (support standing
    on the model above other support) both walls are kept whole, as :func:`column_boxes` draws them: they face
    each other, so the enclosed volume is still the columns' own.

    Parameters
    ----------
    bottoms, heights, cell, basis
        As :func:`column_boxes`: ``bottoms @ basis.T`` puts each column's foot at the centre of a cell of a
        square grid of side ``cell`` (the ray grid's).

    Returns
    -------
    V : (v, 3) float64
    F : (f, 3) int64
        Outward triangles (not welded: neighbouring quads repeat their shared corners). The signed volume is
        ``heights.sum() * cell**2``; ``f <= 12 c``.
    """
    bottoms = np.asarray(bottoms, np.float64).reshape(-1, 3)
    heights = np.asarray(heights, np.float64).reshape(-1)
    basis = np.asarray(basis, np.float64)
    if len(heights) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    local = bottoms @ basis.T  # (u, w, foot) per column
    lo, hi = local[:, 2], local[:, 2] + heights
    eps = 1e-9 * max(float(cell), float(np.ptp(np.r_[lo, hi])))  # rounding of the frame change: the same height
    cells = np.rint((local[:, :2] - local[:, :2].min(axis=0)) / cell).astype(np.int64) + 1  # a ring of empty cells
    shape = tuple(cells.max(axis=0) + 2)
    count = np.zeros(shape, np.int64)
    np.add.at(count, (cells[:, 0], cells[:, 1]), 1)
    low, high = np.zeros(shape), np.zeros(shape)
    low[cells[:, 0], cells[:, 1]], high[cells[:, 0], cells[:, 1]] = lo, hi  # read only where count == 1
    single = count[cells[:, 0], cells[:, 1]] == 1
    h = cell / 2
    quads = []
    ring = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], np.float64) * h  # counter-clockwise seen from +up
    for z, order in ((hi, [0, 1, 2, 3]), (lo, [0, 3, 2, 1])):  # the tops face up, the feet down
        q = np.empty((len(z), 4, 3))
        q[..., :2] = local[:, None, :2] + ring[order]
        q[..., 2] = z[:, None]
        quads.append(q)
    for side in _SIDES:
        n = cells + side
        k = count[n[:, 0], n[:, 1]]
        nlo, nhi = low[n[:, 0], n[:, 1]], high[n[:, 0], n[:, 1]]
        exact = single & (k == 1)
        apart = exact & ((nlo >= hi - eps) | (nhi <= lo + eps))
        whole = ~exact | apart
        below = exact & ~apart & (nlo > lo + eps)  # the part under the neighbour's column
        above = exact & ~apart & (nhi < hi - eps)  # the part over it
        spans = [(whole, lo, hi), (below, lo, nlo), (above, nhi, hi)]
        t = np.array([-side[1], side[0]], np.float64)  # along the wall, so that (t, up) turns toward side
        for mask, z0, z1 in spans:
            idx = np.flatnonzero(mask)
            if len(idx) == 0:
                continue
            foot = local[idx, :2] + side * h
            q = np.empty((len(idx), 4, 3))
            q[:, 0, :2], q[:, 1, :2] = foot - t * h, foot + t * h
            q[:, 2, :2], q[:, 3, :2] = q[:, 1, :2], q[:, 0, :2]
            q[:, 0, 2] = q[:, 1, 2] = z0[idx]
            q[:, 2, 2] = q[:, 3, 2] = z1[idx]
            quads.append(q)
    V, F = _quads(np.concatenate(quads))
    return V @ basis, F
