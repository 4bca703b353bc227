"""Rigged glTF/GLB characters: the print body and bones from the skin, and the posed asset out.

:func:`~supportless.files.gltf_skin.read_gltf_skin` reads the skin in its rest
pose, every joint posed by its whole ancestry (:mod:`supportless.files.gltf_skin`);
:func:`load_gltf_character` makes the print body and the bones from it
(:func:`~supportless.files.joints.skeleton_from_joints` turns the joint
hierarchy into the bones the search rotates), and :func:`write_posed_gltf`
writes the original asset with a pose set on its joint nodes (compressed
primitives stay compressed).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..base.errors import InputError
from .gltf_skin import (GltfSkin, load_document, node_local, node_parents, read_accessor, read_gltf_skin,
                        read_rest_triangles, skin_of)
from .joints import joint_order

__all__ = ["GLTF_SUFFIXES", "GltfSkin", "is_gltf", "load_gltf_character", "posed_joint_transforms", "read_accessor",
           "read_gltf_skin", "read_rest_triangles", "write_posed_gltf"]

GLTF_SUFFIXES = (".glb", ".gltf")

#: glTF lengths are metres; the print body is in millimetres.
METRES_TO_MM = 1000.0


def is_gltf(path) -> bool:
    """Whether a path names a glTF asset (``.glb`` or ``.gltf``)."""
    return Path(path).suffix.lower() in GLTF_SUFFIXES


def _matrix_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w) of a rotation matrix (3, 3)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_quat()


# --------------------------------------------------------------------------- #
# the character to prepare
# --------------------------------------------------------------------------- #
def load_gltf_character(path, progress=None):
    """The print body, bones and skin weights of a rigged glTF/GLB asset.

    Reads the skin in its rest pose (:func:`~supportless.files.gltf_skin.read_gltf_skin`),
    makes the closed print body from all its parts with the weights carried
    along (:func:`~supportless.files.printbody.print_body`), derives the bones from
    the joints (:func:`~supportless.files.joints.skeleton_from_joints`) and converts
    the file's metres to millimetres.

    Parameters
    ----------
    path : str or os.PathLike
    progress : callable(str), optional

    Returns
    -------
    V : (n, 3) float64
        Print body, millimetres, +Y up.
    F : (f, 3) int64
    J : (j, 3) float64
    B : (m, 2) int64
    W : (n, m) float64
        Skin weights per bone, rows summing to 1.
    labels : list of str
        Bone names after the joints.
    source : dict
        ``path``, ``scale`` (file units to the rig's), ``joint_nodes``,
        ``driver`` (bone each skin joint follows) and ``log`` (one line per
        step), for writing the posed asset and for the report.
    """
    from .joints import skeleton_from_joints
    from .printbody import print_body

    say = progress or (lambda msg: None)
    say("reading the glTF skin")
    skin = read_gltf_skin(path)
    say("making the print body")
    try:
        body = print_body(skin.vertices, skin.faces, skin.part, skin.weights, skin.part_names)
    except InputError as exc:
        raise InputError(path, exc.reason) from None
    try:
        sk = skeleton_from_joints(skin.joint_positions, skin.joint_parents, body.values, skin.joint_names,
                                  body.vertices)
    except InputError as exc:
        raise InputError(path, exc.reason) from None
    log = list(skin.notes) + list(body.log)
    kept = len(skin.joint_names) - len(sk.pruned)
    log.append(f"skeleton: {len(sk.bones)} bones from {kept} of {len(skin.joint_names)} joints"
               + (f"; pruned {len(sk.pruned)} without weight: {', '.join(sk.pruned[:12])}"
                  + (" ..." if len(sk.pruned) > 12 else "") if sk.pruned else ""))
    scale = METRES_TO_MM
    source = {"path": str(path), "scale": scale, "joint_nodes": skin.joint_nodes.tolist(),
              "driver": sk.driver.tolist(), "log": log}
    return body.vertices * scale, body.faces, sk.joints * scale, sk.bones, sk.weights, sk.names, source


# --------------------------------------------------------------------------- #
# the posed asset
# --------------------------------------------------------------------------- #
def posed_joint_transforms(bone_transforms: np.ndarray, driver: np.ndarray, scale: float,
                           offset: np.ndarray | None = None) -> np.ndarray:
    """The world transform of every skin joint, in the file's units, from the rig's bone transforms.

    Parameters
    ----------
    bone_transforms : (m, 3, 4) float64
        ``[A | t]`` per bone in the rig's frame (file units times ``scale``).
    driver : (J,) int64
        The bone each skin joint follows (:attr:`~supportless.files.joints.RigSkeleton.driver`), -1 for
        none (it only takes ``offset``).
    scale : float
        Rig units per file unit.
    offset : (3,) float64, optional
        A translation added after posing, rig units (e.g. onto the plate).

    Returns
    -------
    transforms : (J, 4, 4) float64
    """
    T = np.asarray(bone_transforms, np.float64)
    driver = np.asarray(driver, np.int64)
    out = np.tile(np.eye(4), (len(driver), 1, 1))
    has = driver >= 0
    out[has, :3, :3] = T[driver[has], :, :3]
    out[has, :3, 3] = T[driver[has], :, 3] / scale
    if offset is not None:
        out[:, :3, 3] += np.asarray(offset, np.float64) / scale
    return out


def write_posed_gltf(source, destination, joint_transforms: np.ndarray, joint_nodes: np.ndarray) -> None:
    """Write the original asset with a pose set on its joint nodes.

    Every primitive, material, texture, animation and the skin are kept; only
    the joint nodes' local transforms change, so that the glTF skinning
    formula poses the skin as ``joint_transforms`` say.

    Parameters
    ----------
    source : str or os.PathLike
        The asset the pose was found for.
    destination : str or os.PathLike
        ``.glb`` or ``.gltf`` (a ``.gltf`` embeds its buffers).
    joint_transforms : (J, 4, 4) float64
        World-space rigid transform (the file's units) each joint's rest
        global is moved by: its new global is ``T_j · G_j``.
    joint_nodes : (J,) int64
        The node of each joint (:attr:`GltfSkin.joint_nodes`).
    """
    import pygltflib

    from .paths import atomic_path

    skin = skin_of(*load_document(source), source)
    doc = pygltflib.GLTF2().load(str(source))  # written as it is: compressed meshes stay compressed
    parents = node_parents(doc, source)
    locals_ = np.array([node_local(n) for n in doc.nodes])
    new_global = {int(j): np.asarray(T) @ skin.rest_globals[int(j)] for j, T in zip(joint_nodes, joint_transforms)}
    G = np.full_like(locals_, np.nan)
    for i in joint_order(parents):
        p = parents[i]
        if i in new_global:
            G[i] = new_global[i]
        else:
            G[i] = locals_[i] if p < 0 else G[p] @ locals_[i]
    for i in new_global:
        p = parents[i]
        L = G[i] if p < 0 else np.linalg.solve(G[p], G[i])
        node = doc.nodes[i]
        A = L[:3, :3]
        U, S, Vt = np.linalg.svd(A)
        R = U @ Vt
        if np.linalg.det(R) < 0:
            U[:, -1] *= -1
            R = U @ Vt
        scale = np.diag(R.T @ A)
        if node.matrix is not None and len(node.matrix) == 16:
            node.matrix = L.T.ravel().tolist()
        else:
            node.translation = L[:3, 3].tolist()
            node.rotation = _matrix_quat(R).tolist()
            node.scale = scale.tolist()
    destination = Path(destination)
    with warnings.catch_warnings():  # pygltflib warns that the source's .bin is not used by the copy
        warnings.simplefilter("ignore", UserWarning)
        if destination.suffix.lower() == ".gltf":
            doc.convert_buffers(pygltflib.BufferFormat.DATAURI)
        elif str(source).lower().endswith(".gltf"):
            doc.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
    with atomic_path(destination) as tmp:
        if destination.suffix.lower() == ".gltf":
            doc.save_json(str(tmp))
        elif str(source).lower().endswith(".gltf"):
            doc.save_binary(str(tmp))
        else:
            Path(tmp).write_bytes(_glb_bytes(doc))


def _glb_bytes(doc) -> bytes:
    """A GLB of ``doc`` with its binary chunk as it is.

    pygltflib's writer rebuilds the chunk from the buffer views and drops the
    bytes only an extension points at (meshopt's compressed streams).
    """
    import struct

    blob = doc.binary_blob() or b""
    blob += b"\0" * (-len(blob) % 4)
    text = doc.to_json().encode("utf-8")
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    if blob:
        chunks += struct.pack("<I4s", len(blob), b"BIN\0") + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks
