"""Exact self-intersection of a triangle surface, and its removal (CGAL through libigl).

The ray-grid estimate (:mod:`supportless.energies.intersection`) steers the
search away from overlaps but cannot see overlaps thinner than a grid cell.
This module answers exactly which triangle pairs intersect, and resolves them
on a print body whose shells cut each other (:func:`self_union`). It is the
only place in the package that calls ``igl.copyleft.cgal`` (GPL-licensed CGAL
code inside libigl's wheel).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from ..base.crossing_filter import possibly_crossing_faces
from ..base.geometry import surface_digest

__all__ = ["PART_FACES", "face_parts", "intersecting_faces", "intersecting_faces_since", "intersecting_face_pairs",
           "self_intersects", "self_union", "split_at_crossings"]

#: A surface with more triangles than this is checked in parts (:func:`face_parts`), one CGAL call each: the
#: same pairs, in a fraction of the memory (CGAL's exact kernel holds every triangle of a part at once; the
#: bunny subdivided four times, 1.8 million triangles, in one call peaked at about 6 GB). The answers of the
#: last :data:`REMEMBERED` such surfaces are kept, keyed by their bytes: a report that counts the pairs of a
#: pose the search checked already does not ask CGAL again.
PART_FACES = 250_000
REMEMBERED = 8

_answers: OrderedDict = OrderedDict()  # (vertices' and faces' digest) -> (pairs or None, intersects)


def intersecting_faces(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The pairs of triangles that intersect each other, by CGAL's exact predicates.

    Triangles that share a vertex or an edge and touch only there do not count.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64

    Returns
    -------
    pairs : (k, 2) int64
        Face indices of each intersecting pair; ``k = 0`` for a surface free
        of self-intersections.

    Raises
    ------
    ValueError
        For a planar (2D) mesh: its overlaps are areas, measured by
        :func:`supportless.energies.intersection.self_intersection_volume`.
    """
    return _detect(vertices, faces, first_only=False)


#: :func:`intersecting_faces_since` asks CGAL about the whole surface when the triangles near those that moved are
#: more than this share of it (a part costs about as much as the whole then).
NEAR_SHARE = 0.6


def intersecting_faces_since(vertices: np.ndarray, faces: np.ndarray, before: np.ndarray | None = None,
                             pairs_before: np.ndarray | None = None) -> np.ndarray:
    """:func:`intersecting_faces` of a surface whose earlier state's pairs are known, asking CGAL only about the
    triangles that moved and those their bounding box meets.

    A pair of triangles neither of which moved intersects as it did; a pair with one that moved has both in the
    box of the moved triangles, so it is among the pairs of the triangles asked (one CGAL call on them, shared
    vertices kept shared). An edit of one bone of a skinned character moves the triangles it weighs on.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    before : (n, 3) float64, optional
        The same surface's vertices when ``pairs_before`` was found (None, or another shape: the whole surface
        is asked).
    pairs_before : (k, 2) int64, optional
        Its pairs (:func:`intersecting_faces`, or this function's).

    Returns
    -------
    pairs : (k', 2) int64
        Each pair once, smaller face first, sorted.
    """
    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    if before is None or np.shape(before) != V.shape:
        return _normalised(intersecting_faces(V, F))
    moved = np.any(V != np.asarray(before, np.float64), axis=1)[F].any(axis=1)
    old = _normalised(pairs_before)
    if not moved.any():
        return old
    corners = V[F]
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    near = np.all((hi >= lo[moved].min(axis=0)) & (lo <= hi[moved].max(axis=0)), axis=1)
    if near.mean() > NEAR_SHARE:
        return _normalised(intersecting_faces(V, F))
    found = _pairs_of_parts(V, F, [np.flatnonzero(near)], False)
    return _normalised(np.concatenate([old[~moved[old].any(axis=1)], *found]))


def _normalised(pairs) -> np.ndarray:
    """(k, 2) int64: each pair once, smaller face first, sorted."""
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    return np.unique(np.sort(pairs, axis=1), axis=0)


