"""Measure support material with CuraEngine, Cura's slicer, headless: normal or tree supports.

CuraEngine slices from the command line given Cura's printer definitions
(``fdmprinter.def.json`` and ``fdmextruder.def.json``, which ship with Cura,
not with the engine). With ``-v`` it writes ``Filament (mm^3): N`` and
``Print time (s): N`` on stderr (the G-code header's own figures are
placeholders): the whole print. The support is the G-code's ``;TYPE:SUPPORT``
extrusions of a slice with supports (what ``slice_check`` reports, as for
PrusaSlicer), or the difference between a slice with supports and one without,
which also counts the brim the supports add. Every setting is Cura's own default
(``fdmprinter``: 0.1 mm layers, 20 % infill, a brim, supports from
:data:`~supportless.files.printer.CURA_SUPPORT_ANGLE` degrees off the vertical) except the filament
diameter, 1.75 mm, and a build volume made to fit the model.

The engine is ``$SUPPORTLESS_CURA_ENGINE`` if set, else ``CuraEngine`` on
``PATH``; the definitions folder is the one given (``--cura-definitions``),
else ``$SUPPORTLESS_CURA_DEFINITIONS``, else the first of
:data:`DEFINITION_DIRS` that holds ``fdmprinter.def.json``.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from ..base.errors import SlicerError

__all__ = ["CURA_SETTINGS", "DEFINITIONS_ENV_VAR", "DEFINITION_DIRS", "ENGINE_ENV_VAR",
           "STRUCTURES", "CuraNotFound", "cura_command", "cura_version", "find_cura_definitions", "find_cura_engine",
           "read_cura_log", "slice_with_cura"]

ENGINE_ENV_VAR = "SUPPORTLESS_CURA_ENGINE"
DEFINITIONS_ENV_VAR = "SUPPORTLESS_CURA_DEFINITIONS"

#: Where Cura's printer definitions usually are: Debian's and a source build's, a user's extracted Cura
#: AppImage (``squashfs-root`` in the home folder), macOS and Windows installs.
DEFINITION_DIRS = (
    "/usr/share/cura/resources/definitions",
    "/usr/local/share/cura/resources/definitions",
    "~/squashfs-root/share/cura/resources/definitions",
    "~/.local/share/cura/resources/definitions",
    "/Applications/Ultimaker Cura.app/Contents/Resources/share/cura/resources/definitions",
    "C:/Program Files/Ultimaker Cura/share/cura/resources/definitions",
)

#: Cura's support structures by this tool's name: ``grid`` is Cura's "normal" support.
STRUCTURES = {"grid": "normal", "tree": "tree"}

#: Settings given on the command line besides the definitions' defaults.
CURA_SETTINGS: dict[str, str] = {"material_diameter": "1.75"}

#: Two slices whose volumes differ by no more than this (mm^3: CuraEngine prints whole mm^3) lay down no support.
ROUNDING_MM3 = 2.0

_FILAMENT_RE = re.compile(r"Filament \(mm\^3\):\s*([0-9.eE+-]+)")
_TIME_RE = re.compile(r"Print time \(s\):\s*([0-9.eE+-]+)")


class CuraNotFound(SlicerError):
    """CuraEngine, or Cura's printer definitions, are not installed where this tool looks."""


def find_cura_engine() -> str | None:
    """Path of the CuraEngine executable, or None.

    Returns
    -------
    path : str or None
        ``$SUPPORTLESS_CURA_ENGINE`` (a path or a command on ``PATH``) if set, None if it names no
        executable; otherwise ``CuraEngine`` on ``PATH``.
    """
    env = os.environ.get(ENGINE_ENV_VAR, "").strip()
    if env:
        p = Path(env).expanduser()
        return str(p) if p.is_file() and os.access(p, os.X_OK) else shutil.which(env)
    return shutil.which("CuraEngine")


def find_cura_definitions(folder: str | os.PathLike | None = None) -> Path | None:
    """The folder of Cura's printer definitions (holding ``fdmprinter.def.json``), or None.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        Given by the user: used when it holds the definitions (None otherwise, never another).

    Returns
    -------
    folder : Path or None
        ``folder``, else ``$SUPPORTLESS_CURA_DEFINITIONS``, else the first of :data:`DEFINITION_DIRS`.
    """
    explicit = folder if folder is not None else (os.environ.get(DEFINITIONS_ENV_VAR, "").strip() or None)
    candidates = [explicit] if explicit is not None else list(DEFINITION_DIRS)
    for c in candidates:
        p = Path(c).expanduser()
        if (p / "fdmprinter.def.json").is_file() and (p / "fdmextruder.def.json").is_file():
            return p
    return None


