"""Output locations checked before any work: writable, and never one of the inputs."""

from __future__ import annotations

import os
from pathlib import Path

from ..base.errors import InputError

__all__ = ["check_output_paths"]


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
