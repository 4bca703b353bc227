"""Measure support material the way a slicer does, with PrusaSlicer's CLI.

:func:`slice_check` slices an *original* and a *posed* mesh with
``prusa-slicer --export-gcode``, each once with automatic supports
(``--support-material --support-material-auto``) and once without, and reads
``; filament used [mm] = X`` from the G-code.  Support filament is the
difference ``with - without``; the report compares it before (original) and
after (posed).

Placement
    Both meshes are rotated so ``up`` becomes +Z (a proper rotation, never a
    mirror), scaled by one common factor chosen so the *original* is exactly
    ``height_mm`` tall along +Z, moved so their lowest point is at z = 0 and
    centred on the bed.  They are written as binary STL files in a temporary
    directory and passed with ``--dont-arrange`` so PrusaSlicer keeps that
    placement.

Print config
    A fixed, explicit set of options (:data:`DEFAULT_CONFIG`) is given on the
    command line, so nothing depends on user presets; ``--datadir`` points at
    an empty temporary directory for the same reason.  It is a generic
    PLA / 0.4 mm nozzle / 0.2 mm layer profile.  Support settings are left at
    PrusaSlicer's defaults except that auto supports are enabled and
    ``support_material_threshold`` is set to 45.  PrusaSlicer's default for
    that option is 0 ("automatic", derived from extrusion width and layer
    height); a non-zero value is the most horizontal slope, measured from the
    horizontal plane (90 = vertical wall), that prints without support.  45
    therefore means "support every surface that leans more than 45 degrees
    away from vertical", the usual 45-degree rule.  Skirt and brim are off so
    they cannot differ between the two runs.  The options used are recorded
    in :attr:`SliceReport.config`.

Reference figures (PrusaSlicer 2.5.0, Stanford bunny, up +Y, 60 mm tall)
    ``config="prusa-defaults"`` (the default used by ``slice_check``:
    PrusaSlicer's built-in defaults, 0.3 mm layers, automatic threshold, one
    skirt loop): 3360 mm, the project's reference value, so our figures
    compare directly with it.
    ``config="standard"`` (0.2 mm layers, 45 degree threshold, above): 2663 mm.  Most of the gap is the layer height and the threshold
    (auto at 0.3 mm layers supports more than 45 degrees at 0.2 mm).
    PrusaSlicer is multi-threaded and not bit-for-bit deterministic: repeated
    slices of one mesh can differ by ~0.01 %.

Headless machines
    CLI slicing (``--export-gcode``) needs no display: PrusaSlicer 2.5 (the
    Debian/Ubuntu ``prusa-slicer`` package) runs fine with ``DISPLAY`` unset,
    and this module does not set any display-related variable.  If a build
    does try to open a display (some AppImage builds initialise GTK early),
    point ``SUPPORTLESS_PRUSA_SLICER`` at a wrapper script that runs it under
    a virtual display, e.g.::

        #!/bin/sh
        exec xvfb-run -a /opt/PrusaSlicer.AppImage "$@"

    (``xvfb-run`` is in the Debian/Ubuntu ``xvfb`` package.)

Finding the slicer
    ``$SUPPORTLESS_PRUSA_SLICER`` if set, else ``prusa-slicer`` /
    ``PrusaSlicer`` on ``PATH``.  If neither exists, :class:`SlicerNotFound`
    is raised; any failure of PrusaSlicer itself raises :class:`SlicerError`
    with a one-line message (the last line PrusaSlicer wrote to stderr).
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Mapping, Sequence, Union

import numpy as np

__all__ = [
    "DEFAULT_CONFIG",
    "FAST_CONFIG",
    "PRUSA_DEFAULTS_CONFIG",
    "PRESETS",
    "SUPPORT_OPTIONS",
    "FILAMENT_DIAMETER_MM",
    "SliceReport",
    "SlicerError",
    "SlicerNotFound",
    "find_prusa_slicer",
    "slice_check",
    "parse_filament_used",
    "place_vertices",
    "rotation_to_z",
    "mm_to_cm3",
    "reduction_percent",
]

ENV_VAR = "SUPPORTLESS_PRUSA_SLICER"
FILAMENT_DIAMETER_MM = 1.75
DEFAULT_TIMEOUT_S = 300.0

#: Print options passed to every slice (PrusaSlicer option name -> value).
#: Generic PLA profile: 0.4 mm nozzle, 1.75 mm filament, 0.2 mm layers,
#: 2 perimeters, 15 % infill.
DEFAULT_CONFIG: dict[str, str] = {
    "printer-technology": "FFF",
    "gcode-flavor": "marlin2",
    "nozzle-diameter": "0.4",
    "filament-diameter": str(FILAMENT_DIAMETER_MM),
    "filament-type": "PLA",
    "filament-density": "1.24",
    "temperature": "215",
    "first-layer-temperature": "215",
    "bed-temperature": "60",
    "first-layer-bed-temperature": "60",
    "layer-height": "0.2",
    "first-layer-height": "0.2",
    "perimeters": "2",
    "top-solid-layers": "5",
    "bottom-solid-layers": "4",
    "fill-density": "15%",
    "fill-pattern": "grid",
    "skirts": "0",
    "brim-width": "0",
    "support-material-threshold": "45",
}

#: Coarser, faster settings for tests (0.3 mm layers, 1 perimeter, 10 %).
FAST_CONFIG: dict[str, str] = {
    **DEFAULT_CONFIG,
    "layer-height": "0.3",
    "first-layer-height": "0.3",
    "perimeters": "1",
    "top-solid-layers": "2",
    "bottom-solid-layers": "2",
    "fill-density": "10%",
    "fill-pattern": "rectilinear",
}

#: PrusaSlicer 2.5's own built-in defaults, spelled out (0.3 mm layers,
#: 0.35 mm first layer, 3 perimeters, 20 % stars infill, one skirt loop,
#: automatic overhang threshold).  This reproduces the project's reference
#: figure (upright bunny, 60 mm: 3360 mm of support filament) exactly; note
#: that the skirt loop, which goes around the supports too, is part of it.
PRUSA_DEFAULTS_CONFIG: dict[str, str] = {
    "printer-technology": "FFF",
    "gcode-flavor": "reprap",
    "nozzle-diameter": "0.4",
    "filament-diameter": str(FILAMENT_DIAMETER_MM),
    "temperature": "200",
    "first-layer-temperature": "200",
    "bed-temperature": "0",
    "first-layer-bed-temperature": "0",
    "layer-height": "0.3",
    "first-layer-height": "0.35",
    "perimeters": "3",
    "top-solid-layers": "3",
    "bottom-solid-layers": "3",
    "fill-density": "20%",
    "fill-pattern": "stars",
    "skirts": "1",
    "brim-width": "0",
    "support-material-threshold": "0",
}

#: Named configs accepted by ``slice_check(config=...)``.
PRESETS: dict[str, dict[str, str]] = {
    "standard": DEFAULT_CONFIG,
    "fast": FAST_CONFIG,
    "prusa-defaults": PRUSA_DEFAULTS_CONFIG,
}

#: The preset used when no config is given: matches the reference figures.
DEFAULT_PRESET = "prusa-defaults"

#: Extra flags for the "with supports" slice (support settings otherwise at
#: PrusaSlicer defaults).
SUPPORT_OPTIONS: tuple[str, ...] = ("--support-material", "--support-material-auto")

MeshLike = Union[str, os.PathLike, tuple]


class SlicerError(RuntimeError):
    """PrusaSlicer failed; the message is a single human-readable line."""


class SlicerNotFound(SlicerError):
    """PrusaSlicer is not installed (or not where we were told it is)."""

    def __init__(self, message: str | None = None):
        super().__init__(
            message
            or (
                "PrusaSlicer not found: it is needed to measure support material. "
                "Install it (Debian/Ubuntu: `apt-get install prusa-slicer`; other "
                "systems: https://www.prusa3d.com/prusaslicer/) or set "
                f"{ENV_VAR}=/path/to/prusa-slicer."
            )
        )


# ---------------------------------------------------------------------------
# Finding the slicer
# ---------------------------------------------------------------------------


def find_prusa_slicer() -> str | None:
    """Path of the PrusaSlicer executable, or None.

    ``$SUPPORTLESS_PRUSA_SLICER`` wins if set (a path or a command name on
    PATH); if it is set but does not name an executable, None is returned
    rather than silently using another install.
    """
    env = os.environ.get(ENV_VAR, "").strip()
    if env:
        p = Path(env).expanduser()
        if p.is_file() and os.access(p, os.X_OK):
            return str(p)
        return shutil.which(env)
    for name in ("prusa-slicer", "PrusaSlicer", "prusaslicer"):
        found = shutil.which(name)
        if found:
            return found
    return None


@lru_cache(maxsize=8)
def _slicer_version(exe: str) -> str:
    """First line of ``prusa-slicer --help`` (e.g. 'PrusaSlicer-2.5.0+...')."""
    try:
        out = subprocess.run(
            [exe, "--help"], capture_output=True, text=True, timeout=60
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    for line in out.splitlines():
        line = line.strip()
        if line and not _LOG_PREFIX_RE.match(line):
            return line.split(" based on")[0]
    return "unknown"


# ---------------------------------------------------------------------------
# Pure helpers
# ---------------------------------------------------------------------------

_FILAMENT_MM_RE = re.compile(r"^;\s*filament used \[mm\]\s*=\s*(.+?)\s*$", re.M)
_FILAMENT_CM3_RE = re.compile(r"^;\s*filament used \[cm3\]\s*=\s*(.+?)\s*$", re.M)


def _sum_values(text: str) -> float:
    # Multi-extruder G-code lists one value per extruder, comma separated.
    return float(sum(float(v) for v in text.split(",") if v.strip()))


def parse_filament_used(gcode: str) -> tuple[float, float | None]:
    """``(mm, cm3)`` from PrusaSlicer G-code text (cm3 None if absent).

    Raises SlicerError if there is no ``; filament used [mm]`` line.
    """
    m = _FILAMENT_MM_RE.search(gcode)
    if m is None:
        raise SlicerError("PrusaSlicer G-code has no '; filament used [mm]' line")
    try:
        mm = _sum_values(m.group(1))
    except ValueError:
        raise SlicerError(
            f"cannot read filament length from G-code line: {m.group(0).strip()!r}"
        ) from None
    cm3 = None
    c = _FILAMENT_CM3_RE.search(gcode)
    if c is not None:
        try:
            cm3 = _sum_values(c.group(1))
        except ValueError:
            cm3 = None
    return mm, cm3


def _read_gcode_tail(path: Path) -> str:
    """The end of a G-code file, where PrusaSlicer writes its summary."""
    size = path.stat().st_size
    with open(path, "rb") as fh:
        # The summary + embedded config are a few tens of kB at the end; the
        # "filament used" lines come before the config block.
        fh.seek(max(0, size - 400_000))
        return fh.read().decode("utf-8", errors="replace")


def mm_to_cm3(mm: float, diameter_mm: float = FILAMENT_DIAMETER_MM) -> float:
    """Volume in cm³ of ``mm`` of filament of the given diameter."""
    return mm * math.pi * (diameter_mm / 2.0) ** 2 / 1000.0


def reduction_percent(before: float, after: float) -> float | None:
    """``100 * (1 - after / before)``; None when ``before`` is ~0 (undefined)."""
    if before <= 1e-9:
        return None
    return 100.0 * (1.0 - after / before)


def rotation_to_z(up: Sequence[float]) -> np.ndarray:
    """Proper 3x3 rotation taking the direction ``up`` to +Z.

    The rotation is about the axis ``up x z`` (minimal rotation), so for
    ``up = +Y`` it is +90° about X: y -> z, z -> -y.
    """
    u = np.asarray(up, dtype=np.float64).reshape(3)
    n = np.linalg.norm(u)
    if not np.isfinite(n) or n < 1e-12:
        raise ValueError(f"up direction must be a non-zero 3-vector, got {up!r}")
    u = u / n
    z = np.array([0.0, 0.0, 1.0])
    c = float(np.dot(u, z))
    if c > 1.0 - 1e-12:
        return np.eye(3)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])  # 180° about X
    axis = np.cross(u, z)
    s = np.linalg.norm(axis)
    k = axis / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def scale_for_height(vertices: np.ndarray, up: Sequence[float], height_mm: float) -> float:
    """Uniform factor making ``vertices`` ``height_mm`` tall along ``up``."""
    R = rotation_to_z(up)
    z = np.asarray(vertices, dtype=np.float64) @ R[2]
    extent = float(z.max() - z.min())
    if not np.isfinite(extent) or extent <= 0:
        raise ValueError("mesh has zero extent along the up direction")
    return float(height_mm) / extent


def place_vertices(
    vertices: np.ndarray,
    up: Sequence[float],
    scale: float,
    center_xy: Sequence[float] = (0.0, 0.0),
) -> np.ndarray:
    """Rotate ``up`` to +Z, scale, put min z at 0 and centre the XY bbox."""
    R = rotation_to_z(up)
    v = (np.asarray(vertices, dtype=np.float64) @ R.T) * float(scale)
    lo, hi = v.min(axis=0), v.max(axis=0)
    shift = np.array(
        [center_xy[0] - 0.5 * (lo[0] + hi[0]), center_xy[1] - 0.5 * (lo[1] + hi[1]), -lo[2]]
    )
    return v + shift


def _load_mesh(mesh: MeshLike, what: str) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(mesh, (str, os.PathLike)):
        import trimesh

        path = Path(mesh)
        if not path.is_file():
            raise FileNotFoundError(f"{what} mesh not found: {path}")
        m = trimesh.load(str(path), process=False, force="mesh")
        V, F = np.asarray(m.vertices), np.asarray(m.faces)
    else:
        try:
            V, F = mesh
        except (TypeError, ValueError):
            raise TypeError(f"{what} must be a path or a (V, F) pair") from None
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if V.ndim != 2 or V.shape[1] != 3 or len(V) == 0:
        raise ValueError(f"{what}: V must be (n, 3), got {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3 or len(F) == 0:
        raise ValueError(f"{what}: F must be (f, 3) triangles, got {F.shape}")
    if F.min() < 0 or F.max() >= len(V):
        raise ValueError(f"{what}: face indices out of range")
    return V, F


def _write_stl(path: Path, V: np.ndarray, F: np.ndarray) -> None:
    """Binary STL (written directly; normals from the winding)."""
    tri = V[F].astype(np.float64)
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    ln = np.linalg.norm(nrm, axis=1, keepdims=True)
    nrm = np.divide(nrm, ln, out=np.zeros_like(nrm), where=ln > 0)
    rec = np.zeros(
        len(F),
        dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")],
    )
    rec["n"] = nrm
    rec["v"] = tri
    with open(path, "wb") as fh:
        fh.write(b"supportless slice_check".ljust(80, b" "))
        fh.write(np.uint32(len(F)).tobytes())
        fh.write(rec.tobytes())


# ---------------------------------------------------------------------------
# Running PrusaSlicer
# ---------------------------------------------------------------------------

_LOG_PREFIX_RE = re.compile(r"^\[[^\]]*\]\s*\[[^\]]*\]\s*\[\s*\w+\s*\]\s*")


def _last_error_line(stderr: str, stdout: str = "") -> str:
    """The last meaningful stderr line (log prefix stripped)."""
    for text in (stderr, stdout):
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        # Skip the boost-log trace banner PrusaSlicer always prints.
        lines = [ln for ln in lines if "Initializing StaticPrintConfigs" not in ln]
        if lines:
            return _LOG_PREFIX_RE.sub("", lines[-1])
    return "no error message"


def _config_args(config: Mapping[str, str]) -> list[str]:
    args: list[str] = []
    for k, v in config.items():
        k = k.replace("_", "-")
        if isinstance(v, bool):
            args.append(f"--{k}" if v else f"--no-{k}")
        else:
            args.append(f"--{k}={v}")
    return args


@dataclass
class _Job:
    label: str
    cmd: list[str]
    gcode: Path
    log_out: Path
    log_err: Path
    proc: subprocess.Popen | None = None
    started: float = 0.0
    elapsed: float = 0.0


def _run_jobs(jobs: list[_Job], workers: int, timeout: float) -> None:
    """Run jobs, at most ``workers`` at a time; each gets ``timeout`` seconds.

    On any failure or timeout all running jobs are killed and SlicerError is
    raised.
    """
    pending = list(jobs)
    running: list[_Job] = []

    def kill_all() -> None:
        for j in running:
            if j.proc is not None and j.proc.poll() is None:
                j.proc.kill()
        for j in running:
            if j.proc is not None:
                try:
                    j.proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    pass

    env = dict(os.environ)
    try:
        while pending or running:
            while pending and len(running) < workers:
                j = pending.pop(0)
                with open(j.log_out, "wb") as out, open(j.log_err, "wb") as err:
                    try:
                        j.proc = subprocess.Popen(
                            j.cmd, stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=env
                        )
                    except OSError as e:
                        raise SlicerError(f"cannot run PrusaSlicer ({j.cmd[0]}): {e}") from None
                j.started = time.monotonic()
                running.append(j)
            time.sleep(0.02)
            now = time.monotonic()
            for j in list(running):
                rc = j.proc.poll()
                if rc is None:
                    if now - j.started > timeout:
                        raise SlicerError(
                            f"PrusaSlicer timed out after {timeout:g} s slicing {j.label} "
                            "(raise the timeout, or use a coarser config / smaller mesh)"
                        )
                    continue
                j.elapsed = now - j.started
                running.remove(j)
                if rc != 0 or not j.gcode.is_file():
                    err = j.log_err.read_text(errors="replace")
                    out = j.log_out.read_text(errors="replace")
                    line = _last_error_line(err, out)
                    hint = ""
                    if re.search(r"display|gtk|x11", line, re.I):
                        hint = " (needs a display? see supportless.slicer docs: xvfb-run)"
                    raise SlicerError(
                        f"PrusaSlicer failed slicing {j.label} (exit {rc}): {line}{hint}"
                    )
    finally:
        kill_all()


# ---------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------


@dataclass
class SliceReport:
    """Support filament before (original) and after (posed), from PrusaSlicer."""

    support_mm_before: float
    support_mm_after: float
    support_cm3_before: float
    support_cm3_after: float
    reduction_percent: float | None
    total_mm_before: float  # original, sliced with supports
    total_mm_after: float  # posed, sliced with supports
    model_mm_before: float  # original, sliced without supports
    model_mm_after: float  # posed, sliced without supports
    total_cm3_before: float | None = None  # as written by PrusaSlicer, if present
    total_cm3_after: float | None = None
    up: list[float] = field(default_factory=lambda: [0.0, 1.0, 0.0])
    height_mm: float = 60.0
    scale: float = 1.0  # model units -> mm
    size_mm_before: list[float] = field(default_factory=list)  # x, y, z after placement
    size_mm_after: list[float] = field(default_factory=list)
    filament_diameter_mm: float = FILAMENT_DIAMETER_MM
    slicer: str = ""
    slicer_version: str = ""
    config: dict[str, str] = field(default_factory=dict)
    support_options: list[str] = field(default_factory=lambda: list(SUPPORT_OPTIONS))
    slices: dict[str, dict] = field(default_factory=dict)  # per-run details
    elapsed_s: float = 0.0

    def to_dict(self) -> dict:
        """JSON-ready dict (plain floats, lists, strings, None).

        Layout::

            {"before": {"support_mm", "support_cm3", "total_mm", "total_cm3",
                        "model_mm", "size_mm"},
             "after": {...same keys...},
             "reduction_percent", "up", "height_mm", "scale",
             "filament_diameter_mm", "slicer", "slicer_version", "config",
             "support_options", "slices", "elapsed_s"}
        """
        flat = asdict(self)
        d: dict = {}
        for side in ("before", "after"):
            d[side] = {
                "support_mm": flat.pop(f"support_mm_{side}"),
                "support_cm3": flat.pop(f"support_cm3_{side}"),
                "total_mm": flat.pop(f"total_mm_{side}"),
                "total_cm3": flat.pop(f"total_cm3_{side}"),
                "model_mm": flat.pop(f"model_mm_{side}"),
                "size_mm": flat.pop(f"size_mm_{side}"),
            }
        d.update(flat)

        def clean(x):
            if isinstance(x, dict):
                return {str(k): clean(v) for k, v in x.items()}
            if isinstance(x, (list, tuple)):
                return [clean(v) for v in x]
            if isinstance(x, (np.floating, np.integer)):
                x = x.item()
            if isinstance(x, float) and not math.isfinite(x):
                return None
            return x

        return clean(d)


def slice_check(
    original: MeshLike,
    posed: MeshLike,
    up: Sequence[float] = (0, 1, 0),
    height_mm: float = 60.0,
    timeout: float = DEFAULT_TIMEOUT_S,
    *,
    config: Mapping[str, str] | str | None = None,
    workers: int | None = None,
    slicer: str | None = None,
    keep_dir: str | os.PathLike | None = None,
) -> SliceReport:
    """Slice original and posed meshes with and without supports; compare.

    Parameters
    ----------
    original, posed
        A mesh file path (anything trimesh loads) or a ``(V, F)`` pair.
    up
        The models' up direction; it becomes +Z on the print bed.
    height_mm
        The original is scaled to this height along ``up``; the posed mesh
        gets the same factor.
    timeout
        Seconds allowed for *each* PrusaSlicer run (four runs in total).
    config
        PrusaSlicer options (name -> value), or a preset name from
        :data:`PRESETS` ("prusa-defaults" = :data:`PRUSA_DEFAULTS_CONFIG`, the
        default: PrusaSlicer's own defaults, which reproduce the reference
        figures; "standard" = :data:`DEFAULT_CONFIG`, 0.2 mm layers and a 45
        degree threshold; "fast" = :data:`FAST_CONFIG`, coarser, for tests).
    workers
        Concurrent PrusaSlicer processes (default: CPU count, at most 4).
    slicer
        Explicit path of the executable (default: :func:`find_prusa_slicer`).
    keep_dir
        If given, STL and G-code files are written there and kept.
    """
    t0 = time.monotonic()
    exe = slicer or find_prusa_slicer()
    if exe is None:
        raise SlicerNotFound()
    if height_mm <= 0:
        raise ValueError("height_mm must be positive")
    if config is None:
        config = PRESETS[DEFAULT_PRESET]
    elif isinstance(config, str):
        try:
            config = PRESETS[config]
        except KeyError:
            raise ValueError(
                f"unknown slicer config preset {config!r}; choose from {', '.join(PRESETS)}"
            ) from None
    cfg = {
        k.replace("_", "-"): (v if isinstance(v, bool) else str(v)) for k, v in config.items()
    }

    Vo, Fo = _load_mesh(original, "original")
    Vp, Fp = _load_mesh(posed, "posed")
    s = scale_for_height(Vo, up, height_mm)
    # Place both at the origin first to learn their footprints.
    Po = place_vertices(Vo, up, s)
    Pp = place_vertices(Vp, up, s)
    ext = np.maximum(np.ptp(Po, axis=0), np.ptp(Pp, axis=0))
    # Bed big enough for either mesh (at least an MK3-sized 250 x 210 bed).
    bed_x = float(max(250.0, math.ceil(ext[0] + 20.0)))
    bed_y = float(max(210.0, math.ceil(ext[1] + 20.0)))
    center = (bed_x / 2.0, bed_y / 2.0)
    Po[:, :2] += center
    Pp[:, :2] += center
    cfg.setdefault("bed-shape", f"0x0,{bed_x:g}x0,{bed_x:g}x{bed_y:g},0x{bed_y:g}")
    cfg.setdefault("max-print-height", f"{max(210.0, math.ceil(ext[2] + 10.0)):g}")

    if workers is None:
        workers = max(1, min(4, os.cpu_count() or 1))

    tmp_ctx = tempfile.TemporaryDirectory(prefix="supportless-slice-") if keep_dir is None else None
    work = Path(tmp_ctx.name if tmp_ctx else keep_dir)
    work.mkdir(parents=True, exist_ok=True)
    try:
        datadir = work / "prusa-datadir"
        datadir.mkdir(exist_ok=True)
        meshes = {"original": (Po, Fo), "posed": (Pp, Fp)}
        jobs: list[_Job] = []
        base = ["--loglevel=1", f"--datadir={datadir}", "--dont-arrange"] + _config_args(cfg)
        for name, (V, F) in meshes.items():
            stl = work / f"{name}.stl"
            _write_stl(stl, V, F)
            for support in (True, False):
                tag = f"{name}-{'support' if support else 'nosupport'}"
                gcode = work / f"{tag}.gcode"
                cmd = [exe, "--export-gcode", *base]
                if support:
                    cmd += list(SUPPORT_OPTIONS)
                cmd += ["--output", str(gcode), str(stl)]
                label = f"{name} mesh ({'with' if support else 'without'} supports)"
                jobs.append(
                    _Job(label, cmd, gcode, work / f"{tag}.out.log", work / f"{tag}.err.log")
                )
        _run_jobs(jobs, workers, float(timeout))

        results: dict[str, dict] = {}
        for j in jobs:
            mm, cm3 = parse_filament_used(_read_gcode_tail(j.gcode))
            key = Path(j.gcode).stem
            results[key] = {"filament_mm": mm, "filament_cm3": cm3, "seconds": round(j.elapsed, 3)}
    finally:
        if tmp_ctx is not None:
            tmp_ctx.cleanup()

    sup_b = results["original-support"]["filament_mm"] - results["original-nosupport"]["filament_mm"]
    sup_a = results["posed-support"]["filament_mm"] - results["posed-nosupport"]["filament_mm"]
    return SliceReport(
        support_mm_before=sup_b,
        support_mm_after=sup_a,
        support_cm3_before=mm_to_cm3(sup_b),
        support_cm3_after=mm_to_cm3(sup_a),
        reduction_percent=reduction_percent(sup_b, sup_a),
        total_mm_before=results["original-support"]["filament_mm"],
        total_mm_after=results["posed-support"]["filament_mm"],
        model_mm_before=results["original-nosupport"]["filament_mm"],
        model_mm_after=results["posed-nosupport"]["filament_mm"],
        total_cm3_before=results["original-support"]["filament_cm3"],
        total_cm3_after=results["posed-support"]["filament_cm3"],
        up=[float(x) for x in np.asarray(up, dtype=float).reshape(3)],
        height_mm=float(height_mm),
        scale=s,
        size_mm_before=[float(x) for x in np.ptp(Po, axis=0)],
        size_mm_after=[float(x) for x in np.ptp(Pp, axis=0)],
        slicer=exe,
        slicer_version=_slicer_version(exe),
        config=dict(cfg),
        support_options=list(SUPPORT_OPTIONS),
        slices=results,
        elapsed_s=time.monotonic() - t0,
    )
