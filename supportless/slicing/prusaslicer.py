"""Measure support material the way a slicer does, with PrusaSlicer's command line.

:func:`slice_check` slices an original and a posed mesh once each, with
automatic supports, and reads the support filament from the G-code's support
features (``;TYPE:Support material`` and its interface,
:func:`~supportless.slicing.gcode.feature_filament`); the whole print's
filament is ``; filament used [mm]``. No slice without supports is needed, so
a print that touches the plate only at a tip, which PrusaSlicer refuses to
slice without supports ("no extrusions in the first layer"), is measured too.
With CuraEngine (which slices any print) the support stays the filament with
supports minus without: the brim Cura lays round its supports is support too.
Both meshes are turned so ``up`` is +Z, scaled by one factor that makes the
original ``height_mm`` tall, and centred on the bed; the print options are
given explicitly (:data:`PRESETS`) with an empty ``--datadir``, so user
presets never matter. The default preset is PrusaSlicer 2.5's own defaults,
which give the reference figure (Stanford bunny, up +Y, 60 mm tall: 3345 mm of
support features; filament with supports minus without, the skirt around the
supports included, is 3360 mm). PrusaSlicer is multi-threaded; repeated slices
of one mesh can differ by about 0.01 %.

The executable is ``$SUPPORTLESS_PRUSA_SLICER`` if set, else ``prusa-slicer``
on ``PATH``; slicing needs no display (for a build that wants one, point the
variable at a script running it under ``xvfb-run -a``).
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import time
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Mapping, Sequence, Union

import numpy as np

from ..base.errors import InputError, SlicerError
from ..base.scratch import scratch_dir
from ..files.meshes import check_mesh_arrays, read_mesh
from ..files.printer import DEFAULT_DENSITY, PrinterProfile, prusa_default_config, reduction
from ..files.printframe import REFERENCE_HEIGHT_MM, place_vertices, rotation_to_z
from .cura import cura_version
from .gcode import (
    FILAMENT_DIAMETER_MM,
    SUPPORT_FEATURES,
    feature_filament,
    mm_to_cm3,
    parse_filament_used,
    parse_print_time,
    read_gcode_tail,
)
from .jobs import build_volume, mesh_jobs, run_jobs

__all__ = [
    "DEFAULT_CONFIG", "DEFAULT_PRESET", "ENV_VAR", "FAST_CONFIG", "FILAMENT_DIAMETER_MM", "PRESETS",
    "PRUSA_DEFAULTS_CONFIG", "STANDARD_CONFIG", "SUPPORT_OPTIONS", "SliceReport", "SlicerError", "SlicerNotFound", "SupportSlices",
    "find_prusa_slicer", "mm_to_cm3", "parse_filament_used", "parse_print_time", "place_vertices", "rotation_to_z",
    "scale_for_height", "slice_check", "slice_support",
]

ENV_VAR = "SUPPORTLESS_PRUSA_SLICER"
DEFAULT_TIMEOUT_S = 300.0

#: The ``standard`` preset, a generic PLA profile (not the default, :data:`DEFAULT_PRESET`): 0.4 mm nozzle,
#: 0.2 mm layers, 2 perimeters, 15 % infill, no skirt or brim, and the 45-degree rule
#: (``support-material-threshold`` is the most horizontal slope, from the horizontal, that prints unsupported).
STANDARD_CONFIG: dict[str, str] = {
    "printer-technology": "FFF", "gcode-flavor": "marlin2", "nozzle-diameter": "0.4",
    "filament-diameter": str(FILAMENT_DIAMETER_MM), "filament-type": "PLA", "filament-density": "1.24",
    "temperature": "215", "first-layer-temperature": "215", "bed-temperature": "60", "first-layer-bed-temperature": "60",
    "layer-height": "0.2", "first-layer-height": "0.2", "perimeters": "2", "top-solid-layers": "5",
    "bottom-solid-layers": "4", "fill-density": "15%", "fill-pattern": "grid", "skirts": "0", "brim-width": "0",
    "support-material-threshold": "45",
}

#: Coarser, faster settings for tests (0.3 mm layers, 1 perimeter, 10 % infill).
FAST_CONFIG: dict[str, str] = {
    **STANDARD_CONFIG, "layer-height": "0.3", "first-layer-height": "0.3", "perimeters": "1", "top-solid-layers": "2",
    "bottom-solid-layers": "2", "fill-density": "10%", "fill-pattern": "rectilinear",
}

#: PrusaSlicer 2.5's built-in defaults spelled out (0.3 mm layers, 3 perimeters,
#: 20 % stars infill, one skirt loop, automatic overhang threshold), from the one table of them,
#: :data:`supportless.files.printer.PRUSA_DEFAULTS` (:func:`~supportless.files.printer.prusa_default_config`).
#: They give the reference figure exactly (upright bunny, 60 mm: 3360 mm of support,
#: the skirt around the supports included).
PRUSA_DEFAULTS_CONFIG: dict[str, str] = prusa_default_config()

#: Named configs accepted by ``slice_check(config=...)``.
PRESETS: dict[str, dict[str, str]] = {
    "standard": STANDARD_CONFIG,
    "fast": FAST_CONFIG,
    "prusa-defaults": PRUSA_DEFAULTS_CONFIG,
}

#: The preset used when no config is given: matches the reference figures.
DEFAULT_PRESET = "prusa-defaults"

#: The config used when none is given: the :data:`DEFAULT_PRESET`'s (PrusaSlicer's own defaults).
DEFAULT_CONFIG: dict[str, str] = PRESETS[DEFAULT_PRESET]

#: Extra flags of the "with supports" slice.
SUPPORT_OPTIONS: tuple[str, ...] = ("--support-material", "--support-material-auto")

MeshLike = Union[str, os.PathLike, tuple]


class SlicerNotFound(SlicerError):
    """PrusaSlicer is not installed, or not where ``$SUPPORTLESS_PRUSA_SLICER`` says."""

    def __init__(self, message: str | None = None):
        super().__init__(
            message
            or "PrusaSlicer not found: it is needed to measure support material. Install it "
            "(Debian/Ubuntu: `apt-get install prusa-slicer`; other systems: "
            f"https://www.prusa3d.com/prusaslicer/) or set {ENV_VAR}=/path/to/prusa-slicer."
        )


# --------------------------------------------------------------------------- #
# finding the slicer
# --------------------------------------------------------------------------- #
def find_prusa_slicer() -> str | None:
    """Path of the PrusaSlicer executable, or None.

    Returns
    -------
    path : str or None
        ``$SUPPORTLESS_PRUSA_SLICER`` (a path or a command on ``PATH``) if it is
        set, and None if it names no executable (another install is never used
        instead); otherwise ``prusa-slicer`` / ``PrusaSlicer`` on ``PATH``.
    """
    env = os.environ.get(ENV_VAR, "").strip()
    if env:
        p = Path(env).expanduser()
        return str(p) if p.is_file() and os.access(p, os.X_OK) else shutil.which(env)
    for name in ("prusa-slicer", "PrusaSlicer", "prusaslicer"):
        found = shutil.which(name)
        if found:
            return found
    return None


@lru_cache(maxsize=8)
def _slicer_version(exe: str) -> str:
    """First line of ``prusa-slicer --help`` (e.g. ``PrusaSlicer-2.5.0+linux-x64-GTK3``)."""
    try:
        out = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    for line in out.splitlines():
        line = line.strip()
        if line and not _LOG_PREFIX_RE.match(line):
            return line.split(" based on")[0]
    return "unknown"


# --------------------------------------------------------------------------- #
# placement on the bed
# --------------------------------------------------------------------------- #
def scale_for_height(vertices: np.ndarray, up: Sequence[float], height_mm: float) -> float:
    """The uniform factor making a mesh ``height_mm`` tall along ``up``.

    Parameters
    ----------
    vertices : (n, 3) float64
    up : (3,) float
    height_mm : float

    Returns
    -------
    scale : float
        ``height_mm`` divided by the extent of ``vertices`` along ``up``.

    Raises
    ------
    InputError
        When the mesh is flat along ``up``.
    """
    z = np.asarray(vertices, dtype=np.float64) @ rotation_to_z(up)[2]
    extent = float(z.max() - z.min())
    if not np.isfinite(extent) or extent <= 0:
        raise InputError(None, "mesh has zero extent along the up direction: nothing to print")
    return float(height_mm) / extent


def _load_mesh(mesh: MeshLike, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``(V (n, 3) float64, F (f, 3) int64)`` from a mesh file or a ``(V, F)`` pair."""
    if isinstance(mesh, (str, os.PathLike)):
        V, F = read_mesh(mesh)
    else:
        try:
            V, F = mesh
        except (TypeError, ValueError):
            raise TypeError(f"the {what} mesh must be a file path or a (V, F) pair") from None
        try:
            V, F = check_mesh_arrays(V, F)
        except InputError as exc:
            raise InputError(None, f"{what} mesh: {exc.reason}") from None
    if V.shape[1] != 3:
        raise InputError(None, f"{what} mesh: only 3D meshes can be sliced, got vertices of shape {V.shape}")
    return V, F


