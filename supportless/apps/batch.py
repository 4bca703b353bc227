"""A whole folder of models at once, on Dask: one task per model, resumable, one failure never stops the rest.

:func:`find_models` pairs the models of a folder (``X.glb``/``X.gltf``, or a
mesh ``X.obj``/``.stl``/... with its skeleton ``X.tgf``). :func:`run_model`
is the task a Dask worker runs for one model: it prepares the rig (through
the shared on-disk cache), searches, and writes ``OUT/X/`` -- the mesh to
print ``X.stl``, the pose ``X.pose.json``, ``report.json``, the pictures and
``row.json`` -- into a temporary folder first and renames it into place, so a
folder ``OUT/X`` exists only when complete. :func:`run_batch` submits the
tasks to a ``LocalCluster`` (one single-threaded worker per core, numba's
threads set to one so workers do not oversubscribe the cores) or to an
existing scheduler, skips models whose folder is complete (unless
``force``), and writes ``OUT/summary.csv`` after every finished model and a
contact sheet at the end. A local worker ends with the process that runs the
batch (:func:`dask_setup`), however that process ends.
"""

from __future__ import annotations

import csv
import glob
import io
import json
import os
import shutil
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..base.crash import advice, last_stage, recording_stages, stage
from ..base.errors import InputError, SupportlessError
from ..base.interrupt import pause_point
from ..base.lifetime import end_with_parent
from ..files.meshes import MESH_FORMATS, atomic_path, write_json

__all__ = ["COLUMNS", "ModelSpec", "find_models", "finished_row", "run_batch", "run_model", "write_contact_sheet",
           "write_summary"]

#: The columns of ``summary.csv``.
COLUMNS = ("model", "status", "reason", "predicted_before_mm", "predicted_after_mm", "predicted_reduction",
           "slicer", "slicer_before_mm", "slicer_after_mm", "slicer_reduction", "distortion", "seconds")

#: Environment of each local worker: one thread for the BLAS, as each worker is one core (numba's: :func:`_one_numba_thread`).
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}

#: Names, in a local worker's environment, the process the worker ends with (:func:`dask_setup`).
PARENT_ENV = "SUPPORTLESS_BATCH_PARENT"

#: How often the local scheduler retries a model whose worker died under it: a crash in native code
#: comes back on the same model, so it is not retried (the row says the stage instead).
WORKER_RETRIES = 0

#: The file in a model's scratch folder naming the stage its worker is in.
STAGE_FILE = "stage"


@dataclass(frozen=True)
class ModelSpec:
    """One model of the input folder: its name, mesh and skeleton (None for glTF), or why it cannot be one."""

    name: str
    mesh: str
    skeleton: str | None = None
    problem: str | None = None


