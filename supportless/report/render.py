"""Headless pictures of meshes, skeletons and optimisation runs.

Everything is drawn with matplotlib's Agg backend (no display needed) using a
hand-rolled orthographic projection and painter's algorithm: faces are
projected to the screen, Lambert-shaded from their normals and drawn far to
near, each in one colour, by the renderer's triangles in one call (a 2D
figure's as a :class:`~matplotlib.collections.PolyCollection`).  The printing
direction ``up`` is always shown vertically on screen and the build plate is
drawn as a light grid at the mesh's lowest point along ``up``.

All writers produce the PNG in a temporary file in the destination directory
and move it into place with :func:`os.replace`, so a reader never sees a
half-written picture.

The camera, the box a picture frames and the plate's rectangle are
:mod:`supportless.report.projection`'s; this module draws.
"""

from __future__ import annotations

import os

import numpy as np
from matplotlib.artist import Artist, allow_rasterization
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure

from .projection import _plate_corners, _plate_rect, _screen_limits, _view_frame, view_bounds

__all__ = ["view_bounds", "render_mesh", "render_before_after", "plot_convergence"]

_BASE_COLOR = np.array([0.80, 0.82, 0.86])
_RISKY_COLOR = np.array([0.90, 0.12, 0.10])
_FLAT_COLOR = np.array([0.72, 0.80, 0.92])
_DPI = 100


# ---------------------------------------------------------------------------
# drawing
# ---------------------------------------------------------------------------

def _face_base_colors(n_faces, face_colors, risky, default):
    """Unshaded RGB colour of every face.

    Parameters
    ----------
    n_faces : int
    face_colors : numpy.ndarray, shape (f, 3) or (f, 4) or (3,), or None
        RGB(A) in [0, 1] or [0, 255]; None gives ``default`` everywhere.
    risky : numpy.ndarray, shape (f,), dtype bool, or None
        Faces painted red.
    default : numpy.ndarray, shape (3,), dtype float64

    Returns
    -------
    numpy.ndarray, shape (f, 3), dtype float64
    """
    if face_colors is None:
        base = np.tile(default, (n_faces, 1))
    else:
        fc = np.asarray(face_colors, dtype=np.float64)
        if fc.ndim == 1:
            fc = np.tile(fc, (n_faces, 1))
        if fc.shape[0] != n_faces or fc.shape[1] not in (3, 4):
            raise ValueError("face_colors must have shape (f, 3) or (f, 4)")
        if fc.max() > 1.0:
            fc = fc / 255.0
        base = fc[:, :3].copy()
    if risky is not None:
        mask = np.asarray(risky, dtype=bool).reshape(-1)
        if mask.shape[0] != n_faces:
            raise ValueError("risky must have one entry per face")
        base[mask] = _RISKY_COLOR
    return base


def _draw_plate(ax, V, u, e1, e2, right, sup, bounds):
    """Draw the build plate and its grid under a 3D mesh.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    V : numpy.ndarray, shape (n, 3), dtype float64
        The plate is at its lowest point along ``u``.
    u, e1, e2, right, sup : numpy.ndarray, shape (3,), dtype float64
        Up, the plate axes and the screen axes (from :func:`_view_frame`).
    bounds : numpy.ndarray, shape (2, 3), dtype float64
        The framed box, whose footprint the plate covers.
    """
    h0 = float((V @ u).min())
    origin, lim, step = _plate_rect(bounds, u, e1, e2, h0)
    quad = _plate_corners(origin, lim, e1, e2)
    ax.add_collection(PolyCollection([np.c_[quad @ right, quad @ sup]],
                                     facecolors=[(0.93, 0.93, 0.90)],
                                     edgecolors=[(0.6, 0.6, 0.6)],
                                     linewidths=0.8, zorder=0))
    segs = []
    for a in np.arange(lim[0, 0], lim[0, 1] + 0.5 * step, step):
        p0, p1 = origin + a * e1 + lim[1, 0] * e2, origin + a * e1 + lim[1, 1] * e2
        segs.append([[p0 @ right, p0 @ sup], [p1 @ right, p1 @ sup]])
    for b in np.arange(lim[1, 0], lim[1, 1] + 0.5 * step, step):
        p0, p1 = origin + lim[0, 0] * e1 + b * e2, origin + lim[0, 1] * e1 + b * e2
        segs.append([[p0 @ right, p0 @ sup], [p1 @ right, p1 @ sup]])
    ax.add_collection(LineCollection(segs, colors=[(0.80, 0.80, 0.78)],
                                     linewidths=0.5, zorder=0.5))


