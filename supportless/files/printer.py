"""The printer's PrusaSlicer profile: what the overhang threshold is, and what to slice with.

A profile is a PrusaSlicer config as PrusaSlicer exports it (File > Export >
Export Config: ``key = value`` lines, ``#`` comments). :func:`read_printer_profile`
reads the keys this tool uses and keeps every other key for the slicer;
a key the file does not have takes PrusaSlicer's own default
(:data:`PRUSA_DEFAULTS`). :func:`overhang_threshold` is the slope, in degrees
from the build plate, under which PrusaSlicer lays down support for that
profile:

* ``support_material_threshold = T`` (T > 0): PrusaSlicer counts slopes up to
  ``T + 1`` degrees (it adds one degree so the threshold is inclusive);
* ``support_material_threshold = 0`` (automatic): a layer is unsupported
  where it overhangs the layer below by more than half the external
  perimeter's extrusion width ``w``, which is a slope of
  ``atan(layer_height / (w / 2))`` -- 53.1 degrees for PrusaSlicer's defaults
  (0.3 mm layers, 0.45 mm external perimeters from a 0.4 mm nozzle).

Extrusion widths follow PrusaSlicer's rules: 0 means automatic (1.125 x the
nozzle for external perimeters, 1.05 x for other lines) or the general
``extrusion_width`` when that is set, and a percentage is of the nozzle
diameter.

:func:`reduction` (a percentage less, rest -> found) and :func:`slicer_label`
(which slicer measured) are what a slicer's report and the JSON report both
say: they live here, below both, so choosing a slice never loads
:mod:`supportless.report` (and its matplotlib).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..base.errors import InputError

__all__ = ["CURA_DEFAULTS", "CURA_SUPPORT_ANGLE", "DEFAULT_DENSITY", "DEFAULT_OVERHANG_ANGLE", "FILAMENT_DIAMETER_MM", "MAX_SEARCH_ANGLE", "OVERHANG_MARGIN",
           "PRUSA_DEFAULTS", "PRUSA_PRESET_KEYS", "PrinterProfile", "SEARCH_OVERHANG_ANGLE", "default_profile", "mm_to_cm3",
           "cura_default_profile", "overhang_threshold", "prusa_default_config", "read_cura_profile", "read_printer_profile", "reduction",
           "search_angle", "slicer_label"]

#: PrusaSlicer's built-in defaults (PrusaSlicer 2.5, no vendor preset), keys as a config file spells them: the one
#: table of them. Of the keys this tool reads, what a profile that lacks one means; the keys of
#: :data:`PRUSA_PRESET_KEYS` are the slicer's ``prusa-defaults`` preset
#: (:data:`supportless.slicing.prusaslicer.PRUSA_DEFAULTS_CONFIG`), which gives the reference figures.
PRUSA_DEFAULTS: dict[str, str] = {
    "printer_technology": "FFF",
    "gcode_flavor": "reprap",
    "layer_height": "0.3",
    "first_layer_height": "0.35",
    "nozzle_diameter": "0.4",
    "filament_diameter": "1.75",
    "filament_density": "0",
    "temperature": "200",
    "first_layer_temperature": "200",
    "bed_temperature": "0",
    "first_layer_bed_temperature": "0",
    "perimeters": "3",
    "top_solid_layers": "3",
    "bottom_solid_layers": "3",
    "fill_density": "20%",
    "fill_pattern": "stars",
    "skirts": "1",
    "brim_width": "0",
    "support_material_threshold": "0",
    "external_perimeter_extrusion_width": "0",
    "extrusion_width": "0",
    "support_material_extrusion_width": "0",
    "support_material_contact_distance": "0.2",
    "support_material_buildplate_only": "0",
    "support_material_spacing": "2.5",
}

#: The keys of :data:`PRUSA_DEFAULTS` the slicer bridge passes to PrusaSlicer, in this order, for its
#: ``prusa-defaults`` preset (0.3 mm layers, 3 perimeters, 20 % stars infill, one skirt loop, the automatic
#: overhang threshold): :func:`prusa_default_config`.
PRUSA_PRESET_KEYS: tuple[str, ...] = (
    "printer_technology", "gcode_flavor", "nozzle_diameter", "filament_diameter", "temperature",
    "first_layer_temperature", "bed_temperature", "first_layer_bed_temperature", "layer_height", "first_layer_height",
    "perimeters", "top_solid_layers", "bottom_solid_layers", "fill_density", "fill_pattern", "skirts", "brim_width",
    "support_material_threshold",
)


def prusa_default_config() -> dict[str, str]:
    """PrusaSlicer's defaults of :data:`PRUSA_PRESET_KEYS` as its command line spells them (``layer-height``)."""
    return {key.replace("_", "-"): PRUSA_DEFAULTS[key] for key in PRUSA_PRESET_KEYS}

