"""Relaxed poses to start a search from: limbs let down toward gravity.

A figure modelled in a T-pose prints with its arms as two long overhangs; the
pose a person would give it to print standing lets them down, toward the
sides (an A-pose, or arms resting against the body). A particle swarm started
at the rest pose alone rarely walks that far through a landscape of
self-intersections, so the search starts some particles there
(:func:`relaxed_poses`):

* a rig whose bone names the anatomy tables know
  (:func:`supportless.search.anatomy.bone_parts`): each upper arm turned down
  by each of :data:`ARM_DROPS` degrees (never past hanging straight down),
  in the plane of the arm and gravity;
* a rig with no named arms: each **limb** (a free bone that leaves a
  junction of the skeleton, or a chain's first free bone below an anchored
  one) that is neither hanging nor rising (:data:`HANGING_DEGREES`,
  :data:`RISING_DEGREES`) turned toward gravity about its root joint by each
  share of :data:`LIMB_SHARES` of the angle between it and straight down.

Every seed is cut to the bone's joint limit, keeps the anchored bones (those
on the plate) where they are, and is mirror-symmetric for a symmetric rest
skeleton (each side turns toward its own down). The rest pose stays among the
particles (the search adds it); the symmetry, chain, anatomy and standing
rules judge the seeds like any other position.

Letting an arm down is no departure from a natural pose: :func:`arm_drops`
names each upper arm's way down (an axis and how far, to hanging straight),
and :func:`without_drop` takes that turn out of a rotation, so the pose prior
and the chain limit (:class:`supportless.search.objective.Objective`) judge
what the arm and the hand do besides coming down.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from dataclasses import dataclass

from ..base.kinematics import euler_to_matrix, matrix_to_euler
from ..base.rotations import matrix_to_quaternion
from ..rig.rig import Rig
from .anatomy import bone_parts

__all__ = ["ARM_DROPS", "LIMB_SHARES", "ArmDrops", "arm_drops", "arms_above", "limb_bones", "relaxed_poses",
           "without_drop"]

#: Degrees a named upper arm is turned down from its rest direction, one seed each (capped at hanging down).
ARM_DROPS = (30.0, 45.0, 60.0, 75.0)

#: Shares of the angle to straight down that every limb is turned by, one seed each.
LIMB_SHARES = (0.5, 0.8)

#: A limb already within this many degrees of straight down (a leg standing) is left as it is, and so is one
#: further than this from it (pointing up more than 45 degrees: a spine, a neck, an ear).
HANGING_DEGREES = 20.0
RISING_DEGREES = 135.0


@dataclass(frozen=True)
class ArmDrops:
    """The named upper arms of a rig and their way down.

    Attributes
    ----------
    bones : (k,) int64
        The upper arms.
    axes : (k, 3) float64
        Unit axis of each arm's turn toward straight down (rest direction x down).
    reach : (k,) float64
        How far, radians: the rest angle between the arm and straight down.
    """

    bones: np.ndarray
    axes: np.ndarray
    reach: np.ndarray


def arm_drops(rig: Rig) -> ArmDrops | None:
    """The :class:`ArmDrops` of a rig whose bone names the anatomy tables read as upper arms; None for other rigs
    (and a planar one)."""
    if rig.labels is None or rig.dim != 3:
        return None
    down = -np.asarray(rig.up, np.float64)
    bones, axes, reach = [], [], []
    for b, part in enumerate(bone_parts(rig.labels)):
        if part[0] != "upper_arm":
            continue
        root, tip = rig.joints[rig.bones[b]]
        d = tip - root
        axis = np.cross(d, down)
        if np.linalg.norm(d) <= 0 or np.linalg.norm(axis) < 1e-9 * np.linalg.norm(d):
            continue
        bones.append(b)
        axes.append(axis / np.linalg.norm(axis))
        reach.append(float(np.arccos(np.clip(d @ down / np.linalg.norm(d), -1.0, 1.0))))
    if not bones:
        return None
    return ArmDrops(np.array(bones, np.int64), np.array(axes), np.array(reach))


def without_drop(R: np.ndarray, axes: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Rotations with their turn down taken out: ``D^T R``, ``D`` the turn about ``axes`` nearest ``R`` (its twist
    about the axis) with its angle held in ``[0, reach]``.

    Parameters
    ----------
    R : (..., k, 3, 3) float64
    axes : (k, 3) float64
        Unit axes.
    reach : (k,) float64
        Radians.

    Returns
    -------
    rest : (..., k, 3, 3) float64
        The identity for a rotation that is only a turn down within reach.
    """
    R = np.asarray(R, np.float64)
    q = matrix_to_quaternion(R)  # x, y, z, w
    along = np.einsum("...ki,ki->...k", q[..., :3], axes)
    theta = 2.0 * np.arctan2(along, q[..., 3])
    theta = np.where(theta > np.pi, theta - 2 * np.pi, np.where(theta < -np.pi, theta + 2 * np.pi, theta))
    theta = np.clip(theta, 0.0, reach)
    D = Rotation.from_rotvec((axes * theta[..., None]).reshape(-1, 3)).as_matrix().reshape(R.shape)
    return np.swapaxes(D, -1, -2) @ R