def _draw_skeleton(ax, joints, bones, right, sup):
    """Draw bones as lines and joints as dots, above the mesh.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    joints : numpy.ndarray, shape (j, d), dtype float64
    bones : numpy.ndarray, shape (m, 2), dtype int64, or None
    right, sup : numpy.ndarray, shape (d,), dtype float64
        Screen axes.
    """
    J = np.asarray(joints, dtype=np.float64)
    P = np.c_[J @ right, J @ sup]
    if bones is not None and len(bones):
        B = np.asarray(bones, dtype=np.int64)
        ax.add_collection(LineCollection(P[B], colors=[(0.05, 0.15, 0.45)],
                                         linewidths=3.2, zorder=10))
        ax.add_collection(LineCollection(P[B], colors=[(0.35, 0.65, 1.0)],
                                         linewidths=1.6, zorder=11))
    ax.scatter(P[:, 0], P[:, 1], s=26, c=[(1.0, 0.78, 0.1)],
               edgecolors=[(0.05, 0.15, 0.45)], linewidths=1.0, zorder=12)


def _draw_balance(ax, balance, u, right, sup, h0):
    """Draw the support polygon on the plate and the centre of mass above its projection.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    balance : dict
        ``centre_of_mass`` (d,) float64 and ``support`` (q, d) float64: the
        support polygon's corners, in order, on the plate.
    u, right, sup : numpy.ndarray, shape (d,), dtype float64
        Up and the screen axes.
    h0 : float
        Height of the plate along ``u``.
    """
    com = np.asarray(balance["centre_of_mass"], np.float64)
    poly = np.asarray(balance["support"], np.float64)
    S = np.c_[poly @ right, poly @ sup]
    if len(S) >= 3:
        ax.add_collection(PolyCollection([S], facecolors=[(0.2, 0.75, 0.3, 0.35)],
                                         edgecolors=[(0.1, 0.5, 0.15)], linewidths=1.5, zorder=1.5))
    else:
        ax.plot(S[:, 0], S[:, 1], color=(0.1, 0.5, 0.15), lw=2.5, zorder=1.5)
    foot = com - (com @ u - h0) * u
    c, f = np.array([com @ right, com @ sup]), np.array([foot @ right, foot @ sup])
    ax.plot([c[0], f[0]], [c[1], f[1]], color=(0.1, 0.5, 0.15), lw=1.0, ls="--", zorder=13)
    ax.scatter([c[0]], [c[1]], s=70, marker="o", c=[(1.0, 1.0, 1.0)], edgecolors=[(0.1, 0.5, 0.15)],
               linewidths=2.0, zorder=14)
    ax.scatter([f[0]], [f[1]], s=40, marker="x", c=[(0.1, 0.5, 0.15)], linewidths=2.0, zorder=14)


def _draw_mesh(ax, vertices, faces, up, joints, bones, face_colors, risky,
               title, camera, bounds, aspect, balance=None):
    """Draw one mesh panel; the arguments are those of :func:`render_mesh`.

    ``aspect`` is the panel's width / height in pixels; ``bounds`` None frames
    the mesh (and joints) alone; ``balance`` is drawn by :func:`_draw_balance`.
    """
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    if V.ndim != 2 or V.shape[1] not in (2, 3):
        raise ValueError("vertices must have shape (n, 2) or (n, 3)")
    if F.ndim != 2 or F.shape[1] != 3:
        raise ValueError("faces must have shape (f, 3)")
    dim = V.shape[1]
    if bounds is None:
        pts = [V] if joints is None else [V, np.asarray(joints, dtype=np.float64)]
        bounds = view_bounds(*pts)
    right, sup, toward, u, e1, e2 = _view_frame(up, camera, dim)
    x0, x1, y0, y1 = _screen_limits(bounds, up, camera, aspect)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_axis_off()
    P = np.c_[V @ right, V @ sup]
    tris = P[F]

    if dim == 2:
        base = _face_base_colors(len(F), face_colors, risky, _FLAT_COLOR)
        ax.add_collection(PolyCollection(tris, facecolors=base,
                                         edgecolors=[(0.35, 0.42, 0.55)],
                                         linewidths=0.25, zorder=2), autolim=False)
        # boundary outline
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        uniq, cnt = np.unique(E, axis=0, return_counts=True)
        bnd = uniq[cnt == 1]
        ax.add_collection(LineCollection(P[bnd], colors=[(0.1, 0.1, 0.15)],
                                         linewidths=1.4, zorder=3), autolim=False)
        h0 = float((V @ u).min())
        ax.plot([x0, x1], [h0, h0], color=(0.55, 0.55, 0.55), lw=1.2, zorder=1)
        ax.fill_between([x0, x1], [h0, h0], [y0, y0], color=(0.93, 0.93, 0.90), zorder=0)
    else:
        _draw_plate(ax, V, u, e1, e2, right, sup, bounds)
        N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        ln = np.linalg.norm(N, axis=1)
        N = N / np.where(ln > 0, ln, 1.0)[:, None]
        light = 0.45 * right + 0.75 * sup + 0.9 * toward
        light /= np.linalg.norm(light)
        facing = N @ toward
        lam = N @ light
        # two-sided shading; back faces are drawn first and darker
        shade = np.where(facing >= 0, 0.42 + 0.58 * np.clip(lam, 0, 1),
                         0.22 + 0.35 * np.clip(-lam, 0, 1))
        base = _face_base_colors(len(F), face_colors, risky, _BASE_COLOR)
        rgb = np.clip(base * shade[:, None], 0, 1)
        depth = (V @ toward)[F].mean(axis=1)
        order = np.lexsort((depth, facing >= 0))  # back faces first, far to near
        ax.add_artist(_FlatTriangles(tris[order], rgb[order], zorder=2))
    if joints is not None:
        _draw_skeleton(ax, joints, bones, right, sup)
    if balance is not None:
        _draw_balance(ax, balance, u, right, sup, float((V @ u).min()))
    if title:
        ax.set_title(title, fontsize=13)


