"""Reading PrusaSlicer's G-code summary: filament used and printing time; filament units.

Pure text functions (no slicer is run here): :mod:`supportless.slicing.prusaslicer` runs
PrusaSlicer and reads its output with them.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..base.errors import SlicerError
from ..files.printer import FILAMENT_DIAMETER_MM, mm_to_cm3  # noqa: F401 (re-exported)

__all__ = ["FILAMENT_DIAMETER_MM", "SUPPORT_FEATURES", "feature_filament", "mm_to_cm3", "parse_filament_used",
           "parse_print_time", "read_gcode_tail"]



_FILAMENT_RE = {unit: re.compile(rf"^;\s*filament used \[{unit}\]\s*=\s*(.+?)\s*$", re.M) for unit in ("mm", "cm3")}


def _sum_values(text: str) -> float:
    # multi-extruder G-code lists one value per extruder, comma separated
    return float(sum(float(v) for v in text.split(",") if v.strip()))


def parse_filament_used(gcode: str) -> tuple[float, float | None]:
    """Filament length and volume from PrusaSlicer G-code.

    Parameters
    ----------
    gcode : str
        G-code text (the end of the file, where PrusaSlicer writes its summary, is enough).

    Returns
    -------
    mm : float
        ``; filament used [mm]``, summed over extruders.
    cm3 : float or None
        ``; filament used [cm3]``, or None when the line is missing or unreadable.

    Raises
    ------
    SlicerError
        When there is no readable ``; filament used [mm]`` line.
    """
    m = _FILAMENT_RE["mm"].search(gcode)
    if m is None:
        raise SlicerError("PrusaSlicer G-code has no '; filament used [mm]' line")
    try:
        mm = _sum_values(m.group(1))
    except ValueError:
        raise SlicerError(f"cannot read filament length from G-code line: {m.group(0).strip()!r}") from None
    c = _FILAMENT_RE["cm3"].search(gcode)
    try:
        cm3 = None if c is None else _sum_values(c.group(1))
    except ValueError:
        cm3 = None
    return mm, cm3


#: PrusaSlicer's ``;TYPE:`` labels of support extrusion.
SUPPORT_FEATURES = ("Support material", "Support material interface")

# a ;TYPE: line, or a move / extruder reset / extrusion mode line:
# (feature, command, the text up to an X or Y before any E (empty: no X or Y), E value)
_LINE_RE = re.compile(r"^(?:;TYPE:([^\n]*)|(G[01] |G92|M82|M83)([^\n;EXY]*[XY])?[^\n;E]*(?:E(-?\d*\.?\d+))?)", re.M)


def feature_filament(gcode: str) -> dict[str, float]:
    """Filament extruded per feature (``;TYPE:`` label) of PrusaSlicer G-code.

    Extrusion is counted on moves in X or Y that push filament forward
    (``G1 X.. Y.. E..``): retractions and their undoing are not filament laid
    down. Absolute (``M82``, PrusaSlicer's default, with ``G92 E`` resets) and
    relative (``M83``) extrusion are both read.

    Parameters
    ----------
    gcode : str
        The whole G-code.

    Returns
    -------
    mm : dict of str -> float
        Filament length per feature, mm; moves before the first ``;TYPE:``
        count under ``""``. Their sum is the file's ``; filament used [mm]``.
    """
    rows = _LINE_RE.findall(gcode)
    if not rows:
        return {}
    feature, command, planar_text, e_text = (np.array(column) for column in zip(*rows))
    n = len(rows)
    is_type = command == ""
    labels, code = np.unique(np.char.strip(feature[is_type]), return_inverse=True)
    codes = np.full(n, -1)
    codes[is_type] = code
    # the feature of each line: that of the last ;TYPE: at or before it (-1: none yet)
    last = np.maximum.accumulate(np.where(is_type, np.arange(n), -1))
    feature_of = np.where(last >= 0, codes[np.maximum(last, 0)], -1)
    # the extrusion mode of each line: the last M82/M83 at or before it (absolute before any)
    set_at = np.maximum.accumulate(np.where((command == "M82") | (command == "M83"), np.arange(n), -1))
    relative = (set_at >= 0) & (command[np.maximum(set_at, 0)] == "M83")
    idx = np.flatnonzero(e_text != "")
    e = e_text[idx].astype(np.float64)
    previous = np.concatenate([[0.0], e[:-1]])  # the E the last extruding move or reset left
    step = np.where(relative[idx], e, e - previous)
    planar = planar_text[idx] != ""
    counted = planar & (command[idx] != "G92") & (step > 0)
    sums = np.bincount(feature_of[idx][counted] + 1, weights=step[counted], minlength=len(labels) + 1)
    return {name: float(mm) for name, mm in zip(["", *labels.tolist()], sums) if name or mm > 0}


_TIME_RE = re.compile(r"^;\s*estimated printing time \(normal mode\)\s*=\s*(.+?)\s*$", re.M)
_TIME_UNITS = {"d": 86400.0, "h": 3600.0, "m": 60.0, "s": 1.0}


def parse_print_time(gcode: str) -> float | None:
    """PrusaSlicer's estimated printing time, seconds.

    Parameters
    ----------
    gcode : str
        G-code text (its summary at the end is enough).

    Returns
    -------
    seconds : float or None
        ``; estimated printing time (normal mode) = 1d 2h 3m 4s``, or None
        when the line is missing or unreadable.
    """
    m = _TIME_RE.search(gcode)
    if m is None:
        return None
    parts = re.findall(r"(\d+(?:\.\d+)?)\s*([dhms])", m.group(1))
    if not parts or "".join(v + u for v, u in parts) != re.sub(r"\s+", "", m.group(1)):
        return None
    return float(sum(float(v) * _TIME_UNITS[u] for v, u in parts))


def read_gcode_tail(path: Path) -> str:
    """The last 400 kB of a G-code file: the summary comes before the embedded config."""
    with open(path, "rb") as fh:
        fh.seek(max(0, path.stat().st_size - 400_000))
        return fh.read().decode("utf-8", errors="replace")
