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
from ..copyleft.cgal import intersecting_faces, self_union, split_at_crossings
from .gridsurface import ISLAND_MIN_VOLUME, grid_surface  # noqa: F401 (re-exported)
from .meshes import closes_up
from .simplify import simplify_surface
from .surfaceops import _collapse_short_edges, _components, _flip_caps, _is_closed, _volume, _weld, transfer_values

__all__ = ["ISLAND_MIN_VOLUME", "LOCAL_FACES", "SIMPLIFY_TOLERANCE", "WINDING_CELLS", "local_union", "united_surface",
           "winding_surface"]


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

#: A surface with more triangles than this has its crossings resolved where they are (:func:`local_union`): the
#: whole self-union of the bunny subdivided four times (1.8 million triangles, three crossing pairs where the
#: ears touch) took 40 s and each check of it 11 s, for a few triangles' change.
LOCAL_FACES = 250_000

#: Rings of triangles (through shared corners) around the crossing ones that :func:`local_union` cuts with
#: them: the surface it changes ends two triangles away from any crossing, on edges nothing cuts.
LOCAL_RINGS = 2

LOCALLY = "where they cross"


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
    found = intersecting_faces(V, F)
    pairs = len(found)
    before = _volume(V, F)
    log: list[str] = []
    Vx, Fx, _ = _resolve_crossings(V, F, np.zeros((len(V), 0)), SIMPLIFY_TOLERANCE * size, log, found, np.float32)
    after = _volume(Vx, Fx)
    how = "none" if not pairs else ("exact self-union" if "exact self-union" in log[0] else "winding-number surface")
    return Vx, Fx, {"pairs": pairs, "volume_before": before, "volume": after, "merged_volume": before - after,
                    "how": how, "note": log[0] if log else ""}


def _resolve_crossings(V, F, values, tol, log, pairs=None, stored=np.float64):
    """Remove crossing triangles: CGAL's exact self-union, else the winding-number surface.

    The self-union keeps every detail; the slivers it leaves are collapsed
    (and flattened caps flipped, unless that makes triangles cross again).
    When it leaves crossings (also once rescaled: points left exactly on a
    face) or edges shared by four triangles (parts that touch along an
    edge), the body is remade from its winding number (:func:`winding_surface`):
    closed, free of crossings, true to a grid cell of :data:`WINDING_CELLS`.
    Returns the surface and its values (carried from the surface before by
    closest point); ``log`` gets a line when there were crossings, and says
    how many remain. ``pairs``: the crossing pairs, when found already. A
    surface of more than :data:`LOCAL_FACES` triangles is united where it
    crosses (:func:`local_union`), the whole of it only when that fails.
    Either union must also be free of crossings once stored as ``stored``.
    """
    pairs = intersecting_faces(V, F) if pairs is None else pairs
    before = len(pairs)
    if before == 0:
        return V, F, values
    if len(F) > LOCAL_FACES:
        found = local_union(V, F, pairs, tol, stored)
        if found is not None:
            Vx, Fx, source = found
            out = values[np.maximum(source, 0)]
            if np.any(source < 0):
                out[source < 0] = transfer_values(Vx[source < 0], V, F, values)
            log.append(f"resolved {before} pairs of crossing triangles by an exact self-union {LOCALLY} "
                       f"(volume {(_volume(Vx, Fx) / _volume(V, F) - 1) * 100:+.2f} %)")
            return Vx, Fx, out
    try:
        Vx, Fx = self_union(V, F)
        Vx, Fx, _, _ = _weld(Vx, Fx, np.zeros((len(Vx), 0)), tol * 1e-3)
        Vx, Fx, _ = _collapse_short_edges(Vx, Fx, np.zeros((len(Vx), 0)), tol)
        flipped = _flip_caps(Vx, Fx, tol)
        if len(intersecting_faces(Vx, flipped)) == 0:
            Fx = flipped
        if (len(Fx) and _is_closed(Fx) and not _touches_itself(Vx, Fx)
                and (np.dtype(stored) == np.float64  # and as the file stores it (an STL's float32)
                     or not len(intersecting_faces(Vx.astype(stored).astype(np.float64), Fx)))):
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


def local_union(vertices: np.ndarray, faces: np.ndarray, pairs: np.ndarray, tol: float,
                stored=np.float64) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The self-union of a large surface made only where it crosses itself.

    The crossing triangles and :data:`LOCAL_RINGS` rings around them are cut along the crossing curves (CGAL's
    exact cut); the surface falls into pieces bounded by those curves, and a piece is kept where it bounds the
    solid: a point just in front of it outside, one just behind it inside (libigl's fast winding number of the
    whole surface, by the vote of the piece's largest triangles). What another part swallowed goes, including a
    piece that sank whole into it, and so does the sheet of a fold. The
    slivers of the cut are collapsed and its flat caps flipped; every triangle away from the crossings is kept as
    it was. What it changed is checked where it changed: closed, and no triangles crossing, as given, rescaled,
    and stored as ``stored`` (an STL's float32).

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, outward oriented.
    pairs : (k, 2) int64
        Its crossing triangle pairs (:func:`~supportless.copyleft.cgal.intersecting_faces`), k > 0.
    tol : float
        Edges shorter than this are collapsed.
    stored : numpy dtype
        The precision the result must also be free of crossings in.

    Returns
    -------
    vertices : (n', 3) float64
    faces : (f', 3) int64
    source : (n',) int64
        The input vertex each output vertex is, or -1 for a point on a crossing curve.
    None
        When the result is not closed or still crosses itself there: the caller unites the whole surface.
    """
    import igl

    V, F = np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
    n = len(V)
    region = np.zeros(len(F), bool)
    region[np.unique(pairs)] = True
    for _ in range(LOCAL_RINGS):
        corner = np.zeros(n, bool)
        corner[F[region]] = True
        region |= corner[F].any(axis=1)
    used, local = np.unique(F[region], return_inverse=True)
    Vs, Fs, _ = split_at_crossings(V[used], local.reshape(-1, 3))
    ids = np.concatenate([used, n + np.arange(len(Vs) - len(used))])  # the cut's points among all points
    Va = np.vstack([V, Vs[len(used):]])
    rest = F[~region]
    Fa = np.vstack([rest, ids[Fs]])
    piece = _pieces(Fa, n, len(rest))
    vote = _bounding(Va, Fa, piece, V, F)
    for choice in _choices(vote, np.bincount(piece)):
        found = _assembled(Va, Fa, choice[piece], n, len(rest), used, tol, stored)
        if found is not None:
            return found
    return None


#: How many ways of keeping the pieces :func:`local_union` tries: the vote's, then with the smaller pieces' verdicts
#: turned (one, then two, ...): a fold's pieces are a few triangles each, whose points just in front and behind
#: can fall on either side of a sheet a hair away.
LOCAL_CHOICES = 16


def _choices(vote: np.ndarray, sizes: np.ndarray):
    """The ways of keeping pieces to try: ``vote``, then with the verdicts of up to all pieces but the largest
    turned, fewest turned first, smallest pieces first; at most :data:`LOCAL_CHOICES`."""
    from itertools import combinations, islice

    others = [int(k) for k in np.argsort(sizes, kind="stable") if k != int(np.argmax(sizes))]

    def ways():
        for count in range(len(others) + 1):
            for turned in combinations(others, count):
                choice = vote.copy()
                choice[list(turned)] = ~choice[list(turned)]
                yield choice

    return islice(ways(), LOCAL_CHOICES)


def _assembled(Va, Fa, keep, n, untouched, used, tol, stored):
    """:func:`local_union`'s surface of the kept triangles ``keep`` (f,) bool of ``Fa`` (the ``untouched`` first,
    then the cut's), tidied and checked where the cut changed it; ``(vertices, faces, source)`` or None."""
    cut = keep.copy()
    cut[:untouched] = False
    # the cut's kept triangles tidied on their own; the points they share with the untouched ones must not move
    T = Fa[cut]
    if len(T) == 0:
        return None
    tv, tl = np.unique(T, return_inverse=True)
    shared = np.zeros(len(Va), bool)
    shared[Fa[keep & ~cut].ravel()] = True
    Vt, Tt, idt = _collapse_short_edges(Va[tv], tl.reshape(-1, 3), tv[:, None].astype(np.float64), tol)
    # a point the tidying left alone keeps its index (the mean of one) and its place
    back = np.array([int(i) if i == int(i) and shared[int(i)] and np.array_equal(p, Va[int(i)]) else -1
                     for i, p in zip(idt[:, 0], Vt)], np.int64)
    if not np.isin(tv[shared[tv]], back).all():
        return None
    fresh = back < 0
    Vb = np.vstack([Va, Vt[fresh]])
    slot = np.where(fresh, len(Va) + np.cumsum(fresh) - 1, back)
    kept = np.vstack([Fa[keep & ~cut], slot[Tt]])
    mark = np.zeros(len(Vb), bool)
    mark[kept.ravel()] = True
    remap = np.cumsum(mark) - 1
    Vx, Fx = Vb[mark], remap[kept]
    source = np.where(np.flatnonzero(mark) < n, np.flatnonzero(mark), -1)
    first_cut = int(np.count_nonzero(keep & ~cut))
    near = np.zeros(len(Vx), bool)  # the points whose edges the cut may have changed
    near[Fx[first_cut:].ravel()] = True
    near[remap[used[mark[used]]]] = True
    if not _closed_near(Fx, near):
        return None
    flipped = Fx.copy()
    flipped[first_cut:] = _flip_caps(Vx, Fx[first_cut:], tol)
    for candidate in (flipped, Fx):
        box = _faces_near(Vx, candidate, first_cut, tol)
        Vn, Fn = Vx, candidate[box]
        if (_closed_near(candidate, near) and not _touches_itself(Vn, Fn)
                and not len(intersecting_faces(Vn.astype(stored).astype(np.float64), Fn))):
            return Vx, candidate, source
    return None


def _pieces(F: np.ndarray, n: int, start: int) -> np.ndarray:
    """(f,) int64: the piece of each triangle of a surface cut along curves, in 0..k-1.

    Among the cut's triangles (from ``start`` on), two are joined across an edge only they share (an edge on a
    curve has four); any two through an input point (``< n``) that is on no curve (a crossing of triangles with
    a common corner, a fold, runs through that corner).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    f = len(F)
    cut = F[start:]
    E = np.sort(np.concatenate([cut[:, [0, 1]], cut[:, [1, 2]], cut[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(start, f), 3)
    _, inverse, count = np.unique(E, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    on_curve = np.zeros(int(F.max()) + 1, bool)
    on_curve[E[count[inverse] > 2].ravel()] = True
    corner = F.ravel()
    joins = (corner < n) & ~on_curve[corner]
    two = count[inverse] == 2
    order = np.argsort(inverse[two], kind="stable")
    ends = owner[two][order].reshape(-1, 2)
    rows = np.concatenate([np.repeat(np.arange(f), 3)[joins], ends[:, 0]])
    cols = np.concatenate([corner[joins] + f, ends[:, 1]])
    A = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(f + n, f + n))
    _, labels = connected_components(A, directed=False)
    return np.unique(labels[:f], return_inverse=True)[1].ravel()


#: Triangles of a piece that vote on whether it bounds the solid (the largest ones; an odd number: no tie).
VOTERS = 9


def _bounding(Va, Fa, piece, V, F) -> np.ndarray:
    """(k,) bool: whether each piece bounds the solid (V, F) encloses: most of its voters have a winding number
    under 1/2 just in front and at least 1/2 just behind."""
    import igl

    a, b, c = Va[Fa[:, 0]], Va[Fa[:, 1]], Va[Fa[:, 2]]
    normal = np.cross(b - a, c - a)
    area2 = np.linalg.norm(normal, axis=1)
    order = np.lexsort((-area2, piece))
    start = np.searchsorted(piece[order], np.arange(piece.max() + 1))
    rank = np.arange(len(order)) - start[piece[order]]
    voters = order[(rank < VOTERS) & (area2[order] > 0)]
    unit = normal[voters] / area2[voters, None]
    step = unit * (0.01 * np.sqrt(area2[voters]))[:, None]
    centre = (a + b + c)[voters] / 3
    w = np.asarray(igl.fast_winding_number(V, F, np.ascontiguousarray(np.vstack([centre + step, centre - step]))),
                   np.float64).ravel()
    bounds = (w[:len(voters)] < 0.5) & (w[len(voters):] >= 0.5)  # outside in front, inside behind
    out = np.ones(piece.max() + 1, bool)
    for k in np.unique(piece[voters]):
        out[k] = np.median(bounds[piece[voters] == k]) > 0.5
    return out


def _closed_near(F: np.ndarray, near: np.ndarray) -> bool:
    """Whether every edge with an end among the ``near`` points is in two triangles, in opposite directions."""
    touching = F[near[F].any(axis=1)]
    E = np.concatenate([touching[:, [0, 1]], touching[:, [1, 2]], touching[:, [2, 0]]])
    E = E[near[E].any(axis=1)]
    return closes_up(E)


def _faces_near(V: np.ndarray, F: np.ndarray, start: int, tol: float) -> np.ndarray:
    """(f,) bool: the triangles whose bounding box meets that of a connected group of the triangles from
    ``start`` on (two that cross share a point, so a pair with one of those has both here)."""
    corners = V[F]
    lo, hi = corners.min(axis=1) - tol, corners.max(axis=1) + tol
    group = _components(F[start:], len(V))
    near = np.zeros(len(F), bool)
    for g in range(group.max() + 1 if len(group) else 0):
        mine = start + np.flatnonzero(group == g)
        near |= np.all((hi >= lo[mine].min(axis=0)) & (lo <= hi[mine].max(axis=0)), axis=1)
    return near


def _touches_itself(V, F) -> bool:
    """Whether triangles cross, as given or rescaled (points a union leaves exactly on a face cross once rounded)."""
    return any(len(intersecting_faces(V * k, F)) for k in (1.0, 1000.0 / np.sqrt(2.0), 1.0 / np.pi))


def winding_surface(V, F, cells: int = WINDING_CELLS):
    """:func:`~supportless.files.gridsurface.grid_surface` of (V, F) by winding number (shells may cross), simplified
    to at most :data:`WINDING_MAX_FACES` triangles when that stays closed and free of crossings.

    Returns vertices (k, 3) float64 and outward faces (g, 3) int64.
    """
    Vs, Fs = grid_surface(V, F, cells)
    if len(Fs) > WINDING_MAX_FACES:  # cells smaller than the details of a low-poly body: fewer, larger triangles
        simpler = simplify_surface(Vs, Fs, WINDING_MAX_FACES)
        if simpler is not None and not _touches_itself(*simpler):
            Vs, Fs = simpler
    return Vs, Fs
