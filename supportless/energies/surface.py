"""The surface the energies act on: argument checks, orientation, boundary, frame.

Every energy takes ``(vertices, faces, up)``: :func:`prepare` checks and
batches them and turns ``up`` (an axis name such as ``"-z"``, a string
``"0,1,0"`` or a vector) into a unit vector.  The outward side of a surface
comes from the sign of its total signed volume (3D) or signed area (2D), per
pose (:func:`orientation_sign`), so either consistent winding works.  A 2D
model is a planar triangle mesh whose surface is its boundary
(:func:`boundary_edges`).  The ray grid works in a right-handed frame whose
last axis is ``up`` (:func:`plane_basis`, :func:`to_frame`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..base.geometry import parse_up, plane_basis
from ..base.threads import over

__all__ = [
    "BACKENDS",
    "check_backend",
    "prepare",
    "orientation_sign",
    "signed_volume3",
    "signed_area2",
    "boundary_edges",
    "plane_basis",
    "frame_matrix",
    "to_frame",
]

#: The implementations every energy offers: numba kernels or plain numpy.
BACKENDS = ("fast", "numpy")


def check_backend(backend):
    """Raise ValueError unless ``backend`` is one of :data:`BACKENDS`.

    Parameters
    ----------
    backend : str
        ``"fast"`` (numba kernels) or ``"numpy"`` (plain numpy).
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, not {backend!r}")


def prepare(vertices, faces, up):
    """Validate and normalise the arguments every energy takes.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Vertex positions of a batch of ``P`` poses or of one pose, ``d`` in {2, 3}.
    faces : (f, 3) int
        Triangle indices.
    up : str or (d,) array_like of float
        Printing direction.  A string is an axis name ``"x" | "y" | "z" | "-x"
        | "-y" | "-z"`` or numbers ``"0,1,0"`` / ``"0 1 0"``, read by
        :func:`supportless.base.geometry.parse_up` (in 2D an axis in the plane).  A
        vector is any finite nonzero vector of length ``d``, normalised here.

    Returns
    -------
    V : (P, n, d) float64
        Batched, C-contiguous vertices (``P = 1`` for a single pose).
    F : (f, 3) int64
        C-contiguous faces.
    up : (d,) float64
        Unit printing direction.
    single : bool
        True when ``vertices`` was a single pose ``(n, d)``.

    Raises
    ------
    supportless.base.errors.InputError
        For a string that names no direction (or, in 2D, one out of the plane).
    ValueError
        For vertices of the wrong shape, or a vector ``up`` of the wrong
        length, zero or not finite.
    """
    V = np.asarray(vertices, dtype=np.float64)
    single = V.ndim == 2
    if single:
        V = V[None]
    if V.ndim != 3 or V.shape[-1] not in (2, 3):
        raise ValueError("vertices must have shape (P, n, d) or (n, d) with d in {2, 3}")
    V = np.ascontiguousarray(V)
    F = np.ascontiguousarray(np.asarray(faces, dtype=np.int64).reshape(-1, 3))
    d = V.shape[-1]
    if isinstance(up, str):
        return V, F, parse_up(up, d), single
    u = np.asarray(up, dtype=np.float64).reshape(-1)
    if u.shape != (d,):
        raise ValueError(f"up must be a vector of length {d}")
    nrm = np.linalg.norm(u)
    if not np.isfinite(nrm) or nrm == 0.0:
        raise ValueError("up must be a finite nonzero vector")
    return V, F, u / nrm, single


# ---------------------------------------------------------------------------
# orientation
# ---------------------------------------------------------------------------


@njit(cache=True)
def signed_volume3(X, F):
    """Signed volume enclosed by one pose's triangles (numba).

    Parameters
    ----------
    X : (n, 3) float64
        Vertices of one pose.
    F : (f, 3) int64
        Triangles.

    Returns
    -------
    volume : float
        ``sum_f a . (b x c) / 6``, summed face by face in order (every caller
        gets the same bits); positive for outward-oriented faces.
    """
    t = 0.0
    for f in range(F.shape[0]):
        a = F[f, 0]
        b = F[f, 1]
        c = F[f, 2]
        t += X[a, 0] * (X[b, 1] * X[c, 2] - X[b, 2] * X[c, 1])
        t += X[a, 1] * (X[b, 2] * X[c, 0] - X[b, 0] * X[c, 2])
        t += X[a, 2] * (X[b, 0] * X[c, 1] - X[b, 1] * X[c, 0])
    return t / 6.0


