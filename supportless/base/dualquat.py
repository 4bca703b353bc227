"""Dual quaternion skinning (Kavan, Collins, Zara and O'Sullivan 2007): a volume-keeping alternative to LBS.

Linear blend skinning (:func:`~supportless.base.kinematics.skin`) averages the bones' affine maps: where two
bones turn far apart the average is no longer a rotation, and an elbow bent 90 degrees collapses (the candy
wrapper of a twisted wrist is the same thing). Dual quaternion skinning averages each bone's rigid motion
as a unit dual quaternion instead and normalises the blend, so every vertex moves rigidly.

Conventions:

* A quaternion is ``(w, x, y, z)``; it turns a point ``v`` as ``q v q*``.
* A unit dual quaternion is 8 numbers ``[q_r | q_d]``: the rotation ``q_r`` and
  ``q_d = t q_r / 2`` for the translation ``t`` (a pure quaternion ``(0, t)``),
  so ``x -> R x + t`` of a bone transform ``[R | t]``
  (:mod:`~supportless.base.kinematics`) is ``[q_r | t q_r / 2]``. ``q_r`` is
  taken with ``w >= 0``.
* Blending: for vertex ``i`` with pivot bone ``k`` (its heaviest),
  ``b_i = sum_j w_ij s_ijk Q_j`` with ``s = sign(q_r,j . q_r,k)`` (the
  antipodality fix: ``Q`` and ``-Q`` are the same motion, the blend must take
  them from one hemisphere), divided by ``|b_r|``. So weights need not sum
  to 1: only their ratios count.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .skinning import weight_blocks

__all__ = ["ROTATION_TOLERANCE", "dual_quaternion_skin", "dual_quaternion_to_transforms",
           "matrix_to_quaternion", "transforms_to_dual_quaternions"]

#: How far ``A^T A`` may be from the identity before a transform's linear part is refused as no rotation.
ROTATION_TOLERANCE = 1e-6


def matrix_to_quaternion(R: np.ndarray) -> np.ndarray:
    """Unit quaternions of rotation matrices (Shepperd's method: the branch of the largest component).

    Parameters
    ----------
    R : (..., 3, 3) float64
        Rotation matrices.

    Returns
    -------
    q : (..., 4) float64
        ``(w, x, y, z)`` with ``w >= 0``, turning a point as ``R`` does.
    """
    R = np.asarray(R, np.float64)
    r00, r01, r02 = R[..., 0, 0], R[..., 0, 1], R[..., 0, 2]
    r10, r11, r12 = R[..., 1, 0], R[..., 1, 1], R[..., 1, 2]
    r20, r21, r22 = R[..., 2, 0], R[..., 2, 1], R[..., 2, 2]
    # 4 q_c^2 for c = w, x, y, z; the largest is >= 1, so its branch divides by at least 1
    four = np.stack([1 + r00 + r11 + r22, 1 + r00 - r11 - r22, 1 - r00 + r11 - r22, 1 - r00 - r11 + r22], -1)
    # the branches, each scaled by 4 q_c (row c: 4 q_c * (w, x, y, z))
    rows = np.stack([
        np.stack([four[..., 0], r21 - r12, r02 - r20, r10 - r01], -1),
        np.stack([r21 - r12, four[..., 1], r01 + r10, r02 + r20], -1),
        np.stack([r02 - r20, r01 + r10, four[..., 2], r12 + r21], -1),
        np.stack([r10 - r01, r02 + r20, r12 + r21, four[..., 3]], -1),
    ], -2)  # (..., 4, 4)
    c = np.argmax(four, axis=-1)[..., None, None]
    best = np.take_along_axis(rows, c, axis=-2)[..., 0, :]  # (..., 4)
    q = best / (2.0 * np.sqrt(np.take_along_axis(four, c[..., 0], axis=-1)))
    return np.where(q[..., :1] < 0, -q, q)


def _rotation_check(A: np.ndarray, tolerance: float) -> None:
    gram = np.einsum("...ki,...kj->...ij", A, A)
    off = np.abs(gram - np.eye(3)).max(axis=(-2, -1), initial=0.0)
    det = np.linalg.det(A) if A.size else np.ones(A.shape[:-2])
    bad = (off > tolerance) | (det <= 0)
    if np.any(bad):
        where = np.argwhere(bad)[0]
        raise ValueError(f"transform {tuple(int(i) for i in where)} is no rotation and translation: "
                         f"|A^T A - I| = {float(off[tuple(where)]):.3g}, det A = {float(det[tuple(where)]):.3g}")


def transforms_to_dual_quaternions(transforms: np.ndarray, tolerance: float = ROTATION_TOLERANCE) -> np.ndarray:
    """Unit dual quaternions of rigid bone transforms.

    Parameters
    ----------
    transforms : (..., m, 3, 4) float64
        ``[R | t]`` per bone (:func:`~supportless.base.kinematics.forward_kinematics`);
        ``R`` must be a rotation. A planar rig's ``(..., m, 2, 3)`` is taken as
        turning about z.
    tolerance : float
        Largest entry of ``|R^T R - I|`` accepted.

    Returns
    -------
    dq : (..., m, 8) float64
        ``[q_r | q_d]`` per bone, ``q_r`` with ``w >= 0`` and ``q_d = t q_r / 2``.

    Raises
    ------
    ValueError
        If some ``R`` is not a rotation (a scale, a shear or a mirror).
    """
    T = _as_3d(np.asarray(transforms, np.float64))
    A, t = T[..., :3], T[..., 3]
    _rotation_check(A, tolerance)
    qr = matrix_to_quaternion(A)
    # (0, t) * q_r / 2
    w, v = qr[..., :1], qr[..., 1:]
    qd = 0.5 * np.concatenate([-np.sum(t * v, -1, keepdims=True), w * t + np.cross(t, v)], -1)
    return np.concatenate([qr, qd], -1)


def dual_quaternion_to_transforms(dq: np.ndarray) -> np.ndarray:
    """Rigid transforms of unit dual quaternions: the inverse of :func:`transforms_to_dual_quaternions`.

    Parameters
    ----------
    dq : (..., 8) float64
        ``[q_r | q_d]``; ``q_r`` is normalised here (with ``q_d``), and the part of
        ``q_d`` along ``q_r`` is ignored.

    Returns
    -------
    transforms : (..., 3, 4) float64
        ``[R | t]``.
    """
    dq = np.asarray(dq, np.float64)
    norm = np.linalg.norm(dq[..., :4], axis=-1, keepdims=True)
    qr, qd = dq[..., :4] / norm, dq[..., 4:] / norm
    w, x, y, z = np.moveaxis(qr, -1, 0)
    R = np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)
    return np.concatenate([R, _translation(qr, qd)[..., None]], -1)


def _translation(qr: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """``2 vec(q_d q_r*)`` of a unit ``q_r``: ``2 (w_r t_d - w_d t_r + t_r x t_d)``, (..., 3)."""
    wr, vr = qr[..., :1], qr[..., 1:]
    wd, vd = qd[..., :1], qd[..., 1:]
    return 2.0 * (wr * vd - wd * vr + np.cross(vr, vd))


def _as_3d(T: np.ndarray) -> np.ndarray:
    """(..., 3, 4) transforms; a planar (..., 2, 3) one turning about z."""
    if T.shape[-2:] == (3, 4):
        return T
    if T.shape[-2:] != (2, 3):
        raise ValueError(f"transforms must be (..., 3, 4) or (..., 2, 3), not {T.shape}")
    out = np.zeros(T.shape[:-2] + (3, 4))
    out[..., :2, :2] = T[..., :2]
    out[..., :2, 3] = T[..., 2]
    out[..., 2, 2] = 1.0
    return out


def _blocks(weights, n: int, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each vertex's non-zero weights as ``start (n+1,) int64, bone (q,) int32, weight (q,) float64`` and its
    heaviest bone ``(n,) int64``."""
    if hasattr(weights, "tocsr"):
        W = weights.tocsr()
        if W.shape != (n, m):
            raise ValueError(f"weights {W.shape} do not match {n} vertices and {m} bones")
        heaviest = np.asarray(W.argmax(axis=1)).ravel().astype(np.int64)
        return W.indptr.astype(np.int64), W.indices.astype(np.int32), W.data.astype(np.float64), heaviest
    W = np.asarray(weights, np.float64)
    if W.shape != (n, m):
        raise ValueError(f"weights {W.shape} do not match {n} vertices and {m} bones")
    blocks = weight_blocks(np.zeros((n, 3)), W)  # (its vertices are not read here)
    return blocks.start, blocks.bone, blocks.weight, np.argmax(W, axis=1).astype(np.int64) if n else np.zeros(0, int)


@njit(parallel=True, cache=True)
def _skin_dq(start, bone, weight, pivot, V, Q, out):  # pragma: no cover - compiled
    # per pose, per vertex (in parallel): its bones' dual quaternions, each signed to the pivot's hemisphere,
    # summed with its weights, normalised by the real part's length, applied as in _translation and
    # q v q* = v + 2 r x (r x v + w v); a vertex whose blend is 0 stays
    for p in range(Q.shape[0]):
        Qp = Q[p]
        for i in prange(V.shape[0]):
            k = pivot[i]
            b0 = b1 = b2 = b3 = b4 = b5 = b6 = b7 = 0.0
            for e in range(start[i], start[i + 1]):
                j = bone[e]
                w = weight[e]
                if Qp[j, 0] * Qp[k, 0] + Qp[j, 1] * Qp[k, 1] + Qp[j, 2] * Qp[k, 2] + Qp[j, 3] * Qp[k, 3] < 0.0:
                    w = -w
                b0 += w * Qp[j, 0]
                b1 += w * Qp[j, 1]
                b2 += w * Qp[j, 2]
                b3 += w * Qp[j, 3]
                b4 += w * Qp[j, 4]
                b5 += w * Qp[j, 5]
                b6 += w * Qp[j, 6]
                b7 += w * Qp[j, 7]
            vx = V[i, 0]
            vy = V[i, 1]
            vz = V[i, 2]
            norm = np.sqrt(b0 * b0 + b1 * b1 + b2 * b2 + b3 * b3)
            if norm == 0.0:
                out[p, i, 0] = vx
                out[p, i, 1] = vy
                out[p, i, 2] = vz
                continue
            w0 = b0 / norm
            x0 = b1 / norm
            y0 = b2 / norm
            z0 = b3 / norm
            we = b4 / norm
            xe = b5 / norm
            ye = b6 / norm
            ze = b7 / norm
            # u = r x v + w v, then v + 2 r x u
            ux = y0 * vz - z0 * vy + w0 * vx
            uy = z0 * vx - x0 * vz + w0 * vy
            uz = x0 * vy - y0 * vx + w0 * vz
            # translation 2 (w0 t_e - w_e r + r x t_e)
            out[p, i, 0] = vx + 2.0 * (y0 * uz - z0 * uy) + 2.0 * (w0 * xe - we * x0 + y0 * ze - z0 * ye)
            out[p, i, 1] = vy + 2.0 * (z0 * ux - x0 * uz) + 2.0 * (w0 * ye - we * y0 + z0 * xe - x0 * ze)
            out[p, i, 2] = vz + 2.0 * (x0 * uy - y0 * ux) + 2.0 * (w0 * ze - we * z0 + x0 * ye - y0 * xe)


def dual_quaternion_skin(vertices: np.ndarray, weights, transforms: np.ndarray, *,
                         pivots: np.ndarray | None = None) -> np.ndarray:
    """Dual quaternion skinning of a batch of poses.

    Each vertex blends its bones' unit dual quaternions, each taken in the
    hemisphere of its pivot bone's, normalises the blend and moves by that
    rigid motion. A vertex on one bone, or on bones that all move alike, moves
    exactly as the bone transform does.

    A compiled loop over each vertex's non-zero weights (as
    :func:`~supportless.base.skinning.skin_blocks` for LBS), parallel over the
    vertices of a pose: no memory besides the output and the weights' blocks.

    Parameters
    ----------
    vertices : (n, d) float64
        Rest positions, d = 3 (or 2 for a planar rig).
    weights : (n, m) float64 array or scipy.sparse matrix
        Non-negative skinning weights; each row's scale does not count, only
        its ratios. A vertex whose blend is 0 (no weight) stays where it is.
    transforms : (P, m, d, d+1) or (m, d, d+1) float64
        ``[R | t]`` per bone, ``R`` a rotation.
    pivots : (n,) int64, optional
        The bone whose hemisphere each vertex's blend is taken in (default:
        its heaviest).

    Returns
    -------
    vertices : (P, n, d) or (n, d) float64

    Raises
    ------
    ValueError
        If some transform is not a rotation and translation, or the shapes disagree.
    """
    V = np.asarray(vertices, np.float64)
    T = np.asarray(transforms, np.float64)
    single = T.ndim == 3
    T = T[None] if single else T
    n, d = V.shape
    P, m = T.shape[:2]
    if T.shape[2:] != (d, d + 1):
        raise ValueError(f"transforms {T.shape} do not fit {d}D vertices")
    start, bone, weight, heaviest = _blocks(weights, n, m)
    pivot = heaviest if pivots is None else np.asarray(pivots, np.int64)
    if pivot.shape != (n,) or (n and (pivot.min() < 0 or pivot.max() >= m)):
        raise ValueError(f"pivots must be {n} bones in 0..{m - 1}")
    V3 = np.ascontiguousarray(V if d == 3 else np.column_stack([V, np.zeros(n)]))
    Q = np.ascontiguousarray(transforms_to_dual_quaternions(T))  # (P, m, 8)
    out = np.empty((P, n, 3))
    _skin_dq(start, bone, weight, pivot, V3, Q, out)
    out = out if d == 3 else out[..., :2]
    return out[0] if single else out
