"""Undo/redo of poses for the interactive viewer.

A slider drag or a gizmo drag sends many small updates; :class:`PoseHistory`
groups consecutive edits of the same control made within ``merge_seconds`` into
one undo step, so one undo restores the pose from before the whole drag.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["PoseHistory"]


class PoseHistory:
    """Undo and redo stacks of ``(m, 3)`` angle arrays.

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
        self._undo: list[np.ndarray] = []
        self._redo: list[np.ndarray] = []
        self._last_key = None
        self._last_time = -np.inf

    def record(self, current: np.ndarray, key=None) -> bool:
        """Remember ``current`` (the pose before an edit) as an undo step.

        Parameters
        ----------
        current : (m, 3) float64
            The pose about to be changed.
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
        if self._undo and np.array_equal(self._undo[-1], current):
            self._redo.clear()
            return False
        self._undo.append(np.array(current, dtype=np.float64, copy=True))
        del self._undo[: -self.limit]
        self._redo.clear()
        return True

    def undo(self, current: np.ndarray) -> np.ndarray | None:
        """The pose before the last edit (``current`` goes on the redo stack), or None."""
        self._last_key = None
        if not self._undo:
            return None
        self._redo.append(np.array(current, copy=True))
        return self._undo.pop()

    def redo(self, current: np.ndarray) -> np.ndarray | None:
        """The pose undone last (``current`` goes on the undo stack), or None."""
        self._last_key = None
        if not self._redo:
            return None
        self._undo.append(np.array(current, copy=True))
        return self._redo.pop()

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)
