"""Compressed glTF (:mod:`supportless.gltf_decode`): Draco and meshopt meshes read as their plain twins."""

from __future__ import annotations

import DracoPy
import meshoptimizer
import numpy as np
import pygltflib
import pytest

from test_gltf import _blob, _values, assert_input_error, character, load, write_gltf
from supportless.gltf import read_gltf_skin, write_posed_gltf



@pytest.fixture
def cache(tmp_path):
    return tmp_path / "cache"


def _append(blob: bytearray, data: bytes) -> int:
    """Append 4-byte aligned; returns the offset."""
    blob.extend(b"\0" * (-len(blob) % 4))
    offset = len(blob)
    blob.extend(data)
    return offset


def draco_copy(plain, out):
    """``plain`` with every primitive in a Draco stream and its accessors' own data zeroed."""
    doc = pygltflib.GLTF2().load(str(plain))
    blob = bytearray(_blob(doc, plain))
    for mesh in doc.meshes:
        for prim in mesh.primitives:
            X = _values(doc, bytes(blob), prim.attributes.POSITION).astype(np.float32)
            faces = _values(doc, bytes(blob), prim.indices).astype(np.uint32).reshape(-1, 3)
            generic, ids = {}, {}
            for uid, name in enumerate(("JOINTS_0", "WEIGHTS_0"), start=1):
                index = getattr(prim.attributes, name, None)
                if index is not None:
                    acc = doc.accessors[index]
                    raw = _values(doc, bytes(blob), index)
                    generic[uid] = (raw.astype(np.uint16) if name == "JOINTS_0" else raw.astype(np.float32))
                    ids[name] = uid
                    assert not acc.normalized
            data = DracoPy.encode(X, faces, quantization_bits=30, preserve_order=True,
                                  generic_attributes=generic or None)
            decoded = DracoPy.decode(data)
            ids["POSITION"] = next(a["unique_id"] for a in decoded.attributes if a["attribute_type"] == 0)
            for index in [prim.indices, *(getattr(prim.attributes, n) for n in ids)]:
                acc = doc.accessors[index]
                view = doc.bufferViews[acc.bufferView]
                blob[view.byteOffset:view.byteOffset + view.byteLength] = bytes(view.byteLength)
                acc.bufferView, acc.byteOffset = None, None
            offset = _append(blob, data)
            doc.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=offset, byteLength=len(data)))
            prim.extensions = {"KHR_draco_mesh_compression": {"bufferView": len(doc.bufferViews) - 1,
                                                              "attributes": ids}}
    doc.extensionsUsed = ["KHR_draco_mesh_compression"]
    doc.extensionsRequired = ["KHR_draco_mesh_compression"]
    doc.buffers[0].byteLength = len(blob)
    doc.set_binary_blob(bytes(blob))
    doc.save_binary(str(out))
    return out


