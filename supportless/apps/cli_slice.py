"""``supportless slice-check``: the support a real slicer lays down for two mesh files, the original and the posed."""

from __future__ import annotations

import json

import click

from ..files.printframe import REFERENCE_HEIGHT_MM
from .cli_common import HEIGHT_MM, UP_HELP, _fail, _slicer_setup, slicer_options

__all__ = ["slice_check_cmd"]


@click.command(name="slice-check")
@click.argument("original", type=click.Path(dir_okay=False))
@click.argument("posed", type=click.Path(dir_okay=False))
@click.option("--up", default="auto", show_default=True, help="Printing direction of ORIGINAL. " + UP_HELP)
@click.option("--height-mm", default=REFERENCE_HEIGHT_MM, show_default=True, type=HEIGHT_MM,
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


def _grams_and_time(side: dict) -> str:
    """``6.4 g, 26 min of printing`` of one side of a slice report."""
    from ..report.report import duration_text

    grams = f"{side['support_g']:.1f} g" if side.get("support_g") is not None else "? g"
    t = side.get("support_time_s")
    return grams + (f", {duration_text(t)} of printing" if t is not None else "")
