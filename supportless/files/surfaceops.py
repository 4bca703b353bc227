"""Small operations on a triangle surface that carries values on its vertices (skin weights).

What the print body (:mod:`supportless.files.printbody`) and the removal of
crossings (:mod:`supportless.files.crossings`) are made of: the enclosed volume,
vertices welded, connected pieces, the closed-surface test, short edges
collapsed and flat caps flipped (what a boolean leaves), and values carried to
new points from the closest point of a surface.
"""

from __future__ import annotations

import numpy as np

from .meshes import _key_base, _pair_keys, closes_up

__all__ = ["transfer_values"]


def _volume(V: np.ndarray, F: np.ndarray) -> float:
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _weld(V, F, values, tol):
    """Merge vertices within ``tol`` of each other; values averaged. Returns V, F, values, merged count."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    if len(V) == 0:
        return V, F, values, 0
    pairs = cKDTree(V).query_pairs(tol, output_type="ndarray")
    if len(pairs) == 0:
        return V, F, values, 0
    A = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(V), len(V)))
    k, inverse = connected_components(A, directed=False)
    first = np.arange(k)
    count = np.bincount(inverse, minlength=k).astype(np.float64)
    Vn = np.zeros((k, 3))
    np.add.at(Vn, inverse, V)
    Vn /= count[:, None]
    Wn = np.zeros((len(first), values.shape[1]))
    np.add.at(Wn, inverse, values)
    Wn /= count[:, None]
    return Vn, inverse[F], Wn, len(V) - len(first)


def _components(F: np.ndarray, n: int) -> np.ndarray:
    """(f,) int64: connected component (through shared vertices) of each face."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    f = len(F)
    rows = np.repeat(np.arange(f), 3)
    A = coo_matrix((np.ones(3 * f), (rows, F.ravel() + f)), shape=(f + n, f + n))
    _, labels = connected_components(A, directed=False)
    return np.unique(labels[:f], return_inverse=True)[1].ravel()


def _is_closed(F: np.ndarray) -> bool:
    """Every edge has exactly two faces, in opposite directions."""
    return closes_up(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]))


def _collapse_short_edges(V, F, values, tol):
    """Merge the ends of edges shorter than ``tol``; drop the faces that vanish.

    A face left with a repeated vertex is dropped, and so is a pair of faces
    on the same three vertices (a collapsed sliver of volume).
    """
    for _ in range(3):
        E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
        short = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1) < tol
        if not np.any(short):
            break
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        S = E[short]
        k, label = connected_components(coo_matrix((np.ones(len(S)), (S[:, 0], S[:, 1])), shape=(len(V),) * 2),
                                        directed=False)
        count = np.bincount(label, minlength=k).astype(np.float64)[:, None]
        Vn = np.zeros((k, 3))
        np.add.at(Vn, label, V)
        Wn = np.zeros((k, values.shape[1]))
        np.add.at(Wn, label, values)
        V, values, F = Vn / count, Wn / count, label[F]
        F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])]
        key = np.sort(F, axis=1)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        F = F[cnt[inv.ravel()] == 1]
        used = np.unique(F)
        remap = np.full(len(V), -1, np.int64)
        remap[used] = np.arange(len(used))
        V, values, F = V[used], values[used], remap[F]
    return V, F, values


def _flip_caps(V, F, tol, rounds: int = 5):
    """Flip the longest edge of each cap (a triangle flatter than ``tol``) with its neighbour's.

    Each round flips the caps in order, each with the triangle across its longest edge (the last one listed
    on that edge, should there be more), unless either was flipped this round or the new edge is already one.
    """
    F = F.copy()
    for _ in range(rounds):
        a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        lengths = np.column_stack([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                                   np.linalg.norm(a - c, axis=1)])
        height = np.linalg.norm(np.cross(b - a, c - a), axis=1) / np.maximum(lengths.max(1), 1e-300)
        caps = np.flatnonzero(height < tol)
        if len(caps) == 0:
            break
        directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]).astype(np.int64)
        n = _key_base(directed)  # every key below is p * n + q
        owners = np.tile(np.arange(len(F)), 3)
        keys = _pair_keys(directed)
        order = np.lexsort((owners, keys))  # by edge, then face: an edge's last face ends its run
        keys, owners = keys[order], owners[order]
        edges = np.unique(_pair_keys(np.sort(directed, axis=1)))
        added: set[int] = set()
        touched: set[int] = set()

        def owner(p: int, q: int) -> int | None:
            at = int(np.searchsorted(keys, p * n + q, side="right")) - 1
            return int(owners[at]) if at >= 0 and keys[at] == p * n + q else None

        def is_edge(p: int, q: int) -> bool:
            key = min(p, q) * n + max(p, q)
            at = int(np.searchsorted(edges, key))
            return key in added or (at < len(edges) and edges[at] == key)

        for f in caps.tolist():
            if f in touched:
                continue
            k = int(np.argmax(lengths[f]))
            p, q, r = (int(v) for v in np.roll(F[f], -k))  # longest edge p->q, r opposite
            g = owner(q, p)
            if g is None or g in touched:
                continue
            d = int(next(v for v in F[g] if v not in (p, q)))
            if is_edge(r, d) or r == d:
                continue
            F[f] = (p, d, r)
            F[g] = (d, q, r)
            added.add(min(r, d) * n + max(r, d))
            touched.update((f, g))
    return F


def transfer_values(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Values at points from the closest point of a surface (barycentric interpolation).

    Parameters
    ----------
    points : (p, 3) float64
    vertices : (n, 3) float64
    faces : (f, 3) int64
    values : (n, k) float64

    Returns
    -------
    out : (p, k) float64
    """
    import igl

    if np.shape(values)[1] == 0:  # nothing to carry: no closest points to find
        return np.zeros((len(points), 0))
    P = np.ascontiguousarray(points, np.float64)
    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    _, I, C = igl.point_mesh_squared_distance(P, V, F)
    I = np.asarray(I, np.int64).ravel()
    C = np.asarray(C, np.float64)
    tri = F[I]
    bary = _barycentric(C, V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]])
    return np.einsum("pk,pkc->pc", bary, values[tri])


def _barycentric(p, a, b, c) -> np.ndarray:
    v0, v1, v2 = b - a, c - a, p - a
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = d00 * d11 - d01 * d01
    den = np.where(np.abs(den) > 1e-300, den, 1.0)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    out = np.column_stack([1 - v - w, v, w])
    out = np.clip(out, 0.0, None)
    return out / np.maximum(out.sum(1, keepdims=True), 1e-300)
