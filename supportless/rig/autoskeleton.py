"""A skeleton from the shape alone, for figures that come without one.

Most printable figures have no rig. :func:`auto_skeleton` draws one the way a
person would:

1. the surface's vertices are clustered on a grid (:data:`GRID_CELLS` cells
   along the longest side), which makes any mesh — open, non-manifold, a
   million triangles — a graph of a few thousand nodes (:func:`surface_graph`);
2. PyGEL3D's multi-scale local-separator skeleton (Bærentzen & Rotenberg) turns
   that graph into a curve skeleton (:func:`curve_skeleton`), made a tree by
   its shortest spanning tree (a genus-4 figure has loops);
3. twigs shorter than :data:`TWIG_SHARE` of the height are pruned, the
   branches between junctions and tips are simplified to a few straight bones
   each, with the tolerance chosen so that the bone count lands in
   ``bones`` (8–40 by default, :func:`bones_from_tree`);
4. a joint outside the skin (a fingertip's node) moves in along its bone, or goes (:func:`inside_joints`).

The result is a joints/bones pair like a TGF file's, and everything after it
(tetrahedra, weights, search) runs on it unchanged.
"""

from __future__ import annotations

import contextlib
import os

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import minimum_spanning_tree

from ..base.errors import InputError
from ..files.joints import winding_numbers_of

__all__ = ["BONE_RANGE", "GRID_CELLS", "TWIG_SHARE", "auto_skeleton", "planar_skeleton", "bones_from_tree", "curve_skeleton",
           "inside_joints", "surface_graph"]

#: Grid cells along the longest side of the model for the graph the skeleton is computed on.
GRID_CELLS = 48

#: Branches ending in a tip shorter than this share of the model's height are pruned.
TWIG_SHARE = 0.06

#: The default number of bones, (fewest, most).
BONE_RANGE = (8, 40)


def surface_graph(vertices: np.ndarray, faces: np.ndarray, cells: int = GRID_CELLS) -> tuple[np.ndarray, np.ndarray]:
    """The surface's vertices clustered on a grid, and the edges between clusters.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    cells : int
        Grid cells along the longest side of the bounding box.

    Returns
    -------
    points : (k, 3) float64
        The mean of each cluster's vertices.
    edges : (e, 2) int64
        Cluster pairs joined by a mesh edge, each once.
    """
    V = np.asarray(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    size = float(np.ptp(V, axis=0).max()) / cells
    key = np.floor((V - V.min(axis=0)) / size).astype(np.int64)
    _, cluster = np.unique(key, axis=0, return_inverse=True)
    cluster = cluster.ravel()
    k = int(cluster.max()) + 1
    points = np.zeros((k, 3))
    np.add.at(points, cluster, V)
    points /= np.bincount(cluster, minlength=k)[:, None]
    E = cluster[np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])]
    E = np.unique(np.sort(E[E[:, 0] != E[:, 1]], axis=1), axis=0)
    return points, E


@contextlib.contextmanager
def _quiet():
    """PyGEL3D prints its progress on the process's standard output: send it to /dev/null meanwhile."""
    try:
        fd = os.dup(1)
    except OSError:  # no standard output to silence
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(fd, 1)
        os.close(fd)


