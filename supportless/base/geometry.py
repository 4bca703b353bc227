"""Small geometry shared by every layer: the printing direction, volumes, the plate.

Nothing here knows about rigs, energies or searches; every other module may
import it.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = ["parse_up", "row_groups", "place_on_plate", "plane_basis", "points_in_triangles", "print_pose", "print_transform",
           "signed_volume", "surface_digest"]

_AXES = {"x": 0, "y": 1, "z": 2}


def parse_up(up, dim: int = 3) -> np.ndarray:
    """Turn a printing direction into a unit vector.

    Parameters
    ----------
    up : str or sequence of float
        ``"x" | "y" | "z" | "-x" | "-y" | "-z"``, or three (``dim``) numbers,
        as a sequence or as a string ``"0,1,0"`` / ``"0 1 0"``.
    dim : int
        2 for a planar figure (the z component is dropped; it must be 0), else 3.

    Returns
    -------
    up : (dim,) float64
        Unit vector.

    Raises
    ------
    InputError
        For an unknown name, a zero or non-finite vector, or (``dim=2``) a
        direction out of the plane.
    """
    if isinstance(up, str):
        s = up.strip().lower()
        sign = -1.0 if s.startswith("-") else 1.0
        key = s.lstrip("+-")
        if key in _AXES:
            vec = np.zeros(3)
            vec[_AXES[key]] = sign
        else:
            try:
                vec = np.array([float(t) for t in s.replace(",", " ").split()])
            except ValueError:
                raise InputError(None, f"up direction {up!r} is not x|y|z|-x|-y|-z or three numbers") from None
            if len(vec) != 3 and not (dim == 2 and len(vec) == 2):
                raise InputError(None, f"up direction {up!r} has {len(vec)} numbers; give three, e.g. '0,1,0'")
    else:
        vec = np.asarray(up, dtype=float).ravel()
    if vec.shape == (2,):
        vec = np.append(vec, 0.0)
    if vec.shape != (3,) or not np.all(np.isfinite(vec)) or np.linalg.norm(vec) == 0:
        raise InputError(None, f"up direction {up!r} must be a nonzero vector of three numbers")
    vec = vec / np.linalg.norm(vec)
    if dim == 2:
        if abs(vec[2]) > 1e-12:
            raise InputError(None, f"up direction {up!r} must lie in the plane (z = 0) of a planar figure")
        return vec[:2] / np.linalg.norm(vec[:2])
    return vec


def signed_volume(V: np.ndarray, F: np.ndarray) -> float:
    """Enclosed volume of a closed surface (area of a planar mesh in 2D).

    Parameters
    ----------
    V : (n, 3) or (n, 2) float64
    F : (f, 3) int64

    Returns
    -------
    volume : float
        Positive for an outward-oriented surface (counter-clockwise in 2D).
    """
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    if V.shape[1] == 2:
        return float(0.5 * np.sum((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def place_on_plate(vertices: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Translate a surface so its lowest point along ``up`` is at 0.

    Parameters
    ----------
    vertices : (n, d) float64
    up : (d,) float64
        Unit printing direction.

    Returns
    -------
    placed : (n, d) float64
    """
    return vertices - (vertices @ up).min() * up


def print_transform(vertices: np.ndarray, rotation: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The translation that, after ``rotation``, puts a surface in its print place.

    The surface is turned by ``rotation`` about its bounding-box centre (so it
    stays where it was across the plate) and moved along ``up`` so its lowest
    point is at 0: ``printed = vertices @ rotation.T + shift``.

    Parameters
    ----------
    vertices : (n, d) float64
        The surface in the display frame (as the model stands).
    rotation : (d, d) float64
        The print rotation R: ``R @ u == up`` for the display-frame direction
        ``u`` that prints upwards.
    up : (d,) float64
        Unit printing direction (of the input's frame convention).

    Returns
    -------
    shift : (d,) float64
    """
    V = np.asarray(vertices, np.float64)
    R = np.asarray(rotation, np.float64)
    centre = 0.5 * (V.min(axis=0) + V.max(axis=0))
    shift = centre - R @ centre
    return shift - ((V @ R.T + shift) @ up).min() * up


def print_pose(vertices: np.ndarray, rotation: np.ndarray, up: np.ndarray) -> np.ndarray:
    """A surface turned into its print orientation and placed on the plate (see :func:`print_transform`).

    Parameters
    ----------
    vertices : (n, d) float64
    rotation : (d, d) float64
    up : (d,) float64

    Returns
    -------
    printed : (n, d) float64
    """
    V = np.asarray(vertices, np.float64)
    return V @ np.asarray(rotation, np.float64).T + print_transform(V, rotation, up)


def points_in_triangles(V: np.ndarray, F: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Whether each planar point lies in a counter-clockwise triangle (or on its edge).

    Parameters
    ----------
    V : (n, 2) float64
    F : (f, 3) int64
        Counter-clockwise triangles.
    Q : (q, 2) float64

    Returns
    -------
    inside : (q,) bool
    """
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    inside = np.zeros(len(Q), bool)
    for k, q in enumerate(Q):
        def side(u, v):
            return (v - u)[:, 0] * (q - u)[:, 1] - (v - u)[:, 1] * (q - u)[:, 0]
        s0, s1, s2 = side(a, b), side(b, c), side(c, a)
        inside[k] = np.any((s0 >= -1e-12) & (s1 >= -1e-12) & (s2 >= -1e-12))
    return inside


def plane_basis(up):
    """Orthonormal basis of the plane orthogonal to ``up``.

    Parameters
    ----------
    up : (d,) float64
        Unit vector, ``d`` in {2, 3}.

    Returns
    -------
    B : (d - 1, d) float64
        Rows span the plane orthogonal to ``up``; the frame
        ``(B[0], ..., up)`` is right-handed (determinant +1).
    """
    up = np.asarray(up, dtype=np.float64)
    if up.shape[0] == 2:
        return np.array([[up[1], -up[0]]])
    helper = np.zeros(3)
    helper[np.argmin(np.abs(up))] = 1.0
    e1 = np.cross(helper, up)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    return np.stack([e1, e2])


def surface_digest(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    """16 bytes that change with any bit of a surface: the key of answers remembered per surface.

    Parameters
    ----------
    vertices : (n, d) float64
    faces : (f, 3) int64

    Returns
    -------
    digest : bytes
    """
    import hashlib

    h = hashlib.blake2b(digest_size=16)
    for a in (np.ascontiguousarray(vertices, np.float64), np.ascontiguousarray(faces, np.int64)):
        h.update(str(a.shape).encode())
        h.update(memoryview(a).cast("B"))
    return h.digest()


def row_groups(X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows of ``X`` grouped by equal values: ``np.unique(X, axis=0, return_index, return_inverse,
    return_counts)`` without the unique rows, by one lexsort (3.6x faster on 5.3 million float32 rows: a written sculpt's corners).

    Parameters
    ----------
    X : (n, d) array

    Returns
    -------
    first : (k,) int64
        The first row of each group, groups in the order of their rows' values.
    inverse : (n,) int64
        Each row's group.
    counts : (k,) int64
        The rows in each group.
    """
    X = np.asarray(X)
    if len(X) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)
    order = np.lexsort(X.T[::-1])  # by the first column, then the next; stable: each run starts at its first row
    ordered = X[order]
    starts = np.r_[True, np.any(ordered[1:] != ordered[:-1], axis=1)]
    inverse = np.empty(len(X), np.int64)
    inverse[order] = np.cumsum(starts) - 1
    return order[starts].astype(np.int64), inverse, np.diff(np.r_[np.flatnonzero(starts), len(X)])
