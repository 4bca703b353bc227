"""What the commands share: exit statuses, one-line errors, loading a rig, the rig and search options.

Separate from :mod:`supportless.apps.cli` (the command group) so that the
commands, each in its own module (:mod:`supportless.apps.cli_optimize`,
:mod:`supportless.apps.cli_batch`, ...), use the same options and errors without
importing the group.
"""

from __future__ import annotations

import errno
import sys
from pathlib import Path

import click

from ..base.errors import InputError, SupportlessError
from ..base.terminal import ClosableStdout, drop_stdout
from ..files.printframe import PRINT_HEIGHT_RANGE_MM, REFERENCE_HEIGHT_MM

EXIT_USER_ERROR = 2
#: Exit status when an output file could not be written (the others were).
EXIT_WRITE_FAILED = 1
#: Exit status of a search stopped by Ctrl-C, after its best pose is written.
EXIT_INTERRUPTED = 130
#: Exit status when a tool the command needs (PrusaSlicer) is missing or fails.
EXIT_MISSING_TOOL = 3


def _fail(message: str) -> None:
    click.echo(f"supportless: error: {message}", err=True)
    sys.exit(EXIT_USER_ERROR)


def _console():
    from rich.console import Console

    return Console(file=ClosableStdout(sys.stdout), highlight=False)


def _load(model, skeleton, up, tets=None, weights=None, no_cache=False, cache_dir=None, quiet=False, height_mm=None,
          keep_units=False, bones=None, skeleton_out=None, warm_up=False):
    """The rig of MODEL and its print frame (:mod:`supportless.files.printframe`; :func:`_say_frame` says it).

    The rig stays in the file's units; ``height_mm`` and ``keep_units`` only
    choose how the files are printed. With ``warm_up`` (a command that searches), a first run's kernels are
    compiled on both cores meanwhile (:mod:`supportless.apps.warmup`).
    """
    from ..base.crash import stage
    from ..files.printframe import rig_print_frame
    from ..rig.load import load_rig

    stage("preparing the rig")

    def progress(msg):
        if not quiet:
            click.echo(f"  {msg} ...", err=True)

    if keep_units and height_mm is not None:
        _fail("--keep-units and --height-mm do not go together; choose one")
    warming = start_warm_up() if warm_up else None
    rig = load_rig(model, skeleton, up, tets=tets, weights=weights, cache=not no_cache, cache_dir=cache_dir,
                   progress=progress, bones=bones, skeleton_out=skeleton_out)
    if warming is not None:
        finish_warm_up(warming, progress, planar=rig.dim != 3)
    source = rig.info.get("gltf")
    if source is not None:  # what was done to the glTF asset, one line per step
        for line in source["log"]:
            if not quiet and not line.startswith("warning"):
                click.echo(f"  glTF: {line}", err=True)
    for warning in rig.info.get("warnings", []):
        if source is not None and warning in source["log"] and not warning.startswith("warning"):
            continue
        click.echo(f"supportless: warning: {rig.name}: {warning.removeprefix('warning: ')}", err=True)
    return rig, rig_print_frame(rig, height_mm, keep_units)


def start_warm_up():
    """:func:`supportless.apps.warmup.start`: a first run's kernels start compiling in a helper process."""
    from .warmup import start

    return start()


def finish_warm_up(warming, progress, planar: bool = False) -> None:
    """Compile the rest of a first run's kernels here and wait for the helper (``progress(message)`` says so);
    a planar figure's search needs none of them: the helper is stopped."""
    if not warming.active:
        return
    if planar:
        warming.cancel()
        return
    progress("compiling the numerical kernels: a first run only, on both cores")
    warming.finish()


def _say_frame(rig, frame, quiet=False) -> None:
    """The printed size in one line on stderr (unless ``quiet``); a size far from a figure's is a warning."""
    if not quiet:
        if rig.info.get("up"):  # the printing direction guessed (--up auto)
            click.echo(f"  {rig.info['up']}", err=True)
        click.echo(f"  {frame.note()}", err=True)
    if (unusual := frame.unusual()) is not None:
        click.echo(f"supportless: warning: {rig.name}: {unusual}", err=True)


#: The type of every command's ``--height-mm``: the printed heights :data:`~supportless.files.printframe.PRINT_HEIGHT_RANGE_MM`
#: allows (the search settings' ``print_height_mm`` range too).
HEIGHT_MM = click.FloatRange(*PRINT_HEIGHT_RANGE_MM)

UP_HELP = ("Printing direction: x|y|z|-x|-y|-z, three numbers '0,1,0', or auto: the file format's convention "
           "(STL/3MF +Z; OBJ/OFF/PLY/glTF +Y), or the flat base the model was cut to stand on.")


