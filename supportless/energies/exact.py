"""Exact self-intersection test of a triangle surface (CGAL through libigl).

The ray-grid estimate (:mod:`supportless.energies.intersection`) steers the
search away from overlaps but cannot see overlaps thinner than a grid cell.
This module answers exactly which triangle pairs intersect. It is the only
place in the package that calls ``igl.copyleft.cgal`` (GPL-licensed CGAL code
inside libigl's wheel).
"""

from __future__ import annotations

import numpy as np

__all__ = ["broad_phase_groups", "faces_that_can_meet", "intersecting_faces", "intersecting_face_pairs",
           "rigid_face_groups", "self_intersects"]


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


def self_intersects(vertices: np.ndarray, faces: np.ndarray, groups: np.ndarray | None = None) -> bool:
    """Whether any two triangles intersect (CGAL's exact predicates), stopping at the first pair found.

    Half the time of :func:`intersecting_faces` on a surface that does
    intersect itself (the search's rejected candidates); the same on one that
    does not.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    groups : (f,) int64, optional
        Rigid parts (:func:`rigid_face_groups`) of a surface whose rest pose
        does not intersect itself: then only the faces that can meet another
        part (:func:`faces_that_can_meet`) go to CGAL, with the same answer.

    Returns
    -------
    intersects : bool
    """
    if groups is not None:
        faces = np.asarray(faces)[faces_that_can_meet(vertices, faces, groups)]
        if len(faces) < 2:
            return False
    return len(_detect(vertices, faces, first_only=True)) > 0


def rigid_face_groups(weights: np.ndarray, faces: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """The bone each triangle follows rigidly, or -1.

    A triangle whose three vertices all have weight 1 (within ``tol``) on one
    bone moves rigidly with it: two such triangles of the same bone keep
    their rest relation in every pose, so if they did not intersect at rest
    they never do. Game characters skinned part by part (a robot, armour) are
    mostly rigid parts; bounded biharmonic weights blend everywhere, and
    their triangles are -1.

    Parameters
    ----------
    weights : (n, m) float64
        Skinning weights of the surface vertices.
    faces : (f, 3) int64

    Returns
    -------
    groups : (f,) int64
        The bone, or -1 for a triangle that blends bones.
    """
    W = np.asarray(weights, np.float64)
    bone = np.argmax(W, axis=1)
    rigid = W[np.arange(len(W)), bone] >= 1.0 - tol
    F = np.asarray(faces, np.int64)
    same = rigid[F].all(axis=1) & (bone[F[:, 0]] == bone[F[:, 1]]) & (bone[F[:, 0]] == bone[F[:, 2]])
    return np.where(same, bone[F[:, 0]], -1).astype(np.int64)


def faces_that_can_meet(vertices: np.ndarray, faces: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """The triangles that may intersect another one, given rigid parts (a broad phase).

    Every blending triangle (group -1), and every rigid one whose bounding box
    overlaps the bounding box of another group's triangles (a rigid part's
    triangles cannot intersect each other, see :func:`rigid_face_groups`).
    Two intersecting triangles have overlapping boxes, so every intersecting
    pair has both triangles in the result.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    groups : (f,) int64

    Returns
    -------
    kept : (q,) int64
        Indices into ``faces``, increasing.
    """
    T = np.asarray(vertices, np.float64)[np.asarray(faces, np.int64)]
    lo, hi = T.min(axis=1), T.max(axis=1)
    labels, inverse = np.unique(groups, return_inverse=True)
    g = len(labels)
    glo = np.full((g, 3), np.inf)
    ghi = np.full((g, 3), -np.inf)
    np.minimum.at(glo, inverse, lo)
    np.maximum.at(ghi, inverse, hi)
    # faces x groups box overlap, one group at a time (g is at most the bone count + 1)
    meets = groups < 0
    for k in range(g):
        overlap = np.all((lo <= ghi[k]) & (hi >= glo[k]), axis=1) & (inverse != k)
        meets |= overlap
    return np.flatnonzero(meets)


def _detect(vertices, faces, first_only: bool) -> np.ndarray:
    """(k, 2) int64 intersecting face pairs from CGAL (only the first found with ``first_only``)."""
    V = np.ascontiguousarray(vertices, np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"vertices must be (n, 3) for the exact test, not {V.shape}")
    import igl
    import igl.copyleft.cgal  # noqa: F401  (registers the submodule)

    out = igl.copyleft.cgal.remesh_self_intersections(V, np.ascontiguousarray(faces, np.int64), detect_only=True,
                                                       first_only=first_only)
    return np.asarray(out[2], np.int64).reshape(-1, 2)


def broad_phase_groups(vertices: np.ndarray, faces: np.ndarray, weights: np.ndarray) -> np.ndarray | None:
    """The ``groups`` to give :func:`self_intersects` for the poses of a rig, or None when they cannot help.

    None when no triangle is rigid, or when the rest surface (``vertices``)
    intersects itself (then a rigid part may already hold an intersecting
    pair, which the broad phase would skip).

    Parameters
    ----------
    vertices : (n, 3) float64
        Rest surface.
    faces : (f, 3) int64
    weights : (n, m) float64

    Returns
    -------
    groups : (f,) int64 or None
    """
    groups = rigid_face_groups(weights, faces)
    if np.all(groups < 0) or self_intersects(vertices, faces):
        return None
    return groups
