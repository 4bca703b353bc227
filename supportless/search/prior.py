"""A natural-pose prior: how much of the body a pose turns, and how far each joint turns.

The distortion energy only sees the skin near joints: turning a whole head
54 degrees sideways costs almost nothing there, yet a person calls the pose
broken. :class:`PosePrior` adds what a person sees:

* each joint's rotation as one angle — the geodesic angle of its rotation
  relative to its parent, ``arccos((trace R - 1) / 2)``, not a box on three
  Euler angles — held under a limit per joint (:meth:`PosePrior.excess`);
* a cost ``sum_b c_b theta_b^2`` where ``c_b`` is the share of the body's
  volume bone ``b`` carries (its own region and everything hanging from it in
  the kinematic tree), so turning a torso or a head costs more than turning
  an ear or a tail tip by the same angle (:meth:`PosePrior.cost`).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from ..base.kinematics import euler_to_matrix, topological_order
from ..rig.rig import Rig
from .relaxed import ArmDrops, without_drop

__all__ = ["PosePrior", "joint_angles"]


def joint_angles(angles: np.ndarray, dim: int = 3) -> np.ndarray:
    """Geodesic rotation angle of each bone's relative rotation.

    Parameters
    ----------
    angles : (P, m, 3) or (m, 3) float64
        XYZ Euler angles, radians.
    dim : int
        2: only the angle about the plane normal (``[..., 2]``) counts.

    Returns
    -------
    theta : (P, m) or (m,) float64
        In [0, pi] radians.
    """
    angles = np.asarray(angles, np.float64)
    if dim == 2:
        return np.abs((angles[..., 2] + np.pi) % (2 * np.pi) - np.pi)
    R = euler_to_matrix(angles)
    cos = (np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.arccos(np.clip(cos, -1.0, 1.0))


class PosePrior:
    """Joint limits and the volume-weighted rotation cost of a rig's poses.

    Parameters
    ----------
    rig : Rig
    limits : (m,) float64
        Largest rotation of each joint, degrees.
    """

    def __init__(self, rig: Rig, limits: np.ndarray, drops: ArmDrops | None = None):
        self.rig = rig
        self.drops = drops
        self.limits = np.radians(np.asarray(limits, np.float64))
        if self.limits.shape != (rig.bone_count,):
            raise ValueError(f"limits must have one value per bone ({rig.bone_count}), not {self.limits.shape}")

    @cached_property
    def carried(self) -> np.ndarray:
        """(m,) float64: share of the body's volume each bone moves (itself and its subtree), in [0, 1]."""
        carried = self.rig.mass_moments[:, -1].copy()
        parents = self.rig.parents
        for b in topological_order(parents)[::-1]:  # children before parents
            if parents[b] >= 0:
                carried[parents[b]] += carried[b]
        return carried

    def angles(self, angles: np.ndarray) -> np.ndarray:
        """Joint rotation angles (radians), (P, m) or (m,) float64; see :func:`joint_angles`."""
        return joint_angles(angles, self.rig.dim)

    def cost(self, angles: np.ndarray) -> np.ndarray:
        """Volume-weighted rotation cost ``sum_b c_b theta_b^2``, (P,) float64 or float.

        A named upper arm's ``theta`` is what it turns besides letting itself down toward the body
        (:func:`~supportless.search.relaxed.without_drop`, with ``drops``): arms at the sides are no less
        natural than in a T.
        """
        theta = self.angles(angles)
        if self.drops is not None and self.rig.dim == 3:
            b = self.drops.bones
            R = euler_to_matrix(np.asarray(angles, np.float64)[..., b, :])
            rest = without_drop(R, self.drops.axes, self.drops.reach)
            theta = theta.copy()
            theta[..., b] = np.arccos(np.clip((np.trace(rest, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0))
        return theta ** 2 @ self.carried

    def excess(self, angles: np.ndarray) -> np.ndarray:
        """How far joints turn past their limits, summed (radians), (P,) float64 or float; 0 within them."""
        return np.maximum(0.0, self.angles(angles) - self.limits).sum(axis=-1)
