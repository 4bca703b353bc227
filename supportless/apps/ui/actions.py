"""What the page's controls do: edits of the pose, undo and redo, pose and mesh files, settings, the view, locks.

:class:`PageActions` is the part of :class:`~supportless.apps.ui.app.App` that
the panel (:class:`~supportless.apps.ui.panel.Panel`) and the 3D view
(:class:`~supportless.apps.ui.scene.Scene`: a joint clicked, the gizmo dragged)
call. Each action goes to the :class:`~supportless.apps.ui.state.EditorState`;
a bad input or a failing file is a message in the page, never an exception.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ...base.errors import SupportlessError
from ...search.settings import bone_index
from .posefiles import FRAMES

__all__ = ["PageActions"]


class PageActions:
    """The actions of the panel's buttons and fields, the sliders, a joint clicked and the gizmo.

    A mixin of :class:`~supportless.apps.ui.app.App`, which sets what they act
    on: ``rig``, ``state``, ``panel``, ``scene``, ``server``, ``view`` and
    ``_dragging``, and says and draws through ``_set_status``, ``_error`` and
    ``_request_render``.
    """

    def undo(self) -> bool:
        """Go back one edit; False (and a message) when there is nothing to undo."""
        if not self.state.undo():
            self._set_status("nothing to undo")
            return False
        return True

    def redo(self) -> bool:
        """Redo the last undone edit; False (and a message) when there is none."""
        if not self.state.redo():
            self._set_status("nothing to redo")
            return False
        return True

    def reset(self) -> None:
        """Back to the rest pose, printed as it stands (undoable)."""
        self.state.reset()
        self._set_status("reset to the rest pose")

    def print_upright(self) -> None:
        """Drop the print rotation: print the pose as it stands (undoable)."""
        self.state.set_rotation(np.eye(self.rig.dim))
        self._set_status("printing the pose as it stands")

    def _attempt(self, failure: str, action: Callable, *args, done: Callable[[object], str]) -> bool:
        """Run a state action; its error becomes a message in the page, never an exception."""
        try:
            value = action(*args)
        except (OSError, SupportlessError, ValueError) as exc:
            self._error(f"{failure}: {exc}")
            return False
        self._set_status(done(value))
        return True

    def save_pose(self, path) -> bool:
        """Write the current pose as JSON; False (and a message in the page) on failure."""
        return self._attempt("cannot save the pose", self.state.save_pose, path, done=lambda p: f"saved pose to {p}")

    def load_pose(self, path) -> bool:
        """Read a pose JSON written for this skeleton; False (and a message) on a bad file.

        The server keeps running on any bad file (missing, not JSON, another skeleton).
        """
        return self._attempt("cannot load the pose", self.state.load_pose, path,
                             done=lambda p: f"loaded pose from {p}")

    def load_pose_bytes(self, name: str, content: bytes) -> bool:
        """Load an uploaded pose file (same checks as :meth:`load_pose`)."""
        return self._attempt("cannot load the pose", self.state.load_pose_bytes, name, content,
                             done=lambda _: f"loaded uploaded pose {name}")

    def export_mesh(self, path) -> bool:
        """Write the posed mesh (on the plate) as STL/3MF/OBJ/PLY by extension; False on failure."""
        return self._attempt("cannot export the mesh", self.state.export_mesh, path,
                             done=lambda p: f"exported the posed mesh to {p}")

    def download(self, filename: str, make: Callable[[], bytes], client=None) -> None:
        """Send ``make()`` as a file download to ``client`` (the browser that asked), or to every one when None."""
        try:
            data = make()
        except Exception as exc:  # noqa: BLE001 - reported in the page
            self._error(f"cannot prepare {filename}: {exc}")
            return
        clients = [client] if client is not None else list(self.server.get_clients().values())
        if not clients:
            self._error("no browser connected to send the download to")
            return
        for c in clients:
            c.send_file_download(filename, data, save_immediately=True)
        self._set_status(f"sent {filename} ({len(data) // 1024} KiB)")

    def change_setting(self, name: str, value) -> bool:
        """A search setting edited in the panel: the state takes it, or the panel says why not.

        Parameters
        ----------
        name : str
            A :class:`SearchSettings` field (``w_arap``, ``fix``...).
        value
            Its new value (a bone list as text).
        """
        self.panel.invalid.pop(name, None)
        try:
            self.state.update_settings(**{name: value})
        except (TypeError, ValueError) as exc:
            self.panel.invalid[name] = f"{name}: {exc}"
            self.panel.show_settings(self.state.settings, self.state.fixed)
            return False
        return True

    def start_optimize(self, **overrides) -> bool:
        """Run the search (:meth:`EditorState.start_optimize`) with the settings in force.

        Keyword arguments override settings for this search only. Returns
        False (with a message in the page) when a search is already running,
        the settings are invalid or the panel holds a setting the state refused.
        """
        if self.state.optimizing:
            self._set_status("a search is already running")
            return False
        try:
            if self.panel.invalid:
                raise ValueError(next(iter(self.panel.invalid.values())))
            return self.state.start_optimize(**overrides)
        except ValueError as exc:
            self._error(f"cannot start the search: {exc}")
            return False

    def set_view(self, show_risky: bool | None = None, weights: bool | None = None,
                 opacity: float | None = None, frame: str | None = None, show_support: bool | None = None,
                 before: bool | None = None, show_strength: bool | None = None) -> None:
        """View options: risky-face overlay, colouring by bone weights, mesh opacity, frame, support preview.

        Parameters
        ----------
        frame : {"standing", "print"}, optional
            Show the model standing or as printed (turned by the print rotation onto the plate).
        show_support : bool, optional
            Draw the predicted support columns (:func:`supportless.energies.support.support_columns`).
        before : bool, optional
            Show the rest pose, standing, instead of the current pose (the pose is kept).
        show_strength : bool, optional
            Colour the weak sections of the pose as printed and name the weakest (:mod:`.strength`).

        Raises
        ------
        ValueError
            For an unknown frame.
        """
        if frame is not None:
            if frame not in FRAMES:
                raise ValueError(f"frame must be one of {FRAMES}, not {frame!r}")
            self.panel.show_view(frame)
        for key, value in (("show_risky", show_risky), ("weights", weights), ("frame", frame),
                           ("show_support", show_support), ("before", before), ("show_strength", show_strength)):
            if value is not None:
                self.view[key] = value
        if opacity is not None:
            self.scene.set_opacity(opacity)
        self._request_render()

    def locked(self) -> np.ndarray:
        """The bones the user locked: those named in the settings' ``fix``, (m,) bool."""
        rig, out = self.rig, np.zeros(self.rig.bone_count, bool)
        for name in self.state.settings.fix:
            if str(name).lower() == "all":
                out[:] = True
            else:
                out[bone_index(name, rig.bone_count, rig.labels)] = True
        return out

    def lock_bone(self, bone: int, locked: bool = True) -> bool:
        """Lock bone ``bone`` (0-based): Optimize and the front keep it as it is; or unlock it.

        A lock is a bone number in the search's ``fix`` setting (saved with the pose).
        """
        names = self.rig.bone_names()
        number = str(bone + 1)
        fix = [f for f in self.state.settings.fix if f not in (number, names[bone])]
        if locked:
            fix.append(number)
        if not self.change_setting("fix", ",".join(fix)):
            return False
        word = "locked: Optimize keeps it as it is" if locked else "unlocked"
        if not locked and self.state.fixed[bone]:
            word += " (it rests on the plate, so the search still keeps it; free it with Free bones)"
        self._set_status(f"bone {number} ({names[bone]}) {word}")
        self._request_render()
        return True

    def on_slider(self, axis: int, degrees: float) -> None:
        """An X/Y/Z slider of the selected bone moved in the page."""
        b = self.state.selected
        angles = self.state.get_angles()
        angles[b, axis] = np.radians(degrees)
        self.state.set_angles(angles, key=("slider", b, axis), origin="slider")

    def _on_joint_click(self, joint: int) -> None:
        bones = self.rig.bones
        candidates = np.concatenate([np.flatnonzero(bones[:, 0] == joint), np.flatnonzero(bones[:, 1] == joint)])
        if len(candidates):
            bone = int(candidates[0])
            self.state.select_bone(bone)
            self._set_status(f"selected {self.rig.bone_names()[bone]} (joint {joint + 1})")

    def _on_gizmo(self, phase: str, rotation: np.ndarray) -> None:
        if phase == "start":
            self._dragging = True
            self.state.checkpoint()
        elif phase == "end":
            self._dragging = False
            self._request_render()
        else:
            self.state.set_bone_rotation(self.state.selected, rotation)