def intersecting_face_pairs(vertices: np.ndarray, faces: np.ndarray) -> int:
    """Number of intersecting triangle pairs (:func:`intersecting_faces`), -1 for a 2D mesh.

    Parameters
    ----------
    vertices : (n, 3) or (n, 2) float64
    faces : (f, 3) int64

    Returns
    -------
    count : int
        0 for a surface free of self-intersections; -1 for a planar mesh,
        which has no exact test.
    """
    if np.shape(vertices)[-1] != 3:
        return -1
    return int(len(intersecting_faces(vertices, faces)))


def self_intersects(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """Whether any two triangles intersect (CGAL's exact predicates), stopping at the first pair found.

    Half the time of :func:`intersecting_faces` on a surface that does
    intersect itself (the search's rejected candidates); the same on one that
    does not.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64

    Returns
    -------
    intersects : bool
    """
    return len(_detect(vertices, faces, first_only=True)) > 0


def _detect(vertices, faces, first_only: bool) -> np.ndarray:
    """(k, 2) int64 intersecting face pairs from CGAL (only the first found with ``first_only``)."""
    V = np.ascontiguousarray(vertices, np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"vertices must be (n, 3) for the exact test, not {V.shape}")
    F = np.ascontiguousarray(faces, np.int64)
    if len(F) <= PART_FACES:
        return _filtered(V, F, first_only)
    key = surface_digest(V, F)
    known = _answers.setdefault(key, {})  # "all": every pair, "first": the first-only answer
    _answers.move_to_end(key)
    while len(_answers) > REMEMBERED:
        _answers.popitem(last=False)
    if "all" in known:
        return known["all"][:1] if first_only else known["all"]
    if "first" in known and (first_only or len(known["first"]) == 0):
        return known["first"]
    pairs = _normalised(_filtered(V, F, first_only))
    known["first" if first_only else "all"] = pairs
    return pairs


def _filtered(V: np.ndarray, F: np.ndarray, first_only: bool) -> np.ndarray:
    """CGAL's pairs among the triangles that floating-point tests cannot prove apart from their neighbours
    (:func:`~supportless.base.crossing_filter.possibly_crossing_faces`): every intersecting pair of the surface,
    as face indices of the whole; none asked of CGAL when every triangle is proven apart."""
    maybe = np.flatnonzero(possibly_crossing_faces(V, F))
    if len(maybe) == 0:
        return np.zeros((0, 2), np.int64)
    used, local = np.unique(F[maybe], return_inverse=True)  # shared corners stay shared
    Vs, Fs = np.ascontiguousarray(V[used]), local.reshape(-1, 3).astype(np.int64)
    pairs = _cgal(Vs, Fs, first_only) if len(Fs) <= PART_FACES else _detect_in_parts(Vs, Fs, first_only)
    return maybe[pairs]


def _cgal(V: np.ndarray, F: np.ndarray, first_only: bool) -> np.ndarray:
    """CGAL's pairs of one surface, as it reports them."""
    import igl
    import igl.copyleft.cgal  # noqa: F401  (registers the submodule)

    out = igl.copyleft.cgal.remesh_self_intersections(V, F, detect_only=True, first_only=first_only)
    return np.asarray(out[2], np.int64).reshape(-1, 2)


def face_parts(vertices: np.ndarray, faces: np.ndarray, count: int) -> list[np.ndarray]:
    """The triangles of each of ``count`` slabs across the surface's longest extent; a triangle is in every slab
    its bounding box meets.

    Two triangles that intersect share a point, so a slab holding that point holds both: the pairs of the
    parts together are the pairs of the whole surface.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    count : int

    Returns
    -------
    parts : list of (f_i,) int64
        Face indices of each slab (none empty), increasing.
    """
    V, F = np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
    axis = int(np.argmax(np.ptp(V, axis=0)))
    x = V[:, axis][F]  # (f, 3): the triangles' extent along the axis
    lo, hi = x.min(axis=1), x.max(axis=1)
    cuts = np.quantile((lo + hi) / 2, np.linspace(0, 1, count + 1)[1:-1]) if count > 1 else np.zeros(0)
    edges = np.concatenate([[-np.inf], cuts, [np.inf]])
    parts = [np.flatnonzero((hi >= a) & (lo <= b)) for a, b in zip(edges[:-1], edges[1:])]
    return [p for p in parts if len(p)]


def _detect_in_parts(V: np.ndarray, F: np.ndarray, first_only: bool) -> np.ndarray:
    """:func:`_detect` of a large surface, part by part (:func:`face_parts`): (k, 2) int64, each pair once,
    smaller face first, sorted."""
    from ..base.isolated import run_beside

    parts = face_parts(V, F, -(-len(F) // PART_FACES))  # half in a forked child, half here: two cores
    theirs, mine = run_beside(_pairs_of_parts, (V, F, parts[1::2], first_only), _pairs_of_parts,
                              (V, F, parts[::2], first_only), what="CGAL's self-intersection check")
    found = mine + theirs
    if not found:
        return np.zeros((0, 2), np.int64)
    return np.unique(np.concatenate(found), axis=0)


def _pairs_of_parts(V: np.ndarray, F: np.ndarray, parts: list[np.ndarray], first_only: bool) -> list[np.ndarray]:
    """The intersecting pairs of each part of a surface that has any, as (k, 2) face indices of the whole (with
    ``first_only``, those CGAL found first in the first such part)."""
    found = []
    for part in parts:
        used, local = np.unique(F[part], return_inverse=True)  # shared vertices stay shared
        pairs = _cgal(np.ascontiguousarray(V[used]), local.reshape(-1, 3).astype(np.int64), first_only)
        if len(pairs):
            found.append(np.sort(part[pairs], axis=1))
            if first_only:
                break
    return found


def self_union(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The outer surface of a surface that cuts itself: its union with nothing, by exact arithmetic.

    CGAL splits every triangle along the curves where others cross it and
    keeps the pieces on the outside (winding number > 0), rounding the new
    vertices to doubles at the end. Runs in a child process
    (:func:`supportless.base.isolated.run_isolated`): a crash inside CGAL is an
    error, not the end of the program.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Outward-oriented; may intersect itself.

    Returns
    -------
    vertices : (n', 3) float64
    faces : (f', 3) int64
        May hold zero-area triangles where the cut curves meet edges
        (:func:`supportless.files.printbody.print_body` collapses them).

    Raises
    ------
    supportless.base.isolated.NativeFailure
        When CGAL fails or crashes.
    """
    from ..base.isolated import run_isolated

    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    return run_isolated(_union_with_nothing, V, F, what="CGAL's self-union")


def _union_with_nothing(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    import igl
    import igl.copyleft.cgal  # noqa: F401  (registers the submodule)

    out = igl.copyleft.cgal.mesh_boolean(V, F, np.zeros((0, 3)), np.zeros((0, 3), np.int64), "union")
    return np.asarray(out[0], np.float64), np.asarray(out[1], np.int64)


def split_at_crossings(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each triangle split along the curves where others cross it (CGAL's exact cut, rounded to doubles).

    The pieces are not sorted into inside and outside: that is the caller's (a self-union keeps those outside the
    solid). Points where curves meet are shared by the pieces of every triangle that meets there.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64

    Returns
    -------
    vertices : (n', 3) float64
        The input's first, unchanged, then the points on the crossing curves.
    faces : (f', 3) int64
        The pieces; a triangle that nothing crosses is one piece, itself.
    parent : (f',) int64
        The input triangle each piece comes from.
    """
    import igl
    import igl.copyleft.cgal  # noqa: F401  (registers the submodule)

    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    VV, FF, _, J, IM = igl.copyleft.cgal.remesh_self_intersections(V, F)
    IM = np.asarray(IM, np.int64)
    FF = IM[np.asarray(FF, np.int64)]  # the copies of a point on a curve, one per triangle, made one
    used = np.unique(np.concatenate([np.arange(len(V)), FF.ravel()]))
    remap = np.full(len(VV), -1, np.int64)
    remap[used] = np.arange(len(used))
    solid = (FF[:, 0] != FF[:, 1]) & (FF[:, 1] != FF[:, 2]) & (FF[:, 2] != FF[:, 0])
    return np.asarray(VV, np.float64)[used], remap[FF[solid]], np.asarray(J, np.int64)[solid]
