"""``supportless optimize``: a pose (and a print orientation) that needs less support, searched and written.

The command runs the answer's stages in order, each a named function:

1. searched         :func:`_run_search`: :func:`supportless.search.answer.optimize`, whose own stages
                    (on the proxy, on the full surface, polished, chosen by the slicer model, checked as
                    written) are listed at the top of :mod:`supportless.search.answer`; or the front of
                    :func:`_run_front` (``--pareto``)
2. sliced           :func:`_slice_choice`: the slicer's choice among the best answers
                    (:func:`supportless.slicing.ranking.slice_choice`, checked as written again)
3. reported         :func:`_reported`: the report (:func:`supportless.report.report.build_report`), the rest
                    pose instead when the slicer model predicts the answer needs more support
4. written          :func:`_write_outputs`
5. slice-checked    with ``--slice-check``, :func:`_slice_and_report`: the slicer's figures for the written
                    file, the rest pose written instead when the slicer lays more support under the answer

``demo`` runs the same steps on a built-in figure.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ..base.errors import InputError
from ..base.interrupt import deferred_interrupt
from ..base.interrupt import requested as interrupt_requested
from ..base.progress import listening, step
from ..files.paths import check_output_paths
from .cli_common import (
    EXIT_INTERRUPTED,
    EXIT_MISSING_TOOL,
    EXIT_WRITE_FAILED,
    _check_bones_early,
    _check_mesh_path,
    _console,
    _fail,
    _inputs,
    _load,
    _require_slicer,
    _say_frame,
    _search_options,
    _settings,
    _slicer_missing,
    _slicer_setup,
    rig_options,
    slicer_options,
)
from .cli_summary import _print_choice, _print_results
from .rest_guard import fallback_warnings, predicted_worse, rest_instead, sliced_worse

__all__ = ["optimize"]


def _run_search(rig, console, settings, quiet=False):
    """Run the search with a progress bar; returns the PoseResult."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from ..base.crash import stage

    stage("searching")

    from ..search.anatomy import joint_ranges
    from ..search.answer import optimize

    progress = Progress(TextColumn("[bold]search[/bold] {task.fields[phase]}"), BarColumn(bar_width=16),
                        MofNCompleteColumn(), TimeElapsedColumn(), TextColumn("{task.fields[status]}"),
                        console=console, disable=quiet, transient=False)
    with progress:
        # the whole search's iterations (every phase, the polish) are known from its first report on
        task = progress.add_task("search", total=None, status="", phase="")

        def callback(it, info):
            t = info["terms"]
            progress.update(task, total=info["iterations"], completed=it, phase=info.get("phase", ""),
                            status=f"best {info['value']:.4f} = arap {t['arap']:.3f} "
                                                       f"· overhang {t['overhang']:.3f} "
                                                       f"· intersect {t['intersection']:.3f}")

        why = settings.all_fixed(rig)  # a bad --fix/--free, or nothing left to move: before the search
        if why and settings.orient == "keep":
            raise InputError(None, f"{why}: free some with --free 2,3 or --free all, or let the search turn it "
                                   "with --orient free")
        if why:
            click.echo(f"supportless: note: {why}: the search only turns it (--free 2,3 or --free all to pose it)",
                       err=True)
        ranges = joint_ranges(rig) if settings.anatomy else None
        if ranges is not None and not quiet:
            click.echo(ranges.describe() + " (--no-anatomy: the generic limits only)")
        return optimize(rig, settings, callback=callback)


def _run_front(rig, console, settings, count, method, quiet=False):
    """Search the front of least support against least distortion (see :mod:`supportless.apps.pareto`)."""
    from .pareto import pareto_front

    settings.fixed_bones(rig)  # a bad --fix/--free: before the searches
    front = pareto_front(rig, settings, count, method=method, callback=None if quiet else lambda *a: console.print(
        f"  front: search {a[0]} of {a[1]} took {a[2].runtime_seconds:.1f} s"))
    for line in [] if quiet else front.summary():
        console.print(f"  {line}")
    return front


