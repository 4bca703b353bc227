"""Loading a rig from files: the model read (a mesh, a rigged glTF asset or a built-in figure), its skeleton read
or built from the shape, its printing direction chosen, and the prepared rig kept in the on-disk cache keyed by a
hash of the inputs and settings, so loading the same model again takes a fraction of a second."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from ..base.errors import InputError
from ..base.geometry import parse_up
from ..base.progress import step
from ..files.meshes import read_dmat, read_mesh, read_tet_mesh, read_tgf
from ..files.solid import closed_solid
from ..files.upaxis import guess_up
from .cache import (
    default_cache_dir,
    gltf_cache_file,
    read_entry,
    read_skeleton,
    rig_cache_key,
    skeleton_cache_file,
    write_entry,
    write_skeleton,
)
from .rig import SAMPLES_PER_BONE, Rig, prepare_rig
from .weights import BBW_ITERATIONS

__all__ = ["load_rig"]


def load_rig(model, skeleton=None, up="auto", *, cache: bool = True, cache_dir=None, tets=None, weights=None,
             samples_per_bone: int = SAMPLES_PER_BONE, bbw_iterations: int = BBW_ITERATIONS,
             progress=None, height_mm: float | None = None, bones=None, skeleton_out=None) -> Rig:
    """Read a model and its skeleton and prepare (or load from the cache) its rig.

    Parameters
    ----------
    model : str or os.PathLike
        Surface mesh file (OBJ, STL, PLY, OFF, 3MF, GLB), a rigged glTF/GLB
        asset (with no ``skeleton``: its skin is read, see
        :func:`~supportless.files.gltf.load_gltf_character`), or ``"demo:NAME"`` for a built-in figure
        (then ``skeleton`` is not needed).
    skeleton : str or os.PathLike
        TGF skeleton. Defaults to the model's path with ``.tgf``; when there
        is no such file (or with ``"auto"``) a skeleton is built from the shape
        (:func:`supportless.rig.autoskeleton.auto_skeleton`, said in
        ``info["warnings"]``).
    up : str or sequence of float
        Printing direction (:func:`~supportless.base.geometry.parse_up`), or ``"auto"``: the file format's
        convention or the model's flat base (:func:`~supportless.files.upaxis.guess_up`; glTF and the built-in
        figures +Y); the line saying which is ``info["up"]``.
    cache : bool
        Use the on-disk cache.
    cache_dir : str or os.PathLike, optional
        Defaults to :func:`default_cache_dir`.
    tets : str or os.PathLike, optional
        Precomputed libigl ``.mesh`` volume mesh.
    weights : str or os.PathLike, optional
        Precomputed ``.dmat`` weights on the ``tets`` vertices (t rows, m
        columns); for a glTF asset ``"skin"`` (default: the file's skin
        weights) or ``"bbw"`` (bounded biharmonic weights recomputed).
    samples_per_bone, bbw_iterations : int
        See :func:`prepare_rig`.
    progress : callable(str), optional
    height_mm : float, optional
        Scale the model so its height along ``up`` is this many millimetres
        (default: as read; a glTF asset's metres become millimetres).
    bones : int or (int, int), optional
        A skeleton built from the shape: about how many bones (:func:`~supportless.rig.autoskeleton.auto_skeleton`).
    skeleton_out : str or os.PathLike, optional
        Write the skeleton used there (TGF, the file's units), e.g. a built one to edit and pass back.

    Returns
    -------
    rig : Rig
    """
    from ..files.gltf import is_gltf, load_gltf_character

    surface_weights = labels = source = None
    up_note = None
    notes: list[str] = []  # a damaged cache entry, said on the rig prepared again
    if isinstance(model, str) and model.startswith("demo:"):
        from ..shapes import demo_figure

        figure = model.split(":", 1)[1]
        V, F, J, B = demo_figure(figure)
        up = "y" if _is_auto(up) else up
        name, mesh_path, skel_path = figure, None, None
    elif skeleton is None and is_gltf(model):
        mesh_path, skel_path, name = Path(model), Path(model), Path(model).stem
        if weights not in (None, "skin", "bbw"):
            raise InputError(weights, "a glTF model takes --weights skin (its own, the default) or --weights bbw")
        if tets is not None:
            raise InputError(tets, "--tets does not go with a glTF model's skin; leave it out")
        up = "y" if _is_auto(up) else up
        # keyed by the file's bytes, so a cached rig skips reading the skin and making the print body
        file = gltf_cache_file(mesh_path, cache_dir, weights or "skin", height_mm, up, samples_per_bone,
                                bbw_iterations)
        if cache and (rig := _try_cached(file, name, notes)) is not None and "gltf" in rig.info:
            rig.info["gltf"]["path"] = str(mesh_path)  # the same bytes may have moved
            rig.info["up"] = up_note
            return rig
        V, F, J, B, surface_weights, labels, source = load_gltf_character(mesh_path, progress=progress)
        if weights == "bbw":
            surface_weights = None
        weights = None
    else:
        mesh_path = Path(model)
        skel_path = Path(skeleton) if skeleton not in (None, "auto") else mesh_path.with_suffix(".tgf")
        with step("reading the mesh"):
            V, F = read_mesh(mesh_path)
            V, F = closed_solid(V, F, mesh_path, notes)
        if _is_auto(up):
            up, up_note = guess_up(V, F, mesh_path) if V.shape[1] == 3 and np.any(V[:, 2] != 0) else ("y", None)
        if skeleton == "auto" or (skeleton is None and not skel_path.exists()):
            from .autoskeleton import auto_skeleton, planar_skeleton

            if progress:
                progress("building a skeleton from the shape")
            planar = V.shape[1] == 2 or np.all(V[:, 2] == 0)
            kept = skeleton_cache_file(V, F, parse_up(up, 3), bones, cache_dir)
            found = read_skeleton(kept) if cache else None
            if found is None:
                J, B = (planar_skeleton if planar else auto_skeleton)(V, F, parse_up(up, 3), bones)
                if cache:
                    write_skeleton(kept, J, B)
            else:
                J, B = found
            skel_path = None
            notes.append(f"no skeleton given: built one from the shape, {len(B)} bones "
                         "(--skeleton-out FILE.tgf keeps it to edit and pass back with --skeleton)")
        else:
            J, B = read_tgf(skel_path)
        name = mesh_path.stem
    if skeleton_out is not None:
        from ..files.meshes import write_tgf

        try:
            write_tgf(skeleton_out, J, B)
        except OSError as exc:
            raise InputError(skeleton_out, f"cannot write the skeleton: {exc.strerror or exc}") from None
    if height_mm is not None:
        h = np.ptp(V @ parse_up(up, V.shape[1]))
        if not h > 0:
            raise InputError(mesh_path, "the model has no height along the printing direction")
        factor = float(height_mm) / h
        V, J = V * factor, J * factor
        if source is not None:
            source["scale"] *= factor
    settings = dict(samples_per_bone=samples_per_bone, bbw_iterations=bbw_iterations)
    if surface_weights is not None:
        settings["skin"] = hashlib.sha256(np.ascontiguousarray(surface_weights).tobytes()).hexdigest()
        settings["labels"] = "|".join(labels)
    tet_arrays = read_tet_mesh(tets) if tets is not None else None
    W = None
    if weights is not None:
        if tet_arrays is None:
            raise InputError(weights, "precomputed weights need the tet mesh they were computed on (--tets)")
        W = read_dmat(weights, (len(tet_arrays[0]), len(B)))
    if tet_arrays is not None:
        h = hashlib.sha256(np.ascontiguousarray(tet_arrays[0], np.float64).tobytes())
        h.update(np.ascontiguousarray(tet_arrays[1], np.int64).tobytes())
        settings["tets"] = h.hexdigest()
    if W is not None:
        settings["weights"] = hashlib.sha256(W.tobytes()).hexdigest()
    if source is None:
        planar = V.shape[1] == 2 or (np.all(V[:, 2] == 0) and np.all(J[:, 2] == 0))
        key = rig_cache_key(V, F, J, B, np.resize(parse_up(up, 2 if planar else 3), 3) * [1, 1, not planar],
                            **settings)
        file = (Path(cache_dir) if cache_dir is not None else default_cache_dir()) / f"rig-{key}.npz"
        if cache and (rig := _try_cached(file, name, notes)) is not None:
            rig.info["warnings"] = list(rig.info.get("warnings", [])) + notes
            rig.info["up"] = up_note
            return rig
    try:
        rig = prepare_rig(V, F, J, B, up, name=name, samples_per_bone=samples_per_bone, bbw_iterations=bbw_iterations,
                          tet_mesh=tet_arrays, tet_weights=W, mesh_path=mesh_path, skeleton_path=skel_path,
                          progress=progress, surface_weights=surface_weights, labels=labels,
                          pivots_only=source is not None)
    except InputError as exc:
        if source is None or surface_weights is not None:
            raise
        raise InputError(mesh_path, f"{exc.reason}; with --weights bbw the bones must fit inside the body: use "
                         "the file's own skin weights (leave --weights out)") from None
    if source is not None:
        rig.info["gltf"] = source
        rig.info["warnings"] = list(source["log"]) + list(rig.info.get("warnings", []))
    rig.info["from_cache"] = False
    if cache:
        try:
            write_entry(file, rig)
            rig.info["cache"] = str(file)
        except OSError as exc:
            rig.info["cache"] = None
            rig.info.setdefault("warnings", []).append(
                f"the rig cache {file.parent} cannot be written ({exc.strerror or exc}): the rig is prepared again "
                f"next time; --cache-dir DIR chooses another folder")
    rig.info["warnings"] = list(rig.info.get("warnings", [])) + notes  # after the entry: said once
    rig.info["up"] = up_note
    return rig


def _is_auto(up) -> bool:
    return isinstance(up, str) and up.strip().lower() == "auto"


def _try_cached(file: Path, name: str, notes: list[str]) -> Rig | None:
    """The rig cached in ``file``, or None (missing or damaged: a damaged entry is recomputed, with a note)."""
    fields = read_entry(file, notes)
    if fields is None:
        return None
    rig = Rig(**fields, name=name)
    rig.info["cache"] = str(file)
    rig.info["from_cache"] = True
    return rig