#: ``fdmprinter.def.json``'s defaults of the Cura settings this tool reads (Cura 4.13), but the filament,
#: 1.75 mm as the tool slices with (:data:`supportless.slicing.cura.CURA_SETTINGS`).
CURA_DEFAULTS: dict[str, str] = {
    "support_angle": "50",
    "layer_height": "0.1",
    "layer_height_0": "0.3",
    "machine_nozzle_size": "0.4",
    "wall_line_width_0": "0.4",
    "support_z_distance": "0.1",
    "support_type": "everywhere",
    "material_diameter": "1.75",
}

#: Cura's default ``support_angle`` (degrees from the vertical).
CURA_SUPPORT_ANGLE = 50.0

#: Density used for grams when the profile gives none (PLA, g/cm3).
DEFAULT_DENSITY = 1.24

#: The filament diameter when a profile gives none, mm.
FILAMENT_DIAMETER_MM = 1.75


def _number(raw: dict, key: str, source: str) -> float:
    """The first value of a (possibly per-extruder, comma-separated) numeric key."""
    text = raw.get(key, PRUSA_DEFAULTS[key]).split(",")[0].strip()
    try:
        value = float(text)
    except ValueError:
        raise InputError(source, f"{key} = {raw.get(key)!r} is not a number; fix the value or "
                                 "remove the line for PrusaSlicer's default") from None
    if not math.isfinite(value) or value < 0:
        raise InputError(source, f"{key} = {text} must be a finite number >= 0")
    return value


def _width(raw: dict, key: str, nozzle: float, source: str) -> float:
    """An extrusion width in mm: absolute, or a percentage of the nozzle, 0 meaning automatic."""
    text = raw.get(key, PRUSA_DEFAULTS[key]).split(",")[0].strip()
    if text.endswith("%"):
        try:
            return float(text[:-1]) / 100.0 * nozzle
        except ValueError:
            raise InputError(source, f"{key} = {text!r} is not a width (mm or a percentage)") from None
    return _number({key: text}, key, source)


