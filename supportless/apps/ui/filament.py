"""The support figure the panel leads with: filament, as a slicer user reads it.

A slicer says how much support filament it lays down (mm and grams), not the
solid volume of the preview's columns, which weighs far more (the Fox at rest:
34 g of columns, 14 g of PrusaSlicer's support). So the panel leads with the figure the command line's summary prints: PrusaSlicer's
support filament as the slicer model predicts it
(:func:`supportless.report.report.predicted_filament_mm`, its grams by
:func:`~supportless.report.report.filament_grams`), labelled an estimate. After
the Slice button measured the very pose shown, the slicer's own figure leads
and the estimate stays beside it. The rest pose's estimate is computed once
per rig, threshold and height, so an edit costs one pose's estimate.
"""

from __future__ import annotations

import weakref

import numpy as np

from ...base.geometry import place_on_plate, print_pose
from ...report.report import filament_grams, predicted_filament_mm, reduction, slicer_label

__all__ = ["predicted_figure", "sliced_figure", "sliced_this_pose", "slice_meshes", "support_lead"]

#: The rest pose's predicted filament, mm, of each open rig: ``{rig: {(threshold, height): mm}}``.
_REST_MM: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _figure(source: str, mm: float, g: float | None, rest_mm: float, rest_g: float | None,
            height_mm: float) -> dict:
    return {"source": source, "mm": float(mm), "g": None if g is None else float(g), "rest_mm": float(rest_mm),
            "rest_g": None if rest_g is None else float(rest_g), "reduction_percent": reduction(rest_mm, mm),
            "height_mm": float(height_mm)}


def _rest_mm(rig, overhang_angle: float, height_mm: float) -> float:
    """The rest pose's predicted filament (standing on the plate, as the summary's ``before``), once per rig."""
    known = _REST_MM.setdefault(rig, {})
    key = (float(overhang_angle), float(height_mm))
    if key not in known:
        rest = place_on_plate(rig.vertices, np.asarray(rig.up, np.float64))
        known[key] = float(predicted_filament_mm(rig, rest, overhang_angle, height_mm))
    return known[key]


def predicted_figure(rig, printed: np.ndarray, overhang_angle: float, height_mm: float) -> dict | None:
    """The support filament the command line's summary predicts for a pose as printed, and for the rest pose.

    Parameters
    ----------
    rig : supportless.rig.rig.Rig
    printed : (n, 3) float64
        The posed surface as printed: turned by its print rotation, on the plate (model units).
    overhang_angle : float
        The printer's threshold, degrees (the settings' ``overhang_angle``).
    height_mm : float
        The rest pose's printed height (the print frame's).

    Returns
    -------
    figure : dict or None
        ``source`` ("estimate"), ``mm`` and ``g`` (the pose's filament), ``rest_mm`` and ``rest_g`` (the rest
        pose's), ``reduction_percent`` (rest -> pose; None when the rest pose needs none) and ``height_mm``;
        None for a planar rig.
    """
    mm = predicted_filament_mm(rig, printed, overhang_angle, height_mm)
    if mm is None:
        return None
    rest = _rest_mm(rig, overhang_angle, height_mm)
    return _figure("estimate", mm, filament_grams(mm), rest, filament_grams(rest), height_mm)


def sliced_figure(report: dict) -> dict:
    """A Slice's figures (:class:`~supportless.apps.ui.slicerun.SliceRun`) as :func:`predicted_figure` gives its own.

    ``source`` names the slicer (:func:`~supportless.report.report.slicer_label`: ``PrusaSlicer``, ``Cura``, ...);
    ``mm``/``g`` are the pose's support filament, ``rest_mm``/``rest_g`` the rest pose's.
    """
    b, a = report["before"], report["after"]
    return _figure(slicer_label(report), a["support_mm"], a.get("support_g"), b["support_mm"], b.get("support_g"),
                   report.get("height_mm") or 0.0)


def sliced_this_pose(report: dict | None, angles: np.ndarray, rotation: np.ndarray) -> bool:
    """Whether a Slice's report is of this very pose and print rotation (its ``pose``, :func:`slice_meshes`)."""
    pose = (report or {}).get("pose")
    return pose is not None and np.array_equal(pose[0], angles) and np.array_equal(pose[1], rotation)


def _measured(report: dict) -> bool:
    """Whether a Slice's report has both support lengths (a slicer's non-finite figure is None)."""
    return report["before"].get("support_mm") is not None and report["after"].get("support_mm") is not None


def slice_meshes(state) -> dict:
    """What the Slice button slices: the rest pose and the current pose as printed, in millimetres.

    Parameters
    ----------
    state : supportless.apps.ui.state.EditorState

    Returns
    -------
    meshes : dict
        :meth:`~supportless.apps.ui.slicerun.SliceRun.start`'s ``rest`` and ``posed`` (each ((n, 3) float64,
        (f, 3) int64), on the plate in the print frame: +Z up, millimetres) and ``pose`` (the angles and print
        rotation ``posed`` is of, read once: a search streaming poses cannot split them).
    """
    rig, frame = state.rig, state.print_frame
    angles, R = state.get_pose()
    posed = frame.place(print_pose(rig.pose(angles), R, rig.up))
    return {"rest": (frame.place(rig.vertices), rig.faces), "posed": (posed, rig.faces), "pose": (angles, R)}


def support_lead(state, angles: np.ndarray, rotation: np.ndarray, vertices: np.ndarray | None = None,
                 slice_report: dict | None = None) -> dict | None:
    """The support figure the panel leads with, for a pose as printed.

    Parameters
    ----------
    state : supportless.apps.ui.state.EditorState
        The rig, the printer's threshold (its settings) and the print frame's height.
    angles : (m, 3) float64
    rotation : (3, 3) float64
        The print rotation.
    vertices : (n, 3) float64, optional
        ``rig.pose(angles)`` (standing) when the caller has it.
    slice_report : dict, optional
        The last Slice's report (with its ``pose``).

    Returns
    -------
    lead : dict or None
        The slicer's figure (:func:`sliced_figure`) when ``slice_report`` is of this pose, else the estimate
        (:func:`predicted_figure`); with ``estimate`` (the estimate's figure when the slicer leads, else None) and
        ``other_slice`` (a Slice of another pose is not shown). None for a planar rig.
    """
    rig = state.rig
    V = rig.pose(angles) if vertices is None else vertices
    estimate = predicted_figure(rig, print_pose(V, rotation, rig.up), state.settings.overhang_angle,
                                state.print_frame.height_mm)
    if estimate is None:
        return None
    if sliced_this_pose(slice_report, angles, rotation) and _measured(slice_report):
        return sliced_figure(slice_report) | {"estimate": estimate, "other_slice": False}
    return estimate | {"estimate": None, "other_slice": slice_report is not None}