# --------------------------------------------------------------------------- #
# running PrusaSlicer
# --------------------------------------------------------------------------- #
_LOG_PREFIX_RE = re.compile(r"^\[[^\]]*\]\s*\[[^\]]*\]\s*\[\s*\w+\s*\]\s*")


def _last_error_line(stderr: str, stdout: str = "") -> str:
    """The last meaningful line PrusaSlicer wrote (stderr first), log prefix stripped."""
    for text in (stderr, stdout):
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        lines = [ln for ln in lines if "Initializing StaticPrintConfigs" not in ln]  # the usual banner
        lines = [_LOG_PREFIX_RE.sub("", ln) for ln in lines]
        if lines and lines[-1].startswith("Object name:") and len(lines) > 1:  # the error is the line before
            return f"{lines[-2]} ({lines[-1]})"
        if lines:
            return lines[-1]
    return "no error message"


def _config_args(config: Mapping[str, str]) -> list[str]:
    """``--name=value`` flags (booleans as ``--name`` / ``--no-name``)."""
    args = []
    for k, v in config.items():
        k = k.replace("_", "-")
        args.append((f"--{k}" if v else f"--no-{k}") if isinstance(v, bool) else f"--{k}={v}")
    return args


# --------------------------------------------------------------------------- #
# public API
# --------------------------------------------------------------------------- #
@dataclass
class SliceReport:
    """Support filament before (original) and after (posed), measured by PrusaSlicer or Cura.

    Lengths are mm of filament, volumes cm3, masses g (the volume times the
    profile's filament density, PLA's 1.24 g/cm3 when it gives none), times
    seconds of the slicer's estimate. Each mesh is sliced once, with supports:
    ``support`` is its G-code's support extrusions, ``total`` the whole print
    (``total_time_s`` its printing time), ``model`` the total minus the
    support (the skirt or brim included). ``support_time_s`` is None: neither
    slicer gives the time of one feature, and the printing time the supports
    add would need a second slice without them, which a print standing on a
    tip cannot have. Sizes are the ``[x, y, z]`` extents in mm on the bed;
    ``slices`` has the filament and seconds of each run
    (``original-support``, ``posed-support``).
    """

    support_mm_before: float
    support_mm_after: float
    support_cm3_before: float
    support_cm3_after: float
    reduction_percent: float | None
    total_mm_before: float
    total_mm_after: float
    model_mm_before: float
    model_mm_after: float
    total_cm3_before: float | None = None
    total_cm3_after: float | None = None
    support_g_before: float | None = None
    support_g_after: float | None = None
    support_time_s_before: float | None = None
    support_time_s_after: float | None = None
    total_time_s_before: float | None = None
    total_time_s_after: float | None = None
    filament_density: float = 1.24
    profile: str = ""
    up: list[float] = field(default_factory=lambda: [0.0, 1.0, 0.0])
    height_mm: float = REFERENCE_HEIGHT_MM
    scale: float = 1.0
    size_mm_before: list[float] = field(default_factory=list)
    size_mm_after: list[float] = field(default_factory=list)
    filament_diameter_mm: float = FILAMENT_DIAMETER_MM
    slicer: str = ""
    slicer_version: str = ""
    engine: str = "prusa"
    support: str = "grid"
    config: dict[str, str] = field(default_factory=dict)
    support_options: list[str] = field(default_factory=lambda: list(SUPPORT_OPTIONS))
    slices: dict[str, dict] = field(default_factory=dict)
    elapsed_s: float = 0.0

    def to_dict(self) -> dict:
        """The report as plain JSON values, the before/after figures nested.

        Returns
        -------
        report : dict
            ``{"before": {"support_mm", "support_cm3", "support_g",
            "support_time_s", "total_mm", "total_cm3", "total_time_s", "model_mm", "size_mm"},
            "after": {...}, "reduction_percent", "up",
            "height_mm", "scale", "filament_diameter_mm", "slicer",
            "slicer_version", "engine" (``prusa`` or ``cura``), "support" (``grid`` or ``tree``), "config", "support_options", "slices",
            "elapsed_s"}``; non-finite numbers become None.
        """
        flat = asdict(self)
        d = {side: {key: flat.pop(f"{key}_{side}") for key in
                    ("support_mm", "support_cm3", "support_g", "support_time_s", "total_mm", "total_cm3",
                     "total_time_s", "model_mm", "size_mm")}
             for side in ("before", "after")}
        d.update(flat)

        def clean(x):
            if isinstance(x, dict):
                return {str(k): clean(v) for k, v in x.items()}
            if isinstance(x, (list, tuple)):
                return [clean(v) for v in x]
            if isinstance(x, np.generic):
                x = x.item()
            return None if isinstance(x, float) and not math.isfinite(x) else x

        return clean(d)


