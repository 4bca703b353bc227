"""How natural a pose looks, in numbers: how far each chain's end turned, how far mirrored pairs differ.

A joint limit bounds each joint's own turn, but a chain of joints adds them
up: three neck joints at 30 degrees each bend a head 90 degrees into the
chest. :func:`world_turn_deg` is how far each bone turned in the world from
its rest direction (its rotation composed with every parent's), and
:func:`chain_ends` the bones that end a chain (a head, a hand, a tail tip),
whose turn is the one a person sees, and :func:`head_bones` the head among
them, which a person reads first and which gets a tighter bound of its own
(:attr:`supportless.search.settings.SearchSettings.head_limit`). :func:`mirror_error_deg` is how far a
pose is from symmetric, for a skeleton with a mirror plane
(:func:`supportless.search.layout.find_mirror`). :func:`naturalness` gathers
them for the report, so that a regression shows as a number.
"""

from __future__ import annotations

import numpy as np

from ..rig.rig import Rig
from .anatomy import bone_parts, joint_ranges
from .layout import Mirror, find_mirror

__all__ = ["HEAD_TOP_SHARE", "chain_ends", "head_bones", "mirror_error_deg", "naturalness", "rotation_angle_deg",
           "world_turn_deg"]

#: A head found from the skeleton's shape (:func:`head_bones`) ends the only chain reaching the top 15 % of
#: the rest skeleton's height, over at least two chains (legs) ending in its bottom 15 %.
HEAD_TOP_SHARE = 0.15


