"""A compiled kernel's loop split over threads: consecutive ranges of its items, one range per thread.

numba's ``parallel=True`` turns a kernel's ``prange`` loop into a parallel function of its own, and compiling
that costs seconds per kernel (4.5 s for the ray grid, 3.4 s for the crossing filter, on the machine of
``benchmarks/RESULTS.md``): about a third of what a first run spends compiling. The kernels on a search's path
are therefore compiled serial and ``nogil`` (they release Python's lock while they run), with the loop's first
and last item as its last two arguments, and :func:`over` (:func:`split`) calls them on consecutive ranges from
threads of this process.
Each item is computed by the same code as before, so the results are the same bits.

A product of many poses at once is one matrix product instead (ARAP's covariances), and :func:`one_blas_thread`
keeps BLAS on the calling thread for the whole search: BLAS's own threads wait busy for a while after each
product, on the cores these kernels run on (with them the Xbot's search took 27 s instead of 21 s).

The number of threads is numba's (``NUMBA_NUM_THREADS``, :func:`numba.set_num_threads`), so a batch worker
lowered to one numba thread runs these kernels on one thread too.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor

__all__ = ["one_blas_thread", "over", "ranges", "split", "thread_count"]

_POOL: tuple[int, int, ThreadPoolExecutor] | None = None  # (process id, workers, pool)
_POOL_LOCK = threading.Lock()


def thread_count() -> int:
    """The threads numba would use here (at least 1)."""
    import numba

    return max(1, int(numba.get_num_threads()))


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Within the block, the BLAS libraries loaded in this process (NumPy's OpenBLAS) use one thread: the
    calling one. (threadpoolctl's controller, made once; switching costs about 15 microseconds.)"""
    with _blas_controller().limit(limits=1, user_api="blas"):
        yield


_CONTROLLER = None


def _blas_controller():
    """threadpoolctl's controller of the libraries loaded when first asked (NumPy's BLAS is loaded with NumPy)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        from threadpoolctl import ThreadpoolController

        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def ranges(n: int, parts: int) -> list[tuple[int, int]]:
    """``parts`` consecutive ranges ``[lo, hi)`` covering ``range(n)``, sizes differing by one at most (fewer
    when ``n < parts``; none when ``n == 0``)."""
    parts = max(1, min(int(parts), int(n)))
    if n <= 0:
        return []
    edges = [(n * k) // parts for k in range(parts + 1)]
    return [(edges[k], edges[k + 1]) for k in range(parts)]


def _pool(workers: int) -> ThreadPoolExecutor:
    """This process's pool of ``workers`` threads (a new one after a fork, whose child has no threads)."""
    global _POOL
    with _POOL_LOCK:
        if _POOL is None or _POOL[0] != os.getpid() or _POOL[1] < workers:
            _POOL = (os.getpid(), workers, ThreadPoolExecutor(workers, thread_name_prefix="supportless-kernel"))
        return _POOL[2]


def split(call: Callable[[int, int, int], object], n: int, threads: int | None = None) -> None:
    """Run ``call(lo, hi, t)`` for the consecutive ranges ``[lo, hi)`` of ``range(n)``, one per thread.

    ``t`` numbers the ranges from 0 (a kernel's scratch row, like :func:`numba.get_thread_id` in a ``prange``).
    The last range runs in this thread, the others in a pool; every range has finished when this returns, and
    an exception in any is raised here. ``call`` must release Python's lock (a ``nogil`` kernel) for the
    ranges to run at once.

    Parameters
    ----------
    call : callable (lo: int, hi: int, t: int) -> object
    n : int
        Items.
    threads : int, optional
        At most this many ranges; numba's thread count by default (:func:`thread_count`).
    """
    parts = ranges(n, thread_count() if threads is None else threads)
    if len(parts) <= 1:
        for t, (lo, hi) in enumerate(parts):
            call(lo, hi, t)
        return
    pool = _pool(len(parts) - 1)
    futures = [pool.submit(call, lo, hi, t) for t, (lo, hi) in enumerate(parts[:-1])]
    try:
        call(parts[-1][0], parts[-1][1], len(parts) - 1)
    finally:
        for future in futures:
            future.result()


def over(kernel: Callable[..., object], n: int, *args) -> None:
    """Run ``kernel(*args, lo, hi)`` for the consecutive ranges ``[lo, hi)`` of ``range(n)``, one per thread
    (:func:`split`): a ``nogil`` kernel whose loop runs over its items ``lo:hi``, writing into arrays of ``args``."""
    split(lambda lo, hi, _: kernel(*args, lo, hi), n)