def limb_bones(rig: Rig, free: np.ndarray) -> np.ndarray:
    """(k,) int64: the bones that start a limb: free bones whose parent in the kinematic tree is anchored, fixed
    or has more than one child (a junction: shoulders, hips, the root of a tail).

    Parameters
    ----------
    rig : Rig
    free : (m,) bool
        The bones the search may turn.
    """
    parents = rig.parents
    children = np.bincount(parents[parents >= 0], minlength=rig.bone_count)
    out = [b for b in range(rig.bone_count)
           if free[b] and (parents[b] < 0 or not free[parents[b]] or children[parents[b]] > 1)]
    return np.array(out, np.int64)


def _turn_down(rig: Rig, bone: int, degrees: float | None, share: float | None) -> np.ndarray | None:
    """(3, 3) float64: the world rotation about ``bone``'s root joint turning it toward straight down, by
    ``degrees`` or by ``share`` of its angle to straight down (never past it); None when it already hangs."""
    root, tip = rig.joints[rig.bones[bone]]
    d = tip - root
    if np.linalg.norm(d) <= 0:
        return None
    d = d / np.linalg.norm(d)
    down = -np.asarray(rig.up, np.float64)
    angle = float(np.degrees(np.arccos(np.clip(d @ down, -1.0, 1.0))))
    if angle < HANGING_DEGREES or angle > RISING_DEGREES:
        return None
    axis = np.cross(d, down)
    if np.linalg.norm(axis) < 1e-9:  # pointing straight up: no preferred side
        return None
    turn = min(angle, degrees) if degrees is not None else angle * float(share)
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * np.radians(turn)).as_matrix()


def _relative(rig: Rig, world: dict) -> np.ndarray:
    """(m, 3) float64 relative Euler angles of a pose given by the world rotations of some bones (the others
    follow their parents)."""
    m = rig.bone_count
    Q = np.tile(np.eye(3), (m, 1, 1))
    out = np.zeros((m, 3))
    for b in rig.order:
        p = rig.parents[b]
        parent = Q[p] if p >= 0 else np.eye(3)
        Q[b] = world.get(int(b), parent)
        out[b] = matrix_to_euler(parent.T @ Q[b])
    return out


def _within(rig: Rig, angles: np.ndarray, limits_deg: np.ndarray) -> np.ndarray:
    """``angles`` (m, 3) with each bone's rotation cut to its joint limit (a hair inside it)."""
    out = angles.copy()
    R = euler_to_matrix(angles)
    rotvec = Rotation.from_matrix(R).as_rotvec()
    size = np.linalg.norm(rotvec, axis=1)
    cap = np.radians(np.asarray(limits_deg, np.float64)) * 0.98
    over = size > cap
    if np.any(over):
        rotvec[over] *= (cap[over] / size[over])[:, None]
        out[over] = matrix_to_euler(Rotation.from_rotvec(rotvec[over]).as_matrix())
    return out


def relaxed_poses(rig: Rig, free: np.ndarray, limits_deg: np.ndarray) -> np.ndarray:
    """Poses with limbs let down toward gravity (module docstring), distinct, not the rest pose.

    Parameters
    ----------
    rig : Rig
    free : (m,) bool
        The bones the search turns (the others stay at rest).
    limits_deg : (m,) float64
        Each bone's joint limit, degrees.

    Returns
    -------
    angles : (s, m, 3) float64
        Relative Euler angles of each seed (``s`` may be 0: a 2D figure, or nothing to let down).
    """
    if rig.dim != 3:
        return np.zeros((0, rig.bone_count, 3))
    free = np.asarray(free, bool)
    seeds = []
    if rig.labels is not None:
        arms = [b for b, part in enumerate(bone_parts(rig.labels)) if part[0] == "upper_arm" and free[b]]
        for drop in ARM_DROPS if arms else ():
            world = {b: R for b in arms if (R := _turn_down(rig, b, drop, None)) is not None}
            if world:
                seeds.append(_relative(rig, world))
    limbs = limb_bones(rig, free) if not seeds else ()  # a named rig's arms say more than its shape
    for share in LIMB_SHARES if len(limbs) else ():
        world = {int(b): R for b in limbs if (R := _turn_down(rig, int(b), None, share)) is not None}
        if world:
            seeds.append(_relative(rig, world))
    if not seeds:
        return np.zeros((0, rig.bone_count, 3))
    out = np.stack([_within(rig, s, limits_deg) for s in seeds])
    out[:, ~free] = 0.0
    moved = np.abs(out).reshape(len(out), -1).max(axis=1) > 1e-9
    out = out[moved]
    return out[np.sort(np.unique(np.round(out.reshape(len(out), -1), 9), axis=0, return_index=True)[1])]


def arms_above(rig: Rig, ends: np.ndarray, drops: ArmDrops | None) -> np.ndarray:
    """(k,) int64: for each chain end, the index in ``drops`` of the named upper arm it hangs from in the
    kinematic tree, -1 for none."""
    out = np.full(len(ends), -1, np.int64)
    if drops is None:
        return out
    where = {int(b): i for i, b in enumerate(drops.bones)}
    for j, end in enumerate(ends):
        b = int(end)
        while b >= 0 and b not in where:
            b = int(rig.parents[b])
        out[j] = where.get(b, -1)
    return out
