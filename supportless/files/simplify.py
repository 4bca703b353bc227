"""A closed surface simplified to fewer triangles, closed and free of self-intersections: the proxy a dense
model is searched through, and the surface a volume mesh is made of.

libigl's careful collapses (:func:`simplify_surface`) keep the surface from crossing itself and its triangles
even (the volume mesh and its weights need both); they take about two minutes on a sculpt of 1.8M triangles.
A surface first reduced fast to 200 000 triangles (``fast_simplification``'s quadric collapses), then by
libigl, took 20 s but its volume mesh failed the weight solve on the 1.8M-triangle bunny, so the proxy is made
by libigl alone. The fast collapses serve where only the shape counts: the copies of a sculpt's answers
that are sliced to choose among them (:func:`reduced_alike`).
"""

from __future__ import annotations

import numpy as np

from ..base.errors import InputError
from ..base.geometry import signed_volume

__all__ = ["SLICE_FACES", "reduced_alike", "simplify_surface"]

def simplify_surface(vertices: np.ndarray, faces: np.ndarray, max_faces: int) -> tuple[np.ndarray, np.ndarray] | None:
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

    Returns
    -------
    simplified : ((n', 3) float64, (f', 3) int64) or None
        None when the result is not a closed, consistently oriented surface.
    """
    import igl

    from .meshes import check_closed_surface

    U, G, _, _ = igl.decimate(np.asfortranarray(vertices, np.float64), np.asfortranarray(faces, np.int32),
                              int(max_faces), True)
    U, G = np.ascontiguousarray(U, np.float64), np.ascontiguousarray(G, np.int64)
    try:
        check_closed_surface(G)
    except InputError:
        return None
    return (U, G) if signed_volume(U, G) > 0 else (U, G[:, ::-1].copy())


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
