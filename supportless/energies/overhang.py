"""Overhang (prism) energy.

A surface element ``f`` (a triangle in 3D, a boundary edge of a planar
triangle mesh in 2D) with unit outward normal ``n_f`` is *risky* when

    n_f . up < -tau,    tau = cos(theta),

where ``theta`` (``overhang_angle``, degrees) is the threshold slope measured
from the build plate: a downward-facing element tilted less than ``theta``
from horizontal needs support.  Its support is approximated by a prism

    lambda(f) = A_f * |n_f . up| * h_f,

with ``A_f`` the area (length in 2D) and ``h_f`` the height of the element's
centroid above the build plate, the lowest vertex of the same pose along
``up``.  The energy is the sum of ``lambda`` over risky elements;
:func:`projected_risky_area` sums ``A_f |n_f . up|`` (the prism without its
height) and :func:`risky_area` sums ``A_f``.

Outward orientation is taken from the sign of the total signed volume (3D)
or signed area (2D) of each pose, so either consistent winding works.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..base.threads import over
from ..files.printer import SEARCH_OVERHANG_ANGLE
from .surface import boundary_edges, check_backend, orientation_sign, prepare

__all__ = ["overhang_energy", "overhang_measures", "risky_faces", "risky_area", "projected_risky_area"]


def _per_pose(kernel, V, S, up, orient, tau, mask, floor):
    """``kernel`` (:func:`_kernel3_poses` or :func:`_kernel2_poses`) over every pose of ``V``, split over threads:
    (P, 2) float64."""
    out = np.zeros((V.shape[0], 2), np.float64)
    over(kernel, len(V), V, S, up, orient, float(tau), mask, float(floor), out)
    return out


@njit(cache=True, nogil=True)
def _kernel3_poses(V, F, up, orient, tau, mask, floor, out, lo, hi):
    """Energy and risky area of the poses ``lo:hi`` (3D).

    ``V`` (P, n, 3) float64 poses, ``F`` (f, 3) int64, ``up`` (P, 3) float64
    unit, one per pose, ``orient`` (P,) float64 orientation signs; fills ``mask`` (P, f)
    bool with the risky faces and ``out`` (P, 2) float64 with [energy, risky area].
    """
    for p in range(lo, hi):
        ux, uy, uz = up[p, 0], up[p, 1], up[p, 2]
        X = V[p]
        plate = np.inf
        for i in range(X.shape[0]):
            plate = min(plate, X[i, 0] * ux + X[i, 1] * uy + X[i, 2] * uz)
        e = 0.0
        ra = 0.0
        for f in range(F.shape[0]):
            a = F[f, 0]
            b = F[f, 1]
            c = F[f, 2]
            e1x = X[b, 0] - X[a, 0]
            e1y = X[b, 1] - X[a, 1]
            e1z = X[b, 2] - X[a, 2]
            e2x = X[c, 0] - X[a, 0]
            e2y = X[c, 1] - X[a, 1]
            e2z = X[c, 2] - X[a, 2]
            nx = e1y * e2z - e1z * e2y
            ny = e1z * e2x - e1x * e2z
            nz = e1x * e2y - e1y * e2x
            dbl = np.sqrt(nx * nx + ny * ny + nz * nz)
            risky = False
            if dbl > 0.0:
                proj = orient[p] * (nx * ux + ny * uy + nz * uz)
                if proj < -tau * dbl:
                    risky = True
                    h = ((X[a, 0] + X[b, 0] + X[c, 0]) * ux
                         + (X[a, 1] + X[b, 1] + X[c, 1]) * uy
                         + (X[a, 2] + X[b, 2] + X[c, 2]) * uz) / 3.0 - plate + floor
                    # A |n.d| h = |cross . d| / 2 * h
                    e += -0.5 * proj * h
                    ra += 0.5 * dbl
            mask[p, f] = risky
        out[p, 0] = e
        out[p, 1] = ra


@njit(cache=True, nogil=True)
def _kernel2_poses(V, E, up, orient, tau, mask, floor, out, lo, hi):
    """Energy and risky length of the poses ``lo:hi`` (2D).

    ``V`` (P, n, 2) float64 poses, ``E`` (e, 2) int64 boundary edges
    (:func:`.surface.boundary_edges`), ``up`` (P, 2) float64 unit, one per pose, ``orient``
    (P,) float64; fills ``mask`` (P, e) bool with the risky edges and ``out`` (P, 2) float64 with
    [energy, risky length].
    """
    for p in range(lo, hi):
        ux, uy = up[p, 0], up[p, 1]
        X = V[p]
        plate = np.inf
        for i in range(X.shape[0]):
            plate = min(plate, X[i, 0] * ux + X[i, 1] * uy)
        e = 0.0
        rl = 0.0
        for k in range(E.shape[0]):
            a = E[k, 0]
            b = E[k, 1]
            tx = X[b, 0] - X[a, 0]
            ty = X[b, 1] - X[a, 1]
            ln = np.sqrt(tx * tx + ty * ty)
            risky = False
            if ln > 0.0:
                # outward normal of a counter-clockwise boundary: (ty, -tx)
                proj = orient[p] * (ty * ux - tx * uy)
                if proj < -tau * ln:
                    risky = True
                    h = 0.5 * ((X[a, 0] + X[b, 0]) * ux + (X[a, 1] + X[b, 1]) * uy) - plate + floor
                    e += -proj * h
                    rl += ln
            mask[p, k] = risky
        out[p, 0] = e
        out[p, 1] = rl


def _numpy(V, F, u, orient, tau, floor=0.0):
    """Plain numpy version of the kernels, poses in chunks of bounded memory.

    Same arguments as :func:`_kernel3_poses` (faces ``F``; boundary edges taken
    here in 2D); returns ((P, 2) float64 [energy, risky measure], (P, m) bool mask).
    """
    P = V.shape[0]
    d = V.shape[-1]
    E = F if d == 3 else boundary_edges(F)
    U = np.broadcast_to(u, (P, d))
    out = np.zeros((P, 2))
    mask = np.zeros((P, E.shape[0]), np.bool_)
    chunk = max(1, 2_000_000 // max(1, E.shape[0]))
    for s in range(0, P, chunk):  # bounded memory: poses in chunks
        X = V[s:s + chunk]
        u = U[s:s + chunk, None, :]  # (p, 1, d): each pose's direction

        def along(A):
            return np.sum(A * u, axis=-1)

        o = orient[s:s + chunk, None]
        plate = along(X).min(axis=1)[:, None]
        if d == 3:
            a, b, c = X[:, E[:, 0]], X[:, E[:, 1]], X[:, E[:, 2]]
            n = np.cross(b - a, c - a)  # doubled area times unit normal
            size = np.linalg.norm(n, axis=-1)
            proj = o * along(n)
            h = along(a + b + c) / 3.0 - plate + floor
            scale = 0.5
        else:
            a, b = X[:, E[:, 0]], X[:, E[:, 1]]
            t = b - a
            size = np.linalg.norm(t, axis=-1)
            proj = o * (t[..., 1] * u[..., 0] - t[..., 0] * u[..., 1])  # outward normal (ty, -tx)
            h = 0.5 * along(a + b) - plate + floor
            scale = 1.0
        risky = (size > 0.0) & (proj < -tau * size)
        out[s:s + chunk, 0] = np.sum(np.where(risky, -scale * proj * h, 0.0), axis=1)
        out[s:s + chunk, 1] = np.sum(np.where(risky, scale * size, 0.0), axis=1)
        mask[s:s + chunk] = risky
    return out, mask


def _compute(vertices, faces, up, overhang_angle, backend="fast", floor=0.0, orient=None):
    """Check the arguments and run a backend.

    ``orient`` (+1/-1, or (P,) of them) is the winding of the faces when the
    caller knows it; otherwise it is measured per pose.

    Returns ((P, 2) float64 [energy, risky measure], (P, m) bool mask, single).
    """
    check_backend(backend)
    per_pose = np.ndim(up) == 2 and not isinstance(up, str)
    V, F, u, single = prepare(vertices, faces, up[0] if per_pose else up)
    if per_pose:  # (P, d): one direction per pose
        u = np.asarray(up, np.float64)
        u = np.ascontiguousarray(u / np.linalg.norm(u, axis=1, keepdims=True))
    tau = float(np.cos(np.deg2rad(float(overhang_angle))))
    if orient is None:
        orient = orientation_sign(V, F, backend)
    else:
        orient = np.broadcast_to(np.asarray(orient, np.float64), (V.shape[0],)).copy()
    if backend == "numpy":
        return (*_numpy(V, F, u, orient, tau, float(floor)), single)
    U = np.broadcast_to(u, (V.shape[0], V.shape[-1])).copy()  # writable, like every caller's: one compiled kernel
    if V.shape[-1] == 3:
        mask = np.zeros((V.shape[0], F.shape[0]), np.bool_)
        out = _per_pose(_kernel3_poses, V, F, U, orient, tau, mask, floor)
    else:
        E = boundary_edges(F)
        mask = np.zeros((V.shape[0], E.shape[0]), np.bool_)
        out = _per_pose(_kernel2_poses, V, E, U, orient, tau, mask, floor)
    return out, mask, single


def _out(x, single):
    """(P,) float64 ``x`` as given, or its one value as a float for a single pose."""
    return float(x[0]) if single else np.ascontiguousarray(x)


def risky_faces(vertices, faces, up, overhang_angle=SEARCH_OVERHANG_ANGLE, backend="fast"):
    """Mask of risky (support-needing) surface elements.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Deformed vertex positions, ``d`` in {2, 3}.
    faces : (f, 3) int
        Consistently oriented triangles of a closed surface (3D) or of a
        planar region (2D).
    up : str or (d,) array_like of float
        Printing direction: ``"x"`` ... ``"-z"``, ``"0,1,0"`` or a vector
        (:func:`supportless.energies.surface.prepare`).
    overhang_angle : float
        Threshold slope ``theta`` in degrees measured from the build plate;
        risky when ``n . up < -cos(theta)``.
    backend : {"fast", "numpy"}
        ``fast``: numba kernels (parallel over poses); ``numpy``: the plain
        numpy reference (same result up to round-off).

    Returns
    -------
    mask : (P, m) or (m,) bool
        ``m = f`` in 3D; in 2D ``m`` is the number of boundary edges, in the
        order of :func:`boundary_edges` ``(faces)``.
    """
    _, mask, single = _compute(vertices, faces, up, overhang_angle, backend)
    return mask[0] if single else mask


def risky_area(vertices, faces, up, overhang_angle=SEARCH_OVERHANG_ANGLE, backend="fast"):
    """Total area (length in 2D) of the risky surface elements.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Deformed vertex positions, ``d`` in {2, 3}.
    faces : (f, 3) int
        Consistently oriented triangles.
    up : str or (d,) array_like of float
        Printing direction: ``"x"`` ... ``"-z"``, ``"0,1,0"`` or a vector
        (:func:`supportless.energies.surface.prepare`).
    overhang_angle : float
        Threshold slope in degrees from the build plate (default: the default
        search's, :data:`~supportless.files.printer.SEARCH_OVERHANG_ANGLE`).
    backend : {"fast", "numpy"}
        ``fast``: numba kernels (parallel over poses); ``numpy``: the plain
        numpy reference (same result up to round-off).

    Returns
    -------
    area : (P,) float64 or float
        Sum of the areas (lengths) of risky elements per pose.
    """
    out, _, single = _compute(vertices, faces, up, overhang_angle, backend)
    return _out(out[:, 1], single)


def overhang_measures(vertices, faces, up, overhang_angle=SEARCH_OVERHANG_ANGLE, backend="fast"):
    """:func:`overhang_energy` and :func:`risky_area` of the same poses, from one pass over their faces.

    Parameters
    ----------
    vertices, faces, up, overhang_angle, backend
        As :func:`overhang_energy`.

    Returns
    -------
    energy : (P,) float64 or float
        :func:`overhang_energy` (no floor), the same value.
    area : (P,) float64 or float
        :func:`risky_area`, the same value.
    """
    out, _, single = _compute(vertices, faces, up, overhang_angle, backend)
    return _out(out[:, 0], single), _out(out[:, 1], single)


def overhang_energy(vertices, faces, up, overhang_angle=SEARCH_OVERHANG_ANGLE, backend="fast", floor=0.0, orient=None):
    """Prism overhang energy ``sum_f A_f |n_f . up| (h_f + floor)`` over risky faces.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Deformed vertex positions, ``d`` in {2, 3}.  The build plate of each
        pose is its lowest vertex along ``up``.
    faces : (f, 3) int
        Consistently oriented triangles (closed surface in 3D; planar region
        in 2D, whose boundary edges are the surface).
    up : str or (d,) array_like of float, or (P, d) float64
        Printing direction: ``"x"`` ... ``"-z"``, ``"0,1,0"`` or a vector
        (:func:`supportless.energies.surface.prepare`); or one per pose (a
        turned pose ``V @ R.T`` measured along ``up`` is ``V`` measured
        along ``R.T @ up``: the search passes that instead of turning).
    overhang_angle : float
        Threshold slope ``theta`` in degrees from the build plate (default:
        the default search's, 55.1); risky when ``n . up < -cos(theta)``.
    backend : {"fast", "numpy"}
        ``fast``: numba kernels (parallel over poses); ``numpy``: the plain
        numpy reference (same result up to round-off).
    floor : float
        Added to every prism's height (length units): what a support costs
        however low it is (its interface layers and base). 0 is the paper's
        estimate.
    orient : float or (P,) float64, optional
        +1 when the faces are outward oriented (counter-clockwise in 2D), -1
        when inverted, if the caller knows it (a rig's surface, posed);
        measured per pose when not given.

    Returns
    -------
    energy : (P,) float64 or float
        Approximate support volume (area in 2D) per pose.  Scales as ``s**3``
        (``s**2`` in 2D) under uniform scaling and is invariant under
        rotations about ``up`` and translations.
    """
    out, _, single = _compute(vertices, faces, up, overhang_angle, backend, floor, orient)
    return _out(out[:, 0], single)


def projected_risky_area(vertices, faces, up, overhang_angle=SEARCH_OVERHANG_ANGLE):
    """Area of the risky faces projected on the build plate.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Closed surface (3D) or planar triangle mesh (2D).
    faces : (f, 3) int
        Triangles, consistently oriented, either winding.
    up : str or (d,) array_like of float
        Printing direction: ``"x"`` ... ``"-z"``, ``"0,1,0"`` or a vector
        (:func:`supportless.energies.surface.prepare`).
    overhang_angle : float
        Threshold slope in degrees from the build plate (default: the default
        search's, :data:`~supportless.files.printer.SEARCH_OVERHANG_ANGLE`).

    Returns
    -------
    area : (P,) float64 or float
        ``sum A_f |n_f . up|`` over faces with ``n_f . up < -cos(angle)``
        (lengths of boundary edges in 2D).
    """
    V, F, up, single = prepare(vertices, faces, up)
    tau = np.cos(np.radians(overhang_angle))
    if V.shape[-1] == 3:
        a, b, c = V[:, F[:, 0]], V[:, F[:, 1]], V[:, F[:, 2]]
        scaled_normal = 0.5 * np.cross(b - a, c - a)  # area * unit normal
    else:
        E = boundary_edges(F)  # triangle direction; orientation_sign below makes it outward
        d = V[:, E[:, 1]] - V[:, E[:, 0]]
        scaled_normal = np.stack([d[..., 1], -d[..., 0]], -1)  # length * outward normal
    along = (scaled_normal @ up) * orientation_sign(V, F)[:, None]  # either winding
    size = np.linalg.norm(scaled_normal, axis=-1)
    out = np.where(along < -tau * size, -along, 0.0).sum(-1)
    return float(out[0]) if single else out
