"""A first run's kernels compiled on both cores: in a helper process while the rig is built, then in both.

numba compiles a kernel the first time it is called and keeps it in its cache (``cache=True``). A run after
install therefore spends much of its time compiling, one kernel after another on one core: the kernels of a
search take 26–32 s (56–58 s while numba built their loops' parallel versions; they are now serial, split
over threads by :mod:`supportless.base.threads`), against 11 s for the whole of a warm ``supportless demo``.
:func:`start` starts a
helper process that compiles the kernels a search uses (:data:`KERNELS`), largest first, into the same cache
while this process builds the rig; :meth:`WarmUp.finish` then compiles them here too, and each process takes
the next kernel the other has not claimed (a file made once in a shared folder), so the two cores stay busy
until the last. Every kernel is then loaded from the cache where it is first called. Nothing changes in what
the kernels compute: the cache holds the code numba would have compiled here.

When numba's cache already holds every kernel, nothing is started; nor with ``SUPPORTLESS_WARMUP=0`` in the
environment (one process only, each kernel compiled where it is first called). Should the helper fail, each
kernel it did not compile is compiled where it is first called, as without a warm-up.
"""

from __future__ import annotations

import atexit
import importlib
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["HELPER_TIMEOUT_S", "KERNELS", "Kernel", "WarmUp", "claim", "cold_kernels", "compile_claimed", "compile_kernels",
           "start"]


#: Seconds :meth:`WarmUp.finish` waits for the helper at most (its half takes about 15 s on 2 cores); past them
#: it is stopped and each kernel it did not compile is compiled where it is first called.
HELPER_TIMEOUT_S = 600.0

#: The environment variable that gives the helper its parent's pid (it ends when that process ends).
_PARENT = "SUPPORTLESS_WARMUP_PARENT"


@dataclass(frozen=True)
class Kernel:
    """A compiled kernel a 3D search calls from Python, with the one signature it is called with.

    ``seconds`` is its compilation time on the machine of ``benchmarks/RESULTS.md`` (callees included), which
    only orders them: the largest are claimed first.
    """

    module: str
    name: str
    signature: str
    seconds: float

    @property
    def label(self) -> str:
        """``module.name``."""
        return f"{self.module}.{self.name}"


_F1, _F2, _F3, _F4 = "float64[::1]", "float64[:, ::1]", "float64[:, :, ::1]", "float64[:, :, :, ::1]"
_I1, _I2 = "int64[::1]", "int64[:, ::1]"

#: The kernels a 3D search, its exact checks and its choice call from Python (``tests/apps/test_warmup.py`` checks
#: that a run calls no other), largest first.
KERNELS: tuple[Kernel, ...] = (
    Kernel("supportless.energies._grid_fast", "_grid3_fast",
           f"({_F3}, {_I2}, {_F2}, int64, float64, boolean, {_F2}, int32[::1], {_F1}, int8[::1], int32[::1], {_I1}, "
           f"{_F1}, int8[::1], {_I1}, {_I1}, int32[::1], int64, int64, {_F2}, boolean[::1])", 8.2),
    Kernel("supportless.base.crossing_filter", "_pairs",
           f"({_F2}, {_I2}, {_F2}, {_F2}, {_I2}, {_I1}, {_I1}, int32[::1], boolean[::1], int64, int64)", 6.0),
    Kernel("supportless.energies.arap", "_rotation_terms_of", f"({_F4}, {_F1}, int64, int64)", 3.0),
    Kernel("supportless.base.closest", "_nearest_of", f"({_F2}, {_I1}, {_F2}, {_I2}, {_I1}, {_F1}, {_I1}, int64, int64)",
           1.9),
    Kernel("supportless.base.graph", "_components", f"(int64, {_I1}, {_I1})", 1.8),
    Kernel("supportless.energies.overhang", "_kernel3_poses", f"({_F3}, {_I2}, {_F2}, {_F1}, float64, boolean[:, ::1], "
           f"float64, {_F2}, int64, int64)", 1.6),
    Kernel("supportless.base.chain", "_chain3", f"({_F4}, {_F2}, {_I1}, {_I1}, {_F4})", 1.6),
    Kernel("supportless.base.skinning", "_skin_dense3", f"({_F2}, {_F3}, {_F3}, int64, int64)", 1.5),
    Kernel("supportless.energies.surface", "_signed_measure_of", f"({_F3}, {_I2}, {_F1}, int64, int64)", 1.4),
    Kernel("supportless.base.crossing_filter", "_grouped", f"({_I1}, int32[::1], int64, int64)", 1.4),
    Kernel("supportless.energies.footprint", "_sections_of", f"({_F3}, {_I2}, {_F2}, {_F1}, {_F1}, int64, int64)",
           1.3),
    Kernel("supportless.rig.balance", "_lowest_of", f"({_F3}, {_I1}, {_F1}, {_F1}, int64, int64)", 1.0),
    Kernel("supportless.base.crossing_filter", "_cells_of", f"({_F2}, {_F2}, {_F1}, float64, {_I2}, {_I2}, {_F1}, int64, "
           "int64)", 0.9),
    Kernel("supportless.base.kinematics", "_skin_blocks3", f"({_I1}, {_I1}, {_F2}, {_F3}, {_F3}, int64, int64)", 0.9),
    Kernel("supportless.base.crossing_filter", "_entries", f"({_I2}, {_I2}, {_I1}, {_I1}, int32[::1], int64, int64)",
           0.8),
    Kernel("supportless.base.crossing_filter", "_boxes_of", f"({_F2}, {_I2}, {_F2}, {_F2}, int64, int64)", 0.6),
    Kernel("supportless.base.chain", "_euler3", f"({_F2}, {_F3})", 0.6),
)


