"""Bounded biharmonic skinning weights of a volume mesh (libigl's ``bbw``)."""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = ["compute_weights"]

#: Active-set iterations of the weight solve.
BBW_ITERATIONS = 10


def compute_weights(tet_vertices: np.ndarray, tets: np.ndarray, joints: np.ndarray, bones: np.ndarray,
                    iterations: int = BBW_ITERATIONS) -> np.ndarray:
    """Bounded biharmonic weights of a volume mesh, fixed to 1 on each bone.

    Parameters
    ----------
    tet_vertices : (t, d) float64
        Must have vertices exactly on the bones (see :mod:`supportless.tetmesh`).
    tets : (k, d+1) int64
    joints : (j, d) float64
    bones : (m, 2) int64
    iterations : int
        Active-set iterations of ``igl.bbw``.

    Returns
    -------
    weights : (t, m) float64
        In [0, 1], rows summing to 1.
    """
    import igl

    TV = np.ascontiguousarray(tet_vertices, np.float64)
    TT = np.ascontiguousarray(tets, np.int64)
    C = np.ascontiguousarray(joints, np.float64)
    BE = np.ascontiguousarray(bones, np.int64)
    # libigl's boundary_conditions only handles 3D points: lift planar ones to z = 0
    lift = (lambda X: np.column_stack([X, np.zeros(len(X))])) if TV.shape[1] == 2 else (lambda X: X)
    try:
        b, bc = igl.boundary_conditions(lift(TV), TT, lift(C), np.zeros(0, np.int64), BE,
                                        np.zeros((0, 2), np.int64), np.zeros((0, 3), np.int64))
    except Exception as exc:
        raise InputError(None, f"cannot fix weights on the bones ({exc})") from None
    if len(bones) == 1:
        return np.ones((len(TV), 1))
    W = np.asarray(igl.bbw(TV, TT, np.asarray(b, np.int64), np.asarray(bc, np.float64),
                           partition_unity=True, max_iter=iterations), np.float64)
    W = np.clip(W, 0.0, 1.0)
    s = W.sum(1, keepdims=True)
    bad = s[:, 0] <= 1e-12
    if np.any(bad):  # vertex with no influence at all: give it to the nearest bone sample
        W[bad] = 1.0 / W.shape[1]
        s = W.sum(1, keepdims=True)
    return W / s
