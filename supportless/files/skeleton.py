"""Checks of a skeleton's graph: a tree of bones with length.

Forward kinematics walks each bone's parents to a root; a cycle would make
that walk endless, two bones into one joint would make the parent ambiguous,
and a bone of zero length (or two bones' joints at one place) leaves the
skinning weights' boundary conditions without a cause to report. Every
reader of skeletons and every rig built from arrays calls :func:`check_skeleton`.
"""

from __future__ import annotations

import os

import numpy as np

from ..base.errors import InputError

__all__ = ["check_skeleton"]


def check_skeleton(joints: np.ndarray, bones: np.ndarray, path: str | os.PathLike | None = None) -> None:
    """Refuse a skeleton that is not a tree of bones with length.

    Parameters
    ----------
    joints : (j, d) float64
        Joint positions.
    bones : (m, 2) int64
        0-based ``[root, tip]`` joint indices, in range.
    path : str or os.PathLike, optional
        The skeleton's file, for the message.

    Raises
    ------
    InputError
        One line naming the bones or joints (1-based, as in a TGF file) at
        fault: a bone listed twice, a joint at the tip of two bones, a cycle
        of bones, a bone of zero length, or two joints of bones at one place.
    """
    J = np.asarray(joints, np.float64)
    B = np.asarray(bones, np.int64)
    seen: dict[tuple[int, int], int] = {}
    for k, (a, b) in enumerate(B.tolist()):
        key = (min(a, b), max(a, b))
        if key in seen:
            raise InputError(path, f"bones {seen[key] + 1} and {k + 1} both join joints {a + 1} and {b + 1}; "
                                   f"list each bone once")
        seen[key] = k
    parent_bone = {}
    for k, tip in enumerate(B[:, 1].tolist()):
        if tip in parent_bone:
            raise InputError(path, f"joint {tip + 1} is the tip of bones {parent_bone[tip] + 1} and {k + 1}; a "
                                   f"skeleton is a tree: each joint ends at most one bone (write bones root -> tip)")
        parent_bone[tip] = k
    # every joint has at most one bone into it: following parents from any bone ends at a root or runs in a cycle
    for k in range(len(B)):
        path_bones, j = [k], int(B[k, 0])
        while j in parent_bone:
            p = parent_bone[j]
            if p == k:
                names = " -> ".join(str(b + 1) for b in reversed(path_bones))
                raise InputError(path, f"bones {names} form a cycle; a skeleton is a tree with a root")
            if len(path_bones) > len(B):
                break  # a cycle further up, found when its own bones are visited
            path_bones.append(p)
            j = int(B[p, 0])
    used = np.unique(B)
    size = float(np.ptp(J[used], axis=0).max()) if len(used) else 0.0
    tol = 1e-9 * max(size, np.finfo(float).tiny)
    lengths = np.linalg.norm(J[B[:, 1]] - J[B[:, 0]], axis=1)
    short = np.flatnonzero(lengths <= tol)
    if len(short):
        k = int(short[0])
        raise InputError(path, f"bone {k + 1} has zero length: joints {B[k, 0] + 1} and {B[k, 1] + 1} are at the "
                               f"same place; move or remove one")
    P = J[used]
    order = np.lexsort(P.T[::-1])
    same = np.flatnonzero(np.all(np.abs(np.diff(P[order], axis=0)) <= tol, axis=1))
    if len(same):
        a, b = sorted((int(used[order[same[0]]]), int(used[order[same[0] + 1]])))
        raise InputError(path, f"joints {a + 1} and {b + 1} are at the same place {np.round(J[a], 6).tolist()}; "
                               f"bones that share a point must share the joint")
