"""Where numba keeps compiled kernels, and which threads run them, chosen before numba is imported.

The kernels are compiled with ``cache=True``. numba caches next to the
sources (``__pycache__``) or in the user's cache folder (``~/.cache/numba``);
when neither can be written (a read-only install run by a service account
or ``docker --user`` with no home) it refuses to compile at all, and even
``supportless --help`` fails. :func:`configure` then points
``NUMBA_CACHE_DIR`` at a folder in the system's temporary directory. A
``NUMBA_CACHE_DIR`` set by the user is left alone.

numba runs parallel kernels on the first threading layer it finds of TBB, OpenMP and its own work queue. With
TBB (Debian's ``libtbb12``, which PrusaSlicer brings) every launch of a kernel took longer than the one before
in a long-lived process: a loop over four points, 28 microseconds a launch at first, 250 after 5 000 launches;
the crossing filter's grid, 0.5 ms, then 19 ms (numba 0.68, TBB 2021.8). With OpenMP it stays at 5
microseconds. :func:`configure` therefore puts OpenMP first (``NUMBA_THREADING_LAYER_PRIORITY``), TBB next;
a layer or an order the user chose is left alone.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["THREADING_LAYERS", "configure", "fallback_cache_dir", "writable"]

#: numba's threading layers in the order they are tried (the first that loads is used).
THREADING_LAYERS = "omp tbb workqueue"


def writable(folder: str | os.PathLike) -> bool:
    """Whether ``folder`` exists or can be made, and a file can be written in it (as numba checks)."""
    try:
        os.makedirs(folder, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
        return True
    except OSError:
        return False


def _user_cache_dir() -> Path:
    """numba's user-wide cache folder: ``$XDG_CACHE_HOME/numba`` or ``~/.cache/numba`` (Linux, macOS alike)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "numba"


def fallback_cache_dir(package_dir: str | os.PathLike, user_cache_dir: str | os.PathLike) -> str | None:
    """The folder to give numba, or None when one of its own places can be written.

    Parameters
    ----------
    package_dir : path
        The folder of the package's sources (numba's first choice is its ``__pycache__``).
    user_cache_dir : path
        numba's user-wide cache folder.

    Returns
    -------
    folder : str or None
        A per-user folder under the system's temporary directory, when
        neither ``package_dir/__pycache__`` nor ``user_cache_dir`` is writable.
    """
    if writable(Path(package_dir) / "__pycache__") or writable(user_cache_dir):
        return None
    uid = os.getuid() if hasattr(os, "getuid") else "user"
    return os.path.join(tempfile.gettempdir(), f"supportless-numba-{uid}")


def configure() -> None:
    """Set ``NUMBA_CACHE_DIR`` to :func:`fallback_cache_dir` when numba has nowhere to write (silently), and the
    order of the threading layers to :data:`THREADING_LAYERS` unless the user set a layer or an order."""
    if not (os.environ.get("NUMBA_THREADING_LAYER") or os.environ.get("NUMBA_THREADING_LAYER_PRIORITY")):
        os.environ["NUMBA_THREADING_LAYER_PRIORITY"] = THREADING_LAYERS
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    folder = fallback_cache_dir(Path(__file__).parent, _user_cache_dir())
    if folder is not None:
        os.environ["NUMBA_CACHE_DIR"] = folder
