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
    """The rows of ``X`` grouped by equal values (``np.unique(X, axis=0, return_index, return_inverse,
    return_counts)`` without the unique rows), the groups in the order of their first rows.

    Each row's 64-bit hash, its top bits packed with the row's index, is sorted as one integer
    (:func:`_grouped_by_hash`): 1.1 s where a lexsort of the columns takes 2.0 s on 5.3 million float32
    rows (a written sculpt's corners, 2 cores, ``benchmarks/weld.py``). Rows that hash alike but differ are
    then told apart by their values, so the groups are exact. ``-0.0`` and ``0.0`` are one value; a NaN
    equals nothing, as under ``==``.

    Parameters
    ----------
    X : (n, d) array
        Integer, boolean or floating point.

    Returns
    -------
    first : (k,) int64
        The first row of each group, increasing.
    inverse : (n,) int64
        Each row's group.
    counts : (k,) int64
        The rows in each group.
    """
    X = np.asarray(X)
    if len(X) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)
    X = X.reshape(len(X), -1)
    h = _row_hash(X)
    order, starts = _grouped_by_lexsort(X) if h is None else _grouped_by_hash(X, h)
    first = order[starts]  # each group's rows come in increasing order
    by_first = np.argsort(first)  # the groups renumbered in the order of their first rows
    number = np.empty(len(first), np.int64)
    number[by_first] = np.arange(len(first))
    inverse = np.empty(len(X), np.int64)
    inverse[order] = number[np.cumsum(starts) - 1]
    return first[by_first].astype(np.int64), inverse, np.bincount(inverse, minlength=len(first))


def _column_bits(column: np.ndarray) -> np.ndarray | None:
    """A column's entries as unsigned 64-bit integers, equal where the values are (``-0.0`` made ``0.0``), (n,)
    uint64; None for a kind of value that has no such bits (objects, strings, extended precision)."""
    if column.dtype.kind == "f" and column.dtype.itemsize <= 8:
        y = np.asarray(column, np.float32 if column.dtype.itemsize <= 4 else np.float64) + 0.0  # -0.0 + 0.0 is 0.0
        return y.view(np.uint32 if y.dtype.itemsize == 4 else np.uint64).astype(np.uint64)
    if column.dtype.kind in "biu":
        return column.astype(np.uint64)
    return None


def _row_hash(X: np.ndarray) -> np.ndarray | None:
    """A 64-bit hash of each row of ``X`` (n, d), equal for equal rows, its top bits well mixed; (n,) uint64, or None
    when :func:`_column_bits` has no bits for its values."""
    h = np.zeros(len(X), np.uint64)
    for j in range(X.shape[1]):
        bits = _column_bits(X[:, j])
        if bits is None:
            return None
        bits *= np.uint64(_HASH_FACTORS[j % len(_HASH_FACTORS)])
        h ^= bits
        h ^= h >> np.uint64(29)
    h *= np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(32)
    return h


#: Odd multipliers of :func:`_row_hash`, one per column (reused past the third).
_HASH_FACTORS = (0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9)


def _grouped_by_hash(X: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows ordered so that equal ones are adjacent, each group's rows in increasing order; (order, starts).

    The sort key is the hash's top bits above the row's index: one sort of integers, and rows of one hash
    come out in increasing order. Hashes that collide on rows of different values are sorted by value within
    their run (stably: still in increasing order).
    """
    n = len(X)
    b = np.uint64(max(1, (n - 1).bit_length()))
    key = (h >> b << b) | np.arange(n, dtype=np.uint64)
    key.sort()
    order = (key & ((np.uint64(1) << b) - np.uint64(1))).astype(np.int64)
    same = (key[1:] >> b) == (key[:-1] >> b)
    differ = _neighbours_differ(X, order)
    if np.any(same & differ):  # distinct rows sharing a hash: order each such run by value
        run = np.cumsum(np.r_[True, ~same]) - 1
        at = np.flatnonzero(np.isin(run, run[1:][same & differ]))
        by_value = np.lexsort((*X[order[at]].T[::-1], run[at]))
        order[at] = order[at][by_value]
        differ = _neighbours_differ(X, order)
    return order, np.r_[True, ~same | differ]


def _neighbours_differ(X: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Whether row ``order[i + 1]`` of ``X`` differs from row ``order[i]``, (n - 1,) bool (a column at a time: a
    third of the time of gathering whole rows)."""
    differ = np.zeros(len(order) - 1, bool)
    for j in range(X.shape[1]):
        column = X[:, j].take(order)
        differ |= column[1:] != column[:-1]
    return differ


def _grouped_by_lexsort(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """As :func:`_grouped_by_hash`, by one lexsort of the columns (rows of any comparable kind)."""
    order = np.lexsort(X.T[::-1])  # by the first column, then the next; stable: each run starts at its first row
    ordered = X[order]
    return order, np.r_[True, np.any(ordered[1:] != ordered[:-1], axis=1)]
