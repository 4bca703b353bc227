"""Self-intersection volume by ray casting along the printing direction.

A regular grid of rays parallel to ``up`` is cast through the model's
footprint (the bounding box of the vertices projected onto the plane
orthogonal to ``up``).  Along each ray the surface crossings are sorted by
height; going up, a face with ``n . up < 0`` enters material (+1) and one
with ``n . up > 0`` leaves it (-1).  The length along which the running count
is at least 2 is summed over rays and multiplied by the cell area.  The rays
and their crossing rule are those of :mod:`supportless.energies.raygrid`.
"""

from __future__ import annotations

from .raygrid import DEFAULT_RESOLUTION, ray_grid
from .surface import prepare

__all__ = ["self_intersection_volume", "DEFAULT_RESOLUTION"]


def self_intersection_volume(vertices, faces, up, resolution=DEFAULT_RESOLUTION, backend="fast"):
    """Volume (area in 2D) of the regions covered by two or more layers.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Deformed vertex positions, ``d`` in {2, 3}.
    faces : (f, 3) int
        Consistently oriented triangles of a closed surface (3D), or of a
        planar region whose boundary edges are the surface (2D).  Either
        winding is accepted (sign of the total signed volume/area).
    up : str or (d,) array_like of float
        Printing direction: ``"x"`` ... ``"-z"``, ``"0,1,0"`` or a vector
        (:func:`supportless.energies.surface.prepare`).
    resolution : int
        Number of square ray cells along the longer side of the footprint
        (default 192, i.e. up to 192 x 192 rays in 3D, 192 rays in 2D).
        Rays start at cell centres; a ray through a shared edge or vertex is
        counted once (half-open rule with symbolic perturbation).  At the
        default the error on the test shapes (overlapping boxes, overlapping
        spheres, a limb swung into a body, squares) is below 2 % (max measured
        1.8 %); in general the error is about one cell over the width of the
        overlapping region.  Cost grows with ``resolution**2``.
    backend : {"fast", "numpy"}
        ``fast``: numba kernel, parallel over poses, sweeping only the rays
        with four or more crossings; ``numpy``: the plain numpy reference
        (same crossings; equal up to round-off in the sums).

    Returns
    -------
    volume : (P,) float64 or float
        Self-intersection volume per pose (0 for a clean closed surface).
    """
    V, F, u, single = prepare(vertices, faces, up)
    res = ray_grid(V, F, u, resolution, 1.0, backend=backend, support=False)[:, 0]
    return float(res[0]) if single else res
