"""Reports of a pose: support before and after, distortion, intersections.

:func:`pose_measures` measures one pose (the command line's report and the
browser app's panel both use it); :func:`build_report` puts the rest pose and
a search's pose side by side as the JSON report of ``optimize``;
:func:`write_pictures` draws them. :func:`predicted_filament_mm` (with
:func:`filament_grams`) is the support filament estimate the summary and the
browser app's panel both lead with.
"""

from __future__ import annotations

import copy
import dataclasses
import datetime as _dt
import os
import platform
from pathlib import Path

import numpy as np

from ..base.geometry import place_on_plate, print_pose, print_transform
from ..copyleft.cgal import intersecting_face_pairs
from ..energies.intersection import self_intersection_volume
from ..energies.overhang import overhang_measures, risky_faces
from ..energies.slicer_model import predicted_support_mm
from ..energies.support import support_volume
from ..files.printer import DEFAULT_DENSITY, FILAMENT_DIAMETER_MM, mm_to_cm3, reduction, slicer_label
from ..energies.footprint import footprint_area
from ..energies.materials import MATERIALS
from ..energies.strength import HANDLING_LOAD_N, Strength
from ..files.printframe import REFERENCE_HEIGHT_MM, PrintFrame, rig_print_frame
from ..search.naturalness import naturalness
from ..search.orientation import print_direction, rotation_axis_angle
from ..search.sturdiness import pose_strength
from .render import plot_convergence, render_before_after
from .weakness import LEGEND, weak_face_colors, weakest_caption

__all__ = ["REFERENCE_HEIGHT_MM", "build_report", "duration_text", "filament_grams", "pose_measures",
           "predicted_filament_mm", "predicted_slicer", "reduction", "slicer_label", "strength_line",
           "strength_summary", "support_headline", "weakest_section", "write_pictures"]


def _support_measures(V, faces, up, angle, resolution) -> dict:
    prism, area = overhang_measures(V, faces, up, angle)
    return {"support_prism": float(prism), "support_column": float(support_volume(V, faces, up, angle, resolution)),
            "risky_area": float(area)}


def pose_measures(objective, angles: np.ndarray, exact: bool = True, overhang_angle: float | None = None,
                  vertices: np.ndarray | None = None, rotation: np.ndarray | None = None) -> dict:
    """Everything a report says about one pose.

    Parameters
    ----------
    objective : supportless.search.objective.Objective
        The objective the search minimises; its value and terms are reported.
    angles : (m, 3) float64
    exact : bool
        Also count intersecting face pairs exactly (CGAL; slower). 2D meshes
        report -1.
    overhang_angle : float, optional
        Threshold of the support measures (default: the objective's).
    vertices : (n, d) float64, optional
        ``objective.rig.pose(angles)`` when the caller has it already.
    rotation : (d, d) float64, optional
        The print rotation: the support measures (and the objective) are
        then those of the print frame, and ``upright`` holds the support
        measures of the pose as it stands.

    Returns
    -------
    measures : dict
        ``arap`` (raw distortion); the two support estimates ``support_prism``
        (the paper's overhang energy,
        :func:`~supportless.energies.overhang.overhang_energy`) and
        ``support_column`` (:func:`~supportless.energies.support.support_volume`);
        ``self_intersection_volume``, ``risky_area``, the normalised ``terms``
        and ``objective``, contact and balance (``new_contact_vertices``,
        ``stability_margin``, ``stands``, ``centre_of_mass``; see
        :meth:`supportless.search.standing.Standing.measures`), and
        ``intersecting_face_pairs`` (when ``exact``). Contact, balance and
        distortion are always judged as the pose stands.
    """
    rig = objective.rig
    V = rig.pose(angles) if vertices is None else vertices
    value, terms, raw = objective.evaluate(angles, rotation)
    angle = objective.overhang_angle if overhang_angle is None else overhang_angle
    printed = V if rotation is None else V @ np.asarray(rotation, np.float64).T
    out = {
        "objective": float(value),
        "terms": {k: float(v) for k, v in terms.items()},
        "arap": float(raw["arap"]),
        "overhang_angle": float(angle),
        **_support_measures(printed, rig.faces, rig.up, angle, objective.resolution),
        "self_intersection_volume": _intersection_volume(objective, angles, V, raw, vertices is None),
    }
    if rotation is not None:
        out["upright"] = _support_measures(V, rig.faces, rig.up, angle, objective.resolution)
    out |= objective.standing.measures(rig.transforms(angles), V)
    if exact:
        out["intersecting_face_pairs"] = intersecting_face_pairs(V, rig.faces)
    return out


