"""The ``supportless`` command line: thin commands over the Python API.

Every user error (bad file, bad option) prints one line on stderr and exits
with status 2; nothing half-written is left on disk.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click
import numpy as np

from ..base.errors import InputError
from ..base.interrupt import deferred_interrupt
from ..base.interrupt import requested as interrupt_requested
from ..base.progress import listening, step
from ..files.paths import check_output_paths
from ..files.printframe import REFERENCE_HEIGHT_MM
from ..search.settings import RANGES, SearchSettings
from ..shapes import DEMO_FIGURES
from .cli_batch import batch
from .rest_guard import fallback_warnings, predicted_worse, rest_instead, sliced_worse
from .cli_common import (
    EXIT_INTERRUPTED,
    EXIT_MISSING_TOOL,
    EXIT_WRITE_FAILED,
    UP_HELP,
    _check_bones_early, _console, _contact_line, _print_choice, strength_rows,
    _fail,
    _Group,
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

__all__ = ["main"]

@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="supportless")
def main():
    """Re-pose a rigged model so it 3D-prints with less support material."""


# --------------------------------------------------------------------------- #
@main.command()
@click.argument("model", type=click.Path(dir_okay=False))
@rig_options
def prepare(model, skeleton, up, tets, weights, height_mm, keep_units, no_cache, cache_dir, bones=None,
            skeleton_out=None):
    """Tetrahedralise MODEL and compute its skinning weights (cached)."""
    t0 = time.perf_counter()
    rig, _ = _load(model, skeleton, up, tets, weights, no_cache, cache_dir, height_mm=height_mm, keep_units=keep_units,
                   bones=bones, skeleton_out=skeleton_out)
    dt = time.perf_counter() - t0
    source = "from the cache" if rig.info.get("from_cache") else "prepared"
    click.echo(f"{rig.name}: {len(rig.vertices)} vertices, {len(rig.faces)} faces, {len(rig.tets)} "
               f"{'tets' if rig.dim == 3 else 'triangles'}, {rig.bone_count} bones, {rig.dim}D")
    click.echo(f"{source} in {dt:.2f} s" + (f"  (cache: {rig.info['cache']})" if rig.info.get("cache") else ""))
    if rig.info.get("up"):
        click.echo(rig.info["up"])


# --------------------------------------------------------------------------- #
def _run_search(rig, console, settings, quiet=False):
    """Run the search with a progress bar; returns the PoseResult."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from ..base.crash import stage

    stage("searching")

    from ..search.anatomy import joint_ranges
    from ..search.optimizer import optimize

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


def _standing_word(before: dict, after: dict) -> str:
    """How the found pose stands, said against the rest pose."""
    if after["stands"]:
        return "stands"
    if not before["stands"] and after.get("as_steady_as_rest"):
        return "does not stand, nor does the rest pose (no worse)"
    return "FALLS OVER" if after["stability_margin"] < 0 else "touches the plate anew"


