"""The pictures' projection: an orthographic camera with the printing direction up, and what it frames.

:func:`_view_frame` gives the screen axes of a camera (azimuth about the
printing direction ``up``, elevation above the plate; ``up`` always drawn
vertically), :func:`view_bounds` and :func:`_screen_limits` the box a picture
frames and its rectangle on screen, :func:`_plate_rect` the build plate under
it, snapped to a round grid step. :mod:`supportless.report.render` draws with
them.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["view_bounds"]

_DEFAULT_CAMERA = {"azimuth": 25.0, "elevation": 12.0}


def _unit(v):
    """``v`` scaled to length 1.

    Parameters
    ----------
    v : array_like, shape (d,)

    Returns
    -------
    numpy.ndarray, shape (d,), dtype float64

    Raises
    ------
    ValueError
        For a zero or non-finite vector.
    """
    v = np.asarray(v, dtype=np.float64)
    n = np.linalg.norm(v)
    if not np.isfinite(n) or n == 0.0:
        raise ValueError("up must be a non-zero finite vector")
    return v / n


def _parse_camera(camera):
    """``(azimuth, elevation)`` in degrees from ``{"azimuth", "elevation"}``, a pair, or None (the default)."""
    if camera is None:
        camera = _DEFAULT_CAMERA
    if isinstance(camera, dict):
        az = float(camera.get("azimuth", _DEFAULT_CAMERA["azimuth"]))
        el = float(camera.get("elevation", _DEFAULT_CAMERA["elevation"]))
    else:
        az, el = (float(c) for c in camera)
    return az, el


def _view_frame(up, camera, dim):
    """Orthonormal screen frame for a given up direction and camera.

    Parameters
    ----------
    up : array_like, shape (dim,)
        Printing direction; drawn vertically on screen.
    camera : dict or tuple or None
        ``{"azimuth": deg, "elevation": deg}`` or ``(azimuth, elevation)``.
        Azimuth 0 looks along the horizontal axis most perpendicular to up
        (for ``up = +Y``: from ``+Z``, with ``+X`` to the right); elevation is
        the angle of the eye above the plate.  Ignored in 2D.
    dim : int
        2 or 3.

    Returns
    -------
    right : numpy.ndarray, shape (dim,), dtype float64
        World direction drawn to the right.
    screen_up : numpy.ndarray, shape (dim,), dtype float64
        World direction drawn upwards.
    toward : numpy.ndarray, shape (dim,), dtype float64 or None
        Direction from the scene to the eye (3D only).
    u : numpy.ndarray, shape (dim,), dtype float64
        Unit up.
    e1, e2 : numpy.ndarray, shape (dim,), dtype float64 or None
        Horizontal plate axes (3D only).
    """
    u = _unit(up)
    if dim == 2:
        right = np.array([u[1], -u[0]])
        return right, u, None, u, None, None
    # horizontal reference axes: e1 ~ "right" at azimuth 0, e2 ~ "front"
    if abs(u[2]) < 0.9:
        ref_front = np.array([0.0, 0.0, 1.0])
    else:  # z-up convention: look from -Y so +X stays to the right
        ref_front = np.array([0.0, -1.0, 0.0]) * np.sign(u[2])
    e2 = ref_front - u * (ref_front @ u)
    e2 /= np.linalg.norm(e2)
    e1 = np.cross(u, e2)
    az, el = _parse_camera(camera)
    a, e = math.radians(az), math.radians(el)
    toward = math.cos(e) * (math.cos(a) * e2 + math.sin(a) * e1) + math.sin(e) * u
    right = np.cross(u, toward)
    if np.linalg.norm(right) < 1e-9:  # looking straight down/up
        right = e1.copy()
    right /= np.linalg.norm(right)
    screen_up = np.cross(toward, right)
    return right, screen_up, toward, u, e1, e2


def view_bounds(*vertex_arrays):
    """Axis-aligned box enclosing several meshes, for shared framing.

    Parameters
    ----------
    *vertex_arrays : numpy.ndarray, shape (n_k, d), dtype float64
        Vertex (or joint) arrays of the same dimension ``d``.

    Returns
    -------
    numpy.ndarray, shape (2, d), dtype float64
        ``[min corner, max corner]``.
    """
    pts = np.vstack([np.asarray(v, dtype=np.float64) for v in vertex_arrays])
    return np.stack([pts.min(axis=0), pts.max(axis=0)])


def _box_corners(bounds):
    """The ``2**d`` corners of a box.

    Parameters
    ----------
    bounds : numpy.ndarray, shape (2, d), dtype float64
        ``[min corner, max corner]``.

    Returns
    -------
    numpy.ndarray, shape (2**d, d), dtype float64
    """
    lo, hi = np.asarray(bounds, dtype=np.float64)
    d = len(lo)
    idx = np.array(np.meshgrid(*[[0, 1]] * d, indexing="ij")).reshape(d, -1).T
    return np.where(idx == 1, hi, lo)


def _nice_step(extent):
    """A 1, 2 or 5 times a power of ten grid step giving about 8 lines across ``extent``."""
    raw = extent / 8.0
    p = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * p >= raw:
            return m * p
    return 10.0 * p


def _screen_limits(bounds, up, camera, aspect):
    """The screen rectangle framing a box (and, in 3D, its plate).

    Parameters
    ----------
    bounds : numpy.ndarray, shape (2, d), dtype float64
        World box to frame.
    up : array_like, shape (d,)
    camera : dict or tuple or None
        See :func:`_view_frame`.
    aspect : float
        Width / height of the axes in pixels.

    Returns
    -------
    xmin, xmax, ymin, ymax : float
        Screen coordinates, with a 2 % margin and the given aspect ratio.
    """
    lo, hi = np.asarray(bounds, dtype=np.float64)
    dim = len(lo)
    right, sup, _, u, e1, e2 = _view_frame(up, camera, dim)
    corners = _box_corners(bounds)
    if dim == 3:
        # include the plate, which extends beyond the footprint
        h0 = (corners @ u).min()
        origin, lim, _ = _plate_rect(bounds, u, e1, e2, h0)
        corners = np.vstack([corners, _plate_corners(origin, lim, e1, e2)])
    xs, ys = corners @ right, corners @ sup
    x0, x1, y0, y1 = xs.min(), xs.max(), ys.min(), ys.max()
    w, h = max(x1 - x0, 1e-12), max(y1 - y0, 1e-12)
    pad = 0.02 * max(w, h)
    w, h = w + 2 * pad, h + 2 * pad
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    if w / h < aspect:
        w = h * aspect
    else:
        h = w / aspect
    return cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2


def _plate_rect(bounds, u, e1, e2, h0, margin=0.12):
    """Plate rectangle around the footprint of ``bounds``.

    Returns
    -------
    origin : numpy.ndarray, shape (3,), dtype float64
        A point on the plate (height ``h0`` along ``u``).
    lim : numpy.ndarray, shape (2, 2), dtype float64
        ``[[a0, a1], [b0, b1]]`` coordinate ranges along ``e1`` and ``e2``,
        snapped to multiples of the grid step.
    step : float
        Grid spacing.
    """
    corners = _box_corners(bounds)
    c1, c2 = corners @ e1, corners @ e2
    ext = max(c1.max() - c1.min(), c2.max() - c2.min(), 1e-12)
    step = _nice_step(ext * (1 + 2 * margin))
    m = margin * ext
    lim = np.array([[c1.min() - m, c1.max() + m], [c2.min() - m, c2.max() + m]])
    lim[:, 0] = np.floor(lim[:, 0] / step) * step
    lim[:, 1] = np.ceil(lim[:, 1] / step) * step
    origin = u * h0
    return origin, lim, step


def _plate_corners(origin, lim, e1, e2):
    """The 4 corners, shape (4, 3), of the plate rectangle from :func:`_plate_rect`."""
    return np.array([origin + a * e1 + b * e2
                     for a, b in ((lim[0, 0], lim[1, 0]), (lim[0, 1], lim[1, 0]),
                                  (lim[0, 1], lim[1, 1]), (lim[0, 0], lim[1, 1]))])
