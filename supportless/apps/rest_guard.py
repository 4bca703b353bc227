"""The last guard of a command's answer: never hand back a pose that needs more support than the rest pose.

With a slicer (``--slice-check``) its word decides, after the files are written and sliced; without one, the
slicer model's prediction (:func:`supportless.report.report.predicted_slicer`) decides before they are written.
Either way the rest pose, standing as the input stood, is written instead and the command says so.
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["fallback_warnings", "predicted_worse", "rest_instead", "sliced_worse"]


def predicted_worse(report: dict) -> bool:
    """Whether the report's predicted slicer support (``predicted_slicer``) of the answer exceeds the rest pose's."""
    predicted = report.get("predicted_slicer") or {}
    before, after = predicted.get("before_mm"), predicted.get("after_mm")
    return before is not None and after is not None and after > before


def sliced_worse(report: dict) -> bool:
    """Whether the slicer (``slice_check``) laid down more support filament for the written file than for the
    rest pose."""
    sliced = report.get("slice_check") or {}
    try:
        return float(sliced["after"]["support_mm"]) > float(sliced["before"]["support_mm"])
    except (KeyError, TypeError):
        return False


def rest_instead(rig, result, by: str):
    """The rest pose, standing as the input stood, in place of ``result``; its ``rest_instead`` says why.

    Parameters
    ----------
    rig : Rig
    result : PoseResult
    by : str
        Who found the answer worse ("PrusaSlicer", "Cura", "the slicer model's prediction").

    Returns
    -------
    rest : PoseResult
    """
    from ..search.result import measured_at

    rest = measured_at(rig, result, np.zeros_like(result.angles), np.eye(rig.dim))
    why = f"{by} found the answer needs more support than the rest pose"
    written = None if result.written is None else dataclasses.replace(result.written, contacts=[])
    return dataclasses.replace(rest, choice=None, rest_instead=why, written=written)


def fallback_warnings(rig, result) -> list[str]:
    """The lines that say the rest pose was written in place of the answer found, and why (none when not)."""
    lines = []
    written = result.written
    if written is not None and written.fell_back_to_rest:
        turned = not np.allclose(result.rotation, np.eye(rig.dim))
        lines.append(f"supportless: warning: {rig.name}: the pose found crosses itself as written "
                     f"({written.fell_back_to_rest} triangle pairs"
                     + (f": {written.refused_as_written}" if written.refused_as_written else "")
                     + f"); the rest pose{', turned,' if turned else ''} is written instead")
    if result.rest_instead:
        lines.append(f"supportless: warning: {rig.name}: {result.rest_instead}; the rest pose is written instead")
    return lines
