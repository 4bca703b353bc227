"""The project's exception types.

Every error a user can cause (a bad file, a bad option) is raised as an
:class:`InputError` whose message is one line: which file, what is wrong and
what to do. The command line prints that line and exits non-zero; it never
shows a traceback for these. Failures of an outside tool are
:class:`SlicerError` (PrusaSlicer; :class:`supportless.slicing.prusaslicer.SlicerNotFound`
when it is missing).
"""

from __future__ import annotations

import os

__all__ = ["InputError", "SlicerError", "SupportlessError"]


class SupportlessError(Exception):
    """Base class of the errors this package raises on purpose."""


class InputError(SupportlessError, ValueError):
    """Bad input: a file that cannot be read or does not describe a valid model.

    Parameters
    ----------
    path : str or os.PathLike or None
        The file at fault, if there is one. It is put at the start of the message.
    message : str
        What is wrong and, where it helps, what to do about it.
    """

    def __init__(self, path: str | os.PathLike | None, message: str):
        self.path = None if path is None else os.fspath(path)
        self.reason = message
        super().__init__(f"{self.path}: {message}" if self.path else message)


class SlicerError(SupportlessError, RuntimeError):
    """PrusaSlicer failed, timed out or wrote output that cannot be read; the message is one line."""
