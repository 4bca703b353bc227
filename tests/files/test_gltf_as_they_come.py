"""glTF as published: Draco and meshopt meshes read as their plain twins; messy characters write no crossing."""

from __future__ import annotations

import DracoPy
import meshoptimizer
import numpy as np
import pygltflib
import pytest
from test_gltf import Prim, _blob, _values, assert_input_error, box_prim, character, load, one_hot, write_gltf

from supportless.files.gltf import read_gltf_skin, write_posed_gltf


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


@pytest.mark.slow
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


# --------------------------------------------------------------------------- #
# messy characters as they come (issue 31): each runs, and nothing written crosses itself
# --------------------------------------------------------------------------- #
def open_tube(y0, y1, rx, rz, joint, segments=12):
    """An open elliptic tube around the y axis (no caps), outward, fully on skin joint ``joint``."""
    t = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    ring = np.column_stack([rx * np.cos(t), np.zeros(segments), rz * np.sin(t)])
    V = np.vstack([ring + [0, y0, 0], ring + [0, y1, 0]])
    F = []
    for i in range(segments):
        a, b = i, (i + 1) % segments
        F += [[a, b + segments, b], [a, a + segments, b + segments]]
    J, W = one_hot(len(V), joint)
    return Prim(V, np.asarray(F, np.int64), J, W)


def test_overlapping_open_clothing_and_joint_caps_run_and_write_no_crossing(tmp_path, cache):
    """A jacket (an open tube crossing the column's sides), a sleeve, and small caps over the joints."""
    import supportless as sl
    from supportless.copyleft.cgal import intersecting_face_pairs

    asset = character()
    # wider than the column in x, narrower in z: its surface cuts through the column's
    asset.meshes[0].append(open_tube(0.015, 0.045, 0.016, 0.008, 1))
    asset.meshes[0].append(open_tube(0.035, 0.058, 0.007, 0.013, 2))
    for k, y in enumerate((0.02, 0.04)):  # caps at J1 and J2, half in, half out
        asset.meshes[0].append(box_prim((-0.012, y - 0.003, -0.012), (0.012, y + 0.003, 0.012), k + 1))
    path = write_gltf(asset, tmp_path / "jacket.glb")
    rig = load(path, cache)
    assert intersecting_face_pairs(rig.vertices, rig.faces) == 0
    result = sl.optimize(rig, particles=8, iterations=3, seed=0)
    # the posed surface crosses itself only where jointed parts press together, and is written as one clean solid
    assert result.written.rest_pairs == 0
    assert result.written.written_pairs == 0 or result.written.contacts
    from supportless.files.printbody import united_surface

    U, G, _ = united_surface(result.print_vertices, rig.faces)
    assert intersecting_face_pairs(U, G) == 0


def test_a_vertex_with_no_weight_takes_its_neighbours_not_an_unweighted_root(tmp_path, cache):
    """Skin joint 0 is an unweighted root (RootA): a weightless vertex on it would stop the roots' pruning."""
    plain = load(write_gltf(character(helpers=True), tmp_path / "plain.glb"), cache)
    asset = character(helpers=True)
    prim = asset.meshes[0][0]
    prim.weights = prim.weights.copy()
    prim.weights[0] = 0.0
    path = write_gltf(asset, tmp_path / "zeroed.glb")
    skin = read_gltf_skin(path)
    assert any("1 skinned vertices had no weight" in note for note in skin.notes)
    first = int(np.flatnonzero(skin.weights[0])[0])
    assert skin.joint_names[first] == "J0" and skin.weights[0, first] == 1.0  # its ring's joint, not RootA
    rig = load(path, tmp_path / "cache2")
    assert rig.bone_count == plain.bone_count and rig.labels == plain.labels
