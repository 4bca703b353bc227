"""A first run's kernels compiled on both cores (:mod:`supportless.apps.warmup`).

The list of kernels must be the one a search calls: a kernel a run calls but the list lacks is compiled
where it is first called, on one core, and the warm-up silently loses its point. So a fresh process runs
small searches and says which kernels (and signatures) it called from Python.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time

import numba
import pytest
from processes import gone, linux_only

from supportless.apps import warmup
from supportless.apps.warmup import KERNELS, Kernel


def test_each_kernel_is_compiled_by_the_process_that_claims_it_first(tmp_path, monkeypatch):
    compiled = []
    monkeypatch.setattr(warmup, "compile_kernels", lambda kernels: compiled.extend(k.name for k in kernels))
    kernels = [Kernel("m", name, "()", s) for name, s in zip("abc", (3.0, 2.0, 1.0))]
    assert warmup.claim(kernels[1], tmp_path)  # the other process took b
    assert not warmup.claim(kernels[1], tmp_path)
    assert [k.name for k in warmup.compile_claimed(kernels, tmp_path)] == ["a", "c"]
    assert compiled == ["a", "c"]
    assert warmup.compile_claimed(kernels, tmp_path) == [] and compiled == ["a", "c"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.a", "m.b", "m.c"]


def test_every_listed_kernel_is_a_cached_numba_kernel_with_its_arity():
    assert len({k.label for k in KERNELS}) == len(KERNELS)
    for kernel in KERNELS:
        dispatcher = warmup._dispatcher(kernel)
        assert isinstance(dispatcher, numba.core.registry.CPUDispatcher), kernel.label
        assert dispatcher._cache is not None and type(dispatcher._cache).__name__ == "FunctionCache", kernel.label
        params = dispatcher.py_func.__code__.co_argcount
        assert len(warmup._argument_types(kernel)) == params, kernel.label


_RUN = textwrap.dedent("""
    import json, sys, tempfile
    import supportless as sl
    from numba.core.dispatcher import Dispatcher
    from supportless.apps import warmup
    from supportless.search.settings import SearchSettings

    called = set()  # the kernels called from Python (a kernel's callees are compiled into it, not called)
    compile_for_args = Dispatcher._compile_for_args

    def recording(self, *args, **kws):
        if self.py_func.__module__.startswith("supportless."):
            types = tuple(self.typeof_pyval(a) for a in args)
            called.add((f"{self.py_func.__module__}.{self.py_func.__name__}", str(types)))
        return compile_for_args(self, *args, **kws)

    Dispatcher._compile_for_args = recording
    cache = tempfile.mkdtemp()
    for source in sys.argv[1:]:
        rig = sl.load_rig(source, cache_dir=cache, **({"up": "y"} if source.startswith("demo:") else {}))
        result = sl.optimize(rig, SearchSettings(particles=8, iterations=3, seed=0))
        rig.self_intersects(result.angles)
    listed = {(k.label, str(warmup._argument_types(k))) for k in warmup.KERNELS}
    called = {(label, types) for label, types in called if not label.startswith("supportless.shapes")}
    print(json.dumps({"unlisted": sorted(called - listed), "uncalled": sorted(listed - called)}))
""")


def test_a_search_calls_no_kernel_the_warm_up_does_not_compile(shared_file):
    character = str(shared_file("gltf/CesiumMan.glb"))
    out = subprocess.run([sys.executable, "-c", _RUN, "demo:tpose", character], capture_output=True, text=True,
                         timeout=900)
    assert out.returncode == 0, out.stderr[-2000:]
    found = json.loads(out.stdout.strip().splitlines()[-1])
    assert found["unlisted"] == [], "kernels a search calls that warmup.KERNELS lacks (or with another signature)"
    # every listed kernel is one these runs call (a stale entry would be compiled for nothing)
    assert found["uncalled"] == []


def test_the_helper_and_a_warm_up_leave_their_kernels_in_the_cache(tmp_path):
    """With an empty cache every kernel is cold. The helper, run as :func:`warmup.start` runs it, compiles the
    kernel it claims into the cache (this process compiles nothing); a whole warm-up (:func:`warmup.start`, then
    :meth:`WarmUp.finish`) of another leaves it in the cache and its claims removed; then nothing is cold."""
    if (os.cpu_count() or 1) < 2:
        pytest.skip("one core: the warm-up compiles every kernel in the calling process, no helper to test")
    first, second = sorted(KERNELS, key=lambda k: k.seconds)[:2]
    script = textwrap.dedent(f"""
        import json, os, subprocess, sys, tempfile
        from supportless.apps import warmup
        first, second = ([k for k in warmup.KERNELS if k.label == label] for label in ({first.label!r},
                                                                                      {second.label!r}))
        cold = len(warmup.cold_kernels())
        claims = tempfile.mkdtemp()
        subprocess.run([sys.executable, "-m", "supportless.apps.warmup", claims, first[0].label], check=True)
        helper = {{"claimed": os.listdir(claims), "cold": len(warmup.cold_kernels(first)),
                   "here": len(warmup._dispatcher(first[0]).signatures)}}
        warming = warmup.start(second)
        started, folder = warming.helper is not None, warming.claims
        warming.finish()
        whole = {{"started": started, "cold": len(warmup.cold_kernels(second)),
                  "claims_left": os.path.exists(folder), "helper_left": warming.helper is not None}}
        print(json.dumps({{"cold": cold, "helper": helper, "whole": whole,
                           "again": warmup.start(first + second).active}}))
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600, env=env)
    assert out.returncode == 0, out.stderr[-2000:]
    found = json.loads(out.stdout.strip().splitlines()[-1])
    assert found == {"cold": len(KERNELS), "helper": {"claimed": [first.label], "cold": 0, "here": 0},
                     "whole": {"started": True, "cold": 0, "claims_left": False, "helper_left": False},
                     "again": False}


@linux_only
def test_the_helper_ends_with_the_run_that_started_it(tmp_path):
    """A run killed outright (``kill -9``) leaves no helper compiling for it."""
    if (os.cpu_count() or 1) < 2:
        pytest.skip("one core: no helper is started")
    script = textwrap.dedent("""
        import os, signal
        from supportless.apps import warmup
        warming = warmup.start()
        print(warming.helper.pid, flush=True)
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))  # every kernel cold: the helper has work
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=env)
    helper = int(out.stdout.split()[0])
    deadline = time.monotonic() + 10  # (compiling every kernel takes the helper about 30 s)
    while not gone(helper) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert gone(helper)


def test_view_starts_the_warm_up_in_the_background_and_says_so(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from supportless.apps import cli_view
    from supportless.apps.cli import main
    from supportless.apps.ui import app

    class Started:
        helper = object()

        def finish(self):
            pytest.fail("the page does not wait for the kernels")

    opened = []
    monkeypatch.setattr(cli_view, "start_warm_up", lambda: Started())
    monkeypatch.setattr(app, "run_app", lambda rig, **kw: opened.append(rig))
    result = CliRunner().invoke(main, ["view", "--workdir", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert opened == [None] and "compiling the numerical kernels in the background" in result.output
