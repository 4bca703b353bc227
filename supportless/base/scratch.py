"""Temporary names a killed run leaves behind, recognised and removed by the next run.

Every temporary file or folder the tool makes carries its owner in its name:
``PREFIX`` + ``HOST-PID-`` + random characters (+ a suffix), e.g.
``.out.myhost-4242-k3j9x0ab.stl`` beside ``out.stl`` or
``supportless-native-myhost-4242-q8w7e6r5`` in the system's temporary folder.
:func:`remove_leftovers` removes those whose process is gone on this host
(whatever their age) and any older than :data:`STALE_SECONDS` (another
host's, on a shared folder, or a name from before owners were written), and
leaves a live process's work alone. :func:`scratch_dir` makes a scratch folder
so named, clears the leftovers of its kind first and removes itself at the end.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import socket
import tempfile
import time
from pathlib import Path

__all__ = ["STALE_SECONDS", "file_bytes", "owner_tag", "remove_leftovers", "scratch_dir"]

#: A temporary name untouched this long is a leftover whoever made it.
STALE_SECONDS = 3600.0


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9]", "", socket.gethostname())[:16] or "host"


def owner_tag() -> str:
    """``HOST-PID``: who makes a temporary name (this process on this machine)."""
    return f"{_host()}-{os.getpid()}"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: alive
        return True
    return True


def remove_leftovers(folder: str | os.PathLike, prefix: str, suffix: str = "") -> list[str]:
    """Remove the temporary files and folders of dead or stale owners named ``PREFIX...SUFFIX`` in ``folder``.

    Parameters
    ----------
    folder : str or os.PathLike
    prefix, suffix : str
        The fixed parts of the names (``".out."`` and ``".stl"`` for :func:`supportless.files.meshes.atomic_path`'s
        temporaries of ``out.stl``).

    Returns
    -------
    removed : list of str
        The names removed.
    """
    tagged = re.compile(rf"^{re.escape(prefix)}(?:([A-Za-z0-9]+)-(\d+)-)?[A-Za-z0-9_]{{8}}{re.escape(suffix)}$")
    removed = []
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    now, host = time.time(), _host()
    for name in names:
        m = tagged.match(name)
        if m is None:
            continue
        path = Path(folder) / name
        try:
            dead = m.group(1) == host and not _alive(int(m.group(2)))
            if dead or now - path.lstat().st_mtime > STALE_SECONDS:
                shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()
                removed.append(name)
        except OSError:  # gone already, or not ours to remove
            pass
    return removed


@contextlib.contextmanager
def scratch_dir(prefix: str, folder: str | os.PathLike | None = None):
    """A scratch folder ``PREFIX + HOST-PID-XXXXXXXX`` (system temporary folder by default), removed at the end.

    Leftovers of the same prefix (:func:`remove_leftovers`) are removed first.
    """
    folder = tempfile.gettempdir() if folder is None else folder
    remove_leftovers(folder, prefix)
    path = Path(tempfile.mkdtemp(prefix=f"{prefix}{owner_tag()}-", dir=folder))
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)


def file_bytes(name: str, write) -> bytes:
    """The bytes ``write(path)`` puts in a temporary file called ``name`` (for a writer that only takes a path)."""
    with scratch_dir("supportless-bytes-") as tmp:
        path = Path(tmp) / name
        write(path)
        return path.read_bytes()
