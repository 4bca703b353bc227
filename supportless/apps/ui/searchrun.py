"""The page's Optimize: the pose search run in the background, streaming its best pose into the state.

:class:`BackgroundSearch` is the part of :class:`~supportless.apps.ui.state.EditorState`
that runs :func:`supportless.search.answer.optimize` in a thread from the
current pose, lets the slicer choose among its answers as the command line does
(:func:`supportless.slicing.ranking.slice_choice_if_found`), and announces
``"search_started"``, ``"progress"``, ``"pose"`` and ``"search_done"``.
"""

from __future__ import annotations

import logging
import threading

import numpy as np

from ...search.objective import Objective
from ...search.answer import optimize
from ...search.settings import SearchSettings
from ...slicing.prusaslicer import find_prusa_slicer
from ...slicing.ranking import slice_choice_if_found

__all__ = ["BackgroundSearch"]

logger = logging.getLogger("supportless.apps.ui")


class BackgroundSearch:
    """The pose search in a background thread, cancellable, one at a time.

    A mixin of :class:`~supportless.apps.ui.state.EditorState`, which sets what
    it works on: ``rig``, ``settings``, ``history``, ``print_frame``,
    ``progress``, ``search_settings``, ``last_result``, ``_search`` (the
    thread), ``_cancel`` (a :class:`threading.Event`), ``_lock``, ``_angles``,
    ``_rotation``, ``_objective_for`` and ``_notify``.
    """

    @property
    def optimizing(self) -> bool:
        """True while a search runs."""
        t = self._search
        return t is not None and t.is_alive()

    def start_optimize(self, **overrides) -> bool:
        """Run :func:`supportless.search.answer.optimize` from the current pose in a background thread.

        The search streams its best pose and print rotation into the state
        (``"pose"`` events with ``origin="search"``) and ends with the best it
        found (``result.angles`` and ``result.rotation``; with
        ``orient="keep"`` the rotation is the identity), which one undo takes
        back to the pose and rotation it started from. With ``orient="free"``
        (the default) the search turns the model too, starting from the
        model as it stands.

        Parameters
        ----------
        **overrides
            Settings for this search only (``particles=20``, ``fix="1"``...);
            by default :attr:`settings`, whose objective the panel shows.

        Returns
        -------
        started : bool
            False when a search is already running.

        Raises
        ------
        ValueError
            For invalid settings, or when every bone is fixed and the search
            may not turn the model (``orient="keep"``).
        """
        if self.optimizing:
            return False
        settings = self.settings.replace(**overrides)
        why = settings.all_fixed(self.rig)
        if why and settings.orient == "keep":
            raise ValueError(f"{why}: free some bones (e.g. Free bones: all), "
                             "or let the search turn the model (Orientation: free)")
        objective = self._objective_for(settings)
        self._cancel.clear()
        with self._lock:
            self.history.record((self._angles, self._rotation))
            start = self._angles.copy()
            start_rotation = self._rotation.copy()
            self.progress = {"iteration": 0, "iterations": settings.iterations, "value": None, "running": True,
                             "cancelled": False, "free_bones": int((~settings.fixed_bones(self.rig)).sum())}
        self.search_settings = settings
        self._search = threading.Thread(target=self._run_search, args=(settings, objective, start, start_rotation),
                                        name="supportless-ui-search", daemon=True)
        self._notify("search_started")
        self._search.start()
        return True

    def _run_search(self, settings: SearchSettings, objective: Objective, start: np.ndarray,
                    start_rotation: np.ndarray) -> None:
        def callback(iteration, info):
            with self._lock:
                self._angles = np.array(info["angles"], np.float64)
                self._rotation = np.array(info["rotation"], np.float64)
                self.progress.update(iteration=iteration, iterations=int(info["iterations"]),
                                     value=float(info["value"]))
            self._notify("pose", origin="search")
            self._notify("progress")
            return False if self._cancel.is_set() else None

        try:
            result = optimize(self.rig, settings, objective=objective, start=start, start_rotation=start_rotation,
                              callback=callback)
            if result.choice is not None and not self._cancel.is_set() and find_prusa_slicer():  # as optimize does
                with self._lock:
                    self.progress["phase"] = "slicing the best answers"
                self._notify("progress")
                result = slice_choice_if_found(self.rig, result, self.print_frame.height_mm, on_failure=lambda why: (
                    logger.warning("slicing the answers failed, the slicer model's choice is kept: %s", why)))
        except Exception as exc:  # noqa: BLE001 - reported to the listeners, the app keeps running
            logger.exception("pose search failed")
            with self._lock:
                self.progress["running"] = False
            self._notify("search_done", error=exc)
            return
        with self._lock:
            self._angles = np.array(result.angles, np.float64)
            self._rotation = np.array(result.rotation, np.float64)
            self.last_result = result
            self.progress.update(running=False, cancelled=bool(result.interrupted), value=result.value)
            self.progress.pop("phase", None)
        self._notify("pose", origin="search")
        self._notify("search_done", result=result)

    def cancel_optimize(self) -> None:
        """Ask the running search to stop after its current iteration (it keeps its best pose)."""
        self._cancel.set()

    def wait_optimize(self, timeout: float | None = None) -> bool:
        """Wait for the search thread; True when no search is running."""
        t = self._search
        if t is not None:
            t.join(timeout)
        return not self.optimizing