def _summary_table(report: dict, verbose: bool = False):
    """The rest pose against the found pose; the support estimates only when ``verbose``.

    Volumes and areas are shown in the print frame's millimetres (the report
    keeps them in the model's units).
    """
    from rich.table import Table

    b, a, red = report["before"], report["after"], report["reduction_percent"]
    scale = (report.get("print_frame") or {}).get("scale", 1.0)

    def pct(x):  # a reduction of 40 % shows as -40.0 %
        return "-" if x is None else f"{-x:+.1f} %"

    def cm3(x):  # a volume of the model's units^3, in cm3 as printed
        return f"{x * scale ** 3 / 1000:,.2f} cm3"

    def mm3(x):
        return f"{x * scale ** 3:,.1f} mm3"

    table = Table(title=f"{report['model']}: rest pose vs found pose")
    for col in ("measure", "before", "after", "change"):
        table.add_column(col, justify="right" if col != "measure" else "left")
    if verbose:
        predicted = report.get("predicted_slicer")
        if predicted:
            fraction = predicted["reduction"]
            table.add_row(f"estimate: PrusaSlicer's support filament ({predicted['height_mm']:g} mm tall)",
                          f"{predicted['before_mm']:,.0f} mm", f"{predicted['after_mm']:,.0f} mm",
                          pct(None if fraction is None else 100 * fraction))
        table.add_row("estimate: support volume (prisms)", cm3(b["support_prism"]), cm3(a["support_prism"]),
                      pct(red["support_prism"]))
        table.add_row("estimate: support volume (columns)", cm3(b["support_column"]), cm3(a["support_column"]),
                      pct(red["support_column"]))
        table.add_row("area needing support", f"{b['risky_area'] * scale ** 2:,.0f} mm2",
                      f"{a['risky_area'] * scale ** 2:,.0f} mm2", pct(red["risky_area"]))
    table.add_row("distortion (ARAP / volume)", f"{b['terms']['arap']:.3f}", f"{a['terms']['arap']:.3f}", "")
    table.add_row("self-intersection volume", mm3(b["self_intersection_volume"]),
                  mm3(a["self_intersection_volume"]), "")

    def pairs(x):
        return "n/a (2D)" if x is None or x < 0 else str(x)

    table.add_row("intersecting face pairs (exact)", pairs(b.get("intersecting_face_pairs")),
                  pairs(a.get("intersecting_face_pairs")), "contact: one solid as written" if report.get("contacts") else "")
    table.add_row("new contacts with the plate", str(b["new_contact_vertices"]), str(a["new_contact_vertices"]), "")
    table.add_row("stability margin (of the height)", f"{100 * b['stability_margin']:.1f} %",
                  f"{100 * a['stability_margin']:.1f} %", _standing_word(b, a))
    table.add_row("largest joint rotation", "0°", f"{report['largest_rotation_deg']:.0f}°", "")
    natural = report.get("naturalness") or {}
    if natural.get("largest_chain_turn_deg") is not None:
        end = natural.get("chain_end_name") or f"bone {natural['chain_end']}"
        table.add_row("largest turn of a chain's end", "0°", f"{natural['largest_chain_turn_deg']:.0f}°", end)
    sym = report.get("symmetry")
    if sym and sym.get("free_mm") is not None:
        table.add_row("left and right", "mirrored", sym["kept"],
                      f"predicted support: mirrored {sym['mirrored_mm']:,.0f} mm, free {sym['free_mm']:,.0f} mm "
                      f"(free kept only {100 * sym['share']:.0f} % below)")
    use = natural.get("joint_range")
    if use:
        table.add_row("named joint nearest its range", "", f"{use['angle_deg']:.0f}° of {use['limit_deg']:.0f}°",
                      f"{use['joint']} ({use['measure']})"
                      + (f", {use['outside_deg']:.0f}° outside" if use["outside_deg"] >= 0.5 else ""))
    for row in strength_rows(report):
        table.add_row(*row)
    rot = report.get("print_rotation")
    if rot and rot["angle_deg"] >= 0.5:  # a turn that shows in whole degrees
        up = report["up"]
        table.add_row("printed turned by", "0°", f"{rot['angle_deg']:.0f}°",
                      f"model {[round(x, 2) for x in rot['printing_direction_in_model_frame']]} up, was {up}")
        if report.get("footprint"):  # the first layer's contact (a turn rests on at least the bound)
            fp = report["footprint"]
            table.add_row("first layer on the plate", f"{fp['rest_mm2']:.0f} mm²", f"{fp['answer_mm2']:.0f} mm²",
                          f"a turn rests on ≥ {fp['bound_mm2']:g} mm²")
        if verbose:
            table.add_row("estimate: support standing (prisms)", cm3(b["support_prism"]),
                          cm3(a["upright"]["support_prism"]),
                          pct(None if b["support_prism"] <= 0 else
                              100 * (1 - a["upright"]["support_prism"] / b["support_prism"])))
    return table


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


def _inputs(model, skeleton=None, tets=None, weights=None, *more):
    """The files a command reads: MODEL, its skeleton (given or MODEL.tgf), tets, weights and ``more``."""
    default_skeleton = Path(model).with_suffix(".tgf") if model and not str(model).startswith("demo:") else None
    return [p for p in (model, skeleton, default_skeleton, tets, weights, *more) if p]


