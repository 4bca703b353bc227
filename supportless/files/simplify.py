"""A closed surface simplified to fewer triangles, closed and free of self-intersections: the proxy a dense
model is searched through, and the surface a volume mesh is made of.

libigl's careful collapses (:func:`simplify_surface`) keep the surface from crossing itself but take about
two minutes on a sculpt of 1.8M triangles; a sculpt is first reduced fast (``fast_simplification``'s quadric
collapses, :func:`_pre_reduced`) when that result is closed and does not cross itself.
"""

from __future__ import annotations

import numpy as np

from ..base.errors import InputError
from ..base.geometry import signed_volume
from ..copyleft.cgal import intersecting_faces

__all__ = ["PRE_REDUCTION", "PRE_REDUCTION_FACES", "SLICE_FACES", "reduced_alike", "simplify_surface"]

#: Above this many triangles (and :data:`PRE_REDUCTION` times the target), :func:`simplify_surface` first
#: reduces the surface quickly (quadric edge collapse, ``fast_simplification``) to that many: libigl's careful
#: collapses take about 2 minutes on a 1.8M-triangle sculpt and 13 s from 200k. Chosen so a figure of the
#: zoo (at most 111k triangles) is simplified as before.
PRE_REDUCTION_FACES = 200_000
#: The fast reduction stops at this multiple of the target, leaving the last collapses to libigl.
PRE_REDUCTION = 20


def _pre_reduced(vertices: np.ndarray, faces: np.ndarray, max_faces: int) -> tuple[np.ndarray, np.ndarray]:
    """A dense closed surface reduced fast to :data:`PRE_REDUCTION_FACES` triangles when that keeps it closed
    and free of self-intersections (checked); else the surface as it is."""
    keep = max(PRE_REDUCTION_FACES, PRE_REDUCTION * int(max_faces))
    if len(faces) <= keep:
        return vertices, faces
    import fast_simplification

    from .meshes import check_closed_surface

    U, G = fast_simplification.simplify(np.asarray(vertices, np.float32), np.asarray(faces, np.int32),
                                        target_count=keep)
    U, G = np.asarray(U, np.float64), np.asarray(G, np.int64)
    try:
        check_closed_surface(G)
    except InputError:
        return vertices, faces
    if len(G) == 0 or len(intersecting_faces(U, G)):
        return vertices, faces
    return U, G


def simplify_surface(vertices: np.ndarray, faces: np.ndarray, max_faces: int) -> tuple[np.ndarray, np.ndarray] | None:
    """A closed surface simplified to at most ``max_faces`` triangles (libigl's ``decimate``).

    Shortest edges collapse first, to their midpoints (the even triangles a
    volume mesh and its weights need; quadric placement left slivers that
    made the weight solve fail); collapses that would make the surface cross
    itself are refused. A sculpt (over :data:`PRE_REDUCTION_FACES`
    triangles) is first reduced fast to that many, when the result is closed
    and does not cross itself (:func:`_pre_reduced`).

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

    vertices, faces = _pre_reduced(vertices, faces, max_faces)
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

    The collapses are those of the first pose (``fast_simplification``'s quadric collapses), replayed on the
    others. A surface of at most ``max_faces`` triangles is returned as it is.

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
    _, G, collapses = fast_simplification.simplify(np.asarray(vertex_sets[0], np.float32), F, target_count=max_faces,
                                                   return_collapses=True)
    reduced = [np.asarray(fast_simplification.replay_simplification(np.asarray(V, np.float32), F, collapses)[0],
                          np.float64) for V in vertex_sets]
    return reduced, np.asarray(G, np.int64)