@dataclass
class SupportSlices:
    """PrusaSlicer's support for several meshes placed alike (:func:`slice_support`).

    ``meshes[i]`` holds mesh ``i``'s runs ``{"support": {...}, "nosupport": {...}}``
    (each ``filament_mm``, ``filament_cm3``, ``print_seconds``, ``seconds``; read
    by feature, only ``support``, with its ``support_features_mm``),
    ``support_mm`` (with minus without, or the support features), ``size_mm``
    (its ``[x, y, z]`` extent on the bed); ``slicer`` is the executable and ``config`` the options given
    on its command line.
    """

    meshes: list[dict]
    slicer: str
    config: dict[str, str]

    @property
    def support_mm(self) -> list[float]:
        """Support filament of each mesh, mm."""
        return [m["support_mm"] for m in self.meshes]


def slice_support(meshes: Sequence[MeshLike], up: Sequence[float], scale: float, timeout: float = DEFAULT_TIMEOUT_S,
                  *, config: Mapping[str, str] | str | None = None, workers: int | None = None,
                  slicer: str | None = None, keep_dir: str | os.PathLike | None = None,
                  profile: PrinterProfile | None = None, names: Sequence[str] | None = None,
                  by_feature: bool = False, choice=None) -> SupportSlices:
    """Slice meshes with and without supports; the support filament of each.

    Parameters
    ----------
    meshes : sequence of str or os.PathLike or tuple
        Mesh files or ``(V (n, 3) float64, F (f, 3) int64)`` pairs, in model units.
    up : (3,) float
        Their printing direction; it becomes +Z on the bed.
    scale : float
        Model units to mm, the same for every mesh
        (:func:`scale_for_height` of the reference mesh).
    timeout : float
        Seconds allowed for each PrusaSlicer run.
    config, workers, slicer, keep_dir, profile
        As in :func:`slice_check`.
    names : sequence of str, optional
        Labels of the meshes in file names and messages (default ``mesh-0`` ...).
    by_feature : bool
        Slice each mesh once, with supports, and read the support filament
        from the G-code's support features (:func:`~supportless.slicing.gcode.feature_filament`)
        instead of the difference with a slice without supports: half the
        PrusaSlicer runs. The two agree within the skirt's few mm (the bunny
        at 60 mm: 3345 mm against 3360 mm); Cura's ``;TYPE:SUPPORT`` extrusions likewise.
    choice : supportless.slicing.choice.SlicerChoice, optional
        The slicer and support (default PrusaSlicer's grid): with Cura
        (:func:`~supportless.slicing.cura.slice_with_cura`) ``slicer`` is
        CuraEngine, ``config`` is ignored and a Cura profile's settings are given.

    Returns
    -------
    slices : SupportSlices

    Raises
    ------
    SlicerNotFound, SlicerError, InputError
        As :func:`slice_check`.
    """
    cura = getattr(choice, "engine", "prusa") == "cura"
    exe = slicer or (None if cura else find_prusa_slicer())
    if exe is None and not cura:
        raise SlicerNotFound()
    if not scale > 0:
        raise ValueError("scale must be positive")
    names = list(names) if names is not None else [f"mesh-{i}" for i in range(len(meshes))]
    if len(names) != len(meshes):
        raise ValueError("names must have one label per mesh")
    if cura:
        from .cura import slice_with_cura

        placed = [(place_vertices(V, up, scale), F) for V, F in (_load_mesh(m, n) for n, m in zip(names, meshes))]
        settings = profile.raw if profile is not None and profile.slicer == "cura" else None
        out, exe, cfg = slice_with_cura(placed, names, choice.support, timeout=timeout, keep_dir=keep_dir, engine=exe,
                                        workers=workers or max(1, min(2, os.cpu_count() or 1)),
                                        definitions=choice.cura_definitions, settings=settings,
                                        by_feature=by_feature)
        return SupportSlices(meshes=out, slicer=exe, config=cfg)
    if profile is not None and profile.slicer != "prusa":
        raise InputError(profile.path, "a Cura profile goes with --slicer cura")
    from_file = profile is not None and profile.path is not None
    if from_file:
        config = {}
    elif config is None or isinstance(config, str):
        name = DEFAULT_PRESET if config is None else config
        if name not in PRESETS:
            raise ValueError(f"unknown slicer config preset {name!r}; choose from {', '.join(PRESETS)}")
        config = PRESETS[name]
    cfg = {k.replace("_", "-"): (v if isinstance(v, bool) else str(v)) for k, v in config.items()}
    placed = []
    for label, mesh in zip(names, meshes):
        V, F = _load_mesh(mesh, label)
        placed.append((place_vertices(V, up, scale), F))
    # a bed big enough for every mesh, each centred on it
    bed_x, bed_y, bed_z = build_volume(np.max([np.ptp(V, axis=0) for V, _ in placed], axis=0))
    for V, _ in placed:
        V[:, :2] += (bed_x / 2.0, bed_y / 2.0)
    cfg.setdefault("bed-shape", f"0x0,{bed_x:g}x0,{bed_x:g}x{bed_y:g},0x{bed_y:g}")
    cfg.setdefault("max-print-height", f"{bed_z:g}")
    workers = workers or max(1, min(4, os.cpu_count() or 1))

    with scratch_dir("supportless-slice-") as tmp:
        work = Path(keep_dir if keep_dir is not None else tmp)
        datadir = work / "prusa-datadir"
        datadir.mkdir(parents=True, exist_ok=True)
        load = ["--load", str(profile.path)] if from_file else []
        base = ["--loglevel=1", f"--datadir={datadir}", "--dont-arrange", *load, *_config_args(cfg)]
        jobs = mesh_jobs(placed, names, work, lambda stl, gcode, support: [
            exe, "--export-gcode", *base, *(SUPPORT_OPTIONS if support else ("--no-support-material",)),
            "--output", str(gcode), str(stl)], by_feature)
        run_jobs(jobs, workers, float(timeout), last_line=_last_error_line)
        runs = []
        for j in jobs:
            tail = read_gcode_tail(j.gcode)
            mm, cm3 = parse_filament_used(tail)
            run = {"filament_mm": mm, "filament_cm3": cm3, "print_seconds": parse_print_time(tail),
                   "seconds": round(j.elapsed, 3)}
            if by_feature:
                features = feature_filament(j.gcode.read_text(errors="replace"))
                run["support_features_mm"] = sum(features.get(name, 0.0) for name in SUPPORT_FEATURES)
            runs.append(run)
    out = []
    for i, (V, _) in enumerate(placed):
        size = [float(x) for x in np.ptp(V, axis=0)]
        if by_feature:
            out.append({"support": runs[i], "support_mm": runs[i]["support_features_mm"], "size_mm": size})
            continue
        with_, without = runs[2 * i], runs[2 * i + 1]
        out.append({"support": with_, "nosupport": without,
                    "support_mm": with_["filament_mm"] - without["filament_mm"], "size_mm": size})
    return SupportSlices(meshes=out, slicer=exe, config=cfg)