@main.command()
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
                           bones=bones, skeleton_out=skeleton_out)
    if slice_rank_count and rig.dim != 3:
        _fail(f"{model}: --slice-rank slices 3D models only; this one is planar")
    if slice_check_flag and rig.dim != 3:
        _fail(f"{model}: --slice-check slices 3D models only; this one is planar")
    _say_frame(rig, frame, quiet)
    settings = settings.replace(print_height_mm=frame.height_mm)  # the plate contact is judged at the printed size
    with deferred_interrupt(), listening(_announce(console, quiet)):  # Ctrl-C stops the search; what it found is still written
        front = _run_front(rig, console, settings, pareto_count, pareto_method, quiet) if pareto_count else None
        result = front.default if front else _run_search(rig, console, settings, quiet)
        if result.interrupted:
            console.print("[yellow]stopped early: writing the best pose found so far[/yellow]")
        extra = {"printer_profile": profile.summary()}
        sliced = False
        if not result.interrupted and front is None:
            result, sliced = _slice_choice(rig, result, slice_rank_count, console, profile, frame, quiet, choice)
        if front is not None:
            from .pareto import write_front

            extra["pareto"], front_written = write_front(rig, front, output, frame)
            extra["pareto_seconds"] = front.seconds
        with step("measuring the report (rest and found pose)"):
            report = build_report(rig, result, frame) | extra
            if not slice_check_flag and predicted_worse(report):  # without a slicer, the prediction guards
                result = rest_instead(rig, result, "the slicer model's prediction")
                report = build_report(rig, result, frame) | extra
        outputs, more = (output, pose, report_path, pictures, frame), {"upright": upright_out, "standing": standing_out}
        written, failed = _write_outputs(rig, result, report, *outputs, **more)
        if front is not None:
            written += front_written
    stopped = result.interrupted or interrupt_requested()
    for attempt in (0, 1) if slice_check_flag and not failed and not stopped else ():  # the slicer's word leads
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


def _print_results(console, report, verbose=False):
    """The one support figure, the before/after table and the search time."""
    headline = report.get("support")
    if headline:
        console.print(headline["line"])
    console.print(_summary_table(report, verbose))
    console.print(_contact_line(report))
    console.print(f"search took {report['runtime_seconds']:.1f} s")


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


