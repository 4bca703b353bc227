"""Shared fixtures: prepared rigs of the built-in figures, files on disk, and what lies outside the package.

The rigs are session-scoped so every test module reuses one preparation; they
are cached under a per-session temporary folder, never in the user's cache.

Three things come from outside the Python package: the shared test models
(``../shared/data`` beside the repository, or ``$SUPPORTLESS_SHARED_DATA``),
PrusaSlicer (``prusa-slicer``, or ``$SUPPORTLESS_PRUSA_SLICER``) and Chromium
(``chromium``, or ``$SUPPORTLESS_CHROMIUM``). Tests get them only through the
fixtures :func:`shared_data`, :func:`shared_file`, :func:`prusa_slicer` and
:func:`chromium`. When one is missing, those tests are skipped with the reason
on a developer's machine, and fail with the reason under ``CI=true``, where
everything must run. Pointing a variable at a missing path simulates its absence.
"""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest
from meshes import box

import supportless as sl

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def in_ci() -> bool:
    """True when ``$CI`` is set to anything but empty, ``0``, ``false`` or ``no``."""
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


def unavailable(reason: str):
    """Skip the test with ``reason``; under CI, fail it instead (nothing may be skipped there)."""
    if in_ci():
        pytest.fail(f"{reason} (CI requires it)", pytrace=False)
    pytest.skip(reason)


