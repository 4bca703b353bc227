"""Editing a pose: the angles and print rotation the page shows, the selected bone, undo and redo.

:class:`PoseEditing` is the part of :class:`~supportless.apps.ui.state.EditorState`
that changes the pose: whole poses, one bone's angles (the sliders), one bone's
rotation in the world (the gizmo), the print rotation, and steps back and
forth through :class:`~supportless.apps.ui.history.PoseHistory`. Each change is
announced as a ``"pose"`` (or ``"selection"``) event.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ...base.kinematics import matrix_to_euler

__all__ = ["PoseEditing"]


def _check_rotation(rotation, dim: int) -> np.ndarray:
    """``rotation`` as a (dim, dim) float64 rotation matrix; ValueError otherwise."""
    R = np.array(rotation, np.float64)
    if R.shape != (dim, dim) or not np.allclose(R @ R.T, np.eye(dim), atol=1e-6) or np.linalg.det(R) < 0:
        raise ValueError(f"the print rotation must be a {dim}x{dim} rotation matrix")
    return R


class PoseEditing:
    """The pose, its print rotation and the selected bone, edited with undo and redo.

    A mixin of :class:`~supportless.apps.ui.state.EditorState`, which sets what
    it works on: ``rig``, ``history`` (a
    :class:`~supportless.apps.ui.history.PoseHistory`), ``_lock`` (guards
    ``_angles`` and ``_rotation``), ``_angles`` ((m, 3) radians),
    ``_rotation`` ((d, d) the print rotation R), ``_selected`` (a bone) and
    ``_notify`` (tells the listeners).
    """

    def get_angles(self) -> np.ndarray:
        """A copy of the current pose.

        Returns
        -------
        angles : (m, 3) float64
            XYZ Euler angles per bone, radians.
        """
        with self._lock:
            return self._angles.copy()

    def get_rotation(self) -> np.ndarray:
        """A copy of the current print rotation R (the identity until a search turns the model).

        Returns
        -------
        rotation : (d, d) float64
            The pose is printed as ``vertices @ R.T``, then put on the plate.
        """
        with self._lock:
            return self._rotation.copy()

    def get_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The current pose and print rotation, read together (copies).

        Returns
        -------
        angles : (m, 3) float64
            Radians.
        rotation : (d, d) float64
            The print rotation R.
        """
        with self._lock:
            return self._angles.copy(), self._rotation.copy()

    @property
    def selected(self) -> int:
        """The bone the sliders and the gizmo act on (0-based)."""
        return self._selected

    def set_angles(self, angles, *, rotation=None, record: bool = True, key=None,
                   origin: str | None = None) -> None:
        """Replace the whole pose (the print rotation stays unless given).

        Parameters
        ----------
        angles : (m, 3) float64
            Radians.
        rotation : (d, d) float64, optional
            A new print rotation R (default: keep the current one).
        record : bool
            Make it an undo step.
        key : hashable, optional
            The control making the edit: edits of one control in a row are one
            undo step (see :class:`PoseHistory`).
        origin : str, optional
            Passed on to the listeners.

        Raises
        ------
        ValueError
            When ``angles`` is not one triple per bone, or ``rotation`` not a
            rotation of the rig's dimension.
        """
        angles = np.array(angles, np.float64)
        if angles.shape != self._angles.shape:
            raise ValueError(f"pose has shape {angles.shape}, the rig needs {self._angles.shape}")
        if not np.all(np.isfinite(angles)):
            raise ValueError("pose angles must be finite numbers")
        R = None if rotation is None else _check_rotation(rotation, self.rig.dim)
        with self._lock:
            if record:
                self.history.record((self._angles, self._rotation), key)
            self._angles = angles
            if R is not None:
                self._rotation = R
        self._notify("pose", origin=origin)

    def set_rotation(self, rotation, *, record: bool = True, origin: str | None = None) -> None:
        """Replace the print rotation R, keeping the angles (see :meth:`set_angles`).

        Parameters
        ----------
        rotation : (d, d) float64
        """
        with self._lock:
            angles = self._angles.copy()
        self.set_angles(angles, rotation=rotation, record=record, origin=origin)

    def set_bone_angles(self, bone: int, degrees, *, key=None, origin: str | None = None) -> None:
        """Set one bone's Euler angles.

        Parameters
        ----------
        bone : int
            0-based.
        degrees : (3,) float64
            XYZ Euler angles relative to the parent bone, degrees.
        key : hashable, optional
            Undo grouping (default: one step per call unless the same bone is
            edited again within a second).
        """
        bone = self._check_bone(bone)
        angles = self.get_angles()
        angles[bone] = np.radians(np.asarray(degrees, np.float64))
        self.set_angles(angles, key=("bone", bone) if key is None else key, origin=origin)

    def _check_bone(self, bone) -> int:
        """A 0-based bone index of the rig, or ValueError (a client may send anything)."""
        if isinstance(bone, bool) or not isinstance(bone, (int, np.integer)) or not 0 <= bone < self.rig.bone_count:
            raise ValueError(f"bone {bone!r} is not one of this rig's {self.rig.bone_count} bones")
        return int(bone)

    def set_bone_rotation(self, bone: int, rotation, *, record: bool = False, origin: str | None = "gizmo") -> None:
        """Turn a bone to a rotation given in world coordinates (what the gizmo shows).

        Parameters
        ----------
        bone : int
            0-based.
        rotation : (3, 3) float64
            The bone's rotation in the world; it becomes Euler angles relative
            to the parent bone. A planar rig keeps the angle about z.
        record : bool
            Make it an undo step (a drag records once, when it starts).
        """
        bone = self._check_bone(bone)
        R = np.asarray(rotation, np.float64)
        d = self.rig.dim
        if R.ndim != 2 or R.shape[0] != R.shape[1] or R.shape[0] < d or not np.all(np.isfinite(R)):
            raise ValueError("a bone's rotation must be a finite 3x3 matrix")
        angles = self.get_angles()
        parent = int(self.rig.parents[bone])
        local = R[:d, :d] if parent < 0 else self.rig.transforms(angles)[parent][:, :d].T @ R[:d, :d]
        angles[bone] = [0.0, 0.0, np.arctan2(local[1, 0], local[0, 0])] if d == 2 else matrix_to_euler(local)
        self.set_angles(angles, record=record, origin=origin)

    def select_bone(self, bone: int) -> None:
        """Select the bone the sliders and the gizmo act on (0-based).

        Raises
        ------
        ValueError
            For a bone number outside ``0..m-1``.
        """
        self._selected = self._check_bone(bone)
        self._notify("selection")

    def checkpoint(self) -> None:
        """Make the current pose an undo step (a drag calls it once, when it starts)."""
        with self._lock:
            self.history.record((self._angles, self._rotation))

    def _step(self, go: Callable[[tuple], tuple | None]) -> bool:
        with self._lock:
            pose = go((self._angles, self._rotation))
            if pose is None:
                return False
            self._angles, self._rotation = pose
        self._notify("pose", origin=None)
        return True

    def undo(self) -> bool:
        """Go back one edit; False when there is nothing to undo."""
        return self._step(self.history.undo)

    def redo(self) -> bool:
        """Redo the last undone edit; False when there is none."""
        return self._step(self.history.redo)

    def reset(self) -> None:
        """Back to the rest pose, printed as it stands (R = identity; undoable)."""
        self.set_angles(self.rig.rest_angles(), rotation=np.eye(self.rig.dim))