def _intersection_volume(objective, angles: np.ndarray, V: np.ndarray, raw: dict, posed_here: bool) -> float:
    """The self-intersection volume of ``V`` (n, d) float64, the pose ``angles`` (m, 3) float64: the objective's own
    measure ``raw["intersection"]`` when it measured this very surface (``rig.pose(angles)``, bit for bit, with the
    default kernel), else measured."""
    rig = objective.rig
    if objective.backend == "fast" and (posed_here or np.array_equal(V, rig.pose(angles))):
        return float(raw["intersection"])
    return float(self_intersection_volume(V, rig.faces, rig.up, objective.resolution))


#: The printed height the report's predicted slicer filament is for when no print frame is given, mm.


def predicted_slicer(rig, result, height_mm: float = REFERENCE_HEIGHT_MM) -> dict | None:
    """PrusaSlicer's support filament for the rest pose and the found pose, as the slicer model predicts it.

    Parameters
    ----------
    rig : Rig
    result : supportless.search.optimizer.PoseResult
    height_mm : float
        The rest pose is printed this tall; the found pose at the same scale.

    Returns
    -------
    prediction : dict or None
        ``height_mm``, ``threshold_deg``, ``before_mm``, ``after_mm`` (support
        filament, mm of 1.75 mm filament) and ``reduction`` (a fraction,
        rest -> found; None when the rest pose needs none); None for planar rigs.
    """
    angle = float(result.settings.overhang_angle)
    rest = place_on_plate(rig.vertices, np.asarray(rig.up, np.float64))
    predicted = predicted_filament_mm(rig, np.stack([rest, result.print_vertices]), angle, height_mm)
    if predicted is None:
        return None
    before, after = predicted
    return {"height_mm": float(height_mm), "threshold_deg": angle, "before_mm": float(before),
            "after_mm": float(after), "reduction": None if before <= 0 else float(1.0 - after / before)}


def predicted_filament_mm(rig, print_vertices: np.ndarray, overhang_angle: float,
                          height_mm: float = REFERENCE_HEIGHT_MM) -> np.ndarray | float | None:
    """PrusaSlicer's support filament of poses as printed, as the slicer model predicts it, at a printed height.

    The one estimate the summary (:func:`predicted_slicer`) and the browser app's panel lead with.

    Parameters
    ----------
    rig : Rig
    print_vertices : (P, n, 3) or (n, 3) float64
        Posed surfaces of ``rig`` in the print frame, on the plate, model units.
    overhang_angle : float
        The printer's threshold, degrees.
    height_mm : float
        The rest pose is printed this tall; the poses at the same scale.

    Returns
    -------
    filament_mm : (P,) float64 or float or None
        mm of 1.75 mm filament; None for a planar rig or one with no height.
    """
    if rig.dim != 3:
        return None
    up = np.asarray(rig.up, np.float64)
    extent = float(np.ptp(rig.vertices @ up))
    if not extent > 0:
        return None
    return predicted_support_mm(print_vertices, rig.faces, up, float(overhang_angle), float(height_mm) / extent)


def filament_grams(mm: float) -> float:
    """Grams of ``mm`` of 1.75 mm filament at the default density: the grams beside a predicted length."""
    return float(mm_to_cm3(mm, FILAMENT_DIAMETER_MM) * DEFAULT_DENSITY)


