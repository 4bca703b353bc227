"""The ray grid: self-intersection volume and column support volume in one sweep.

The self-intersection volume (:mod:`supportless.energies.intersection`) and
the column support estimator (:mod:`supportless.energies.support`) both cast
a regular grid of rays along the printing direction ``up`` through the
model's footprint, collect every surface crossing along each ray, sort the
crossings by height and sweep upwards.  Both quantities come out of one
sweep, so :func:`ray_grid` computes them together.

Coordinates
-----------
Vertices are first expressed in a right-handed orthonormal frame whose last
axis is ``up`` (:func:`supportless.energies.surface.to_frame`): ``(u, w, z)``
in 3D and ``(u, z)`` in 2D.  Since the change of frame is a rotation,
orientations (triangle winding, signed areas) are kept.  In 3D, ``resolution``
square cells span the longer side of the footprint's bounding rectangle and
the grid is centred on it (:func:`._grid_common.grid_layout`); in 2D,
``resolution`` cells split the footprint interval.  Rays start at cell centres.

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

Sweep
-----
Going up a ray, a face with ``n . up < 0`` enters material and one with
``n . up > 0`` leaves it.  The length along which at least two layers are
entered is the self-intersection; a risky face (``n . up < -tau``) met from
air needs a column down to the crossing below it or to the build plate (the
lowest vertex).  Lengths times the cell area (length in 2D) give volumes.

Implementations
---------------
* :mod:`._grid_reference`: reference numba kernels, parallel over poses
  (``backend="fast"`` in 2D; the fallback of the fast kernel in 3D);
* :mod:`._grid_fast`: the fast 3D numba kernel (``backend="fast"``), the
  same crossings and sweep as the reference, so bit-identical results;
* :mod:`._grid_numpy`: plain numpy (``backend="numpy"``), the same crossings,
  sums in another order (equal up to round-off);
* :mod:`._grid_common`: the pieces they share.

Numba's on-disk cache (``cache=True``) checks only the file of each kernel:
after editing a helper that a kernel in another file calls
(:mod:`._grid_common`, :func:`.surface.signed_volume3`), delete the cache
files ``supportless/energies/__pycache__/*.nb[ci]``.
"""

from __future__ import annotations

import numpy as np

from . import _grid_fast, _grid_numpy, _grid_reference
from .surface import boundary_edges, check_backend, orientation_sign, to_frame

__all__ = ["DEFAULT_RESOLUTION", "ray_grid"]

#: Default number of square ray cells along the longer side of the footprint.
#: At 192 the relative error on the test shapes (rotated overlapping boxes,
#: overlapping spheres, a limb swung into a body, tilted-arm support) is at
#: most 1.8 %; in general it is about one cell over the feature width.
DEFAULT_RESOLUTION = 192


def ray_grid(V, F, up, resolution, tau, backend="fast", support=True):
    """Cast the ray grid for a batch of poses.

    Parameters
    ----------
    V : (P, n, d) float64
        C-contiguous batched vertices, ``d`` in {2, 3}
        (:func:`supportless.energies.surface.prepare`).
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
    tau = float(tau)
    if backend == "fast" and V.shape[-1] == 3:
        return _grid_fast.ray_grid3_fast(V, F, up, R, tau, support)
    orient = np.ascontiguousarray(orientation_sign(V, F, backend))
    X = to_frame(V, up)
    if backend == "fast":
        return _grid_reference.grid_batch(X, boundary_edges(F), orient, R, tau)
    if V.shape[-1] == 3:
        out = [_grid_numpy.pose3_numpy(x, F, o, R, tau, support) for x, o in zip(X, orient)]
    else:
        E = boundary_edges(F)
        out = [_grid_numpy.pose2_numpy(x, E, o, R, tau) for x, o in zip(X, orient)]
    return np.array(out).reshape(-1, 2)