@dataclass(frozen=True)
class PrinterProfile:
    """The printer settings the search and the slicer share.

    Attributes
    ----------
    layer_height, first_layer_height, nozzle_diameter : float
        mm.
    support_threshold : float
        ``support_material_threshold`` as written, degrees (0: automatic).
    external_perimeter_width : float
        Width of the external perimeter, mm (automatic widths resolved).
    support_contact_distance : float
        Gap between support and the part, mm.
    buildplate_only : bool
        Support only on the build plate, never on the part.
    filament_diameter : float
        mm.
    filament_density : float
        g/cm3 (:data:`DEFAULT_DENSITY` when the profile says 0).
    path : str or None
        The file read, or None for the slicer's defaults.
    raw : dict of str -> str
        Every ``key = value`` of the file (a Cura profile: every setting it overrides).
    slicer : str
        ``prusa`` (a PrusaSlicer config) or ``cura`` (a Cura definition or settings override, JSON).
    support_angle : float
        Cura's ``support_angle``: overhangs steeper than this from the vertical get support (Cura only).
    """

    layer_height: float = 0.3
    first_layer_height: float = 0.35
    nozzle_diameter: float = 0.4
    support_threshold: float = 0.0
    external_perimeter_width: float = 0.45
    support_contact_distance: float = 0.2
    buildplate_only: bool = False
    filament_diameter: float = 1.75
    filament_density: float = DEFAULT_DENSITY
    path: str | None = None
    raw: dict = field(default_factory=dict, compare=False)
    slicer: str = "prusa"
    support_angle: float = CURA_SUPPORT_ANGLE

    @property
    def overhang_angle(self) -> float:
        """The slope under which the slicer supports, degrees from the plate: :func:`overhang_threshold`."""
        return overhang_threshold(self)

    @property
    def name(self) -> str:
        """The file's name, or ``PrusaSlicer defaults`` / ``Cura defaults``."""
        return Path(self.path).name if self.path else ("Cura defaults" if self.slicer == "cura" else "PrusaSlicer defaults")

    def summary(self) -> dict:
        """JSON-ready description for reports."""
        if self.slicer == "cura":
            return {"profile": self.path or self.name, "slicer": "cura", "layer_height": self.layer_height,
                    "support_angle": self.support_angle, "overhang_angle": round(self.overhang_angle, 3),
                    "support_buildplate_only": self.buildplate_only, "filament_density": self.filament_density}
        return {"profile": self.path or "PrusaSlicer defaults", "layer_height": self.layer_height,
                "support_material_threshold": self.support_threshold,
                "external_perimeter_width": round(self.external_perimeter_width, 6),
                "overhang_angle": round(self.overhang_angle, 3),
                "support_material_buildplate_only": self.buildplate_only,
                "filament_density": self.filament_density}


def overhang_threshold(profile: PrinterProfile) -> float:
    """The slope under which PrusaSlicer supports a surface with ``profile``.

    Parameters
    ----------
    profile : PrinterProfile

    Returns
    -------
    angle : float
        Degrees from the build plate: ``support_threshold + 1`` when it is
        set, else ``atan(layer_height / (external_perimeter_width / 2))``;
        for a Cura profile ``90 - support_angle`` (Cura measures from the vertical).
    """
    if profile.slicer == "cura":
        return 90.0 - profile.support_angle
    if profile.support_threshold > 0:
        return min(profile.support_threshold + 1.0, 90.0)
    return math.degrees(math.atan2(profile.layer_height, profile.external_perimeter_width / 2.0))


def default_profile() -> PrinterProfile:
    """PrusaSlicer's own defaults (automatic threshold, 0.3 mm layers): 53.1 degrees."""
    return _profile_of({}, None, "PrusaSlicer defaults")


def _profile_of(raw: dict, path: str | None, source: str) -> PrinterProfile:
    nozzle = _number(raw, "nozzle_diameter", source)
    if nozzle <= 0:
        raise InputError(source, "nozzle_diameter must be above 0")
    external = _width(raw, "external_perimeter_extrusion_width", nozzle, source)
    general = _width(raw, "extrusion_width", nozzle, source)
    external = external or general or 1.125 * nozzle
    layer = _number(raw, "layer_height", source)
    if layer <= 0:
        raise InputError(source, "layer_height must be above 0")
    threshold = _number(raw, "support_material_threshold", source)
    if threshold > 90:
        raise InputError(source, f"support_material_threshold = {threshold:g} is not within 0..90 degrees")
    density = _number(raw, "filament_density", source)
    return PrinterProfile(
        layer_height=layer, first_layer_height=_number(raw, "first_layer_height", source), nozzle_diameter=nozzle,
        support_threshold=threshold, external_perimeter_width=external,
        support_contact_distance=_number(raw, "support_material_contact_distance", source),
        buildplate_only=raw.get("support_material_buildplate_only", "0").strip() in ("1", "true"),
        filament_diameter=_number(raw, "filament_diameter", source),
        filament_density=density or DEFAULT_DENSITY, path=path, raw=dict(raw))


