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
``up``.  The energy is the sum of ``lambda`` over risky elements.

Outward orientation is taken from the sign of the total signed volume (3D)
or signed area (2D) of each pose, so either consistent winding works.
"""

from __future__ import annotations

import numpy as np

from ._raycast import boundary_edges, orientation_sign, prepare

__all__ = ["overhang_energy", "risky_faces", "risky_area", "boundary_edges"]


def _tau(overhang_angle):
    return float(np.cos(np.deg2rad(float(overhang_angle))))


def _elements(vertices, faces, up):
    """Per-element measure, normal component along up and centroid height.

    Returns
    -------
    meas : (P, m) float64
        Area (3D faces) or length (2D boundary edges).
    ndot : (P, m) float64
        ``n . up`` of the outward unit normal (0 for degenerate elements).
    h : (P, m) float64
        Centroid height above the build plate.
    single : bool
    """
    V, F, u, single = prepare(vertices, faces, up)
    orient = orientation_sign(V, F)[:, None]
    height = V @ u  # (P, n)
    plate = height.min(axis=1, keepdims=True)
    if V.shape[-1] == 3:
        a, b, c = V[:, F[:, 0]], V[:, F[:, 1]], V[:, F[:, 2]]
        cr = np.cross(b - a, c - a)
        dbl = np.linalg.norm(cr, axis=-1)
        meas = 0.5 * dbl
        h = (height[:, F[:, 0]] + height[:, F[:, 1]] + height[:, F[:, 2]]) / 3.0 - plate
    else:
        E = boundary_edges(F)
        a, b = V[:, E[:, 0]], V[:, E[:, 1]]
        t = b - a
        # outward normal of a counter-clockwise boundary: (dy, -dx)
        cr = np.stack([t[..., 1], -t[..., 0]], axis=-1)
        dbl = np.linalg.norm(cr, axis=-1)
        meas = dbl
        h = 0.5 * (height[:, E[:, 0]] + height[:, E[:, 1]]) - plate
    proj = cr @ u
    with np.errstate(invalid="ignore", divide="ignore"):
        ndot = np.where(dbl > 0.0, orient * proj / np.where(dbl > 0.0, dbl, 1.0), 0.0)
    return meas, ndot, h, single


def _out(x, single):
    return float(x[0]) if single else x


def risky_faces(vertices, faces, up, overhang_angle=45.0):
    """Mask of risky (support-needing) surface elements.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Deformed vertex positions, ``d`` in {2, 3}.
    faces : (f, 3) int
        Consistently oriented triangles of a closed surface (3D) or of a
        planar region (2D).
    up : (d,) float
        Printing direction (normalised internally).
    overhang_angle : float
        Threshold slope ``theta`` in degrees measured from the build plate;
        risky when ``n . up < -cos(theta)``.

    Returns
    -------
    mask : (P, m) or (m,) bool
        ``m = f`` in 3D; in 2D ``m`` is the number of boundary edges, in the
        order of :func:`boundary_edges` ``(faces)``.
    """
    _, ndot, _, single = _elements(vertices, faces, up)
    mask = ndot < -_tau(overhang_angle)
    return mask[0] if single else mask


def risky_area(vertices, faces, up, overhang_angle=45.0):
    """Total area (length in 2D) of the risky surface elements.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Deformed vertex positions, ``d`` in {2, 3}.
    faces : (f, 3) int
        Consistently oriented triangles.
    up : (d,) float
        Printing direction (normalised internally).
    overhang_angle : float
        Threshold slope in degrees from the build plate (default 45).

    Returns
    -------
    area : (P,) float64 or float
        Sum of the areas (lengths) of risky elements per pose.
    """
    meas, ndot, _, single = _elements(vertices, faces, up)
    res = np.where(ndot < -_tau(overhang_angle), meas, 0.0).sum(axis=1)
    return _out(res, single)


def overhang_energy(vertices, faces, up, overhang_angle=45.0):
    """Prism overhang energy ``sum_f A_f |n_f . up| h_f`` over risky faces.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Deformed vertex positions, ``d`` in {2, 3}.  The build plate of each
        pose is its lowest vertex along ``up``.
    faces : (f, 3) int
        Consistently oriented triangles (closed surface in 3D; planar region
        in 2D, whose boundary edges are the surface).
    up : (d,) float
        Printing direction (normalised internally).
    overhang_angle : float
        Threshold slope ``theta`` in degrees from the build plate (default
        45); risky when ``n . up < -cos(theta)``.

    Returns
    -------
    energy : (P,) float64 or float
        Approximate support volume (area in 2D) per pose.  Scales as ``s**3``
        (``s**2`` in 2D) under uniform scaling and is invariant under
        rotations about ``up`` and translations.
    """
    meas, ndot, h, single = _elements(vertices, faces, up)
    lam = meas * np.abs(ndot) * h
    res = np.where(ndot < -_tau(overhang_angle), lam, 0.0).sum(axis=1)
    return _out(res, single)