def _write_outputs(rig, result, report, output, pose, report_path, pictures, frame, upright=None, standing=None):
    """Write the result's files (:func:`supportless.report.outputs.write_result`); a file that cannot be
    written is one line on stderr. Returns ([(label, path)] written, number that failed)."""
    from ..base.crash import stage
    from ..report.outputs import write_result

    stage("writing")
    written, failed = write_result(rig, result, report, frame, output=output, upright=upright, pose=pose,
                                   pictures=pictures, report_path=report_path, standing=standing)
    for path, exc in failed:
        click.echo(f"supportless: error: {path}: cannot write: {exc.strerror or exc}", err=True)
    return written, len(failed)


@click.command()
@click.argument("model", type=click.Path(dir_okay=False))
@rig_options
@_search_options
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="Posed mesh to write in its print orientation: +Z up, in millimetres, on the plate, centred "
                   "(.stl, .3mf, .obj, .ply, .off; .glb: glTF's +Y up, metres).")
@click.option("--upright-out", type=click.Path(dir_okay=False), default=None,
              help="Also write the posed mesh standing as the input stood.")
@click.option("--standing-out", type=click.Path(dir_okay=False), default=None,
              help="Also write the best answer printed standing, as displayed (when the answer is turned to print).")
@click.option("--report", "report_path", type=click.Path(dir_okay=False), default=None, help="JSON report.")
@click.option("--pose", type=click.Path(dir_okay=False), default=None, help="Pose JSON (for `apply`).")
@click.option("--pictures", type=click.Path(file_okay=False), default=None,
              help="Folder for before/after pictures and the convergence plot.")
@click.option("--slice-check", "slice_check_flag", is_flag=True,
              help="Slice the rest pose and the written file with the slicer (--slicer; PrusaSlicer by default).")
@click.option("--slice-rank", "slice_rank_count", type=click.IntRange(min=0), default=None,
              help="Slice up to K of the best answers (the search's, the best pose as it stands, the best turned "
                   "rest pose; by predicted support) with the slicer, two at a time, and keep the one with the "
                   "least support. Default: 4 when the slicer is found, else the slicer model chooses. "
                   "0: no choice, the search's own best.")
@click.option("--pareto", "pareto_count", type=click.IntRange(min=2), default=None,
              help="Also return up to N poses along the front of least support against least distortion: "
                   "OUT-1 .. OUT-N (least support first), their poses and OUT-front.png.")