class _FlatTriangles(Artist):
    """Triangles filled each with one colour, in the order given (later ones over earlier ones), by the renderer's
    Gouraud triangles in one call: no path object a triangle, and no seam between neighbours (a collection of
    40 000 polygons took 3 s of a character's pictures, with its edges stroked over its seams)."""

    def __init__(self, tris: np.ndarray, rgb: np.ndarray, zorder: float):
        """``tris`` (k, 3, 2) float64 in data coordinates, ``rgb`` (k, 3) float64 in [0, 1]."""
        super().__init__()
        self._tris = np.ascontiguousarray(tris, np.float64)
        rgba = np.concatenate([rgb, np.ones((len(rgb), 1))], axis=1)
        self._colors = np.ascontiguousarray(np.repeat(rgba[:, None, :], 3, axis=1), np.float64)
        self.set_zorder(zorder)

    @allow_rasterization
    def draw(self, renderer):
        if not self.get_visible() or not len(self._tris):
            return
        gc = renderer.new_gc()
        self._set_gc_clip(gc)
        renderer.draw_gouraud_triangles(gc, self._tris, self._colors, self.get_transform().frozen())
        gc.restore()
        self.stale = False


def _save_atomic(fig, path):
    """Save ``fig`` as PNG through :func:`supportless.files.meshes.atomic_path`; return ``path`` as str."""
    from ..files.meshes import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=_DPI)
    return os.fspath(path)


def _new_figure(size):
    """A white Agg figure of ``size = (width, height)`` pixels."""
    w, h = (int(s) for s in size)
    if w <= 0 or h <= 0:
        raise ValueError("size must be positive")
    return Figure(figsize=(w / _DPI, h / _DPI), dpi=_DPI, facecolor="white")


def _panel_axes(fig, rect, has_title):
    """Axes filling ``rect = (x, y, w, h)`` in figure fractions, leaving 7 % on top for a title."""
    x, y, w, h = rect
    if has_title:
        h = h * 0.93
    return fig.add_axes((x, y, w, h))


# ---------------------------------------------------------------------------
# public API
# ---------------------------------------------------------------------------

