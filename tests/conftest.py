"""Shared fixtures: prepared rigs of the built-in figures, files on disk, shared models.

The rigs are session-scoped so every test module reuses one preparation; they
are cached under a per-session temporary folder, never in the user's cache.
The shared test models (``../shared/data`` beside the repository) are optional:
tests that need them skip with a visible reason when the folder is absent.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import supportless as sl

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


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
def shared_data() -> Path:
    """``../shared/data`` relative to the repository root; skips when it is missing."""
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data not present: shared test models are missing")
    return SHARED_DATA


@pytest.fixture(scope="session")
def bunny_rig(shared_data) -> sl.Rig:
    """The shared Stanford bunny rig.

    About 15 s to prepare cold, so it goes through the user's rig cache
    (``$SUPPORTLESS_CACHE`` or ``~/.cache/supportless``, keyed by a hash of the
    inputs): later sessions load it in a fraction of a second.
    """
    path = shared_data / "bunny.obj"
    if not path.is_file():
        pytest.skip(f"{path} not present")
    return sl.load_rig(path, up="y")


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


def _box_surface(lo=(0.0, 0.0, 0.0), hi=(1.0, 1.0, 1.0)):
    """Closed, outward-oriented triangle surface of an axis-aligned box (8 vertices, 12 faces)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    V = np.array([[(hi if (c >> a) & 1 else lo)[a] for a in range(3)] for c in range(8)], dtype=float)
    F = np.array([
        [0, 2, 1], [1, 2, 3],  # z = lo
        [4, 5, 6], [5, 7, 6],  # z = hi
        [0, 1, 4], [1, 5, 4],  # y = lo
        [2, 6, 3], [3, 6, 7],  # y = hi
        [0, 4, 2], [2, 4, 6],  # x = lo
        [1, 3, 5], [3, 7, 5],  # x = hi
    ], dtype=np.int64)
    return V, F


@pytest.fixture(scope="session")
def box_surface():
    """A function ``(lo, hi) -> (V, F)``: the closed surface of an axis-aligned box."""
    return _box_surface
