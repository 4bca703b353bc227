"""A local web app (viser) to pose a rig by hand and run the pose search.

:func:`run_app` serves the page. :class:`App` wires four parts:

* :class:`~supportless.apps.ui.state.EditorState`: the pose, undo/redo, files,
  search settings, measures and the background search (no browser needed);
* :class:`~supportless.apps.ui.scene.Scene`: the 3D view;
* :class:`~supportless.apps.ui.panel.Panel`: the side panel;
* :mod:`supportless.apps.ui.ports`: which port the server takes.

How it stays responsive: the view is a skinned mesh, so an edit streams only the bone frames; edits only change
the state and wake one render thread, which always draws the latest pose (a burst of slider events becomes one
redraw), then measures it with the full weights and redraws the overlays. The search runs in its own thread and
streams its best pose and print rotation into the view; the strength overlay is analysed in its own too.

The view shows the model standing (where the bones are edited) or as printed: turned by the state's print rotation
onto the plate (:meth:`EditorState.frame_transform`), skeleton and risky faces in that frame.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from typing import Callable

import numpy as np

from ...base.errors import SupportlessError
from ...energies.support import support_columns
from ...search.orientation import rotation_axis_angle
from ...search.settings import SearchSettings, bone_index
from .filament import slice_meshes, support_lead
from .front import FrontBrowser
from .guard import Guard, is_loopback, limit_uploads
from .opener import MAX_UPLOAD_BYTES, OpenOptions, Uploads, prepare_model
from .panel import Panel, measures_markdown
from .ports import page_url, start_server
from .readout import broken_rules
from .scene import Scene, draw_welcome
from .slicerun import SliceRun, slice_markdown
from .state import FRAMES, EditorState
from .strength import StrengthOverlay

#: Ray cells along the footprint's longer side of the support preview (coarser than the measure's, to draw fast).
PREVIEW_RESOLUTION = 64
WELCOME = "Drop a model here: .glb/.gltf, or a mesh with its .tgf (or use Open model… in the panel)"

__all__ = ["App", "run_app"]

logger = logging.getLogger("supportless.apps.ui")


class App:
    """The viewer and editor of one rig, served by viser on ``host:port``.

    Parameters
    ----------
    rig : supportless.rig.rig.Rig or None
        None: an empty page that opens the models sent to it (:meth:`receive_upload`).
    host : str
        Interface to listen on (default: only this computer).
    port : int or None
        ``None``: 8080 or the next free port. A given port must be free, else
        :class:`~supportless.base.errors.InputError` ("port N on HOST is taken; use --port N").
    verbose : bool
        Let viser print its banner.
    workdir : str or os.PathLike, optional
        Folder of relative pose/mesh paths typed in the page (default: current folder).
    settings : SearchSettings, optional
        Search settings the panel starts with (default: the tool's defaults).
    frame : supportless.files.printframe.PrintFrame, optional
        How ``rig`` is printed; the view is drawn in its millimetres.
    open_options : OpenOptions, optional
        How models sent from the page are read (the ``view`` command's options).

    Attributes
    ----------
    state : EditorState
        The pose, its history, settings, measures and search.
    url : str
    port : int
    measures : dict
        :meth:`EditorState.measure` of the last drawn pose, and the ``support_lead`` (:func:`.filament.support_lead`).
    shown_vertices : (n, d) float64 or None
        The exactly posed surface last drawn: standing, or as printed (``print_pose(rig.pose(angles), R, up)``).
    view : dict
        ``frame`` (``"standing"`` or ``"print"``), ``show_risky``, ``weights``, ``show_support`` (the predicted
        support columns), ``before`` (the rest pose shown instead of the pose) and ``show_strength`` (the weak
        sections: ``self.strength``, a :class:`~supportless.apps.ui.strength.StrengthOverlay`, draws them).
    slice_report : dict or None
        The last Slice's figures (:func:`~supportless.apps.ui.slicerun.slice_markdown` shows them).
    uploads : Uploads
        Files sent from the page (a private folder, removed by :meth:`stop`).
    latency_ms : dict
        ``mesh`` (input to bone frames sent), ``full`` (to energies and overlays drawn) and ``median_mesh`` of the
        last 50 edits, ms.
    status : str
        The last status or error message shown in the page.
    """

    def __init__(self, rig=None, host: str = "127.0.0.1", port: int | None = None, *, verbose: bool = True,
                 workdir=None, settings: SearchSettings | None = None, frame=None,
                 open_options: OpenOptions | None = None):
        self.workdir, self.base_settings = workdir, settings
        self.open_options = open_options or OpenOptions()
        self.rig = self.state = self.scene = self.front = self.panel = None
        self.status = "ready"
        self.measures: dict = {}
        self.shown_vertices: np.ndarray | None = None
        self.latency_ms: dict = {}
        self._latencies: list[float] = []
        self._cond = threading.Condition()
        self._swap = threading.RLock()  # held while a model is drawn or replaced
        self._requested = self._rendered = 0
        self._input_time = time.perf_counter()
        self._stopping = False
        self._dragging = False
        self._opening: threading.Thread | None = None
        self._opened = 0  # models opened in this page
        self.uploads = Uploads()
        self.slicing, self.strength = SliceRun(self._slice_done), StrengthOverlay(self._request_render)
        self.slice_report: dict | None = None

        #: checks the token, Host and Origin of every request (:mod:`supportless.apps.ui.guard`)
        self.guard = Guard(host)
        self.server = start_server(host, port, "supportless", verbose, self.guard)
        limit_uploads(self.server, MAX_UPLOAD_BYTES, lambda name, size: self._error(
            f"{name}: {size / 2**20:.0f} MB is more than the {MAX_UPLOAD_BYTES // 2**20} MB a page may send; "
            "open it with `supportless view FILE`"))
        self.port = int(self.server.get_port())
        self.url = page_url(host, self.port, self.guard.token)
        self._worker = threading.Thread(target=self._render_loop, name="supportless-ui-render", daemon=True)
        self._worker.start()
        if rig is None:
            self.panel = Panel(self.server.gui, self)
            draw_welcome(self.server, WELCOME)
        else:
            self.open_rig(rig, frame)

    def open_rig(self, rig, frame=None) -> None:
        """Show ``rig`` instead of the model on screen (its search and slicing stopped), printed by ``frame``.

        Parameters
        ----------
        rig : supportless.rig.rig.Rig
        frame : supportless.files.printframe.PrintFrame, optional
            How it is printed (default: the rest pose 60 mm tall); the view is drawn in its millimetres.
        """
        with self._swap:
            if self.state is not None:
                self.state.cancel_optimize()
                self.front.cancel()
                self.slicing.cancel()
                self.state.wait_optimize(30)
                self.front.wait(30)
            if self.scene is None:
                self.server.scene.reset()  # the welcome
            else:
                self.scene.close()
            if self.panel is not None:
                self.panel.close()
            self._opened += 1
            state = EditorState(rig, self.base_settings, self.workdir, frame)
            self.rig, self.state, self.slice_report = rig, state, None
            self.view = {"frame": "standing", "show_risky": True, "weights": False, "show_support": True,
                         "before": False, "show_strength": False}
            self.scene = Scene(self.server, rig, self._on_joint_click, self._on_gizmo,
                               scale=state.print_frame.scale, mesh_key=self._opened)
            self.front = FrontBrowser(state)
            self.panel = Panel(self.server.gui, self, previous=self.panel)
            state.subscribe(lambda event, **info: self._on_state(event, **info) if state is self.state else None)
            self._on_state("settings")
            self._on_state("selection")

    # ============================================================ opening
    def receive_upload(self, name: str, content: bytes) -> bool:
        """A file sent from the page: a skeleton is kept for its mesh; a model is prepared, then shown.

        Returns
        -------
        accepted : bool
            False (with one line in the page) for a bad file, or while another model is being prepared.
        """
        if self._opening is not None and self._opening.is_alive():
            self._error(f"{name}: another model is being prepared; send it again when it is open")
            return False
        try:
            model = self.uploads.receive(name, content)
        except SupportlessError as exc:
            self._error(str(exc))
            return False
        if model is None:
            self._set_status(f"skeleton {name} received; now send its mesh")
            return True
        skeleton = self.uploads.skeleton_for(model)
        self._opening = threading.Thread(target=self._prepare, args=(model, skeleton), name="supportless-ui-open",
                                         daemon=True)
        self._opening.start()
        return True

    def _prepare(self, model, skeleton) -> None:
        with_what = f" with {skeleton.name}" if skeleton is not None else ""
        self._set_status(f"opening {model.name}{with_what} ...")
        try:
            rig, frame = prepare_model(model, skeleton, self.open_options,
                                       progress=lambda step: self._set_status(f"opening {model.name}: {step} ..."))
            self.open_rig(rig, frame)
        except (SupportlessError, OSError, ValueError) as exc:  # said with the file's own name, not where it was kept
            self._error(f"cannot open {model.name}: {str(exc).replace(str(model) + ': ', '')}")
            return
        except Exception as exc:  # noqa: BLE001 - the app keeps serving whatever the file does
            logger.exception("opening %s failed", model.name)
            self._error(f"cannot open {model.name}: {type(exc).__name__}: {exc}")
            return
        notes = [w for w in rig.info.get("warnings", []) if "skeleton" in w and "built" in w]
        self._set_status(f"opened {rig.name}: {rig.bone_count} bones, {len(rig.faces)} triangles; "
                         f"{frame.note()}" + (f"; {notes[0]}" if notes else ""))

    # ============================================================ actions
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

    # ============================================================= slicing
    def start_slice(self, slicer: tuple[str, str] = ("prusa", "grid")) -> bool:
        """Slice the rest pose and the current pose (as printed) with a real slicer, in the background.

        Parameters
        ----------
        slicer : tuple of str
            ``(engine, support)``: ``("prusa", "grid")``, ``("cura", "grid")`` or ``("cura", "tree")``.

        Returns
        -------
        started : bool
            False (and one line in the page) when the slicer is missing or a slice already runs.
        """
        from ...slicing.choice import SlicerChoice
        from ..cli_common import _slicer_missing

        try:
            choice = SlicerChoice(*slicer)
        except SupportlessError as exc:
            self._error(f"cannot slice: {exc}")
            return False
        missing = _slicer_missing(choice)
        if missing:
            self._error(f"cannot slice: {missing}")
            return False
        if not self.slicing.start(choice=choice, **slice_meshes(self.state)):
            self._set_status("a slice is already running")
            return False
        self.panel.show_slicing(True, f"slicing with {choice.label}: the rest pose and this pose, with and without "
                                      "support (four runs) ...")
        self._set_status(f"slicing with {choice.label} ...")
        return True

    def cancel_slice(self) -> None:
        """Stop the running slice (its slicer processes too)."""
        if self.slicing.cancel():
            self.panel.show_slicing(False, "slicing cancelled")
            self._set_status("slicing cancelled")

    def _slice_done(self, report: dict | None, error: str | None) -> None:
        if error is not None:
            self.panel.show_slicing(False, f"⚠ slicing failed: {error}")
            self._error(f"slicing failed: {error}")
            return
        self.slice_report = report
        self._request_render()  # the panel leads with the slicer's figure while the pose is the one sliced
        self.panel.show_slicing(False, slice_markdown(report))
        self._set_status("sliced: the slicer's figures are in the Slice folder")

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

    # ============================================================ state -> page
    def start_front(self, count: int = 5) -> bool:
        """Find the front of least support against least distortion in the background (the Front folder)."""
        try:
            started = self.front.start(count)
        except (SupportlessError, ValueError) as exc:
            self._error(f"cannot find the front: {exc}")
            return False
        if started:
            self.panel.find_front.disabled = True
            self._set_status(f"finding a front of up to {count} poses (about three searches) ...")
        return started

    def show_front_pose(self, index: int) -> None:
        """Show pose ``index`` (0-based) of the front."""
        try:
            m = self.front.show(index)
        except ValueError as exc:
            self._error(str(exc))
            return
        self._set_status(f"front pose {index + 1}: support {m['support']:.4g}, distortion {m['distortion']:.3g}")

    def _on_state(self, event: str, origin: str | None = None, result=None, error=None, front=None) -> None:
        state = self.state
        if event == "front_done":
            if error is not None:
                self.panel.find_front.disabled = False
                self._error(f"the front search failed: {error}")
            else:
                self.panel.show_front(front)
                self._set_status(f"front found: {len(front.poses)} poses; move 'Front pose' to see them")
            return
        if event in ("pose", "selection") and origin != "slider":
            b = state.selected
            self.panel.select(b, np.degrees(state.get_angles()[b]))
        elif event == "settings":
            self.panel.show_settings(state.settings, state.fixed)
        elif event == "search_started":
            s, p = state.search_settings, state.progress
            self.panel.search_started(s.iterations)
            turns = " and the print orientation" if s.orient == "free" else ""
            self._set_status(f"searching{turns}: {s.particles} particles × {s.iterations} iterations, "
                             f"{p['free_bones']} free bones")
        elif event == "progress":
            self.panel.show_progress(state.progress)
            return
        elif event == "search_done":
            self.panel.search_finished()
            if error is not None:
                self._error(f"the search failed: {error}")
            else:
                word = "cancelled" if result.interrupted else "finished"
                degrees = rotation_axis_angle(result.rotation)[1]
                turn = f"printed turned {degrees:.0f}°" if abs(degrees) >= 0.05 else "printed as it stands"
                chosen = ""
                if result.choice is not None:
                    c = result.choice
                    who = "PrusaSlicer" if c.by == "slicer" else "the slicer model"
                    chosen = f"; answer: {c.candidates[c.chosen].kind}, chosen by {who} ({c.reason})"
                self._set_status(f"search {word} after {result.runtime_seconds:.1f} s: objective "
                                 f"{result.value:.4g}, {turn}{chosen}; keep editing, or Undo to go back")
        self._request_render()

    def _set_status(self, text: str) -> None:
        self.status = text
        logger.info(text)
        self.panel.show_status(text)

    def _error(self, text: str) -> None:
        """Show an error in the page (status line + notification) and log it; never raises."""
        self.status = f"Error: {text}"
        logger.error(text)
        self.panel.show_status(text, error=True)
        try:
            for client in self.server.get_clients().values():
                client.add_notification("supportless", text, color="red", auto_close_seconds=10.0)
        except Exception:  # noqa: BLE001 - a closing browser must not break the app
            pass

    # ================================================================ render
    def _request_render(self) -> None:
        with self._cond:
            if self._rendered >= self._requested:  # latency counts from the oldest input not yet drawn
                self._input_time = time.perf_counter()
            self._requested += 1
            self._cond.notify_all()

    def wait_idle(self, timeout: float = 10.0) -> bool:
        """Wait until the latest change is drawn and measured; True on success."""
        end = time.monotonic() + timeout
        with self._cond:
            target = self._requested
            while self._rendered < target:
                left = end - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def _render_loop(self) -> None:
        while True:
            with self._cond:
                while self._rendered >= self._requested and not self._stopping:
                    self._cond.wait(0.5)
                if self._stopping:
                    return
                version, t_in = self._requested, self._input_time
            try:
                self._render(t_in)
            except Exception as exc:  # noqa: BLE001 - keep serving
                if self._stopping:
                    return
                logger.exception("drawing the pose failed")
                self._error(f"drawing the pose failed: {exc}")
            with self._cond:
                self._rendered = max(self._rendered, version)
                self._cond.notify_all()

    def _render(self, t_in: float) -> None:
        with self._swap:
            if self.state is not None:
                self._draw(t_in)

    def _draw(self, t_in: float) -> None:
        state, view, rig = self.state, dict(self.view), self.rig
        (angles, R), selected, fixed, settings = state.get_pose(), state.selected, state.fixed, state.settings
        if view["before"]:  # the rest pose, standing, for a look back
            angles, R, view["frame"] = rig.rest_angles(), np.eye(rig.dim), "standing"
        printed = view["frame"] == "print"
        V = rig.pose(angles) if printed else None  # the plate placement needs the exact surface
        Q, shift = state.frame_transform(view["frame"], V, R)
        locked = self.locked()
        self.scene.draw_pose(angles, selected, fixed, move_gizmo=not self._dragging, placement=(Q, shift),
                             locked=locked)
        t_mesh = time.perf_counter()
        V = rig.pose(angles) if V is None else V
        m = state.measure(angles, rotation=R, exact=True, vertices=V)
        shown = V @ Q.T + shift
        weights = view["weights"]
        risky = m["risky"] if printed else m["risky_standing"]
        self.scene.draw_overlays(shown, risky if view["show_risky"] and not weights else None,
                                 None if weights else m["intersecting_faces"], selected if weights else None)
        if rig.dim == 3:
            self.scene.draw_support(support_columns(shown, rig.faces, rig.up, settings.overhang_angle,
                                                    PREVIEW_RESOLUTION) if view["show_support"] else None)
        m["support_lead"] = lead = support_lead(state, angles, R, V, self.slice_report)
        t_done = time.perf_counter()
        self.measures, self.shown_vertices = m, shown
        mesh_ms, full_ms = 1e3 * (t_mesh - t_in), 1e3 * (t_done - t_in)
        self._latencies = (self._latencies + [mesh_ms])[-50:]
        self.latency_ms = {"mesh": mesh_ms, "full": full_ms, "median_mesh": float(np.median(self._latencies))}
        rules = broken_rules(state.objective, angles) if m["terms"]["violation"] > 0 else []
        text = measures_markdown(m, settings, self.latency_ms, rig.dim, state.print_frame.scale, rules, lead)
        text += self.strength.show(self.scene, state, angles, R, shown, view["show_strength"] and not weights)
        self.panel.show_measures(("**Showing the rest pose (before)**\n\n" if view["before"] else "") + text)
        self.panel.show_bone(selected, fixed, locked)

    # ============================================================= lifecycle
    def stop(self) -> None:
        """Cancel any search and slice, stop drawing, close the server and remove the uploaded files."""
        if self.state is not None:
            self.state.cancel_optimize()
            self.front.cancel()
        self.slicing.cancel()
        with self._cond:
            self._stopping = True
            self._cond.notify_all()
        if self.state is not None:
            self.state.wait_optimize(30)
            self.front.wait(30)
        self.slicing.wait(30)
        self._worker.join(5)
        self.server.stop()
        self.uploads.close()


def run_app(rig=None, host: str = "127.0.0.1", port: int | None = None, open_browser: bool = False,
            block: bool = True, verbose: bool = False, settings: SearchSettings | None = None, frame=None,
            workdir=None, open_options: OpenOptions | None = None) -> App:
    """Serve the viewer of ``rig``, or an empty page that opens models sent to it.

    Parameters
    ----------
    rig : supportless.rig.rig.Rig or None
        None: start on an empty scene (a model is opened from the page).
    host : str
        ``127.0.0.1`` (default) serves only this computer; ``0.0.0.0`` the network.
    port : int or None
        ``None``: 8080, or the next free port. A given port must be free, else
        :class:`~supportless.base.errors.InputError` "port N on HOST is taken; use --port N".
    open_browser : bool
        Open the page in the default browser.
    block : bool
        Serve until Ctrl-C (then stop and return the app); False returns at once.
    verbose : bool
        Let viser print its banner (off: its address lacks the token).
    settings : SearchSettings, optional
        Search settings the panel starts with.
    frame : supportless.files.printframe.PrintFrame, optional
        How exported meshes are printed (default: the rest pose 60 mm tall).
    workdir : str or os.PathLike, optional
        The only folder the page's files are read from and written to
        (default: the current folder).
    open_options : OpenOptions, optional
        How models sent from the page are read (the ``view`` command's ``--up``, ``--height-mm``...).

    Returns
    -------
    app : App
        ``app.url``, ``app.port``, ``app.stop()``.
    """
    app = App(rig, host=host, port=port, verbose=verbose, settings=settings, frame=frame, workdir=workdir,
              open_options=open_options)
    logger.info("supportless viewer at %s", app.url)
    if not is_loopback(host):
        print(f"supportless: warning: the app listens on {host}: anyone who can reach this machine on port "
              f"{app.port} and has the address below (with its token) can pose the model and write files in "
              f"{app.state.workdir.resolve()}; --host 127.0.0.1 keeps it to this computer", file=sys.stderr,
              flush=True)
    if open_browser:
        import webbrowser

        webbrowser.open(app.url)
    if block:
        what = rig.name if rig is not None else "an empty scene (drop a model on the page)"
        print(f"supportless: viewing {what} at {app.url} (Ctrl-C to stop)", flush=True)
        try:
            while True:
                time.sleep(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            app.stop()
    return app