def missing_message(engine: str | None, definitions: Path | None, asked: str | os.PathLike | None = None) -> str:
    """One line: what of Cura is missing and how to install it."""
    if engine is None:
        return ("CuraEngine not found: it is needed to measure Cura's support. Install it (Debian/Ubuntu: "
                f"`apt-get install cura-engine`) or set {ENGINE_ENV_VAR}=/path/to/CuraEngine.")
    env = os.environ.get(DEFINITIONS_ENV_VAR, "").strip()
    where = (f"{asked} has no fdmprinter.def.json" if asked is not None else
             f"{DEFINITIONS_ENV_VAR}={env} has no fdmprinter.def.json" if env else "no Cura printer definitions found")
    return (f"{where}: CuraEngine needs Cura's fdmprinter.def.json and fdmextruder.def.json. Give their folder "
            f"with --cura-definitions DIR or {DEFINITIONS_ENV_VAR}=DIR (Debian: `apt-get download cura`, "
            "`dpkg-deb -x cura_*.deb x`, then x/usr/share/cura/resources/definitions).")


@lru_cache(maxsize=8)
def cura_version(exe: str) -> str:
    """``Cura_SteamEngine version 4.13.0`` as the engine says it, or ``unknown``."""
    try:
        proc = subprocess.run([exe, "help"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    for line in (proc.stdout + proc.stderr).splitlines():
        if "version" in line.lower():
            return line.strip()
    return "unknown"


def cura_command(exe: str, definitions: Path, stl: Path, gcode: Path, support: bool, structure: str = "grid",
                 settings: Mapping[str, str] | None = None, build_volume: Sequence[float] = (250.0, 210.0, 210.0)
                 ) -> list[str]:
    """The CuraEngine command slicing ``stl`` into ``gcode``.

    Parameters
    ----------
    exe : str
        CuraEngine.
    definitions : Path
        Folder of ``fdmprinter.def.json`` and ``fdmextruder.def.json``.
    stl, gcode : Path
        The mesh (+Z up, mm, x/y centred on 0, lowest point at z = 0) and the G-code written.
    support : bool
        Slice with supports (``support_enable``).
    structure : str
        ``grid`` (Cura's normal support) or ``tree`` (:data:`STRUCTURES`).
    settings : mapping of str to str, optional
        Cura settings (``-s key=value``) over the definitions' defaults and :data:`CURA_SETTINGS`.
    build_volume : (3,) float
        ``machine_width``, ``machine_depth``, ``machine_height`` in mm.

    Returns
    -------
    cmd : list of str
    """
    if structure not in STRUCTURES:
        raise ValueError(f"unknown support structure {structure!r}; choose from {', '.join(STRUCTURES)}")
    values = {**CURA_SETTINGS, "machine_width": f"{build_volume[0]:g}", "machine_depth": f"{build_volume[1]:g}",
              "machine_height": f"{build_volume[2]:g}", **dict(settings or {}),
              "support_enable": "true" if support else "false", "support_structure": STRUCTURES[structure]}
    machine = [a for k, v in values.items() if not k.startswith("material_") for a in ("-s", f"{k}={v}")]
    extruder = [a for k, v in values.items() if k.startswith("material_") for a in ("-s", f"{k}={v}")]
    return [exe, "slice", "-v", "-j", str(definitions / "fdmprinter.def.json"), *machine,
            "-e0", "-j", str(definitions / "fdmextruder.def.json"), *extruder,
            "-e0", "-l", str(stl), "-o", str(gcode)]


def read_cura_log(text: str) -> tuple[float, float | None]:
    """The filament volume (mm^3) and print time (s) CuraEngine reported on stderr.

    Parameters
    ----------
    text : str
        CuraEngine's stderr with ``-v``.

    Returns
    -------
    volume_mm3 : float
        The last ``Filament (mm^3): N`` line.
    seconds : float or None
        The last ``Print time (s): N`` line.

    Raises
    ------
    SlicerError
        When the log has no filament line.
    """
    volumes = _FILAMENT_RE.findall(text)
    if not volumes:
        raise SlicerError("CuraEngine reported no filament volume (no 'Filament (mm^3):' line on stderr)")
    times = _TIME_RE.findall(text)
    return float(volumes[-1]), (float(times[-1]) if times else None)


def slice_with_cura(placed: Sequence[tuple[np.ndarray, np.ndarray]], names: Sequence[str], structure: str = "grid", *,
                    timeout: float = 300.0, workers: int = 2, keep_dir: str | os.PathLike | None = None,
                    engine: str | None = None, definitions: str | os.PathLike | None = None,
                    settings: Mapping[str, str] | None = None, by_feature: bool = False
                    ) -> tuple[list[dict], str, dict[str, str]]:
    """Slice meshes placed on the bed with and without Cura's supports.

    Parameters
    ----------
    placed : sequence of (V (n, 3) float64, F (f, 3) int64)
        +Z up, millimetres, x/y centred on 0, lowest point at z = 0 (CuraEngine puts 0, 0 at the bed's centre).
    names : sequence of str
        Labels in file names and messages.
    structure : str
        ``grid`` (Cura's normal support) or ``tree``.
    timeout : float
        Seconds allowed for each run.
    workers : int
        Runs at a time.
    keep_dir : str or os.PathLike, optional
        Keep the STL, G-code and logs there.
    engine, definitions : optional
        CuraEngine and the definitions folder (default :func:`find_cura_engine`, :func:`find_cura_definitions`).
    settings : mapping, optional
        Cura settings over the defaults (a profile's overrides).
    by_feature : bool
        Slice each mesh once, with supports, and read the support from the G-code's ``;TYPE:SUPPORT*``
        extrusions (:func:`~supportless.slicing.gcode.feature_filament`): half the runs, as the slice check
        and the choice among answers measure (it leaves out what the supports add to the brim: the 60 mm
        bunny's normal supports 1942 against 2162 mm).

    Returns
    -------
    meshes : list of dict
        Per mesh, as :class:`~supportless.slicing.prusaslicer.SupportSlices` has them: ``support`` and
        ``nosupport`` runs (``filament_mm``, ``filament_cm3``, ``print_seconds``, ``seconds``; only
        ``support`` by feature, with its ``support_features_mm``), ``support_mm``, ``size_mm``.
    engine : str
    settings : dict of str to str
        The settings given on the command line.

    Raises
    ------
    CuraNotFound
        No CuraEngine or no definitions (one line saying how to install them).
    SlicerError
        CuraEngine failed or timed out.
    """
    from ..base.scratch import scratch_dir
    from .gcode import feature_filament
    from .jobs import build_volume, mesh_jobs, run_jobs

    exe = engine or find_cura_engine()
    folder = find_cura_definitions(definitions) if exe is not None else None
    if exe is None or folder is None:
        raise CuraNotFound(missing_message(exe, folder, definitions))
    given = {**CURA_SETTINGS, **{k: str(v) for k, v in dict(settings or {}).items()}}
    diameter = float(given.get("material_diameter", CURA_SETTINGS["material_diameter"]))
    volume = build_volume(np.max([np.ptp(V, axis=0) for V, _ in placed], axis=0))
    with scratch_dir("supportless-cura-") as tmp:
        work = Path(keep_dir if keep_dir is not None else tmp)
        work.mkdir(parents=True, exist_ok=True)
        jobs = mesh_jobs(placed, names, work, lambda stl, gcode, support: cura_command(
            exe, folder, stl, gcode, support, structure, given, volume), by_feature)
        run_jobs(jobs, workers, float(timeout), name="CuraEngine", last_line=_last_error_line)
        runs = []
        for j in jobs:
            mm3, seconds = read_cura_log(j.log("err").read_text(errors="replace"))
            runs.append({"filament_mm": mm3 / (math.pi * diameter ** 2 / 4.0), "filament_cm3": mm3 / 1000.0,
                         "print_seconds": seconds, "seconds": round(j.elapsed, 3)})
            if by_feature:
                features = feature_filament(j.gcode.read_text(errors="replace"))
                runs[-1]["support_features_mm"] = sum(v for k, v in features.items() if k.startswith("SUPPORT"))
    out = []
    for i, (V, _) in enumerate(placed):
        if by_feature:
            out.append({"support": runs[i], "support_mm": runs[i]["support_features_mm"],
                        "size_mm": [float(x) for x in np.ptp(V, axis=0)]})
            continue
        with_, without = runs[2 * i], runs[2 * i + 1]
        support_mm = with_["filament_mm"] - without["filament_mm"]
        if abs(with_["filament_cm3"] - without["filament_cm3"]) * 1000.0 <= ROUNDING_MM3:
            support_mm = 0.0  # CuraEngine rounds each volume to 1 mm^3
        out.append({"support": with_, "nosupport": without, "support_mm": support_mm,
                    "size_mm": [float(x) for x in np.ptp(V, axis=0)]})
    return out, exe, {**given, "support_structure": STRUCTURES[structure]}


def _last_error_line(stderr: str, stdout: str = "") -> str:
    """CuraEngine's last error line (``[ERROR] ...``), else its last line that is not a settings dump."""
    for text in (stderr, stdout):
        lines = [ln.strip() for ln in text.splitlines() if ln.strip() and " -s " not in ln]
        errors = [ln for ln in lines if ln.startswith("[ERROR]")]
        if errors:
            return errors[-1].removeprefix("[ERROR]").strip()
        if lines:
            return lines[-1][:300]
    return "no error message"