def build_report(rig, result, frame: PrintFrame | None = None) -> dict:
    """The JSON report of a pose search: the rest pose and the found pose side by side.

    Parameters
    ----------
    rig : Rig
    result : supportless.search.optimizer.PoseResult
    frame : PrintFrame, optional
        How the files are printed (default: :func:`~supportless.files.printframe.rig_print_frame`,
        the rest pose 60 mm tall): the predicted slicer figures are for its height.

    Returns
    -------
    report : dict
        Sizes (``measured_faces``: the triangles the measures were taken on, fewer than ``faces`` for a
        sculpt, :meth:`~supportless.rig.rig.Rig.measure_rig`, whose exact pair counts are still the full
        surface's: the rest pose's and the file's), ``before``/``after`` measures (:func:`pose_measures` at the
        printer's threshold ``result.settings.overhang_angle``), their
        ``reduction_percent``, ``predicted_slicer`` (:func:`predicted_slicer`:
        the support filament PrusaSlicer is predicted to lay down at the
        frame's height) and its ``predicted_slicer_reduction`` (a fraction),
        ``support`` (:func:`support_headline`: the one support figure a user
        reads), ``print_frame`` (the files' frame and scale), the ``print_rotation`` and which ``frames``
        the figures are in, the largest and RMS vertex displacement, each
        bone's rotation (one angle, degrees) and the largest, the Euler
        angles, runtime, settings and convergence history; ``choice``
        (:meth:`supportless.search.choice.Choice.to_dict`: every answer weighed, its
        kind, predicted and sliced support, and who chose which and why), or
        None when the search's own best was returned unweighed; ``footprint``
        (:func:`footprint_summary`: the plate contact of the rest pose and the answer); ``strength``
        (:func:`strength_summary`: the weakest section of the rest pose and of the answer as printed; a
        sculpt's on the surface its answers were weighed on, as the choice's).

        ``before`` is the rest pose as it stands; ``after`` is the found
        pose in its print orientation (support counted there), with
        ``after["upright"]`` the support of the same pose as it stands.
    """
    objective, angle = result.objective, result.settings.overhang_angle
    R = np.asarray(result.rotation, np.float64)
    reduced = objective.rig is not rig and len(objective.rig.faces) != len(rig.faces)  # a sculpt's measures
    before = pose_measures(objective, rig.rest_angles(), exact=not reduced, overhang_angle=angle)
    after = pose_measures(objective, result.angles, exact=not reduced, overhang_angle=angle, rotation=R)
    if reduced and rig.dim == 3:  # the exact counts are the full surface's: the rest pose's and the file's
        for measures, key, V in ((before, "rest_pairs", rig.vertices), (after, "written_pairs", result.print_vertices)):
            measures["intersecting_face_pairs"] = getattr(result.written, key, None)  # None before the last gate
            if measures["intersecting_face_pairs"] is None:
                measures["intersecting_face_pairs"] = intersecting_face_pairs(V, rig.faces)
    axis, degrees = rotation_axis_angle(R)
    displacement = np.linalg.norm(rig.pose(result.angles) - rig.vertices, axis=1)
    height = float(np.ptp(rig.vertices @ rig.up))
    turned = np.degrees(objective.prior.angles(result.angles))
    frame = rig_print_frame(rig) if frame is None else frame
    if reduced:  # a sculpt's predicted support on the surface its answers were weighed on
        posed = place_on_plate(objective.rig.pose(result.angles), rig.up)
        predicted = predicted_slicer(objective.rig, dataclasses.replace(result, print_vertices=print_pose(
            posed, R, rig.up)), frame.height_mm)
    else:
        predicted = predicted_slicer(rig, result, frame.height_mm)
    report = {
        "model": rig.name,
        "vertices": int(len(rig.vertices)),
        "faces": int(len(rig.faces)),
        "measured_faces": int(len(objective.rig.faces)),
        "bones": int(rig.bone_count),
        "dimension": int(rig.dim),
        "up": rig.up.tolist(),
        "before": before,
        "after": after,
        "reduction_percent": {
            "support_prism": reduction(before["support_prism"], after["support_prism"]),
            "support_column": reduction(before["support_column"], after["support_column"]),
            "risky_area": reduction(before["risky_area"], after["risky_area"]),
        },
        "predicted_slicer": predicted,
        "predicted_slicer_reduction": None if predicted is None else predicted["reduction"],
        "print_frame": frame.to_dict(),
        "print_rotation": {
            "orient": result.settings.orient,
            "matrix": R.round(12).tolist(),
            "axis": None if axis is None else axis.round(12).tolist(),
            "angle_deg": round(degrees, 6),
            "printing_direction_in_model_frame": print_direction(R, rig.up).round(12).tolist(),
        },
        "frames": {
            "before": "rest pose, standing as the input stood (the display frame)",
            "after": "found pose turned by print_rotation, lowest point on the plate (the print frame): "
                     "the mesh to slice; its contact, balance and distortion are judged standing",
            "after.upright": "found pose standing as the input stood (the display frame)",
        },
        "max_vertex_displacement": float(displacement.max()),
        "max_vertex_displacement_relative_to_height": float(displacement.max() / height) if height else None,
        "rms_vertex_displacement_relative_to_height": float(np.sqrt(np.mean(displacement ** 2)) / height)
        if height else None,
        "bone_rotation_deg": [round(float(a), 4) for a in turned],
        "largest_rotation_deg": float(turned.max()),
        "angles_deg": np.degrees(result.angles).round(4).tolist(),
        "runtime_seconds": float(result.runtime_seconds),
        "choice": None if result.choice is None else result.choice.to_dict(),
        "symmetry": result.symmetry,
        "naturalness": naturalness(rig, result.angles),
        "interrupted": bool(result.interrupted),
        "settings": result.settings.to_dict() | {"fixed_bones": [int(b) + 1 for b in np.flatnonzero(result.fixed)]},
        "history": [float(v) for v in result.history],
        "term_history": {k: [float(x) for x in v] for k, v in result.term_history.items()},
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "machine": f"{platform.machine()}, {_cpu_count()} cores, Python {platform.python_version()}",
    }
    report["contacts"] = contact_summary(rig, result, frame)
    report["footprint"] = footprint_summary(rig, result, frame)
    report["strength"] = strength_summary(objective.rig if reduced else rig, result, frame)  # a sculpt: as weighed
    report["rest_instead"] = result.rest_instead  # why the rest pose was written, when it was
    report["standing"] = standing_answer(result)
    report["skinning"] = skinning_label(rig)
    report["support"] = support_headline(report)
    return report


