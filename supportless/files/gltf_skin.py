"""Rigged glTF/GLB read: the document, its accessors and node transforms, and the skin in its rest pose.

Read with pygltflib (trimesh drops skins). :func:`read_gltf_skin` returns every
triangle of the asset in its **rest pose** in world space (+Y up, the file's
units) with the skin weights of each vertex over the joints. The rest pose is
the one the file stores (the nodes' own transforms), skinned as the glTF
specification defines it, which is what every viewer shows:

* skinned primitives: ``world = Σ w_j G_j IBM_j v`` (``G_j`` the joint's
  global transform, composed of every ancestor's: the nodes above the
  skeleton that turn a Z-up export upright or scale centimetres to metres
  count; ``IBM_j`` its inverse bind matrix); the skinned node's own transform
  and its ancestors' are ignored, as the specification says, so an armature
  scaled 0.01 over centimetre vertices, or a mesh node scaled 100 that only
  the armature's inverse bind matrices undo, both give the size the joints give;
* rigid meshes (a mesh node under a joint, not skinned) follow their nearest
  joint ancestor: weight 1 on it, placed by their own global transform;
* JOINTS_n/WEIGHTS_n in every component type, normalised and sparse
  accessors, strips and fans; rows of weights that do not sum to 1 are
  normalised (and counted), weights that are not numbers are dropped (and
  counted); morph targets are ignored (and said); Draco- and
  meshopt-compressed primitives are decoded (:mod:`supportless.files.gltf_decode`).

:func:`read_rest_triangles` gives the same triangles to the plain mesh reader
(:func:`~supportless.files.meshes.read_mesh`), so a rigged GLB read as a mesh stands as a viewer shows it.
"""

from __future__ import annotations

import base64
import urllib.parse
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..base.errors import InputError

__all__ = ["GltfSkin", "load_document", "node_globals", "node_local", "node_parents", "read_accessor",
           "read_gltf_skin", "read_rest_triangles", "skin_of"]

_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_NORMALISE = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}
_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_COMPRESSION = ("KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression")

#: Required extensions a loader may meet: the compressions it decodes, quantized attributes (normalized
#: integers, read as such), and extensions of materials, textures, lights and cameras, which leave the mesh
#: and its skin as they are. Any other required extension is refused, as the glTF specification asks.
_READ = (*_COMPRESSION, "KHR_mesh_quantization")
_APPEARANCE = ("KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_lights_", "EXT_lights_", "KHR_xmp",
               "KHR_animation_pointer")


def _understood(extension: str) -> bool:
    """Whether a required glTF extension leaves what supportless reads readable."""
    return extension in _READ or extension.startswith(_APPEARANCE)


# --------------------------------------------------------------------------- #
# low level: buffers, accessors, node transforms
# --------------------------------------------------------------------------- #
def load_document(path):
    """A glTF/GLB file loaded, its compressed primitives decoded.

    Returns
    -------
    doc : pygltflib.GLTF2
    buffers : list of bytes
        Each buffer's content (decoded ones appended).

    Raises
    ------
    InputError
        One line: a missing, unreadable or truncated file, a missing ``.bin``, an extension it cannot read.
    """
    try:
        import pygltflib
    except ImportError:  # pragma: no cover - a declared dependency
        raise InputError(path, "reading glTF needs pygltflib: pip install pygltflib") from None
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    try:
        doc = pygltflib.GLTF2().load(str(path))
    except Exception as exc:  # pygltflib raises many kinds on a corrupt file
        raise InputError(path, f"not a readable glTF file ({type(exc).__name__}: {exc}); "
                         "export it again from the modelling tool") from None
    if doc is None:
        raise InputError(path, "not a readable glTF file; export it again from the modelling tool")
    buffers = []
    for i, buf in enumerate(doc.buffers or []):
        uri = buf.uri
        try:
            if uri is None:
                data = doc.binary_blob() or b""
            elif uri.startswith("data:"):
                data = base64.b64decode(uri.split(",", 1)[1])
            else:
                data = (path.parent / urllib.parse.unquote(uri)).read_bytes()
        except (OSError, ValueError) as exc:
            raise InputError(path, f"buffer {i} ({uri or 'GLB chunk'}) cannot be read ({exc}); "
                             "keep the .bin files next to the .gltf") from None
        if len(data) < (buf.byteLength or 0):
            raise InputError(path, f"buffer {i} holds {len(data)} bytes but the file says {buf.byteLength}; "
                             "the file is truncated")
        buffers.append(data)
    unknown = [ext for ext in doc.extensionsRequired or [] if not _understood(ext)]
    if unknown:
        raise InputError(path, f"the file requires the glTF extension{'s' if len(unknown) > 1 else ''} "
                               f"{', '.join(unknown)}, which supportless does not read; export without it")
    used = set(doc.extensionsRequired or []) | set(doc.extensionsUsed or [])
    if any(ext in used for ext in _COMPRESSION):
        from .gltf_decode import decode_compressed

        buffers = decode_compressed(doc, buffers, path)
    return doc, buffers


