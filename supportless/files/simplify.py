"""A closed surface simplified to fewer triangles, closed and free of self-intersections: the proxy a dense
model is searched through, and the surface a volume mesh is made of.

libigl's careful collapses (:func:`simplify_surface`) keep the surface from crossing itself and its triangles
even (the volume mesh and its weights need both); they take about two minutes on a sculpt of 1.8M triangles.
A surface of more than :data:`FAST_FIRST_FACES` triangles is therefore first reduced to
:data:`FAST_FIRST_TARGET` by ``fast_simplification``'s quadric collapses (:func:`quickly_reduced`: seconds),
its clusters of near-coincident vertices welded (they left vertices of almost no volume around them, and the
weight solve failed on them), and kept only when it is closed and does not cross itself; libigl takes it from
there. The fast collapses alone serve where only the shape counts: the copies of a sculpt's answers that are
sliced to choose among them (:func:`reduced_alike`).
"""

from __future__ import annotations

import numpy as np

from ..base.errors import InputError
from ..base.geometry import signed_volume, surface_digest

__all__ = ["FAST_FIRST_FACES", "FAST_FIRST_TARGET", "PROXY_CELLS", "SLICE_FACES", "folded_pairs", "quickly_reduced",
           "reduced_alike", "simplify_surface"]

#: A surface of more triangles than this is reduced by quadric collapses to :data:`FAST_FIRST_TARGET` before
#: libigl's careful collapses (the 1.8M-triangle bunny: 124 s of libigl alone, 15 s both ways). Surfaces up
#: to here (the zoo, the 111k bunny) are simplified by libigl alone, as they always were.
FAST_FIRST_FACES = 400_000
FAST_FIRST_TARGET = 200_000

#: A sculpt's proxy is collapsed from the surface of its quick reduction's winding number on a grid of this many
#: cells along the longest side (:func:`~supportless.files.gridsurface.grid_surface`: even triangles, a cell
#: 0.3 mm on a 60 mm print), not from the quick reduction itself: collapsed from that, the 5.35M bunny's proxy
#: had 292 pairs of adjacent triangles folded onto each other and its answer 21 % less support (the 1.8M bunny's
#: 65 %); from the grid's surface it has none, and the answers are 64.4 % and 63.9 %. 120 cells answered the
#: 1.8M bunny with 58.6 % (``benchmarks/RESULTS.md``, "Sculpts", 2026-11-28). The grid's surface is collapsed
#: without libigl's test of every collapse for crossings (the 1.8M bunny's: 12.0 s with it, 2.7 s without, both
#: clean); the result is checked (closed, uncrossed, unfolded) and collapsed again with the test when it is not.
PROXY_CELLS = 200

#: Edges shorter than this fraction of the median edge of a quickly reduced surface are welded to a point.
WELD_FRACTION = 1e-2

def simplify_surface(vertices: np.ndarray, faces: np.ndarray, max_faces: int,
                     fast_first: bool = True) -> tuple[np.ndarray, np.ndarray] | None:
    """A closed surface simplified to at most ``max_faces`` triangles (libigl's ``decimate``).

    Shortest edges collapse first, to their midpoints (the even triangles a
    volume mesh and its weights need; quadric placement left slivers that
    made the weight solve fail); collapses that would make the surface cross
    itself are refused.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, manifold.
    max_faces : int
    fast_first : bool
        Past :data:`FAST_FIRST_FACES` triangles, start from :func:`quickly_reduced` when it gives a clean
        surface, and for a proxy (``max_faces`` under :data:`FAST_FIRST_TARGET`) from that one's winding-number
        surface on :data:`PROXY_CELLS` cells (False: libigl's collapses all the way, the slow and sure way).

    Returns
    -------
    simplified : ((n', 3) float64, (f', 3) int64) or None
        None when the result is not a closed, consistently oriented surface.
    """
    import igl

    gridded = False
    if fast_first and len(faces) > max(FAST_FIRST_FACES, max_faces):
        from .gridsurface import grid_surface

        quick = quickly_reduced(vertices, faces, FAST_FIRST_TARGET)
        if quick is not None:
            vertices, faces = quick
            if max_faces < FAST_FIRST_TARGET:  # a proxy: remade on a grid first, so no collapse folds it
                vertices, faces = grid_surface(vertices, faces, PROXY_CELLS, closed=True)  # (checked closed)
                gridded = True

    from .meshes import check_closed_surface

    def collapsed(block):
        U, G, _, _ = igl.decimate(np.asfortranarray(vertices, np.float64), np.asfortranarray(faces, np.int32),
                                  int(max_faces), block)
        return np.ascontiguousarray(U, np.float64), np.ascontiguousarray(G, np.int64)

    U, G = collapsed(not gridded)
    if gridded and not _clean(U, G):  # the grid's even surface seldom needs a collapse refused; when it did
        U, G = collapsed(True)
    try:
        check_closed_surface(G)
    except InputError:
        return None
    return (U, G) if signed_volume(U, G) > 0 else (U, G[:, ::-1].copy())


