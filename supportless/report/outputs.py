"""The files of a result: the posed mesh (or glTF asset), the mesh standing, the pose, the pictures, the report.

One writer for every command that hands a result back (``optimize``, ``demo``,
``batch``): meshes in the print frame (+Z up, millimetres, on the plate), a
glTF rig's posed asset as glTF, each file written atomically by the writers
of :mod:`supportless.files`.
"""

from __future__ import annotations

import os
from typing import Callable

import numpy as np

from ..base.progress import step
from ..files.gltf import is_gltf, posed_joint_transforms, write_posed_gltf
from ..files.meshes import read_mesh, write_json, write_mesh
from ..copyleft.cgal import intersecting_faces
from ..files.printbody import united_surface
from ..search.result import at_full_resolution
from ..files.posefile import write_pose
from ..files.printframe import PrintFrame
from ..files.watertight import apart_by_a_hair, manifold_check
from .report import write_pictures

__all__ = ["pictures_step", "write_posed", "write_result"]


def write_posed(path: str | os.PathLike, rig, angles: np.ndarray, standing: np.ndarray, vertices: np.ndarray,
                frame: PrintFrame) -> str:
    """Write a posed model: the posed asset for a glTF rig written as .glb/.gltf, else the mesh ``vertices``.

    Parameters
    ----------
    path : path
        The file; its extension says the format.
    rig : Rig
    angles : (m, 3) float64
        The pose.
    standing : (n, d) float64
        The posed surface as it stands on the plate.
    vertices : (n, d) float64
        The surface to write (``standing``, or turned as printed).
    frame : PrintFrame
        A mesh file is written in it (+Z up, mm, on the plate, centred); a
        .glb of a mesh that came without glTF in glTF's own frame (+Y up, metres).

    Returns
    -------
    kind : str
        What was written: ``"glTF asset, standing (its skin posed)"``,
        ``"mesh, as printed"`` or ``"mesh"``.
    """
    source = rig.info.get("gltf")
    if source is not None and is_gltf(path):
        offset = (standing - rig.pose(angles))[0]
        T = posed_joint_transforms(rig.transforms(angles), np.asarray(source["driver"]), source["scale"], offset)
        write_posed_gltf(source["path"], path, T, np.asarray(source["joint_nodes"]))
        return "glTF asset, standing (its skin posed)"
    placed = frame.to_gltf(vertices) if is_gltf(path) and rig.dim == 3 else frame.place(vertices)
    faces = rig.faces
    united = ""
    if rig.dim == 3:  # parts pressed together (an arm resting on the torso) print as one solid
        placed, faces, merged = united_surface(placed, faces)
        if merged["pairs"]:
            united = f", one solid ({merged['how']}: {merged['pairs']} crossing pairs merged)"
            vertical = 1 if is_gltf(path) else 2  # a remeshed solid's lowest point back on the plate
            placed[:, vertical] -= placed[:, vertical].min()
    if rig.dim == 3:  # parts that touch along an edge or at a corner: each part's corner a hair onto its side
        apart, moved = apart_by_a_hair(placed, faces)
        if moved and len(intersecting_faces(apart, faces)) <= len(intersecting_faces(placed, faces)):
            placed = apart
            united += f", {moved} corners shared by touching parts moved apart by a hair"
    write_mesh(path, placed, faces)
    return ("mesh, as printed" if vertices is not standing else "mesh") + united + (
        _as_read(path) if rig.dim == 3 else "")


def _as_read(path) -> str:
    """``""`` when the written file reads back closed (every edge in two triangles), else a warning clause."""
    V, F = read_mesh(path)
    found = manifold_check(V, F, None)  # read_mesh welded the file's corners as they are stored
    if found["closed"]:
        return ""
    return (f"; warning: read back, {found['open_edges']} edges are in one triangle and {found['shared_edges']} in "
            "more than two (not a closed solid)")


def pictures_step(folder, rig, result, report) -> list[tuple[str, str]]:
    """:func:`~supportless.report.report.write_pictures`, announced as a step."""
    with step("drawing the pictures"):
        return write_pictures(folder, rig, result, report)


def write_result(rig, result, report: dict, frame: PrintFrame, *, output=None, upright=None, pose=None,
                 pictures=None, report_path=None, standing=None) -> tuple[list[tuple[str, str]], list[tuple[str, OSError]]]:
    """Write the files of ``result`` that are asked for; a file that cannot be written does not stop the others.

    Parameters
    ----------
    rig : Rig
    result : PoseResult
    report : dict
        :func:`supportless.report.report.build_report`'s.
    frame : PrintFrame
        The print frame of the meshes.
    output, upright, pose, pictures, report_path : path, optional
        The posed mesh as printed, the posed mesh standing, the pose file, the
        pictures' folder and the report; ``None`` skips one.
    standing : path, optional
        The best answer printed standing (``report["standing"]``, :func:`supportless.report.report.standing_answer`),
        as it stands; the answer itself when it is that one or the search weighed no others.

    Returns
    -------
    written : list of (str, str)
        ``(what, path)`` of each file written.
    failed : list of (str, OSError)
        ``(path, error)`` of each file that could not be written.
    """
    def posed(path, vertices, standing_label=False):
        with step(f"writing {os.path.basename(path)}"):
            kind = write_posed(path, rig, result.angles, result.vertices, vertices, frame)
        return [(f"posed {kind.replace('as printed', 'standing') if standing_label else kind}", path)]

    def posed_standing(path):
        info = report.get("standing")
        answer = result if not info or info["is_answer"] else \
            at_full_resolution(rig, result.choice.candidates[info["index"]].result)
        with step(f"writing {os.path.basename(path)}"):
            kind = write_posed(path, rig, answer.angles, answer.vertices, answer.vertices, frame)
        return [(f"best standing answer: {kind}", path)]

    def pose_file():
        extra = {"objective": result.value, "print_frame": frame.to_dict()}
        if rig.labels is not None:
            extra["bone_names"] = rig.bone_names()
        write_pose(pose, result.angles, rig.bones, rig.joints, extra=extra, rotation=result.rotation, tree=rig.tree)
        return [("pose", pose)]

    def report_file():
        write_json(report_path, report)
        return [("report", report_path)]

    steps: list[tuple[object, Callable[[], list]]] = [
        (output, lambda: posed(output, result.print_vertices)),
        (upright, lambda: posed(upright, result.vertices, standing_label=True)),
        (standing, lambda: posed_standing(standing)),
        (pose, pose_file), (pictures, lambda: pictures_step(pictures, rig, result, report)),
        (report_path, report_file)]
    written, failed = [], []
    for path, write in steps:
        if not path:
            continue
        try:
            written += write()
        except OSError as exc:
            failed.append((str(exc.filename or path), exc))
    return written, failed