def render_mesh(path, vertices, faces, up, joints=None, bones=None,
                face_colors=None, risky=None, title=None, camera=None,
                size=(800, 800), bounds=None):
    """Write a shaded PNG picture of a mesh (and optionally its skeleton).

    Parameters
    ----------
    path : str or os.PathLike
        Output PNG path; written atomically (temporary file + ``os.replace``).
    vertices : numpy.ndarray, shape (n, 3) or (n, 2), dtype float64
        Vertex positions.  2D meshes are drawn flat with their boundary.
    faces : numpy.ndarray, shape (f, 3), dtype int64
        Triangles.
    up : array_like, shape (3,) or (2,)
        Printing direction; shown vertically on screen.  The build plate is
        drawn at the lowest vertex along ``up``.
    joints : numpy.ndarray, shape (j, d), dtype float64, optional
        Joint positions, drawn as dots on top.
    bones : numpy.ndarray, shape (m, 2), dtype int64, optional
        Bones as joint index pairs, drawn as lines on top.
    face_colors : numpy.ndarray, shape (f, 3) or (f, 4) or (3,), dtype float64, optional
        Base RGB(A) colours in [0, 1] (or [0, 255]); shaded by lighting.
    risky : numpy.ndarray, shape (f,), dtype bool, optional
        Faces to paint red (e.g. overhangs needing support).
    title : str, optional
        Title drawn above the picture.
    camera : dict or tuple, optional
        ``{"azimuth": deg, "elevation": deg}`` or ``(azimuth, elevation)``;
        default ``(25, 12)``.  Azimuth 0 views along ``-Z`` for ``up = +Y``.
    size : tuple of int
        ``(width, height)`` of the PNG in pixels.
    bounds : numpy.ndarray, shape (2, d), dtype float64, optional
        World box to frame (see :func:`view_bounds`); pass the same box to
        several renders to get identical framing.  Default: the mesh's box.

    Returns
    -------
    str
        The path written.
    """
    fig = _new_figure(size)
    ax = _panel_axes(fig, (0.0, 0.0, 1.0, 1.0), bool(title))
    aspect = size[0] / (size[1] * (0.93 if title else 1.0))
    _draw_mesh(ax, vertices, faces, up, joints, bones, face_colors, risky,
               title, camera, bounds, aspect)
    return _save_atomic(fig, path)


