"""Bones from a joint hierarchy: which joints to keep, which bone carries each joint's weight.

A rigged asset names joints (glTF nodes with a parent); the search rotates
bones (pairs of joints). :func:`skeleton_from_joints` makes the bones and moves
the skin weights from joints onto them. :func:`pull_joints_inside` moves
joints drawn on or just outside the skin inside it (bones are sampled into
the volume for bounded biharmonic weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.errors import InputError
from ..base.geometry import parse_up

__all__ = ["JOINT_INSIDE_MARGIN", "JOINT_OUTSIDE_TOLERANCE", "RigSkeleton", "TREE_FACES", "depth_below", "joint_order",
           "pull_joints_inside", "winding_numbers_of",
           "skeleton_from_joints"]

#: A joint outside the surface by at most this fraction of the model's height is
#: moved inside (:func:`pull_joints_inside`); farther out is an error. Real tips
#: (fingers, toes, the top of the head, a root joint on the floor) lie within
#: about 1 % of the skin; 3 % leaves room for coarse rigs while a skeleton in
#: other units or of another model is still refused.
JOINT_OUTSIDE_TOLERANCE = 0.03

#: How deep inside a moved joint is put, as a fraction of the model's height.
JOINT_INSIDE_MARGIN = 0.005

#: A joint carries weight when its total weight is above this fraction of the
#: total over all joints (one vertex in 10^7 with full weight).
WEIGHT_EPS = 1e-7

#: A weighted leaf's bone reaches this fraction of the way to the farthest
#: point of its skin (inside it, so bones can be sampled into a volume mesh).
LEAF_REACH = 0.9


# --------------------------------------------------------------------------- #
@dataclass
class RigSkeleton:
    """The bones derived from a joint hierarchy (:func:`skeleton_from_joints`).

    Attributes
    ----------
    joints : (k, 3) float64
        Kept joints, then one added tip per weighted leaf.
    bones : (m, 2) int64
        ``[root, tip]`` rows into ``joints``.
    names : list of str
        Per bone: the joint whose weight it carries, or ``"PARENT>CHILD"`` for a
        bone that carries none.
    weights : (n, m) float64
        The skin weights moved from joints to bones; rows sum to 1.
    joint_of : (k,) int64
        The skin joint (column of :attr:`GltfSkin.weights`) of each row of
        ``joints``, -1 for an added tip.
    driver : (J,) int64
        For every skin joint, the bone whose motion it follows when posed.
    pruned : list of str
        Names of the joints left out.
    """

    joints: np.ndarray
    bones: np.ndarray
    names: list
    weights: np.ndarray
    joint_of: np.ndarray
    driver: np.ndarray
    pruned: list


#: Sibling joints closer than this fraction of the model's size are one joint.
SAME_PLACE = 1e-6


def skeleton_from_joints(positions: np.ndarray, parents: np.ndarray, weights: np.ndarray, names: list,
                         vertices: np.ndarray) -> RigSkeleton:
    """Bones from a joint hierarchy and its skin weights.

    A bone per kept parent→child pair. Joints with no weight on them or below
    them are pruned (IK and pole targets, ``*_end`` tips); so is a chain of
    unweighted roots above the first joint that joins weighted parts (a
    ``_rootJoint`` on the floor). A weighted leaf gets a bone of its own,
    towards the centre of the skin it carries (along its parent's direction
    when that centre is at the joint), nearly as far as that skin reaches (:data:`LEAF_REACH`). Each
    joint's weight goes to the bone that starts at it and passes nearest the
    centre of its skin; a bone that starts at a joint but carries none of its
    weight (a hip's second child) carries no weight. Sibling joints at one
    place (a hand's palm joints, all at the wrist) are one joint: the later
    ones' weight and children go to the first, and their nodes follow its bone.

    Parameters
    ----------
    positions : (J, 3) float64
    parents : (J,) int64
        -1 for a root.
    weights : (n, J) float64
    names : list of str, length J
    vertices : (n, 3) float64

    Returns
    -------
    skeleton : RigSkeleton
    """
    P = np.asarray(positions, np.float64)
    parents = np.asarray(parents, np.int64)
    W = np.asarray(weights, np.float64)
    X = np.asarray(vertices, np.float64)
    nj = len(P)
    scale = float(np.ptp(X, axis=0).max()) if len(X) else 1.0
    parents, W, twin = _merge_coincident_siblings(P, parents, W, SAME_PLACE * scale)
    mass = W.sum(0)
    weighted = mass > WEIGHT_EPS * max(mass.sum(), 1e-300)
    children: list[list[int]] = [[] for _ in range(nj)]
    for j, p in enumerate(parents):
        if p >= 0:
            children[p].append(j)
    # kept: weighted, or with a weighted descendant (bottom-up)
    keep = weighted.copy()
    order = joint_order(parents)
    for j in order[::-1]:
        if parents[j] >= 0 and keep[j]:
            keep[parents[j]] = True
    # unweighted roots with a single kept child are dropped, repeatedly
    root = parents.copy()
    changed = True
    while changed:
        changed = False
        for j in range(nj):
            if keep[j] and not weighted[j] and (root[j] < 0 or not keep[root[j]]):
                kids = [c for c in children[j] if keep[c]]
                if len(kids) == 1:
                    keep[j] = False
                    changed = True
    kparent = np.array([p if p >= 0 and keep[p] else -1 for p in parents], np.int64)
    centres = np.zeros((nj, 3))
    for j in np.flatnonzero(weighted):
        centres[j] = W[:, j] @ X / mass[j]
    joints = [P[j] for j in range(nj)]
    joint_of = list(range(nj))
    bones, carrier = [], {}
    for j in order:
        if not keep[j]:
            continue
        kids = [c for c in children[j] if keep[c]]
        for c in kids:
            bones.append((j, c))
        if weighted[j]:
            if kids:
                seg = [_point_segment_distance(centres[j], P[j], P[c]) for c in kids]
                carrier[j] = len(bones) - len(kids) + int(np.argmin(seg))
            else:  # weighted leaf: a bone of its own, as far as its skin reaches
                direction = centres[j] - P[j]
                if np.linalg.norm(direction) < 0.02 * scale and kparent[j] >= 0:
                    direction = P[j] - P[kparent[j]]
                if np.linalg.norm(direction) < 1e-12 * scale:
                    direction = np.array([0.0, 1.0, 0.0])
                direction /= np.linalg.norm(direction)
                region = W[:, j] >= 0.5 * W[:, j].max()
                reach = float(np.max((X[region] - P[j]) @ direction)) if np.any(region) else 0.0
                length = max(LEAF_REACH * reach, 0.02 * scale)  # inside the skin, not on it
                joints.append(P[j] + length * direction)
                joint_of.append(-1)
                bones.append((j, len(joints) - 1))
                carrier[j] = len(bones) - 1
    B = np.asarray(bones, np.int64).reshape(-1, 2)
    if len(B) == 0:
        raise InputError(None, "the skeleton has no bone that carries weight")
    # renumber joints to the kept ones
    used = np.unique(B)
    remap = -np.ones(len(joints), np.int64)
    remap[used] = np.arange(len(used))
    Jout = np.asarray(joints)[used]
    Bout = remap[B]
    jof = np.asarray(joint_of, np.int64)[used]
    Wb = np.zeros((len(X), len(B)))
    for j, b in carrier.items():
        Wb[:, b] += W[:, j]
    s = Wb.sum(1, keepdims=True)
    Wb /= np.where(s > 0, s, 1.0)
    bone_names = []
    owner = {b: j for j, b in carrier.items()}
    for b, (a, c) in enumerate(B):
        if b in owner:
            bone_names.append(names[owner[b]])
        else:
            bone_names.append(f"{names[a]}>{names[c]}" if c < nj else f"{names[a]}>tip")
    # driver: a joint's own bone; joints without one follow their parent's
    driver = np.full(nj, -1, np.int64)
    incoming = {int(c): b for b, (a, c) in enumerate(B) if c < nj}
    for j in order:
        if j in carrier:
            driver[j] = carrier[j]
        elif j in incoming:
            driver[j] = incoming[j]
        elif parents[j] >= 0:
            driver[j] = driver[parents[j]]
    folded = np.flatnonzero(twin >= 0)
    driver[folded] = driver[twin[folded]]
    pruned = [names[j] for j in range(nj) if not keep[j] and twin[j] < 0]
    return RigSkeleton(Jout, Bout, bone_names, Wb, jof, driver, pruned)


def _merge_coincident_siblings(P, parents, W, tol):
    """Fold each joint into an earlier sibling at the same place (within ``tol``).

    Returns the parents with the folded joints' children moved to the sibling
    and the folded joints made roots of nothing, the weights with their
    columns added to the sibling's, and ``twin`` (J,) int64: the sibling a
    joint was folded into, -1 for the others.
    """
    parents = parents.copy()
    W = W.copy()
    twin = np.full(len(P), -1, np.int64)
    for j in range(len(P)):
        p = parents[j]
        if p < 0:
            continue
        same = [s for s in range(j) if parents[s] == p and twin[s] < 0 and np.linalg.norm(P[s] - P[j]) <= tol]
        if not same:
            continue
        s = same[0]
        twin[j] = s
        W[:, s] += W[:, j]
        W[:, j] = 0.0
        parents[parents == j] = s
    # the folded joints leave the tree (no weight, no children, no parent)
    parents[twin >= 0] = -1
    return parents, W, twin


def joint_order(parents: np.ndarray) -> np.ndarray:
    """Joints with parents before children."""
    depth = np.zeros(len(parents), np.int64)
    for j in range(len(parents)):
        d, p = 0, parents[j]
        while p >= 0:
            d, p = d + 1, parents[p]
        depth[j] = d
    return np.argsort(depth, kind="stable")


def _point_segment_distance(x, a, b) -> float:
    ab = b - a
    t = np.clip((x - a) @ ab / max(ab @ ab, 1e-300), 0.0, 1.0)
    return float(np.linalg.norm(x - (a + t * ab)))


#: Past this many triangles the depth of points below a surface is its distance (one AABB tree for every
#: query) signed by the fast winding number; below, libigl's signed distance with the exact winding number
#: (on the 1.8M-triangle bunny it took 23 s for the twelve joints alone, each call anew).
TREE_FACES = 250_000


def depth_below(V: np.ndarray, F: np.ndarray):
    """``depth(points)``: how deep points lie below a closed surface, negative outside.

    Parameters
    ----------
    V : (n, 3) float64
    F : (f, 3) int64
        Closed, outward-oriented.

    Returns
    -------
    depth : callable
        ``depth(points (p, 3) float64) -> (p,) float64``: the distance to the surface, positive where the
        winding number is over 1/2 (exact winding number up to :data:`TREE_FACES` triangles, libigl's fast
        one past them, with the distance tree built once).
    """
    import igl

    V = np.ascontiguousarray(V, np.float64)
    F = np.ascontiguousarray(F, np.int64)
    if len(F) <= TREE_FACES:
        return lambda P: -np.asarray(igl.signed_distance(np.ascontiguousarray(P, np.float64), V, F,
                                                         igl.SIGNED_DISTANCE_TYPE_WINDING_NUMBER)[0])
    tree = igl.AABB()
    tree.init(V, F)
    winding = winding_numbers_of(V, F)

    def depth(P):
        P = np.ascontiguousarray(P, np.float64)
        distance = np.sqrt(np.asarray(tree.squared_distance(V, F, P)[0]))
        return np.where(winding(P) > 0.5, distance, -distance)
    return depth


def winding_numbers_of(V: np.ndarray, F: np.ndarray):
    """libigl's fast winding number of a surface with its tree built once (``igl.fast_winding_number(V, F, P)``
    builds it again at every call: a second on 1.8 million triangles); the same values.

    Parameters
    ----------
    V : (n, 3) float64
    F : (f, 3) int64

    Returns
    -------
    winding : callable
        ``winding(points (p, 3) float64) -> (p,) float64``.
    """
    import igl

    tree = igl.FastWindingNumberBVH()
    tree.init(np.ascontiguousarray(V, np.float64), np.ascontiguousarray(F, np.int64))
    return lambda P: np.asarray(tree.winding_number(np.ascontiguousarray(np.atleast_2d(P), np.float64)))


def pull_joints_inside(V: np.ndarray, F: np.ndarray, joints: np.ndarray, bones: np.ndarray, up,
                       path=None, tolerance: float = JOINT_OUTSIDE_TOLERANCE,
                       within: float = 0.0, reach: float = 0.5) -> tuple[np.ndarray, list[str]]:
    """Move joints that lie just outside a closed surface inside it, along one of their bones.

    Real skeletons put tips (fingertips, toe tips, the top of the head, a root
    joint on the floor) on or just outside the skin. A joint outside by at most
    :data:`JOINT_OUTSIDE_TOLERANCE` of the model's height is moved along the
    bone towards its deepest neighbouring joint, to the first point that lies
    :data:`JOINT_INSIDE_MARGIN` of the height inside (or, on a part thinner
    than that, to the deepest point of the bone's first half). Farther outside
    is an error: such a skeleton belongs to another model or other units.

    Parameters
    ----------
    V : (n, 3) float64
        Closed, outward-oriented surface.
    F : (f, 3) int64
    joints : (j, 3) float64
    bones : (m, 2) int64
    up : str or (3,) float
        Printing direction (the height is measured along it).
    path : str or os.PathLike, optional
        The skeleton file, named in errors.
    tolerance : float
        How far outside a joint may be (fraction of the height) to be moved.
    within : float
        Also move joints less than this deep inside (fraction of the height):
        a glTF rig's joints on the skin, for bones sampled into the volume.
    reach : float
        How far along the bone (share of its length) a joint may move when the bone's first half lies
        outside: the first half is searched first, as always; a larger ``reach`` then searches on to it.
        A simplified proxy thins a fingertip so its bone enters it only past the middle
        (:data:`supportless.rig.rig.PROXY_JOINT_REACH`).

    Returns
    -------
    joints : (j, 3) float64
        A copy with the moved joints.
    warnings : list of str
        One line per moved joint: which joint, how far outside it was, where it went.

    Raises
    ------
    InputError
        A joint farther outside than the tolerance, or one that cannot be
        moved inside along any of its bones.
    """
    joints = np.array(joints, np.float64)
    height = float(np.ptp(V @ parse_up(up)))
    if height <= 0:
        height = float(np.ptp(V, axis=0).max())
    depth_of = depth_below(V, F)
    depth = depth_of(joints)
    outside = np.flatnonzero(depth < within * height)
    far = outside[-depth[outside] > tolerance * height]
    if len(far):
        i = int(far[np.argmin(depth[far])])
        raise InputError(path, f"joint {i + 1} at {np.round(joints[i], 6).tolist()} lies "
                         f"{100 * -depth[i] / height:.1f} % of the model's height outside the surface "
                         f"({len(far)} joints farther out than {100 * tolerance:g} %); "
                         "check the skeleton belongs to this model and uses the same units")
    warnings = []
    margin = JOINT_INSIDE_MARGIN * height
    # the bone's first half, then (with a longer reach, where the first half is outside) on to the reach
    spans = [np.linspace(0.0, 0.5, 51)[1:]] + ([np.linspace(0.5, reach, 2 + round(100 * (reach - 0.5)))[1:]]
                                               if reach > 0.5 else [])
    for i in outside[np.argsort(depth[outside])[::-1]]:  # nearest the skin first
        incident = np.flatnonzero((bones == i).any(axis=1))
        if len(incident) == 0:
            continue  # a joint no bone uses does not move anything
        others = np.where(bones[incident, 0] == i, bones[incident, 1], bones[incident, 0])
        k = int(np.argmax(depth[others]))
        a, b = joints[i], joints[others[k]]
        for t in spans:
            points = a + t[:, None] * (b - a)
            d = depth_of(points)
            deep = np.flatnonzero(d >= margin)
            s = int(deep[0]) if len(deep) else int(np.argmax(d))
            if d[s] > 0:
                break
        if d[s] <= 0:
            raise InputError(path, f"joint {i + 1} lies {100 * -depth[i] / height:.2f} % of the model's height "
                             f"outside the surface and bone {incident[k] + 1} does not enter it; "
                             "move the joint inside")
        warnings.append(f"joint {i + 1} lay {100 * -depth[i] / height:.2f} % of the model's height outside the "
                        f"surface; moved {np.linalg.norm(points[s] - a):.3g} along bone {incident[k] + 1} to lie "
                        "inside")
        joints[i] = points[s]
        depth[i] = d[s]
    return joints, warnings