def _view(doc, buffers, view_index: int, path) -> tuple[bytes, int, int]:
    """(buffer bytes, start offset, stride or 0) of a buffer view."""
    try:
        view = doc.bufferViews[view_index]
        data = buffers[view.buffer]
    except (IndexError, TypeError):
        raise InputError(path, f"buffer view {view_index} does not exist; the file is broken") from None
    return data, view.byteOffset or 0, view.byteStride or 0


def _read_raw(data: bytes, start: int, stride: int, count: int, dtype, width: int, path) -> np.ndarray:
    itemsize = np.dtype(dtype).itemsize * width
    stride = stride or itemsize
    need = start + stride * (count - 1) + itemsize if count else start
    if count and need > len(data):
        raise InputError(path, f"an accessor reads past the end of its buffer ({need} > {len(data)} bytes); "
                         "the file is truncated or broken")
    if count == 0:
        return np.zeros((0, width), dtype)
    raw = np.frombuffer(data, np.uint8, count=stride * (count - 1) + itemsize, offset=start)
    rows = np.lib.stride_tricks.as_strided(raw, (count, itemsize), (stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(count, width)


def read_accessor(doc, buffers, index: int, path=None) -> np.ndarray:
    """The values of one accessor.

    Parameters
    ----------
    doc : pygltflib.GLTF2
    buffers : list of bytes
        Each buffer's content.
    index : int
    path : optional
        Named in error messages.

    Returns
    -------
    values : (count, width) float64 or int64
        Floats, and normalised integers mapped to [0, 1] or [-1, 1], as
        float64; other integers as int64. Sparse substitutions applied.
    """
    try:
        acc = doc.accessors[index]
        dtype = _COMPONENTS[acc.componentType]
        width = _WIDTHS[acc.type]
    except (IndexError, KeyError, TypeError):
        raise InputError(path, f"accessor {index} does not exist or has an unknown type; the file is broken") from None
    if acc.bufferView is None:
        out = np.zeros((acc.count, width), dtype)
    else:
        data, start, stride = _view(doc, buffers, acc.bufferView, path)
        out = _read_raw(data, start + (acc.byteOffset or 0), stride, acc.count, dtype, width, path).copy()
    sparse = acc.sparse
    if sparse is not None and sparse.count:
        idx_dtype = _COMPONENTS.get(sparse.indices.componentType)
        data, start, _ = _view(doc, buffers, sparse.indices.bufferView, path)
        rows = _read_raw(data, start + (sparse.indices.byteOffset or 0), 0, sparse.count, idx_dtype, 1, path)[:, 0]
        data, start, _ = _view(doc, buffers, sparse.values.bufferView, path)
        values = _read_raw(data, start + (sparse.values.byteOffset or 0), 0, sparse.count, dtype, width, path)
        rows = rows.astype(np.int64)
        if rows.size and (rows.min() < 0 or rows.max() >= acc.count):
            raise InputError(path, f"sparse accessor {index} substitutes rows outside 0..{acc.count - 1}")
        out[rows] = values
    if acc.componentType == 5126:
        return out.astype(np.float64)
    if acc.normalized:
        return np.maximum(out.astype(np.float64) / _NORMALISE[acc.componentType], -1.0)
    return out.astype(np.int64)


def _quat_matrix(q) -> np.ndarray:
    x, y, z, w = (float(c) for c in q)
    n = x * x + y * y + z * z + w * w
    if n < 1e-20:
        return np.eye(3)
    s = 2.0 / n
    return np.array([
        [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
        [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
        [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
    ])


def node_local(node) -> np.ndarray:
    """(4, 4) float64: a node's local transform (its matrix, or T·R·S)."""
    if node.matrix is not None and len(node.matrix) == 16:
        return np.asarray(node.matrix, np.float64).reshape(4, 4).T
    M = np.eye(4)
    S = np.diag(np.asarray(node.scale if node.scale is not None else (1, 1, 1), np.float64))
    R = _quat_matrix(node.rotation if node.rotation is not None else (0, 0, 0, 1))
    M[:3, :3] = R @ S
    M[:3, 3] = node.translation if node.translation is not None else (0, 0, 0)
    return M


def node_parents(doc, path=None) -> np.ndarray:
    """(N,) int64: each node's parent (-1 for roots); InputError on a cycle or a shared child."""
    parents = np.full(len(doc.nodes), -1, np.int64)
    for i, node in enumerate(doc.nodes):
        for c in node.children or []:
            if not 0 <= c < len(doc.nodes) or parents[c] >= 0 or c == i:
                raise InputError(path, f"node {i} ({node.name}) has an invalid child {c}; the node tree is broken")
            parents[c] = i
    for i in range(len(doc.nodes)):  # cycle check
        seen, p = 0, i
        while p >= 0:
            p = parents[p]
            seen += 1
            if seen > len(doc.nodes):
                raise InputError(path, f"the node tree has a cycle through node {i} ({doc.nodes[i].name})")
    return parents


def node_globals(locals_: np.ndarray, parents: np.ndarray) -> np.ndarray:
    """(N, 4, 4) float64: global transforms from local ones and the parent of each node."""
    G = np.full_like(locals_, np.nan)
    done = np.zeros(len(parents), bool)

    def visit(i):
        chain = []
        while i >= 0 and not done[i]:
            chain.append(i)
            i = parents[i]
        for k in reversed(chain):
            p = parents[k]
            G[k] = locals_[k] if p < 0 else G[p] @ locals_[k]
            done[k] = True

    for i in range(len(parents)):
        visit(i)
    return G


def _apply(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    return X @ M[:3, :3].T + M[:3, 3]


# --------------------------------------------------------------------------- #
# the skin in the rest pose
# --------------------------------------------------------------------------- #
@dataclass
class GltfSkin:
    """All triangles of a glTF asset in its rest pose, with weights over the joints.

    Attributes
    ----------
    vertices : (n, 3) float64
        Rest pose (the stored one), world space, the file's units (+Y up).
    faces : (f, 3) int64
        Per primitive, vertices not shared between primitives.
    part : (f,) int64
        Which part (primitive instance) each face comes from.
    part_names : list of str
    weights : (n, J) float64
        Rows sum to 1 over the joints.
    joint_nodes : (J,) int64
        The node of each joint.
    joint_names : list of str
    joint_parents : (J,) int64
        Nearest joint ancestor (-1 for none).
    rest_globals : (N, 4, 4) float64
        Every node's global transform as stored (the rest pose).
    notes : list of str
        What was read and what was done (one line each).
    """

    vertices: np.ndarray
    faces: np.ndarray
    part: np.ndarray
    part_names: list
    weights: np.ndarray
    joint_nodes: np.ndarray
    joint_names: list
    joint_parents: np.ndarray
    rest_globals: np.ndarray
    notes: list = field(default_factory=list)

    @property
    def joint_positions(self) -> np.ndarray:
        """(J, 3) float64: joints in the rest pose."""
        return self.rest_globals[self.joint_nodes, :3, 3]


def _triangles(mode, idx: np.ndarray) -> np.ndarray | None:
    """(f, 3) triangles of a primitive's index list, or None for points/lines."""
    if mode in (None, 4):
        return idx[: len(idx) // 3 * 3].reshape(-1, 3)
    if mode == 5:  # strip
        k = np.arange(len(idx) - 2)
        tri = np.column_stack([idx[k], idx[k + 1], idx[k + 2]])
        odd = k % 2 == 1
        tri[odd] = tri[odd][:, [1, 0, 2]]
        return tri
    if mode == 6:  # fan
        k = np.arange(1, len(idx) - 1)
        return np.column_stack([np.full(len(k), idx[0]), idx[k], idx[k + 1]])
    return None


def read_gltf_skin(path) -> GltfSkin:
    """Read a rigged glTF/GLB asset in its rest pose (the one the file stores).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    skin : GltfSkin

    Raises
    ------
    InputError
        One line: unreadable file, compressed meshes, no skin, no triangles, a
        broken node tree or accessor.
    """
    return skin_of(*load_document(path), path)


def read_rest_triangles(path) -> tuple[np.ndarray, np.ndarray] | None:
    """A rigged glTF/GLB asset's triangles as its skin poses them (what a viewer shows), for a plain mesh reader.

    Returns
    -------
    triangles : ((n, 3) float64, (f, 3) int64) or None
        :attr:`GltfSkin.vertices` (world space, the file's units) and :attr:`GltfSkin.faces`; None for a
        file pygltflib cannot read or one with no skin (its nodes alone place it).
    """
    try:
        doc, buffers = load_document(path)
    except InputError:
        return None
    if not doc.skins:
        return None
    skin = skin_of(doc, buffers, path)
    return skin.vertices, skin.faces


def skin_of(doc, buffers, path) -> GltfSkin:
    """:func:`read_gltf_skin` of a document :func:`load_document` loaded (``path`` named in errors)."""
    nodes = doc.nodes or []
    if not doc.skins:
        raise InputError(path, "has no skin (no joints); supportless needs a rigged model — rig it (e.g. in "
                         "Blender) and export it with the armature, or give a mesh with a TGF --skeleton")
    parents = node_parents(doc, path)
    locals_ = np.array([node_local(n) for n in nodes]) if nodes else np.zeros((0, 4, 4))
    default = node_globals(locals_, parents)
    notes: list[str] = []

    # joints: every node any skin lists, in first-seen order; per skin the rest pose's joint
    # matrices G_j · IBM_j (with no IBMs, identity by the spec, the vertices are in each joint's frame)
    joint_nodes: list[int] = []
    skin_matrices: dict[int, np.ndarray] = {}
    for s_idx, skin in enumerate(doc.skins):
        for j in skin.joints:
            if not 0 <= j < len(nodes):
                raise InputError(path, f"skin {s_idx} names node {j}, which does not exist")
            if j not in joint_nodes:
                joint_nodes.append(j)
        M = default[list(skin.joints)]
        if skin.inverseBindMatrices is not None:
            mats = read_accessor(doc, buffers, skin.inverseBindMatrices, path).reshape(-1, 4, 4).transpose(0, 2, 1)
            if len(mats) < len(skin.joints):
                raise InputError(path, f"skin {s_idx} has {len(skin.joints)} joints but {len(mats)} inverse bind matrices")
            M = M @ mats[: len(skin.joints)]
        skin_matrices[s_idx] = M
    is_joint = np.zeros(len(nodes), bool)
    is_joint[joint_nodes] = True

    def joint_ancestor(i):
        p = i
        while p >= 0 and not is_joint[p]:
            p = parents[p]
        return p

    column = {n: k for k, n in enumerate(joint_nodes)}
    J = len(joint_nodes)

    Vs, Fs, Ws, parts, names = [], [], [], [], []
    offset = 0
    morphs = unnormalised = orphans = not_numbers = 0
    max_sum = 1.0
    skipped_modes = 0
    for n_idx, node in enumerate(nodes):
        if node.mesh is None:
            continue
        try:
            mesh = doc.meshes[node.mesh]
        except (IndexError, TypeError):
            raise InputError(path, f"node {n_idx} names mesh {node.mesh}, which does not exist") from None
        skin = doc.skins[node.skin] if node.skin is not None and node.skin < len(doc.skins) else None
        for p_idx, prim in enumerate(mesh.primitives):
            attrs = prim.attributes
            if attrs.POSITION is None:
                continue
            X = read_accessor(doc, buffers, attrs.POSITION, path)[:, :3]
            idx = (read_accessor(doc, buffers, prim.indices, path)[:, 0] if prim.indices is not None
                   else np.arange(len(X)))
            tri = _triangles(prim.mode, np.asarray(idx, np.int64))
            if tri is None:
                skipped_modes += 1
                continue
            if len(tri) and (tri.min() < 0 or tri.max() >= len(X)):
                raise InputError(path, f"mesh {mesh.name or node.mesh} indexes a vertex that does not exist")
            if prim.targets:
                morphs += 1
            W = np.zeros((len(X), J))
            skinned = skin is not None and attrs.JOINTS_0 is not None and attrs.WEIGHTS_0 is not None
            if skinned:
                Wk = np.zeros((len(X), len(skin.joints)))  # over this skin's joints
                for js, ws in (("JOINTS_0", "WEIGHTS_0"), ("JOINTS_1", "WEIGHTS_1")):
                    ja, wa = getattr(attrs, js, None), getattr(attrs, ws, None)
                    if ja is None or wa is None:
                        continue
                    jv = read_accessor(doc, buffers, ja, path).astype(np.int64)
                    wv = read_accessor(doc, buffers, wa, path).astype(np.float64)
                    if jv.size and (jv.min() < 0 or jv.max() >= len(skin.joints)):
                        raise InputError(path, f"mesh {mesh.name or node.mesh} uses joint index {int(jv.max())} "
                                         f"but its skin has {len(skin.joints)} joints")
                    bad = ~np.isfinite(wv)
                    if np.any(bad):
                        not_numbers += int(np.any(bad, axis=1).sum())
                        wv = np.where(bad, 0.0, wv)
                    np.add.at(Wk, (np.repeat(np.arange(len(X)), jv.shape[1]), jv.ravel()), np.clip(wv, 0, None).ravel())
                total = Wk.sum(1)
                none = total <= 1e-9
                if np.any(none):  # no weight: the weights of the nearest weighted vertex (else the skin's first joint)
                    orphans += int(none.sum())
                    if np.all(none):
                        Wk[:, 0] = total[:] = 1.0
                    else:
                        from scipy.spatial import cKDTree

                        near = cKDTree(X[~none]).query(X[none])[1]
                        Wk[none], total[none] = Wk[~none][near], total[~none][near]
                M = skin_matrices[node.skin]
                world = np.einsum("vk,kab,vb->va", Wk / total[:, None], M[:, :3, :],
                                  np.column_stack([X, np.ones(len(X))]))
                cols = np.array([column[j] for j in skin.joints], np.int64)
                for k in range(len(skin.joints)):
                    W[:, cols[k]] += Wk[:, k]
            else:  # rigid: follows its nearest joint ancestor
                world = _apply(default[n_idx], X)
                a = joint_ancestor(n_idx)
                if a < 0 and J:
                    centre = world.mean(0) if len(world) else np.zeros(3)
                    a = joint_nodes[int(np.argmin(np.linalg.norm(default[joint_nodes, :3, 3] - centre, axis=1)))]
                    notes.append(f"mesh '{mesh.name or node.mesh}' hangs from no joint; it follows the nearest "
                                 f"joint '{nodes[a].name or a}'")
                W[:, column[a]] = 1.0
            sums = W.sum(1)
            off = np.abs(sums - 1.0) > 1e-3
            if np.any(off):
                unnormalised += int(off.sum())
                max_sum = max(max_sum, float(sums.max()))
            W /= sums[:, None]
            Vs.append(world)
            Fs.append(tri + offset)
            Ws.append(W)
            parts.append(np.full(len(tri), len(names), np.int64))
            names.append(f"{mesh.name or f'mesh {node.mesh}'}#{p_idx}" if len(mesh.primitives) > 1
                         else (mesh.name or f"mesh {node.mesh}"))
            offset += len(X)
    if not Fs or sum(len(f) for f in Fs) == 0:
        raise InputError(path, "has no triangles to print")
    if not np.any([s.joints for s in doc.skins]):
        raise InputError(path, "its skin lists no joints; export it again with the armature")
    V = np.vstack(Vs)
    if not np.all(np.isfinite(V)):
        raise InputError(path, "has NaN or infinite vertex positions")
    notes.insert(0, f"read {len(names)} primitive(s), {len(V)} vertices, {sum(len(f) for f in Fs)} triangles, "
                 f"{J} joints in {len(doc.skins)} skin(s)")
    if unnormalised:
        notes.append(f"skin weights of {unnormalised} vertices did not sum to 1 (up to {max_sum:.3g}); normalised")
    if not_numbers:
        notes.append(f"skin weights of {not_numbers} vertices were not numbers (NaN or infinite); those weights "
                     "were dropped")
    if orphans:
        notes.append(f"{orphans} skinned vertices had no weight; they take the weights of the nearest vertex "
                     "that has some")
    if morphs:
        notes.append(f"morph targets of {morphs} primitive(s) ignored (the base shape is posed)")
    if skipped_modes:
        notes.append(f"{skipped_modes} point/line primitive(s) ignored")
    parent_joint = np.array([joint_ancestor(parents[j]) if parents[j] >= 0 else -1 for j in joint_nodes], np.int64)
    joint_parents = np.array([column[p] if p >= 0 else -1 for p in parent_joint], np.int64)
    return GltfSkin(V, np.vstack(Fs), np.concatenate(parts), names, np.vstack(Ws), np.asarray(joint_nodes, np.int64),
                    [nodes[j].name or f"joint{k}" for k, j in enumerate(joint_nodes)], joint_parents, default,
                    notes)