def meshopt_copy(plain, out):
    """``plain`` with every vertex-attribute and index buffer view meshopt-compressed (the originals zeroed)."""
    doc = pygltflib.GLTF2().load(str(plain))
    blob = bytearray(_blob(doc, plain))
    first = len(blob)
    done = set()
    for mesh in doc.meshes:
        for prim in mesh.primitives:
            for index, mode in [(prim.indices, "TRIANGLES"), (prim.attributes.POSITION, "ATTRIBUTES"),
                                (prim.attributes.JOINTS_0, "ATTRIBUTES"), (prim.attributes.WEIGHTS_0, "ATTRIBUTES")]:
                if index is None or doc.accessors[index].bufferView in done:
                    continue
                acc = doc.accessors[index]
                view = doc.bufferViews[acc.bufferView]
                raw = bytes(blob[view.byteOffset:view.byteOffset + view.byteLength])
                if mode == "TRIANGLES":
                    idx = _values(doc, bytes(blob), index).astype(np.uint32).ravel()
                    stride = 4
                    data = meshoptimizer.encode_index_buffer(idx, len(idx), int(idx.max()) + 1)
                    view.byteLength = 4 * len(idx)
                    acc.componentType = 5125
                    blob_offset = _append(blob, idx.tobytes())  # the plain data moves; zeroed below
                    view.byteOffset = blob_offset
                else:
                    stride = view.byteLength // acc.count
                    assert stride % 4 == 0
                    data = meshoptimizer.encode_vertex_buffer(np.frombuffer(raw, np.uint8).reshape(acc.count, stride),
                                                              acc.count, stride)
                count = acc.count
                blob[view.byteOffset:view.byteOffset + view.byteLength] = bytes(view.byteLength)
                offset = _append(blob, data)
                view.extensions = {"EXT_meshopt_compression": {
                    "buffer": 0, "byteOffset": offset, "byteLength": len(data), "byteStride": stride,
                    "count": count, "mode": mode}}
                done.add(acc.bufferView)
    # a view over the compressed streams, so pygltflib's writer (which repacks the chunk from the views) keeps them
    doc.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=first, byteLength=len(blob) - first))
    doc.extensionsUsed = ["EXT_meshopt_compression"]
    doc.extensionsRequired = ["EXT_meshopt_compression"]
    doc.buffers[0].byteLength = len(blob)
    doc.set_binary_blob(bytes(blob))
    doc.save_binary(str(out))
    return out


def rolled(F):
    """Each triangle's corners rotated so its smallest index comes first (the same triangle, same orientation)."""
    k = np.argmin(F, axis=1)
    return np.stack([F[np.arange(len(F)), (k + i) % 3] for i in range(3)], axis=1)


@pytest.mark.parametrize("compress", [draco_copy, meshopt_copy], ids=["draco", "meshopt"])
def test_a_compressed_asset_reads_as_its_plain_twin(tmp_path, cache, compress):
    plain = write_gltf(character(), tmp_path / "plain.glb")
    packed = compress(plain, tmp_path / "packed.glb")
    a, b = read_gltf_skin(plain), read_gltf_skin(packed)
    size = float(np.ptp(a.vertices, axis=0).max())
    # Draco may reorder nothing here (preserve_order), and 30-bit positions are exact to float32
    np.testing.assert_allclose(b.vertices, a.vertices, atol=1e-6 * size)
    np.testing.assert_array_equal(rolled(b.faces), rolled(a.faces))  # meshopt may rotate a triangle's corners
    np.testing.assert_allclose(b.weights, a.weights, atol=1e-6)
    # and the rig and the posed copy: the posed copy stays compressed and reads back posed
    rig = load(packed, cache)
    assert rig.bone_count == load(plain, tmp_path / "cache2").bone_count
    out = tmp_path / "posed.glb"
    T = np.tile(np.eye(4), (len(rig.info["gltf"]["joint_nodes"]), 1, 1))
    write_posed_gltf(packed, out, T, rig.info["gltf"]["joint_nodes"])
    again = pygltflib.GLTF2().load(str(out))
    assert again.extensionsRequired == pygltflib.GLTF2().load(str(packed)).extensionsRequired
    np.testing.assert_allclose(read_gltf_skin(out).vertices, b.vertices, atol=1e-6 * size)


def test_a_corrupt_draco_stream_is_one_line(tmp_path, cache):
    plain = write_gltf(character(), tmp_path / "plain.glb")
    packed = draco_copy(plain, tmp_path / "packed.glb")
    doc = pygltflib.GLTF2().load(str(packed))
    view = doc.bufferViews[doc.meshes[0].primitives[0].extensions["KHR_draco_mesh_compression"]["bufferView"]]
    blob = bytearray(doc.binary_blob())
    blob[view.byteOffset:view.byteOffset + view.byteLength] = bytes(range(256)) * (view.byteLength // 256) + \
        bytes(view.byteLength % 256)
    doc.set_binary_blob(bytes(blob))
    doc.save_binary(str(tmp_path / "broken.glb"))
    assert_input_error(tmp_path / "broken.glb", cache, "Draco stream", "cannot be decoded")
