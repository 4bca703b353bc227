"""A rig's volume mesh posed and placed as the figure is printed, for the finite-element strength reference.

The tetrahedra the rig was weighted on (:attr:`~supportless.rig.rig.Rig.tet_vertices`,
:attr:`~supportless.rig.rig.Rig.tets`) are posed by the same forward kinematics and linear blend skinning as
the surface (:meth:`~supportless.rig.rig.Rig.transforms`, :func:`~supportless.base.kinematics.skin`), turned
by the print rotation and put on the plate (:func:`~supportless.base.geometry.print_pose`), then mapped to the
print frame (:class:`~supportless.files.printframe.PrintFrame`: ``up`` to +Z, the rest pose ``height_mm`` tall
along ``up``, x/y centred on 0, lowest point at z = 0). Every placement is taken from the surface (the first
``len(rig.vertices)`` volume vertices), so those rows are exactly the printed surface; the solver of
:mod:`supportless.energies.strength_fem` takes the result. (It lives in the rig stage: the energies take arrays,
never a rig.)
"""

from __future__ import annotations

import numpy as np

from ..base import kinematics as kin
from ..base.geometry import print_transform
from ..files.printframe import print_frame, rotation_to_z

__all__ = ["posed_tet_mesh"]


def posed_tet_mesh(rig, angles, rotation=None, height_mm: float = 60.0) -> tuple[np.ndarray, np.ndarray]:
    """A rig's tetrahedra posed, turned to print and placed in the print frame.

    Parameters
    ----------
    rig : supportless.rig.rig.Rig
        A 3D rig.
    angles : (m, 3) float64
        Relative XYZ Euler angles per bone, radians (zeros: the rest pose).
    rotation : (3, 3) float64, optional
        The print rotation R (``PoseResult.rotation``); None: the identity (printed as it stands).
    height_mm : float
        The printed height of the rest pose along ``rig.up``, mm (the print frame's scale).

    Returns
    -------
    nodes : (t, 3) float64
        In the print frame: mm, +Z up, the surface's lowest point at z = 0 and its x/y box centred on 0. The
        first ``len(rig.vertices)`` rows equal ``frame.place(print_pose(rig.pose(angles), R, rig.up))``.
    tets : (k, 4) int64
        ``rig.tets``.

    Raises
    ------
    ValueError
        For a planar (2D) rig.
    """
    if rig.dim != 3:
        raise ValueError("a planar figure has no tetrahedra: posed_tet_mesh needs a 3D rig")
    n = len(rig.vertices)
    T = rig.transforms(np.asarray(angles, np.float64))
    inner = kin.skin(kin.lbs_operator(rig.tet_vertices[n:], rig.tet_weights[n:]), T)
    posed = np.concatenate([rig.pose(angles), inner])  # the surface exactly as Rig.pose gives it
    R = np.eye(3) if rotation is None else np.asarray(rotation, np.float64)
    turned = posed @ R.T + print_transform(posed[:n], R, rig.up)
    frame = print_frame(rig.vertices, rig.up, height_mm)
    scaled = (turned @ rotation_to_z(frame.up).T) * frame.scale
    lo, hi = scaled[:n].min(axis=0), scaled[:n].max(axis=0)
    nodes = scaled - np.array([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), lo[2]])
    return nodes, np.asarray(rig.tets, np.int64)
