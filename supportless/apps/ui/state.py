"""The viewer's editing state, without a browser or a server.

:class:`EditorState` holds what the page edits and shows: the current pose and print rotation, the
selected bone, undo/redo, the search settings (one :class:`~supportless.search.settings.SearchSettings`), the
objective they define, the measures of a pose, pose and mesh files, and the pose search running in the
background. The web app (:mod:`supportless.apps.ui.app`) draws it and forwards the page's events to it.

Each concern is a part of its own, :class:`EditorState` their union: editing the pose with undo and redo
(:class:`~supportless.apps.ui.editing.PoseEditing`), its files (:class:`~supportless.apps.ui.posefiles.PoseFiles`:
pose files, exported meshes, the frames), the search in the background
(:class:`~supportless.apps.ui.searchrun.BackgroundSearch`); this module keeps the listeners, the settings and
the measures of a pose.

Actions raise on bad input (:class:`~supportless.base.errors.SupportlessError`, ``OSError``, ``ValueError``) and
leave the state as it was; the app turns the exception into a message in the page.

Two frames (see :mod:`supportless.search.orientation`): the pose *standing* as the input stood (the display frame,
where the bones are edited) and the pose *as printed*, turned by the print rotation R the search chose and
put on the plate (:func:`supportless.base.geometry.print_pose`). The support figures are counted as printed;
contact, balance and distortion are judged standing.

Every change is announced to the listeners of :meth:`EditorState.subscribe` as ``listener(event, **info)``:

``"pose"``
    The angles or the print rotation changed (``origin``: who changed them, e.g. ``"slider"``,
    ``"gizmo"``, ``"search"``, or None).
``"selection"``, ``"settings"``
    Another bone is selected; the search settings, and with them the objective and fixed bones, changed.
``"search_started"``
    A search starts (see ``search_settings`` and ``progress``).
``"progress"``
    The running search finished an iteration, or PrusaSlicer is choosing among its answers
    (``progress["phase"]``, :func:`supportless.slicing.ranking.slice_choice_if_found`).
``"search_done"``
    The search ended (``result``: its :class:`~supportless.search.optimizer.PoseResult`, or ``error``: what it raised).
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Callable

import numpy as np

from ...copyleft.cgal import intersecting_faces_since
from ...energies.overhang import risky_faces
from ...files.printframe import PrintFrame, rig_print_frame
from ...report.report import pose_measures, reduction
from ...search.objective import Objective
from ...search.optimizer import PoseResult
from ...search.orientation import print_direction, rotation_axis_angle
from ...search.settings import SearchSettings
from .editing import PoseEditing, _check_rotation
from .history import PoseHistory
from .posefiles import FRAMES, PoseFiles
from .searchrun import BackgroundSearch

__all__ = ["EditorState", "FRAMES", "REDUCED_MEASURES"]

#: Measures compared with the rest pose (``measures["reduction"]``, percent).
REDUCED_MEASURES = ("support_prism", "support_column", "risky_area")


class EditorState(PoseEditing, PoseFiles, BackgroundSearch):
    """The pose being edited, its print rotation, its measures and its search, for one rig.

    The print rotation R (the identity at the start and after
    :meth:`reset`) is what the last search chose, or what a loaded pose file
    held; editing bones keeps it.

    Parameters
    ----------
    rig : supportless.rig.rig.Rig
    settings : SearchSettings, optional
        The search settings to start with (default: ``SearchSettings()``).
    workdir : str or os.PathLike, optional
        Folder of relative pose and mesh paths (default: the current folder).

    Attributes
    ----------
    rig : supportless.rig.rig.Rig
    workdir : pathlib.Path
    history : PoseHistory
        Undo and redo steps, each ``(angles, rotation)``.
    settings : SearchSettings
        What the Optimize button searches with.
    objective : Objective
        ``settings.objective(rig)``: what the search minimises and the
        measures report.
    fixed : (m,) bool
        Bones the search keeps (``settings.fixed_bones(rig)``).
    rest_measures : dict
        :meth:`measure` of the rest pose standing (without the exact test).
    progress : dict
        Of the last search: ``iteration``, ``iterations``, ``value`` (best
        objective), ``running``, ``cancelled``, ``free_bones``.
    search_settings : SearchSettings or None
        What the last search was started with.
    last_result : PoseResult or None
        The last finished search.
    """

    def __init__(self, rig, settings: SearchSettings | None = None, workdir=None, frame: PrintFrame | None = None):
        self.rig = rig
        #: how exported meshes are printed (+Z up, mm, on the plate; default: the rest pose 60 mm tall)
        self.print_frame = rig_print_frame(rig) if frame is None else frame
        self.workdir = Path(workdir) if workdir is not None else Path.cwd()
        self.history = PoseHistory()
        self._lock = threading.RLock()
        self._settings_lock = threading.Lock()
        self._angles = rig.rest_angles()
        self._rotation = np.eye(rig.dim)
        self._selected = 0
        self._listeners: list[Callable] = []
        self.settings = settings if settings is not None else SearchSettings()
        self.fixed = self.settings.fixed_bones(rig)
        self.objective = self.settings.objective(rig)
        self.rest_measures = self._measure(self.objective, self.settings, rig.rest_angles(), exact=False)
        self.progress: dict = {}
        self.last_result: PoseResult | None = None
        self.search_settings: SearchSettings | None = None
        self._search: threading.Thread | None = None
        self._cancel = threading.Event()

    # ------------------------------------------------------------ listeners
    def subscribe(self, listener: Callable[..., None]) -> None:
        """Call ``listener(event, **info)`` after every change (see the module docstring)."""
        self._listeners.append(listener)

    def _notify(self, event: str, **info) -> None:
        for listener in list(self._listeners):
            listener(event, **info)

    # ---------------------------------------------------- settings, measures
    def _objective_for(self, settings: SearchSettings) -> Objective:
        """``settings.objective(rig)``, sharing the ARAP operators; the current one when it is the same."""
        current = self.objective
        shared = current.arap_data if settings.clusters == current.clusters else None
        candidate = settings.objective(self.rig, arap_data=shared)
        same = candidate.settings() == current.settings() and candidate.backend == current.backend
        return current if same else candidate

    def update_settings(self, **changes) -> SearchSettings:
        """Change search settings; the objective and the measures follow.

        Parameters
        ----------
        **changes
            Fields of :class:`SearchSettings` (``w_arap=3.0``,
            ``overhang_angle=50``, ``fix="1,2"``...); None values are ignored.

        Returns
        -------
        settings : SearchSettings
            The new settings.

        Raises
        ------
        ValueError
            For an invalid value, e.g. a bone list naming a bone the rig does
            not have; the settings stay as they were.
        """
        with self._settings_lock:  # one change at a time; the pose stays readable meanwhile
            new = self.settings.replace(**changes)
            fixed = new.fixed_bones(self.rig)
            objective = self._objective_for(new)
            rest = self.rest_measures
            if objective is not self.objective or new.overhang_angle != self.settings.overhang_angle:
                rest = self._measure(objective, new, self.rig.rest_angles(), exact=False)
            with self._lock:
                self.settings, self.fixed, self.objective, self.rest_measures = new, fixed, objective, rest
        self._notify("settings")
        return new

    def measure(self, angles: np.ndarray | None = None, *, rotation: np.ndarray | None = None,
                exact: bool = True, vertices: np.ndarray | None = None) -> dict:
        """Everything the panel shows about a pose and its print rotation, for the current settings.

        Parameters
        ----------
        angles : (m, 3) float64, optional
            Radians (default: the current pose).
        rotation : (d, d) float64, optional
            The print rotation R (default: the current one).
        exact : bool
            Also find the intersecting triangles (CGAL, 3D only).
        vertices : (n, d) float64, optional
            ``rig.pose(angles)`` (standing) when the caller has it.

        Returns
        -------
        measures : dict
            :func:`supportless.report.report.pose_measures` of :attr:`objective` at
            the printer's threshold ``settings.overhang_angle`` with
            ``rotation=R``: the objective and the support figures as
            printed, ``upright`` the support figures standing. Plus
            ``risky`` ((f,) bool in 3D, one per boundary edge in 2D: needs
            support as printed), ``risky_standing`` (the same, standing),
            ``intersecting_faces`` ((k,) int64 faces in an intersecting
            pair, or None when not checked), ``reduction`` (percent less
            than the rest pose standing of each of :data:`REDUCED_MEASURES`,
            None where the rest pose needs none), ``rotation`` ((d, d) R),
            ``turn_deg`` (its angle, degrees), ``turn_axis`` ((3,) unit
            axis, None in 2D) and ``print_direction`` ((d,) the model's
            standing direction printed upward, ``R.T @ up``).
        """
        with self._lock:
            objective, settings, rest = self.objective, self.settings, self.rest_measures
            current_angles, current_R = self._angles.copy(), self._rotation.copy()
        angles = current_angles if angles is None else angles
        R = current_R if rotation is None else _check_rotation(rotation, self.rig.dim)
        return self._measure(objective, settings, angles, R, exact=exact, vertices=vertices, rest=rest)

    def _measure(self, objective: Objective, settings: SearchSettings, angles: np.ndarray,
                 rotation: np.ndarray | None = None, *, exact: bool, vertices: np.ndarray | None = None,
                 rest: dict | None = None) -> dict:
        rig = self.rig
        V = rig.pose(angles) if vertices is None else vertices
        R = np.eye(rig.dim) if rotation is None else np.asarray(rotation, np.float64)
        turned = not np.array_equal(R, np.eye(rig.dim))  # the identity: measure once, standing = printed
        angle = settings.overhang_angle
        out = pose_measures(objective, angles, exact=False, overhang_angle=angle, vertices=V,
                            rotation=R if turned else None)
        standing = np.asarray(risky_faces(V, rig.faces, rig.up, angle), bool)
        out["risky_standing"] = standing
        out["risky"] = np.asarray(risky_faces(V @ R.T, rig.faces, rig.up, angle), bool) if turned else standing
        if not turned:
            out["upright"] = {k: out[k] for k in REDUCED_MEASURES}
        axis, degrees = rotation_axis_angle(R)
        out |= {"rotation": R.copy(), "turn_deg": degrees, "turn_axis": axis,
                "print_direction": print_direction(R, rig.up)}
        out["intersecting_faces"] = None
        if exact and rig.dim == 3:
            out |= self.exact_measures(V)
        if rest is not None:
            out["reduction"] = {k: reduction(rest[k], out[k]) for k in REDUCED_MEASURES}
        return out

    def exact_measures(self, V: np.ndarray) -> dict:
        """The exact crossings of the posed surface ``V`` (n, 3) float64 (CGAL, :meth:`_exact_pairs`):
        ``intersecting_face_pairs`` (int) and ``intersecting_faces`` ((k,) int64 faces in a pair), as
        :meth:`measure` gives them with ``exact``."""
        pairs = self._exact_pairs(V)
        return {"intersecting_face_pairs": len(pairs), "intersecting_faces": np.unique(pairs)}

    def _exact_pairs(self, V: np.ndarray) -> np.ndarray:
        """The intersecting triangle pairs of the surface ``V`` (CGAL), asked only about what moved since the
        last pose checked (:func:`~supportless.copyleft.cgal.intersecting_faces_since`): an edit redraws
        without checking the whole body again."""
        last = getattr(self, "_last_exact", None) or (None, None)  # replaced whole: safe across threads
        pairs = intersecting_faces_since(V, self.rig.faces, *last)
        self._last_exact = (np.array(V, np.float64), pairs)
        return pairs
