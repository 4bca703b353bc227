"""``supportless view``: pose a model in the browser app (:mod:`supportless.apps.ui`)."""

from __future__ import annotations

import click

from .cli_common import _fail, _load, _say_frame, rig_options, start_warm_up

__all__ = ["view"]


@click.command()
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
    warming = start_warm_up()  # a helper compiles the kernels while the page is used; it ends with the app
    if warming.helper is not None:
        click.echo("  compiling the numerical kernels in the background: a first run only (edits are slower until "
                   "it ends, in about 30 s)", err=True)
    if model is not None:
        rig, frame = _load(model, skeleton, up, tets, weights, no_cache, cache_dir, height_mm=height_mm,
                           keep_units=keep_units, bones=bones, skeleton_out=skeleton_out)
        _say_frame(rig, frame)
    run_app(rig, host=host, port=port, block=True, frame=frame, workdir=workdir, open_options=options)