def footprint_summary(rig, result, frame: PrintFrame) -> dict | None:
    """What the prints rest on: ``rest_mm2`` (the rest pose as it stands), ``answer_mm2`` (the answer as printed),
    the first layer's contact at the frame's height (:func:`~supportless.energies.footprint.footprint_area`), and
    the search's ``bound_mm2`` for a turn; None in 2D."""
    if rig.dim != 3:
        return None
    scale = frame.height_mm / float(np.ptp(rig.vertices @ rig.up))
    return {"rest_mm2": round(float(footprint_area(rig.vertices, rig.faces, rig.up, scale)), 2),
            "answer_mm2": round(float(footprint_area(result.print_vertices, rig.faces, rig.up, scale)), 2),
            "bound_mm2": float(result.settings.footprint_mm2), "height_mm": float(frame.height_mm)}


def strength_summary(rig, result, frame: PrintFrame) -> dict | None:
    """How strong the rest pose (as it stands) and the answer (as printed) are: ``rest`` and ``answer`` (each
    :func:`weakest_section`), the choice's ``floor`` (``settings.min_safety``), the ``material`` and the grip
    ``load_n``; None in 2D."""
    if rig.dim != 3:
        return None
    material = MATERIALS[result.settings.material]
    height = float(frame.height_mm)
    names = rig.bone_names()
    rest = pose_strength(rig, rig.rest_angles(), np.eye(3), height, material)
    answer = pose_strength(rig, result.angles, np.asarray(result.rotation, np.float64), height, material)
    return {"rest": weakest_section(rest, names), "answer": weakest_section(answer, names),
            "floor": float(result.settings.min_safety), "material": material.to_dict(), "load_n": HANDLING_LOAD_N}