@click.option("--pareto-method", type=click.Choice(["nsga2", "sweep"]), default="nsga2", show_default=True,
              help="How the front is found: NSGA-II after the single search, or a sweep of the distortion weight.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
@click.option("--verbose", "-v", is_flag=True, help="Also show the support estimates (prisms, columns, predicted).")
@slicer_options
def optimize(model, skeleton, up, tets, weights, height_mm, keep_units, no_cache, cache_dir, output, upright_out,
             report_path, pose, pictures, slice_check_flag, slice_rank_count, pareto_count, pareto_method, quiet,
             verbose, slicer, support, cura_definitions, **search_options):
    """Search a pose (and print orientation) of MODEL that needs less support, and write it."""
    from ..report.report import build_report

    standing_out = search_options.pop("standing_out")
    for path in (output, upright_out, standing_out):
        _check_mesh_path(path)
    profile_path = search_options.pop("printer_profile")
    bones, skeleton_out = search_options.pop("bones"), search_options.pop("skeleton_out")
    front_files = []
    if pareto_count:
        from .pareto import front_paths

        if slice_rank_count:
            _fail("--pareto and --slice-rank do not go together; choose one")
        meshes, poses, gallery = front_paths(output, pareto_count)
        front_files = [("--pareto", f) for f in (*meshes, *poses, gallery)]
    check_output_paths([("-o", output), ("--upright-out", upright_out), ("--standing-out", standing_out),
                        ("--report", report_path), ("--pose", pose),
                    ("--skeleton-out", skeleton_out), *front_files], [("--pictures", pictures)], _inputs(model, skeleton, tets, weights, profile_path))
    choice, profile = _slicer_setup(slicer, support, cura_definitions, profile_path)
    settings = _settings(profile, **search_options)
    if slice_rank_count == 0:
        settings = settings.replace(choose=False)
    console = _console()
    if slice_rank_count:
        _require_slicer("--slice-rank", choice)
    _check_bones_early(settings, model, skeleton)
    with listening(_announce(console, quiet)):
        rig, frame = _load(model, skeleton, up, tets, weights, no_cache, cache_dir, quiet, height_mm, keep_units,
                           bones=bones, skeleton_out=skeleton_out, warm_up=True)
    if slice_rank_count and rig.dim != 3:
        _fail(f"{model}: --slice-rank slices 3D models only; this one is planar")
    if slice_check_flag and rig.dim != 3:
        _fail(f"{model}: --slice-check slices 3D models only; this one is planar")
    _say_frame(rig, frame, quiet)
    settings = settings.replace(print_height_mm=frame.height_mm)  # the plate contact is judged at the printed size
    with deferred_interrupt(), listening(_announce(console, quiet)):  # Ctrl-C stops the search; what it found is still written
        # 1. searched
        front = _run_front(rig, console, settings, pareto_count, pareto_method, quiet) if pareto_count else None
        result = front.default if front else _run_search(rig, console, settings, quiet)
        if result.interrupted:
            console.print("[yellow]stopped early: writing the best pose found so far[/yellow]")
        extra = {"printer_profile": profile.summary()}
        sliced = False
        if not result.interrupted and front is None:  # 2. sliced
            result, sliced = _slice_choice(rig, result, slice_rank_count, console, profile, frame, quiet, choice)
        if front is not None:
            from .pareto import write_front

            extra["pareto"], front_written = write_front(rig, front, output, frame)
            extra["pareto_seconds"] = front.seconds
        result, report = _reported(rig, result, frame, extra, guard=not slice_check_flag)  # 3. reported
        outputs, more = (output, pose, report_path, pictures, frame), {"upright": upright_out, "standing": standing_out}
        written, failed = _write_outputs(rig, result, report, *outputs, **more)  # 4. written
        if front is not None:
            written += front_written
    stopped = result.interrupted or interrupt_requested()
    for attempt in (0, 1) if slice_check_flag and not failed and not stopped else ():  # 5. slice-checked
        report = _slice_and_report(rig, result, report, report_path, console, frame, output, profile=profile,
                                   choice=choice)
        if attempt or not sliced_worse(report):
            break
        result = rest_instead(rig, result, choice.label if choice is not None else "PrusaSlicer")
        report = build_report(rig, result, frame) | extra
        written, failed = _write_outputs(rig, result, report, *outputs, **more)
    _print_results(console, report, verbose)  # after the files: a closed stdout (| head) loses nothing
    if result.choice is not None:
        _print_choice(console, result.choice, slicer_tried=sliced, label=choice.label)
    for line in fallback_warnings(rig, result):
        click.echo(line, err=True)
    console.print("\n".join(f"  {label}: {path}" for label, path in written))
    if failed:
        sys.exit(EXIT_WRITE_FAILED)
    if stopped:
        click.echo("supportless: interrupted: the best pose found so far is written", err=True)
        sys.exit(EXIT_INTERRUPTED)


def _reported(rig, result, frame, extra: dict, guard: bool):
    """The report of ``result`` (:func:`supportless.report.report.build_report` with ``extra`` added); with
    ``guard`` (no slicer to check the written file), the rest pose in place of an answer the slicer model
    predicts needs more support than it (:func:`supportless.apps.rest_guard.predicted_worse`).
    Returns ``(result, report)``."""
    from ..report.report import build_report

    with step("measuring the report (rest and found pose)"):
        report = build_report(rig, result, frame) | extra
        if guard and predicted_worse(report):
            result = rest_instead(rig, result, "the slicer model's prediction")
            report = build_report(rig, result, frame) | extra
    return result, report


def _announce(console, quiet: bool):
    """A :mod:`supportless.base.progress` listener: one line as each long step starts (none with ``quiet``)."""
    def listen(event, name, seconds):
        if event == "start" and not quiet:
            console.print(f"  {name} ...", highlight=False)
    return listen


def _slice_choice(rig, result, count, console, profile, frame, quiet=False, choice=None):
    """The slicer's choice among the best answers (:func:`supportless.slicing.ranking.slice_choice`).

    ``count`` None: :data:`~supportless.slicing.ranking.SLICE_RANK` answers when the slicer (``choice``, default
    PrusaSlicer) is found and the search weighed simpler answers (its default), else the slicer model's choice
    stands. Returns the result and whether the slicer was asked.
    """
    from ..slicing.prusaslicer import SlicerError
    from ..slicing.ranking import SLICE_RANK, slice_choice

    label = choice.label if choice is not None else "PrusaSlicer"
    if count is None:
        count = SLICE_RANK if result.choice is not None and _slicer_missing(choice) is None else 0
    if count:
        from ..base.crash import stage

        stage("slicing")
        if not quiet:
            console.print(f"choosing among the best answers: slicing up to {count} with {label}, two at a "
                          "time ...")
        try:
            result = slice_choice(rig, result, count, profile=profile, height_mm=frame.height_mm, choice=choice)
        except SlicerError as exc:
            if interrupt_requested():  # Ctrl-C reached the slicer too: keep the model's choice
                console.print("[yellow]interrupted: slicing skipped, writing the slicer model's choice[/yellow]")
                return result, False
            click.echo(f"supportless: error: slicing the answers failed: {exc}", err=True)
            sys.exit(EXIT_MISSING_TOOL)
    return result, bool(count)


def _slice_and_report(rig, result, report, report_path, console, frame, printed=None, required=True, profile=None,
                      choice=None):
    """Slice the rest pose and the file written for printing with the slicer (``choice``, default PrusaSlicer),
    after every output is written.

    The rest pose is sliced in the print frame ``frame``; the found pose is
    ``printed`` itself, read back as a user's slicer opens it, when it is a
    mesh file (else the same vertices placed by ``frame``). Returns the report
    with ``slice_check`` and its ``support`` headline, also written to
    ``report_path``. A missing or failing slicer is one line and exit status 3
    when ``required`` (the outputs already written stay), else the report
    unchanged.
    """
    from ..files.meshes import read_mesh, write_json
    from ..report.report import support_headline
    from ..slicing.prusaslicer import SlicerError, slice_check

    missing = _slicer_missing(choice)
    if missing:
        message = f"{missing}: no slicer check"
        if required:
            click.echo(f"supportless: error: {message}; the other outputs are written", err=True)
            sys.exit(EXIT_MISSING_TOOL)
        console.print(message)
        return report
    label = choice.label if choice is not None else "PrusaSlicer"
    console.print(f"slicing the rest pose and the written file as printed with {label} ...")
    from_file = printed is not None and Path(printed).suffix.lower() in (".stl", ".3mf", ".obj", ".ply", ".off")
    try:
        posed = read_mesh(printed) if from_file else (frame.place(result.print_vertices), rig.faces)
        sliced = slice_check((frame.place(rig.vertices), rig.faces), posed, up=(0.0, 0.0, 1.0), height_mm=None,
                             profile=profile, choice=choice).to_dict()
    except SlicerError as exc:
        click.echo(f"supportless: error: slice check failed: {exc}; the other outputs are written", err=True)
        sys.exit(EXIT_MISSING_TOOL)
    sliced["sliced_file"] = str(printed) if from_file else None
    report = report | {"slice_check": sliced}
    report["support"] = support_headline(report)
    if report_path:
        write_json(report_path, report)
        console.print(f"  report with the slicer's figures: {report_path}")
    return report
