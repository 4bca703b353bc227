"""Euler angles -> forward kinematics -> bone transforms -> linear blend skinning.

Conventions used across the project:

* A skeleton is ``joints (j, d)`` and ``bones (m, 2)``: bone ``b`` goes from its
  root joint ``bones[b, 0]`` to its tip ``bones[b, 1]``. Bone ``p`` is the
  parent of ``b`` when ``p``'s tip is ``b``'s root. Bones may come in any order
  and may form a forest.
* A pose is one rotation per bone, relative to its parent, about the bone's root
  joint, given as Euler angles ``(P, m, 3)`` in radians:
  ``R = Rx(a0) @ Ry(a1) @ Rz(a2)``. In 2D only ``a2`` (about the plane normal)
  is used.
* A bone transform is an affine map ``x -> A x + b`` stored as a
  ``(d, d+1)`` matrix ``[A | b]``. A batch is ``(P, m, d, d+1)``.
* Linear blend skinning: ``v'_i = sum_j w_ij (A_j v_i + b_j)``, i.e.
  ``V' = M T`` with :func:`lbs_matrix` and :func:`stack_transforms`.

Forward kinematics composes rotations down the chain like libigl's
``forward_kinematics``: ``Q_b = Q_parent(b) dQ_b`` and the joint of a child
follows its parent's motion.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .chain import chain_transforms3, euler_matrices
from .skinning import WeightBlocks, skin_blocks, skin_dense, weight_blocks
from .threads import over


def bone_parents(bones: np.ndarray) -> np.ndarray:
    """Parent of each bone: the bone whose tip is its root joint.

    Parameters
    ----------
    bones : (m, 2) int64
        ``[root joint, tip joint]`` per bone.

    Returns
    -------
    parents : (m,) int64
        Index of the parent bone, ``-1`` for a root bone.
    """
    bones = np.asarray(bones, dtype=np.int64)
    parents = np.full(len(bones), -1, dtype=np.int64)
    tip_owner = {}
    for b, tip in enumerate(bones[:, 1]):
        tip_owner.setdefault(int(tip), b)
    for b, root in enumerate(bones[:, 0]):
        parents[b] = tip_owner.get(int(root), -1)
    return parents


def topological_order(parents: np.ndarray) -> np.ndarray:
    """Bones ordered so every parent comes before its children.

    Parameters
    ----------
    parents : (m,) int64
        From :func:`bone_parents`.

    Returns
    -------
    order : (m,) int64

    Raises
    ------
    ValueError
        If the parent relation has a cycle.
    """
    m = len(parents)
    depth = np.full(m, -1)
    for b in range(m):
        chain, p = [], b
        while p >= 0 and depth[p] < 0:
            chain.append(p)
            if len(chain) > m:
                raise ValueError("the bones form a cycle")
            p = parents[p]
        d = -1 if p < 0 else depth[p]
        for q in reversed(chain):
            d += 1
            depth[q] = d
    return np.argsort(depth, kind="stable")


def bone_depths(parents: np.ndarray) -> np.ndarray:
    """How many bones lie above each bone in its tree (0 for a root).

    Parameters
    ----------
    parents : (m,) int64

    Returns
    -------
    depth : (m,) int64
    """
    depth = np.zeros(len(parents), np.int64)
    for b in topological_order(parents):
        depth[b] = 0 if parents[b] < 0 else depth[parents[b]] + 1
    return depth


def descendants(parents: np.ndarray, bone: int) -> np.ndarray:
    """The bone and every bone below it in the hierarchy.

    Parameters
    ----------
    parents : (m,) int64
    bone : int

    Returns
    -------
    mask : (m,) bool
    """
    m = len(parents)
    mask = np.zeros(m, bool)
    mask[bone] = True
    for b in topological_order(parents):
        if parents[b] >= 0 and mask[parents[b]]:
            mask[b] = True
    return mask


def reroot(bones: np.ndarray, parents: np.ndarray, anchor: int) -> tuple[np.ndarray, np.ndarray]:
    """The tree of pose files of version 1: the path from ``anchor`` to its root reversed, nothing else.

    The bones on the path from ``anchor`` up to its root have their parent
    pointers reversed: each now hangs from its former child and turns about the
    joint they share (its tip). Every other bone keeps its parent and turns
    about its root joint. With ``anchor`` a root bone nothing changes.

    This tears a skeleton whose root joint has several bones (they stay roots,
    about a joint that now moves): :func:`kinematic_tree` is the rig's tree. It
    is kept to recognise pose files written with it
    (:func:`supportless.files.posefile.read_pose`).

    Parameters
    ----------
    bones : (m, 2) int64
    parents : (m,) int64
        From :func:`bone_parents`.
    anchor : int
        The bone that becomes a root (e.g. the one resting on the build plate).

    Returns
    -------
    parents : (m,) int64
        The re-rooted parent of each bone (-1 for roots).
    pivots : (m,) int64
        The joint each bone turns about.
    """
    bones = np.asarray(bones, np.int64)
    new = np.array(parents, np.int64)
    pivots = bones[:, 0].copy()
    child, b = -1, int(anchor)
    while b >= 0:
        up = int(parents[b])
        new[b] = child
        if child >= 0:
            pivots[b] = bones[b, 1]  # shared with the former child
        child, b = b, up
    return new, pivots


def kinematic_tree(bones: np.ndarray, roots=()) -> tuple[np.ndarray, np.ndarray]:
    """One kinematic tree per connected skeleton, hanging from the given root bones.

    Two bones are connected when they share a joint. From a root bone the tree
    grows breadth first: the first bone of the tree to reach a joint carries it,
    and every other bone at that joint hangs from it and turns about that joint.
    So bones that share a joint always keep it in one place (siblings at a
    skeleton's root joint included), and a chain rooted at its end (a hand on
    the plate) carries the rest of the body. The first of ``roots`` in each
    connected skeleton is its root; a skeleton with none is rooted at its first
    root bone of :func:`bone_parents` (its old root).

    Parameters
    ----------
    bones : (m, 2) int64
        ``[root joint, tip joint]`` per bone.
    roots : sequence of int
        Candidate root bones in order of preference; later ones in an
        already-rooted skeleton hang from its tree.

    Returns
    -------
    parents : (m,) int64
        The parent of each bone in the tree, -1 for the root of each skeleton.
    pivots : (m,) int64
        The joint each bone turns about: the joint it shares with its parent
        (a root's is its root joint ``bones[b, 0]``).
    """
    bones = np.asarray(bones, np.int64)
    m = len(bones)
    parents = np.full(m, -1, np.int64)
    pivots = bones[:, 0].copy() if m else np.zeros(0, np.int64)
    at_joint: dict[int, list[int]] = {}
    for b, (r, t) in enumerate(bones):
        at_joint.setdefault(int(r), []).append(b)
        at_joint.setdefault(int(t), []).append(b)
    seen = np.zeros(m, bool)
    for root in [int(r) for r in roots] + list(topological_order(bone_parents(bones))):
        if seen[root]:
            continue
        seen[root] = True
        queue = [root]
        for b in queue:
            for joint in (pivots[b], *(j for j in bones[b] if j != pivots[b])):
                for c in at_joint[int(joint)]:
                    if not seen[c]:
                        seen[c], parents[c], pivots[c] = True, b, joint
                        queue.append(c)
    return parents, pivots


def connecting_bones(bones: np.ndarray, terminals: np.ndarray) -> np.ndarray:
    """The smallest connected set of bones that contains the given ones.

    Two bones are connected when they share a joint. The set is the union of
    the shortest chains from the first terminal to every other one; in a
    skeleton (a tree of joints) that is the smallest connected set. Terminals in
    separate skeletons (a forest) stay separate.

    Parameters
    ----------
    bones : (m, 2) int64
    terminals : (m,) bool

    Returns
    -------
    mask : (m,) bool
        ``terminals`` and the bones between them.
    """
    bones = np.asarray(bones, np.int64)
    m = len(bones)
    terminals = np.asarray(terminals, bool)
    mask = terminals.copy()
    by_joint: dict[int, list[int]] = {}
    for b, (r, t) in enumerate(bones):
        by_joint.setdefault(int(r), []).append(b)
        by_joint.setdefault(int(t), []).append(b)
    todo = list(np.flatnonzero(terminals))
    while todo:  # one breadth-first search per connected group of terminals
        source = todo[0]
        previous = np.full(m, -2)
        previous[source] = -1
        queue = [source]
        for b in queue:
            for joint in bones[b]:
                for c in by_joint[int(joint)]:
                    if previous[c] == -2:
                        previous[c] = b
                        queue.append(c)
        for t in todo:
            while t >= 0 and previous[t] != -2:  # walk back to the source
                mask[t] = True
                t = previous[t]
        todo = [t for t in todo if previous[t] == -2]
    return mask


def euler_to_matrix(angles: np.ndarray) -> np.ndarray:
    """Rotation matrices from XYZ Euler angles.

    Parameters
    ----------
    angles : (..., 3) float64
        Radians ``(a0, a1, a2)``.

    Returns
    -------
    R : (..., 3, 3) float64
        ``Rx(a0) @ Ry(a1) @ Rz(a2)``.
    """
    a = np.asarray(angles, dtype=np.float64)
    return euler_matrices(np.ascontiguousarray(a.reshape(-1, 3))).reshape(a.shape[:-1] + (3, 3))


def matrix_to_euler(R: np.ndarray) -> np.ndarray:
    """XYZ Euler angles of rotation matrices: the inverse of :func:`euler_to_matrix`.

    ``euler_to_matrix(matrix_to_euler(R))`` is ``R`` to round-off, also at and
    near gimbal lock (``a1 = ±90°``), where only ``a0 ± a2`` is determined: the
    third angle is solved from the first two so the pair still rebuilds ``R``.

    Parameters
    ----------
    R : (..., 3, 3) float64
        Rotation matrices.

    Returns
    -------
    angles : (..., 3) float64
        Radians ``(a0, a1, a2)`` with ``R = Rx(a0) @ Ry(a1) @ Rz(a2)``;
        ``a0, a2`` in ``[-pi, pi]``, ``a1`` in ``[-pi/2, pi/2]``. At gimbal
        lock ``a0 = 0``.
    """
    R = np.asarray(R, dtype=np.float64)
    cos_a1 = np.hypot(R[..., 0, 0], R[..., 0, 1])
    a1 = np.arctan2(R[..., 0, 2], cos_a1)
    # a0 from the last column (-sx cy, cx cy); undefined at gimbal lock (cy = 0): take 0
    locked = np.hypot(R[..., 1, 2], R[..., 2, 2]) < 1e-12
    a0 = np.where(locked, 0.0, np.arctan2(-R[..., 1, 2], R[..., 2, 2]))
    # a2 from the middle row of Rx(a0)^T R = Ry(a1) Rz(a2), which is (sin a2, cos a2, 0)
    c0, s0 = np.cos(a0), np.sin(a0)
    a2 = np.arctan2(c0 * R[..., 1, 0] + s0 * R[..., 2, 0], c0 * R[..., 1, 1] + s0 * R[..., 2, 1])
    return np.stack([a0, a1, a2], axis=-1)


def planar_rotation(theta: np.ndarray) -> np.ndarray:
    """2D rotation matrices.

    Parameters
    ----------
    theta : (...,) float64
        Radians, counter-clockwise.

    Returns
    -------
    R : (..., 2, 2) float64
    """
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def forward_kinematics(joints: np.ndarray, bones: np.ndarray, angles: np.ndarray,
                       parents: np.ndarray | None = None, order: np.ndarray | None = None,
                       pivots: np.ndarray | None = None) -> np.ndarray:
    """Bone transforms of a batch of poses.

    Parameters
    ----------
    joints : (j, d) float64
        Rest joint positions, d = 2 or 3.
    bones : (m, 2) int64
    angles : (P, m, 3) or (m, 3) float64
        Relative XYZ Euler angles per bone, radians (2D uses ``[..., 2]`` only).
    parents, order : (m,) int64, optional
        The kinematic tree (:func:`kinematic_tree`) and :func:`topological_order`
        of it; without ``parents``, ``kinematic_tree(bones)`` (each skeleton
        rooted at its first root bone).
    pivots : (m,) int64, optional
        The joint each bone turns about, shared with its parent (default: the
        tree's, or each bone's root joint ``bones[:, 0]`` when ``parents`` is given).

    Returns
    -------
    transforms : (P, m, d, d+1) or (m, d, d+1) float64
        ``[A | b]`` per bone; zero angles give ``[I | 0]``.
    """
    joints = np.asarray(joints, dtype=np.float64)
    bones = np.asarray(bones, dtype=np.int64)
    angles = np.asarray(angles, dtype=np.float64)
    single = angles.ndim == 2
    if single:
        angles = angles[None]
    P, m = angles.shape[:2]
    if m != len(bones):
        raise ValueError(f"angles have {m} bones, the skeleton has {len(bones)}")
    d = joints.shape[1]
    if parents is None:
        parents, tree_pivots = kinematic_tree(bones)
        pivots = tree_pivots if pivots is None else pivots
    if order is None:
        order = topological_order(parents)
    roots = joints[bones[:, 0] if pivots is None else np.asarray(pivots, np.int64)]  # (m, d)
    if d == 3:  # compiled (base/chain): the bits the loop below gives a 3D rig
        out = chain_transforms3(euler_to_matrix(angles), np.ascontiguousarray(roots), np.asarray(parents, np.int64),
                                np.asarray(order, np.int64))
        return out[0] if single else out
    dQ = planar_rotation(angles[..., 2])
    Q = np.empty((P, m, d, d))
    t = np.empty((P, m, d))
    for b in order:  # m iterations, each vectorised over poses
        r = roots[b]
        p = parents[b]
        if p < 0:
            Q[:, b] = dQ[:, b]
            t[:, b] = r - dQ[:, b] @ r
        else:
            Q[:, b] = Q[:, p] @ dQ[:, b]
            # the pivot joint moves with the parent, then the bone turns about it
            t[:, b] = Q[:, p] @ r + t[:, p] - Q[:, b] @ r
    out = np.concatenate([Q, t[..., None]], axis=-1)
    return out[0] if single else out


def transform_points(transforms: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply per-bone affine transforms to one point per bone.

    Parameters
    ----------
    transforms : (..., m, d, d+1) float64
    points : (m, d) float64

    Returns
    -------
    out : (..., m, d) float64
    """
    A = transforms[..., :-1]
    b = transforms[..., -1]
    return np.einsum("...ij,...j->...i", A, points) + b


def posed_joints(joints: np.ndarray, bones: np.ndarray, transforms: np.ndarray) -> np.ndarray:
    """Joint positions after posing.

    Each bone's root and tip move with the bone; a joint shared by several bones
    gets the first bone's position (they agree for joints connecting a parent's
    tip to a child's root).

    Parameters
    ----------
    joints : (j, d) float64
    bones : (m, 2) int64
    transforms : (P, m, d, d+1) or (m, d, d+1) float64

    Returns
    -------
    joints : (P, j, d) or (j, d) float64
    """
    joints = np.asarray(joints, np.float64)
    single = transforms.ndim == 3
    T = transforms[None] if single else transforms
    out = np.broadcast_to(joints, (T.shape[0],) + joints.shape).copy()
    # tips first, then roots, so roots (which follow the parent) win for shared joints
    out[:, bones[:, 1]] = transform_points(T, joints[bones[:, 1]])
    out[:, bones[:, 0]] = transform_points(T, joints[bones[:, 0]])
    return out[0] if single else out


def lbs_matrix(vertices: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Linear blend skinning matrix ``M`` with ``V' = M T``.

    Parameters
    ----------
    vertices : (n, d) float64
        Rest positions.
    weights : (n, m) float64
        Skinning weights.

    Returns
    -------
    M : (n, m*(d+1)) float64
        ``M[i, j*(d+1) + c] = w_ij * [v_i, 1]_c``; pairs with
        :func:`stack_transforms`.
    """
    V = np.asarray(vertices, np.float64)
    W = np.asarray(weights, np.float64)
    Vh = np.column_stack([V, np.ones(len(V))])
    return (W[:, :, None] * Vh[:, None, :]).reshape(len(V), -1)


def stack_transforms(transforms: np.ndarray) -> np.ndarray:
    """Stack bone transforms into the ``T`` of ``V' = M T``.

    Parameters
    ----------
    transforms : (..., m, d, d+1) float64

    Returns
    -------
    T : (..., m*(d+1), d) float64
    """
    T = np.swapaxes(transforms, -1, -2)
    return T.reshape(T.shape[:-3] + (-1, T.shape[-1]))


#: An LBS matrix with fewer non-zeros than this share is kept sparse
#: (:func:`lbs_operator`). On 2 cores, 200 poses: the bunny (65 % non-zeros)
#: 24 ms sparse against 9 ms dense (one batched product), a non-zero of the
#: compiled sparse loop costing about 4x an entry of the dense product; a glTF
#: skin (2 %) 3-5 ms against 39-41 ms.
SPARSE_LBS = 0.25

#: A 3D surface whose skinning matrix would take more than this many bytes as an array is skinned from its
#: weights (:class:`~supportless.base.skinning.WeightBlocks`) and never builds the matrix: the bunny subdivided
#: twice (111 456 triangles, 20 MB) and the 68-bone character (33 MB) keep the matrix, sculpts of millions of
#: triangles (the bunny subdivided four times: 314 MB) do not.
LBS_MATRIX_BYTES = 128 * 2**20


def lbs_operator(vertices: np.ndarray, weights: np.ndarray):
    """The skinning matrix of :func:`lbs_matrix` in the form :func:`skin` runs fastest on.

    Parameters
    ----------
    vertices : (n, d) float64
    weights : (n, m) float64

    Returns
    -------
    M : (n, m*(d+1)) float64 array, or a scipy.sparse CSR matrix when fewer
        than :data:`SPARSE_LBS` of its entries are non-zero, or for a 3D
        surface whose matrix would exceed :data:`LBS_MATRIX_BYTES`, its
        :class:`~supportless.base.skinning.WeightBlocks` (posed to the same
        bits as the CSR matrix).
    """
    n, d = np.shape(vertices)
    if d == 3 and n * np.shape(weights)[1] * (d + 1) * 8 > LBS_MATRIX_BYTES:
        return weight_blocks(vertices, weights)
    M = lbs_matrix(vertices, weights)
    if np.count_nonzero(M) < SPARSE_LBS * M.size:
        from scipy.sparse import csr_matrix

        return csr_matrix(M)
    return M


@njit(nogil=True, cache=True)
def _skin_blocks3(start, bone, coef, T, out, lo, hi):  # pragma: no cover - compiled
    # per vertex, per bone of its row: the 4 coefficients against the bone's 4 rows of T (a planar rig's padded
    # with zeros), three named sums; the same additions in the same order as a loop over the CSR's non-zeros (a missing one adds 0.0), with one
    # index per bone instead of one per non-zero and the bone's rows of T read together
    # (the poses lo:hi)
    for p in range(lo, hi):
        Tp = T[p]
        for i in range(len(start) - 1):
            x = 0.0
            y = 0.0
            z = 0.0
            for k in range(start[i], start[i + 1]):
                j = 4 * bone[k]
                c0 = coef[k, 0]
                c1 = coef[k, 1]
                c2 = coef[k, 2]
                c3 = coef[k, 3]
                x += c0 * Tp[j, 0]
                y += c0 * Tp[j, 1]
                z += c0 * Tp[j, 2]
                x += c1 * Tp[j + 1, 0]
                y += c1 * Tp[j + 1, 1]
                z += c1 * Tp[j + 1, 2]
                x += c2 * Tp[j + 2, 0]
                y += c2 * Tp[j + 2, 1]
                z += c2 * Tp[j + 2, 2]
                x += c3 * Tp[j + 3, 0]
                y += c3 * Tp[j + 3, 1]
                z += c3 * Tp[j + 3, 2]
            out[p, i, 0] = x
            out[p, i, 1] = y
            out[p, i, 2] = z


def bone_blocks(M, stride: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A sparse LBS matrix as one block of ``stride`` coefficients per (vertex, bone) it couples.

    Parameters
    ----------
    M : scipy.sparse CSR matrix, (n, m*stride) float64
        From :func:`lbs_operator`: column ``stride*b + a`` holds the weight
        of bone ``b`` times coordinate ``a`` of the vertex (1 for the last).
    stride : int
        ``d + 1``.

    Returns
    -------
    start : (n + 1,) int64
        The blocks of vertex ``i`` are ``start[i]:start[i+1]``.
    bone : (q,) int64
        Bone of each block, increasing within a vertex.
    coef : (q, stride) float64
        The block's entries of ``M`` (0 where it has none).
    """
    M = M.tocsr()
    M.sort_indices()
    rows = np.repeat(np.arange(M.shape[0]), np.diff(M.indptr))
    bones = M.indices // stride
    key = rows.astype(np.int64) * (M.shape[1] // stride + 1) + bones
    first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    block = np.cumsum(np.r_[False, key[1:] != key[:-1]])
    coef = np.zeros((len(first), stride))
    coef[block, M.indices % stride] = M.data
    start = np.searchsorted(rows[first], np.arange(M.shape[0] + 1)).astype(np.int64)
    return start, bones[first].astype(np.int64), coef


def pruned_weights(weights: np.ndarray, floor: float) -> np.ndarray:
    """Skinning weights without their tail: entries below ``floor`` set to 0, each row rescaled to its old sum.

    Bounded biharmonic weights are positive far from their bone: a vertex of
    a 68-bone character carries 26 non-zero weights on average, 5 of them
    above 1e-4. Dropping the rest makes skinning that much cheaper and moves
    a posed vertex by at most about the dropped weight times how far the
    bones' transforms disagree there.

    Parameters
    ----------
    weights : (n, m) float64
    floor : float
        Each row keeps its largest entry whatever its size.

    Returns
    -------
    weights : (n, m) float64
    """
    W = np.asarray(weights, np.float64)
    kept = np.where((W >= floor) | (W == W.max(axis=1, keepdims=True)), W, 0.0)
    return kept * (W.sum(axis=1, keepdims=True) / kept.sum(axis=1, keepdims=True))


def skin(M, transforms: np.ndarray) -> np.ndarray:
    """Linear blend skinning of a batch of poses.

    Parameters
    ----------
    M : (n, m*(d+1)) float64 array, scipy.sparse CSR matrix or WeightBlocks
        From :func:`lbs_matrix` or :func:`lbs_operator`. Each kind is applied by a compiled loop, parallel over
        poses: a dense 3D one by :func:`~supportless.base.skinning.skin_dense`, a sparse one over its (vertex,
        bone) blocks (:func:`bone_blocks`), weight blocks by :func:`~supportless.base.skinning.skin_blocks`.
    transforms : (P, m, d, d+1) or (m, d, d+1) float64

    Returns
    -------
    vertices : (P, n, d) or (n, d) float64
    """
    T = stack_transforms(transforms)
    if isinstance(M, WeightBlocks):
        return skin_blocks(M, T[None])[0] if T.ndim == 2 else skin_blocks(M, T)
    if not hasattr(M, "indptr"):
        if T.shape[-1] != 3 or M.ndim != 2:
            return np.matmul(M, T)
        return skin_dense(M, T[None])[0] if T.ndim == 2 else skin_dense(M, T)
    single = T.ndim == 2
    T = T[None] if single else T
    d = T.shape[2]
    # the blocks are kept on the matrix (computed once; the LBS operators are never modified in place)
    # (a planar rig's blocks padded to 4 coefficients)
    blocks = getattr(M, "_supportless_bone_blocks", None)
    if blocks is None:
        start, bone, coef = bone_blocks(M, d + 1)
        blocks = M._supportless_bone_blocks = (start, bone, np.pad(coef, ((0, 0), (0, 3 - d))))
    if d < 3:  # a planar rig: T (m*3, 2) -> (m*4, 3) with a zero row per bone and a zero column, one kernel
        P, m = T.shape[0], T.shape[1] // (d + 1)
        T4 = np.zeros((P, m, 4, 3))
        T4[:, :, : d + 1, :d] = T.reshape(P, m, d + 1, d)
        T = T4.reshape(P, 4 * m, 3)
    out = np.empty((T.shape[0], M.shape[0], 3))
    T = np.ascontiguousarray(T, np.float64)
    over(_skin_blocks3, len(T), *blocks, T, out)
    out = out[..., :d] if d < 3 else out
    return out[0] if single else out
