"""A surface that crosses itself made one closed solid, as the print body's last step and for a posed figure.

:func:`united_surface` is what is printed of a posed figure whose parts press
into each other (an arm resting against the torso): CGAL's exact self-union
(:func:`supportless.copyleft.cgal.self_union`), its slivers collapsed, else the
surface of its winding number (:func:`winding_surface`: closed, never crossing
itself, true to a grid cell). :func:`supportless.files.printbody.print_body`
ends with the same step (:func:`_resolve_crossings`).
"""

from __future__ import annotations

import numpy as np

from ..base.isolated import NativeFailure
from ..copyleft.cgal import intersecting_faces, self_union
from .simplify import simplify_surface
from .surfaceops import _collapse_short_edges, _components, _flip_caps, _is_closed, _volume, _weld, transfer_values

__all__ = ["ISLAND_MIN_VOLUME", "SIMPLIFY_TOLERANCE", "WINDING_CELLS", "united_surface", "winding_surface"]

#: Solids still apart after bridging below this fraction of the volume are
#: dropped (eyes floating in front of a face would print in the air); larger
#: ones are kept as separate pieces, with a warning. Pockets and crumbs of a
#: winding-number surface below it go too.
ISLAND_MIN_VOLUME = 0.01

#: Grid cells along the longest side for the winding-number surface that
#: replaces a body whose crossings an exact self-union cannot resolve (a cell
#: is 0.4 mm on a 60 mm print).
WINDING_CELLS = 160

#: The winding-number surface is simplified to at most this many triangles
#: (when the simplified one is closed and free of crossings).
WINDING_MAX_FACES = 40_000

#: After the union, edges shorter than this fraction of the size are collapsed:
#: the needle and zero-area triangles a boolean leaves, which TetGen cannot mesh.
SIMPLIFY_TOLERANCE = 1e-5


def united_surface(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict]:
    """One closed solid from a surface that presses into itself: its exact self-union (CGAL), else the surface
    of its winding number (as :func:`~supportless.files.printbody.print_body`'s last step).

    A posed figure whose arm rests against its torso crosses itself there; what is printed is the solid the
    two parts make together.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, outward oriented.

    Returns
    -------
    vertices : (n', 3) float64
    faces : (f', 3) int64
        The input when it does not cross itself.
    merged : dict
        ``pairs`` (crossing triangle pairs before), ``volume_before`` (the surface's enclosed volume, overlaps
        counted twice), ``volume`` (the solid's), ``merged_volume`` (their difference: the volume two parts
        shared), ``how`` ("none", "exact self-union" or "winding-number surface") and ``note`` (one line).
    """
    V, F = np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
    size = float(np.ptp(V, axis=0).max()) if len(V) else 1.0
    pairs = len(intersecting_faces(V, F))
    before = _volume(V, F)
    log: list[str] = []
    Vx, Fx, _ = _resolve_crossings(V, F, np.zeros((len(V), 0)), SIMPLIFY_TOLERANCE * size, log, pairs)
    if pairs and len(intersecting_faces(Vx.astype(np.float32).astype(np.float64), Fx)):  # as an STL stores it
        Vx, Fx = winding_surface(V, F, WINDING_CELLS)
        log = [f"{pairs} pairs of crossing triangles: the exact self-union crosses itself once stored in single "
               f"precision, so the body is the surface of its winding number on a {WINDING_CELLS}-cell grid"]
    after = _volume(Vx, Fx)
    how = "none" if not pairs else ("exact self-union" if "exact self-union" in log[0] else "winding-number surface")
    return Vx, Fx, {"pairs": pairs, "volume_before": before, "volume": after, "merged_volume": before - after,
                    "how": how, "note": log[0] if log else ""}


