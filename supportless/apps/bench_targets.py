"""The speed targets of big rigs, measured in one run: ``supportless bench --targets``.

Cases (each in its own Python process, so its peak memory is its own):

* ``bunny`` and ``bb-bunny``: the shared rigged models (``../shared/data``);
* ``character``: the procedural 68-bone character with about 31 000
  triangles (:func:`supportless.shapes.character.character`);
* ``robot``: the shared glTF RobotExpressive (53 joints, its own skin weights);
* ``bunny111k``: the bunny subdivided twice (``igl.upsample``, 111 456
  triangles), rigged with the bunny's skeleton;
* ``bunny4`` and ``bunny5m``: sculpt-sized bunnies (:data:`BIG_CASES`, made by
  :func:`big_model`), measured end to end as the command line runs them.

For each case: preparation from an empty rig cache, the default search
(``supportless optimize``'s settings, numba warmed up by a tiny search first),
the process's peak resident memory, and the result's quality measured on the
full surface: the support reduction of the prism estimate (rest → found, in
the print frame), the distortion term and the exact (CGAL) intersecting face
pairs. With ``reference=True`` the same search also runs on the full surface
without the simplified proxy (the full-resolution reference; only cases that
have a proxy differ from their default search).
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable

from ..files.printframe import REFERENCE_HEIGHT_MM
from .bench import SHARED_DATA

__all__ = ["BIG_CASES", "CASES", "TARGETS", "big_model", "format_table", "measure_case", "run_targets"]

CASES = ("bunny", "bb-bunny", "character", "robot", "bunny111k", "bunny4", "bunny5m")

#: Issue 14's targets on 2 cores: search seconds (bb-bunny: at most twice the bunny's in the same run;
#: the 111k case also prepares within 60 s in at most 6 GB).
TARGETS = {"bunny": "search ≤ 4 s", "bb-bunny": "search ≤ 2× bunny", "character": "search ≤ 20 s",
           "robot": "search ≤ 20 s", "bunny111k": "prepare ≤ 60 s, search ≤ 20 s, ≤ 6 GB",
           "bunny4": "end to end ≤ 60 s, ≤ 3 GB", "bunny5m": "completes, ≤ 8 GB"}


#: The sculpt-sized cases of issue 39 (:func:`big_model`): measured as the command line runs them, end to end.
BIG_CASES = {"bunny4": "the bunny subdivided four times (trimesh), 1 783 296 triangles",
             "bunny5m": "the bunny's triangles each split in three at its centroid, then subdivided four times, "
                        "5 349 888 triangles"}


def big_model(case: str, folder=None) -> tuple[Path, Path]:
    """The OBJ and TGF of a case of :data:`BIG_CASES`, made from the shared bunny once and kept in ``folder``.

    Made in a child process (so a measured process's memory is its own), deterministically: the shared
    ``bunny.obj`` subdivided by trimesh (midpoints, the shape unchanged), written as OBJ next to a copy of
    ``bunny.tgf``. ``folder`` defaults to ``$SUPPORTLESS_BENCH_CACHE``, else ``supportless-bench`` in the
    temporary folder.

    Returns
    -------
    mesh, skeleton : pathlib.Path
    """
    folder = Path(folder or os.environ.get("SUPPORTLESS_BENCH_CACHE")
                  or Path(tempfile.gettempdir()) / "supportless-bench")
    mesh, skeleton = folder / f"{case}.obj", folder / f"{case}.tgf"
    if not (mesh.is_file() and skeleton.is_file()):
        folder.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "supportless.apps.bench_targets", "--make", case, str(folder)],
                       check=True, env=dict(os.environ))
    return mesh, skeleton


def _make_big_model(case: str, folder: Path) -> None:
    """Write ``case``.obj and ``case``.tgf of :func:`big_model` into ``folder``."""
    import numpy as np
    import trimesh

    from ..files.meshes import read_mesh, write_mesh

    V, F = read_mesh(SHARED_DATA / "bunny.obj")
    if case == "bunny5m":  # each triangle split in three at its centroid: 3 x 4^4 x 6966 triangles in the end
        C = np.arange(len(V), len(V) + len(F))
        V = np.vstack([V, V[F].mean(axis=1)])
        F = np.concatenate([np.column_stack([F[:, 0], F[:, 1], C]), np.column_stack([F[:, 1], F[:, 2], C]),
                            np.column_stack([F[:, 2], F[:, 0], C])])
    mesh = trimesh.Trimesh(V, F, process=False)
    for _ in range(4):
        mesh = mesh.subdivide()
    write_mesh(folder / f"{case}.obj", mesh.vertices, mesh.faces)
    (folder / f"{case}.tgf").write_bytes((SHARED_DATA / "bunny.tgf").read_bytes())


def _missing(case: str) -> str | None:
    """Why a case cannot run here, or None."""
    need = {"bunny": ["bunny.obj", "bunny.tgf"], "bb-bunny": ["bb-bunny.obj", "bb-bunny.tgf"],
            "robot": ["gltf/RobotExpressive.glb"], "bunny111k": ["bunny.obj", "bunny.tgf"],
            "bunny4": ["bunny.obj", "bunny.tgf"], "bunny5m": ["bunny.obj", "bunny.tgf"]}.get(case, [])
    absent = [name for name in need if not (SHARED_DATA / name).is_file()]
    return f"{', '.join(absent)} not found in {SHARED_DATA}" if absent else None


def _prepare(case: str, cache_dir: str):
    """The rig of a case, prepared into ``cache_dir``."""
    from ..rig.load import load_rig
    from ..rig.rig import prepare_rig

    if case == "character":
        from ..shapes.character import character

        V, F, J, B = character()
        return prepare_rig(V, F, J, B, up="y", name="character")
    if case == "robot":
        return load_rig(SHARED_DATA / "gltf" / "RobotExpressive.glb", cache_dir=cache_dir, height_mm=REFERENCE_HEIGHT_MM)
    if case == "bunny111k":
        import igl
        import numpy as np

        from ..files.meshes import read_mesh, read_tgf

        V, F = read_mesh(SHARED_DATA / "bunny.obj")
        V, F = igl.upsample(V, F.astype(np.int64), 2)
        J, B = read_tgf(SHARED_DATA / "bunny.tgf")
        return prepare_rig(V, F, J, B, up="y", name="bunny111k")
    return load_rig(SHARED_DATA / f"{case}.obj", SHARED_DATA / f"{case}.tgf", cache_dir=cache_dir)


def _quality(rig, result) -> dict:
    from ..report.report import build_report

    report = build_report(rig, result)
    return {"reduction": report["reduction_percent"]["support_prism"], "distortion": result.terms["arap"],
            "value": result.value, "pairs": report["after"]["intersecting_face_pairs"]}


def measure_case(case: str, reference: bool = False, settings=None, choice: bool = False) -> dict:
    """Prepare and search one case in this process (see the module docstring).

    Parameters
    ----------
    case : str
        One of :data:`CASES`.
    reference : bool
        Also search the full surface when the rig has a proxy.
    settings : SearchSettings, optional
        The search (default: the tool's defaults, as measured for the targets).
    choice : bool
        Also time the pose-only search (``orient="keep"``), the default's
        choice among its answers (:func:`supportless.search.choice.choose`) and,
        when PrusaSlicer is found, the slicer's (:func:`supportless.slicing.ranking.slice_choice`).

    Returns
    -------
    row : dict
        ``case``, ``faces``, ``proxy_faces`` (None without a proxy), ``bones``,
        ``free_bones``, ``prepare_s``, ``search_s``, ``reduction`` (%),
        ``distortion``, ``value``, ``pairs``, ``peak_mb`` and, with
        ``reference``, the same quality keys and ``search_s`` under ``ref_``;
        with ``choice``, ``pose_only_s``, ``choice_s``, ``chosen_kind`` and,
        with a slicer, ``slice_s``, ``sliced`` (answers sliced) and ``sliced_kind``.
    """
    import resource
    import time

    from ..search.answer import optimize
    from ..search.settings import SearchSettings

    if case in BIG_CASES:
        return _end_to_end(case)
    with tempfile.TemporaryDirectory() as cache:
        t = time.perf_counter()
        rig = _prepare(case, cache)
        prepare = time.perf_counter() - t
    settings = SearchSettings() if settings is None else settings
    # numba compiled, operators warm (one polish generation compiles the polish as well as the default's many)
    warm = 1 if settings.polish is None else min(1, settings.polish)
    optimize(rig, settings.replace(particles=4, iterations=1, polish=warm))
    t = time.perf_counter()
    result = optimize(rig, settings)
    row = {"case": case, "faces": len(rig.faces), "bones": rig.bone_count,
           "proxy_faces": None if rig.coarse_faces is None else len(rig.coarse_faces),
           "free_bones": int((~settings.fixed_bones(rig)).sum()), "prepare_s": prepare,
           "search_s": time.perf_counter() - t} | _quality(rig, result)
    if choice:
        row |= _choice_times(rig, settings, result)
    if reference and rig.coarse_faces is not None:
        t = time.perf_counter()
        full = optimize(rig, settings, objective=settings.objective(rig))  # the full surface, no proxy
        row |= {"ref_search_s": time.perf_counter() - t} | {f"ref_{k}": v for k, v in _quality(rig, full).items()}
    row["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return row


def _end_to_end(case: str) -> dict:
    """A case of :data:`BIG_CASES` as a user runs it: ``supportless optimize MESH --skeleton TGF --up y -o OUT
    --seed 0`` (and ``--report``) from an empty rig cache, in a child process; its wall time, peak memory
    (``ru_maxrss`` of the children) and report."""
    import resource
    import time

    mesh, skeleton = big_model(case)
    with tempfile.TemporaryDirectory() as out:
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "supportless.apps.cli", "optimize", str(mesh), "--skeleton",
                        str(skeleton), "--up", "y", "-o", f"{out}/out.stl", "--seed", "0", "--report",
                        f"{out}/report.json", "--cache-dir", f"{out}/cache", "--quiet"], check=True,
                       capture_output=True, env=dict(os.environ))
        seconds = time.perf_counter() - t
        report = json.loads(Path(f"{out}/report.json").read_text())
    after = report["after"]
    return {"case": case, "faces": report["faces"], "bones": report["bones"], "end_to_end_s": seconds,
            "reduction": report["reduction_percent"]["support_prism"], "distortion": after["terms"]["arap"],
            "value": after["objective"], "pairs": after["intersecting_face_pairs"],
            "peak_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024}


def _choice_times(rig, settings, result) -> dict:
    """Seconds of the pose-only search and of the choices after the default search (see :func:`measure_case`)."""
    import time

    from ..search.answer import optimize
    from ..slicing.prusaslicer import find_prusa_slicer
    from ..slicing.ranking import SLICE_RANK, slice_choice

    t = time.perf_counter()
    optimize(rig, settings.replace(orient="keep"))
    choice = result.choice
    row = {"pose_only_s": time.perf_counter() - t, "choice_s": choice.seconds if choice is not None else 0.0,
           "chosen_kind": choice.chosen_kind if choice is not None else None}
    if result.choice is not None and find_prusa_slicer():
        t = time.perf_counter()
        sliced = slice_choice(rig, result, SLICE_RANK, height_mm=REFERENCE_HEIGHT_MM)
        row |= {"slice_s": time.perf_counter() - t, "sliced_kind": sliced.choice.chosen_kind,
                "sliced": sum(c.sliced_mm is not None for c in sliced.choice.candidates)}
    return row


def run_targets(cases=CASES, reference: bool = False, echo: Callable[[str], None] = print,
                choice: bool = False) -> list[dict]:
    """Measure cases, each in a child process; print progress and the table through ``echo``.

    Returns
    -------
    rows : list of dict
        :func:`measure_case`'s rows; a case that failed has ``error`` (and
        ``missing`` when its input files are not here).
    """
    rows = []
    for case in cases:
        why = _missing(case)
        if why is None and case in BIG_CASES:
            big_model(case)  # made (once) before the measured process starts
        if why is None:
            echo(f"{case}: preparing and searching ...")
            run = subprocess.run([sys.executable, "-m", "supportless.apps.bench_targets", case]
                                 + (["--reference"] if reference else []) + (["--choice"] if choice else []),
                                 capture_output=True, text=True, env=dict(os.environ))
            lines = run.stdout.strip().splitlines()
            if run.returncode == 0 and lines:
                rows.append(json.loads(lines[-1]))
                echo(format_table(rows[-1:]).splitlines()[-1])
                continue
            why = (run.stderr.strip().splitlines() or ["no output"])[-1]
            echo(f"{case}: failed: {why}")
            rows.append({"case": case, "error": why})
            continue
        echo(f"{case}: skipped: {why}")
        rows.append({"case": case, "error": why, "missing": True})
    echo(format_table(rows))
    return rows


def format_table(rows: list[dict]) -> str:
    """The rows as a Markdown table with the machine, the targets and the reference next to each case."""
    from ..search.settings import SearchSettings

    def quality(r, p=""):
        return (f"{r[p + 'reduction']:.1f} % / {r[p + 'distortion']:.4f} / {r[p + 'value']:.4f} / "
                f"{r[p + 'pairs']}")

    lines = [f"machine: {platform.machine()}, {os.cpu_count()} cores; load average before the run "
             f"{os.getloadavg()[0]:.2f}; default search ({SearchSettings.particles} × {SearchSettings.iterations}, "
             "orientation free); quality = support "
             "reduction (prism, rest → found) / distortion term / objective / exact intersecting pairs, on the full "
             "surface", "",
             "| case | triangles (searched) | bones (free) | prepare | search | peak memory | quality | "
             "full-resolution reference: search, quality | target |",
             "|---|---|---|---|---|---|---|---|---|"]
    big = [r for r in rows if r["case"] in BIG_CASES]
    rows = [r for r in rows if r["case"] not in BIG_CASES]
    for r in rows:
        if "error" in r:
            what = "skipped" if r.get("missing") else "failed"
            lines.append(f"| {r['case']} | {what}: {r['error']} | | | | | | | {TARGETS[r['case']]} |")
            continue
        searched = f" ({r['proxy_faces']})" if r["proxy_faces"] else ""
        ref = (f"{r['ref_search_s']:.1f} s, {quality(r, 'ref_')}" if "ref_search_s" in r
               else "the same search" if not r["proxy_faces"] else "not run")
        lines.append(f"| {r['case']} | {r['faces']}{searched} | {r['bones']} ({r['free_bones']}) | "
                     f"{r['prepare_s']:.1f} s | {r['search_s']:.1f} s | {r['peak_mb']:.0f} MB | {quality(r)} | "
                     f"{ref} | {TARGETS[r['case']]} |")
    if big:
        lines += ["", "Sculpts (issue 39): `supportless optimize MESH --skeleton TGF --up y -o OUT --seed 0` end to end "
                  "(read, proxy, weights, search, exact checks, slicer choice, report, write), empty rig cache.", "",
                  "| case | triangles | bones | end to end | peak memory | quality | target |", "|---|---|---|---|---|---|---|"]
        for r in big:
            if "error" in r:
                lines.append(f"| {r['case']} | {'skipped' if r.get('missing') else 'failed'}: {r['error']} | | | | | "
                             f"{TARGETS[r['case']]} |")
                continue
            lines.append(f"| {r['case']} | {r['faces']} | {r['bones']} | {r['end_to_end_s']:.1f} s | "
                         f"{r['peak_mb']:.0f} MB | {quality(r)} | {TARGETS[r['case']]} |")
    timed = [r for r in rows if "pose_only_s" in r]
    if timed:
        lines += ["", "The choice among the answers (issue 32): the default search with the slicer model's choice, "
                  "and with PrusaSlicer's, against the pose-only search (`orient='keep'`); targets ≤ 1.6× without a "
                  "slicer, ≤ 2.5× with one.", "",
                  "| case | pose only | default, model's choice | × pose only | + slicing (answers) | "
                  "× pose only with the slicer | kind chosen (model / slicer) |", "|---|---|---|---|---|---|---|"]
        for r in timed:
            model = r["search_s"] / r["pose_only_s"]
            if "slice_s" in r:
                slicing = f"{r['slice_s']:.1f} s ({r['sliced']})"
                ratio = f"{(r['search_s'] + r['slice_s']) / r['pose_only_s']:.2f}"
            else:
                slicing, ratio = "no slicer", "–"
            lines.append(f"| {r['case']} | {r['pose_only_s']:.1f} s | {r['search_s']:.1f} s "
                         f"(choice {r['choice_s']:.2f} s) | {model:.2f} | {slicing} | {ratio} | "
                         f"{r['chosen_kind']} / {r.get('sliced_kind', '–')} |")
    return "\n".join(lines)


if __name__ == "__main__" and sys.argv[1] == "--make":  # the child process of big_model
    _make_big_model(sys.argv[2], Path(sys.argv[3]))
elif __name__ == "__main__":  # the child process of run_targets
    print(json.dumps(measure_case(sys.argv[1], reference="--reference" in sys.argv[2:],
                                  choice="--choice" in sys.argv[2:])))
