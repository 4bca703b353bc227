"""Shewchuk's Triangle (free for non-commercial use only): a quality triangulation of a planar outline.

Every call to Triangle (reached through ``igl.triangle``) lives in this module
and nowhere else. It sits in the licence corner, below the stages that use it:
the built-in 2D figure (:mod:`supportless.shapes.classic`) is meshed with it,
and :mod:`supportless.rig.tetmesh` hands it on under its old name.
"""

from __future__ import annotations

import numpy as np

__all__ = ["triangulate_planar"]


def triangulate_planar(points: np.ndarray, segments: np.ndarray, max_area: float,
                       min_angle: float = 28.0) -> tuple[np.ndarray, np.ndarray]:
    """Quality triangulation of a planar straight-line graph (Triangle).

    Parameters
    ----------
    points : (k, 2) float64
        Outline and interior points; all are kept as vertices.
    segments : (s, 2) int64
        Edges that must appear (the outline, the bones), not split.
    max_area : float
        Largest triangle area.
    min_angle : float
        Smallest angle in degrees.

    Returns
    -------
    vertices : (n, 2) float64
    faces : (f, 3) int64
    """
    import igl.triangle

    V, F, _, _, _ = igl.triangle.triangulate(np.asarray(points, np.float64), np.asarray(segments, np.int64),
                                             flags=f"pq{min_angle:g}a{max_area:g}YQ")
    return np.asarray(V, np.float64), np.asarray(F, np.int64)
