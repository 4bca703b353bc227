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

import numba
import pytest

from supportless.apps import warmup
from supportless.apps.warmup import KERNELS, Kernel, split


def test_split_keeps_every_kernel_once_and_balances_the_halves():
    kernels = [Kernel("m", name, "()", s) for name, s in zip("abcde", (5.0, 4.0, 3.0, 3.0, 1.0))]
    helper, here = split(kernels)
    assert sorted(k.name for k in helper + here) == list("abcde")
    # largest first, each to the lighter half (ties to the helper): a 5 | b 4, c 3 (4 < 5) | d 3 (5 <= 7) | e 1
    assert [k.name for k in helper] == ["a", "d"] and [k.name for k in here] == ["b", "c", "e"]
    helper, here = split(KERNELS)
    gap = abs(sum(k.seconds for k in helper) - sum(k.seconds for k in here))
    assert gap <= max(k.seconds for k in KERNELS)
    assert split([]) == ([], [])


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
    from numba.core.registry import CPUDispatcher
    from supportless.apps import warmup
    from supportless.search.settings import SearchSettings

    cache = tempfile.mkdtemp()
    for source in sys.argv[1:]:
        rig = sl.load_rig(source, cache_dir=cache, **({"up": "y"} if source.startswith("demo:") else {}))
        result = sl.optimize(rig, SearchSettings(particles=8, iterations=3, seed=0))
        rig.self_intersects(result.angles)
    listed = {(k.label, str(warmup._argument_types(k))) for k in warmup.KERNELS}
    called = set()
    for name, module in list(sys.modules.items()):
        if name.startswith("supportless.") and not name.startswith("supportless.shapes"):
            for attr, value in vars(module).items():
                if isinstance(value, CPUDispatcher) and value.py_func.__module__ == name:
                    called |= {(f"{name}.{attr}", str(tuple(sig))) for sig in value.signatures}
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


def test_the_helper_compiles_its_half_into_the_cache(tmp_path):
    """With an empty cache every kernel is cold; a warm-up of the smallest one leaves it in the cache, compiled
    by the helper process (this process only waited, its dispatcher holds nothing); then nothing is cold."""
    if (os.cpu_count() or 1) < 2:
        pytest.skip("one core: the warm-up compiles every kernel in the calling process, no helper to test")
    smallest = min(KERNELS, key=lambda k: k.seconds)
    script = textwrap.dedent(f"""
        import json
        from supportless.apps import warmup
        kernel = [k for k in warmup.KERNELS if k.label == {smallest.label!r}]
        cold = len(warmup.cold_kernels())
        warming = warmup.start(kernel)
        helped = warming.helper is not None and warming.here == []
        warming.finish()
        again = warmup.start(kernel)  # a warm cache: nothing to start
        print(json.dumps({{"cold": cold, "helped": helped, "after": len(warmup.cold_kernels(kernel)),
                           "signatures": len(warmup._dispatcher(kernel[0]).signatures), "again": again.active}}))
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600, env=env)
    assert out.returncode == 0, out.stderr[-2000:]
    found = json.loads(out.stdout.strip().splitlines()[-1])
    assert found == {"cold": len(KERNELS), "helped": True, "after": 0, "signatures": 0, "again": False}