# --------------------------------------------------------------------------- #
@main.command()
@click.argument("model", type=click.Path(dir_okay=False))
@rig_options
@click.option("--pose", type=click.Path(dir_okay=False), required=True, help="Pose JSON from `optimize --pose`.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="Posed mesh to write, in the pose's print orientation: +Z up, in millimetres, on the plate.")
@click.option("--upright-out", type=click.Path(dir_okay=False), default=None,
              help="Also write the posed mesh standing as the input stood.")
def apply(model, skeleton, up, tets, weights, height_mm, keep_units, no_cache, cache_dir, pose, output, upright_out,
          bones=None, skeleton_out=None):
    """Apply a saved pose (and its print orientation) to MODEL and write the posed mesh.

    The mesh is printed as tall as the pose file says (the height `optimize`
    wrote it at) unless --height-mm or --keep-units says otherwise.
    """
    from ..base.geometry import place_on_plate, print_pose
    from ..files.posefile import read_pose, read_pose_print_frame, read_print_rotation
    from ..report.outputs import write_posed

    for path in (output, upright_out):
        _check_mesh_path(path)
    check_output_paths([("-o", output), ("--upright-out", upright_out)], (),
                       _inputs(model, skeleton, tets, weights, pose))
    saved = read_pose_print_frame(pose)
    if height_mm is None and not keep_units and saved is not None:
        keep_units = saved["how"] == "units"
        height_mm = None if keep_units else saved["height_mm"]
    rig, frame = _load(model, skeleton, up, tets, weights, no_cache, cache_dir, height_mm=height_mm,
                       keep_units=keep_units, bones=bones, skeleton_out=skeleton_out)
    angles = read_pose(pose, rig.bones, tree=rig.tree, root_bone=rig.root_bone)
    R = read_print_rotation(pose, rig.dim)
    _say_frame(rig, frame)
    standing = place_on_plate(rig.pose(angles), rig.up)
    failed = 0
    for path, printed in ((output, True), (upright_out, False)):
        if path:
            try:
                write_posed(path, rig, angles, standing, print_pose(standing, R, rig.up) if printed else standing,
                             frame)
            except OSError as exc:  # a full disk, a folder not writable: one line, as optimize says it
                failed += 1
                click.echo(f"supportless: error: {exc.filename or path}: cannot write: {exc.strerror or exc}",
                           err=True)
                continue
            click.echo(f"wrote {path}")
    if failed:
        sys.exit(EXIT_WRITE_FAILED)


def _check_mesh_path(path) -> None:
    """A mesh output path with a known format, or InputError (None is allowed)."""
    from ..files.meshes import MESH_FORMATS

    if path is None:
        return
    ext = Path(path).suffix.lower().lstrip(".")
    if ext not in MESH_FORMATS + ("gltf",):
        raise InputError(path, f"unknown output format '.{ext}'; use one of {', '.join(MESH_FORMATS + ('gltf',))}")


def _grams_and_time(side: dict) -> str:
    """``6.4 g, 26 min of printing`` of one side of a slice report."""
    from ..report.report import duration_text

    grams = f"{side['support_g']:.1f} g" if side.get("support_g") is not None else "? g"
    t = side.get("support_time_s")
    return grams + (f", {duration_text(t)} of printing" if t is not None else "")


# --------------------------------------------------------------------------- #
@main.command(name="slice-check")
@click.argument("original", type=click.Path(dir_okay=False))
@click.argument("posed", type=click.Path(dir_okay=False))
@click.option("--up", default="auto", show_default=True, help="Printing direction of ORIGINAL. " + UP_HELP)
@click.option("--height-mm", default=REFERENCE_HEIGHT_MM, show_default=True, type=click.FloatRange(min=1.0),
              help="ORIGINAL is scaled to this height along --up.")
@click.option("--posed-as", type=click.Choice(["written", "original"]), default="written", show_default=True,
              help="written: POSED is a print file (as `optimize -o` writes it: +Z up, millimetres) and is sliced "
                   "as it is; original: POSED is in ORIGINAL's frame and units (its --up, the same scale).")
@click.option("--printer-profile", type=click.Path(dir_okay=False), default=None,
              help="PrusaSlicer config (.ini) or Cura definition / settings (.json) to slice with [default: the "
                   "slicer's own defaults].")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@slicer_options
def slice_check_cmd(original, posed, up, height_mm, posed_as, printer_profile, as_json, slicer, support,
                    cura_definitions):
    """Measure the support a slicer (PrusaSlicer, or Cura's normal or tree supports) lays down for ORIGINAL and
    POSED."""
    from ..base.geometry import parse_up
    from ..files.meshes import read_mesh
    from ..files.printframe import print_frame
    from ..files.upaxis import guess_up
    from ..report.report import duration_text
    from ..slicing.prusaslicer import SlicerError, SlicerNotFound, slice_check

    choice, profile = _slicer_setup(slicer, support, cura_definitions, printer_profile)
    (Vo, Fo), (Vp, Fp) = read_mesh(original), read_mesh(posed)
    up_vec = guess_up(Vo, Fo, original)[0] if up.strip().lower() == "auto" else parse_up(up)
    frame = print_frame(Vo, up_vec, height_mm)
    placed = (frame.place(Vp) if posed_as == "original" else Vp, Fp)
    try:
        report = slice_check((frame.place(Vo), Fo), placed, up=(0.0, 0.0, 1.0), height_mm=None,
                             profile=profile if printer_profile else None, choice=choice).to_dict()
    except (SlicerNotFound, SlicerError) as exc:
        _fail(str(exc))
    if as_json:
        click.echo(json.dumps(report, indent=2))
        return
    b, a = report["before"], report["after"]
    click.echo(f"support filament at {height_mm:g} mm tall ({choice.label}):")
    click.echo(f"  original: {b['support_mm']:8.0f} mm  ({b['support_cm3']:.2f} cm3, {_grams_and_time(b)})")
    click.echo(f"  posed:    {a['support_mm']:8.0f} mm  ({a['support_cm3']:.2f} cm3, {_grams_and_time(a)})")
    if b["support_time_s"] is not None and a["support_time_s"] is not None:
        saved = b["support_time_s"] - a["support_time_s"]
        click.echo(f"  printing time of the supports: {duration_text(saved)} {'less' if saved >= 0 else 'more'}")
    red = report["reduction_percent"]
    click.echo(f"  reduction: {red:.1f} %" if red is not None else "  reduction: n/a (no support before)")


# --------------------------------------------------------------------------- #
@main.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="supportless-demo", show_default=True,
              help="Folder for the demo's files.")
