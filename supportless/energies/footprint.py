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

__all__ = ["FIRST_LAYER_MM", "footprint_area", "section_area"]

#: The first layer's height, mm (PrusaSlicer's and Cura's default): the plate contact is its section at half of it.
FIRST_LAYER_MM = 0.2


def section_area(vertices: np.ndarray, faces: np.ndarray, up: np.ndarray, above: float | np.ndarray) -> np.ndarray:
    """Area of the horizontal section of closed surfaces at ``above`` over their lowest points.

    Parameters
    ----------
    vertices : (P, n, 3) or (n, 3) float64
        Closed, outward oriented surfaces (one per pose), in the frame where ``up`` is up.
    faces : (f, 3) int64
    up : (3,) float64
        Unit direction the heights are measured along.
    above : float or (P,) float64
        Height of the section over each surface's lowest point, in the vertices' units.

    Returns
    -------
    area : (P,) float64 or float
        In the vertices' units squared; 0 where the plane misses the surface.
    """
    V = np.asarray(vertices, np.float64)
    single = V.ndim == 2
    V = V[None] if single else V
    F = np.asarray(faces, np.int64)
    up = np.asarray(up, np.float64) / np.linalg.norm(up)
    h = V @ up  # (P, n)
    level = h.min(axis=1) + np.broadcast_to(np.asarray(above, np.float64), (len(V),))
    s = h - level[:, None]  # (P, n): below the plane where negative
    sf = s[:, F]  # (P, f, 3)
    low = sf <= 0
    crossing = low.any(axis=2) & ~low.all(axis=2)  # faces the plane cuts (most faces are far above it)
    pose, face = np.nonzero(crossing)
    area = np.zeros(len(V))
    if len(pose):
        corners = V[pose[:, None], F[face]]  # (k, 3, 3)
        sk = sf[pose, face]  # (k, 3)
        ends = []
        for a, b in ((0, 1), (1, 2), (2, 0)):
            sa, sb = sk[:, a], sk[:, b]
            cut = (sa <= 0) != (sb <= 0)
            t = np.where(cut, sa / np.where(cut, sa - sb, 1.0), 0.0)
            ends.append((cut, corners[:, a] + t[:, None] * (corners[:, b] - corners[:, a])))
        # a cut face has exactly two cut edges: the first and the last of them
        first = np.where(ends[0][0][:, None], ends[0][1], ends[1][1])
        second = np.where(ends[2][0][:, None], ends[2][1], ends[1][1])
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        along = np.cross(up, normal)  # the counter-clockwise way round the section, seen from above
        sign = np.sign(np.einsum("kj,kj->k", second - first, along))
        shoelace = 0.5 * sign * (np.cross(first, second) @ up)
        area = np.bincount(pose, weights=shoelace, minlength=len(V))
    area = np.maximum(area, 0.0)
    return float(area[0]) if single else area


def footprint_area(vertices: np.ndarray, faces: np.ndarray, up: np.ndarray, mm_per_unit: float | np.ndarray,
                   first_layer_mm: float = FIRST_LAYER_MM) -> np.ndarray:
    """The first layer's contact with the plate, mm²: the section at half a first layer over the lowest point.

    Parameters
    ----------
    vertices : (P, n, 3) or (n, 3) float64
        Closed, outward oriented surfaces as printed (``up`` up).
    faces : (f, 3) int64
    up : (3,) float64
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
