"""Undo/redo of poses for the interactive viewer.

A slider drag or a gizmo drag sends many small updates; :class:`PoseHistory`
groups consecutive edits of the same control made within ``merge_seconds`` into
one undo step, so one undo restores the pose from before the whole drag.

A step is a pose: one array (e.g. the ``(m, 3)`` angles) or a tuple of
arrays (the viewer keeps the angles with the ``(d, d)`` print rotation).
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["PoseHistory"]


def _copy(pose):
    """A copy of a pose (an array, or a tuple of arrays)."""
    if isinstance(pose, tuple):
        return tuple(np.array(a, dtype=np.float64, copy=True) for a in pose)
    return np.array(pose, dtype=np.float64, copy=True)


def _same(a, b) -> bool:
    """Whether two poses (arrays, or tuples of arrays) are equal."""
    if isinstance(a, tuple) or isinstance(b, tuple):
        return (isinstance(a, tuple) and isinstance(b, tuple) and len(a) == len(b)
                and all(np.array_equal(x, y) for x, y in zip(a, b)))
    return np.array_equal(a, b)


class PoseHistory:
    """Undo and redo stacks of poses: ``(m, 3)`` angle arrays, or tuples of arrays.

    Parameters
    ----------
    limit : int
        Most undo steps kept.
    merge_seconds : float
        Edits with the same ``key`` closer together than this share one step.
    """

    def __init__(self, limit: int = 200, merge_seconds: float = 1.0):
        self.limit = limit
        self.merge_seconds = merge_seconds
        self._undo: list = []
        self._redo: list = []
        self._last_key = None
        self._last_time = -np.inf

    def record(self, current, key=None) -> bool:
        """Remember ``current`` (the pose before an edit) as an undo step.

        Parameters
        ----------
        current : (m, 3) float64, or tuple of arrays
            The pose about to be changed (e.g. ``(angles, rotation)``).
        key : hashable, optional
            Which control makes the edit; ``None`` never merges.

        Returns
        -------
        recorded : bool
            False when the edit was merged into the previous step.
        """
        now = time.monotonic()
        merge = key is not None and key == self._last_key and now - self._last_time < self.merge_seconds
        self._last_key, self._last_time = key, now
        if merge:
            return False
        if self._undo and _same(self._undo[-1], current):
            self._redo.clear()
            return False
        self._undo.append(_copy(current))
        del self._undo[: -self.limit]
        self._redo.clear()
        return True

    def undo(self, current):
        """The pose before the last edit (``current`` goes on the redo stack), or None."""
        self._last_key = None
        if not self._undo:
            return None
        self._redo.append(_copy(current))
        return self._undo.pop()

    def redo(self, current):
        """The pose undone last (``current`` goes on the undo stack), or None."""
        self._last_key = None
        if not self._redo:
            return None
        self._undo.append(_copy(current))
        return self._redo.pop()

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)
