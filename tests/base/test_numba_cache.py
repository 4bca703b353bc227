"""numba's cache folder when the install and the home folder cannot be written (issue 18, item 6)."""

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

import supportless
from supportless.base.numba_cache import fallback_cache_dir, writable


def test_numbas_own_places_are_kept_when_one_is_writable(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    assert writable(tmp_path / "new" / "folder") and not writable(blocker / "x")
    assert fallback_cache_dir(tmp_path / "pkg", blocker / "numba") is None  # the package folder
    assert fallback_cache_dir(blocker / "pkg", tmp_path / "numba") is None  # the user's cache folder
    folder = fallback_cache_dir(blocker / "pkg", blocker / "numba")
    assert folder is not None and writable(folder)


def _read_only_copy(tmp_path):
    """The package copied with a *file* where every __pycache__ folder goes: numba cannot cache beside it
    (even as root, who may write anywhere else)."""
    target = tmp_path / "site"
    shutil.copytree(Path(supportless.__file__).parent, target / "supportless",
                    ignore=shutil.ignore_patterns("__pycache__"))
    for folder in [target / "supportless", *(p for p in (target / "supportless").rglob("*") if p.is_dir())]:
        (folder / "__pycache__").write_text("")
    return target


@pytest.mark.slow
def test_the_package_imports_and_computes_with_no_writable_cache_place(tmp_path):
    site = _read_only_copy(tmp_path)
    home = tmp_path / "home-is-a-file"
    home.write_text("")
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env.update(HOME=str(home), PYTHONPATH=str(site), PYTHONDONTWRITEBYTECODE="1")
    code = ("import os, numpy as np, supportless as sl\n"
            "V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]) + [0, 0, 1]\n"
            "F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])\n"
            "print(os.environ['NUMBA_CACHE_DIR']); print(np.isfinite(sl.overhang_energy(V[None], F, 'z', 45.0)[0]))")
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600,
                         cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    folder, positive = run.stdout.split()
    assert positive == "True"
    assert Path(folder).is_dir() and Path(folder).parent == Path(tempfile.gettempdir())
    assert str(site) in run.stderr or run.stderr == ""  # nothing but, at most, a warning naming the copy


def test_a_users_numba_cache_dir_is_left_alone(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "mine"))
    code = "import os, supportless; print(os.environ['NUMBA_CACHE_DIR'])"
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and run.stdout.strip() == str(tmp_path / "mine"), run.stderr


def test_openmp_runs_the_kernels_unless_the_user_chose_a_threading_layer():
    """TBB's launches grow slower in a long-lived process (the module's doc); OpenMP is tried first."""
    import ctypes.util

    if ctypes.util.find_library("gomp") is None:
        pytest.skip("no OpenMP runtime (libgomp) here: numba cannot use OpenMP (apt-get install libgomp1)")
    code = ("import supportless, numba, numpy as np; from supportless.base.graph import edge_components; "
            "edge_components(3, np.array([0]), np.array([1])); from supportless.base.skinning import skin_dense; "
            "skin_dense(np.ones((4, 4)), np.ones((2, 4, 3))); print(numba.threading_layer())")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_THREADING_LAYER")}
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and run.stdout.split()[-1] == "omp", run.stderr
    run = subprocess.run([sys.executable, "-c", code], env=dict(env, NUMBA_THREADING_LAYER="workqueue"),
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and run.stdout.split()[-1] == "workqueue", run.stderr