def rig_options(f):
    """Options shared by every command that reads a rigged model."""
    f = click.option("--cache-dir", type=click.Path(file_okay=False), default=None,
                     help="Rig cache folder (default: $SUPPORTLESS_CACHE or ~/.cache/supportless).")(f)
    f = click.option("--no-cache", is_flag=True, help="Prepare the rig again; do not read or write the cache.")(f)
    f = click.option("--keep-units", is_flag=True,
                     help="Print the model at the file's own size, its units read as millimetres (glTF metres "
                          "become millimetres).")(f)
    f = click.option("--height-mm", type=HEIGHT_MM, default=None,
                     help=f"Print the rest pose this tall along --up, in millimetres [default: {REFERENCE_HEIGHT_MM:g}]. "
                          "Written files are +Z up, in millimetres, on the plate.")(f)
    f = click.option("--weights", type=click.Path(dir_okay=False), default=None,
                     help="Precomputed skinning weights (.dmat, one row per --tets vertex); for a glTF model "
                          "'skin' (its own weights, the default) or 'bbw' (recomputed).")(f)
    f = click.option("--tets", type=click.Path(dir_okay=False), default=None,
                     help="Precomputed tetrahedral mesh (.mesh) of the model.")(f)
    f = click.option("--up", default="auto", show_default=True, help=UP_HELP)(f)
    f = click.option("--skeleton-out", type=click.Path(dir_okay=False), default=None,
                     help="Write the skeleton used as TGF (e.g. one built from the shape, to edit and pass back "
                          "with --skeleton).")(f)
    f = click.option("--bones", type=click.IntRange(2, 200), default=None,
                     help="About how many bones a skeleton built from the shape gets [default: 8 to 40].")(f)
    f = click.option("--skeleton", "-s", type=click.Path(dir_okay=False), default=None,
                     help="TGF skeleton (default: MODEL with .tgf; a rigged .glb/.gltf needs none; with neither, "
                          "or 'auto', one is built from the shape).")(f)
    return f


