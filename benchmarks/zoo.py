"""The zoo: the default search on every built-in 3D figure and the shared models, checked with PrusaSlicer.

For each model: ``supportless.optimize(rig, SearchSettings())`` (the tool's
defaults unless ``--particles/--iterations/--seed`` say otherwise), the report
of :func:`supportless.report.report.build_report`, and PrusaSlicer on the rest and
the found pose (60 mm tall, its default print settings). Prints a Markdown
table, writes it as the "## Zoo" section of ``--out`` (replacing an older one),
and draws a contact sheet of before/after pictures (``--sheet``, default
``docs/zoo.png``); ``--keep DIR`` also keeps each model's pictures.

    python benchmarks/zoo.py [--models tpose dragon bunny ...] [--particles N] [--iterations N] [--seed S]
        [--out benchmarks/RESULTS.md] [--sheet docs/zoo.png] [--keep DIR]
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import models
import numpy as np
from models import DATA, SHARED, available, write_section

import supportless as sl
from supportless.base.kinematics import euler_to_matrix
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.report.report import build_report, write_pictures
from supportless.slicing.prusaslicer import SlicerError, slice_check

ROOT = Path(__file__).resolve().parents[1]
HEADING = "## Zoo"



def _mm(x: float) -> str:
    """Millimetres of filament, whole; a difference within rounding of 0 (e.g. -0.3) reads 0, not -0."""
    return f"{0.0 if abs(x) < 0.5 else x:.0f}"

def zoo_figures() -> list[str]:
    """The built-in figures that are 3D (every one but the planar ``woody2d``)."""
    return [name for name in sl.DEMO_FIGURES if sl.demo_figure(name)[0].shape[1] == 3]


def load(name: str):
    """The rig of a built-in figure or of a shared model (up ``y``); None with the reason when it is missing."""
    if not available(name):
        return None, f"missing {DATA / name}.obj or .tgf"
    return models.load(name), None


def largest_rotation_deg(report: dict, angles: np.ndarray) -> float:
    """The report's largest joint rotation, or the largest geodesic angle of the bones' relative rotations.

    Parameters
    ----------
    report : dict
        From :func:`~supportless.report.report.build_report`.
    angles : (m, 3) float64
        Relative XYZ Euler angles of the found pose, radians.

    Returns
    -------
    degrees : float
    """
    if report.get("largest_rotation_deg") is not None:
        return float(report["largest_rotation_deg"])
    R = euler_to_matrix(angles)
    cos = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    return float(np.degrees(np.arccos(cos)).max())


def run(name: str, settings, pictures: Path) -> dict:
    """Search, report, slice and draw one model; a row of the table."""
    rig, reason = load(name)
    if rig is None:
        return {"model": name, "skipped": reason}
    t0 = time.perf_counter()
    result = sl.optimize(rig, settings)
    seconds = time.perf_counter() - t0
    report = build_report(rig, result)
    row = {"model": name, "bones": rig.bone_count, "seconds": seconds, "report": report,
           "rotation": largest_rotation_deg(report, result.angles)}
    try:
        row["slicer"] = slice_check((rig.vertices, rig.faces), (result.print_vertices, rig.faces), up=rig.up,
                                    height_mm=REFERENCE_HEIGHT_MM).to_dict()
    except SlicerError as exc:  # SlicerNotFound included
        row["slicer_error"] = str(exc).splitlines()[0]
    written = dict(write_pictures(pictures / name, rig, result, report))
    row["picture"] = written["before/after picture"]
    return row


def _num(x, spec: str, unit: str = "") -> str:
    return "–" if x is None else f"{format(x, spec)}{unit}"


def table(rows: list[dict]) -> str:
    """The Markdown table of the rows that ran."""
    lines = ["| model | bones | support mm before → after (PrusaSlicer) | reduction PrusaSlicer / estimate "
             "| distortion (arap) | largest joint rotation | largest chain-end turn | mirror error "
             "| stability margin | new contacts | exact intersecting pairs | search time |",
             "|" + "---|" * 12]
    for r in rows:
        if "skipped" in r:
            continue
        rep, s = r["report"], r.get("slicer")
        after = rep["after"]
        support = (f"{_mm(s['before']['support_mm'])} → {_mm(s['after']['support_mm'])}" if s
                   else f"not sliced ({r.get('slicer_error', '')})")
        sliced = _num(s["reduction_percent"], ".1f", " %") if s else "–"
        lines.append(
            f"| {r['model']} | {r['bones']} | {support} "
            f"| {sliced} / {_num(rep['reduction_percent']['support_prism'], '.1f', ' %')} "
            f"| {after['terms']['arap']:.4f} | {r['rotation']:.0f}° "
            f"| {_num(rep['naturalness']['largest_chain_turn_deg'], '.0f', '°')} "
            f"| {_num(rep['naturalness']['mirror_error_deg'], '.0f', '°')} "
            f"| {_num(after.get('stability_margin'), '.3f')} "
            f"| {_num(after.get('new_contact_vertices'), 'd')} | {after['intersecting_face_pairs']} "
            f"| {r['seconds']:.1f} s |")
    return "\n".join(lines)


def summary(rows: list[dict], figures: list[str]) -> str:
    """Mean and worst PrusaSlicer reduction over the built-in figures that were sliced."""
    done = [(r["model"], r["slicer"]["reduction_percent"]) for r in rows
            if r["model"] in figures and r.get("slicer") and r["slicer"]["reduction_percent"] is not None]
    if not done:
        return "No built-in figure was sliced."
    values = np.array([v for _, v in done])
    worst = done[int(np.argmin(values))]
    return (f"PrusaSlicer reduction over the {len(done)} built-in figures: mean {values.mean():.1f} %, "
            f"worst {worst[1]:.1f} % ({worst[0]}).")


def contact_sheet(rows: list[dict], path: Path, columns: int = 3) -> None:
    """One before/after picture per model in a grid, written to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt

    drawn = [r for r in rows if r.get("picture")]
    if not drawn:
        return
    n_rows = -(-len(drawn) // columns)
    fig, axes = plt.subplots(n_rows, columns, figsize=(6.4 * columns, 3.3 * n_rows), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, r in zip(axes.ravel(), drawn):
        ax.imshow(mpimg.imread(r["picture"]))
        s = r.get("slicer")
        ax.set_title(f"{r['model']}: PrusaSlicer support {_num(s['reduction_percent'], '.0f', ' %') if s else '–'}"
                     " less", fontsize=11)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def section(rows: list[dict], figures: list[str], settings, command: str) -> str:
    """The "## Zoo" section: settings, machine, command, table and summary."""
    skipped = [f"{r['model']} ({r['skipped']})" for r in rows if "skipped" in r]
    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return "\n".join([
        HEADING,
        "",
        f"The default search (`SearchSettings()`: {settings.particles} particles × {settings.iterations} "
        f"iterations, seed {settings.seed}, search margin {settings.overhang_margin:g}°"
        + (f", chain limit {settings.chain_limit:g}°" if settings.chain_limit is not None else "")
        + (f", w_chain {settings.w_chain:g}" if settings.w_chain else "")
        + ") on every built-in 3D figure and the shared models, at commit "
        f"{commit}. PrusaSlicer: its default print settings, 60 mm tall, support = the G-code's support "
        "features of one slice with supports. Estimate = the prism support estimate (`support_prism`) of the "
        "report. Distortion = the normalised ARAP term of the found pose; largest joint rotation = the largest "
        "rotation of one bone relative to its parent; largest chain-end turn = how far the end of a chain (a "
        "head, a hand, a tail tip) turned in the world from its rest direction; mirror error = how far a "
        "symmetric skeleton's pose is from mirror images (– when it has no mirror plane); stability margin = "
        "distance of the centre of mass inside the support polygon "
        "(fraction of the height, negative = falls over); new contacts = vertices of the found pose that touch "
        "the plate and did not before. Search time includes the exact intersection checks, not the slicing. "
        f"Machine: {platform.machine()}, {cores} cores, Python {platform.python_version()}."
        + (f" Skipped: {', '.join(skipped)}." if skipped else ""),
        "",
        f"Command: `{command}`",
        "",
        table(rows),
        "",
        summary(rows, figures),
        "",
        "Before/after pictures of every model: `docs/zoo.png`.",
        "",
    ])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=None,
                   help="Built-in figure names or shared model names (default: every 3D figure, then the shared models).")
    p.add_argument("--particles", type=int, default=None)
    p.add_argument("--iterations", type=int, default=None)
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--out", default=None, help="Write the table as the '## Zoo' section of this Markdown file.")
    p.add_argument("--sheet", default=str(ROOT / "docs" / "zoo.png"), help="Contact sheet PNG.")
    p.add_argument("--overhang-margin", type=float, default=None,
                   help="Search margin in degrees over the threshold (default: the tool's).")
    p.add_argument("--keep", default=None, help="Folder for each model's before/after and convergence pictures.")
    p.add_argument("--chain-limit", type=float, default=None, help="SearchSettings.chain_limit, degrees.")
    p.add_argument("--w-chain", type=float, default=None, help="SearchSettings.w_chain.")
    p.add_argument("--symmetric", choices=("auto", "on", "off"), default="auto",
                   help="SearchSettings.symmetric: None (the tool's choice), True or False.")
    p.add_argument("--no-anatomy", action="store_true", help="SearchSettings.anatomy=False.")
    args = p.parse_args(argv)
    figures = zoo_figures()
    models = args.models or [*figures, *SHARED]
    settings = sl.SearchSettings().replace(particles=args.particles, iterations=args.iterations, seed=args.seed)
    if args.overhang_margin is not None:
        settings = settings.replace(overhang_margin=args.overhang_margin)
    if args.chain_limit is not None:
        settings = settings.replace(chain_limit=args.chain_limit)
    if args.w_chain is not None:
        settings = settings.replace(w_chain=args.w_chain)
    settings = settings.replace(symmetric={"auto": None, "on": True, "off": False}[args.symmetric],
                                anatomy=not args.no_anatomy)
    command = "python benchmarks/zoo.py " + " ".join(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        pictures = Path(args.keep) if args.keep else Path(tmp)
        for name in models:
            print(f"running {name} ...", file=sys.stderr, flush=True)
            rows.append(run(name, settings, pictures))
            if "skipped" in rows[-1]:
                print(f"skipped {name}: {rows[-1]['skipped']}", flush=True)
            else:
                print(table(rows[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
        contact_sheet(rows, Path(args.sheet))
    text = section(rows, figures, settings, command.strip())
    print(text)
    if args.out:
        write_section(Path(args.out), HEADING, text)


if __name__ == "__main__":
    main()
