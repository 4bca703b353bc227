"""Bounded biharmonic skinning weights of a volume mesh (libigl's ``bbw``, in a child process: a crash is one line)."""

from __future__ import annotations

import numpy as np

from ..base.errors import InputError
from ..base.isolated import NativeFailure, run_isolated

__all__ = ["check_weights", "compute_weights"]

#: Active-set iterations of the weight solve.
BBW_ITERATIONS = 10


def _components(n: int, elements: np.ndarray) -> np.ndarray:
    """Connected component of each of ``n`` vertices through ``elements`` (k, d+1); (n,) int."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    E = np.asarray(elements, np.int64)
    rows = np.repeat(E[:, :1], E.shape[1] - 1, axis=1).ravel()
    cols = E[:, 1:].ravel()
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def _point_segment_distance(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Distances (n, m) from points ``P`` (n, d) to segments ``A``-``B`` (m, d)."""
    AB = B - A
    t = np.clip(np.einsum("nmd,md->nm", P[:, None] - A[None], AB) / np.maximum((AB * AB).sum(1), 1e-300), 0, 1)
    return np.linalg.norm(P[:, None] - (A[None] + t[..., None] * AB[None]), axis=-1)


def _bbw(TV, TT, b, bc, iterations):
    """libigl's bounded biharmonic weights (the call :func:`_isolated_bbw` runs in a child process)."""
    import igl

    return igl.bbw(TV, TT, b, bc, partition_unity=True, max_iter=iterations)


def _isolated_bbw(TV, TT, b, bc, iterations):
    """:func:`_bbw` where a crash of libigl's solver is one line (:func:`supportless.base.isolated.run_isolated`)."""
    try:
        return run_isolated(_bbw, TV, TT, b, bc, iterations, what="the skinning weights (libigl's BBW)")
    except NativeFailure as exc:
        raise InputError(None, f"{exc}: the volume mesh may be broken; repair the surface (close holes, remove "
                               "parts that cut each other) or prepare it with fewer bones") from None


def compute_weights(tet_vertices: np.ndarray, tets: np.ndarray, joints: np.ndarray, bones: np.ndarray,
                    iterations: int = BBW_ITERATIONS, notes: list | None = None) -> np.ndarray:
    """Bounded biharmonic weights of a volume mesh, fixed to 1 on each bone.

    A connected part of the mesh that no bone passes through (a separate
    base, a loose prop) has nothing to fix its weights: it follows the bone
    nearest to it rigidly (weight 1), and a line in ``notes`` says so.

    Parameters
    ----------
    tet_vertices : (t, d) float64
        Must have vertices exactly on the bones (see :mod:`supportless.rig.tetmesh`).
    tets : (k, d+1) int64
    joints : (j, d) float64
    bones : (m, 2) int64
    iterations : int
        Active-set iterations of ``igl.bbw``.
    notes : list of str, optional
        Receives one line per part with no bone.

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
    b = np.asarray(b, np.int64)
    part = _components(len(TV), TT)
    boned = np.isin(part, part[b])
    W = np.zeros((len(TV), len(BE)))
    if boned.all():
        W[:] = _isolated_bbw(TV, TT, b, np.asarray(bc, np.float64), iterations)
    else:  # solve where bones are; each bone-less part follows its nearest bone
        keep = np.flatnonzero(boned)
        index = np.full(len(TV), -1)
        index[keep] = np.arange(len(keep))
        sub = TT[boned[TT].all(axis=1)]
        W[keep] = _isolated_bbw(np.ascontiguousarray(TV[keep]), np.ascontiguousarray(index[sub]), index[b],
                                np.asarray(bc, np.float64), iterations)
        for label in np.unique(part[~boned]):
            verts = np.flatnonzero(part == label)
            nearest = int(np.argmin(_point_segment_distance(TV[verts], C[BE[:, 0]], C[BE[:, 1]]).min(axis=0)))
            W[verts, nearest] = 1.0
            if notes is not None and len(np.intersect1d(verts, TT)):
                centre = np.round(TV[verts].mean(axis=0), 3).tolist()
                notes.append(f"a part of the model with no bone in it ({len(verts)} vertices around {centre}) "
                             f"follows bone {nearest + 1}, the nearest; give it a bone to pose it on its own")
    W = np.clip(W, 0.0, 1.0)
    s = W.sum(1, keepdims=True)
    bad = s[:, 0] <= 1e-12
    if np.any(bad):  # vertex with no influence at all: give it to the nearest bone sample
        W[bad] = 1.0 / W.shape[1]
        s = W.sum(1, keepdims=True)
    return W / s


def check_weights(weights: np.ndarray, notes: list | None = None) -> np.ndarray:
    """Skinning weights given with the model, checked: finite, not negative, rows summing to 1.

    Parameters
    ----------
    weights : (t, m) float64
        One row per volume vertex, one column per bone.
    notes : list of str, optional
        Receives a line when rows had to be scaled to sum to 1.

    Returns
    -------
    weights : (t, m) float64
        Rows summing to 1: rows off by more than 1e-6 scaled, tiny negative
        round-off clipped to 0, the rest as given.

    Raises
    ------
    InputError
        One line naming the first vertex and bone at fault: a NaN or infinite
        weight, a negative one, or a vertex with no weight at all.
    """
    W = np.asarray(weights, np.float64)
    bad = np.argwhere(~np.isfinite(W))
    if len(bad):
        v, b = bad[0]
        raise InputError(None, f"the weight of vertex {v} on bone {b + 1} is {W[v, b]}; weights must be numbers "
                               f"0..1 ({len(bad)} such weights)")
    bad = np.argwhere(W < -1e-6)
    if len(bad):
        v, b = bad[0]
        raise InputError(None, f"the weight of vertex {v} on bone {b + 1} is {W[v, b]:.4g}; weights must be 0..1 "
                               f"({len(bad)} negative weights)")
    W = np.clip(W, 0.0, None)
    s = W.sum(1)
    empty = np.flatnonzero(s <= 1e-12)
    if len(empty):
        raise InputError(None, f"vertex {empty[0]} has no weight on any bone ({len(empty)} such vertices); every "
                               f"vertex needs weights summing to 1")
    off = np.abs(s - 1.0) > 1e-6
    if off.any():  # (rows within round-off of 1 stay exactly as given)
        W[off] /= s[off, None]
        if notes is not None:
            notes.append(f"{int(off.sum())} rows of the given weights did not sum to 1 and were scaled to 1")
    return W
