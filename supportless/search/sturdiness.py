"""How strong a pose prints: :func:`~supportless.energies.strength.analyse_strength` of a rig posed and turned.

The body is analysed as it goes to the slicer: posed, turned, on the plate, +Z up, in millimetres at the printed
height (the rest pose's height along up, as the print frame scales it), each face following the bone with the
most skinning weight on it, the skeleton posed with it.
"""

from __future__ import annotations

import numpy as np

from ..base.geometry import print_pose
from ..base.isolated import NativeFailure, run_beside
from ..energies.materials import Material
from ..energies.strength import HANDLING_LOAD_N, Strength, analyse_strength
from ..files.printframe import rotation_to_z
from ..rig.rig import Rig

__all__ = ["face_bones", "pose_strength", "pose_strengths", "printed_body"]


def face_bones(rig: Rig) -> np.ndarray:
    """(f,) int64: the bone with the most skinning weight over each face's corners."""
    W = rig.weights
    if hasattr(W, "toarray"):
        W = W.toarray()
    return np.asarray(W)[rig.faces].sum(axis=1).argmax(axis=1)


def printed_body(rig: Rig, angles: np.ndarray, rotation: np.ndarray, height_mm: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The surface and skeleton of a pose as printed: +Z up, mm, the lowest point at z = 0.

    Parameters
    ----------
    rig : Rig
        3D.
    angles : (m, 3) float64
    rotation : (3, 3) float64
        The print rotation (:func:`~supportless.base.geometry.print_pose`).
    height_mm : float
        The rest pose's printed height along ``rig.up``.

    Returns
    -------
    vertices : (n, 3) float64
    joints : (j, 3) float64
    """
    up = np.asarray(rig.up, np.float64)
    posed = rig.pose(angles)
    joints = rig.posed_joints(angles)
    low = (posed @ up).min()
    placed, joints = posed - low * up, joints - low * up
    R = np.asarray(rotation, np.float64)
    printed = print_pose(placed, R, up)
    shift = printed[0] - placed[0] @ R.T
    joints = joints @ R.T + shift
    to_z = rotation_to_z(up) * (float(height_mm) / float(np.ptp(rig.vertices @ up)))
    return printed @ to_z.T, joints @ to_z.T


def pose_strength(rig: Rig, angles: np.ndarray, rotation: np.ndarray, height_mm: float,
                  material: Material | None = None, load_n: float = HANDLING_LOAD_N,
                  layer_mm: float = 0.2) -> Strength | None:
    """The strength of a pose as printed (:func:`~supportless.energies.strength.analyse_strength`); None in 2D.

    Parameters
    ----------
    rig : Rig
    angles : (m, 3) float64
    rotation : (3, 3) float64
    height_mm : float
    material : Material, optional
    load_n : float
        The grip at each chain end, N.
    layer_mm : float
        The printed layer's height, mm.
    """
    if rig.dim != 3:
        return None
    key = _key(angles, rotation, height_mm, material, load_n, layer_mm)
    cache = _strength_cache(rig)
    if key not in cache:
        V, J = printed_body(rig, angles, rotation, height_mm)
        _remember(cache, key, analyse_strength(V, rig.faces, J, rig.bones, face_bones(rig), material, load_n,
                                               layer_mm))
    return cache[key]


def pose_strengths(rig: Rig, poses: list, height_mm: float, material: Material | None = None,
                   load_n: float = HANDLING_LOAD_N, layer_mm: float = 0.2) -> list:
    """:func:`pose_strength` of several poses, the analyses not yet made shared between two processes: every other
    one in a forked child (:func:`~supportless.base.isolated.run_beside`), the others here meanwhile; should the
    child fail, every one is made here. The analysis is numpy's small steps on one core: two poses take the time of one.

    Parameters
    ----------
    rig : Rig
    poses : list of ((m, 3) float64, (3, 3) float64)
        Angles and print rotation of each pose.
    height_mm, material, load_n, layer_mm
        As :func:`pose_strength`.

    Returns
    -------
    strengths : list of Strength or None
    """
    if rig.dim != 3:
        return [None] * len(poses)
    cache = _strength_cache(rig)
    todo: dict = {}  # each analysis not yet made, once: key -> the first pose asking for it
    for i, (a, q) in enumerate(poses):
        key = _key(a, q, height_mm, material, load_n, layer_mm)
        if key not in cache:
            todo.setdefault(key, i)
    if len(todo) >= 2:
        keys = list(todo)
        bodies = [printed_body(rig, *poses[i], height_mm) for i in todo.values()]
        args = (rig.faces, rig.bones, face_bones(rig), material, load_n, layer_mm)
        try:
            theirs, mine = run_beside(_analyses, (bodies[1::2], *args), _analyses, (bodies[::2], *args),
                                      what="the strength analysis")
        except NativeFailure:  # the analyses not made are made here, one by one, below
            theirs, mine = [], []
        for key, strength in [*zip(keys[1::2], theirs), *zip(keys[::2], mine)]:
            _remember(cache, key, strength)
    return [pose_strength(rig, a, q, height_mm, material, load_n, layer_mm) for a, q in poses]


def _analyses(bodies, faces, bones, labels, material, load_n, layer_mm) -> list:
    """(one Strength per ``(vertices, joints)`` of ``bodies``, as printed)."""
    return [analyse_strength(V, faces, J, bones, labels, material, load_n, layer_mm) for V, J in bodies]


def _key(angles, rotation, height_mm, material, load_n, layer_mm) -> tuple:
    """A pose's analysis in the rig's cache, by its bytes and the analysis's settings."""
    return (np.asarray(angles, np.float64).tobytes(), np.asarray(rotation, np.float64).tobytes(), float(height_mm),
            material, float(load_n), float(layer_mm))


def _remember(cache: dict, key: tuple, strength: Strength) -> None:
    """Keep ``strength`` under ``key``, the oldest analysis dropped past :data:`STRENGTH_CACHE_SIZE`."""
    if key not in cache and len(cache) >= STRENGTH_CACHE_SIZE:
        cache.pop(next(iter(cache)))
    cache[key] = strength


#: Analyses kept per rig (:func:`pose_strength`): the choice's answers, the rest pose, the report's and the
#: pictures' ask again about the same poses.
STRENGTH_CACHE_SIZE = 32


def _strength_cache(rig: Rig) -> dict:
    """The rig's analyses by pose (insertion ordered: the oldest is dropped first). A rig is not modified after
    it is built, so its poses' analyses stay true for its lifetime."""
    cache = rig.__dict__.get("_strength_cache")
    if cache is None:
        cache = rig.__dict__["_strength_cache"] = {}
    return cache

