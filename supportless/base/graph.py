"""Connected components of an undirected graph given by its edges, in one compiled pass (union-find).

The strength analysis labels the loops of every section it cuts and the part of the surface beyond each bone
section: thousands of small graphs per analysis, where building a sparse matrix for
:func:`scipy.sparse.csgraph.connected_components` cost more than the labelling.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["edge_components"]


def edge_components(count: int, first: np.ndarray, second: np.ndarray) -> tuple[int, np.ndarray]:
    """The connected components of the undirected graph on ``count`` nodes with edges ``first[i] - second[i]``.

    The labels are those of :func:`scipy.sparse.csgraph.connected_components` (``directed=False``): components
    numbered in the order of their smallest node.

    Parameters
    ----------
    count : int
        Nodes ``0 .. count-1``.
    first, second : (e,) int
        The edges' ends.

    Returns
    -------
    components : int
    labels : (count,) int64
    """
    a = np.ascontiguousarray(first, np.int64)
    b = np.ascontiguousarray(second, np.int64)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"the edges' ends must be two (e,) arrays, not {a.shape} and {b.shape}")
    if len(a) and (min(a.min(), b.min()) < 0 or max(a.max(), b.max()) >= count):
        raise ValueError(f"an edge's end is outside the {count} nodes")
    return _components(int(count), a, b)


@njit(cache=True)
def _root(parent, x):  # pragma: no cover - compiled
    while parent[x] != x:
        parent[x] = parent[parent[x]]  # path halving
        x = parent[x]
    return x


@njit(cache=True)
def _components(count, a, b):  # pragma: no cover - compiled
    # every root is the smallest node of its set (the larger root is hung under the smaller): the labels, given
    # in increasing node order at each root, number the components by their smallest node
    parent = np.arange(count)
    for e in range(a.shape[0]):
        x = _root(parent, a[e])
        y = _root(parent, b[e])
        if x < y:
            parent[y] = x
        elif y < x:
            parent[x] = y
    labels = np.empty(count, np.int64)
    components = 0
    for i in range(count):
        r = _root(parent, i)
        if r == i:
            labels[i] = components
            components += 1
        else:
            labels[i] = labels[r]
    return components, labels