def curve_skeleton(points: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A curve skeleton of a graph, as a tree.

    Parameters
    ----------
    points : (k, 3) float64
    edges : (e, 2) int64

    Returns
    -------
    nodes : (s, 3) float64
        Skeleton node positions.
    tree : (s - c, 2) int64
        The edges of the skeleton's shortest spanning forest (``c`` its parts; one for a connected body).
    """
    from pygel3d import graph

    g = graph.Graph()
    for p in points:
        g.add_node(p)
    for a, b in edges:
        g.connect_nodes(int(a), int(b))
    with _quiet():
        s = graph.MSLS_skeleton(g)
    ids = list(s.nodes())
    index = {n: i for i, n in enumerate(ids)}
    nodes = np.asarray(s.positions(), np.float64)[ids]
    pairs = np.array([(index[a], index[b]) for a in ids for b in s.neighbors(a) if b in index and index[a] < index[b]],
                     np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        return nodes, pairs
    length = np.linalg.norm(nodes[pairs[:, 0]] - nodes[pairs[:, 1]], axis=1) + 1e-12
    mst = minimum_spanning_tree(coo_matrix((length, (pairs[:, 0], pairs[:, 1])), shape=(len(nodes),) * 2)).tocoo()
    return nodes, np.column_stack([mst.row, mst.col]).astype(np.int64)


def _adjacency(count: int, edges: np.ndarray) -> list[set]:
    adj = [set() for _ in range(count)]
    for a, b in edges:
        adj[int(a)].add(int(b))
        adj[int(b)].add(int(a))
    return adj


def _prune(nodes: np.ndarray, adj: list[set], shortest: float) -> None:
    """Remove tip branches shorter than ``shortest`` (in place), shortest first, until none is left."""
    while True:
        twigs = []
        for tip in [n for n in range(len(adj)) if len(adj[n]) == 1]:
            path, length, prev, cur = [tip], 0.0, -1, tip
            while True:
                nxt = [x for x in adj[cur] if x != prev]
                if len(adj[cur]) > 2 and cur != tip or not nxt:
                    break
                length += float(np.linalg.norm(nodes[nxt[0]] - nodes[cur]))
                prev, cur = cur, nxt[0]
                path.append(cur)
                if len(adj[cur]) != 2:
                    break
            if len(adj[cur]) > 2 and length < shortest:  # a twig off a junction (not a whole chain)
                twigs.append((length, path[:-1]))
        if not twigs:
            return
        _, path = min(twigs)
        for n in path:
            for x in list(adj[n]):
                adj[x].discard(n)
            adj[n].clear()


def _branches(adj: list[set]) -> list[list[int]]:
    """The tree's branches: node paths between nodes that are not of degree 2 (tips and junctions)."""
    ends = [n for n in range(len(adj)) if adj[n] and len(adj[n]) != 2]
    seen, out = set(), []
    for start in ends:
        for first in adj[start]:
            if (start, first) in seen:
                continue
            path, prev, cur = [start, first], start, first
            while len(adj[cur]) == 2:
                nxt = next(x for x in adj[cur] if x != prev)
                prev, cur = cur, nxt
                path.append(cur)
            seen.add((path[-1], path[-2]))
            seen.add((start, first))
            out.append(path)
    return out


def _simplify(points: np.ndarray, tolerance: float) -> list[int]:
    """Douglas-Peucker on a polyline: the indices of the points kept (the ends always)."""
    keep = {0, len(points) - 1}
    stack = [(0, len(points) - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        a, b = points[i], points[j]
        ab = b - a
        t = np.clip(((points[i + 1:j] - a) @ ab) / max(float(ab @ ab), 1e-300), 0.0, 1.0)
        d = np.linalg.norm(points[i + 1:j] - (a + t[:, None] * ab), axis=1)
        k = int(np.argmax(d))
        if d[k] > tolerance:
            keep.add(i + 1 + k)
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return sorted(keep)


def bones_from_tree(nodes: np.ndarray, tree: np.ndarray, height: float, bones: tuple = BONE_RANGE,
                    twig_share: float = TWIG_SHARE, centre: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Joints and bones a person would draw from a curve skeleton.

    Parameters
    ----------
    nodes : (s, 3) float64
    tree : (t, 2) int64
        A forest over ``nodes`` (its largest tree is used).
    height : float
        The model's height: the scale of the twig length and the simplification.
    bones : (int, int)
        Fewest and most bones wanted.
    twig_share : float
        Tip branches shorter than this share of ``height`` are pruned.
    centre : (3,) float64, optional
        The body's centre: the root is the junction nearest it (default: the nodes' mean).

    Returns
    -------
    joints : (j, 3) float64
    bone_pairs : (j - 1, 2) int64
        A tree, each bone written root -> tip (as a TGF file wants them).
    """
    centre = np.asarray(nodes, np.float64).mean(axis=0) if centre is None else np.asarray(centre, np.float64)
    adj = _adjacency(len(nodes), tree)
    # the largest connected part
    part = -np.ones(len(nodes), np.int64)
    for s in range(len(nodes)):
        if part[s] >= 0:
            continue
        stack, part[s] = [s], s
        while stack:
            n = stack.pop()
            for x in adj[n]:
                if part[x] < 0:
                    part[x] = s
                    stack.append(x)
    biggest = np.bincount(part).argmax()
    for n in np.flatnonzero(part != biggest):
        adj[n].clear()
    _prune(nodes, adj, twig_share * height)
    branches = _branches(adj)
    if not branches:
        raise InputError(None, "the shape's skeleton is a single point: give a skeleton (--skeleton S.tgf)")
    low, high = bones

    def draw(tolerance):
        kept = [[path[i] for i in _simplify(nodes[path], tolerance)] for path in branches]
        return kept, sum(len(k) - 1 for k in kept)

    lo_t, hi_t = 1e-4 * height, 0.5 * height
    kept, count = draw(0.04 * height)
    for _ in range(40):  # bisection on the tolerance (fewer bones as it grows)
        if low <= count <= high or hi_t - lo_t < 1e-6 * height:
            break
        t = 0.5 * (lo_t + hi_t)
        if count > high:
            lo_t = t
        else:
            hi_t = t
        kept, count = draw(0.5 * (lo_t + hi_t))
    used = sorted({n for k in kept for n in k})
    index = {n: i for i, n in enumerate(used)}
    pairs = {tuple(sorted((index[a], index[b]))) for k in kept for a, b in zip(k[:-1], k[1:])}
    joints = nodes[used].copy()
    return joints, _rooted(joints, np.array(sorted(pairs), np.int64), centre)


def _rooted(joints: np.ndarray, pairs: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """The bones of a tree written root -> tip, from the junction (or joint) nearest ``centre``, in BFS order."""
    adj = _adjacency(len(joints), pairs)
    degree = np.array([len(a) for a in adj])
    pool = np.flatnonzero(degree > 2) if (degree > 2).any() else np.arange(len(joints))
    root = int(pool[np.argmin(np.linalg.norm(joints[pool] - centre, axis=1))])
    out, seen, queue = [], {root}, [root]
    while queue:
        n = queue.pop(0)
        for x in sorted(adj[n]):
            if x not in seen:
                seen.add(x)
                out.append((n, x))
                queue.append(x)
    return np.array(out, np.int64).reshape(-1, 2)


def auto_skeleton(vertices: np.ndarray, faces: np.ndarray, up, bones: tuple | int | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """A skeleton for a figure that has none.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Any triangle surface (open or non-manifold is fine).
    up : (3,) float64
        The printing direction (the height is measured along it).
    bones : int or (int, int), optional
        About how many bones (an int: within 25 % of it), or the fewest and
        most; default :data:`BONE_RANGE`. Never fewer than one per branch of
        the pruned skeleton.

    Returns
    -------
    joints : (j, 3) float64
        Inside the surface where it is closed.
    bone_pairs : (m, 2) int64
    """
    V = np.asarray(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    up = np.asarray(up, np.float64)
    height = float(np.ptp(V @ up)) or float(np.ptp(V, axis=0).max())
    wanted = BONE_RANGE if bones is None else (
        (max(1, int(round(0.75 * bones))), max(1, int(round(1.25 * bones)))) if np.ndim(bones) == 0 else tuple(bones))
    nodes, tree = curve_skeleton(*surface_graph(V, F))
    J, B = bones_from_tree(nodes, tree, height, wanted, centre=V.mean(axis=0))
    return inside_joints(V, F, J, B)


def planar_skeleton(vertices: np.ndarray, faces: np.ndarray, up, bones: tuple | int | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """A skeleton for a planar figure (the paper's 2D mode) that has none: that of the figure extruded.

    The figure becomes a slab as thick as its limbs are wide (twice its area
    over its outline's length: a strip of width w gives w), whose curve
    skeleton (:func:`auto_skeleton`) lies in the middle plane; its joints are
    put back on the plane.

    Parameters
    ----------
    vertices : (n, 2) or (n, 3) float64
        z = 0 when three columns.
    faces : (f, 3) int64
        A triangulated region (one piece, its outline its boundary edges).
    up : (2,) or (3,) float64
        The printing direction, in the plane.
    bones : int or (int, int), optional
        As for :func:`auto_skeleton`.

    Returns
    -------
    joints : (j, d) float64
        As many columns as ``vertices``; inside the figure.
    bone_pairs : (m, 2) int64
    """
    V2 = np.asarray(vertices, np.float64)[:, :2]
    F = np.asarray(faces, np.int64)
    e1, e2 = V2[F[:, 1]] - V2[F[:, 0]], V2[F[:, 2]] - V2[F[:, 0]]
    signed = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    F = np.where((signed > 0)[:, None], F, F[:, [0, 2, 1]])  # every triangle counter-clockwise
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(directed, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    outline = directed[counts[inverse.ravel()] == 1]
    length = float(np.linalg.norm(V2[outline[:, 1]] - V2[outline[:, 0]], axis=1).sum())
    thickness = (float(np.abs(signed).sum()) / length) if length > 0 else float(np.ptp(V2, axis=0).max()) * 0.05
    n = len(V2)
    slab = np.vstack([np.column_stack([V2, np.full(n, thickness / 2)]), np.column_stack([V2, np.full(n, -thickness / 2)])])
    a, b = outline[:, 0], outline[:, 1]
    walls = np.vstack([np.column_stack([b, a, a + n]), np.column_stack([b, a + n, b + n])])
    slab_faces = np.vstack([F, F[:, [0, 2, 1]] + n, walls])
    up3 = np.zeros(3)
    up3[:2] = np.asarray(up, np.float64).ravel()[:2]
    J, B = auto_skeleton(slab, slab_faces, up3, bones)
    return J[:, :np.asarray(vertices).shape[1]] * ([1.0, 1.0, 0.0][:np.asarray(vertices).shape[1]]), B


def inside_joints(vertices: np.ndarray, faces: np.ndarray, joints: np.ndarray, bones: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Joints moved inside the surface along their bones; a tip that cannot be is dropped with its bone.

    A skeleton node of a thin part (a finger) can lie just outside. Each joint
    outside (winding number below 1/2) moves to the first point inside along
    one of its bones, nearest the joint; a tip with none inside is removed, and
    so on until every joint is inside (or the skeleton would lose its last bone).

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    joints : (j, 3) float64
    bones : (m, 2) int64
        Root -> tip.

    Returns
    -------
    joints : (j', 3) float64
    bones : (m', 2) int64
    """
    V = np.asarray(vertices, np.float64)
    J, B = np.array(joints, np.float64), np.array(bones, np.int64)
    winding = winding_numbers_of(V, faces)  # the tree built once for every question below

    def inside(points):
        return winding(points) > 0.5

    t = np.linspace(0.02, 0.98, 49)
    while True:
        outside = np.flatnonzero(~inside(J))
        if len(outside) == 0 or len(B) <= 1:
            return J, B
        degree = np.bincount(B.ravel(), minlength=len(J))
        drop = None
        for j in outside:
            moved = False
            for a, b in B[(B[:, 0] == j) | (B[:, 1] == j)]:
                other = b if a == j else a
                samples = J[j] + t[:, None] * (J[other] - J[j])
                ok = np.flatnonzero(inside(samples))
                if len(ok):
                    J[j] = samples[ok[0]]
                    moved = True
                    break
            if not moved and degree[j] == 1:
                drop = j
                break
        if drop is None:
            return J, B
        B = B[(B[:, 0] != drop) & (B[:, 1] != drop)]
        keep = np.setdiff1d(np.arange(len(J)), [drop])
        remap = -np.ones(len(J), np.int64)
        remap[keep] = np.arange(len(keep))
        J, B = J[keep], remap[B]
