"""The first layer's contact with the plate: the area a print rests on.

A slicer's first layer is the section of the solid at half a layer above the plate (PrusaSlicer slices each layer
at its middle). A print that touches the plate at a tip has almost no first layer: PrusaSlicer then refuses to slice
it without supports ("no extrusions in the first layer"), and with supports it stands on a few square millimetres.
:func:`section_area` measures a closed surface's horizontal section at a height above its lowest point, batched over
poses; :func:`footprint_area` is that section at half a first layer.

For a closed, outward oriented surface the section is a set of closed polygons whose edges are the crossings of the
triangles with the plane. Each crossing segment, run so that the face's outward normal is on its right (seen from
above), is an edge of those polygons run counter-clockwise; the polygons' area is then the shoelace sum
``1/2 up · Σ p × q`` over the segments — holes (a ring's inside) subtract themselves.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..base.threads import over

__all__ = ["FIRST_LAYER_MM", "footprint_area", "section_area"]

#: The first layer's height, mm (PrusaSlicer's and Cura's default): the plate contact is its section at half of it.
FIRST_LAYER_MM = 0.2


def section_area(vertices: np.ndarray, faces: np.ndarray, up: np.ndarray, above: float | np.ndarray) -> np.ndarray:
    """Area of the horizontal section of closed surfaces at ``above`` over their lowest points.

    Parameters
    ----------
    vertices : (P, n, 3) or (n, 3) float64
        Closed, outward oriented surfaces (one per pose).
    faces : (f, 3) int64
    up : (3,) or (P, 3) float64
        Direction the heights are measured along, one for all poses or one per pose (normalised here). A turned
        pose ``V @ R.T`` measured along ``up`` is the pose ``V`` measured along ``R.T @ up``: the search passes
        that direction instead of turning its poses.
    above : float or (P,) float64
        Height of the section over each surface's lowest point, in the vertices' units.

    Returns
    -------
    area : (P,) float64 or float
        In the vertices' units squared; 0 where the plane misses the surface.
    """
    V = np.asarray(vertices, np.float64)
    single = V.ndim == 2
    V = np.ascontiguousarray(V[None] if single else V)
    U = np.broadcast_to(np.asarray(up, np.float64), (len(V), 3))
    U = np.ascontiguousarray(U / np.linalg.norm(U, axis=1, keepdims=True))
    level = np.broadcast_to(np.asarray(above, np.float64), (len(V),)).copy()  # writable: one compiled kernel
    area = _sections(V, np.ascontiguousarray(faces, np.int64), U, level)
    return float(area[0]) if single else area


def _sections(V, F, U, above):
    """(P,) float64: :func:`section_area` of ``V`` (P, n, 3) along ``U`` (P, 3) unit at ``above`` (P,)."""
    out = np.zeros(len(V))
    over(_sections_of, len(V), V, F, U, above, out)
    return out


@njit(cache=True, nogil=True)
def _sections_of(V, F, U, above, out, lo, hi):
    """Fill ``out`` (P,) at the poses ``lo:hi`` (see :func:`_sections`).

    Each cut face adds ``1/2 sign (p x q) . u`` for the segment ``pq`` where the plane cuts it, ``sign`` turning the
    segment so that the face's outward normal is on its right seen from above (counter-clockwise round the section).
    """
    n = V.shape[1]
    for p in range(lo, hi):
        ux, uy, uz = U[p, 0], U[p, 1], U[p, 2]
        h = np.empty(n)
        low = np.inf
        for i in range(n):
            h[i] = V[p, i, 0] * ux + V[p, i, 1] * uy + V[p, i, 2] * uz
            low = min(low, h[i])
        level = low + above[p]
        area = 0.0
        for f in range(F.shape[0]):
            a, b, c = F[f, 0], F[f, 1], F[f, 2]
            sa, sb, sc = h[a] - level, h[b] - level, h[c] - level
            below = (sa <= 0.0) + (sb <= 0.0) + (sc <= 0.0)
            if below == 0 or below == 3:
                continue
            # the two cut edges in the order ab, bc, ca: the first (f) and the last (s) of them
            fx = fy = fz = sx = sy = sz = 0.0
            first = True
            for i, j, si, sj in ((a, b, sa, sb), (b, c, sb, sc), (c, a, sc, sa)):
                if (si <= 0.0) != (sj <= 0.0):
                    t = si / (si - sj)
                    x = V[p, i, 0] + t * (V[p, j, 0] - V[p, i, 0])
                    y = V[p, i, 1] + t * (V[p, j, 1] - V[p, i, 1])
                    z = V[p, i, 2] + t * (V[p, j, 2] - V[p, i, 2])
                    if first:
                        fx, fy, fz, first = x, y, z, False
                    else:
                        sx, sy, sz = x, y, z
            e1x, e1y, e1z = V[p, b, 0] - V[p, a, 0], V[p, b, 1] - V[p, a, 1], V[p, b, 2] - V[p, a, 2]
            e2x, e2y, e2z = V[p, c, 0] - V[p, a, 0], V[p, c, 1] - V[p, a, 1], V[p, c, 2] - V[p, a, 2]
            nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
            ax_, ay_, az_ = uy * nz - uz * ny, uz * nx - ux * nz, ux * ny - uy * nx  # up x normal
            run = (sx - fx) * ax_ + (sy - fy) * ay_ + (sz - fz) * az_
            sign = 1.0 if run > 0.0 else (-1.0 if run < 0.0 else 0.0)
            cross_u = (fy * sz - fz * sy) * ux + (fz * sx - fx * sz) * uy + (fx * sy - fy * sx) * uz
            area += 0.5 * sign * cross_u
        out[p] = max(area, 0.0)


def footprint_area(vertices: np.ndarray, faces: np.ndarray, up: np.ndarray, mm_per_unit: float | np.ndarray,
                   first_layer_mm: float = FIRST_LAYER_MM) -> np.ndarray:
    """The first layer's contact with the plate, mm²: the section at half a first layer over the lowest point.

    Parameters
    ----------
    vertices : (P, n, 3) or (n, 3) float64
        Closed, outward oriented surfaces as printed (``up`` up).
    faces : (f, 3) int64
    up : (3,) or (P, 3) float64
        One direction, or one per pose (:func:`section_area`).
    mm_per_unit : float or (P,) float64
        Millimetres per unit of ``vertices`` at the printed size.
    first_layer_mm : float
        The first layer's height.

    Returns
    -------
    area_mm2 : (P,) float64 or float
    """
    k = np.asarray(mm_per_unit, np.float64)
    area = section_area(vertices, faces, up, 0.5 * first_layer_mm / k)
    return area * k ** 2
