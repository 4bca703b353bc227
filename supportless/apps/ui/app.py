"""A local web app (viser) to pose a rig by hand and run the pose search.

:func:`run_app` serves the page. :class:`App` wires four parts:

* :class:`~supportless.apps.ui.state.EditorState`: the pose, undo/redo, files,
  search settings, measures and the background search (no browser needed);
* :class:`~supportless.apps.ui.scene.Scene`: the 3D view;
* :class:`~supportless.apps.ui.panel.Panel`: the side panel;
* :mod:`supportless.apps.ui.ports`: which port the server takes.

Its own work is in three parts besides this module (which opens a model, turns the state's events into the
panel's and the status line, and stops): what the page's controls do
(:class:`~supportless.apps.ui.actions.PageActions`), the long jobs — a model sent from the page, a Slice, the
front (:class:`~supportless.apps.ui.jobs.BackgroundJobs`) — and the render thread
(:class:`~supportless.apps.ui.rendering.Rendering`).

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

import numpy as np

from ...search.orientation import rotation_axis_angle
from ...search.settings import SearchSettings
from .actions import PageActions
from .front import FrontBrowser
from .guard import Guard, is_loopback, limit_uploads
from .jobs import BackgroundJobs
from .opener import MAX_UPLOAD_BYTES, OpenOptions, Uploads
from .panel import Panel
from .ports import page_url, start_server
from .rendering import Rendering
from .scene import Scene, draw_welcome
from .slicerun import SliceRun
from .state import EditorState
from .strength import StrengthOverlay

WELCOME = "Drop a model here: .glb/.gltf, or a mesh with its .tgf (or use Open model… in the panel)"

__all__ = ["App", "run_app"]

logger = logging.getLogger("supportless.apps.ui")


class App(PageActions, BackgroundJobs, Rendering):
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