def _resolve_crossings(V, F, values, tol, log, before=None):
    """Remove crossing triangles: CGAL's exact self-union, else the winding-number surface.

    The self-union keeps every detail; the slivers it leaves are collapsed
    (and flattened caps flipped, unless that makes triangles cross again).
    When it leaves crossings (also once rescaled: points left exactly on a
    face) or edges shared by four triangles (parts that touch along an
    edge), the body is remade from its winding number (:func:`winding_surface`):
    closed, free of crossings, true to a grid cell of :data:`WINDING_CELLS`.
    Returns the surface and its values (carried from the surface before by
    closest point); ``log`` gets a line when there were crossings, and says
    how many remain. ``before``: the crossing pairs, when counted already.
    """
    before = len(intersecting_faces(V, F)) if before is None else before
    if before == 0:
        return V, F, values
    try:
        Vx, Fx = self_union(V, F)
        Vx, Fx, _, _ = _weld(Vx, Fx, np.zeros((len(Vx), 0)), tol * 1e-3)
        Vx, Fx, _ = _collapse_short_edges(Vx, Fx, np.zeros((len(Vx), 0)), tol)
        flipped = _flip_caps(Vx, Fx, tol)
        if len(intersecting_faces(Vx, flipped)) == 0:
            Fx = flipped
        if len(Fx) and _is_closed(Fx) and not _touches_itself(Vx, Fx):
            log.append(f"resolved {before} pairs of crossing triangles by an exact self-union "
                       f"(volume {(_volume(Vx, Fx) / _volume(V, F) - 1) * 100:+.2f} %)")
            return Vx, Fx, transfer_values(Vx, V, F, values)
    except NativeFailure:
        pass
    Vx, Fx = winding_surface(V, F, WINDING_CELLS)
    after = len(intersecting_faces(Vx, Fx))
    log.append(f"{before} pairs of crossing triangles that an exact self-union could not resolve cleanly: the "
               f"body remade as the surface of its winding number on a {WINDING_CELLS}-cell grid, {len(F)} -> "
               f"{len(Fx)} triangles (volume {(_volume(Vx, Fx) / _volume(V, F) - 1) * 100:+.1f} %)"
               + (f"; warning: {after} remain" if after else ""))
    return Vx, Fx, transfer_values(Vx, V, F, values)


def _touches_itself(V, F) -> bool:
    """Whether triangles cross, as given or rescaled (points a union leaves exactly on a face cross once rounded)."""
    return any(len(intersecting_faces(V * k, F)) for k in (1.0, 1000.0 / np.sqrt(2.0), 1.0 / np.pi))


def winding_surface(V, F, cells: int = WINDING_CELLS):
    """The outer surface of (V, F) remade by marching cubes: inside by winding number, placed by distance.

    Inside is where the shells wind around a point at least half a turn
    (libigl's fast winding number), so overlapping and crossing shells are
    one solid; the field marching cubes meets is that sign times the
    distance to the surface (computed at the grid points next to a change of
    sign: the others only need their sign), so the surface is as smooth as
    the input, not a staircase of cells. On a grid of ``cells`` along the
    longest side; closed, manifold, never crossing itself. Deterministic.

    Returns vertices (k, 3) float64 and outward faces (g, 3) int64.
    """
    import igl

    lo, hi = V.min(0), V.max(0)
    h = float((hi - lo).max()) / cells
    lo, hi = lo - 2 * h, hi + 2 * h
    nx, ny, nz = (np.ceil((hi - lo) / h).astype(np.int64) + 1).tolist()
    axes = [lo[i] + h * np.arange(n) for i, n in enumerate((nx, ny, nz))]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).transpose(2, 1, 0, 3).reshape(-1, 3)  # x fastest
    inside = (igl.fast_winding_number(V, F, np.ascontiguousarray(grid)) > 0.5).reshape(nz, ny, nx)
    near = np.zeros_like(inside)
    for axis in range(3):  # grid points with a neighbour across the surface
        change = np.diff(inside, axis=axis)
        lower = [slice(None)] * 3
        upper = [slice(None)] * 3
        lower[axis], upper[axis] = slice(0, -1), slice(1, None)
        near[tuple(lower)] |= change
        near[tuple(upper)] |= change
    field = np.full(inside.shape, 2.0 * h)
    d2 = igl.point_mesh_squared_distance(np.ascontiguousarray(grid[near.ravel()]), V, F)[0]
    field[near] = np.minimum(np.sqrt(d2), 2.0 * h)
    # no grid point exactly on the surface: marching cubes would put a vertex on it, shared by needle triangles
    field = np.maximum(field, 1e-2 * h)
    field = np.where(inside, -field, field).ravel()
    out = igl.marching_cubes(np.ascontiguousarray(field), grid, nx, ny, nz, 0.0)
    Vs, Fs = np.asarray(out[0], np.float64), np.asarray(out[1], np.int64)
    if len(Fs) and _volume(Vs, Fs) < 0:
        Fs = Fs[:, ::-1]
    # pockets the winding number left inside (closed voids) and crumbs go: a print body is solid
    comp = _components(Fs, len(Vs))
    vols = np.array([_volume(Vs, Fs[comp == c]) for c in range(comp.max() + 1)]) if len(Fs) else np.zeros(0)
    Fs = Fs[vols[comp] >= ISLAND_MIN_VOLUME * vols[vols > 0].sum()] if len(Fs) else Fs
    used = np.unique(Fs)
    remap = np.full(len(Vs), -1, np.int64)
    remap[used] = np.arange(len(used))
    Vs, Fs = Vs[used], remap[Fs]
    if len(Fs) > WINDING_MAX_FACES:  # cells smaller than the details of a low-poly body: fewer, larger triangles
        simpler = simplify_surface(Vs, Fs, WINDING_MAX_FACES)
        if simpler is not None and not _touches_itself(*simpler):
            Vs, Fs = simpler
    return Vs, Fs
