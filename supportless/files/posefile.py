"""Pose files: a pose (Euler angles per bone), its print rotation and print frame, as JSON.

``optimize --pose`` writes one, ``apply`` and the browser app read it back. The
skeleton is stored with the angles, so a pose is never applied to another
skeleton; every reader raises :class:`~supportless.base.errors.InputError` with one
clear line on bad input.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..base.errors import InputError
from ..base.kinematics import bone_parents, reroot
from .meshes import _one_line, write_json

__all__ = ["POSE_FORMAT", "read_pose", "read_pose_print_frame", "read_print_rotation", "write_pose"]

POSE_FORMAT = "supportless-pose"


def write_pose(path: str | os.PathLike, angles: np.ndarray, bones: np.ndarray, joints: np.ndarray | None = None,
               extra: dict | None = None, rotation: np.ndarray | None = None,
               tree: tuple[np.ndarray, np.ndarray] | None = None) -> None:
    """Write a pose (Euler angles per bone) as JSON, atomically.

    Parameters
    ----------
    path : str or os.PathLike
    angles : (m, 3) float64
        Radians, XYZ Euler angles per bone (see :mod:`supportless.base.kinematics`).
    bones : (m, 2) int64
        The skeleton the pose belongs to (0-based), stored so a pose is never
        applied to another skeleton.
    joints : (j, d) float64, optional
        Stored for reference.
    extra : dict, optional
        More fields (e.g. the objective value).
    rotation : (d, d) float64, optional
        The print rotation R (the posed model is printed turned by R), stored
        as ``print_rotation``; read back with :func:`read_print_rotation`.
    tree : ((m,) int64, (m,) int64), optional
        The kinematic tree the angles are relative to, ``(parents, pivots)``
        (:attr:`supportless.rig.rig.Rig.parents` and ``pivots``), stored as
        ``tree`` (version 2) so the angles are never read against another tree.
    """
    angles = np.asarray(angles, np.float64)
    data = {
        "format": POSE_FORMAT,
        "version": 1 if tree is None else 2,
        "euler": "XYZ, radians, about each bone's root joint, relative to the parent bone" if tree is None else
                 "XYZ, radians, about each bone's pivot joint (tree.pivots, 0-based), relative to its parent bone "
                 "(tree.parents, 0-based, -1 for a root)",
        "bones": np.asarray(bones).tolist(),
        "angles": angles.tolist(),
        "angles_deg": np.degrees(angles).round(6).tolist(),
    }
    if tree is not None:
        data["tree"] = {"parents": np.asarray(tree[0], np.int64).tolist(),
                        "pivots": np.asarray(tree[1], np.int64).tolist()}
    if joints is not None:
        data["joints"] = np.asarray(joints).tolist()
    if rotation is not None:
        data["print_rotation"] = np.asarray(rotation, np.float64).tolist()
    if extra:
        data.update(extra)
    write_json(path, data)


def read_pose(path: str | os.PathLike, bones: np.ndarray | None = None,
              tree: tuple[np.ndarray, np.ndarray] | None = None, root_bone: int | None = None) -> np.ndarray:
    """Read a pose written by :func:`write_pose`.

    Parameters
    ----------
    path : str or os.PathLike
    bones : (m, 2) int64, optional
        The skeleton the pose must belong to.
    tree : ((m,) int64, (m,) int64), optional
        The rig's kinematic tree ``(parents, pivots)`` (:attr:`supportless.rig.rig.Rig.tree`):
        a file that records another tree is refused, and so is a file without
        one (version 1) unless the tree such files were written with
        (:func:`~supportless.base.kinematics.reroot` at ``root_bone``) is the same.
    root_bone : int, optional
        :attr:`supportless.rig.rig.Rig.root_bone`, with ``tree``.

    Returns
    -------
    angles : (m, 3) float64
        Radians.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    try:
        data = json.loads(path.read_text())
        angles = np.asarray(data["angles"], dtype=np.float64)
    except (ValueError, KeyError, TypeError, RecursionError, OverflowError) as exc:  # nested 100 000 deep, 1e400
        raise InputError(path, f"not a pose file (JSON with 'angles' and 'bones'): {_one_line(exc)}") from None
    if angles.ndim != 2 or angles.shape[1] != 3:
        raise InputError(path, f"'angles' must be a list of [x, y, z] per bone, got shape {angles.shape}")
    bad = np.flatnonzero(~np.isfinite(angles).all(axis=1))
    if len(bad):
        raise InputError(path, f"the angles of bone {bad[0] + 1} are not finite numbers ({len(bad)} such bones)")
    if bones is not None:
        bones = np.asarray(bones)
        if len(angles) != len(bones):
            raise InputError(path, f"pose is for a skeleton with {len(angles)} bones, not this one with "
                                   f"{len(bones)}; use the skeleton the pose was made with")
        try:
            stored = np.asarray(data.get("bones", []), dtype=np.int64)
        except (TypeError, ValueError, OverflowError, RecursionError):  # an index of 10**30
            raise InputError(path, "'bones' must be a list of [i, j] joint pairs") from None
        if stored.size and (stored.shape != bones.shape or np.any(stored != bones)):
            k = next((i for i in range(min(len(stored), len(bones))) if stored.ndim != 2
                      or not np.array_equal(stored[i], bones[i])), 0)
            have = stored[k].tolist() if stored.ndim == 2 and k < len(stored) else stored.tolist()
            raise InputError(path, f"pose is for another skeleton with as many bones: its bone {k + 1} joins "
                                   f"joints {have}, this skeleton's {bones[k].tolist()} (0-based); use the "
                                   f"skeleton the pose was made with")
    if tree is not None:
        tree_v1 = None if root_bone is None or bones is None else reroot(bones, bone_parents(bones), root_bone)
        _check_tree(path, data, tree, tree_v1)
    return angles


