"""The on-disk rig cache: where it lives, the key of an entry, and reading and writing an entry.

A prepared rig (:class:`supportless.rig.rig.Rig`) is stored as one ``.npz`` per
key (:func:`rig_cache_key`, or :func:`gltf_cache_file` for a glTF asset),
written through :func:`supportless.files.meshes.atomic_path`: a reader, in this
process or another one sharing the folder, sees either no entry or a whole
one, never a half-written file. An entry that cannot be read (truncated by a
full disk, damaged, from another version) is not fatal: :func:`read_entry`
returns None with a note, and the rig is prepared again and the entry
rewritten.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ..base.geometry import parse_up
from ..files.meshes import atomic_path

__all__ = ["ARRAYS", "CACHE_VERSION", "default_cache_dir", "gltf_cache_file", "read_entry", "rig_cache_key",
           "write_entry"]

#: Bumped whenever what a rig holds, or how it is prepared, changes: older entries are prepared again.
CACHE_VERSION = 8

#: The rig's arrays an entry holds.
ARRAYS = ("vertices", "faces", "joints", "bones", "tet_vertices", "tets", "tet_weights", "up")


def default_cache_dir() -> Path:
    """The rig cache folder: ``$SUPPORTLESS_CACHE``, else ``$XDG_CACHE_HOME/supportless``, else ``~/.cache/supportless``."""
    env = os.environ.get("SUPPORTLESS_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "supportless"


def rig_cache_key(V, F, J, B, up, **settings) -> str:
    """Hash of everything a prepared rig depends on (hex string)."""
    h = hashlib.sha256()
    h.update(f"supportless-rig-v{CACHE_VERSION}".encode())
    for a in (V, F, J, B, up):
        a = np.ascontiguousarray(a)
        h.update(str(a.dtype).encode() + str(a.shape).encode())
        h.update(a.tobytes())
    h.update(repr(sorted(settings.items())).encode())
    return h.hexdigest()[:24]


def gltf_cache_file(path: Path, cache_dir, weights, height_mm, up, samples_per_bone, bbw_iterations) -> Path:
    """The cache file of a glTF rig: a hash of the file's bytes and every setting that changes the rig."""
    h = hashlib.sha256(f"supportless-gltf-rig-v{CACHE_VERSION}".encode())
    try:
        h.update(path.read_bytes())
    except OSError:  # reading it properly says what is wrong
        h.update(b"unreadable")
    h.update(repr((weights, height_mm, np.asarray(parse_up(up), np.float64).tolist(), samples_per_bone,
                   bbw_iterations)).encode())
    return (Path(cache_dir) if cache_dir is not None else default_cache_dir()) / f"rig-{h.hexdigest()[:24]}.npz"


def write_entry(file: Path, rig) -> None:
    """Write ``rig`` (a :class:`~supportless.rig.rig.Rig`) as the entry ``file``, atomically."""
    file.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(file) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, version=CACHE_VERSION, warnings=np.array(rig.info.get("warnings", []), dtype=str),
                     labels=np.array(rig.labels if rig.labels is not None else [], dtype=str),
                     has_labels=rig.labels is not None,
                     coarse_faces=rig.coarse_faces if rig.coarse_faces is not None else np.zeros((0, 3), np.int64),
                     gltf=np.array(json.dumps(rig.info.get("gltf"))),
                     **{k: getattr(rig, k) for k in ARRAYS})


def read_entry(file: Path, notes: list[str] | None = None) -> dict | None:
    """The :class:`~supportless.rig.rig.Rig` fields of the entry ``file``, or None when there is none to use.

    Parameters
    ----------
    file : pathlib.Path
    notes : list of str, optional
        Gets one line when the entry exists but cannot be read (damaged or
        truncated; an entry of an older version is replaced without a note).

    Returns
    -------
    fields : dict or None
        The arrays of :data:`ARRAYS`, ``info`` (``warnings`` and the glTF
        source, if any), ``labels`` and ``coarse_faces``.
    """
    if not file.is_file():
        return None
    try:
        with np.load(file) as data:
            if int(data["version"]) != CACHE_VERSION:
                return None
            arrays = {k: data[k] for k in ARRAYS}
            warnings = [str(w) for w in data["warnings"]]
            labels = [str(x) for x in data["labels"]] if bool(data["has_labels"]) else None
            coarse = data["coarse_faces"] if len(data["coarse_faces"]) else None
            source = json.loads(str(data["gltf"]))
    except Exception as exc:  # noqa: BLE001 - whatever is wrong with the entry, the rig is prepared again
        if notes is not None:
            notes.append(f"the rig cache entry {file} was damaged ({type(exc).__name__}): the rig was prepared "
                         "again and the entry rewritten")
        return None
    info = {"warnings": warnings} | ({"gltf": source} if source is not None else {})
    return arrays | {"info": info, "labels": labels, "coarse_faces": coarse}


def skeleton_cache_file(V, F, up, bones, cache_dir) -> Path:
    """The cache file of a skeleton built from a shape: a hash of the surface, the printing direction and ``bones``.

    The builder is randomised (PyGEL3D's multi-scale local separators seed themselves), so a model keeps the
    skeleton it got first: the same input gives the same rig and the same answer on the next run.
    """
    h = hashlib.sha256(f"supportless-skeleton-v{CACHE_VERSION}".encode())
    for a in (V, F, np.asarray(up, np.float64)):
        a = np.ascontiguousarray(a)
        h.update(str(a.dtype).encode() + str(a.shape).encode() + a.tobytes())
    h.update(repr(bones).encode())
    return (Path(cache_dir) if cache_dir is not None else default_cache_dir()) / f"skeleton-{h.hexdigest()[:24]}.npz"


def read_skeleton(file: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """``(joints (j, d) float64, bones (m, 2) int64)`` cached in ``file``, or None (missing or unreadable)."""
    try:
        with np.load(file) as data:
            return np.asarray(data["joints"], np.float64), np.asarray(data["bones"], np.int64)
    except Exception:  # noqa: BLE001 - missing or damaged: the skeleton is built again
        return None


def write_skeleton(file: Path, joints: np.ndarray, bones: np.ndarray) -> None:
    """Keep a built skeleton in ``file``, atomically; a cache that cannot be written is no error."""
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(file) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, joints=joints, bones=bones)
    except OSError:
        pass