def weakest_section(strength: Strength, names: list[str]) -> dict:
    """A body's weakest section as JSON values: ``safety_factor`` (None: nothing pulls it), and ``weakest``:
    ``bone`` (its name), ``height_mm`` over the plate, ``direction`` (``"across"`` or ``"along"`` the layers),
    ``breaks_at_n`` (the grip that breaks it, None: none does), ``stress_mpa``, ``strength_mpa``, ``area_mm2``,
    ``section`` (``"layer"``: a horizontal cut, ``"bone"``: square to the bone)."""
    w = strength.weakest
    if w is None or not np.isfinite(w.safety_factor):
        return {"safety_factor": None, "weakest": None}
    return {"safety_factor": round(float(w.safety_factor), 3), "weakest": {
        "bone": names[w.bone] if 0 <= w.bone < len(names) else None, "height_mm": round(w.height_mm, 1),
        "direction": "across" if w.across else "along",
        "breaks_at_n": round(w.breaks_at_n, 2) if np.isfinite(w.breaks_at_n) else None,
        "stress_mpa": round(w.stress_mpa, 2), "strength_mpa": round(w.strength_mpa, 2),
        "area_mm2": round(w.area_mm2, 2), "section": w.kind}}


def strength_line(summary: dict | None) -> str | None:
    """The summary's one line: ``weakest: LeftLeg 7 mm up, across the layers, breaks at 0.9 N`` (the answer's)."""
    if not summary or not summary["answer"]["weakest"]:
        return None
    w = summary["answer"]["weakest"]
    bone = (w["bone"] or "?").split(":")[-1]
    breaks = "never breaks under a grip" if w["breaks_at_n"] is None else f"breaks at {w['breaks_at_n']:.1f} N"
    return f"weakest: {bone} {w['height_mm']:.0f} mm up, {w['direction']} the layers, {breaks}"


def _contact_title(report: dict | None) -> str:
    """" (arms resting on the chest: 6 mm³ merged)" for a found pose with contact, else ""."""
    contacts = [c for c in (report or {}).get("contacts") or [] if c["parts"][0] != c["parts"][1]]
    if not contacts:
        return ""
    def short(name):
        name = name.split(":")[-1].split(" (")[0]
        return name if len(name) <= 18 else name[:17] + "…"

    named = ", ".join(f"{short(c['parts'][0])}–{short(c['parts'][1])}" for c in contacts[:2])
    more = f" and {len(contacts) - 2} more" if len(contacts) > 2 else ""
    return f"\ncontact merged as written: {named}{more} ({report['contacts'][0]['overlap_mm3']:.0f} mm³)"


def standing_answer(result) -> dict | None:
    """The best answer printed standing, beside the one handed back (:func:`supportless.search.choice.best_standing`).

    Returns
    -------
    standing : dict or None
        ``standing_mm``/``standing_g`` (its support filament: sliced when the choice sliced it, else
        predicted), ``answer_mm``/``answer_g`` (the answer's, alike), ``answer_turned_deg`` (how far the answer
        is turned from standing), ``is_answer`` (the answer is that standing one) and ``source``; None when the
        search weighed no answers.
    """
    from ..search.choice import best_standing

    choice = result.choice
    if choice is None or (i := best_standing(choice)) is None:
        return None
    pick, chosen = choice.candidates[i], choice.candidates[choice.chosen]
    sliced = pick.sliced_mm is not None and chosen.sliced_mm is not None
    mm = [c.sliced_mm if sliced else c.predicted_mm for c in (pick, chosen)]
    grams = [filament_grams(v) for v in mm]
    return {"standing_mm": float(mm[0]), "standing_g": float(grams[0]), "answer_mm": float(mm[1]),
            "answer_g": float(grams[1]), "answer_turned_deg": float(rotation_axis_angle(result.rotation)[1]),
            "is_answer": i == choice.chosen, "source": "sliced" if sliced else "predicted", "index": int(i)}