def read_print_rotation(path: str | os.PathLike, dim: int = 3) -> np.ndarray:
    """The print rotation stored in a pose file (the identity when there is none).

    Parameters
    ----------
    path : str or os.PathLike
        A pose file of :func:`write_pose`.
    dim : int
        The rig's dimension (2 or 3).

    Returns
    -------
    R : (dim, dim) float64

    Raises
    ------
    InputError
        When ``print_rotation`` is not a ``dim`` x ``dim`` rotation matrix.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError, RecursionError) as exc:
        raise InputError(path, f"not a pose file: {_one_line(exc)}") from None
    if "print_rotation" not in data:
        return np.eye(dim)
    try:
        R = np.asarray(data["print_rotation"], np.float64)
    except (ValueError, TypeError, OverflowError, RecursionError):
        R = np.zeros(0)
    if R.shape != (dim, dim) or not np.allclose(R @ R.T, np.eye(dim), atol=1e-6) or np.linalg.det(R) < 0:
        raise InputError(path, f"'print_rotation' must be a {dim}x{dim} rotation matrix (rows of numbers); "
                               "remove it to print the pose as it stands")
    return R


def read_pose_print_frame(path: str | os.PathLike) -> dict | None:
    """The print frame a pose file was written with (``print_frame``), or None when it has none.

    Parameters
    ----------
    path : str or os.PathLike
        A pose file of :func:`write_pose`.

    Returns
    -------
    frame : dict or None
        ``height_mm`` (float, positive) and ``how`` ("default", "height" or
        "units"), as :meth:`supportless.files.printframe.PrintFrame.to_dict` wrote them.

    Raises
    ------
    InputError
        When ``print_frame`` is there but not a frame.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError, RecursionError) as exc:
        raise InputError(path, f"not a pose file: {_one_line(exc)}") from None
    frame = data.get("print_frame") if isinstance(data, dict) else None
    if frame is None:
        return None
    try:
        height, how = float(frame["height_mm"]), str(frame["how"])
    except (KeyError, TypeError, ValueError):
        height, how = float("nan"), ""
    if not (np.isfinite(height) and height > 0) or how not in ("default", "height", "units"):
        raise InputError(path, "'print_frame' must hold a positive 'height_mm' and 'how' (default, height or "
                               "units); remove it to print at the default size")
    return {"height_mm": height, "how": how}


def _same_tree(a, b) -> bool:
    return all(np.array_equal(np.asarray(x, np.int64), np.asarray(y, np.int64)) for x, y in zip(a, b))


def _check_tree(path: Path, data: dict, tree, tree_v1) -> None:
    """InputError unless the pose's angles are relative to ``tree`` (see :func:`read_pose`)."""
    stored = data.get("tree")
    if stored is None:
        if tree_v1 is not None and _same_tree(tree_v1, tree):
            return
        raise InputError(path, "this pose was written before pose files recorded their kinematic tree, and this "
                               "skeleton's tree has changed since (bones that share a joint now keep it together): "
                               "its angles would give another pose; run optimize again for a pose of this rig")
    try:
        parents, pivots = (np.asarray(stored[k], np.int64) for k in ("parents", "pivots"))
    except (KeyError, TypeError, ValueError, OverflowError):
        raise InputError(path, "'tree' must hold 'parents' and 'pivots', one integer per bone") from None
    if parents.shape != np.shape(tree[0]) or not _same_tree((parents, pivots), tree):
        raise InputError(path, "the pose's angles are relative to another kinematic tree of this skeleton (another "
                               "bone rests on the plate, or another --up): run optimize again for this rig")
