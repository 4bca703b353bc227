"""Output locations: checked before any work (writable, and never one of the inputs), and written atomically."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

from ..base.errors import InputError
from ..base.interrupt import pause_point
from ..base.scratch import owner_tag, remove_leftovers

__all__ = ["atomic_path", "check_output_paths"]


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_output_paths(files=(), folders=(), inputs=()) -> None:
    """Refuse output locations that cannot be written or would replace an input, before any work.

    Parameters
    ----------
    files : iterable of (str, path or None)
        ``(option, path)`` of each output file (``None`` paths are skipped).
    folders : iterable of (str, path or None)
        ``(option, path)`` of each output folder.
    inputs : iterable of path or None
        The files the command reads.

    Raises
    ------
    InputError
        One line naming the path and the option: an output that is an input
        (the same file, after resolving links), two outputs at one path, a
        file where a folder is needed or a folder where a file is, or a
        location that cannot be created or written.
    """
    ins = [Path(p) for p in inputs if p is not None]
    seen: dict[Path, str] = {}
    for kind, entries in (("file", files), ("folder", folders)):
        for option, raw in entries:
            if raw is None:
                continue
            path = Path(raw)
            for source in ins:
                if _same_file(path, source) or path.resolve() == source.resolve():
                    raise InputError(path, f"{option} would overwrite the input {source}; choose another path")
            key = path.resolve()
            if key in seen:
                raise InputError(path, f"{option} and {seen[key]} are the same path; give each output its own")
            seen[key] = option
            if kind == "file" and path.is_dir():
                raise InputError(path, f"{option} is a folder; give a file name")
            if kind == "folder" and path.exists() and not path.is_dir():
                raise InputError(path, f"{option} is a file; give a folder")
            folder = path.parent if kind == "file" else path
            while not folder.exists() and folder != folder.parent:
                folder = folder.parent
            if not folder.is_dir():
                raise InputError(path, f"{option}: {folder} is a file, not a folder; choose another location")
            if not os.access(folder, os.W_OK | os.X_OK):
                raise InputError(path, f"{option}: no permission to write in {folder}; choose another location")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    Parameters
    ----------
    path : str or os.PathLike
        The final destination. Its folder is created if missing.

    Yields
    ------
    tmp : pathlib.Path
        Where to write. It keeps ``path``'s suffix so format sniffing by
        extension still works. It is removed if the block raises.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_leftovers(path.parent, f".{path.stem}.", path.suffix)  # of killed runs (supportless.base.scratch)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.{owner_tag()}-", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the file the usual mode
        pause_point(f"rename {path.name}")
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
