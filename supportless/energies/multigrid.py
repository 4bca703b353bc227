"""Solving a held elastic problem: sparse LU when small, else conjugate gradients with a multigrid cycle.

The multigrid preconditioner is one symmetric V-cycle (:func:`vcycle`: a forward Gauss-Seidel sweep over the
3 × 3 node blocks before each coarse correction, a backward one after) over:

1. the P2 problem (when the mesh is quadratic);
2. the P1 problem on the same tetrahedra (exactly the P2 one's Galerkin coarse problem under the P1 → P2
   interpolation, :func:`supportless.energies.elasticity.prolongation`);
3. a smoothed-aggregation coarse problem of the P1 one (:func:`aggregate`, :func:`rigid_prolongation`): the
   nodes gathered into aggregates of a node and its neighbours, each moving as a rigid body (six unknowns), the
   prolongation smoothed by one damped Jacobi step; solved by sparse LU.

The levels below the finest are cycled :data:`INNER_CYCLES` times (they are several times cheaper). The matrix
products and sweeps over the 3 × 3 blocks are compiled (numba; the products parallel over rows).

A rig's TetGen mesh has slivers (the bunny's worst tetrahedra have a volume 0.25 % of a regular one's with
their longest edge), which is what the iterations depend on: Gauss-Seidel smooths them better than Jacobi (the
bunny, 92 841 unknowns, to a relative residual of 1e-8: 74 iterations against 122), an exact P1 solve would save
few (70); a box of regular tetrahedra takes 24 (438 204 unknowns).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from numba import njit, prange

from .elasticity import restrict_blocks

__all__ = ["CG_TOLERANCE", "COARSE_DOFS", "DIRECT_DOFS", "INNER_CYCLES", "Level", "aggregate", "block_jacobi",
           "block_matvec", "gauss_seidel", "hierarchy", "largest_eigenvalue", "rigid_prolongation", "solve_held",
           "vcycle"]

#: Systems with at most this many unknowns are solved by sparse LU; larger ones by multigrid CG.
DIRECT_DOFS = 6_000

#: A multigrid level with at most this many unknowns is solved by sparse LU.
COARSE_DOFS = 6_000

#: Cycles at every level but the finest (cheaper ones): more make the coarse correction nearer exact.
INNER_CYCLES = 2

#: Relative residual at which conjugate gradients stop (the bunny's largest section stress is the same to 8
#: digits at 1e-6 and 1e-8; 62 iterations against 74).
CG_TOLERANCE = 1e-6


def solve_held(K: sp.bsr_matrix, f: np.ndarray, held: np.ndarray, positions: np.ndarray,
               coarse: tuple | None = None) -> tuple[np.ndarray, dict]:
    """Solve ``K u = f`` with ``u = 0`` at the held nodes.

    Parameters
    ----------
    K : (3N, 3N) scipy.sparse.bsr_matrix float64
        3 × 3 blocks, one per pair of nodes (scalar degrees of freedom).
    f : (3N,) float64
    held : (N,) bool
    positions : (N, 3) float64
        Every node's position (P2: the vertices, then the edges' midpoints).
    coarse : (K1 (3t, 3t) bsr_matrix, P (N, t) csr_matrix), optional
        For a P2 problem, the P1 problem on its ``t`` vertices (its first ``t`` nodes) and the P1 → P2
        interpolation of a node's value.

    Returns
    -------
    u : (N, 3) float64
    info : dict
        ``solver`` ("lu" or "multigrid-cg"), ``unknowns``, ``iterations``, ``levels`` (unknowns per
        level), ``residual`` (relative).
    """
    free = ~held
    A = restrict_blocks(K, free)
    b = f.reshape(-1, 3)[free].ravel()
    if len(b) <= DIRECT_DOFS:
        x = sla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A").solve(b)
        info = {"solver": "lu", "iterations": 1, "levels": [len(b)]}
    else:
        levels, lu = hierarchy(A, free, positions, coarse)
        count = [0]

        def tick(_):
            count[0] += 1

        op = sla.LinearOperator(A.shape, matvec=lambda v: block_matvec(A, np.ravel(v)), dtype=np.float64)
        M = sla.LinearOperator(A.shape, matvec=lambda r: vcycle(levels, lu, np.ravel(r)), dtype=np.float64)
        x, status = sla.cg(op, b, rtol=CG_TOLERANCE, atol=0.0, maxiter=1000, M=M, callback=tick)
        if status != 0:
            raise RuntimeError(f"conjugate gradients did not converge in {count[0]} iterations")
        info = {"solver": "multigrid-cg", "iterations": count[0],
                "levels": [lv.A.shape[0] for lv in levels] + [lu.shape[0]]}
    u = np.zeros((len(held), 3))
    u[free] = x.reshape(-1, 3)
    norm = np.linalg.norm(b)
    info.update(unknowns=len(b), residual=float(np.linalg.norm(A @ x - b) / norm) if norm > 0 else 0.0)
    return u, info


@dataclass(frozen=True)
class Level:
    """One level of the multigrid cycle.

    Attributes
    ----------
    A : (3n, 3n) scipy.sparse.bsr_matrix float64
        This level's matrix, 3 × 3 blocks with sorted indices.
    Dinv : (n, 3, 3) float64
        The inverses of its diagonal blocks.
    P : (3n, m) scipy.sparse.csr_matrix float64
        The prolongation from the next level; ``R = Pᵀ``.
    R : (m, 3n) scipy.sparse.csr_matrix float64
    """

    A: sp.bsr_matrix
    Dinv: np.ndarray
    P: sp.csr_matrix
    R: sp.csr_matrix


def hierarchy(A: sp.bsr_matrix, free: np.ndarray, positions: np.ndarray, coarse: tuple | None
              ) -> tuple[list[Level], object]:
    """The levels of the cycle, finest first, and the sparse LU of the coarsest problem.

    Parameters
    ----------
    A : (3n, 3n) scipy.sparse.bsr_matrix float64
        The free nodes' problem.
    free : (N,) bool
    positions : (N, 3) float64
        Node positions.
    coarse : (K1, P) or None
        See :func:`solve_held`.

    Returns
    -------
    levels : list of Level
    lu : scipy.sparse.linalg.SuperLU
    """
    levels = []
    where = positions[free]
    if coarse is not None:  # P2 -> P1 on the same tetrahedra, exactly Galerkin
        K1, P = coarse
        vfree = free[: P.shape[1]]
        P3 = sp.kron(P[free][:, vfree], sp.identity(3), format="csr")
        levels.append(Level(A, block_jacobi(A), P3, P3.T.tocsr()))
        A, where = restrict_blocks(K1, vfree), positions[: P.shape[1]][vfree]
    if A.shape[0] > COARSE_DOFS:
        T = rigid_prolongation(where, aggregate(_node_graph(A)))
        Dinv = block_jacobi(A)
        omega = 4.0 / (3.0 * largest_eigenvalue(A, Dinv))
        Asp = A.tocsr()
        Dinv_sp = sp.bsr_matrix((Dinv, np.arange(len(Dinv)), np.arange(len(Dinv) + 1)), shape=A.shape)
        P = (T - omega * (Dinv_sp @ (Asp @ T))).tocsr()  # one Jacobi step: smoothed aggregation
        levels.append(Level(A, Dinv, P, P.T.tocsr()))
        A = P.T @ (Asp @ P)
    A = sp.csc_matrix(0.5 * (A + A.T))
    return levels, sla.splu(A, permc_spec="MMD_AT_PLUS_A")


def vcycle(levels: list[Level], lu, r: np.ndarray, k: int = 0) -> np.ndarray:
    """One symmetric cycle from level ``k``: forward Gauss-Seidel, the next level's correction, backward Gauss-Seidel.

    Parameters
    ----------
    levels : list of Level
    lu : scipy.sparse.linalg.SuperLU
        The coarsest problem, factorised.
    r : (n,) float64
        The residual at level ``k``.
    k : int

    Returns
    -------
    x : (n,) float64
        An approximation of ``A_k⁻¹ r``; the map is linear, symmetric and positive definite. Below the finest
        level the cycle is repeated :data:`INNER_CYCLES` times.
    """
    if k == len(levels):
        return lu.solve(r)
    level = levels[k]
    r = np.ascontiguousarray(r, np.float64)
    x = np.zeros(r.shape)
    for _ in range(1 if k == 0 else INNER_CYCLES):
        gauss_seidel(level.A, level.Dinv, r, x, True)
        x += level.P @ vcycle(levels, lu, level.R @ (r - block_matvec(level.A, x)), k + 1)
        gauss_seidel(level.A, level.Dinv, r, x, False)
    return x


@njit(cache=True, parallel=True)
def _block_matvec(indptr, indices, data, x, y):  # pragma: no cover - compiled
    for i in prange(len(indptr) - 1):
        y0 = 0.0
        y1 = 0.0
        y2 = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            j = 3 * indices[k]
            a = data[k]
            y0 += a[0, 0] * x[j] + a[0, 1] * x[j + 1] + a[0, 2] * x[j + 2]
            y1 += a[1, 0] * x[j] + a[1, 1] * x[j + 1] + a[1, 2] * x[j + 2]
            y2 += a[2, 0] * x[j] + a[2, 1] * x[j + 1] + a[2, 2] * x[j + 2]
        y[3 * i] = y0
        y[3 * i + 1] = y1
        y[3 * i + 2] = y2


def block_matvec(A: sp.bsr_matrix, x: np.ndarray) -> np.ndarray:
    """``A @ x`` for a matrix of 3 × 3 blocks (compiled, parallel over block rows).

    Parameters
    ----------
    A : (3n, 3n) scipy.sparse.bsr_matrix float64
    x : (3n,) float64

    Returns
    -------
    y : (3n,) float64
    """
    y = np.empty(A.shape[0])
    _block_matvec(A.indptr, A.indices, A.data, np.ascontiguousarray(x, np.float64), y)
    return y


@njit(cache=True)
def _gauss_seidel(indptr, indices, data, dinv, b, x, forward):  # pragma: no cover - compiled
    n = len(indptr) - 1
    for step in range(n):
        i = step if forward else n - 1 - step
        r0 = b[3 * i]
        r1 = b[3 * i + 1]
        r2 = b[3 * i + 2]
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            if j != i:
                a = data[k]
                j3 = 3 * j
                r0 -= a[0, 0] * x[j3] + a[0, 1] * x[j3 + 1] + a[0, 2] * x[j3 + 2]
                r1 -= a[1, 0] * x[j3] + a[1, 1] * x[j3 + 1] + a[1, 2] * x[j3 + 2]
                r2 -= a[2, 0] * x[j3] + a[2, 1] * x[j3 + 1] + a[2, 2] * x[j3 + 2]
        d = dinv[i]
        x[3 * i] = d[0, 0] * r0 + d[0, 1] * r1 + d[0, 2] * r2
        x[3 * i + 1] = d[1, 0] * r0 + d[1, 1] * r1 + d[1, 2] * r2
        x[3 * i + 2] = d[2, 0] * r0 + d[2, 1] * r1 + d[2, 2] * r2


def gauss_seidel(A: sp.bsr_matrix, Dinv: np.ndarray, b: np.ndarray, x: np.ndarray, forward: bool) -> None:
    """One block Gauss-Seidel sweep for ``A x = b``, in place: each node's 3 × 3 block solved in turn.

    Parameters
    ----------
    A : (3n, 3n) scipy.sparse.bsr_matrix float64
    Dinv : (n, 3, 3) float64
        Inverses of the diagonal blocks.
    b : (3n,) float64
    x : (3n,) float64
        Updated in place.
    forward : bool
        Nodes in increasing order, else decreasing (the two together are symmetric).
    """
    _gauss_seidel(A.indptr, A.indices, A.data, Dinv, b, x, forward)


def block_jacobi(A: sp.bsr_matrix) -> np.ndarray:
    """The inverses of the 3 × 3 node blocks on the diagonal of a stiffness matrix.

    Parameters
    ----------
    A : (3n, 3n) scipy.sparse.bsr_matrix float64
        3 × 3 blocks, every diagonal block stored.

    Returns
    -------
    Dinv : (n, 3, 3) float64
    """
    n = A.shape[0] // 3
    rows = np.repeat(np.arange(n), np.diff(A.indptr))
    diagonal = np.empty((n, 3, 3))
    on = rows == A.indices
    diagonal[rows[on]] = A.data[on]
    return np.linalg.inv(diagonal)


def largest_eigenvalue(A: sp.bsr_matrix, Dinv: np.ndarray, steps: int = 12) -> float:
    """An upper estimate of the largest eigenvalue of ``D⁻¹ A`` (power iteration, 10 % margin).

    Parameters
    ----------
    A : (3n, 3n) scipy.sparse.bsr_matrix float64
    Dinv : (n, 3, 3) float64
    steps : int

    Returns
    -------
    value : float
    """
    x = np.random.default_rng(0).standard_normal(A.shape[0])
    value = 1.0
    for _ in range(steps):
        y = np.einsum("nij,nj->ni", Dinv, block_matvec(A, x).reshape(-1, 3)).ravel()
        value = float(np.linalg.norm(y) / np.linalg.norm(x))
        x = y / np.linalg.norm(y)
    return 1.1 * value


def _node_graph(A: sp.bsr_matrix) -> sp.csr_matrix:
    """(n, n) scipy.sparse.csr_matrix: which nodes of a block matrix are coupled (its block pattern)."""
    n = A.shape[0] // 3
    return sp.csr_matrix((np.ones(A.indices.size, bool), A.indices, A.indptr), shape=(n, n))


def aggregate(graph: sp.csr_matrix) -> np.ndarray:
    """Gather the nodes of a graph into aggregates: stars of a node and its neighbours, then the rest attached.

    Pass 1 makes an aggregate of each node whose neighbours are all still free, with them; pass 2 attaches
    every node left to the aggregate of a neighbour; pass 3 makes aggregates of what is left (nodes whose
    neighbours were all left too) the same way.

    Parameters
    ----------
    graph : (n, n) scipy.sparse.csr_matrix
        Symmetric; the diagonal is ignored.

    Returns
    -------
    labels : (n,) int64
        The aggregate of each node, ``0 .. count - 1``.
    """
    n = graph.shape[0]
    indptr, indices = graph.indptr, graph.indices
    labels = np.full(n, -1, np.int64)
    count = 0
    for i in range(n):  # pass 1: stars of free nodes
        nbrs = indices[indptr[i]:indptr[i + 1]]
        if labels[i] < 0 and (labels[nbrs] < 0).all():
            labels[nbrs] = count
            labels[i] = count
            count += 1
    for i in np.flatnonzero(labels < 0):  # pass 2: attach to a neighbour's aggregate
        nbrs = indices[indptr[i]:indptr[i + 1]]
        taken = labels[nbrs][labels[nbrs] >= 0]
        if len(taken):
            labels[i] = taken[0]
    for i in np.flatnonzero(labels < 0):  # pass 3: what is left (isolated clusters)
        if labels[i] < 0:
            nbrs = indices[indptr[i]:indptr[i + 1]]
            labels[nbrs[labels[nbrs] < 0]] = count
            labels[i] = count
            count += 1
    return labels


def rigid_prolongation(positions: np.ndarray, labels: np.ndarray) -> sp.csr_matrix:
    """The tentative prolongation of smoothed aggregation: each aggregate moves as a rigid body.

    Each aggregate's rigid motions (three translations, three rotations about its centroid) are
    orthonormalised over its nodes; an aggregate too small for six independent motions (one node, or nodes on
    a line) keeps those it has.

    Parameters
    ----------
    positions : (n, 3) float64
        Node positions.
    labels : (n,) int64
        Aggregate of each node, ``0 .. g - 1``.

    Returns
    -------
    T : (3n, c) scipy.sparse.csr_matrix float64
        ``c <= 6 g`` columns, orthonormal.
    """
    order = np.argsort(labels, kind="stable")
    starts = np.searchsorted(labels[order], np.arange(labels.max() + 2))
    rows, cols, vals = [], [], []
    column = 0
    for g in range(len(starts) - 1):
        nodes = order[starts[g]:starts[g + 1]]
        r = positions[nodes] - positions[nodes].mean(axis=0)
        r /= max(float(np.sqrt((r ** 2).sum(axis=1).mean())), 1e-300)
        modes = np.zeros((len(nodes), 3, 6))
        modes[:, :, :3] = np.eye(3)
        modes[:, 0, 4], modes[:, 0, 5] = r[:, 2], -r[:, 1]  # the rotations' displacements w × r, by column
        modes[:, 1, 3], modes[:, 1, 5] = -r[:, 2], r[:, 0]
        modes[:, 2, 3], modes[:, 2, 4] = r[:, 1], -r[:, 0]
        U, S, _ = np.linalg.svd(modes.reshape(-1, 6), full_matrices=False)
        keep = U[:, S > 1e-8 * S[0]]
        dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
        rows.append(np.repeat(dofs, keep.shape[1]))
        cols.append(np.tile(np.arange(column, column + keep.shape[1]), len(dofs)))
        vals.append(keep.ravel())
        column += keep.shape[1]
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(3 * len(positions), column))
