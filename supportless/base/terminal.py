"""A standard output that its reader may close (``supportless ... | head -1``) without harm."""

from __future__ import annotations

import io
import os
import sys

__all__ = ["ClosableStdout", "drop_stdout"]


class ClosableStdout:
    """stdout that a reader may close (``supportless ... | head -1``): writes after that are dropped."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            drop_stdout()
            return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except BrokenPipeError:
            drop_stdout()

    def __getattr__(self, name):
        return getattr(self._stream, name)


def drop_stdout() -> None:
    """Point a closed stdout at /dev/null, so later writes (and the flush at exit) are silent."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        pass
