"""Left/right symmetry of a skeleton, and symmetric poses.

:func:`find_mirror` looks for a vertical mirror plane (one that contains the
printing direction) that maps the rest skeleton onto itself: every joint onto a
joint, every bone onto a bone. A bone mapped onto another is one of a
left/right pair; a bone mapped onto itself lies in the plane (a spine, a neck).

A pose is symmetric when each pair turns as mirror images, ``R_q = S R_p S``
with ``S = I - 2 n n^T`` the reflection, and each bone in the plane turns only
about the plane's normal ``n`` (nodding, not tilting sideways) — the only
rotations that equal their own mirror image. :class:`PoseLayout` maps the
search's variables to the Euler angles of every bone, with or without symmetry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .errors import InputError
from .kinematics import euler_to_matrix, matrix_to_euler
from .rig import Rig

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

    Without a mirror every free bone has its three Euler angles (one, about
    the plane normal, in 2D). With a mirror, each left/right pair has the three
    angles of its first bone (the second mirrors it) and each bone in the plane
    one angle about the plane's normal.

    Parameters
    ----------
    rig : Rig
    fixed : (m,) bool
        Bones that keep their angles in ``base``. With a mirror, a pair is
        fixed when either of its bones is.
    base : (m, 3) float64
        Angles of the fixed bones (and of everything at ``X = 0`` without a mirror).
    mirror : Mirror, optional
    """

    def __init__(self, rig: Rig, fixed: np.ndarray, base: np.ndarray, mirror: Mirror | None = None):
        self.base = np.asarray(base, np.float64)
        self.mirror = mirror
        fixed = np.asarray(fixed, bool).copy()
        if mirror is not None:
            fixed |= fixed[mirror.partner]
            m = rig.bone_count
            self.pairs = np.array([b for b in range(m) if not fixed[b] and mirror.partner[b] > b], np.int64)
            self.images = mirror.partner[self.pairs]
            self.central = np.array([b for b in range(m) if not fixed[b] and mirror.partner[b] == b], np.int64)
            self.count = 3 * len(self.pairs) + len(self.central)
        else:
            self.free = np.zeros((rig.bone_count, 3), bool)
            if rig.dim == 2:
                self.free[~fixed, 2] = True
            else:
                self.free[~fixed] = True
            self.count = int(self.free.sum())
        self.fixed = fixed

    def to_angles(self, X: np.ndarray) -> np.ndarray:
        """Euler angles of every bone, (P, m, 3) float64, from variables ``X`` (P, count)."""
        X = np.asarray(X, np.float64)
        A = np.repeat(self.base[None], len(X), axis=0)
        if self.mirror is None:
            A[:, self.free] = X
            return A
        k = 3 * len(self.pairs)
        if len(self.pairs):
            own = X[:, :k].reshape(len(X), -1, 3)
            A[:, self.pairs] = own
            S = self.mirror.reflection
            A[:, self.images] = matrix_to_euler(S @ euler_to_matrix(own) @ S)
        if len(self.central):
            A[:, self.central] = matrix_to_euler(_axis_rotation(self.mirror.normal, X[:, k:]))
        return A

    def from_angles(self, angles: np.ndarray) -> np.ndarray:
        """Variables ``(count,)`` of a pose (its symmetric part, with a mirror)."""
        angles = np.asarray(angles, np.float64)
        if self.mirror is None:
            return angles[self.free]
        R = euler_to_matrix(angles[self.central])
        n = self.mirror.normal
        # the angle about n of each central bone's rotation: from its antisymmetric part
        theta = np.arctan2(np.einsum("bij,i,j->b", R, np.cross(n, _any_orthogonal(n)), _any_orthogonal(n)),
                           np.einsum("bij,i,j->b", R, _any_orthogonal(n), _any_orthogonal(n)))
        return np.concatenate([angles[self.pairs].ravel(), theta])


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