class _Group(click.Group):
    """Turns the package's own errors into one line and exit status 2; a failed write into one line and
    :data:`EXIT_WRITE_FAILED`."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except SupportlessError as exc:
            _fail(str(exc))
        except KeyboardInterrupt:
            click.echo("supportless: interrupted", err=True)
            sys.exit(EXIT_INTERRUPTED)
        except BrokenPipeError:  # the reader of stdout went away; the files are written before the summary
            drop_stdout()
            sys.exit(0)
        except OSError as exc:  # a full disk, a read-only or vanished folder while writing: one line
            if exc.errno not in _WRITE_ERRNOS:
                raise
            where = f"{exc.filename}: " if exc.filename else ""
            hint = "free some space" if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG) else \
                "check the permissions, or choose another folder"
            click.echo(f"supportless: error: {where}{exc.strerror or exc}; {hint}", err=True)
            sys.exit(EXIT_WRITE_FAILED)


#: Errors of a file the tool writes that say where and why in one line (:class:`_Group`).
_WRITE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM, errno.EFBIG, errno.EIO}


def _search_options(f):
    """The search's options; their defaults are :class:`~supportless.search.settings.SearchSettings`'s."""
    from ..search.settings import RANGES, SearchSettings

    d = SearchSettings()
    opts = [
        click.option("--optimizer", type=click.Choice(["pso", "cma"]), default=d.optimizer, show_default=True,
                     help="pso: the paper's particle swarm, --particles for --iterations; cma: CMA-ES, "
                          "--particles/5 samples per generation for --iterations generations (faster, "
                          "sometimes worse)."),
        click.option("--particles", default=d.particles, show_default=True, type=click.IntRange(*RANGES["particles"])),
        click.option("--iterations", default=d.iterations, show_default=True,
                     type=click.IntRange(*RANGES["iterations"])),
        click.option("--seed", default=d.seed, show_default=True, type=click.IntRange(*RANGES["seed"])),
        click.option("--polish", default=d.polish, type=click.IntRange(*RANGES["polish"]),
                     help="Generations of a local CMA-ES from the swarm's best pose, small steps [default: on a "
                          "dense model, after the search on its simplified proxy, on the full surface; none "
                          "otherwise]."),
        click.option("--printer-profile", type=click.Path(dir_okay=False), default=None,
                     help="PrusaSlicer config (.ini, File > Export > Export Config) or Cura definition / settings "
                          "(.json): the overhang threshold follows from it, and the slicer slices with it. Default: "
                          "the slicer's own defaults."),
        click.option("--overhang-angle", default=None, type=click.FloatRange(*RANGES["overhang_angle"]),
                     help="Overhang threshold, degrees from the build plate [default: the printer profile's: "
                          f"support_material_threshold + 1, or PrusaSlicer's automatic one, {d.overhang_angle:.1f} "
                          "for its defaults]."),
        click.option("--overhang-margin", default=d.overhang_margin, show_default=True,
                     type=click.FloatRange(*RANGES["overhang_margin"]),
                     help="The search treats faces up to threshold + margin as needing support, so none "
                          "are left just past the threshold, where slicers still support them."),
        click.option("--w-arap", type=float, default=d.w_arap, show_default=True,
                     help="Weight of the distortion term."),
        click.option("--w-overhang", type=float, default=d.w_overhang, show_default=True,
                     help="Weight of the support term."),
        click.option("--w-intersect", type=float, default=d.w_intersect, show_default=True,
                     help="Weight of the self-intersection term."),
        click.option("--overhang-model", type=click.Choice(["prism", "column", "slicer"]), default=d.overhang_model,
                     show_default=True,
                     help="Support estimate the search minimises: the paper's prisms, columns to the body "
                          "below, or the slicer model fitted to PrusaSlicer (3D)."),
        click.option("--w-prior", type=float, default=d.w_prior, show_default=True,
                     help="Weight of the natural-pose prior (turning much of the body costs more)."),
        click.option("--joint-limit", type=click.FloatRange(*RANGES["joint_limit"]), default=d.joint_limit,
                     show_default=True, help="Largest rotation of any joint, degrees (one angle); 0 with "
                                             "--orient free turns the model without posing it."),
        click.option("--chain-limit", type=click.FloatRange(*RANGES["chain_limit"]), default=d.chain_limit,
                     show_default=True,
                     help="Largest turn of a chain's end (a head, a hand, a tail tip) from its rest direction, "
                          "degrees: a limit on the whole chain, where --joint-limit bounds each joint alone "
                          "(180: none)."),
        click.option("--head-limit", type=click.FloatRange(*RANGES["head_limit"]), default=d.head_limit,
                     show_default=True,
                     help="Largest turn of a head from its rest direction, degrees (the chest, neck and head "
                          "together): tighter than --chain-limit, a face is read first (180: none)."),
        click.option("--w-chain", type=click.FloatRange(*RANGES["w_chain"]), default=d.w_chain, show_default=True,
                     help="Weight, inside the natural-pose prior, of how far the chains' ends turn in the world "
                          "(three joints turning one way cost more than three turning different ways)."),
        click.option("--orient", type=click.Choice(["free", "keep"]), default=d.orient, show_default=True,
                     help="free: choose the print orientation with the pose (-o is written turned); "
                          "keep: print the model as it stands."),
        click.option("--min-footprint", "footprint_mm2", type=click.FloatRange(*RANGES["footprint_mm2"]),
                     default=d.footprint_mm2, show_default=True,
                     help="With --orient free, the least area a turned print's first layer rests on, mm² at the "
                          "printed size: a turn onto a tip or an edge is refused (0: no such rule)."),
        click.option("--min-safety", "min_safety", type=click.FloatRange(*RANGES["min_safety"]),
                     default=d.min_safety, show_default=True,
                     help="The answer is never weaker than both the rest pose (as it stands) and this safety factor "
                          "(strength over the stress of a 2 N grip at a hand, head or tail; 0: strength not weighed)."),
        click.option("--limit", "limits", multiple=True,
                     help="Per-bone joint limit BONE=DEGREES (1-based): --limit 5=15 --limit 7=10."),
        click.option("--anatomy/--no-anatomy", default=d.anatomy, show_default=True,
                     help="Keep the joints the bone names identify (knees, elbows, spine, neck of a Mixamo, VRM, "
                          "Unreal or Blender rig) within their range of motion; other bones keep --joint-limit."),
        click.option("--contact/--no-contact", default=d.contact, show_default=True,
                     help="Let a part press into the part it is jointed to, near their shared joint (an arm "
                          "resting against the torso, thighs together); the written body is then one solid, "
                          "the posed surface united with itself. --no-contact: refuse any crossing."),
        click.option("--keep-standing/--no-keep-standing", default=d.keep_standing, show_default=True,
                     help="Reject poses that touch the plate with a new part or would fall over."),
        click.option("--symmetric/--no-symmetric", default=d.symmetric,
                     help="Keep left/right pairs of bones mirror images (found from the rest skeleton), or pose "
                          "each freely [default: mirrored for a figure whose rest skeleton has a mirror plane]."),
        click.option("--fix", multiple=True, help="Bones (1-based, TGF order) to keep fixed: --fix 3,4 or --fix 3 --fix 4."),
        click.option("--free", multiple=True, help="Bones to free even if fixed by default ('all' frees every bone)."),
    ]
    for opt in reversed(opts):
        f = opt(f)
    return f


def _printer_profile(path):
    """The printer profile of ``--printer-profile`` (PrusaSlicer's defaults when None)."""
    from ..files.printer import default_profile, read_printer_profile

    return default_profile() if path is None else read_printer_profile(path)


def _settings(profile=None, **options):
    """The :class:`~supportless.search.settings.SearchSettings` of the search options.

    ``overhang_angle=None`` takes the threshold of ``profile``.
    """
    from ..search.settings import SearchSettings

    from ..energies.materials import material_of

    if options.get("overhang_angle", 0.0) is None:
        options["overhang_angle"] = (profile or _printer_profile(None)).overhang_angle
    options.setdefault("material", material_of(profile).name)  # strength is judged in the profile's filament
    return SearchSettings(**options)  # bad values are InputError: one line


def slicer_options(f):
    """``--slicer``, ``--support`` and ``--cura-definitions``: who measures the support, and which support."""
    from ..slicing.choice import ENGINES, SUPPORTS

    f = click.option("--cura-definitions", type=click.Path(file_okay=False), default=None,
                     help="Folder of Cura's printer definitions (fdmprinter.def.json) [default: "
                          "$SUPPORTLESS_CURA_DEFINITIONS, then the usual install locations].")(f)
    f = click.option("--support", type=click.Choice(SUPPORTS), default="grid", show_default=True,
                     help="Support the slicer lays down: grid (PrusaSlicer's; Cura's normal) or tree (Cura).")(f)
    f = click.option("--slicer", type=click.Choice(ENGINES), default=None,
                     help="Slicer that measures the support [default: PrusaSlicer if found, else Cura; cura for "
                          "--support tree or a Cura .json --printer-profile].")(f)
    return f


def _slicer_setup(slicer, support, cura_definitions, profile_path):
    """The :class:`~supportless.slicing.choice.SlicerChoice` and the printer profile of the options.

    A Cura profile (``.json``) chooses Cura; Cura with no profile takes Cura's defaults, so the search's
    overhang threshold is Cura's. A profile of the other slicer is one line and exit status 2.
    """
    from ..files.printer import cura_default_profile
    from ..slicing.choice import choose_slicer

    profile = _printer_profile(profile_path)
    if slicer is None and profile.slicer == "cura":
        slicer = "cura"
    choice = choose_slicer(slicer, support, cura_definitions)
    if profile_path is None and choice.engine == "cura":
        profile = cura_default_profile()
    if profile.slicer != choice.engine:
        kind = "a Cura profile (.json)" if profile.slicer == "cura" else "a PrusaSlicer config (.ini)"
        _fail(f"{profile_path}: {kind} goes with --slicer {profile.slicer}, not --slicer {choice.engine}")
    return choice, profile


def _slicer_missing(choice=None) -> str | None:
    """One line saying what to install when the chosen slicer (default PrusaSlicer) is missing, else None."""
    if choice is not None and choice.engine == "cura":
        from ..slicing.cura import find_cura_definitions, find_cura_engine, missing_message

        engine = find_cura_engine()
        folder = find_cura_definitions(choice.cura_definitions) if engine else None
        return None if engine and folder else missing_message(engine, folder, choice.cura_definitions)
    from ..slicing.prusaslicer import find_prusa_slicer

    return None if find_prusa_slicer() else ("PrusaSlicer not found (apt-get install prusa-slicer, or set "
                                             "SUPPORTLESS_PRUSA_SLICER)")


def _require_slicer(option: str, choice=None) -> None:
    """Exit with one line (status 3) before any work when the chosen slicer (default PrusaSlicer) is missing."""
    missing = _slicer_missing(choice)
    if missing:
        who = "PrusaSlicer" if choice is None or choice.engine == "prusa" else "Cura"
        click.echo(f"supportless: error: {option} needs {who}: {missing}", err=True)
        sys.exit(EXIT_MISSING_TOOL)


def _check_bones_early(settings, model, skeleton) -> None:
    """--fix, --free and --limit against a TGF skeleton before the (long) rig preparation."""
    from ..files.meshes import read_tgf

    tgf = Path(skeleton) if skeleton else Path(model).with_suffix(".tgf")
    if tgf.suffix.lower() == ".tgf" and tgf.is_file() and not str(model).startswith("demo:"):
        settings.check_bones(len(read_tgf(tgf)[1]))


def _inputs(model, skeleton=None, tets=None, weights=None, *more):
    """The files a command reads: MODEL, its skeleton (given or MODEL.tgf), tets, weights and ``more``."""
    default_skeleton = Path(model).with_suffix(".tgf") if model and not str(model).startswith("demo:") else None
    return [p for p in (model, skeleton, default_skeleton, tets, weights, *more) if p]


def _check_mesh_path(path) -> None:
    """A mesh output path with a known format, or InputError (None is allowed)."""
    from ..files.meshes import MESH_FORMATS

    if path is None:
        return
    ext = Path(path).suffix.lower().lstrip(".")
    if ext not in MESH_FORMATS + ("gltf",):
        raise InputError(path, f"unknown output format '.{ext}'; use one of {', '.join(MESH_FORMATS + ('gltf',))}")
