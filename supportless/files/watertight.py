"""A written surface read back as a closed, manifold solid: every edge in exactly two triangles.

A print file (STL above all) has no topology: a reader welds the corners that share a position. Two parts of a
body that touch along an edge or at a corner (modular characters' skins, a union's pieces that meet exactly) are
closed shells each, but once welded their common edge has four triangles and the file is not "closed" to a strict
reader (trimesh's ``is_watertight``, a slicer's repair report). :func:`edge_counts` counts the edges as a reader
sees them (corners welded at the precision the file stores, single for STL and 3MF); :func:`apart_by_a_hair`
moves each shell's copy of such a shared corner onto its own part by a hair (:data:`HAIR`, a share of the size
far above single precision and far below a printer's resolution), so the file reads as the closed shells it is;
:func:`manifold_check` says what a reader finds.
"""

from __future__ import annotations

import numpy as np

from ..base.geometry import row_groups
from .meshes import edge_counts as _edges_and_counts

__all__ = ["HAIR", "apart_by_a_hair", "edge_counts", "manifold_check"]

#: How far a shared corner is moved into its own shell, as a share of the surface's largest extent: 0.6 µm at
#: 60 mm, a hundred steps of single precision there, a five-hundredth of a 0.3 mm print layer.
HAIR = 1e-5


def welded(vertices: np.ndarray, faces: np.ndarray, dtype=np.float32) -> np.ndarray:
    """The faces with corners that share a position (rounded to ``dtype``) made one, as a file reader welds them.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    dtype : numpy dtype
        The precision the file stores (single for STL and 3MF).

    Returns
    -------
    faces : (f, 3) int64
        Indices of the first vertex at each position.
    """
    first, inverse, _ = row_groups(np.asarray(vertices).astype(dtype))
    return first[inverse][np.asarray(faces, np.int64)]


def edge_counts(faces: np.ndarray) -> np.ndarray:
    """How many triangles use each undirected edge of ``faces`` (f, 3) int64; (e,) int64, one per distinct edge."""
    return _edges_and_counts(np.asarray(faces, np.int64))[1]


def manifold_check(vertices: np.ndarray, faces: np.ndarray, dtype=np.float32) -> dict:
    """What a file reader finds of a surface: ``open_edges`` (in one triangle), ``shared_edges`` (in three or more),
    ``closed`` (every edge in exactly two triangles), with corners welded at ``dtype`` (None: ``faces`` as they
    are, their corners welded already)."""
    counts = edge_counts(faces if dtype is None else welded(vertices, faces, dtype))
    open_, shared = int(np.sum(counts == 1)), int(np.sum(counts > 2))
    return {"open_edges": open_, "shared_edges": shared, "closed": open_ == 0 and shared == 0}


def apart_by_a_hair(vertices: np.ndarray, faces: np.ndarray, hair: float = HAIR,
                    dtype=np.float32) -> tuple[np.ndarray, int]:
    """Move every corner whose position another corner shares a hair into its own shell.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, outward oriented shells (each edge in two triangles by index), some of whose corners may share
        positions. A surface that is not (its shells are closed only once welded) is returned as it is.
    hair : float
        The distance, as a share of the largest extent of ``vertices``.
    dtype : numpy dtype
        The precision positions are compared at (the file's).

    Returns
    -------
    vertices : (n, 3) float64
        A copy, each shared corner moved from the middle of the other copies' rings of neighbours toward the
        middle of its own (onto its own side of the contact).
    moved : int
        How many corners moved.
    """
    V = np.array(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    if len(F) == 0:
        return V, 0
    _, inverse, counts = row_groups(V.astype(dtype))
    shared = np.flatnonzero(counts[inverse] > 1)
    shared = shared[np.isin(shared, F)]  # a corner no triangle uses is no edge of the file
    if len(shared) == 0 or np.any(edge_counts(F) != 2):  # none, or not closed shells by index (a seam a reader
        return V, 0  # closes): as it is
    # away from the other copies' rings of neighbours, toward its own: each onto its own side of the contact,
    # be the parts face to face, side by side along a seam or back to back in a thin fold
    ring = np.zeros_like(V)
    degree = np.zeros(len(V))
    for k in range(3):
        for j in (1, 2):
            np.add.at(ring, F[:, k], V[F[:, (k + j) % 3]])
            np.add.at(degree, F[:, k], 1.0)
    ring = ring[shared] / degree[shared, None]
    group = inverse.reshape(-1)[shared]
    totals = np.zeros((group.max() + 1, 3))
    np.add.at(totals, group, ring)
    copies = np.bincount(group)[group][:, None]
    others = (totals[group] - ring) / np.maximum(copies - 1, 1)
    n = ring - others
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    size = float(np.ptp(V, axis=0).max()) if len(V) else 1.0
    V[shared] += hair * size * n
    return V, int(np.count_nonzero(length[:, 0] > 0))
