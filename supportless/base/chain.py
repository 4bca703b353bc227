"""Compiled kernels of a 3D skeleton's pose: XYZ Euler rotations and their composition down the chain.

The search turns every bone of 200 poses at every step, so these small products run a few hundred times a
search on arrays of a few thousand 3 x 3 matrices, where numpy's per-call overhead and OpenBLAS's per-matrix
calls cost more than the arithmetic. Each kernel makes the bits of the numpy expression it replaces
(:func:`~supportless.base.kinematics.euler_to_matrix`, :func:`~supportless.base.kinematics.forward_kinematics`):

* a rotation's entries are the same products and sums of the same sines and cosines, without fused
  multiply-adds;
* a matrix product's and a matrix-vector product's entries are summed with fused multiply-adds in the order
  OpenBLAS's ``dgemm`` and ``dgemv`` kernels use on a processor with FMA (``np.matmul`` with OpenBLAS 0.3.31
  on an AMD EPYC; elsewhere the last bits may differ, as any two BLAS builds' do).
"""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.core.extending import intrinsic

__all__ = ["chain_transforms3", "euler_matrices"]


def euler_matrices(angles: np.ndarray) -> np.ndarray:
    """``Rx(a0) @ Ry(a1) @ Rz(a2)`` for every row of angles.

    Parameters
    ----------
    angles : (q, 3) float64
        C-contiguous XYZ Euler angles, radians.

    Returns
    -------
    R : (q, 3, 3) float64
    """
    R = np.empty((angles.shape[0], 3, 3))
    _euler3(angles, R)
    return R


@njit(cache=True)
def _euler3(a, R):  # pragma: no cover - compiled
    for p in range(a.shape[0]):
        cx, cy, cz = np.cos(a[p, 0]), np.cos(a[p, 1]), np.cos(a[p, 2])
        sx, sy, sz = np.sin(a[p, 0]), np.sin(a[p, 1]), np.sin(a[p, 2])
        R[p, 0, 0] = cy * cz
        R[p, 0, 1] = -cy * sz
        R[p, 0, 2] = sy
        R[p, 1, 0] = sx * sy * cz + cx * sz
        R[p, 1, 1] = -sx * sy * sz + cx * cz
        R[p, 1, 2] = -sx * cy
        R[p, 2, 0] = -cx * sy * cz + sx * sz
        R[p, 2, 1] = cx * sy * sz + sx * cz
        R[p, 2, 2] = cx * cy


def chain_transforms3(dQ: np.ndarray, roots: np.ndarray, parents: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Bone transforms ``[Q | t]`` of a batch of 3D poses from each bone's rotation relative to its parent.

    ``Q_b = Q_parent dQ_b`` and ``t_b = Q_parent r_b + t_parent - Q_b r_b`` (``r_b`` the joint the bone turns
    about, which moves with the parent); a root bone has ``Q_b = dQ_b``, ``t_b = r_b - dQ_b r_b``.

    Parameters
    ----------
    dQ : (P, m, 3, 3) float64
        C-contiguous relative rotations.
    roots : (m, 3) float64
        C-contiguous pivot joint of each bone.
    parents, order : (m,) int64
        The kinematic tree (-1 for a root) and a topological order of it (parents first).

    Returns
    -------
    transforms : (P, m, 3, 4) float64
    """
    out = np.empty(dQ.shape[:2] + (3, 4))
    _chain3(dQ, roots, parents, order, out)
    return out


@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` rounded once (LLVM's ``fma``), float64."""
    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return types.float64(types.float64, types.float64, types.float64), codegen


@njit(cache=True)
def _product(A, B, i, j):  # pragma: no cover - compiled
    """``(A @ B)[i, j]`` of 3 x 3 matrices as OpenBLAS's ``dgemm`` sums it: from zero, ``k`` in order."""
    return _fma(A[i, 2], B[2, j], _fma(A[i, 1], B[1, j], _fma(A[i, 0], B[0, j], 0.0)))


@njit(cache=True)
def _apply(A, r, i):  # pragma: no cover - compiled
    """``(A @ r)[i]`` of a 3 x 3 (or 3 x 4) matrix and a 3-vector as OpenBLAS's ``dgemv`` sums it: the first two
    terms' sum with one rounding of the second product, then the third."""
    return _fma(A[i, 2], r[2], _fma(A[i, 0], r[0], A[i, 1] * r[1]))


@njit(cache=True)
def _chain3(dQ, roots, parents, order, out):  # pragma: no cover - compiled
    P = dQ.shape[0]
    for b in order:
        r = roots[b]
        p = parents[b]
        for q in range(P):
            D = dQ[q, b]
            T = out[q, b]
            if p < 0:
                for i in range(3):
                    for j in range(3):
                        T[i, j] = D[i, j]
                for i in range(3):
                    T[i, 3] = r[i] - _apply(D, r, i)
            else:
                A = out[q, p]
                for i in range(3):
                    for j in range(3):
                        T[i, j] = _product(A, D, i, j)
                for i in range(3):
                    T[i, 3] = (_apply(A, r, i) + A[i, 3]) - _apply(T, r, i)