def slice_check(original: MeshLike, posed: MeshLike, up: Sequence[float] = (0, 1, 0), height_mm: float | None = REFERENCE_HEIGHT_MM,
                timeout: float = DEFAULT_TIMEOUT_S, *, config: Mapping[str, str] | str | None = None,
                workers: int | None = None, slicer: str | None = None,
                keep_dir: str | os.PathLike | None = None, profile: PrinterProfile | None = None,
                choice=None) -> SliceReport:
    """Slice the original and the posed mesh with supports and compare their support extrusions.

    Each mesh is sliced once, with supports, and its support read from the
    G-code's support features (:func:`slice_support` with ``by_feature``), so a
    print standing on a tip, which PrusaSlicer will not slice without
    supports, has a figure too. With CuraEngine, with supports minus without
    (its brim round the supports counted).

    Parameters
    ----------
    original, posed : str or os.PathLike or tuple
        A mesh file (read with :func:`supportless.files.meshes.read_mesh`) or a pair
        ``(V (n, 3) float64, F (f, 3) int64)``.
    up : (3,) float
        The models' printing direction; it becomes +Z on the bed.
    height_mm : float or None
        The original is scaled to this height along ``up``; the posed mesh by
        the same factor. None slices both as they are, in millimetres (print
        files, see :mod:`supportless.files.printframe`).
    timeout : float
        Seconds allowed for each of the two slicer runs (one per mesh).
    config : dict or str, optional
        PrusaSlicer options (name -> value) or a name from :data:`PRESETS`
        (default :data:`DEFAULT_PRESET`, PrusaSlicer's own defaults).
    workers : int, optional
        Concurrent PrusaSlicer runs (default: the CPU count, at most 4).
    slicer : str, optional
        The executable (default: :func:`find_prusa_slicer`).
    keep_dir : str or os.PathLike, optional
        Keep the STL, G-code and log files there instead of a temporary folder.
    profile : PrinterProfile, optional
        A printer profile read from a file (:func:`supportless.files.printer.read_printer_profile`):
        PrusaSlicer loads the file itself (``--load``) and ``config`` is
        ignored; only the bed is set to fit the meshes. A Cura profile's settings go to CuraEngine.
    choice : supportless.slicing.choice.SlicerChoice, optional
        The slicer and its support (default: PrusaSlicer, grid); ``slicer`` is then that slicer's executable.

    Returns
    -------
    report : SliceReport

    Raises
    ------
    SlicerNotFound
        No PrusaSlicer.
    SlicerError
        The slicer failed or timed out (one-line message), e.g. PrusaSlicer
        refusing a mesh even with supports.
    InputError
        A mesh that cannot be read or is not a valid triangle mesh.
    """
    t0 = time.monotonic()
    engine, support = getattr(choice, "engine", "prusa"), getattr(choice, "support", "grid")
    exe = slicer or (find_prusa_slicer() if engine == "prusa" else None)
    if exe is None and engine == "prusa":
        raise SlicerNotFound()
    if height_mm is not None and not height_mm > 0:
        raise ValueError("height_mm must be positive")
    Vo, Fo = _load_mesh(original, "original")
    Vp, Fp = _load_mesh(posed, "posed")
    s = 1.0 if height_mm is None else scale_for_height(Vo, up, height_mm)
    if height_mm is None:
        height_mm = float(np.ptp(Vo @ rotation_to_z(up)[2]))
    sliced = slice_support([(Vo, Fo), (Vp, Fp)], up, s, timeout, config=config, workers=workers, slicer=exe,
                           keep_dir=keep_dir, profile=profile, names=("original", "posed"), choice=choice,
                           # PrusaSlicer refuses a print on a tip without supports: its support features; Cura
                           # slices anything, and the brim it lays round supports is theirs: with minus without
                           by_feature=engine == "prusa")
    cfg, exe = sliced.config, sliced.slicer
    from_file = profile is not None and profile.path is not None
    o, p = sliced.meshes  # the original's and the posed mesh's slice with supports
    before, after = o["support_mm"], p["support_mm"]
    diameter = profile.filament_diameter if profile is not None else FILAMENT_DIAMETER_MM
    density = profile.filament_density if profile is not None else DEFAULT_DENSITY
    return SliceReport(
        support_mm_before=before,
        support_mm_after=after,
        support_cm3_before=mm_to_cm3(before, diameter),
        support_cm3_after=mm_to_cm3(after, diameter),
        support_g_before=mm_to_cm3(before, diameter) * density,
        support_g_after=mm_to_cm3(after, diameter) * density,
        total_time_s_before=o["support"]["print_seconds"],
        total_time_s_after=p["support"]["print_seconds"],
        filament_density=density,
        filament_diameter_mm=diameter,
        profile=profile.path if from_file else "",
        reduction_percent=reduction(before, after),
        total_mm_before=o["support"]["filament_mm"],
        total_mm_after=p["support"]["filament_mm"],
        model_mm_before=o["support"]["filament_mm"] - before,
        model_mm_after=p["support"]["filament_mm"] - after,
        total_cm3_before=o["support"]["filament_cm3"],
        total_cm3_after=p["support"]["filament_cm3"],
        up=[float(x) for x in np.asarray(up, dtype=float).reshape(3)],
        height_mm=float(height_mm),
        scale=s,
        size_mm_before=o["size_mm"],
        size_mm_after=p["size_mm"],
        slicer=exe,
        slicer_version=_slicer_version(exe) if engine == "prusa" else cura_version(exe),
        engine=engine,
        support=support,
        config=dict(profile.raw) if from_file else dict(cfg),
        support_options=list(SUPPORT_OPTIONS) if engine == "prusa" else
        ["support_enable=true", f"support_structure={cfg['support_structure']}"],
        slices={"original-support": o["support"], "posed-support": p["support"]},
        elapsed_s=time.monotonic() - t0,
    )