def read_printer_profile(path: str | os.PathLike) -> PrinterProfile:
    """Read a PrusaSlicer config file (``.ini``), or a Cura profile (``.json``: :func:`read_cura_profile`).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    profile : PrinterProfile
        Keys the file lacks take :data:`PRUSA_DEFAULTS`.

    Raises
    ------
    InputError
        The file cannot be read, is not a PrusaSlicer config (no
        ``key = value`` line, binary content), or a value this tool uses is
        not a number: one line naming the file and the key.
    """
    source = str(path)
    if Path(path).suffix.lower() == ".json":
        return read_cura_profile(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise InputError(source, f"cannot read the printer profile ({exc.strerror or exc})") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = None
    if text is None or "\x00" in text:
        raise InputError(source, "not a PrusaSlicer config (binary content); export one from PrusaSlicer "
                                 "with File > Export > Export Config")
    raw = {}
    for line in text.splitlines():
        line = line.strip()
        if not line or line[0] in "#;" or (line.startswith("[") and line.endswith("]")):
            continue
        key, sep, value = line.partition("=")
        if not sep or not key.strip() or " " in key.strip():
            raise InputError(source, f"not a PrusaSlicer config: the line {line[:60]!r} is not key = value")
        raw[key.strip()] = value.strip()
    if not raw:
        raise InputError(source, "not a PrusaSlicer config: no key = value line; export one from PrusaSlicer "
                                 "with File > Export > Export Config")
    return _profile_of(raw, str(Path(path).resolve()), source)


def cura_default_profile() -> PrinterProfile:
    """Cura's own defaults (``fdmprinter``: supports from 50 degrees off the vertical, 0.1 mm layers): 40 degrees."""
    return _cura_profile_of({}, None, "Cura defaults")


def read_cura_profile(path: str | os.PathLike) -> PrinterProfile:
    """Read a Cura printer definition or settings override (JSON).

    Parameters
    ----------
    path : str or os.PathLike
        A definition as Cura's ``definitions/*.def.json`` (settings under ``overrides``, each with a
        ``default_value`` or a plain value), or a flat ``{"setting": value}`` object.

    Returns
    -------
    profile : PrinterProfile
        ``slicer = "cura"``; settings the file lacks take ``fdmprinter``'s defaults
        (:data:`CURA_DEFAULTS`); ``raw`` holds every setting it gives, for CuraEngine.

    Raises
    ------
    InputError
        Not JSON, not an object, or a setting this tool reads is not a number.
    """
    import json

    source = str(path)
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8-sig"))
    except OSError as exc:
        raise InputError(source, f"cannot read the printer profile ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise InputError(source, f"not a Cura profile: not JSON ({exc}); give a Cura definition (.def.json) or "
                                 "an object of settings") from None
    if not isinstance(data, dict):
        raise InputError(source, "not a Cura profile: the JSON is not an object of settings")
    entries = data.get("overrides", data if "metadata" not in data and "inherits" not in data else {})
    if not isinstance(entries, dict):
        raise InputError(source, "not a Cura profile: 'overrides' is not an object")
    raw = {}
    for key, value in entries.items():
        if isinstance(value, dict):
            if "default_value" not in value:
                continue  # a formula ("value") only Cura's front end evaluates
            value = value["default_value"]
        raw[str(key)] = str(value).lower() if isinstance(value, bool) else str(value)
    return _cura_profile_of(raw, str(Path(path).resolve()), source)


def _cura_profile_of(raw: dict, path: str | None, source: str) -> PrinterProfile:
    def number(key):
        text = raw.get(key, CURA_DEFAULTS[key])
        try:
            value = float(text)
        except ValueError:
            raise InputError(source, f"{key} = {text!r} is not a number") from None
        if not math.isfinite(value) or value < 0:
            raise InputError(source, f"{key} = {text} must be a finite number >= 0")
        return value

    angle = number("support_angle")
    if angle > 90:
        raise InputError(source, f"support_angle = {angle:g} is not within 0..90 degrees")
    layer = number("layer_height")
    if layer <= 0:
        raise InputError(source, "layer_height must be above 0")
    nozzle = number("machine_nozzle_size") or 0.4
    return PrinterProfile(
        layer_height=layer, first_layer_height=number("layer_height_0"), nozzle_diameter=nozzle,
        external_perimeter_width=number("wall_line_width_0") or nozzle,
        support_contact_distance=number("support_z_distance"),
        buildplate_only=raw.get("support_type", CURA_DEFAULTS["support_type"]).strip() == "buildplate",
        filament_diameter=number("material_diameter"), path=path, raw=dict(raw), slicer="cura",
        support_angle=angle)


def mm_to_cm3(mm: float, diameter_mm: float = FILAMENT_DIAMETER_MM) -> float:
    """Volume of a length of filament.

    Parameters
    ----------
    mm : float
        Filament length in mm.
    diameter_mm : float
        Filament diameter in mm.

    Returns
    -------
    cm3 : float
        ``mm * pi * (diameter_mm / 2)**2 / 1000``.
    """
    return mm * math.pi * (diameter_mm / 2.0) ** 2 / 1000.0


def reduction(before: float, after: float) -> float | None:
    """Percentage reduction ``100 (1 - after / before)``.

    Parameters
    ----------
    before, after : float
        A quantity (support volume, filament length, ...) before and after.

    Returns
    -------
    percent : float or None
        Positive when ``after`` is smaller; None when ``before`` is not positive.
    """
    return None if before <= 0 else 100.0 * (1.0 - after / before)


def slicer_label(sliced: dict) -> str:
    """``PrusaSlicer``, ``Cura`` or ``Cura, tree supports``: who measured a ``slice_check`` report."""
    if sliced.get("engine", "prusa") == "prusa":
        return "PrusaSlicer"
    return "Cura, tree supports" if sliced.get("support") == "tree" else "Cura"


# --------------------------------------------------------------------------- #
# the threshold rule: the printer's threshold, and the one the search minimises
# --------------------------------------------------------------------------- #
#: The printer's overhang threshold when no profile is given: PrusaSlicer's
#: defaults, whose automatic threshold is 53.1 degrees (:func:`overhang_threshold`).
DEFAULT_OVERHANG_ANGLE = default_profile().overhang_angle

#: Degrees added to the printer's threshold during the search. A search that
#: counts faces as risky only up to the threshold parks them just past it,
#: where a slicer working layer by layer still supports some of them. The
#: margin used to be 10 degrees on a 45-degree threshold: most of that was the
#: gap to PrusaSlicer's real (automatic) threshold of 53.1 degrees, which the
#: threshold now follows from the profile; 2 degrees remain, so the default
#: search counts faces up to 55.1 degrees as before (55).
OVERHANG_MARGIN = 2.0

#: The steepest threshold the search uses, degrees (90 would count vertical walls).
MAX_SEARCH_ANGLE = 89.0


def search_angle(threshold: float, margin: float = OVERHANG_MARGIN) -> float:
    """The threshold the search minimises for a printer's ``threshold``: ``min(threshold + margin, 89)`` degrees."""
    return min(threshold + margin, MAX_SEARCH_ANGLE)


#: The search's threshold at the default profile (55.1 degrees): the energies' default angle, so that
#: ``overhang_energy(V, F, "y")`` measures what the default search minimises.
SEARCH_OVERHANG_ANGLE = search_angle(DEFAULT_OVERHANG_ANGLE)
