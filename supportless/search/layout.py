"""Left/right symmetry of a skeleton, and symmetric poses.

:func:`find_mirror` looks for a vertical mirror plane (one that contains the
printing direction) that maps the rest skeleton onto itself: every joint onto a
joint, every bone onto a bone. A bone mapped onto another is one of a
left/right pair; a bone mapped onto itself lies in the plane (a spine, a neck).

A pose is symmetric when each pair turns as mirror images, ``R_q = S R_p S``
with ``S = I - 2 n n^T`` the reflection, and each bone in the plane turns only
about the plane's normal ``n`` (nodding, not tilting sideways) — the only
rotations that equal their own mirror image. :class:`PoseLayout` maps the
search's variables (rotation vectors inside each joint's limit) to the Euler
angles of every bone, with or without symmetry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..base.errors import InputError
from ..base.kinematics import euler_to_matrix, matrix_to_euler
from ..rig.rig import Rig

__all__ = ["MIRROR_TOLERANCE", "Mirror", "PoseLayout", "find_mirror", "require_mirror"]

#: Joints whose mirror images land within this fraction of the model's height
#: of another joint count as a mirror pair. Hand-placed joints are not exact:
#: the shared bb-bunny's feet are 5.1 % of its height from mirror images.
MIRROR_TOLERANCE = 0.06


@dataclass(frozen=True)
class Mirror:
    """A mirror plane of a skeleton.

    Attributes
    ----------
    normal : (3,) float64
        Unit normal of the plane (orthogonal to up).
    point : (3,) float64
        A point on the plane.
    partner : (m,) int64
        The mirror image of each bone (itself for a bone in the plane).
    error : float
        Largest distance between a mirrored joint and its partner, as a
        fraction of the height.
    """

    normal: np.ndarray
    point: np.ndarray
    partner: np.ndarray
    error: float

    @property
    def reflection(self) -> np.ndarray:
        """(3, 3) float64: ``S = I - 2 n n^T``."""
        return np.eye(3) - 2.0 * np.outer(self.normal, self.normal)


def find_mirror(rig: Rig, tolerance: float = MIRROR_TOLERANCE, steps: int = 180) -> Mirror | None:
    """The vertical mirror plane of a rig's rest skeleton, if it has one.

    Parameters
    ----------
    rig : Rig
        A 3D rig.
    tolerance : float
        Largest joint mismatch, as a fraction of the height.
    steps : int
        Plane orientations tried (half a turn about ``up``).

    Returns
    -------
    mirror : Mirror or None
        None when no plane maps every joint onto a joint and every bone onto a bone.
    """
    if rig.dim != 3:
        return None
    J, up = rig.joints, rig.up
    height = float(np.ptp(rig.vertices @ up))
    helper = np.eye(3)[np.argmin(np.abs(up))]
    e1 = np.cross(helper, up)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    centre = rig.vertices.mean(axis=0)
    tree = cKDTree(J)
    best = None
    for a in np.linspace(0.0, np.pi, steps, endpoint=False):
        n = np.cos(a) * e1 + np.sin(a) * e2
        # the plane through the joints' mean along n, so off-centre skeletons are found too
        point = centre + ((J - centre) @ n).mean() * n
        image = J - 2.0 * ((J - point) @ n)[:, None] * n
        dist, match = tree.query(image)
        if best is None or dist.max() < best[0]:
            best = (float(dist.max()), n, point, match)
    error, n, point, match = best
    if error > tolerance * height:
        return None
    bones = {tuple(b): i for i, b in enumerate(rig.bones.tolist())}
    partner = np.empty(rig.bone_count, np.int64)
    for i, (r, t) in enumerate(rig.bones):
        j = bones.get((int(match[r]), int(match[t])))
        if j is None:
            return None
        partner[i] = j
    if not np.array_equal(partner[partner], np.arange(rig.bone_count)):
        return None
    return Mirror(n, point, partner, error / height)


class PoseLayout:
    """The search's variables and the pose they stand for.

    Each free bone's rotation is a rotation vector (axis times angle, radians)
    kept inside the ball of its joint limit: a variable vector longer than the
    limit stands for the rotation at the limit, so every point of the search
    box is a pose within the limits. In 2D a bone has one angle, about the
    plane normal. With a mirror, each left/right pair has the rotation vector
    of its first bone (the second mirrors it) and each bone in the plane one
    angle about the plane's normal.

    Parameters
    ----------
    rig : Rig
    fixed : (m,) bool
        Bones that keep their angles in ``base``. With a mirror, a pair is
        fixed when either of its bones is.
    base : (m, 3) float64
        Euler angles of the fixed bones.
    limits : (m,) float64
        Largest rotation of each bone, radians.
    mirror : Mirror, optional

    Attributes
    ----------
    count : int
        Number of variables.
    lower, upper : (count,) float64
        The search box.
    fixed : (m,) bool
    """

    def __init__(self, rig: Rig, fixed: np.ndarray, base: np.ndarray, limits: np.ndarray,
                 mirror: Mirror | None = None):
        self.base = np.asarray(base, np.float64)
        self.mirror = mirror
        self.limits = np.broadcast_to(np.asarray(limits, np.float64), (rig.bone_count,))
        self.dim = rig.dim
        fixed = np.asarray(fixed, bool).copy()
        m = rig.bone_count
        if mirror is not None:
            fixed |= fixed[mirror.partner]
            self.full = np.array([b for b in range(m) if not fixed[b] and mirror.partner[b] > b], np.int64)
            self.images = mirror.partner[self.full]
            self.turns = np.array([b for b in range(m) if not fixed[b] and mirror.partner[b] == b], np.int64)
            self.axis = mirror.normal
        else:
            free = np.flatnonzero(~fixed)
            self.full = free if rig.dim == 3 else np.zeros(0, np.int64)
            self.images = np.zeros(0, np.int64)
            self.turns = free if rig.dim == 2 else np.zeros(0, np.int64)
            self.axis = None
        self.fixed = fixed
        self.count = 3 * len(self.full) + len(self.turns)
        self.upper = np.concatenate([np.repeat(self.limits[self.full], 3), self.limits[self.turns]])
        self.lower = -self.upper

    def to_angles(self, X: np.ndarray) -> np.ndarray:
        """Euler angles of every bone, (P, m, 3) float64, from variables ``X`` (P, count)."""
        X = np.asarray(X, np.float64)
        P = len(X)
        A = np.repeat(self.base[None], P, axis=0)
        k = 3 * len(self.full)
        if len(self.full):
            v = X[:, :k].reshape(P, -1, 3)
            norm = np.linalg.norm(v, axis=2, keepdims=True)
            lim = self.limits[self.full][None, :, None]
            v = np.where(norm > lim, v * (lim / np.where(norm > 0, norm, 1.0)), v)
            R = Rotation.from_rotvec(v.reshape(-1, 3)).as_matrix().reshape(P, -1, 3, 3)
            A[:, self.full] = matrix_to_euler(R)
            if self.mirror is not None:
                S = self.mirror.reflection
                A[:, self.images] = matrix_to_euler(S @ R @ S)
        if len(self.turns):
            theta = np.clip(X[:, k:], -self.limits[self.turns], self.limits[self.turns])
            if self.axis is None:  # 2D: the angle about the plane normal
                A[:, self.turns] = 0.0
                A[:, self.turns, 2] = theta
            else:
                A[:, self.turns] = matrix_to_euler(_axis_rotation(self.axis, theta))
        return A

    def from_angles(self, angles: np.ndarray) -> np.ndarray:
        """Variables ``(count,)`` of a pose (its symmetric part, with a mirror)."""
        angles = np.asarray(angles, np.float64)
        full = Rotation.from_matrix(euler_to_matrix(angles[self.full])).as_rotvec().ravel() \
            if len(self.full) else np.zeros(0)
        if self.axis is None:
            turns = angles[self.turns, 2]
        else:
            R = euler_to_matrix(angles[self.turns])
            u = _any_orthogonal(self.axis)
            v = np.cross(self.axis, u)
            # the angle about the axis of each rotation: R u = cos t u + sin t v
            turns = np.arctan2(np.einsum("bij,i,j->b", R, v, u), np.einsum("bij,i,j->b", R, u, u))
        return np.concatenate([full, turns])


def _any_orthogonal(n: np.ndarray) -> np.ndarray:
    helper = np.eye(3)[np.argmin(np.abs(n))]
    u = np.cross(n, helper)
    return u / np.linalg.norm(u)


def _axis_rotation(n: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Rotations by ``theta`` (...,) radians about the unit axis ``n``, (..., 3, 3) float64."""
    K = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
    t = np.asarray(theta, np.float64)[..., None, None]
    return np.eye(3) + np.sin(t) * K + (1.0 - np.cos(t)) * (K @ K)


def require_mirror(rig: Rig) -> Mirror:
    """:func:`find_mirror`, or an InputError saying the skeleton has no left/right symmetry."""
    mirror = find_mirror(rig)
    if mirror is None:
        raise InputError(None, f"{rig.name}: the skeleton has no mirror plane through the printing direction "
                               f"(joints matched within {100 * MIRROR_TOLERANCE:g} % of the height); "
                               "search without --symmetric")
    return mirror