def rotation_angle_deg(R: np.ndarray) -> np.ndarray:
    """The angle of rotation matrices, degrees.

    Parameters
    ----------
    R : (..., d, d) float64
        Rotations, ``d`` in {2, 3}.

    Returns
    -------
    angle : (...) float64
        In ``[0, 180]``: ``arccos((trace R - 1) / 2)`` in 3D, ``|atan2(R10, R00)|`` in 2D.
    """
    R = np.asarray(R, np.float64)
    if R.shape[-1] == 2:
        return np.degrees(np.abs(np.arctan2(R[..., 1, 0], R[..., 0, 0])))
    c = (np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def chain_ends(rig: Rig) -> np.ndarray:
    """The bones no other bone hangs from (the ends of the skeleton's chains), (k,) int64."""
    parents = np.asarray(rig.parents)
    has_child = np.zeros(rig.bone_count, bool)
    has_child[parents[parents >= 0]] = True
    return np.flatnonzero(~has_child).astype(np.int64)


def head_bones(rig: Rig) -> np.ndarray:
    """The bones that are the skeleton's head, (k,) int64 (empty when none is clear).

    A bone whose name says head (:func:`supportless.search.anatomy.bone_parts`:
    Mixamo ``mixamorig:Head``, VRM and Unreal ``head``, VRoid ``J_Bip_C_Head``,
    Rigify ``DEF-spine.006``, Quaternius ``Head``, the Fox's ``b_Head_05``) is
    one, whatever hangs from it. A rig without such a name has a head when it
    stands upright: the chain end (:func:`chain_ends`) that reaches the top
    :data:`HEAD_TOP_SHARE` of the rest skeleton's height alone, pointing up
    (within 45 degrees), over at least two chain ends in its bottom share (the
    legs). A pair of arms or wings (bones off the mirror plane of a skeleton
    that has one, :func:`supportless.search.layout.find_mirror`) is no head and
    does not hide one. Otherwise none.
    """
    if rig.labels is not None:
        named = [b for b, part in enumerate(bone_parts(rig.labels)) if part[0] == "head"]
        if named:
            return np.array(named, np.int64)
    J, B, up = np.asarray(rig.joints, np.float64), np.asarray(rig.bones), np.asarray(rig.up, np.float64)
    h = J @ up
    span = float(np.ptp(h))
    ends = chain_ends(rig)
    if span <= 0 or len(ends) == 0:
        return np.zeros(0, np.int64)
    pivots = np.asarray(rig.pivots)
    far = np.where(B[:, 0] == pivots, B[:, 1], B[:, 0])  # each bone's joint away from the one it turns about
    mirror = find_mirror(rig) if rig.dim == 3 else None
    single = ends if mirror is None else ends[mirror.partner[ends] == ends]
    top = single[h[far[single]] >= h.max() - HEAD_TOP_SHARE * span]
    feet = ends[h[far[ends]] <= h.min() + HEAD_TOP_SHARE * span]
    if len(top) != 1 or len(feet) < 2:
        return np.zeros(0, np.int64)
    d = J[far[top[0]]] - J[pivots[top[0]]]
    if d @ up < np.cos(np.radians(45.0)) * np.linalg.norm(d):
        return np.zeros(0, np.int64)
    return top.astype(np.int64)


def world_turn_deg(rig: Rig, angles: np.ndarray) -> np.ndarray:
    """How far each bone turned in the world from rest, degrees.

    Parameters
    ----------
    rig : Rig
    angles : (P, m, 3) or (m, 3) float64
        Relative Euler angles per bone, radians.

    Returns
    -------
    turn : (P, m) or (m,) float64
        The angle of each bone's world rotation (the linear part of its
        skinning transform: its own rotation composed with its parents').
    """
    T = rig.transforms(np.asarray(angles, np.float64))
    d = rig.dim
    return rotation_angle_deg(T[..., :d, :d])


def mirror_error_deg(rig: Rig, angles: np.ndarray, mirror: Mirror) -> np.ndarray:
    """The largest difference between a left/right pair's world rotations and mirror images, degrees.

    Parameters
    ----------
    rig : Rig
        A 3D rig.
    angles : (P, m, 3) or (m, 3) float64
    mirror : Mirror
        Its mirror plane (:func:`supportless.search.layout.find_mirror`).

    Returns
    -------
    error : (P,) or () float64
        ``max`` over bones ``p`` of the angle of ``R_q^T S R_p S`` with ``q``
        the partner of ``p`` and ``S`` the reflection: 0 for a symmetric pose.
    """
    T = rig.transforms(np.asarray(angles, np.float64))
    R = T[..., :3, :3]
    S = mirror.reflection
    mirrored = S @ R @ S  # (..., m, 3, 3): the mirror image of each bone's rotation
    partner = R[..., np.asarray(mirror.partner), :, :]
    return rotation_angle_deg(np.swapaxes(partner, -1, -2) @ mirrored).max(axis=-1)


def naturalness(rig: Rig, angles: np.ndarray) -> dict:
    """The naturalness figures of one pose, JSON-ready.

    Parameters
    ----------
    rig : Rig
    angles : (m, 3) float64

    Returns
    -------
    figures : dict
        ``largest_chain_turn_deg`` and ``chain_end`` (the bone, 1-based, and
        its name when the rig has names): the chain end turned furthest from
        its rest direction; ``largest_joint_deg``: the largest single bone's
        world turn; ``mirror_error_deg``: the pose's distance from symmetric
        (None when the skeleton has no mirror plane, or in 2D); ``head_turn_deg``:
        the largest world turn of a head (:func:`head_bones`; None without
        one); ``joint_range``:
        the named joint nearest (or furthest past) its range of motion
        (:meth:`supportless.search.anatomy.JointRanges.usage`; None when no
        bone's name is one the tables know).
    """
    turn = world_turn_deg(rig, angles)
    ends = chain_ends(rig)
    end = int(ends[np.argmax(turn[ends])])
    heads = head_bones(rig)
    names = rig.bone_names() if rig.labels is not None else None
    mirror = find_mirror(rig) if rig.dim == 3 else None
    ranges = joint_ranges(rig)
    return {"joint_range": None if ranges is None else ranges.usage(rig.transforms(np.asarray(angles, np.float64))),
            "largest_chain_turn_deg": float(turn[end]), "chain_end": end + 1,
            "chain_end_name": names[end] if names else None, "largest_joint_deg": float(turn.max()),
            "head_turn_deg": float(turn[heads].max()) if len(heads) else None,
            "mirror_error_deg": None if mirror is None else float(mirror_error_deg(rig, angles, mirror))}
