"""``supportless prepare`` and ``supportless apply``: a model's rig made ready, and a saved pose put on it."""

from __future__ import annotations

import sys
import time

import click

from ..files.paths import check_output_paths
from .cli_common import EXIT_WRITE_FAILED, _check_mesh_path, _inputs, _load, _say_frame, rig_options

__all__ = ["apply", "prepare"]


@click.command()
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


@click.command()
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
