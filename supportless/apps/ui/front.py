"""The front of poses in the browser app: find it in the background, then step through it.

:class:`FrontBrowser` runs :func:`supportless.apps.pareto.pareto_front` from the
editor's settings in a thread and, once it is there, sets the editor's pose
and print rotation to any of its poses (an undo step each), so the app's
slider shows the trade-off between least support and least distortion.
"""

from __future__ import annotations

import logging
import threading

from ..pareto import Front, pareto_front
from .state import EditorState

__all__ = ["FrontBrowser"]

logger = logging.getLogger(__name__)


class FrontBrowser:
    """The front of one editor's model.

    Parameters
    ----------
    state : EditorState
        Whose rig and settings the front is searched with, and whose pose
        :meth:`show` sets.

    Attributes
    ----------
    front : Front or None
        The last front found.
    shown : int or None
        The 0-based pose of the front on screen.
    """

    def __init__(self, state: EditorState):
        self.state = state
        self.front: Front | None = None
        self.shown: int | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()

    @property
    def running(self) -> bool:
        """True while a front is being searched."""
        return self._thread is not None and self._thread.is_alive()

    def start(self, count: int = 5, **overrides) -> bool:
        """Search a front of up to ``count`` poses in a background thread (False if one is running).

        Listeners of the state get ``"front_done"`` (with ``front=`` or ``error=``) at the end.
        """
        if self.running:
            return False
        settings = self.state.settings.replace(**overrides)
        settings.fixed_bones(self.state.rig)  # bad bone names: here, not in the thread
        self._stop.clear()

        def work():
            try:
                front = pareto_front(self.state.rig, settings, int(count), stop=self._stop.is_set)
            except Exception as exc:  # noqa: BLE001 - reported to the listeners, the app keeps running
                logger.exception("front search failed")
                self.state._notify("front_done", error=exc)
                return
            self.front, self.shown = front, None
            self.state._notify("front_done", front=front)

        self._thread = threading.Thread(target=work, name="supportless-ui-front", daemon=True)
        self._thread.start()
        return True

    def cancel(self) -> None:
        """Stop the front's searches after their current iteration."""
        self._stop.set()

    def wait(self, timeout: float | None = None) -> bool:
        """Wait for the front; True when none is being searched."""
        if self._thread is not None:
            self._thread.join(timeout)
        return not self.running

    def show(self, index: int) -> dict:
        """Set the editor to pose ``index`` (0-based, least support first) of the front; returns its measures.

        Raises
        ------
        ValueError
            When there is no front yet or ``index`` is out of range.
        """
        if self.front is None or not self.front.poses:
            raise ValueError("no front yet: find one first")
        if not 0 <= index < len(self.front.poses):
            raise ValueError(f"front pose {index + 1} is not within 1..{len(self.front.poses)}")
        pose = self.front.poses[index]
        self.state.set_angles(pose.result.angles, rotation=pose.result.rotation, key=("front",), origin="front")
        self.shown = index
        return pose.to_dict()
