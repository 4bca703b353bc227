"""``supportless demo``: the whole pipeline on a built-in figure, its files written to one folder.

The same steps as ``optimize`` (:mod:`supportless.apps.cli_optimize`), with a
quicker search and the rest pose's files beside the answer's.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import click

from ..files.paths import check_output_paths
from ..search.settings import SearchSettings
from ..shapes import DEMO_FIGURES
from .cli_common import EXIT_WRITE_FAILED, _console, _settings, finish_warm_up, start_warm_up
from .cli_optimize import _run_search, _slice_and_report, _write_outputs
from .cli_summary import _print_results

__all__ = ["demo"]


@click.command()
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
    warming = start_warm_up()
    rig = load_rig(f"demo:{figure}", up="y")
    console.print(f"{figure}: {len(rig.vertices)} vertices, {len(rig.faces)} faces, {len(rig.tets)} "
                  f"{'tets' if rig.dim == 3 else 'triangles'}, {rig.bone_count} bones; "
                  f"rig ready in {time.perf_counter() - t0:.1f} s")
    finish_warm_up(warming, lambda message: None if quiet else console.print(f"  {message} ...", highlight=False),
                   planar=rig.dim != 3)
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