def find_models(folder: str | os.PathLike) -> list[ModelSpec]:
    """The models of a folder, by name.

    ``X.glb``/``X.gltf`` is a model on its own; another mesh ``X.ext``
    (:data:`supportless.files.meshes.MESH_FORMATS`) goes with ``X.tgf``. A mesh
    without its skeleton is listed with a ``problem``.

    Raises
    ------
    InputError
        When ``folder`` is not a folder or holds no model.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(folder, "not a folder; give the folder of models to pose")
    specs = []
    for path in sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith(".")):
        ext = path.suffix.lower().lstrip(".")
        if ext in ("glb", "gltf"):
            specs.append(ModelSpec(path.stem, str(path)))
        elif ext in MESH_FORMATS:
            skeleton = path.with_suffix(".tgf")
            specs.append(ModelSpec(path.stem, str(path), str(skeleton)) if skeleton.is_file() else
                         ModelSpec(path.stem, str(path), problem=f"no skeleton {skeleton.name} beside {path.name}"))
    if not specs:
        raise InputError(folder, f"no models here: put X.glb, or X.obj with X.tgf ({', '.join(MESH_FORMATS)})")
    names = [s.name for s in specs]
    out, said = [], set()
    for s in specs:  # one row per name: several meshes under one name are one failed model
        if names.count(s.name) == 1:
            out.append(s)
        elif s.name not in said:
            said.add(s.name)
            files = ", ".join(Path(t.mesh).name for t in specs if t.name == s.name)
            out.append(ModelSpec(s.name, s.mesh, s.skeleton,
                                 f"several meshes are named {s.name} ({files}); rename all but one"))
    return out


def finished_row(out: str | os.PathLike, name: str) -> dict | None:
    """The summary row of a model whose output folder is complete, or None."""
    row = Path(out) / name / "row.json"
    try:
        return json.loads(row.read_text())
    except (OSError, ValueError):
        return None


def _failed(name: str, reason: str, seconds: float) -> dict:
    return {"model": name, "status": "failed", "reason": reason, "seconds": round(seconds, 2)}


def _row_of(future, name: str, out: str | os.PathLike) -> dict:
    """A finished task's row; a worker that died under it (a crash in native code) is a failed row too.

    The dead worker's scratch folder still holds the stage it had reached
    (:func:`supportless.base.crash.recording_stages`): the row says it, with what
    to try, and the folder is removed.
    """
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 - run_model never raises: this is its worker dying (KilledWorker)
        where = _dead_stage(Path(out), name)
        what = "run the batch without --slice-check" if where == "slicing" else advice(where)
        return _failed(name, f"the worker posing it died while {where} ({type(exc).__name__}: a crash in native "
                             f"code or out of memory); {what}", 0.0)


def _scratch_of(out: Path, name: str) -> list[Path]:
    """The scratch folders of model ``name`` in ``out`` (``.NAME.*``; a name may hold ``[ ] * ?``)."""
    return list(out.glob(glob.escape(f".{name}.") + "*"))


def _dead_stage(out: Path, name: str) -> str:
    """The stage recorded in the newest scratch folder a dead worker left for ``name``; those folders go."""
    left = sorted((p for p in _scratch_of(out, name) if (p / STAGE_FILE).exists()),
                  key=lambda p: (p / STAGE_FILE).stat().st_mtime)
    where = last_stage(left[-1] / STAGE_FILE) if left else "starting"
    for folder in left:
        shutil.rmtree(folder, ignore_errors=True)
    return where


def _umask() -> int:
    """The process's file-creation mask (read by setting it, then put back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _one_numba_thread() -> None:
    """Use one numba thread in this worker, whatever numba started with.

    Numba reads ``NUMBA_NUM_THREADS`` again at every compilation and refuses a
    value other than the one its threads were launched with; a Dask worker may
    have launched them before its environment was set (a kernel compiled for
    the first time, e.g. a 2D model after a 3D run filled the cache, then
    failed). The variable is set to what numba has, and the thread count
    lowered with :func:`numba.set_num_threads` instead.
    """
    import numba

    os.environ["NUMBA_NUM_THREADS"] = str(numba.config.NUMBA_NUM_THREADS)
    numba.set_num_threads(1)


