"""Linear blend skinning of a dense surface without its (n, 4m) matrix: the weights, one block per (vertex, bone).

A sculpt of 1.8 million triangles has 900 000 vertices: its skinning matrix
(:func:`supportless.base.kinematics.lbs_matrix`) is 900 000 x 4m float64, 314 MB for the bunny's 11 bones
before scipy makes it sparse (and as much again on the way). :class:`WeightBlocks` keeps only each vertex's
non-zero weights and the bone they belong to, built a chunk of vertices at a time
(:func:`weight_blocks`), and :func:`skin_blocks` poses it by the same additions in the same order as the
sparse path of :func:`~supportless.base.kinematics.skin` (the same bits), each matrix entry ``w * [v, 1]``
formed when it is used.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
from numba import njit

from .threads import over

__all__ = ["BLOCK_CHUNK", "WeightBlocks", "skin_blocks", "skin_dense", "weight_blocks"]

#: Vertices whose weights :func:`weight_blocks` reads at a time (the temporary arrays are this many rows).
BLOCK_CHUNK = 65536


@dataclass(frozen=True)
class WeightBlocks:
    """The non-zero skinning weights of a 3D surface, vertex by vertex (a skinning operator, ``V' = M T``).

    Attributes
    ----------
    vertices : (n, 3) float64
        Rest positions.
    start : (n + 1,) int64
        The blocks of vertex ``i`` are ``start[i]:start[i+1]``.
    bone : (q,) int32
        Bone of each block, increasing within a vertex.
    weight : (q,) float64
        Its weight (never 0).
    bones : int
        ``m``.
    """

    vertices: np.ndarray
    start: np.ndarray
    bone: np.ndarray
    weight: np.ndarray
    bones: int

    @property
    def shape(self) -> tuple[int, int]:
        """``(n, 4 m)``: the shape of the matrix it stands for."""
        return len(self.vertices), 4 * self.bones

    @property
    def nbytes(self) -> int:
        return self.start.nbytes + self.bone.nbytes + self.weight.nbytes


def weight_blocks(vertices: np.ndarray, weights: np.ndarray, chunk: int = BLOCK_CHUNK) -> WeightBlocks:
    """The :class:`WeightBlocks` of a surface, read ``chunk`` vertices at a time.

    Parameters
    ----------
    vertices : (n, 3) float64
    weights : (n, m) float64
    chunk : int

    Returns
    -------
    blocks : WeightBlocks
    """
    V = np.ascontiguousarray(vertices, np.float64)
    W = np.asarray(weights)
    counts, bones, values = [], [], []
    for i in range(0, len(W), chunk):
        part = np.asarray(W[i:i + chunk], np.float64)
        rows, cols = np.nonzero(part)  # row-major: bones increasing within a vertex
        counts.append(np.bincount(rows, minlength=len(part)))
        bones.append(cols.astype(np.int32))
        values.append(part[rows, cols])
    start = np.zeros(len(W) + 1, np.int64)
    if counts:
        np.cumsum(np.concatenate(counts), out=start[1:])
    empty = (np.zeros(0, np.int32), np.zeros(0))
    return WeightBlocks(V, start, np.concatenate(bones) if bones else empty[0],
                        np.concatenate(values) if values else empty[1], int(W.shape[1]))


@njit(nogil=True, cache=True)
def _skin_weights3(start, bone, weight, V, T, out, lo, hi):  # pragma: no cover - compiled
    # as kinematics._skin_blocks3 (the poses lo:hi), each block's coefficients w * [x, y, z, 1] formed here (the
    # same products)
    for p in range(lo, hi):
        Tp = T[p]
        for i in range(len(start) - 1):
            x = 0.0
            y = 0.0
            z = 0.0
            vx = V[i, 0]
            vy = V[i, 1]
            vz = V[i, 2]
            for k in range(start[i], start[i + 1]):
                j = 4 * bone[k]
                w = weight[k]
                c0 = w * vx
                c1 = w * vy
                c2 = w * vz
                x += c0 * Tp[j, 0]
                y += c0 * Tp[j, 1]
                z += c0 * Tp[j, 2]
                x += c1 * Tp[j + 1, 0]
                y += c1 * Tp[j + 1, 1]
                z += c1 * Tp[j + 1, 2]
                x += c2 * Tp[j + 2, 0]
                y += c2 * Tp[j + 2, 1]
                z += c2 * Tp[j + 2, 2]
                x += w * Tp[j + 3, 0]
                y += w * Tp[j + 3, 1]
                z += w * Tp[j + 3, 2]
            out[p, i, 0] = x
            out[p, i, 1] = y
            out[p, i, 2] = z


def skin_blocks(blocks: WeightBlocks, T: np.ndarray) -> np.ndarray:
    """Posed vertices of a batch of stacked transforms.

    Parameters
    ----------
    blocks : WeightBlocks
    T : (P, 4 m, 3) float64
        :func:`~supportless.base.kinematics.stack_transforms` of (P, m, 3, 4) transforms.

    Returns
    -------
    vertices : (P, n, 3) float64
    """
    out = np.empty((T.shape[0], len(blocks.vertices), 3))
    T = np.ascontiguousarray(T, np.float64)
    over(_skin_weights3, len(T), blocks.start, blocks.bone, blocks.weight, blocks.vertices, T, out)
    return out


def skin_dense(M: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``M @ T[p]`` for every pose ``p`` of a 3D rig, by a compiled loop.

    Each entry is the sum over the ``4m`` rows of ``T`` in order, one fused multiply-add at a time: the bits of
    OpenBLAS's ``dgemm`` on an FMA processor (``np.matmul`` here), in a third of its time for a surface's thin
    products (the bunny's 200 poses, (3485 x 44) by (44 x 3) each: 31-38 ms as ``np.matmul``, 10-12 ms).

    Parameters
    ----------
    M : (n, k) float64
        The LBS matrix (:func:`~supportless.base.kinematics.lbs_matrix`), ``k = 4m``.
    T : (P, k, 3) float64
        Stacked transforms (:func:`~supportless.base.kinematics.stack_transforms`).

    Returns
    -------
    vertices : (P, n, 3) float64
    """
    MT = _transposed(M)
    T = np.ascontiguousarray(T, np.float64)
    out = np.empty((T.shape[0], MT.shape[1], 3))
    over(_skin_dense3, len(T), MT, T, out)
    return out


#: ``id(M) -> (M, M.T as a C-contiguous copy)`` of the matrices :func:`skin_dense` has seen, each dropped when
#: its matrix is collected (LBS matrices are never modified in place).
_TRANSPOSES: dict[int, tuple[weakref.ref, np.ndarray]] = {}


def _transposed(M: np.ndarray) -> np.ndarray:
    """``M.T`` as a C-contiguous float64 array, (k, n): made once per matrix, kept while ``M`` lives (for a
    surface of 100 000 vertices and 11 bones, a 35 MB copy at every batch otherwise)."""
    if not isinstance(M, np.ndarray) or M.dtype != np.float64:
        return np.ascontiguousarray(np.asarray(M, np.float64).T)
    kept = _TRANSPOSES.get(id(M))
    if kept is not None and kept[0]() is M:
        return kept[1]
    MT = np.ascontiguousarray(M.T)
    key = id(M)
    _TRANSPOSES[key] = (weakref.ref(M, lambda _, key=key: _TRANSPOSES.pop(key, None)), MT)
    return MT


@njit(nogil=True, cache=True, fastmath={"contract"})
def _skin_dense3(MT, T, out, lo, hi):  # pragma: no cover - compiled
    # the poses lo:hi
    k = T.shape[1]
    n = MT.shape[1]
    for p in range(lo, hi):
        x, y, z = np.zeros(n), np.zeros(n), np.zeros(n)
        for r in range(k):
            tx, ty, tz = T[p, r, 0], T[p, r, 1], T[p, r, 2]
            for v in range(n):  # (vectorised over vertices; each entry one multiply-add per row, rows in order)
                m = MT[r, v]
                x[v] += m * tx
                y[v] += m * ty
                z[v] += m * tz
        for v in range(n):
            out[p, v, 0], out[p, v, 1], out[p, v, 2] = x[v], y[v], z[v]