def render_before_after(path, before, after, up, before_skeleton=None,
                        after_skeleton=None, before_risky=None,
                        after_risky=None, titles=("before", "after"),
                        suptitle=None, camera=None, size=(1600, 800),
                        bounds=None, before_balance=None, after_balance=None,
                        face_colors=(None, None), notes=(None, None)):
    """Write one PNG with the rest pose and the deformed pose side by side.

    Both panels share the camera and framing, so sizes are comparable.

    Parameters
    ----------
    path : str or os.PathLike
        Output PNG path; written atomically.
    before, after : tuple
        ``(V, F)`` with ``V`` of shape (n, d) float64 and ``F`` of shape
        (f, 3) int64 (``F`` may differ between the two).
    up : array_like, shape (d,)
        Printing direction, shown vertically.
    before_skeleton, after_skeleton : tuple, optional
        ``(joints, bones)``: joints (j, d) float64, bones (m, 2) int64.
    before_risky, after_risky : numpy.ndarray, shape (f,), dtype bool, optional
        Faces drawn red in each panel.
    titles : tuple of str
        Panel titles.
    suptitle : str, optional
        Overall title.
    camera : dict or tuple, optional
        See :func:`render_mesh`.
    size : tuple of int
        ``(width, height)`` of the PNG in pixels.
    bounds : numpy.ndarray, shape (2, d), dtype float64, optional
        Shared world box; default encloses both meshes (and skeletons).
    before_balance, after_balance : dict, optional
        ``{"centre_of_mass": (d,) float64, "support": (q, d) float64}``: the
        centre of mass (a ring, with its projection on the plate) and the
        support polygon's corners on the plate (shaded green).
    face_colors : tuple, optional
        Each panel's base face colours, (f, 3) float64 or None (grey), as in :func:`render_mesh`.
    notes : tuple, optional
        Each panel's line written at its foot (e.g. its weakest section, :mod:`.weakness`), or None.

    Returns
    -------
    str
        The path written.
    """
    Vb, Fb = before
    Va, Fa = after
    if bounds is None:
        pts = [np.asarray(Vb, dtype=np.float64), np.asarray(Va, dtype=np.float64)]
        for sk in (before_skeleton, after_skeleton):
            if sk is not None:
                pts.append(np.asarray(sk[0], dtype=np.float64))
        bounds = view_bounds(*pts)
    fig = _new_figure(size)
    top = 0.93 if suptitle else 1.0
    if suptitle:
        fig.suptitle(suptitle, fontsize=15, y=0.985)
    panel_h = top * (0.93 if titles else 1.0)
    aspect = (size[0] / 2) / (size[1] * panel_h)
    panels = ((Vb, Fb, before_skeleton, before_risky, before_balance),
              (Va, Fa, after_skeleton, after_risky, after_balance))
    for i, (V, F, sk, risky, balance) in enumerate(panels):
        ax = _panel_axes(fig, (0.5 * i, 0.0, 0.5, top), bool(titles))
        joints, bones = (None, None) if sk is None else sk
        title = titles[i] if titles else None
        _draw_mesh(ax, V, F, up, joints, bones, face_colors[i], risky, title, camera,
                   bounds, aspect, balance)
        if notes[i]:
            ax.text(0.5, 0.01, notes[i], transform=ax.transAxes, ha="center", va="bottom", fontsize=12,
                    color=(0.0, 0.3, 0.4), bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"})
    return _save_atomic(fig, path)


def plot_convergence(path, history, terms=None, title=None, size=(800, 500)):
    """Plot the best objective value per optimisation iteration.

    Parameters
    ----------
    path : str or os.PathLike
        Output PNG path; written atomically.
    history : array_like, shape (k,), dtype float64
        Best objective value after each iteration.
    terms : dict of str to array_like, optional
        Named per-iteration histories of individual energy terms, each of
        shape (k,) float64 (e.g. weighted overhang, ARAP, intersection);
        drawn in a second panel.
    title : str, optional
        Figure title (default "convergence").
    size : tuple of int
        ``(width, height)`` of the PNG in pixels.

    Returns
    -------
    str
        The path written.

    Notes
    -----
    A logarithmic y axis is used when all values are positive and span more
    than a factor of 20.
    """
    h = np.asarray(history, dtype=np.float64).reshape(-1)
    if h.size == 0:
        raise ValueError("history is empty")
    fig = _new_figure(size)
    n_panels = 2 if terms else 1
    axes = fig.subplots(n_panels, 1, sharex=True, squeeze=False)[:, 0]

    def maybe_log(ax, values):
        v = np.concatenate([np.asarray(x, dtype=np.float64).reshape(-1) for x in values])
        v = v[np.isfinite(v)]
        if v.size and v.min() > 0 and v.max() / v.min() > 20:
            ax.set_yscale("log")

    it = np.arange(h.size)
    ax = axes[0]
    ax.plot(it, h, color="tab:blue", lw=2, label="best objective")
    ax.scatter([it[-1]], [h[-1]], color="tab:blue", zorder=3)
    ax.annotate(f"{h[-1]:.4g}", (it[-1], h[-1]), textcoords="offset points",
                xytext=(-8, 8), ha="right")
    maybe_log(ax, [h])
    ax.set_ylabel("objective")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right")
    if terms:
        ax2 = axes[1]
        for name, vals in terms.items():
            v = np.asarray(vals, dtype=np.float64).reshape(-1)
            ax2.plot(np.arange(v.size), v, lw=1.6, label=str(name))
        maybe_log(ax2, list(terms.values()))
        ax2.set_ylabel("term")
        ax2.grid(True, alpha=0.3)
        ax2.legend(loc="upper right", fontsize=9)
    axes[-1].set_xlabel("iteration")
    fig.suptitle(title or "convergence")
    fig.tight_layout()
    return _save_atomic(fig, path)


def render_front(path, meshes, up, support, distortion, support_label="support", size=None):
    """Write one PNG of a front of poses: a thumbnail of each, and the front plotted.

    Parameters
    ----------
    path : str or os.PathLike
        Output PNG path; written atomically.
    meshes : list of tuple
        ``(V, F)`` per pose, ``V`` (n, d) float64 in its print frame, ``F`` (f, 3) int64.
    up : array_like, shape (d,)
        Printing direction, shown vertically.
    support, distortion : array_like, shape (k,), float64
        Each pose's two measures (numbered 1..k in both panels).
    support_label : str
        The support axis' label.
    size : tuple of int, optional
        ``(width, height)`` in pixels; default 300 px per thumbnail by 700.

    Returns
    -------
    str
        The path written.
    """
    k = len(meshes)
    if k == 0:
        raise ValueError("no poses to draw")
    size = size or (max(900, 300 * k), 760)
    bounds = view_bounds(*[np.asarray(V, np.float64) for V, _ in meshes])
    fig = _new_figure(size)
    thumb_h = 0.52
    aspect = (size[0] / k) / (size[1] * thumb_h * 0.93)
    for i, (V, F) in enumerate(meshes):
        ax = _panel_axes(fig, (i / k, 1.0 - thumb_h, 1.0 / k, thumb_h), True)
        title = f"{i + 1}: {support[i]:.4g} / {distortion[i] if distortion[i] > 1e-9 else 0:.3g}"
        _draw_mesh(ax, V, F, up, None, None, None, None, title, None, bounds, aspect)
    ax = fig.add_axes((0.08, 0.08, 0.88, 0.34))
    s, d = np.asarray(support, np.float64), np.asarray(distortion, np.float64)
    ax.plot(s, d, "-o", color="tab:blue")
    for i in range(k):
        ax.annotate(str(i + 1), (s[i], d[i]), textcoords="offset points", xytext=(6, 6))
    ax.set_xlabel(support_label)
    ax.set_ylabel("distortion")
    ax.grid(True, alpha=0.3)
    return _save_atomic(fig, path)