@click.option("--figure", type=click.Choice(list(DEMO_FIGURES)), default="tpose", show_default=True,
              help="Built-in figure.")
@click.option("--particles", default=60, show_default=True, type=click.IntRange(2, None))
@click.option("--iterations", default=40, show_default=True, type=click.IntRange(0, None))
@click.option("--seed", default=0, show_default=True, type=click.IntRange(min=0))
@click.option("--quiet", "-q", is_flag=True)
def demo(out_dir, figure, particles, iterations, seed, quiet):
    """Run the whole pipeline on a built-in figure and write its files.

    The demo's search is a quick one (60 particles x 40 iterations by
    default); `supportless optimize` runs the full 200 x 120.
    """
    from ..energies.overhang import risky_faces
    from ..files.meshes import write_mesh, write_tgf
    from ..files.printframe import rig_print_frame
    from ..report.render import render_mesh
    from ..report.report import build_report
    from ..rig.load import load_rig

    settings = _settings(particles=particles, iterations=iterations, seed=seed)
    check_output_paths((), [("--out", out_dir)])
    console = _console()
    out = Path(out_dir)
    t0 = time.perf_counter()
    rig = load_rig(f"demo:{figure}", up="y")
    console.print(f"{figure}: {len(rig.vertices)} vertices, {len(rig.faces)} faces, {len(rig.tets)} "
                  f"{'tets' if rig.dim == 3 else 'triangles'}, {rig.bone_count} bones; "
                  f"rig ready in {time.perf_counter() - t0:.1f} s")
    frame = rig_print_frame(rig)
    console.print(f"{frame.note()}")
    rest_mesh = out / f"{figure}-rest.stl" if rig.dim == 3 else out / f"{figure}-rest.obj"
    write_mesh(rest_mesh, frame.place(rig.vertices), rig.faces)
    write_tgf(out / f"{figure}.tgf", rig.joints, rig.bones)
    risky = risky_faces(rig.vertices, rig.faces, rig.up, settings.overhang_angle) if rig.dim == 3 else None
    rest_png = render_mesh(out / f"{figure}-rest.png", rig.vertices, rig.faces, rig.up, rig.joints, rig.bones,
                           risky=risky, title=f"{figure}: rest pose")
    full = SearchSettings()
    console.print(f"search: {settings.particles} particles x {settings.iterations} iterations, the demo's quick "
                  f"search (`supportless optimize` runs {full.particles} x {full.iterations})")
    result = _run_search(rig, console, settings, quiet)
    report = build_report(rig, result, frame)
    posed_ext = "stl" if rig.dim == 3 else "obj"
    report_path = out / f"{figure}-report.json"
    posed_path = out / f"{figure}-posed.{posed_ext}"
    written, failed = _write_outputs(rig, result, report, posed_path, out / f"{figure}-pose.json", report_path, out,
                                     frame, upright=out / f"{figure}-posed-standing.{posed_ext}")
    if rig.dim == 3 and not failed:  # the slicer's figures when PrusaSlicer is there; the demo runs without it
        report = _slice_and_report(rig, result, report, report_path, console, frame, posed_path, required=False)
    _print_results(console, report)
    console.print(f"wrote to {out}/:")
    console.print(f"  rest mesh: {rest_mesh}\n  skeleton: {out / f'{figure}.tgf'}\n  rest picture: {rest_png}")
    console.print("\n".join(f"  {label}: {path}" for label, path in written))
    if failed:
        sys.exit(EXIT_WRITE_FAILED)