@njit(cache=True)
def signed_area2(X, F):
    """Signed area of one pose's planar triangles (numba): :func:`signed_volume3` for
    ``X`` (n, 2) float64; positive when counter-clockwise."""
    t = 0.0
    for f in range(F.shape[0]):
        a = F[f, 0]
        b = F[f, 1]
        c = F[f, 2]
        t += (X[b, 0] - X[a, 0]) * (X[c, 1] - X[a, 1]) - (X[b, 1] - X[a, 1]) * (X[c, 0] - X[a, 0])
    return 0.5 * t


def _signed_measure(V, F):
    """(P,) float64: :func:`signed_volume3` or :func:`signed_area2` of each pose of ``V`` (P, n, d)."""
    out = np.zeros(V.shape[0], np.float64)
    over(_signed_measure_of, V.shape[0], V, F, out)
    return out


@njit(cache=True, nogil=True)
def _signed_measure_of(V, F, out, lo, hi):
    """Fill ``out`` (P,) at the poses ``lo:hi`` (see :func:`_signed_measure`)."""
    for p in range(lo, hi):
        if V.shape[2] == 3:
            out[p] = signed_volume3(V[p], F)
        else:
            out[p] = signed_area2(V[p], F)


def orientation_sign(V, F, backend="fast"):
    """Sign of the total signed volume (3D) or signed area (2D) per pose.

    Parameters
    ----------
    V : (P, n, d) float64
        Batched vertices, ``d`` in {2, 3}.
    F : (f, 3) int64
        Triangles.
    backend : {"fast", "numpy"}
        numba kernel or plain numpy.

    Returns
    -------
    s : (P,) float64
        +1 when the faces are outward oriented (counter-clockwise in 2D),
        -1 when inverted; +1 when the total is exactly zero.
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if backend == "numpy":
        a, b, c = V[:, F[:, 0]], V[:, F[:, 1]], V[:, F[:, 2]]
        if V.shape[-1] == 3:
            tot = np.einsum("pfi,pfi->p", a, np.cross(b, c)) / 6.0
        else:
            e1, e2 = b - a, c - a
            tot = 0.5 * np.sum(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0], axis=-1)
    else:
        tot = _signed_measure(V, F)
    return np.where(tot < 0.0, -1.0, 1.0)


def boundary_edges(faces, vertices=None):
    """Boundary edges of a 2D triangle mesh, oriented outward.

    A boundary edge is used by exactly one triangle.  Edges keep the
    direction in which they appear in their triangle, so for a
    counter-clockwise mesh the region lies to the left of each edge
    ``a -> b`` and the outward normal is ``(b - a)`` rotated clockwise,
    i.e. ``(dy, -dx) / |b - a|``.

    Parameters
    ----------
    faces : (f, 3) int
        Consistently oriented triangles.
    vertices : (n, 2) or (P, n, 2) float64, optional
        If given and the total signed area (of the first pose) is negative
        (clockwise mesh), the edges are reversed so that the convention above
        holds.

    Returns
    -------
    edges : (e, 2) int64
        Directed boundary edges, in the order of the edge list ``(0, 1)`` of
        every face, then ``(1, 2)`` of every face, then ``(2, 0)``.
    """
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    edges = np.ascontiguousarray(E[cnt[inv.reshape(-1)] == 1])
    if vertices is not None:
        V = np.asarray(vertices, dtype=np.float64)
        if V.ndim == 3:
            V = V[0]
        if orientation_sign(V[None], F)[0] < 0:
            edges = np.ascontiguousarray(edges[:, ::-1])
    return edges


# ---------------------------------------------------------------------------
# frame of the printing direction
# ---------------------------------------------------------------------------


def frame_matrix(up):
    """Rotation into the frame of ``up``.

    Parameters
    ----------
    up : (d,) float64
        Unit printing direction.

    Returns
    -------
    R : (d, d) float64
        C-contiguous; rows ``(plane_basis(up), up)``: ``R @ x`` is ``x`` in the
        frame, last coordinate the height along ``up``.
    """
    return np.ascontiguousarray(np.vstack([plane_basis(up), up[None]]))


def to_frame(V, up):
    """Express vertices in the right-handed frame ``(plane basis, up)``.

    Parameters
    ----------
    V : (P, n, d) float64
        Batched vertices.
    up : (d,) float64
        Unit printing direction.

    Returns
    -------
    X : (P, n, d) float64
        Coordinates; the last one is the height along ``up``.  A rotation, so
        orientations (triangle winding, signed areas) are kept.
    """
    R = frame_matrix(up)
    # written out (not V @ R.T) so the fast kernel's in-place transform is bit-identical
    d = V.shape[-1]
    X = np.empty(V.shape)
    for a in range(d):
        x = V[..., 0] * R[a, 0]
        for c in range(1, d):
            x = x + V[..., c] * R[a, c]
        X[..., a] = x
    return X
