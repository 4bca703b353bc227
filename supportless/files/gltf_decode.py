"""Compressed glTF made plain: Draco primitives and meshopt buffer views decoded in place.

Models published on the web are compressed as a rule:

* ``KHR_draco_mesh_compression`` stores a primitive's vertices and triangles
  in one Draco stream (decoded by ``DracoPy``); the primitive's accessors
  then have no buffer view of their own;
* ``EXT_meshopt_compression`` (and its successor ``KHR_meshopt_compression``)
  compresses whole buffer views (decoded by ``meshoptimizer``), with
  optional filters for normals, rotations and exponent-coded floats.

:func:`decode_compressed` rewrites a loaded document so that every such
accessor reads plain little-endian data from a new buffer appended to the
list; the rest of :mod:`supportless.files.gltf_skin` never sees the compression.
"""

from __future__ import annotations

import numpy as np

from ..base.errors import InputError

__all__ = ["DRACO", "MESHOPT", "decode_compressed"]

DRACO = "KHR_draco_mesh_compression"
MESHOPT = ("EXT_meshopt_compression", "KHR_meshopt_compression")

#: glTF componentType -> numpy dtype (little-endian).
_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}


def decode_compressed(doc, buffers: list, path) -> list:
    """Decode every Draco primitive and meshopt buffer view of ``doc`` (changed in place).

    Parameters
    ----------
    doc : pygltflib.GLTF2
    buffers : list of bytes
        The document's buffers, in order.
    path : path-like
        Named in error messages.

    Returns
    -------
    buffers : list of bytes
        ``buffers`` with the decoded data appended as new buffers.

    Raises
    ------
    InputError
        When a decoder is missing or a stream is corrupt.
    """
    buffers = list(buffers)
    for i, view in enumerate(doc.bufferViews or []):
        ext = next(((view.extensions or {}).get(name) for name in MESHOPT if (view.extensions or {}).get(name)), None)
        if ext is not None:
            data = _meshopt_view(ext, buffers, i, path)
            buffers.append(data)
            view.buffer, view.byteOffset, view.byteLength = len(buffers) - 1, 0, len(data)
            view.extensions = {k: v for k, v in view.extensions.items() if k not in MESHOPT}
    for m, mesh in enumerate(doc.meshes or []):
        for p, prim in enumerate(mesh.primitives):
            ext = (prim.extensions or {}).get(DRACO)
            if ext is not None:
                _draco_primitive(doc, prim, ext, buffers, path, f"mesh {m} primitive {p}")
                prim.extensions = {k: v for k, v in prim.extensions.items() if k != DRACO}
    return buffers


def _meshopt_view(ext: dict, buffers: list, index: int, path) -> bytes:
    """The decoded bytes of one meshopt-compressed buffer view."""
    try:
        import meshoptimizer
    except ImportError:
        raise InputError(path, "the meshes are compressed with meshopt; install its decoder: "
                         "pip install meshoptimizer") from None
    try:
        start = int(ext.get("byteOffset", 0))
        source = bytes(buffers[int(ext["buffer"])][start:start + int(ext["byteLength"])])
        count, stride, mode = int(ext["count"]), int(ext["byteStride"]), ext.get("mode", "ATTRIBUTES")
        if mode == "ATTRIBUTES":
            raw = meshoptimizer.decode_vertex_buffer(count, stride, source)
            out = _meshopt_filter(np.frombuffer(np.asarray(raw).tobytes(), np.uint8), ext.get("filter", "NONE"),
                                  count, stride, meshoptimizer)
        elif mode == "TRIANGLES":
            out = meshoptimizer.decode_index_buffer(count, stride, source)
        elif mode == "INDICES":
            out = meshoptimizer.decode_index_sequence(count, stride, source)
        else:
            raise ValueError(f"unknown mode {mode}")
        data = np.asarray(out).tobytes()
    except InputError:
        raise
    except Exception as exc:  # the decoder raises several kinds on a corrupt stream
        raise InputError(path, f"meshopt-compressed buffer view {index} cannot be decoded ({exc}); "
                         "export the model again") from None
    if len(data) != count * stride:
        raise InputError(path, f"meshopt-compressed buffer view {index} decoded to {len(data)} bytes, not "
                         f"{count * stride}; export the model again")
    return data


def _meshopt_filter(raw: np.ndarray, name: str, count: int, stride: int, meshoptimizer) -> np.ndarray:
    """Undo a meshopt filter on decoded bytes (NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL)."""
    if name in (None, "NONE"):
        return raw
    if name == "OCTAHEDRAL":
        typed = raw.view(np.int8 if stride == 4 else np.int16).copy()
        return meshoptimizer.decode_filter_oct(typed, count, stride)
    if name == "QUATERNION":
        return meshoptimizer.decode_filter_quat(raw.view(np.int16).copy(), count, stride)
    if name == "EXPONENTIAL":
        return meshoptimizer.decode_filter_exp(raw.view(np.int32).copy(), count, stride)
    raise ValueError(f"unknown filter {name}")


def _draco_primitive(doc, prim, ext: dict, buffers: list, path, where: str) -> None:
    """Decode one Draco primitive into new buffer views behind its accessors."""
    try:
        import DracoPy
    except ImportError:
        raise InputError(path, "the meshes are compressed with Draco; install its decoder: pip install DracoPy") \
            from None
    try:
        view = doc.bufferViews[int(ext["bufferView"])]
        start = view.byteOffset or 0
        mesh = DracoPy.decode(bytes(buffers[view.buffer][start:start + view.byteLength]))
        arrays = {}
        for name, uid in ext.get("attributes", {}).items():
            attribute = mesh.get_attribute_by_unique_id(int(uid))
            if attribute is None:
                raise ValueError(f"no attribute {uid} ({name}) in the stream")
            arrays[name] = np.asarray(attribute["data"])
        faces = np.asarray(mesh.faces).reshape(-1)
    except Exception as exc:  # DracoPy raises several kinds on a corrupt stream
        raise InputError(path, f"the Draco stream of {where} cannot be decoded ({exc}); export the model again") \
            from None
    for name, values in arrays.items():
        index = getattr(prim.attributes, name, None)
        if index is not None:
            _fill_accessor(doc, buffers, index, values)
    if prim.indices is not None:
        _fill_accessor(doc, buffers, prim.indices, faces)


def _fill_accessor(doc, buffers: list, index: int, values: np.ndarray) -> None:
    """Put ``values`` (cast to the accessor's component type) in a new buffer and point the accessor at it."""
    import pygltflib

    accessor = doc.accessors[index]
    data = np.ascontiguousarray(values.astype(_DTYPES[accessor.componentType]).astype(
        np.dtype(_DTYPES[accessor.componentType]).newbyteorder("<"))).tobytes()
    buffers.append(data)
    doc.bufferViews.append(pygltflib.BufferView(buffer=len(buffers) - 1, byteOffset=0, byteLength=len(data)))
    accessor.bufferView = len(doc.bufferViews) - 1
    accessor.byteOffset = 0
    accessor.count = len(values) if values.ndim > 1 or accessor.type == "SCALAR" else accessor.count