def _clean(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """Whether a surface is closed, crosses itself nowhere (CGAL's exact test) and has no folded pair."""
    from ..copyleft.cgal import self_intersects
    from .meshes import check_closed_surface

    try:
        check_closed_surface(faces)
    except InputError:
        return False
    return not self_intersects(vertices, faces) and len(folded_pairs(vertices, faces)) == 0


def quickly_reduced(vertices: np.ndarray, faces: np.ndarray,
                    max_faces: int) -> tuple[np.ndarray, np.ndarray] | None:
    """A closed surface reduced by quadric collapses (``fast_simplification``), checked clean, or None.

    Collapses leave small clusters of nearly coincident vertices (edges of 1e-8 of the model's size on the
    1.8M-triangle bunny); every edge shorter than :data:`WELD_FRACTION` of the median edge is welded to its
    cluster's centre and the triangles it flattens are dropped.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, manifold.
    max_faces : int

    Returns
    -------
    reduced : ((n', 3) float64, (f', 3) int64) or None
        Closed, manifold, outward, no two triangles crossing (CGAL's exact test); None when the reduction is
        not all of that (the caller then simplifies the surface the slow way). The last two answers are
        kept, by their input's digest (the proxy's reduction is the measuring surface's,
        :meth:`supportless.rig.rig.Rig.measure_rig`).
    """
    key = (surface_digest(vertices, faces), int(max_faces))
    if key not in _quick:
        _quick[key] = _quickly_reduced(vertices, faces, max_faces)
        while len(_quick) > 2:
            _quick.pop(next(iter(_quick)))
    return _quick[key]


_quick: dict = {}  # the last quick reductions, by their input's digest: the proxy's serves the measuring surface


def _quickly_reduced(vertices, faces, max_faces):
    """:func:`quickly_reduced`, computed."""
    import fast_simplification
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from ..copyleft.cgal import self_intersects
    from .meshes import check_closed_surface, edge_counts

    U, G = fast_simplification.simplify(np.asarray(vertices, np.float32), np.asarray(faces, np.int32),
                                        target_count=int(max_faces))
    U, G = np.asarray(U, np.float64), np.asarray(G, np.int64)
    E, _ = edge_counts(G)
    length = np.linalg.norm(U[E[:, 0]] - U[E[:, 1]], axis=1)
    short = E[length < WELD_FRACTION * np.median(length)]
    graph = coo_matrix((np.ones(len(short)), (short[:, 0], short[:, 1])), shape=(len(U), len(U)))
    _, cluster = connected_components(graph, directed=False)
    size = np.bincount(cluster)
    centre = np.zeros((len(size), 3))
    np.add.at(centre, cluster, U)
    G = cluster[G]
    G = G[(G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 2] != G[:, 0])]
    used, G = np.unique(G, return_inverse=True)
    U, G = centre[used] / size[used, None], G.reshape(-1, 3)
    try:
        check_closed_surface(G)
    except InputError:
        return None
    if signed_volume(U, G) <= 0 or self_intersects(U, G):
        return None
    return U, G


#: A sculpt's answers are sliced (to choose among them) from copies of this many triangles: the slicer's
#: support is the same to its noise, and slicing four 1.8M-triangle answers took PrusaSlicer about 2 minutes.
SLICE_FACES = 200_000


def reduced_alike(vertex_sets: list[np.ndarray], faces: np.ndarray, max_faces: int):
    """Several poses of one surface reduced by the same collapses, so they stay poses of one mesh.

    The collapses are those of the first pose (``fast_simplification``'s quadric collapses). Each reduced
    vertex takes, in every pose, the position of one of the vertices collapsed into it: a point of that pose's
    surface (replaying the collapses' quadric placement on a bent pose put vertices far off the body, and a
    slicer refused the mesh as taller than its printer). A surface of at most ``max_faces`` triangles is
    returned as it is.

    Parameters
    ----------
    vertex_sets : list of (n, 3) float64
        The poses.
    faces : (f, 3) int64
    max_faces : int

    Returns
    -------
    reduced : list of (n', 3) float64
    faces : (f', 3) int64
        ``f' <= max_faces``, shared by every reduced pose.
    """
    if len(faces) <= max_faces:
        return [np.asarray(V, np.float64) for V in vertex_sets], np.asarray(faces, np.int64)
    import fast_simplification

    F = np.asarray(faces, np.int32)
    first = np.asarray(vertex_sets[0], np.float32)
    _, _, collapses = fast_simplification.simplify(first, F, target_count=max_faces, return_collapses=True)
    _, G, into = fast_simplification.replay_simplification(first, F, collapses)  # into: (n,) reduced vertex of each
    order = np.argsort(into, kind="stable")
    starts = np.r_[True, into[order][1:] != into[order][:-1]]
    kept = np.empty(int(into.max()) + 1, np.int64)
    kept[into[order][starts]] = order[starts]  # one original vertex per reduced vertex
    return [np.asarray(V, np.float64)[kept] for V in vertex_sets], np.asarray(G, np.int64)


def folded_pairs(vertices: np.ndarray, faces: np.ndarray, limit: float = -0.99) -> np.ndarray:
    """The pairs of triangles that share an edge and lie folded onto each other (their normals opposite).

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, manifold: each edge in two triangles.
    limit : float
        Normals whose dot product is below this are opposite.

    Returns
    -------
    pairs : (k, 2) int64
        Face indices, each pair once.
    """
    V, F = np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
    normal = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(F)), 3)
    order = np.lexsort((E[:, 1], E[:, 0]))
    a, b = owner[order][0::2], owner[order][1::2]  # each edge's two triangles, side by side once sorted
    return np.column_stack([a, b])[np.einsum("ij,ij->i", normal[a], normal[b]) < limit]