def _shared_data_dir() -> Path:
    env = os.environ.get("SUPPORTLESS_SHARED_DATA", "").strip()
    return Path(env).expanduser() if env else SHARED_DATA


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared test models folder (``../shared/data``, or ``$SUPPORTLESS_SHARED_DATA``)."""
    folder = _shared_data_dir()
    if not folder.is_dir():
        unavailable(f"shared test models not found: {folder} is missing")
    return folder


@pytest.fixture(scope="session")
def shared_file(shared_data):
    """A function ``name -> Path`` of one shared test model; missing files are treated like a missing folder."""

    def get(name: str) -> Path:
        path = shared_data / name
        if not path.is_file():
            unavailable(f"shared test model not found: {path} is missing")
        return path

    return get


@pytest.fixture(scope="session")
def prusa_slicer() -> str:
    """Path of the PrusaSlicer executable (:func:`supportless.slicing.prusaslicer.find_prusa_slicer`)."""
    from supportless.slicing.prusaslicer import ENV_VAR, find_prusa_slicer

    exe = find_prusa_slicer()
    if exe is None:
        where = os.environ.get(ENV_VAR, "").strip()
        unavailable(f"PrusaSlicer not found{f' at ${ENV_VAR}={where}' if where else ' on PATH'}: "
                    "apt-get install prusa-slicer")
    return exe


@pytest.fixture(scope="session")
def cura_engine() -> tuple[str, Path]:
    """CuraEngine and the folder of Cura's printer definitions (:mod:`supportless.slicing.cura`)."""
    from supportless.slicing.cura import find_cura_definitions, find_cura_engine, missing_message

    exe = find_cura_engine()
    folder = find_cura_definitions() if exe else None
    if exe is None or folder is None:
        unavailable(missing_message(exe, folder))
    return exe, folder


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of the Chromium executable for Playwright (``chromium`` on PATH, or ``$SUPPORTLESS_CHROMIUM``)."""
    env = os.environ.get("SUPPORTLESS_CHROMIUM", "").strip()
    exe = shutil.which(env) if env else (shutil.which("chromium") or shutil.which("chromium-browser"))
    if exe is None:
        unavailable(f"Chromium not found{f' at $SUPPORTLESS_CHROMIUM={env}' if env else ' on PATH'}: "
                    "apt-get install chromium")
    return exe


#: The environment of a machine with no slicer: ``optimize`` lets the slicer model choose among its answers
#: instead of slicing four of them (seconds each). For a command whose subject is not the slicer, so that it
#: runs the same, and as fast, with or without one installed.
NO_SLICER = {"SUPPORTLESS_PRUSA_SLICER": "/nonexistent/prusa-slicer",
             "SUPPORTLESS_CURA_ENGINE": "/nonexistent/CuraEngine"}


@pytest.fixture
def no_slicer(monkeypatch):
    """No slicer for this test (:data:`NO_SLICER`), in this process and in the commands it starts."""
    for name, value in NO_SLICER.items():
        monkeypatch.setenv(name, value)


@pytest.fixture(scope="session")
def rig_cache_dir(tmp_path_factory) -> Path:
    """A rig cache folder private to this test session."""
    return tmp_path_factory.mktemp("rig-cache")


@pytest.fixture(scope="session")
def branch_rig(rig_cache_dir) -> sl.Rig:
    """The built-in ``branch`` figure (3 bones, < 1500 faces), prepared once."""
    return sl.load_rig("demo:branch", up="y", cache_dir=rig_cache_dir)


@pytest.fixture(scope="session")
def tpose_rig(rig_cache_dir) -> sl.Rig:
    """The built-in ``tpose`` figure (15 bones), prepared once (about 2 s)."""
    return sl.load_rig("demo:tpose", up="y", cache_dir=rig_cache_dir)


@pytest.fixture(scope="session")
def bunny_rig(shared_file) -> sl.Rig:
    """The shared Stanford bunny rig (``bunny.obj`` and ``bunny.tgf``).

    About 15 s to prepare cold, so it goes through the user's rig cache
    (``$SUPPORTLESS_CACHE`` or ``~/.cache/supportless``, keyed by a hash of the
    inputs): later sessions load it in a fraction of a second.
    """
    shared_file("bunny.tgf")
    return sl.load_rig(shared_file("bunny.obj"), up="y")


@pytest.fixture(scope="session")
def branch_files(tmp_path_factory) -> dict:
    """The ``branch`` figure written to disk as STL + TGF (paths in a dict)."""
    folder = tmp_path_factory.mktemp("branch-files")
    V, F, J, B = sl.demo_figure("branch")
    mesh, skel = folder / "branch.stl", folder / "branch.tgf"
    sl.write_mesh(mesh, V, F)
    sl.write_tgf(skel, J, B)
    return {"folder": folder, "mesh": mesh, "skeleton": skel, "cache": folder / "cache",
            "V": V, "F": F, "joints": J, "bones": B}


@pytest.fixture(scope="session")
def box_surface():
    """A function ``(lo, hi) -> (V, F)``: the closed surface of an axis-aligned box."""
    return box


@pytest.fixture(scope="session")
def bad_inputs(tmp_path_factory, branch_files, branch_rig, box_surface) -> dict:
    """Bad models, one per user error, shared by the API and the CLI tests.

    Returns ``{case: (model, kwargs, culprit, fragments)}``: ``model`` is the
    mesh path, ``kwargs`` are ``skeleton`` / ``tets`` / ``weights`` paths,
    ``culprit`` is the file the message must name and ``fragments`` are
    substrings the message must contain.
    """
    from supportless.files.meshes import write_dmat, write_tet_mesh

    d = tmp_path_factory.mktemp("bad-inputs")
    V, F, J, B = (branch_files[k] for k in ("V", "F", "joints", "bones"))
    good_tgf = branch_files["skeleton"]
    cases = {}

    garbage = d / "garbage.stl"
    garbage.write_bytes(bytes(range(256)) * 4)
    cases["garbage mesh"] = (garbage, {"skeleton": good_tgf}, garbage, ["no triangles"])
    garbage_ply = d / "garbage.ply"
    garbage_ply.write_text("this is not a mesh\n")
    cases["garbage ply"] = (garbage_ply, {"skeleton": good_tgf}, garbage_ply, ["cannot read as PLY"])
    garbage_tgf = d / "garbage.tgf"
    garbage_tgf.write_text("hello world\n")
    cases["garbage skeleton"] = (branch_files["mesh"], {"skeleton": garbage_tgf}, garbage_tgf,
                                 ["line 1", "joint"])

    unknown = d / "model.xyz"
    unknown.write_text("0 0 0\n")
    cases["unknown extension"] = (unknown, {"skeleton": good_tgf}, unknown, ["unknown mesh format", ".xyz"])

    open_mesh = d / "open.obj"
    sl.write_mesh(open_mesh, V, F[1:])  # one face removed: a hole with 3 boundary edges
    # an open or non-manifold surface is not bad input any more: it is made a closed solid (tests/rig/test_rig.py)
    cases["not closed"] = (open_mesh, {"skeleton": good_tgf}, open_mesh, ["not closed", "3 boundary edges"])

    V1, F1 = box_surface((0, 0, 0), (1, 1, 1))
    V2, F2 = box_surface((1, 1, 0), (2, 2, 1))  # shares the edge x = y = 1 with the first box
    nonmanifold = d / "two-boxes.obj"
    sl.write_mesh(nonmanifold, np.vstack([V1, V2]), np.vstack([F1, F2 + 8]))
    box_tgf = d / "two-boxes.tgf"
    sl.write_tgf(box_tgf, [[0.2, 0.5, 0.5], [0.8, 0.5, 0.5]], [[0, 1]])
    cases["not manifold"] = (nonmanifold, {"skeleton": box_tgf}, nonmanifold, ["not manifold", "1 edges"])

    outside = d / "outside.tgf"
    sl.write_tgf(outside, np.vstack([J, [[50.0, 50.0, 50.0]]]), np.vstack([B, [[3, 4]]]))
    cases["joint outside"] = (branch_files["mesh"], {"skeleton": outside}, outside, ["joint 5", "outside"])

    out_of_range = d / "out-of-range.tgf"
    out_of_range.write_text("1 0 2 0\n2 0 20 0\n#\n1 2\n2 9\n#\n")
    cases["bone out of range"] = (branch_files["mesh"], {"skeleton": out_of_range}, out_of_range,
                                  ["bone 2", "out of range 1..2"])

    no_bones = d / "no-bones.tgf"
    no_bones.write_text("1 0 2 0\n2 0 20 0\n#\n#\n")
    cases["skeleton without bones"] = (branch_files["mesh"], {"skeleton": no_bones}, no_bones, ["no bones"])
    empty = d / "empty.tgf"
    empty.write_text("")
    cases["empty skeleton file"] = (branch_files["mesh"], {"skeleton": empty}, empty, ["no joints"])

    tets = d / "branch.mesh"
    write_tet_mesh(tets, branch_rig.tet_vertices, branch_rig.tets)
    t, m = branch_rig.tet_weights.shape
    wrong = d / "wrong-shape.dmat"
    write_dmat(wrong, np.full((t, m + 1), 1.0 / (m + 1)))
    cases["weights of the wrong shape"] = (branch_files["mesh"], {"skeleton": good_tgf, "tets": tets,
                                                                  "weights": wrong}, wrong,
                                           [f"{t}x{m + 1}", f"{t}x{m} was expected"])

    missing = d / "missing.stl"
    cases["missing mesh"] = (missing, {"skeleton": good_tgf}, missing, ["no such file"])
    missing_tgf = d / "missing.tgf"
    cases["missing skeleton"] = (branch_files["mesh"], {"skeleton": missing_tgf}, missing_tgf, ["no such file"])
    return cases


@pytest.fixture(params=[
    "garbage mesh", "garbage ply", "garbage skeleton", "unknown extension",
    "joint outside", "bone out of range", "skeleton without bones", "empty skeleton file",
    "weights of the wrong shape", "missing mesh", "missing skeleton",
])
def bad_case(request, bad_inputs):
    """One bad input per test: ``(model, kwargs, culprit, fragments)`` from :func:`bad_inputs`."""
    return bad_inputs[request.param]


@pytest.fixture(scope="session")
def dense_branch():
    """The branch figure subdivided twice, prepared with the proxy thresholds lowered to its size: (rig, target)."""
    import igl

    from supportless.rig import rig as rig_mod

    V, F, J, B = sl.demo_figure("branch")
    V2, F2 = igl.upsample(V, F.astype(np.int64), 2)
    mp = pytest.MonkeyPatch()
    mp.setattr(rig_mod, "PROXY_FACES", len(F2) - 1)
    mp.setattr(rig_mod, "PROXY_TARGET", len(F2) // 8)
    try:
        rig = sl.prepare_rig(V2, F2, J, B, "y", name="dense")
    finally:
        mp.undo()
    return rig, len(F2) // 8


@pytest.fixture(scope="module")
def branch_app(branch_rig, tmp_path_factory):
    """The browser app of the branch figure on a free local port, for one test module."""
    from supportless.apps.ui import App

    a = App(branch_rig, verbose=False, workdir=tmp_path_factory.mktemp("app"))
    assert a.wait_idle(60)
    yield a
    a.stop()


def until(condition, timeout: float = 300.0) -> bool:
    """Poll ``condition()`` until it holds (True) or ``timeout`` seconds pass (False): a wait for a state, not a
    fixed delay, so a slow machine takes longer but reaches the same verdict."""
    end = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > end:
            return False
        time.sleep(0.05)
    return True