def skinning_label(rig) -> str:
    """Which weights and blend posed the result, in words."""
    skin = rig.info.get("weights") == "skin" or ("gltf" in rig.info and rig.info.get("weights", "skin") == "skin")
    source = "the glTF file's skin weights" if skin else "bounded biharmonic weights"
    return f"linear blend skinning with {source}"


def contact_summary(rig, result, frame: PrintFrame) -> list[dict]:
    """The contact regions of the answer as written (:func:`supportless.search.result.written_verdict`'s), named.

    Returns
    -------
    contacts : list of dict
        One per pair of parts pressed together: ``parts`` (two bone names), ``pairs`` (crossing triangle
        pairs), ``depth`` (deepest press, in the thinner part's thicknesses) and ``overlap_mm3`` (the volume
        the whole body covers twice, at the print's scale, on the first only; the written file merges it).
    """
    regions = result.written.contacts if result.written is not None else []
    if not regions or rig.dim != 3:
        return []
    names = rig.bone_names()
    overlap = float(self_intersection_volume(result.print_vertices, rig.faces, rig.up)) * frame.scale ** 3
    return [{"parts": [names[r["bones"][0]], names[r["bones"][1]]], "pairs": int(r["pairs"]),
             "depth": round(float(r["depth"]), 3), "overlap_mm3": round(overlap, 1) if i == 0 else None}
            for i, r in enumerate(regions)]


def support_headline(report: dict) -> dict | None:
    """The one support figure a user compares with their slicer, rest pose -> found pose.

    PrusaSlicer's figures when the report has them (``slice_check``), else the
    slicer model's prediction (``predicted_slicer``), labelled as such.

    Parameters
    ----------
    report : dict
        A :func:`build_report` report, with ``slice_check`` when a slicer ran.

    Returns
    -------
    headline : dict or None
        ``source`` (the slicer, :func:`slicer_label`, or "predicted"), ``height_mm``,
        ``before_mm``/``after_mm`` (filament), ``before_g``/``after_g``,
        ``before_time_s``/``after_time_s`` (printing time the supports add;
        None without a slicer), ``reduction_percent`` and ``line`` (the
        summary's text); None for a planar figure.
    """
    sliced, predicted = report.get("slice_check"), report.get("predicted_slicer")
    if sliced:
        b, a = sliced["before"], sliced["after"]
        out = {"source": slicer_label(sliced), "height_mm": sliced["height_mm"], "before_mm": b["support_mm"],
               "after_mm": a["support_mm"], "before_g": b.get("support_g"), "after_g": a.get("support_g"),
               "before_time_s": b.get("support_time_s"), "after_time_s": a.get("support_time_s")}
    elif predicted:
        grams = [filament_grams(predicted[k]) for k in ("before_mm", "after_mm")]
        out = {"source": "predicted", "height_mm": predicted["height_mm"], "before_mm": predicted["before_mm"],
               "after_mm": predicted["after_mm"], "before_g": grams[0], "after_g": grams[1],
               "before_time_s": None, "after_time_s": None}
    else:
        return None
    out["reduction_percent"] = reduction(out["before_mm"], out["after_mm"])
    out["line"] = _headline_text(out)
    return out


