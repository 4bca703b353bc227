"""Reading and writing the files the tool works with.

Surface meshes (OBJ, STL, PLY, OFF, GLB) go through trimesh, a rigged GLB through
:mod:`supportless.files.gltf_skin` (its skin poses it), 3MF through
:mod:`supportless.files.threemf`; skeletons are libigl's TGF; precomputed volume
meshes and weights are libigl's ``.mesh`` and ``.dmat``; poses are JSON
(:mod:`supportless.files.posefile`). Every writer writes a temporary file next to the
target and renames it, so an interrupted write never leaves a half-written file.
Every reader raises :class:`~supportless.base.errors.InputError` with one clear line
on bad input, and :func:`write_mesh` does the same for arrays that are not a
triangle mesh, before it writes anything.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..base.errors import InputError
from ..base.geometry import row_groups
from .objtext import read_plain_obj as _read_plain_obj
from .paths import atomic_path
from .skeleton import check_skeleton
from .threemf import write_3mf

__all__ = [
    "MESH_FORMATS", "atomic_path", "check_closed_surface", "check_mesh_arrays", "edge_counts",
    "merge_duplicate_vertices", "read_dmat", "read_mesh", "read_tet_mesh", "read_tgf", "write_dmat",
    "write_json", "write_mesh", "write_tet_mesh", "write_text", "write_tgf",
]

MESH_FORMATS = ("obj", "stl", "ply", "off", "3mf", "glb")


def write_text(path: str | os.PathLike, text: str) -> None:
    """Write text to a file atomically (temporary file, then rename).

    Parameters
    ----------
    path : str or os.PathLike
    text : str
    """
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_json(path: str | os.PathLike, data) -> None:
    """Write data as indented JSON, atomically.

    Parameters
    ----------
    path : str or os.PathLike
    data : object
        JSON values; numpy arrays and scalars and paths are converted.
    """
    write_text(path, json.dumps(data, indent=2, default=_json_default) + "\n")


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"cannot write {type(obj).__name__} as JSON")


# --------------------------------------------------------------------------- #
# surface meshes
# --------------------------------------------------------------------------- #
def read_mesh(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read a triangle mesh.

    Parameters
    ----------
    path : str or os.PathLike
        OBJ, STL, PLY, OFF, 3MF or GLB file. Scenes (3MF, GLB) are flattened
        into one mesh with their transforms applied; a rigged GLB is read in
        the rest pose its skin gives (:func:`~supportless.files.gltf_skin.read_rest_triangles`).
        Vertices that coincide exactly are merged (STL stores a triangle soup).

    Returns
    -------
    V : (n, 3) float64
        Vertex positions.
    F : (f, 3) int64
        Triangles, 0-based.

    Raises
    ------
    InputError
        Missing file, unknown format, unreadable or empty mesh.
    """
    import trimesh

    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    ext = path.suffix.lower().lstrip(".")
    if ext not in MESH_FORMATS:
        raise InputError(path, f"unknown mesh format '.{ext}'; use one of {', '.join(MESH_FORMATS)}")
    if ext == "glb":  # a rigged character where its skin puts it, not where its bare mesh nodes would
        from .gltf_skin import read_rest_triangles

        simple = read_rest_triangles(path)
    elif ext == "stl":
        simple = _read_stl(path)
    else:
        simple = _read_plain_obj(path) if ext == "obj" else None
    if simple is not None:
        V, F = simple
    else:
        if ext == "obj":
            _check_obj_vertex_lines(path)
        try:
            loaded = trimesh.load(str(path), file_type=ext, process=False, force="mesh")
        except Exception as exc:  # trimesh raises many types on bad files
            raise InputError(path, f"cannot read as {ext.upper()}: {_one_line(exc)}") from None
        V = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64)
        F = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64)
    if V.ndim != 2 or (len(V) and V.shape[1] != 3):
        raise InputError(path, f"vertices have {V.shape[-1] if V.ndim == 2 else '?'} coordinates, not x y z")
    if len(V) == 0 or len(F) == 0 or F.ndim != 2 or F.shape[1] != 3:
        raise InputError(path, f"no triangles found in this {ext.upper()} file")
    if not np.all(np.isfinite(V)):
        raise InputError(path, "vertex coordinates contain NaN or infinity")
    V, F = merge_duplicate_vertices(V, F)
    return V, F


