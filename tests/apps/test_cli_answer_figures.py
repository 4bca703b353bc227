"""The answer's figures do not move: ``supportless optimize --seed 0`` on the bunny, tpose and the Fox.

The JSON report (:func:`supportless.report.report.build_report`) and the summary the command prints
(:mod:`supportless.apps.cli_summary`) are compared, every float exactly, with those stored in
``tests/data/answer_figures.json``. Only what a clock or a temporary folder decides is left out
(:data:`CLOCK_KEYS`, the summary's ``search took`` line, the folder of the written files).

PrusaSlicer's own figures are not bit for bit the same from one run to the next (one mesh sliced
three times, two slicers at a time on a busy machine: 840.4214, 840.4256 and 840.4233 mm of support),
so the slicer that chooses among the answers (the command's default when PrusaSlicer is found) is a
stand-in here (:func:`stand_in_slicer`: the slicer model at another threshold, exact and repeatable;
no PrusaSlicer needed): the choice, the report and the summary are the command's own, the slicer's
measurement is not.

The figures were recorded at commit de15cad (before the answer's stages became
:mod:`supportless.search.answer`; the same refactor left 20fa53c's figures identical too, before that
commit's cuts to the search changed them in their last digits; both searches' figures were recorded again at
c910bc1, where only the ``term_history`` (the progress shows the search's own measure of its best, posed
with its pruned weights) and a mirrored figure's ``symmetry`` and summary row (one mirrored search) moved; and
again at 6112218, where ARAP's products became one per batch: only the floats that hold ARAP moved, by at most
1.5e-12 of their size, and the rest pose's round-off ARAP, about 1e-14)
with ``../shared`` beside the project, by::

    PYTHONPATH=. python tests/apps/test_cli_answer_figures.py --record            # the test's small search
    PYTHONPATH=. python tests/apps/test_cli_answer_figures.py --record defaults   # the command's own defaults

and are checked by hand at the command's defaults (minutes) with ``--check defaults``. Floats depend on
the machine's libraries: re-record on another machine, at a commit whose figures are trusted.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ROOT / "tests" / "data" / "answer_figures.json"

#: The models: ``{name: optimize's arguments}``, ``{shared}`` standing for the shared models' folder.
MODELS = {
    "bunny": ["{shared}/bunny.obj", "--skeleton", "{shared}/bunny.tgf", "--up", "y"],
    "tpose": ["demo:tpose", "--up", "y"],
    "fox": ["{shared}/gltf/Fox.glb"],
}

#: The searches: the test's (small, under a minute for the three) and the command's defaults.
SEARCHES = {"small": ["--particles", "40", "--iterations", "20"], "defaults": []}

#: Report entries a clock decides, as paths of keys.
CLOCK_KEYS = [("created",), ("machine",), ("runtime_seconds",), ("choice", "sliced_seconds")]


def _without_clock(report: dict) -> dict:
    """``report`` with the entries of :data:`CLOCK_KEYS` removed (in place), returned."""
    for path in CLOCK_KEYS:
        holder = report
        for key in path[:-1]:
            holder = holder.get(key) or {}
        holder.pop(path[-1], None)
    return report


#: The stand-in slicer's overhang threshold, degrees (the slicer model's is the profile's, 53.1).
STAND_IN_DEGREES = 45.0


def stand_in_slicer(meshes, up, scale, *_args, **_options):
    """What :func:`supportless.slicing.prusaslicer.slice_support` returns, from the slicer model at
    :data:`STAND_IN_DEGREES`: ``support_mm``, one float per ``(V (n, 3) float64, F (f, 3) int64)`` of
    ``meshes``, scaled by ``scale`` along ``up`` (3,)."""
    from types import SimpleNamespace

    import numpy as np

    from supportless.energies.slicer_model import predicted_support_mm

    up = np.asarray(up, np.float64)
    return SimpleNamespace(support_mm=[float(predicted_support_mm(V, F, up, STAND_IN_DEGREES, scale))
                                       for V, F in meshes])


def answer_figures(model: str, search: str, shared: Path, cache: Path) -> dict:
    """Run ``optimize --seed 0`` on one of :data:`MODELS`: ``{"report": dict, "summary": list of str}``.

    Parameters
    ----------
    model : str
        A key of :data:`MODELS`.
    search : str
        A key of :data:`SEARCHES`.
    shared : Path
        The shared models' folder.
    cache : Path
        The rig cache folder.
    """
    from click.testing import CliRunner

    from supportless.apps.cli import main

    with tempfile.TemporaryDirectory() as out, pytest.MonkeyPatch.context() as patch:
        patch.setattr("supportless.slicing.prusaslicer.find_prusa_slicer", lambda: "prusa-slicer (stand-in)")
        patch.setattr("supportless.slicing.ranking.slice_support", stand_in_slicer)
        args = [a.format(shared=shared) for a in MODELS[model]] + SEARCHES[search] + [
            "--seed", "0", "-q", "--cache-dir", str(cache), "-o", f"{out}/answer.stl", "--report", f"{out}/report.json"]
        run = CliRunner().invoke(main, ["optimize", *args], env={"COLUMNS": "100"}, catch_exceptions=False)
        assert run.exit_code == 0, run.output
        report = json.loads(Path(out, "report.json").read_text())
        summary = [line.replace(out, "OUT") for line in run.output.splitlines() if not line.startswith("search took ")]
    return {"report": _without_clock(report), "summary": summary}


@pytest.fixture(scope="module")
def recorded() -> dict:
    """The stored figures (:data:`FIGURES`)."""
    return json.loads(FIGURES.read_text())


@pytest.mark.slow
@pytest.mark.parametrize("model", list(MODELS))
def test_the_answer_figures_are_those_recorded(model, recorded, request, rig_cache_dir):
    """The small search's report and summary on each model, bit for bit (a stand-in slicer chooses among the
    answers)."""
    names = [arg.removeprefix("{shared}/") for arg in MODELS[model] if arg.startswith("{shared}/")]
    for name in names:  # a missing shared model is a stated skip (a failure under CI=true)
        request.getfixturevalue("shared_file")(name)
    shared = request.getfixturevalue("shared_data") if names else None
    figures = answer_figures(model, "small", shared, rig_cache_dir)
    expected = recorded["small"][model]
    assert figures["summary"] == expected["summary"]
    assert figures["report"] == expected["report"]


def _main(argv: list[str]) -> int:
    """``--record [small|defaults]`` stores the figures, ``--check [small|defaults]`` compares them."""
    mode, search = argv[0], (argv[1] if len(argv) > 1 else "small")
    shared = Path(os.environ.get("SUPPORTLESS_SHARED_DATA", ROOT.parent / "shared" / "data"))
    stored = json.loads(FIGURES.read_text()) if FIGURES.exists() else {}
    with tempfile.TemporaryDirectory() as cache:
        figures = {model: answer_figures(model, search, shared, Path(cache)) for model in MODELS}
    if mode == "--record":
        FIGURES.parent.mkdir(exist_ok=True)
        FIGURES.write_text(json.dumps(stored | {search: figures}, indent=1, sort_keys=True) + "\n")
        print(f"recorded {search}: {FIGURES}")
        return 0
    differ = [model for model in MODELS if figures[model] != stored[search][model]]
    print(f"{search}: " + (f"differ on {', '.join(differ)}" if differ else "identical on " + ", ".join(MODELS)))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