def _headline_text(h: dict) -> str:
    def side(g, mm, t, first):
        text = f"{g:.1f} g" if g is not None else "? g"
        text += f" ({mm:,.0f} mm of filament)" if first else f" ({mm:,.0f} mm)"
        return text + (f", {duration_text(t)} of printing" if t is not None else "")

    red = h["reduction_percent"]
    change = ("no support before" if red is None else f"{red:.0f} % less" if red >= 0 else f"{-red:.0f} % more")
    source = (h["source"] if h["source"] != "predicted"
              else "predicted for PrusaSlicer, an estimate (--slice-check measures it)")
    return (f"support {side(h['before_g'], h['before_mm'], h['before_time_s'], True)} -> "
            f"{side(h['after_g'], h['after_mm'], h['after_time_s'], False)}: {change} "
            f"({source}; printed {h['height_mm']:.4g} mm tall)")


def duration_text(seconds: float) -> str:
    """``1 h 02 min`` / ``12 min`` / ``40 s`` of a (signed) duration, shown as its size."""
    seconds = abs(float(seconds))
    if seconds >= 3600:
        return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60):02d} min"
    return f"{int(round(seconds / 60))} min" if seconds >= 60 else f"{seconds:.0f} s"


def _cpu_count() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def write_pictures(folder, rig, result, report: dict | None = None) -> list[tuple[str, str]]:
    """Before/after renders (same camera, risky faces red, skeleton, balance), the print orientation, convergence.

    ``before_after.png`` shows the rest pose and the found pose standing as
    the input stood; ``print.png`` (when the search turned the model) shows
    the found pose standing beside the same pose in its print orientation on
    the plate, risky faces counted in each frame.

    Risky faces are those past the printer's threshold
    (``result.settings.overhang_angle``), as the report counts them. In 3D the
    faces of weak sections are painted over them (:mod:`.weakness`: the rest
    pose standing, the answer as printed, in both pictures), each panel's
    weakest section written at its foot.

    Parameters
    ----------
    folder : str or os.PathLike
    rig : Rig
    result : supportless.search.optimizer.PoseResult
    report : dict, optional
        Its :func:`build_report`, for the reduction in the title.

    Returns
    -------
    written : list of (label, path)
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    angle = result.settings.overhang_angle
    rest = place_on_plate(rig.vertices, rig.up)
    posed = result.vertices
    shift_rest = rest[0] - rig.vertices[0]
    shift_posed = posed[0] - rig.pose(result.angles)[0]
    drawn = _drawn_rig(rig)
    if drawn is not rig:  # a sculpt drawn as its proxy, placed where the full surface stands
        R = np.asarray(result.rotation, np.float64)
        rest, posed = drawn.vertices + shift_rest, drawn.pose(result.angles) + shift_posed
        result = copy.copy(result)
        result.vertices = posed
        result.print_vertices = print_pose(posed, R, rig.up) if not np.allclose(R, np.eye(rig.dim)) else posed
        rig = drawn
    joints_rest = rig.joints + shift_rest
    joints_posed = rig.posed_joints(result.angles) + shift_posed
    risky = rig.dim == 3
    change = (report or {}).get("reduction_percent", {}).get("support_prism")
    standing = result.objective.standing
    corners = standing.support_corners()

    def balance(angles, shift):
        return {"centre_of_mass": standing.centre_of_mass(rig.transforms(angles)) + shift,
                "support": corners + shift}

    weak = _picture_strength(rig, result, report)  # each pose's weak faces and weakest section, or None
    legend = f"\n{LEGEND}" if weak else ""

    def coloured(vertices, poses):  # the keywords that colour two panels: risky faces, weak ones over them
        risky_of = [risky_faces(V, rig.faces, rig.up, angle) if risky else None for V in vertices]
        if not weak:
            return {"before_risky": risky_of[0], "after_risky": risky_of[1]}
        return {"face_colors": tuple(weak_face_colors(weak[k][0], r) for k, r in zip(poses, risky_of)),
                "notes": tuple(weak[k][1] for k in poses)}

    before_after = render_before_after(
        folder / "before_after.png", (rest, rig.faces), (posed, rig.faces), rig.up,
        before_skeleton=(joints_rest, rig.bones), after_skeleton=(joints_posed, rig.bones),
        **coloured((rest, posed), (0, 1)),
        titles=("rest pose", "found pose" + _contact_title(report)),
        before_balance=balance(rig.rest_angles(), shift_rest), after_balance=balance(result.angles, shift_posed),
        suptitle=f"{rig.name}: support as printed (prism) {_fmt_pct(change)}; red = needs support (> {angle:.3g} deg); "
                 f"green = support polygon, ring = centre of mass{legend}")
    written = [("before/after picture", str(before_after))]
    R = np.asarray(result.rotation, np.float64)
    if not np.allclose(R, np.eye(rig.dim)):
        printed = np.asarray(result.print_vertices, np.float64)
        shift = print_transform(posed, R, rig.up)
        axis, degrees = rotation_axis_angle(R)
        direction = np.round(print_direction(R, rig.up), 2).tolist()
        printed_change = (report or {}).get("reduction_percent", {}).get("support_prism")
        written.append(("print orientation picture", str(render_before_after(
            folder / "print.png", (posed, rig.faces), (printed, rig.faces), rig.up,
            before_skeleton=(joints_posed, rig.bones), after_skeleton=(joints_posed @ R.T + shift, rig.bones),
            **coloured((posed, printed), (1, 1)),
            titles=("found pose, standing", f"as printed: turned {degrees:.0f} deg, model {direction} up"),
            before_balance=balance(result.angles, shift_posed),
            suptitle=f"{rig.name}: print orientation; support (prism) against the rest pose standing: "
                     f"{_fmt_pct(printed_change)}; red = needs support (> {angle:.3g} deg){legend}"))))
    terms = {k: v for k, v in result.term_history.items() if len(v)}
    convergence = plot_convergence(folder / "convergence.png", result.history, terms=terms or None,
                                   title=f"{rig.name}: best objective per iteration")
    return written + [("convergence plot", str(convergence))]


def _picture_strength(rig, result, report: dict | None) -> list[tuple[np.ndarray, str | None]] | None:
    """The strength the pictures colour: ``[(face_safety (f,) float64, caption)]`` of the rest pose standing and of
    the answer as printed (:func:`~supportless.search.sturdiness.pose_strength` of ``rig``, the surface drawn), the
    captions from the report's ``strength`` when it has one (:func:`~supportless.report.weakness.weakest_caption`);
    None in 2D."""
    if rig.dim != 3:
        return None
    summary = (report or {}).get("strength")
    height = ((report or {}).get("print_frame") or {}).get("height_mm") or rig_print_frame(rig).height_mm
    material = MATERIALS[result.settings.material]
    out = []
    for key, angles, R in (("rest", rig.rest_angles(), np.eye(3)), ("answer", result.angles, result.rotation)):
        R = np.asarray(R, np.float64)
        strength = pose_strength(rig, angles, R, float(height), material)
        entry = summary[key] if summary else weakest_section(strength, rig.bone_names())
        out.append((strength.face_safety, weakest_caption(entry, "weakest" if np.allclose(R, np.eye(3)) else
                                                          "weakest as printed")))
    return out


#: A surface with more triangles than this is drawn as its simplified proxy (:meth:`~supportless.rig.rig.Rig.coarse_rig`):
#: a picture of 1.8 million triangles took 49 s and 3.4 GB and looks the same as one of 10 000.
DRAWN_FACES = 200_000


def _drawn_rig(rig):
    """The rig whose surface the pictures draw: the proxy of a surface past :data:`DRAWN_FACES`, else ``rig``."""
    if len(rig.faces) <= DRAWN_FACES or rig.coarse_faces is None:
        return rig
    return rig.coarse_rig()


def _fmt_pct(x) -> str:
    return "n/a" if x is None else f"{x:.0f} % less"
