"""Degenerate triangles of a closed surface, removed without changing its shape.

Real meshes carry triangles of zero area: a *needle* (two corners at one
place, or nearly) or a *cap* (three corners on a line). TetGen fails on them
with pages of output and a message about self-intersections. A needle is
removed by collapsing its short edge (the two corners become one vertex and
the two triangles on that edge go); a cap by flipping its long edge (the
corner on the line joins the far corner of the neighbouring triangle), which
moves no vertex. Both keep the surface closed and consistently oriented.
"""

from __future__ import annotations

import numpy as np

__all__ = ["THIN_TOLERANCE", "degenerate_faces", "repair_degenerate_faces", "repair_note"]

#: A triangle is degenerate when its height over its longest edge is at most
#: this times the diagonal of the model's bounding box (100 nm on a 10 cm model:
#: far below what prints, and above the round-off of coordinates written with
#: eight digits).
THIN_TOLERANCE = 1e-6

#: A degenerate triangle whose shortest edge is below this fraction of its longest is a needle.
NEEDLE_RATIO = 1e-3


def degenerate_faces(V: np.ndarray, F: np.ndarray, tolerance: float = THIN_TOLERANCE) -> np.ndarray:
    """Indices of triangles that are (nearly) a line or a point, or have a repeated corner.

    Parameters
    ----------
    V : (n, 3) float64
    F : (f, 3) int64
    tolerance : float
        Largest height (over the longest edge) of a degenerate triangle,
        relative to the bounding-box diagonal (:data:`THIN_TOLERANCE`).

    Returns
    -------
    faces : (k,) int64
    """
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    twice_area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    longest = np.max(np.linalg.norm(np.stack([b - a, c - b, a - c]), axis=-1), axis=0)
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    repeated = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    return np.flatnonzero(repeated | (twice_area <= tolerance * diag * longest))


def _faces_on_edge(F: np.ndarray, u: int, v: int) -> np.ndarray:
    has = (F == u).any(axis=1) & (F == v).any(axis=1)
    return np.flatnonzero(has)


def _flip(F: np.ndarray, f: int, u: int, v: int) -> bool:
    """Flip edge ``u v`` of face ``f`` with the other face on it; False when that cannot be done."""
    other = [g for g in _faces_on_edge(F, u, v) if g != f]
    if len(other) != 1:
        return False
    g = other[0]
    # orient: f = (u, v, c) in its cyclic order, g = (v, u, d)
    k = int(np.flatnonzero(F[f] == u)[0])
    if F[f][(k + 1) % 3] != v:
        u, v = v, u
        k = int(np.flatnonzero(F[f] == u)[0])
    c = int(F[f][(k + 2) % 3])
    d = int(next(x for x in F[g] if x != u and x != v))
    if c == d or len(_faces_on_edge(F, c, d)):
        return False  # the new edge exists already: flipping would make the surface non-manifold
    F[f] = (c, u, d)
    F[g] = (c, d, v)
    return True


def repair_degenerate_faces(V: np.ndarray, F: np.ndarray,
                            tolerance: float = THIN_TOLERANCE) -> tuple[np.ndarray, np.ndarray, int]:
    """Remove the degenerate triangles of a closed surface (see the module's description).

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (f, 3) int64
        Closed, consistently oriented triangles.
    tolerance : float
        Relative height below which a triangle is degenerate (:data:`THIN_TOLERANCE`).

    Returns
    -------
    V : (n', 3) float64
        Unchanged but for vertices merged away by a collapse (``n' <= n``).
    F : (f', 3) int64
        Without degenerate triangles where they could be removed.
    repaired : int
        Number of degenerate triangles there were, when every one was removed
        (0: ``V`` and ``F`` are the inputs, or some could not be removed).
    """
    V = np.asarray(V, np.float64)
    given = np.asarray(F, np.int64)
    F = given.copy()
    bad = degenerate_faces(V, F, tolerance)
    if not len(bad):
        return V, given, 0
    found = len(bad)
    for _ in range(4 * len(bad) + 10):
        bad = degenerate_faces(V, F, tolerance)
        if not len(bad):
            break
        f = int(bad[0])
        p = V[F[f]]
        lengths = np.linalg.norm(p - p[[1, 2, 0]], axis=1)  # edge i joins corner i and i+1
        i_short, i_long = int(np.argmin(lengths)), int(np.argmax(lengths))
        u, v = int(F[f][i_short]), int(F[f][(i_short + 1) % 3])
        if u == v or lengths[i_short] <= NEEDLE_RATIO * lengths[i_long]:
            # needle: v becomes u; the faces on edge u-v (now with a repeated corner) go
            F[F == v] = u
            F = F[~((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0]))]
        elif not _flip(F, f, int(F[f][i_long]), int(F[f][(i_long + 1) % 3])):
            break  # cannot be repaired here: the surface checks say what is wrong
    if len(degenerate_faces(V, F, tolerance)):
        return V, given, 0
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    index = np.cumsum(used) - 1
    return V[used], index[F], found


def repair_note(count: int) -> str:
    """The line that tells the user ``count`` degenerate triangles were removed."""
    return (f"{count} degenerate triangle{'s' if count > 1 else ''} (no area) removed before tetrahedralising; "
            f"the surface's shape is unchanged")
