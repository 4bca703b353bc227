"""``supportless batch``: every model of a folder, on Dask (see :mod:`supportless.apps.batch`)."""

from __future__ import annotations

import sys
import time

import click

from ..files.paths import check_output_paths
from .cli_common import (
    EXIT_INTERRUPTED,
    HEIGHT_MM,
    UP_HELP,
    _console,
    _fail,
    _require_slicer,
    _search_options,
    _settings,
    _slicer_setup,
    finish_warm_up,
    slicer_options,
    start_warm_up,
)

__all__ = ["batch"]


@click.command()
@click.argument("in_dir", type=click.Path(file_okay=False))
@click.option("-o", "--out", "out_dir", type=click.Path(file_okay=False), required=True,
              help="Folder for OUT/X/ per model (mesh to print, pose, report, pictures), summary.csv and "
                   "contact_sheet.png.")
@click.option("--up", default="auto", show_default=True, help=UP_HELP)
@click.option("--height-mm", type=HEIGHT_MM, default=None,
              help="Print each model's rest pose this tall along --up, in millimetres [default: 60]; the STL "
                   "is +Z up, in millimetres, on the plate.")
@click.option("--cache-dir", type=click.Path(file_okay=False), default=None,
              help="Rig cache shared by the workers (default: $SUPPORTLESS_CACHE or ~/.cache/supportless).")
@click.option("--slice-check", "slice_check_flag", is_flag=True,
              help="Also measure each model's support with the slicer (--slicer; needs it on every worker).")
@click.option("--scheduler", default=None, help="tcp://HOST:PORT of a running Dask scheduler (default: a local "
                                                 "cluster of this machine's cores).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Local workers (default: one per core); ignored with --scheduler.")
@click.option("--force", is_flag=True, help="Pose models whose output folder is complete again.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
@_search_options
@slicer_options
def batch(in_dir, out_dir, up, height_mm, cache_dir, slice_check_flag, scheduler, workers, force, quiet,
          slicer, support, cura_definitions, **search_options):
    """Pose every model of IN_DIR (X.glb, or X.obj with X.tgf) into OUT_DIR; resumable."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from .batch import find_models, run_batch

    choice, profile = _slicer_setup(slicer, support, cura_definitions, search_options.pop("printer_profile"))
    settings = _settings(profile, **search_options)
    check_output_paths((), [("-o", out_dir)], ())
    if slice_check_flag:
        _require_slicer("--slice-check", choice)
    specs = find_models(in_dir)
    try:
        import dask.distributed  # noqa: F401
    except ImportError:
        _fail("batch runs on Dask, which is not installed: pip install 'supportless[dask]'")
    console = _console()
    if scheduler is None and specs:  # local workers load this machine's kernels: a first run compiles them once here
        finish_warm_up(start_warm_up(), lambda message: None if quiet else console.print(f"  {message} ...",
                                                                                          highlight=False))
    progress = Progress(TextColumn("[bold]models"), BarColumn(bar_width=20), MofNCompleteColumn(), TimeElapsedColumn(),
                        console=console, disable=quiet)
    counts = {"ok": 0, "failed": 0, "skipped": 0}
    t0 = time.perf_counter()
    with progress:
        task = progress.add_task("models", total=len(specs))

        def on_result(row, skipped):
            counts["skipped" if skipped else row["status"]] += 1
            what = "already done" if skipped else (f"{row['status']} in {row.get('seconds', 0):.0f} s"
                                                   + (f": {row['reason']}" if row.get("reason") else ""))
            sliced = row.get("slicer_reduction") is not None  # the slicer's figure where it ran
            red = row.get("slicer_reduction") if sliced else row.get("predicted_reduction")
            extra = (f", support {-100 * red:+.0f} % ({choice.label if sliced else 'predicted'})"
                     if red is not None and row["status"] == "ok" else "")
            progress.console.print(f"  {row['model']}: {what}{extra}")
            progress.advance(task)

        try:
            run_batch(in_dir, out_dir, settings.to_dict(), up=up, height_mm=height_mm, cache_dir=cache_dir,
                      slice_check=slice_check_flag and {**choice.to_dict(), "cura_definitions": choice.cura_definitions},
                      scheduler=scheduler, workers=workers, force=force,
                      on_result=on_result)
        except KeyboardInterrupt:
            click.echo(f"supportless: interrupted: {counts['ok']} models finished are kept; run again to go on",
                       err=True)
            sys.exit(EXIT_INTERRUPTED)
    console.print(f"{counts['ok']} ok, {counts['failed']} failed, {counts['skipped']} already done, in "
                  f"{time.perf_counter() - t0:.1f} s; summary: {out_dir}/summary.csv")
    if counts["failed"]:
        sys.exit(1)