def run_model(spec: ModelSpec, out: str, settings: dict, up: str = "auto", height_mm: float | None = None,
              cache_dir: str | None = None, slice_check: bool | dict = False) -> dict:
    """Pose one model and write ``out/NAME/``; the Dask task. Never raises: a failure is a row.

    Parameters
    ----------
    spec : ModelSpec
    out : str
        The batch's output folder.
    settings : dict
        :class:`supportless.search.settings.SearchSettings` fields.
    up, cache_dir
        As for :func:`supportless.rig.load.load_rig`.
    height_mm : float, optional
        The printed height of the rest pose (:func:`supportless.files.printframe.print_frame`;
        default 60 mm): the STL is written +Z up, in millimetres, on the plate.
    slice_check : bool or dict
        Let the slicer choose among the answers the search weighed
        (:func:`supportless.slicing.ranking.slice_choice`), and slice the rest pose
        and the written STL with it: True for PrusaSlicer, or the fields of a
        :class:`~supportless.slicing.choice.SlicerChoice` (``engine``, ``support``, ``cura_definitions``).

    Returns
    -------
    row : dict
        The model's ``summary.csv`` row (:data:`COLUMNS`).
    """
    t0 = time.perf_counter()
    if spec.problem:
        return _failed(spec.name, spec.problem, 0.0)
    _one_numba_thread()
    final = Path(out) / spec.name
    work = Path(tempfile.mkdtemp(prefix=f".{spec.name}.", dir=out))
    os.chmod(work, 0o777 & ~_umask())  # mkdtemp's 0700 would become the model folder's
    try:
        with recording_stages(work / STAGE_FILE):  # read by the batch if this worker dies
            row = _pose_into(spec, work, settings, up, height_mm, cache_dir, slice_check)
        (work / STAGE_FILE).unlink(missing_ok=True)
        row["seconds"] = round(time.perf_counter() - t0, 2)
        write_json(work / "row.json", row)
        pause_point(f"rename {spec.name}/")
        if final.exists():  # --force: the old result goes only once the new one is complete
            old = Path(tempfile.mkdtemp(prefix=f".{spec.name}.old.", dir=out))
            os.replace(final, old / spec.name)
            os.replace(work, final)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(work, final)
        return row
    except SupportlessError as exc:
        return _failed(spec.name, str(exc), time.perf_counter() - t0)
    except Exception as exc:  # noqa: BLE001 - one model's bug must not stop the catalogue
        where = traceback.extract_tb(exc.__traceback__)[-1]
        return _failed(spec.name, f"{type(exc).__name__}: {exc} ({Path(where.filename).name}:{where.lineno})",
                       time.perf_counter() - t0)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _pose_into(spec: ModelSpec, folder: Path, settings: dict, up, height_mm, cache_dir, slice_check) -> dict:
    from ..files.printframe import rig_print_frame
    from ..report.outputs import write_result
    from ..report.report import build_report, slicer_label, support_headline
    from ..rig.load import load_rig
    from ..search.answer import optimize
    from ..search.settings import SearchSettings

    stage("preparing the rig")
    rig = load_rig(spec.mesh, spec.skeleton, up, cache_dir=cache_dir)
    frame = rig_print_frame(rig, height_mm)
    stage("searching")
    result = optimize(rig, SearchSettings.from_dict(settings))
    choice = _slicer_choice(slice_check)
    if slice_check and result.choice is not None:  # the slicer chooses among the answers, as optimize does
        from ..slicing.ranking import SLICE_RANK, slice_choice

        stage("slicing")
        result = slice_choice(rig, result, SLICE_RANK, height_mm=frame.height_mm, choice=choice)
    stage("writing")
    report = build_report(rig, result, frame)
    stl = folder / f"{spec.name}.stl"
    _, failed = write_result(rig, result, report, frame, output=stl, pose=folder / f"{spec.name}.pose.json",
                             pictures=folder)  # the report last, with the slicer's figures
    if failed:
        raise failed[0][1]
    predicted = report.get("predicted_slicer") or {}
    row = {"model": spec.name, "status": "ok", "reason": "",
           "predicted_before_mm": predicted.get("before_mm"), "predicted_after_mm": predicted.get("after_mm"),
           "predicted_reduction": predicted.get("reduction"),
           "distortion": result.settings.distortion(result.terms)}
    if slice_check and rig.dim == 3:
        from ..slicing.prusaslicer import slice_check as slice_pair

        stage("slicing")
        sliced = slice_pair((frame.place(rig.vertices), rig.faces), stl, up=(0.0, 0.0, 1.0), height_mm=None,
                            choice=choice).to_dict()
        report["slice_check"] = sliced | {"sliced_file": stl.name}
        report["support"] = support_headline(report)
        row |= {"slicer": slicer_label(sliced), "slicer_before_mm": sliced["before"]["support_mm"], "slicer_after_mm": sliced["after"]["support_mm"],
                "slicer_reduction": None if sliced["reduction_percent"] is None else sliced["reduction_percent"] / 100}
    write_json(folder / "report.json", report)
    return row


def _slicer_choice(slice_check):
    """The :class:`~supportless.slicing.choice.SlicerChoice` of ``slice_check`` (a dict of its fields), else None."""
    if not isinstance(slice_check, dict):
        return None
    from ..slicing.choice import SlicerChoice

    return SlicerChoice(slice_check.get("engine", "prusa"), slice_check.get("support", "grid"),
                        slice_check.get("cura_definitions"))


def write_summary(out: str | os.PathLike, rows: list[dict]) -> Path:
    """Write ``out/summary.csv`` (atomically), one row per model in name order."""
    path = Path(out) / "summary.csv"
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=COLUMNS, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    for row in sorted(rows, key=lambda r: r["model"]):
        writer.writerow({k: ("" if row.get(k) is None else row.get(k)) for k in COLUMNS})
    with atomic_path(path) as tmp:
        tmp.write_text(buffer.getvalue())
    return path


def write_contact_sheet(out: str | os.PathLike, rows: list[dict], columns: int = 3) -> Path | None:
    """``out/contact_sheet.png``: each finished model's before/after picture with its reduction, or None."""
    import matplotlib.image as mpimg
    from matplotlib.figure import Figure

    done = [r for r in sorted(rows, key=lambda r: r["model"]) if r.get("status") == "ok"
            and (Path(out) / r["model"] / "before_after.png").is_file()]
    if not done:
        return None
    n_rows = (len(done) + columns - 1) // columns
    fig = Figure(figsize=(6 * columns, 3.3 * n_rows), dpi=80, facecolor="white")
    for i, r in enumerate(done):
        ax = fig.add_subplot(n_rows, columns, i + 1)
        ax.imshow(mpimg.imread(Path(out) / r["model"] / "before_after.png"))
        sliced = r.get("slicer_reduction") not in (None, "")  # the slicer's figure where it ran
        red = r.get("slicer_reduction") if sliced else r.get("predicted_reduction")
        source = (r.get("slicer") or "PrusaSlicer") if sliced else "predicted"
        ax.set_title(r["model"] + ("" if red in (None, "") else f": support {-100 * float(red):+.0f} % ({source})"),
                     fontsize=11)
        ax.axis("off")
    fig.tight_layout()
    path = Path(out) / "contact_sheet.png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    return path


