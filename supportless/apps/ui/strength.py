"""The browser app's strength overlay: the weak sections of the pose as printed, and its weakest one in a line.

:class:`StrengthOverlay` colours the faces of the sections a grip would snap (cyan) or nearly snap (pale cyan), with
the thresholds and colours of the pictures (:mod:`supportless.report.weakness`), and gives the panel one line on the
weakest section (``weakest as printed: LeftLeg 8 mm up, breaks at 0.9 N (safety 0.45)``). The pose is analysed as
it goes to the slicer, whichever frame the view shows: turned by the print rotation, at the app's print height, in
the settings' material (:func:`~supportless.search.sturdiness.pose_strength`); the rest pose shown for a look back
is the rest pose printed as it stands.

The analysis takes a good part of a second on the small built-in figures and longer on big ones, so it never holds
up the render loop: each pose drawn asks for it (:meth:`StrengthOverlay.show`), and a thread of its own analyses
the latest pose asked for whenever it is free (a burst of edits becomes one analysis, as a burst of slider events
becomes one redraw), then asks the app to draw again. Meanwhile the last analysis stays drawn on the surface as it
is now, its line marked as updating. Only the render loop draws; the thread only analyses.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ...energies.materials import MATERIALS
from ...energies.strength import HANDLING_LOAD_N
from ...report.report import weakest_section
from ...report.weakness import WEAK_COLORS, weakest_caption, weakness_levels
from ...search.sturdiness import pose_strength

__all__ = ["WEAK_RGB", "StrengthOverlay", "StrengthView", "analyse_pose"]

#: The overlay's colour of each weakness level (1 marginal, 2 breaks), RGB 0-255: the pictures' colours.
WEAK_RGB = {level: tuple(int(round(255 * c)) for c in color) for level, color in WEAK_COLORS.items()}
#: Above the risky faces (lifted 1) and the intersecting ones (1.5), in 0.2 % of the model's size.
LIFT = 2.0


@dataclass(frozen=True)
class StrengthView:
    """One pose analysed.

    Attributes
    ----------
    key : tuple
        What was analysed: the rig's id, the angles, the print rotation, the height and the material.
    face_safety : (f,) float64
        The least safety factor of the sections cutting each face (inf: none).
    levels : (f,) int8
        0 sound, 1 marginal, 2 breaks (:func:`~supportless.report.weakness.weakness_levels`).
    safety_factor : float
        The pose's (its weakest section's; inf: nothing pulls on it).
    line : str
        The panel's line (markdown).
    rig : supportless.rig.rig.Rig
        The rig analysed.
    """

    key: tuple
    face_safety: np.ndarray
    levels: np.ndarray
    safety_factor: float
    line: str
    rig: object = field(default=None, repr=False, compare=False)


def _key(rig, angles, rotation, height_mm, material) -> tuple:
    return (id(rig), np.asarray(angles, np.float64).tobytes(), np.asarray(rotation, np.float64).tobytes(),
            float(height_mm), material)


def analyse_pose(rig, angles: np.ndarray, rotation: np.ndarray, height_mm: float, material: str = "PLA"
                 ) -> StrengthView:
    """The overlay of one pose: :func:`~supportless.search.sturdiness.pose_strength`, its levels and its line.

    Parameters
    ----------
    rig : supportless.rig.rig.Rig
        3D.
    angles : (m, 3) float64
    rotation : (3, 3) float64
        The print rotation.
    height_mm : float
        The rest pose's printed height.
    material : str
        A :data:`~supportless.energies.materials.MATERIALS` name.

    Returns
    -------
    StrengthView
    """
    R = np.asarray(rotation, np.float64)
    strength = pose_strength(rig, angles, R, height_mm, MATERIALS[material])
    levels = weakness_levels(strength.face_safety)
    label = "weakest" if np.allclose(R, np.eye(3)) else "weakest as printed"
    caption = weakest_caption(weakest_section(strength, rig.bone_names()), label)
    counts = [int(np.sum(levels == k)) for k in (2, 1)]
    faces = f" · {counts[0]} faces break (cyan), {counts[1]} marginal (pale cyan)" if any(counts) else ""
    line = f"- Strength ({HANDLING_LOAD_N:g} N grip, {material}): {caption}{faces}"
    return StrengthView(_key(rig, angles, R, height_mm, material), strength.face_safety, levels,
                        float(strength.safety_factor), line, rig)


class StrengthOverlay:
    """The strength overlay of the app's pose, analysed in a thread of its own (one pose at a time, the latest).

    Parameters
    ----------
    on_ready : callable
        ``on_ready()`` after each analysis, from the analysing thread: the app draws again (:meth:`show`).

    Attributes
    ----------
    current : StrengthView or None
        The last pose analysed.
    """

    def __init__(self, on_ready: Callable[[], None]):
        self.on_ready = on_ready
        self.current: StrengthView | None = None
        self._lock = threading.Lock()
        self._wanted = None  # (key, args) of the latest pose asked for and not yet analysed
        self._running = None  # the key being analysed
        self._thread: threading.Thread | None = None

    def request(self, rig, angles: np.ndarray, rotation: np.ndarray, height_mm: float, material: str = "PLA"
                ) -> StrengthView | None:
        """The analysis of a pose when it is done; else None, and the pose is analysed next (the thread starts).

        Parameters are those of :func:`analyse_pose`.
        """
        key = _key(rig, angles, rotation, height_mm, material)
        with self._lock:
            if self.current is not None and self.current.rig is rig and self.current.key == key:
                return self.current
            if key == self._running:
                self._wanted = None  # the pose being analysed is the latest again
                return None
            self._wanted = (key, (rig, np.array(angles, np.float64), np.array(rotation, np.float64),
                                  float(height_mm), material))
            if self._thread is None:
                self._thread = threading.Thread(target=self._work, name="supportless-ui-strength", daemon=True)
                self._thread.start()
        return None

    def wait(self, timeout: float = 60.0) -> bool:
        """Wait until no analysis runs or waits (True), or ``timeout`` seconds pass (False)."""
        with self._lock:
            thread = self._thread
        if thread is not None:
            thread.join(timeout)
        return not (thread is not None and thread.is_alive())

    def _work(self) -> None:
        while True:
            with self._lock:
                job, self._wanted = self._wanted, None
                if job is None:
                    self._running = self._thread = None
                    return
                self._running = job[0]
            try:
                view = analyse_pose(*job[1])
            except Exception as exc:  # noqa: BLE001 - said in the panel; the app keeps serving
                rig = job[1][0]
                nothing = np.full(len(rig.faces), np.inf)
                view = StrengthView(job[0], nothing, np.zeros(len(nothing), np.int8), float("inf"),
                                    f"- Strength: cannot analyse this pose ({type(exc).__name__}: {exc})", rig)
            with self._lock:
                self.current = view
            self.on_ready()

    def show(self, scene, state, angles: np.ndarray, rotation: np.ndarray, shown: np.ndarray, enabled: bool) -> str:
        """Draw the overlay of the pose shown (asking for its analysis), or hide it; the panel's line.

        Parameters
        ----------
        scene : supportless.apps.ui.scene.Scene
        state : supportless.apps.ui.state.EditorState
            Its rig, print height and material.
        angles : (m, 3) float64
            The pose shown.
        rotation : (3, 3) float64
            Its print rotation.
        shown : (n, 3) float64
            The surface as drawn (standing or as printed), model units.
        enabled : bool
            The overlay's toggle: False hides it (and analyses nothing).

        Returns
        -------
        line : str
            Markdown for the measures list, starting with a newline; empty when hidden.
        """
        rig = state.rig
        view = None
        if enabled and rig.dim == 3:
            view = self.request(rig, angles, rotation, state.print_frame.height_mm, state.settings.material)
            stale = view is None
            view = view or (self.current if self.current is not None and self.current.rig is rig else None)
        with scene.server.atomic():
            for level, color in WEAK_RGB.items():
                scene.draw_faces(f"weak{level}", shown, None if view is None else view.levels == level, color, LIFT)
        if not enabled or rig.dim != 3:
            return ""
        if view is None:
            return "\n- Strength: analysing the pose as printed ..."
        return "\n" + view.line + (" (updating ...)" if stale else "")