# --------------------------------------------------------------------------- #
@main.command()
@click.argument("model", required=False, type=click.Path(dir_okay=False))
@rig_options
@click.option("--demo", "demo_figure", is_flag=True, help="Open the built-in tpose figure.")
@click.option("--port", default=None, type=click.IntRange(1, 65535), help="Port (default: a free one from 8080).")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to bind; another than a loopback address opens the app to the network (its token "
                   "still required).")
@click.option("--workdir", type=click.Path(file_okay=False, exists=True), default=".", show_default=True,
              help="The only folder the page reads and writes files in.")
def view(model, skeleton, up, tets, weights, height_mm, keep_units, no_cache, cache_dir, demo_figure, port, host,
         workdir, bones=None, skeleton_out=None):
    """Pose MODEL in the browser: live supports, optimize, slice, download.

    Without MODEL the page starts empty: drop a glTF character, or a mesh
    with its .tgf skeleton, onto it. Only the address printed (with its
    token) opens the page.
    """
    from .ui.app import run_app
    from .ui.opener import OpenOptions

    if keep_units and height_mm is not None:
        _fail("--keep-units and --height-mm do not go together; choose one")
    options = OpenOptions(up=up, height_mm=height_mm, keep_units=keep_units, cache=not no_cache, cache_dir=cache_dir)
    if demo_figure:
        model = "demo:tpose"
    rig = frame = None
    if model is not None:
        rig, frame = _load(model, skeleton, up, tets, weights, no_cache, cache_dir, height_mm=height_mm,
                           keep_units=keep_units, bones=bones, skeleton_out=skeleton_out)
        _say_frame(rig, frame)
    run_app(rig, host=host, port=port, block=True, frame=frame, workdir=workdir, open_options=options)


# --------------------------------------------------------------------------- #
@main.command()
@click.argument("model", required=False, type=click.Path(dir_okay=False))
@click.option("--skeleton", "-s", type=click.Path(dir_okay=False), default=None)
@click.option("--up", default="auto", show_default=True, help=UP_HELP)
@click.option("--particles", default=SearchSettings.particles, show_default=True,
              type=click.IntRange(*RANGES["particles"]))
@click.option("--iterations", default=SearchSettings.iterations, show_default=True,
              type=click.IntRange(1, RANGES["iterations"][1]))
@click.option("--backend", type=click.Choice(["fast", "numpy", "both"]), default="both", show_default=True)
@click.option("--targets", is_flag=True,
              help="Instead: the speed targets of big rigs (bunny, bb-bunny, a 68-bone character, the glTF robot, "
                   "a 111k-triangle bunny), each prepared and searched in its own process.")
@click.option("--reference", is_flag=True, help="With --targets: also search the full surface of the cases "
                                                "that have a simplified proxy (slow).")
def bench(model, skeleton, up, particles, iterations, backend, targets, reference):
    """Time preparation, one pose, one swarm iteration and a whole search."""
    if targets:
        from .bench_targets import run_targets

        rows = run_targets(reference=reference, echo=click.echo)
        sys.exit(1 if any("error" in r and not r.get("missing") for r in rows) else 0)
    from .bench import run_bench

    run_bench(model, skeleton, up, particles=particles, iterations=iterations, backend=backend,
              echo=click.echo)


main.add_command(batch)


def run() -> None:
    """The ``supportless`` executable: :func:`main` under :func:`supportless.base.crash.supervised` (a crash is one line)."""
    from ..base.crash import supervised

    sys.exit(supervised(main))


if __name__ == "__main__":  # pragma: no cover
    run()