def dask_setup(worker) -> None:
    """Dask's preload hook, run in each local worker as it starts: the worker ends with the batch's process.

    That process started the worker (through its ``LocalCluster``'s nanny)
    and named itself in :data:`PARENT_ENV`; a worker of a scheduler given
    with ``--scheduler`` has no such name and stays its own
    (:func:`supportless.base.lifetime.end_with_parent`).
    """
    parent = os.environ.get(PARENT_ENV)
    if parent:
        end_with_parent(int(parent))


def _client(scheduler: str | None, workers: int | None):
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise InputError(None, "batch runs on Dask, which is not installed: pip install 'supportless[dask]'") from None
    if scheduler:
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError) as exc:
            raise InputError(None, f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    import dask

    n = workers or os.cpu_count() or 1
    with dask.config.set({"distributed.scheduler.allowed-failures": WORKER_RETRIES}):
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               env={**WORKER_ENV, PARENT_ENV: str(os.getpid())}, preload=[__name__],
                               dashboard_address=None, silence_logs=50)  # rows say what failed
    return Client(cluster), cluster


def run_batch(folder: str | os.PathLike, out: str | os.PathLike, settings: dict | None = None, *, up: str = "auto",
              height_mm: float | None = None, cache_dir: str | None = None, slice_check: bool | dict = False,
              scheduler: str | None = None, workers: int | None = None, force: bool = False,
              on_result: Callable[[dict, bool], None] | None = None) -> list[dict]:
    """Pose every model of ``folder`` into ``out`` on Dask; returns the summary rows.

    Parameters
    ----------
    folder, out : path
        The models, and where their folders, ``summary.csv`` and the contact sheet go.
    settings : dict, optional
        :class:`supportless.search.settings.SearchSettings` fields for every model.
    up, height_mm, cache_dir, slice_check
        As for :func:`run_model`.
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a running Dask scheduler; default a
        ``LocalCluster`` of ``workers`` single-threaded processes (default: one per core).
    force : bool
        Pose models whose output folder is complete again.
    on_result : callable, optional
        ``on_result(row, skipped)`` for each model as it finishes (or is skipped).

    Returns
    -------
    rows : list of dict
        One per model (:data:`COLUMNS`). On Ctrl-C, ``KeyboardInterrupt``
        propagates after ``summary.csv`` holds every model finished so far.
    """
    specs = find_models(folder)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for spec in specs:  # scratch folders of a run that was killed
        for stale in _scratch_of(out, spec.name):
            shutil.rmtree(stale, ignore_errors=True)
    for own in ("summary.csv", "contact_sheet.png"):  # and its half-written files: this run owns the folder
        for stale in out.glob(f".{Path(own).stem}.*{Path(own).suffix}"):
            stale.unlink(missing_ok=True)
    rows: dict[str, dict] = {}
    todo = []
    for spec in specs:
        row = None if force else finished_row(out, spec.name)
        if row is not None:
            rows[spec.name] = row
            if on_result is not None:
                on_result(row, True)
        else:
            todo.append(spec)
    if todo:
        from dask.distributed import as_completed

        client, cluster = _client(scheduler, workers)
        try:
            names = {}
            futures = []
            for spec in todo:
                futures.append(client.submit(run_model, spec, str(out), dict(settings or {}), up, height_mm,
                                             cache_dir, slice_check, key=f"supportless-{spec.name}-{time.time_ns()}",
                                             pure=False))
                names[futures[-1].key] = spec.name
            for future in as_completed(futures):
                row = _row_of(future, names[future.key], out)
                rows[row["model"]] = row
                write_summary(out, list(rows.values()))
                if on_result is not None:
                    on_result(row, False)
        except KeyboardInterrupt:
            client.cancel(futures)
            raise
        finally:
            write_summary(out, list(rows.values()))
            client.close()
            if cluster is not None:
                cluster.close()
    write_summary(out, list(rows.values()))
    write_contact_sheet(out, list(rows.values()))
    return [rows[s.name] for s in specs if s.name in rows]