def _dispatcher(kernel: Kernel):
    """The numba dispatcher of ``kernel``."""
    return getattr(importlib.import_module(kernel.module), kernel.name)


def _argument_types(kernel: Kernel) -> tuple:
    """numba's argument types of ``kernel.signature``."""
    from numba.core import sigutils

    args, _ = sigutils.normalize_signature(kernel.signature)
    return tuple(args)


def compile_kernels(kernels) -> None:
    """Compile each of ``kernels`` (or load it from numba's cache) in this process."""
    for kernel in kernels:
        _dispatcher(kernel).compile(_argument_types(kernel))


def cold_kernels(kernels=KERNELS) -> list[Kernel]:
    """The kernels of ``kernels`` numba's cache does not hold yet for this machine and their sources.

    numba keeps no public record of its cache; its index is read as numba reads it. Should that fail (another
    numba), no kernel is said to be cold: nothing is warmed, and each compiles where it is first called.
    """
    cold = []
    try:
        for kernel in kernels:
            dispatcher = _dispatcher(kernel)
            cache = dispatcher._cache
            key = cache._index_key(_argument_types(kernel), dispatcher.targetctx.codegen())
            if key not in cache._cache_file._load_index():
                cold.append(kernel)
    except Exception:  # noqa: BLE001 - numba's private cache layout changed: no warm-up, nothing lost
        return []
    return cold


def claim(kernel: Kernel, claims: Path) -> bool:
    """Whether this process is the first to claim ``kernel`` in the folder ``claims`` (by creating its file
    there, which succeeds once)."""
    try:
        os.close(os.open(claims / kernel.label, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    return True


def compile_claimed(kernels, claims: Path) -> list[Kernel]:
    """Compile, in their order, the kernels of ``kernels`` that no other process has claimed in ``claims``;
    those compiled here."""
    mine = []
    for kernel in kernels:
        if claim(kernel, claims):
            compile_kernels([kernel])
            mine.append(kernel)
    return mine


@dataclass
class WarmUp:
    """A warm-up under way: the cold kernels (largest first), the folder of their claims and the helper
    process (None when none was started)."""

    cold: list[Kernel] = field(default_factory=list)
    claims: Path | None = None
    helper: subprocess.Popen | None = None

    @property
    def active(self) -> bool:
        """Whether any kernel was cold when the warm-up started."""
        return bool(self.cold)

    def finish(self) -> list[Kernel]:
        """Compile here each cold kernel the helper has not claimed, then wait for the helper; the kernels
        compiled here."""
        try:
            if self.claims is None:
                compile_kernels(self.cold)
                return list(self.cold)
            return compile_claimed(self.cold, self.claims)
        finally:
            self.cancel(wait=True)

    def cancel(self, wait: bool = False) -> None:
        """Stop the helper (the kernels are not needed: a planar figure) or, with ``wait``, let it end its
        kernel first; the claims are removed."""
        self.cold = []
        if self.helper is not None:
            if wait:
                try:
                    self.helper.wait(timeout=HELPER_TIMEOUT_S)
                except subprocess.TimeoutExpired:
                    pass
            _stop(self.helper)
            self.helper = None
        if self.claims is not None:
            shutil.rmtree(self.claims, ignore_errors=True)
            self.claims = None


def _stop(process: subprocess.Popen) -> None:
    """End ``process`` if it still runs (numba writes each cache file whole, under a temporary name first)."""
    if process.poll() is None:
        process.kill()
        process.wait()


def start(kernels=KERNELS) -> WarmUp:
    """Start compiling the cold kernels of ``kernels`` in a helper process, largest first.

    Returns
    -------
    warm_up : WarmUp
        Its :meth:`~WarmUp.finish` compiles here each cold kernel the helper has not yet claimed, largest
        first, and waits for the helper. With one core, or when the helper cannot be started, every cold kernel
        is left to :meth:`~WarmUp.finish`; with ``SUPPORTLESS_WARMUP=0``, none.
    """
    if os.environ.get("SUPPORTLESS_WARMUP", "").strip() == "0":
        return WarmUp()
    cold = sorted(cold_kernels(kernels), key=lambda k: -k.seconds)
    if not cold or (os.cpu_count() or 1) < 2:
        return WarmUp(cold=cold)
    claims = Path(tempfile.mkdtemp(prefix="supportless-warmup-"))
    try:
        process = subprocess.Popen([sys.executable, "-m", __name__, str(claims), *(k.label for k in cold)],
                                   stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                   env=dict(os.environ, **{_PARENT: str(os.getpid())}))
    except OSError:
        return WarmUp(cold=cold, claims=claims)
    warming = WarmUp(cold=cold, claims=claims, helper=process)
    atexit.register(warming.cancel)  # an error before finish() leaves no process and no claims behind
    return warming


def _main(claims: str, labels: list[str]) -> int:
    """The helper: compile the kernels named ``module.name`` that the run has not claimed in ``claims``; it ends
    with the run (killed mid-kernel, it leaves no cache file half-written: numba writes each under another name
    first)."""
    from ..base.lifetime import end_with_parent

    parent = os.environ.get(_PARENT, "")
    end_with_parent(int(parent) if parent.isdigit() else None)
    by_label = {k.label: k for k in KERNELS}
    compile_claimed([by_label[label] for label in labels if label in by_label], Path(claims))
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1], sys.argv[2:]))