def _read_stl(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """An STL file's triangle soup by trimesh's own STL reader, without the scene it would be wrapped in (1.7 s of
    copies for a written sculpt's 1.8 million triangles); None for what that reader does not give as one mesh
    (several named solids, no triangle, a damaged file), which :func:`read_mesh` hands to ``trimesh.load``."""
    from trimesh.exchange.stl import load_stl

    try:
        with open(path, "rb") as fh:
            loaded = load_stl(fh)
    except Exception:  # noqa: BLE001 - trimesh.load reads it again and says what is wrong
        return None
    if "vertices" not in loaded or "faces" not in loaded:
        return None
    return np.asarray(loaded["vertices"], np.float64), np.asarray(loaded["faces"], np.int64)


def _check_obj_vertex_lines(path: Path) -> None:
    """Every ``v`` line of an OBJ file has three numbers (x y z; a colour may follow), or InputError naming it."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for lineno, line in enumerate(fh, 1):
                if line.startswith("v ") or line.startswith("v\t"):
                    words = line.split()[1:4]
                    try:
                        ok = len(words) == 3 and all(np.isfinite(float(w)) for w in words)
                    except ValueError:
                        ok = False
                    if not ok:
                        raise InputError(path, f"line {lineno} is not a vertex 'v x y z': {line.strip()[:60]!r}")
    except OSError as exc:
        raise InputError(path, f"cannot read: {_one_line(exc)}") from None


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def merge_duplicate_vertices(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices at exactly the same position and drop unreferenced ones.

    The order of first occurrence is kept, so a mesh without duplicates comes
    back unchanged.

    Parameters
    ----------
    V : (n, d) float64
    F : (f, 3) int64

    Returns
    -------
    V : (n', d) float64
    F : (f, 3) int64
    """
    used = np.zeros(len(V), bool)
    used[F.ravel()] = True
    first, inverse, _ = row_groups(V)
    if len(first) == len(V) and used.all():
        return V, F
    F = first[inverse][F]  # canonical representative: the first occurrence of each position
    keep = np.zeros(len(V), bool)
    keep[F.ravel()] = True
    new_index = np.cumsum(keep) - 1
    return V[keep], new_index[F].astype(np.int64)


def edge_counts(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique undirected edges of a triangle mesh and how many faces use each.

    Parameters
    ----------
    F : (f, 3) int64

    Returns
    -------
    E : (e, 2) int64
        Sorted vertex pairs.
    counts : (e,) int64
        Number of faces using each edge.
    """
    A, B = F.T.ravel(), F[:, [1, 2, 0]].T.ravel()  # every triangle's edges 01, then 12, then 20
    E = np.column_stack([np.minimum(A, B), np.maximum(A, B)])  # each pair sorted (np.sort(axis=1) in twice the time)
    keys, counts = np.unique(_pair_keys(E), return_counts=True)  # one int64 a pair: as np.unique(axis=0), faster
    n = _key_base(E)
    return np.column_stack([keys // n, keys % n]).astype(E.dtype, copy=False), counts


def _key_base(pairs: np.ndarray) -> int:
    return int(pairs.max()) + 1 if pairs.size else 1


def _pair_keys(pairs: np.ndarray) -> np.ndarray:
    """One int64 per row of ``pairs`` (k, 2) non-negative ints, ordered as the rows are lexicographically."""
    return pairs[:, 0].astype(np.int64) * _key_base(pairs) + pairs[:, 1]


def closes_up(E: np.ndarray) -> bool:
    """Whether directed edges close up: none appears twice, and each undirected edge in exactly two of them (in
    opposite directions, then); ``np.unique(axis=0)``'s answer, by one int64 a pair.

    Parameters
    ----------
    E : (k, 2) int
        Directed edges (vertex pairs), for example every triangle's three.

    Returns
    -------
    closed : bool
    """
    if _repeats_a_directed_edge(E):
        return False
    _, counts = np.unique(_pair_keys(np.sort(E, axis=1)), return_counts=True)
    return bool(np.all(counts == 2))


def _repeats_a_directed_edge(E: np.ndarray) -> bool:
    """Whether a directed edge (a row of ``E`` (k, 2)) appears twice: two triangles wound the same way across it."""
    directed = np.sort(_pair_keys(E))
    return bool(np.any(directed[1:] == directed[:-1]))


def check_closed_surface(F: np.ndarray, path=None) -> None:
    """Check that a surface is closed, 2-manifold and consistently oriented.

    Parameters
    ----------
    V : (n, 3) float64
    F : (f, 3) int64
    path : str, optional
        Named in the error message.

    Raises
    ------
    InputError
        With the number of boundary or non-manifold edges.
    """
    _, counts = edge_counts(F)
    boundary = int(np.sum(counts == 1))
    nonmanifold = int(np.sum(counts > 2))
    if boundary:
        raise InputError(
            path,
            f"surface is not closed: {boundary} boundary edges; close the holes "
            "(e.g. with a mesh repair tool) and try again",
        )
    if nonmanifold:
        raise InputError(path, f"surface is not manifold: {nonmanifold} edges are shared by more than two faces")
    if _repeats_a_directed_edge(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])):
        raise InputError(path, "surface is not consistently oriented: some neighbouring faces have opposite winding")


def check_mesh_arrays(V, F, path: str | os.PathLike | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Check that ``(V, F)`` is a triangle mesh and return it as float64 / int64 arrays.

    Parameters
    ----------
    V : (n, 3) or (n, 2) array_like of float
        Vertex positions; all finite.
    F : (f, 3) array_like of int
        Triangles, 0-based indices into ``V`` (integer-valued floats are accepted).
    path : str or os.PathLike, optional
        The file the mesh is for, named in the error message.

    Returns
    -------
    V : (n, 3) or (n, 2) float64
    F : (f, 3) int64

    Raises
    ------
    InputError
        With one line saying what is wrong: shapes, non-finite vertices,
        non-integer, negative or out-of-range face indices.
    """
    try:
        V = np.asarray(V, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(path, "vertices must be an (n, 3) array of numbers") from None
    try:
        F = np.asarray(F)
    except ValueError:  # ragged nested lists
        raise InputError(path, "faces must be an (f, 3) array of vertex indices") from None
    if V.ndim != 2 or V.shape[1] not in (2, 3) or len(V) == 0:
        raise InputError(path, f"vertices must be an (n, 3) or (n, 2) array, got shape {V.shape}")
    bad = np.flatnonzero(~np.isfinite(V).all(axis=1))
    if len(bad):
        raise InputError(path, f"vertex {bad[0]} has a NaN or infinite coordinate ({len(bad)} such vertices)")
    if F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
        raise InputError(path, f"faces must be an (f, 3) array of vertex indices, got shape {F.shape}")
    if F.dtype.kind == "f" and np.all(np.isfinite(F)) and np.all(F == np.round(F)):
        F = F.astype(np.int64)
    if F.dtype.kind not in "iu":
        raise InputError(path, f"face indices must be integers, got {F.dtype}")
    F = F.astype(np.int64, copy=False)
    bad = np.flatnonzero(((F < 0) | (F >= len(V))).any(axis=1))
    if len(bad):
        f = bad[0]
        raise InputError(path, f"face {f} ({' '.join(map(str, F[f]))}) refers to a vertex out of range "
                               f"0..{len(V) - 1} ({len(bad)} such faces)")
    return V, F


def check_not_flat(V: np.ndarray, F: np.ndarray, path: str | os.PathLike | None = None) -> None:
    """Refuse a mesh that has no size or encloses nothing (all its vertices on a point, a line or a plane).

    Parameters
    ----------
    V : (n, 2) or (n, 3) float64
    F : (f, 3) int64
    path : str or os.PathLike, optional
        Named in the message.

    Raises
    ------
    InputError
        ``the mesh has no size`` when its vertices are one point; ``the mesh
        is flat (no volume)`` when a closed surface encloses no volume, or a
        planar mesh covers no area (a closed surface squashed onto z = 0).
    """
    mask = np.zeros(len(V), bool)
    mask[np.asarray(F).ravel()] = True
    size = float(np.ptp(V[mask], axis=0).max())
    if not size > 0:
        raise InputError(path, "the mesh has no size: all its vertices are at one point; export it again")
    corners = V[F]
    if V.shape[1] == 2:
        e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
        enclosed = abs(float(np.sum(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))) / 2 / size ** 2
    else:
        enclosed = abs(float(np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum())) \
            / 6 / size ** 3
    if enclosed < 1e-9:
        raise InputError(path, "the mesh is flat (no volume): its vertices lie on a line or a plane; "
                               "export the closed surface of the model")


def write_mesh(path: str | os.PathLike, V: np.ndarray, F: np.ndarray) -> None:
    """Write a triangle mesh atomically, in the format the extension names.

    Parameters
    ----------
    path : str or os.PathLike
        ``.stl``, ``.obj``, ``.ply``, ``.off``, ``.3mf`` or ``.glb``.
    V : (n, 3) or (n, 2) float64
        Planar vertices are written with z = 0.
    F : (f, 3) int64

    Raises
    ------
    InputError
        For an unknown extension or arrays that are not a triangle mesh (see
        :func:`check_mesh_arrays`); nothing is written then.
    """
    import trimesh

    path = Path(path)
    ext = path.suffix.lower().lstrip(".")
    if ext not in MESH_FORMATS:
        raise InputError(path, f"unknown output format '.{ext}'; use one of {', '.join(MESH_FORMATS)}")
    V, F = check_mesh_arrays(V, F, path)
    if V.shape[1] == 2:
        V = np.column_stack([V, np.zeros(len(V))])
    with atomic_path(path) as tmp:
        if ext == "3mf":
            write_3mf(tmp, V, F)
        else:
            trimesh.Trimesh(V, F, process=False).export(str(tmp), file_type=ext)


# --------------------------------------------------------------------------- #
# TGF skeletons
# --------------------------------------------------------------------------- #
def _tgf_index(token: str) -> int:
    """A joint index of a TGF line; ValueError for one no skeleton has (over a billion: 31 digits overflow)."""
    value = int(token)
    if abs(value) >= 2**31:
        raise ValueError(token)
    return value


def read_tgf(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read a skeleton in libigl's TGF format.

    A joint section (``index x y z [extra columns]``), a line ``#``, a bone
    section (``i j [extra columns]``, 1-based joint indices) and optionally a
    final ``#``. Extra columns are ignored. Joints are placed by their index
    column (1..j, in any order); the skeleton is checked with
    :func:`check_skeleton`. A UTF-8 byte-order mark is skipped.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    joints : (j, 3) float64
        Joint positions, row ``i - 1`` for index ``i``.
    bones : (m, 2) int64
        0-based joint indices ``[root, tip]`` in file order.

    Raises
    ------
    InputError
        Missing file, malformed line, empty skeleton, index out of range,
        joint indices that are not 1..j, a skeleton that is not a tree.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(path, f"cannot read skeleton: {_one_line(exc)}") from None
    joints, index, bones, section = [], [], [], 0
    for lineno, line in enumerate(lines, 1):
        tokens = line.split()
        if not tokens:
            continue
        if tokens[0].startswith("#"):
            section += 1
            continue
        try:
            if section == 0:
                if len(tokens) < 4:
                    raise ValueError
                joints.append([float(t) for t in tokens[1:4]])
                index.append((_tgf_index(tokens[0]), lineno))
            elif section == 1:
                if len(tokens) < 2:
                    raise ValueError
                bones.append([_tgf_index(tokens[0]), _tgf_index(tokens[1])])
        except ValueError:
            what = "joint 'index x y z'" if section == 0 else "bone 'i j'"
            raise InputError(path, f"line {lineno} is not a {what} line: {line.strip()!r}") from None
    if not joints:
        raise InputError(path, "skeleton has no joints; a TGF file lists joints, then '#', then bones")
    if not bones:
        raise InputError(path, "skeleton has no bones; after the joints and a '#' line, list bones as 'i j'")
    J = np.array(joints, dtype=np.float64)
    given = np.array([i for i, _ in index])
    if sorted(given.tolist()) == list(range(len(J))):
        given = given + 1  # numbered from 0
    elif sorted(given.tolist()) != list(range(1, len(J) + 1)):
        counts = np.bincount(np.clip(given, 0, len(J) + 1), minlength=len(J) + 2)
        dup = np.flatnonzero(counts[1:len(J) + 1] > 1)
        if len(dup):
            lines_of = [n for i, n in index if i == dup[0] + 1]
            raise InputError(path, f"joint index {dup[0] + 1} appears on lines {lines_of[0]} and {lines_of[1]}; "
                                   f"number joints 1..{len(J)}, once each")
        i, n = next((i, n) for i, n in index if not 1 <= i <= len(J))
        raise InputError(path, f"line {n}: joint index {i} is not within 1..{len(J)}; number joints 1..{len(J)}")
    J[given - 1] = J.copy()
    B = np.array(bones, dtype=np.int64) - 1
    bad = np.flatnonzero((B < 0).any(1) | (B >= len(J)).any(1))
    if len(bad):
        i = bad[0]
        raise InputError(
            path,
            f"bone {i + 1} ({bones[i][0]} {bones[i][1]}) refers to a joint out of range 1..{len(J)}",
        )
    if np.any(B[:, 0] == B[:, 1]):
        i = int(np.flatnonzero(B[:, 0] == B[:, 1])[0])
        raise InputError(path, f"bone {i + 1} joins joint {bones[i][0]} to itself")
    if not np.all(np.isfinite(J)):
        raise InputError(path, "joint coordinates contain NaN or infinity")
    check_skeleton(J, B, path)
    return J, B


def write_tgf(path: str | os.PathLike, joints: np.ndarray, bones: np.ndarray) -> None:
    """Write a skeleton as TGF (1-based), atomically.

    Parameters
    ----------
    path : str or os.PathLike
    joints : (j, 2) or (j, 3) float64
        Planar joints are written with z = 0.
    bones : (m, 2) int64
        0-based.
    """
    J = np.asarray(joints, dtype=np.float64)
    if J.shape[1] == 2:
        J = np.column_stack([J, np.zeros(len(J))])
    out = [f"{i + 1} {x:.17g} {y:.17g} {z:.17g}" for i, (x, y, z) in enumerate(J)]
    out.append("#")
    out += [f"{a + 1} {b + 1}" for a, b in np.asarray(bones, dtype=np.int64)]
    out.append("#")
    write_text(path, "\n".join(out) + "\n")


# --------------------------------------------------------------------------- #
# libigl .mesh / .dmat
# --------------------------------------------------------------------------- #
def read_tet_mesh(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read a tetrahedral mesh in libigl/Medit ``.mesh`` format.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    V : (t, 3) float64
    T : (k, 4) int64
        0-based vertex indices.

    Raises
    ------
    InputError
        Missing or unreadable file, no tetrahedra, indices out of range.
    """
    import igl

    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    try:
        V, T, _ = igl.readMESH(str(path))
    except Exception as exc:
        raise InputError(path, f"cannot read tet mesh: {_one_line(exc)}") from None
    V = np.asarray(V, np.float64)
    T = np.asarray(T, np.int64)
    if len(T) == 0 or T.shape[1] != 4:
        raise InputError(path, "no tetrahedra found")
    if T.min() < 0 or T.max() >= len(V):
        raise InputError(path, "tetrahedra refer to vertices out of range")
    return V, T


def write_tet_mesh(path: str | os.PathLike, V: np.ndarray, T: np.ndarray, F: np.ndarray | None = None) -> None:
    """Write a tetrahedral mesh as ``.mesh``, atomically.

    Parameters
    ----------
    path : str or os.PathLike
    V : (t, 3) float64
    T : (k, 4) int64
        0-based.
    F : (f, 3) int64, optional
        Boundary triangles to store with them.
    """
    import igl

    F = np.zeros((0, 3), np.int64) if F is None else np.asarray(F, np.int64)
    with atomic_path(path) as tmp:
        igl.writeMESH(str(tmp), np.asarray(V, np.float64), np.asarray(T, np.int64), F)


def read_dmat(path: str | os.PathLike, shape: tuple[int | None, int | None] | None = None) -> np.ndarray:
    """Read a dense matrix in libigl's ``.dmat`` format.

    Parameters
    ----------
    path : str or os.PathLike
    shape : (rows, cols), optional
        Expected shape; ``None`` entries are not checked.

    Returns
    -------
    M : (rows, cols) float64

    Raises
    ------
    InputError
        Missing file, not an ASCII ``.dmat``, or not the expected shape.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    try:
        tokens = path.read_text().split()
        cols, rows = int(tokens[0]), int(tokens[1])
        data = np.array([float(t) for t in tokens[2 : 2 + rows * cols]])
        if data.size != rows * cols:
            raise ValueError("file ends early")
    except (ValueError, IndexError, UnicodeDecodeError) as exc:
        raise InputError(path, f"not an ASCII .dmat matrix ({_one_line(exc)})") from None
    M = data.reshape(cols, rows).T  # column-major
    if shape is not None:
        for axis, (want, got) in enumerate(zip(shape, M.shape)):
            if want is not None and want != got:
                raise InputError(
                    path,
                    f"matrix is {M.shape[0]}x{M.shape[1]} but {shape[0] or '?'}x{shape[1] or '?'} was expected "
                    f"({'one row per vertex' if axis == 0 else 'one column per bone'})",
                )
    return M


def write_dmat(path: str | os.PathLike, M: np.ndarray) -> None:
    """Write a dense matrix as ASCII ``.dmat`` (column-major, ``%.17g``: exact), atomically.

    Parameters
    ----------
    path : str or os.PathLike
    M : (rows, cols) float64
        A 1-D array is written as one row.
    """
    M = np.atleast_2d(np.asarray(M, np.float64))
    body = "\n".join(f"{x:.17g}" for x in M.T.ravel())
    write_text(path, f"{M.shape[1]} {M.shape[0]}\n{body}\n")
