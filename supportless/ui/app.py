"""A local web app (viser) to pose a rig by hand and run the pose search.

:func:`run_app` serves the page; :class:`App` holds the state and exposes every
action the page offers as a method (``set_bone_angles``, ``undo``, ``redo``,
``reset``, ``load_pose``, ``save_pose``, ``export_mesh``, ``start_optimise``,
``cancel_optimise``...), so the same code paths can be driven by tests without a
browser.

How it stays responsive:

* The displayed surface is a viser *skinned* mesh: each edit streams only the
  bone frames (a few hundred bytes); the browser skins with the top four weights
  per vertex. Every measure shown uses the full weights through the package API
  (:class:`supportless.objective.Objective`, :mod:`supportless.energies`).
* Edits only store the new pose and wake one render thread, which always draws
  the latest pose (a burst of slider events becomes one redraw).
* The pose search runs in its own thread and streams its best pose into the view.
"""

from __future__ import annotations

import copy
import logging
import os
import socket
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from .. import io as sio
from ..energies.overhang import overhang_energy, risky_faces
from ..energies.support import support_volume
from ..errors import InputError, SupportlessError
from ..objective import W_ARAP, W_INTERSECT, W_OVERHANG, Objective
from ..report import reduction
from ..geometry import place_on_plate
from ..search import OVERHANG_MARGIN, resolve_fixed_bones
from .history import PoseHistory

logger = logging.getLogger("supportless.ui")

DEFAULT_PORT = 8080

# colours (RGB 0-255)
MESH_COLOR = (170, 190, 215)
RISKY_COLORS = ((250, 205, 60), (245, 130, 40), (215, 35, 35))  # little / more / most support
INTERSECT_COLOR = (200, 40, 220)
BONE_FREE_COLOR = (40, 110, 230)
BONE_FIXED_COLOR = (120, 120, 120)
BONE_SELECTED_COLOR = (255, 140, 0)
JOINT_COLOR = (30, 60, 160)


# --------------------------------------------------------------------------- #
# ports
# --------------------------------------------------------------------------- #
def port_is_free(host: str, port: int) -> bool:
    """True when a server could listen on ``host:port`` now."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def find_free_port(host: str = "127.0.0.1", start: int = DEFAULT_PORT, attempts: int = 200) -> int:
    """The first port from ``start`` on which ``host`` can listen.

    Raises
    ------
    InputError
        When none of ``attempts`` ports is free.
    """
    for port in range(start, min(start + attempts, 65536)):
        if port_is_free(host, port):
            return port
    raise InputError(None, f"no free port in {start}..{start + attempts - 1} on {host}; use --port N")


def port_taken_message(host: str, port: int) -> str:
    return f"port {port} on {host} is taken; use --port N"


# --------------------------------------------------------------------------- #
# small geometry helpers for display (no energies here)
# --------------------------------------------------------------------------- #
def _to3(a: np.ndarray) -> np.ndarray:
    """(..., 2) -> (..., 3) with z = 0; (..., 3) unchanged."""
    a = np.asarray(a, np.float64)
    if a.shape[-1] == 3:
        return a
    return np.concatenate([a, np.zeros(a.shape[:-1] + (1,))], axis=-1)


def _transforms3(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bone transforms (m, d, d+1) -> rotations (m, 3, 3) and translations (m, 3)."""
    d = T.shape[-2]
    if d == 3:
        return T[..., :3], T[..., 3]
    A = np.tile(np.eye(3), T.shape[:-2] + (1, 1))
    A[..., :2, :2] = T[..., :2]
    return A, _to3(T[..., 2])


def matrix_to_euler(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`supportless.kinematics.euler_to_matrix` (``Rx Ry Rz``), radians (3,)."""
    sy = float(np.clip(R[0, 2], -1.0, 1.0))
    b = np.arcsin(sy)
    if abs(sy) < 1.0 - 1e-9:
        a = np.arctan2(-R[1, 2], R[2, 2])
        c = np.arctan2(-R[0, 1], R[0, 0])
    else:  # gimbal lock: put everything in a
        a = np.arctan2(R[2, 1], R[1, 1])
        c = 0.0
    return np.array([a, b, c])


def _quat_from_matrix(R: np.ndarray) -> np.ndarray:
    import viser.transforms as vtf

    return np.asarray(vtf.SO3.from_matrix(R).wxyz, np.float64)


def _matrix_from_quat(wxyz) -> np.ndarray:
    import viser.transforms as vtf

    return np.asarray(vtf.SO3(np.asarray(wxyz, np.float64)).as_matrix(), np.float64)


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation matrix turning unit vector a onto unit vector b."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    v = np.cross(a, b)
    c = float(a @ b)
    if c < -1 + 1e-9:
        axis = np.cross(a, [1.0, 0, 0])
        if np.linalg.norm(axis) < 1e-6:
            axis = np.cross(a, [0, 1.0, 0])
        axis /= np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1 + c)


def _fmt(x: float | None, spec: str = ".4g") -> str:
    return "n/a" if x is None else format(float(x), spec)


def _vs_rest(x: float | None) -> str:
    if x is None:
        return "rest pose needs none"
    return f"{x:.1f} % less than rest" if x >= 0 else f"{-x:.1f} % more than rest"


def _parse_bone_list(text: str) -> list[str]:
    return [t for t in text.replace(";", ",").replace(" ", ",").split(",") if t.strip()]


# --------------------------------------------------------------------------- #
# the app
# --------------------------------------------------------------------------- #
class App:
    """The viewer/editor of one rig, served by viser on ``host:port``.

    Parameters
    ----------
    rig : supportless.rig.Rig
    host : str
        Interface to listen on (default: only this computer).
    port : int or None
        ``None``: 8080 or the next free port. A given port must be free, else
        :class:`~supportless.errors.InputError` ("port N on HOST is taken; use --port N").
    verbose : bool
        Let viser print its banner.
    workdir : str or os.PathLike, optional
        Folder of relative pose/mesh paths typed in the page (default: current folder).

    Attributes
    ----------
    url : str
    port : int
    angles : (m, 3) float64
        The current pose (radians); read it through :meth:`get_angles`.
    measures : dict
        What the panel shows for the last drawn pose (see :meth:`measure`).
    status : str
        The last status or error message shown in the page.
    """

    def __init__(self, rig, host: str = "127.0.0.1", port: int | None = None, *, verbose: bool = True,
                 workdir=None):
        import viser

        self.rig = rig
        self.host = host
        self.workdir = Path(workdir) if workdir is not None else Path.cwd()
        self._lock = threading.RLock()
        self._cond = threading.Condition(self._lock)
        self.angles = rig.rest_angles()
        self.selected = 0
        self.history = PoseHistory()
        self.status = "ready"
        self.measures: dict = {}
        self.latency_ms: dict = {}
        self._latencies: list[float] = []
        self._requested = 0
        self._rendered = 0
        self._stopping = False
        self._dragging = False
        self._weights_view = False
        self._show_risky = True
        self._opt_thread: threading.Thread | None = None
        self._opt_cancel = threading.Event()
        self.opt_progress: dict = {}
        self.last_result = None

        # geometry constants
        self._dim = rig.dim
        self._up3 = _to3(rig.up)
        self._rest3 = _to3(rig.vertices)
        self._roots3 = _to3(rig.joints[rig.bones[:, 0]])
        self._diag = float(np.linalg.norm(np.ptp(self._rest3, axis=0)))
        self._faces = np.asarray(rig.faces, np.int64)
        if self._dim == 2:
            from ..energies._raycast import boundary_edges

            self._edges = np.asarray(boundary_edges(self._faces), np.int64)
        self._settings = dict(particles=200, iterations=120, seed=0, max_angle=30.0, w_arap=W_ARAP,
                              w_overhang=W_OVERHANG, w_intersect=W_INTERSECT, overhang_angle=45.0, fix="", free="")
        self.objective = Objective(rig, overhang_angle=45.0)
        self._rest_measures = self.measure(rig.rest_angles(), exact=False)
        self._fixed = resolve_fixed_bones(rig)

        # server
        if port is None:
            port = find_free_port(host, DEFAULT_PORT)
        elif not port_is_free(host, port):
            raise InputError(None, port_taken_message(host, port))
        self.server = viser.ViserServer(host=host, port=port, label=f"supportless: {rig.name}", verbose=verbose)
        if self.server.get_port() != port:  # viser moved on by itself: the port was taken meanwhile
            self.server.stop()
            raise InputError(None, port_taken_message(host, port))
        self.port = int(self.server.get_port())
        shown_host = "localhost" if host in ("0.0.0.0", "::", "") else f"[{host}]" if ":" in host else host
        self.url = f"http://{shown_host}:{self.port}"

        self._build_scene()
        self._build_gui()
        self._worker = threading.Thread(target=self._render_loop, name="supportless-ui-render", daemon=True)
        self._worker.start()
        self._request_render()

    # ================================================================ state API
    def get_angles(self) -> np.ndarray:
        """A copy of the current pose, (m, 3) radians."""
        with self._lock:
            return self.angles.copy()

    def set_angles(self, angles, *, record: bool = True, key=None, sync: bool = True) -> None:
        """Replace the whole pose.

        Parameters
        ----------
        angles : (m, 3) float64
            Radians.
        record : bool
            Make it an undo step.
        key : hashable, optional
            Control making the edit (edits of one control in a row merge).
        sync : bool
            Move the sliders to the new values.
        """
        angles = np.asarray(angles, np.float64)
        if angles.shape != self.angles.shape:
            raise ValueError(f"pose has shape {angles.shape}, the rig needs {self.angles.shape}")
        with self._lock:
            if record:
                self.history.record(self.angles, key)
            self.angles = angles.copy()
        if sync:
            self._sync_sliders()
        self._request_render()

    def set_bone_angles(self, bone: int, degrees, *, key=None) -> None:
        """Set one bone's XYZ Euler angles (0-based bone, degrees)."""
        with self._lock:
            angles = self.angles.copy()
            angles[bone] = np.radians(np.asarray(degrees, np.float64))
        self.set_angles(angles, key=key if key is not None else ("bone", bone))

    def select_bone(self, bone: int) -> None:
        """Select the bone the sliders and the gizmo act on (0-based)."""
        if not 0 <= bone < self.rig.bone_count:
            raise ValueError(f"bone {bone} out of range")
        with self._lock:
            self.selected = int(bone)
        name = self.rig.bone_names()[bone]
        if self.gui_bone.value != name:
            self.gui_bone.value = name
        self._sync_sliders()
        self._request_render()

    def undo(self) -> bool:
        """Go back one edit; False when there is nothing to undo."""
        with self._lock:
            prev = self.history.undo(self.angles)
            if prev is None:
                self._set_status("nothing to undo")
                return False
            self.angles = prev
        self._sync_sliders()
        self._request_render()
        return True

    def redo(self) -> bool:
        """Redo the last undone edit; False when there is none."""
        with self._lock:
            nxt = self.history.redo(self.angles)
            if nxt is None:
                self._set_status("nothing to redo")
                return False
            self.angles = nxt
        self._sync_sliders()
        self._request_render()
        return True

    def reset(self) -> None:
        """Back to the rest pose (undoable)."""
        self.set_angles(self.rig.rest_angles())
        self._set_status("reset to the rest pose")

    # ----------------------------------------------------------------- files
    def _path(self, path) -> Path:
        p = Path(os.path.expanduser(str(path).strip()))
        return p if p.is_absolute() else self.workdir / p

    def save_pose(self, path) -> bool:
        """Write the current pose as JSON; False (and a message in the page) on failure."""
        try:
            p = self._path(path)
            with self._lock:
                angles = self.angles.copy()
            value = self.measures.get("objective")
            sio.write_pose(p, angles, self.rig.bones, self.rig.joints,
                           extra={"objective": value} if value is not None else None)
        except (OSError, SupportlessError, ValueError) as exc:
            self._error(f"cannot save the pose: {exc}")
            return False
        self._set_status(f"saved pose to {p}")
        return True

    def load_pose(self, path) -> bool:
        """Read a pose JSON written for this skeleton; False (and a message in the page) on failure.

        The server keeps running on any bad file (missing, not JSON, another skeleton).
        """
        try:
            p = self._path(path)
            angles = sio.read_pose(p, self.rig.bones)
        except (OSError, SupportlessError, ValueError) as exc:
            self._error(f"cannot load the pose: {exc}")
            return False
        self.set_angles(angles)
        self._set_status(f"loaded pose from {p}")
        return True

    def load_pose_bytes(self, name: str, content: bytes) -> bool:
        """Load an uploaded pose file (same checks as :meth:`load_pose`)."""
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / (Path(name).name or "pose.json")
            p.write_bytes(content)
            ok = self.load_pose(p)
        if ok:
            self._set_status(f"loaded uploaded pose {name}")
        return ok

    def posed_on_plate(self) -> np.ndarray:
        """The current posed surface placed on the plate, (n, d) float64."""
        with self._lock:
            angles = self.angles.copy()
        return place_on_plate(self.rig.pose(angles), self.rig.up)

    def export_mesh(self, path) -> bool:
        """Write the posed mesh (on the plate) as STL/3MF/OBJ/PLY by extension."""
        try:
            p = self._path(path)
            sio.write_mesh(p, self.posed_on_plate(), self.rig.faces)
        except (OSError, SupportlessError, ValueError) as exc:
            self._error(f"cannot export the mesh: {exc}")
            return False
        self._set_status(f"exported the posed mesh to {p}")
        return True

    def mesh_bytes(self, fmt: str) -> bytes:
        """The posed mesh (on the plate) as a file's bytes, ``fmt`` in stl/3mf/obj/ply."""
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / f"mesh.{fmt}"
            sio.write_mesh(p, self.posed_on_plate(), self.rig.faces)
            return p.read_bytes()

    def pose_bytes(self) -> bytes:
        with tempfile.TemporaryDirectory() as tmp:
            p = Path(tmp) / "pose.json"
            with self._lock:
                angles = self.angles.copy()
            sio.write_pose(p, angles, self.rig.bones, self.rig.joints)
            return p.read_bytes()

    def _download(self, filename: str, make) -> None:
        try:
            data = make()
        except Exception as exc:  # noqa: BLE001 - reported in the page
            self._error(f"cannot prepare {filename}: {exc}")
            return
        clients = self.server.get_clients()
        if not clients:
            self._error("no browser connected to send the download to")
            return
        for client in clients.values():
            client.send_file_download(filename, data, save_immediately=True)
        self._set_status(f"sent {filename} ({len(data) // 1024} KiB)")

    # ---------------------------------------------------------- optimisation
    def optimise_settings(self) -> dict:
        """The search settings currently in the panel."""
        return dict(particles=int(self.gui_particles.value), iterations=int(self.gui_iterations.value),
                    seed=int(self.gui_seed.value), max_angle=float(self.gui_max_angle.value),
                    w_arap=float(self.gui_w_arap.value), w_overhang=float(self.gui_w_overhang.value),
                    w_intersect=float(self.gui_w_intersect.value),
                    overhang_angle=float(self.gui_overhang_angle.value),
                    fix=_parse_bone_list(self.gui_fix.value), free=_parse_bone_list(self.gui_free.value))

    @property
    def optimising(self) -> bool:
        t = self._opt_thread
        return t is not None and t.is_alive()

    def start_optimise(self, **overrides) -> bool:
        """Run :func:`supportless.search.optimize` in a background thread.

        Settings come from the panel; keyword arguments override them
        (``particles``, ``iterations``, ``seed``, ``max_angle``, ``w_*``,
        ``fix``, ``free``). Returns False when a search is already running
        or the settings are invalid.
        """
        from ..search import optimize

        if self.optimising:
            self._set_status("a search is already running")
            return False
        settings = self.optimise_settings()
        settings.update(overrides)
        try:
            fixed = resolve_fixed_bones(self.rig, settings["fix"], settings["free"])
        except ValueError as exc:
            self._error(f"bad fixed/free bones: {exc}")
            return False
        if fixed.all():
            self._error("every bone is fixed: free some bones (e.g. Free bones: all)")
            return False
        # the search looks past the threshold by a margin (see supportless.search.OVERHANG_MARGIN)
        objective = self._make_objective(settings["w_arap"], settings["w_overhang"], settings["w_intersect"],
                                         min(float(settings["overhang_angle"]) + OVERHANG_MARGIN, 89.0))
        self._opt_cancel.clear()
        with self._lock:
            self.history.record(self.angles)
            start = np.array(self.angles, np.float64)  # the search starts from the pose on screen
            self.opt_progress = {"iteration": 0, "iterations": settings["iterations"], "value": None,
                                 "running": True, "cancelled": False}
        total = settings["iterations"]

        def callback(iteration, info):
            with self._lock:
                self.angles = np.array(info["angles"], np.float64)
                self.opt_progress.update(iteration=iteration, value=float(info["value"]))
            self._request_render()
            self.gui_progress.value = 100.0 * iteration / max(total, 1)
            self.gui_opt_info.content = f"iteration {iteration} / {total} · best objective {info['value']:.4g}"
            self.gui_status.content = (f"**Status:** searching, iteration {iteration} / {total}, "
                                       f"best objective {info['value']:.4g}")
            return False if self._opt_cancel.is_set() else None

        def run():
            t0 = time.perf_counter()
            try:
                result = optimize(self.rig, particles=settings["particles"], iterations=total,
                                  seed=settings["seed"], max_angle=settings["max_angle"], fix=settings["fix"],
                                  free=settings["free"], objective=objective, callback=callback,
                                  start=start)
            except Exception as exc:  # noqa: BLE001 - shown in the page, the server keeps running
                logger.exception("pose search failed")
                self._error(f"the search failed: {exc}")
                with self._lock:
                    self.opt_progress["running"] = False
                self._opt_done_ui()
                return
            with self._lock:
                self.angles = np.array(result.angles, np.float64)
                self.last_result = result
                self.opt_progress.update(running=False, cancelled=bool(result.interrupted), value=result.value)
            self._sync_sliders()
            self._request_render()
            word = "cancelled" if result.interrupted else "finished"
            self._set_status(f"search {word} after {time.perf_counter() - t0:.1f} s: objective "
                             f"{result.value:.4g}; keep editing, or Undo to go back")
            self._opt_done_ui()

        self.gui_optimise.disabled = True
        self.gui_cancel.disabled = False
        self.gui_progress.value = 0.0
        self.gui_opt_info.content = f"iteration 0 / {total}"
        self._set_status(f"searching: {settings['particles']} particles × {total} iterations, "
                         f"{int((~fixed).sum())} free bones")
        self._opt_thread = threading.Thread(target=run, name="supportless-ui-search", daemon=True)
        self._opt_thread.start()
        return True

    def _opt_done_ui(self):
        self.gui_optimise.disabled = False
        self.gui_cancel.disabled = True
        self.gui_progress.value = 100.0

    def cancel_optimise(self) -> None:
        """Ask the running search to stop after its current iteration (keeps its best pose)."""
        self._opt_cancel.set()

    def wait_optimise(self, timeout: float | None = None) -> bool:
        """Wait for the search thread; True when it has finished."""
        t = self._opt_thread
        if t is not None:
            t.join(timeout)
        return not self.optimising

    # ------------------------------------------------------------- measures
    def _make_objective(self, w_arap, w_overhang, w_intersect, overhang_angle) -> Objective:
        """An Objective with these settings, sharing the precomputed ARAP operators."""
        if float(overhang_angle) == self.objective.overhang_angle:
            obj = copy.copy(self.objective)  # keeps the cached operators and rest overhang
        else:
            obj = Objective(self.rig, overhang_angle=overhang_angle)
            if "arap_data" in self.objective.__dict__:
                obj.__dict__["arap_data"] = self.objective.arap_data
        obj.w_arap, obj.w_overhang, obj.w_intersect = float(w_arap), float(w_overhang), float(w_intersect)
        return obj

    def measure(self, angles: np.ndarray, exact: bool = True, vertices: np.ndarray | None = None) -> dict:
        """Everything the panel shows about a pose.

        Returns
        -------
        dict
            ``objective``, ``terms`` (normalised), ``prism`` and ``column``
            support estimates, their ``*_reduction`` % from the rest pose,
            ``risky`` mask, ``intersecting`` face indices (CGAL, 3D, when
            ``exact``) and ``vertices``.
        """
        obj = self.objective
        V = self.rig.pose(angles) if vertices is None else vertices
        value, terms, _raw = obj.evaluate(angles)
        prism = float(overhang_energy(V, self.rig.faces, self.rig.up, obj.overhang_angle))
        column = float(support_volume(V, self.rig.faces, self.rig.up, obj.overhang_angle, obj.resolution))
        risky = np.asarray(risky_faces(V, self.rig.faces, self.rig.up, obj.overhang_angle), bool)
        out = {"objective": float(value), "terms": {k: float(v) for k, v in terms.items()},
               "prism": prism, "column": column, "risky": risky, "vertices": V}
        rest = getattr(self, "_rest_measures", None)
        if rest is not None:
            out["prism_reduction"] = reduction(rest["prism"], prism)
            out["column_reduction"] = reduction(rest["column"], column)
        if exact and self._dim == 3:
            out["intersecting"] = self._intersecting_faces(V)
        return out

    def _intersecting_faces(self, V: np.ndarray) -> np.ndarray | None:
        try:
            import igl
            import igl.copyleft.cgal  # noqa: F401

            res = igl.copyleft.cgal.remesh_self_intersections(np.ascontiguousarray(V, np.float64),
                                                              np.ascontiguousarray(self._faces), detect_only=True)
            IF = np.asarray(res[2], np.int64).reshape(-1, 2)
            return np.unique(IF)
        except Exception as exc:  # noqa: BLE001 - the highlight is optional
            logger.debug("no self-intersection highlight: %s", exc)
            return None

    # ========================================================== scene & gui
    def _build_scene(self):
        s = self.server.scene
        up = self._up3
        axis = int(np.argmax(np.abs(up)))
        if np.allclose(np.abs(up), np.eye(3)[axis]):
            s.set_up_direction(("+" if up[axis] > 0 else "-") + "xyz"[axis])
        else:
            s.set_up_direction(tuple(up))
        size = self._diag
        centre = self._rest3.mean(axis=0)
        lo = float((self._rest3 @ up).min())
        # build plate: grid in the plane normal to up, moved to the lowest point
        self._plate_rot = _quat_from_matrix(_rotation_between(np.array([0, 0, 1.0]), up))
        step = 10 ** np.floor(np.log10(size / 3))
        centre_plate = centre - (centre @ up) * up
        self.h_grid = s.add_grid("/plate", width=3 * size, height=3 * size, plane="xy", cell_size=step,
                                 section_size=step * 5, wxyz=self._plate_rot,
                                 position=centre_plate + lo * up, cell_color=(190, 195, 205),
                                 section_color=(120, 125, 140), plane_color=(235, 238, 242), plane_opacity=0.6,
                                 shadow_opacity=0.2)
        self._centre_plate = centre_plate
        side = self._perp(up)
        back = -np.cross(up, side)
        a0 = centre_plate + lo * up + 0.55 * size * (back - side)
        self.h_up = s.add_arrows("/up_arrow", points=np.array([[a0, a0 + 0.3 * size * up]]),
                                 colors=(20, 160, 60), shaft_radius=0.005 * size, head_radius=0.015 * size,
                                 head_length=0.045 * size)
        s.add_label("/up_label", "up", position=a0 + 0.34 * size * up)

        # the skinned mesh: bones start at their root joints, unrotated
        m = self.rig.bone_count
        self.h_mesh = s.add_mesh_skinned(
            "/model/mesh", self._rest3.astype(np.float32), self._faces,
            bone_wxyzs=np.tile([1.0, 0, 0, 0], (m, 1)), bone_positions=self._roots3,
            skin_weights=np.asarray(self.rig.weights, np.float64), color=MESH_COLOR, opacity=0.55,
            side="double" if self._dim == 2 else "front", flat_shading=False)
        self._mesh_opacity = 0.55
        self.h_weights = None
        self._overlays: dict = {}
        self.h_risky_edges = None

        # skeleton
        r = 0.011 * size
        J = _to3(self.rig.joints)
        self.h_joints = []
        for j, p in enumerate(J):
            h = s.add_icosphere(f"/model/joints/{j}", radius=r, color=JOINT_COLOR, position=p, subdivisions=2)
            h.on_click(self._make_joint_click(j))
            self.h_joints.append(h)
        self.h_bones = s.add_line_segments("/model/bones", points=J[self.rig.bones],
                                           colors=self._bone_colors(), thickness=0.006 * size)
        self.h_gizmo = s.add_transform_controls("/gizmo", scale=0.3 * size, disable_axes=True,
                                                disable_sliders=True, depth_test=False,
                                                position=self._roots3[0])

        @self.h_gizmo.on_update
        async def _(event):  # async: phases arrive in order
            if event.phase == "start":
                with self._lock:
                    self._dragging = True
                    self.history.record(self.angles)
            elif event.phase == "end":
                with self._lock:
                    self._dragging = False
                self._request_render()
            else:
                self._on_gizmo(np.asarray(event.target.wxyz, np.float64))

        cam = self.server.initial_camera
        cam.look_at = tuple(centre)
        side = self._perp(up)
        fwd = np.cross(up, side)
        cam.position = tuple(centre + size * (0.85 * fwd + 0.35 * side + 0.4 * up))
        cam.up = tuple(up)

    @staticmethod
    def _perp(up: np.ndarray) -> np.ndarray:
        ref = np.array([1.0, 0, 0]) if abs(up[0]) < 0.9 else np.array([0, 0, 1.0])
        v = ref - (ref @ up) * up
        return v / np.linalg.norm(v)

    def _bone_colors(self) -> np.ndarray:
        m = self.rig.bone_count
        cols = np.empty((m, 2, 3), np.uint8)
        for b in range(m):
            c = BONE_SELECTED_COLOR if b == self.selected else (BONE_FIXED_COLOR if self._fixed[b] else BONE_FREE_COLOR)
            cols[b] = c
        return cols

    def _make_joint_click(self, joint: int):
        def on_click(_event):
            roots = np.flatnonzero(self.rig.bones[:, 0] == joint)
            tips = np.flatnonzero(self.rig.bones[:, 1] == joint)
            bone = int(roots[0]) if len(roots) else int(tips[0]) if len(tips) else None
            if bone is not None:
                self.select_bone(bone)
                self._set_status(f"selected {self.rig.bone_names()[bone]} (joint {joint + 1})")
        return on_click

    def _build_gui(self):
        g = self.server.gui
        g.configure_theme(control_width="large", dark_mode=False)
        self.gui_status = g.add_markdown("**Status:** ready")
        with g.add_folder("Energies"):
            self.gui_measures = g.add_markdown("computing…")
        with g.add_folder("Pose"):
            names = self.rig.bone_names()
            self.gui_bone = g.add_dropdown("Bone", names, initial_value=names[0],
                                           hint="Bone to rotate; you can also click a joint")
            labels = ("X°", "Y°", "Z°")
            self.gui_sliders = []
            for i in range(3):
                sl = g.add_slider(labels[i], min=-180.0, max=180.0, step=1.0, initial_value=0.0,
                                  disabled=self._dim == 2 and i < 2,
                                  hint="Euler angle of the selected bone relative to its parent")
                sl.on_update(self._make_slider_cb(i))
                self.gui_sliders.append(sl)
            undo, redo = g.add_button("Undo", icon=None), g.add_button("Redo")
            reset = g.add_button("Reset to rest pose")
            self.gui_show_risky = g.add_checkbox("Show risky faces", True)
            self.gui_weights = g.add_checkbox("Colour by bone weights", False,
                                              hint="Colour the mesh by the selected bone's skinning weights")
            self.gui_opacity = g.add_slider("Mesh opacity", min=0.1, max=1.0, step=0.05, initial_value=0.55)
            self.gui_bone_info = g.add_markdown("")

        @self.gui_bone.on_update
        def _(event):
            if event.client is None:
                return
            self.select_bone(names.index(self.gui_bone.value))

        undo.on_click(lambda _e: self.undo())
        redo.on_click(lambda _e: self.redo())
        reset.on_click(lambda _e: self.reset())

        @self.gui_show_risky.on_update
        def _(_event):
            self._show_risky = bool(self.gui_show_risky.value)
            self._request_render()

        @self.gui_weights.on_update
        def _(_event):
            self._weights_view = bool(self.gui_weights.value)
            self._request_render()

        @self.gui_opacity.on_update
        def _(_event):
            self._mesh_opacity = float(self.gui_opacity.value)
            self.h_mesh.opacity = self._mesh_opacity if self._mesh_opacity < 0.999 else None

        with g.add_folder("Optimise"):
            st = self._settings
            self.gui_particles = g.add_number("Particles", st["particles"], min=2, max=5000, step=1)
            self.gui_iterations = g.add_number("Iterations", st["iterations"], min=1, max=10000, step=1)
            self.gui_seed = g.add_number("Seed", st["seed"], min=0, step=1)
            self.gui_max_angle = g.add_number("Max angle °", st["max_angle"], min=1.0, max=180.0, step=1.0)
            self.gui_w_arap = g.add_number("w ARAP", st["w_arap"], min=0.0, step=0.1)
            self.gui_w_overhang = g.add_number("w overhang", st["w_overhang"], min=0.0, step=0.1)
            self.gui_w_intersect = g.add_number("w intersect", st["w_intersect"], min=0.0, step=1.0)
            self.gui_overhang_angle = g.add_number("Overhang angle °", st["overhang_angle"], min=1.0, max=89.0,
                                                   step=1.0)
            self.gui_fix = g.add_text("Fix bones", "", hint="1-based bone numbers, e.g. 1,4 or 'all'")
            self.gui_free = g.add_text("Free bones", "", hint="1-based bone numbers to free, or 'all'")
            self.gui_fixed_info = g.add_markdown("")
            self.gui_optimise = g.add_button("Optimise", color="green")
            self.gui_cancel = g.add_button("Cancel search", color="red", disabled=True)
            self.gui_progress = g.add_progress_bar(0.0)
            self.gui_opt_info = g.add_markdown("idle")
        self._update_fixed_info()

        for h in (self.gui_w_arap, self.gui_w_overhang, self.gui_w_intersect, self.gui_overhang_angle):
            h.on_update(self._on_weights_changed)
        for h in (self.gui_fix, self.gui_free):
            h.on_update(lambda _e: self._update_fixed_info())
        self.gui_optimise.on_click(lambda _e: self.start_optimise())
        self.gui_cancel.on_click(lambda _e: self.cancel_optimise())

        with g.add_folder("Files", expand_by_default=False):
            self.gui_pose_path = g.add_text("Pose file", f"{self.rig.name}-pose.json",
                                            hint=f"On the server; relative to {self.workdir}")
            save, load = g.add_button("Save pose"), g.add_button("Load pose")
            upload = g.add_upload_button("Upload pose…", mime_type="application/json")
            dl_pose = g.add_button("Download pose JSON")
            self.gui_mesh_path = g.add_text("Mesh file", f"{self.rig.name}-posed.stl",
                                            hint="On the server; .stl .3mf .obj .ply")
            export = g.add_button("Export mesh to file")
            dl_stl, dl_3mf = g.add_button("Download STL"), g.add_button("Download 3MF")

        save.on_click(lambda _e: self.save_pose(self.gui_pose_path.value))
        load.on_click(lambda _e: self.load_pose(self.gui_pose_path.value))
        export.on_click(lambda _e: self.export_mesh(self.gui_mesh_path.value))

        @upload.on_upload
        def _(_event):
            f = upload.value
            self.load_pose_bytes(f.name, f.content)

        name = self.rig.name
        dl_pose.on_click(lambda _e: self._download(f"{name}-pose.json", self.pose_bytes))
        dl_stl.on_click(lambda _e: self._download(f"{name}-posed.stl", lambda: self.mesh_bytes("stl")))
        dl_3mf.on_click(lambda _e: self._download(f"{name}-posed.3mf", lambda: self.mesh_bytes("3mf")))
        self._sync_sliders()

    # ---------------------------------------------------------- gui callbacks
    def _make_slider_cb(self, i: int):
        def cb(event):
            if event.client is None:  # set by the server itself
                return
            with self._lock:
                b = self.selected
                angles = self.angles.copy()
            angles[b, i] = np.radians(float(self.gui_sliders[i].value))
            self.set_angles(angles, key=("slider", b, i), sync=False)
        return cb

    def _on_gizmo(self, wxyz: np.ndarray) -> None:
        R = _matrix_from_quat(wxyz)
        with self._lock:
            b = self.selected
            angles = self.angles.copy()
            p = int(self.rig.parents[b])
        if p >= 0:
            Qp, _ = _transforms3(self.rig.transforms(angles)[p])
            dQ = Qp.T @ R
        else:
            dQ = R
        if self._dim == 2:
            angles[b] = [0.0, 0.0, np.arctan2(dQ[1, 0], dQ[0, 0])]
        else:
            angles[b] = matrix_to_euler(dQ)
        self.set_angles(angles, record=False)

    def _on_weights_changed(self, _event=None):
        try:
            obj = self._make_objective(self.gui_w_arap.value, self.gui_w_overhang.value, self.gui_w_intersect.value,
                                       self.gui_overhang_angle.value)
        except Exception as exc:  # noqa: BLE001
            self._error(f"bad objective settings: {exc}")
            return
        with self._lock:
            self.objective = obj
            self._rest_measures = None
        self._rest_measures = self.measure(self.rig.rest_angles(), exact=False)
        self._request_render()

    def _update_fixed_info(self):
        try:
            fixed = resolve_fixed_bones(self.rig, _parse_bone_list(self.gui_fix.value),
                                        _parse_bone_list(self.gui_free.value))
        except ValueError as exc:
            self.gui_fixed_info.content = f"⚠ {exc}"
            return
        self._fixed = fixed
        fixed_list = ", ".join(str(b + 1) for b in np.flatnonzero(fixed)) or "none"
        self.gui_fixed_info.content = (f"Fixed in the search (grey): bones {fixed_list}. "
                                       "Default: the bones on the plate and their parents.")
        self._request_render()

    def _sync_sliders(self):
        with self._lock:
            b = self.selected
            deg = np.degrees(self.angles[b])
        for i, sl in enumerate(self.gui_sliders):
            v = float(np.clip(np.round(deg[i], 1), -180.0, 180.0))
            if abs(sl.value - v) > 1e-9:
                sl.value = v

    # ------------------------------------------------------------- messages
    def _set_status(self, text: str) -> None:
        self.status = text
        logger.info(text)
        if hasattr(self, "gui_status"):
            self.gui_status.content = f"**Status:** {text}"

    def _error(self, text: str) -> None:
        """Show an error in the page (status line + notification) and log it; never raises."""
        self.status = f"Error: {text}"
        logger.error(text)
        if hasattr(self, "gui_status"):
            self.gui_status.content = f"**⚠ Error:** {text}"
        try:
            for client in self.server.get_clients().values():
                client.add_notification("supportless", text, color="red", auto_close_seconds=10.0)
        except Exception:  # noqa: BLE001 - a closing browser must not break the app
            pass

    # =============================================================== render
    def _request_render(self) -> None:
        with self._cond:
            if self._rendered >= self._requested:  # latency counts from the oldest input not yet drawn
                self._input_time = time.perf_counter()
            self._requested += 1
            self._cond.notify_all()

    def wait_idle(self, timeout: float = 10.0) -> bool:
        """Wait until the latest requested pose is drawn and measured; True on success."""
        end = time.monotonic() + timeout
        with self._cond:
            target = self._requested
            while self._rendered < target:
                left = end - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def _render_loop(self):
        while True:
            with self._cond:
                while self._rendered >= self._requested and not self._stopping:
                    self._cond.wait(0.5)
                if self._stopping:
                    return
                version = self._requested
                angles = self.angles.copy()
                selected = self.selected
                t_in = self._input_time
            try:
                self._render(angles, selected, t_in)
            except Exception as exc:  # noqa: BLE001 - keep serving
                if self._stopping:
                    return
                logger.exception("drawing the pose failed")
                self._error(f"drawing the pose failed: {exc}")
            with self._cond:
                self._rendered = max(self._rendered, version)
                self._cond.notify_all()

    def _render(self, angles: np.ndarray, selected: int, t_in: float) -> None:
        rig = self.rig
        T = rig.transforms(angles)
        Q, t = _transforms3(T)
        pos = np.einsum("bij,bj->bi", Q, self._roots3) + t
        J = _to3(rig.posed_joints(angles))
        # 1. the mesh (bone frames only) and the skeleton
        with self.server.atomic():
            for b, bone in enumerate(self.h_mesh.bones):
                bone.wxyz = _quat_from_matrix(Q[b])
                bone.position = pos[b]
            for j, h in enumerate(self.h_joints):
                h.position = J[j]
            self.h_bones.points = J[rig.bones].astype(np.float32)
            self.h_bones.colors = self._bone_colors()
            if not self._dragging:
                self.h_gizmo.position = pos[selected]
                self.h_gizmo.wxyz = _quat_from_matrix(Q[selected])
        self.server.flush()
        t_mesh = time.perf_counter()

        # 2. measures with the full weights
        V = rig.pose(angles)
        meas = self.measure(angles, exact=True, vertices=V)
        V3 = _to3(V)
        lo = float((V3 @ self._up3).min())
        self.h_grid.position = self._centre_plate + (lo - 1e-4 * self._diag) * self._up3
        self._draw_overlays(V3, meas, selected)
        t_done = time.perf_counter()
        self.measures = meas
        mesh_ms, full_ms = 1e3 * (t_mesh - t_in), 1e3 * (t_done - t_in)
        self._latencies = (self._latencies + [mesh_ms])[-50:]
        self.latency_ms = {"mesh": mesh_ms, "full": full_ms, "median_mesh": float(np.median(self._latencies))}
        self.gui_measures.content = self._measures_markdown(meas)
        b = selected
        kids = int(np.sum(rig.parents == b))
        self.gui_bone_info.content = (f"Bone {b + 1}: joints {rig.bones[b, 0] + 1}→{rig.bones[b, 1] + 1}, parent "
                                      f"{'none' if rig.parents[b] < 0 else rig.parents[b] + 1}, {kids} child bone(s); "
                                      f"{'fixed' if self._fixed[b] else 'free'} in the search.")

    def _draw_overlays(self, V3: np.ndarray, meas: dict, selected: int) -> None:
        s = self.server.scene
        F = self._faces
        weights_view = self._weights_view
        show_risky = self._show_risky and not weights_view
        # weight view: a vertex-coloured copy of the posed mesh
        if weights_view:
            import trimesh
            from matplotlib import colormaps

            w = np.asarray(self.rig.weights[:, selected])
            rgba = (colormaps["viridis"](w) * 255).astype(np.uint8)
            tm = trimesh.Trimesh(V3, F, vertex_colors=rgba, process=False)
            self.h_weights = s.add_mesh_trimesh("/model/weights", tm)
            self.h_mesh.visible = False
        else:
            if self.h_weights is not None:
                self.h_weights.remove()
                self.h_weights = None
            self.h_mesh.visible = True

        eps = 0.002 * self._diag
        if self._dim == 3:
            risky = meas["risky"] if show_risky else np.zeros(len(F), bool)
            a, b, c = V3[F[:, 0]], V3[F[:, 1]], V3[F[:, 2]]
            n = np.cross(b - a, c - a)
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
            # how much support a face needs: steepness times height above the plate
            h = ((a + b + c) / 3) @ self._up3
            need = np.abs(n @ self._up3) * (h - h.min())
            level = np.zeros(len(F), int)
            if risky.any():
                top = max(float(need[risky].max()), 1e-30)
                level = np.digitize(need / top, [1 / 3, 2 / 3])

            def lifted(sel, k):  # the selected faces, lifted off the surface so they show on top
                return (np.stack([a[sel], b[sel], c[sel]], 1) + k * eps * n[sel][:, None, :]).reshape(-1, 3)

            inter = meas.get("intersecting")
            inter_sel = np.zeros(len(F), bool)
            if inter is not None and not weights_view:
                inter_sel[inter] = True
            with self.server.atomic():
                for k in range(3):
                    self._overlay(f"risky{k}", lifted(risky & (level == k), 1.0), RISKY_COLORS[k])
                self._overlay("intersections", lifted(inter_sel, 1.5), INTERSECT_COLOR, side="double")
        else:
            E = self._edges
            risky = meas["risky"] if show_risky else np.zeros(len(E), bool)
            h = self.h_risky_edges
            if risky.any():
                pts = V3[E[risky]].astype(np.float32)
                cols = np.broadcast_to(np.asarray(RISKY_COLORS[2], np.uint8), pts.shape).copy()
                if h is None:
                    self.h_risky_edges = s.add_line_segments("/model/risky_edges", pts, colors=cols,
                                                             thickness=0.01 * self._diag)
                else:
                    with self.server.atomic():
                        h.points, h.colors, h.visible = pts, cols, True
            elif h is not None:
                h.visible = False

    def _overlay(self, key: str, tri: np.ndarray, color, side: str = "front") -> None:
        """Show triangles ``tri`` (3k, 3) as a single-colour overlay node, reusing the node."""
        h = self._overlays.get(key)
        if len(tri) == 0:
            if h is not None and h.visible:
                h.visible = False
            return
        V = np.ascontiguousarray(tri, np.float32)
        F = np.arange(len(V), dtype=np.uint32).reshape(-1, 3)
        if h is None:
            self._overlays[key] = self.server.scene.add_mesh_simple(f"/model/{key}", V, F, color=color,
                                                                    flat_shading=True, side=side)
            return
        h.vertices = V  # fresh arrays: viser sends what changed
        if len(h.faces) != len(F):
            h.faces = F
        if not h.visible:
            h.visible = True

    def _measures_markdown(self, m: dict) -> str:
        t = m["terms"]
        obj = self.objective
        lat = self.latency_ms
        inter = m.get("intersecting")
        inter_txt = ("not checked (2D)" if self._dim == 2 else "n/a" if inter is None
                     else f"{len(inter)} faces" + (" (magenta)" if len(inter) else ""))
        return "\n".join([
            f"- Objective: **{_fmt(m['objective'])}**",
            f"- ARAP term: {_fmt(t['arap'])} (× {obj.w_arap:g})",
            f"- Overhang term: {_fmt(t['overhang'])} (× {obj.w_overhang:g})",
            f"- Intersection term: {_fmt(t['intersection'])} (× {obj.w_intersect:g})",
            f"- Support (prism): {_fmt(m['prism'])} ({_vs_rest(m.get('prism_reduction'))})",
            f"- Support (column): {_fmt(m['column'])} ({_vs_rest(m.get('column_reduction'))})",
            f"- Risky faces: {int(np.sum(m['risky']))} · self-intersecting: {inter_txt}",
            f"- Update time: mesh {lat.get('mesh', 0):.1f} ms · with energies {lat.get('full', 0):.1f} ms",
        ])

    # ============================================================ lifecycle
    def stop(self) -> None:
        """Cancel any search, stop drawing and close the server."""
        self._opt_cancel.set()
        with self._cond:
            self._stopping = True
            self._cond.notify_all()
        if self._opt_thread is not None:
            self._opt_thread.join(30)
        self._worker.join(5)
        self.server.stop()


def run_app(rig, host: str = "127.0.0.1", port: int | None = None, open_browser: bool = False,
            block: bool = True, verbose: bool = True) -> App:
    """Serve the viewer of ``rig``.

    Parameters
    ----------
    rig : supportless.rig.Rig
    host : str
        ``127.0.0.1`` (default) serves only this computer; ``0.0.0.0`` the network.
    port : int or None
        ``None``: 8080, or the next free port. A given port must be free, else
        :class:`~supportless.errors.InputError` "port N on HOST is taken; use --port N".
    open_browser : bool
        Open the page in the default browser.
    block : bool
        Serve until Ctrl-C (then stop and return the app); False returns at once.

    Returns
    -------
    app : App
        ``app.url``, ``app.port``, ``app.stop()``.
    """
    app = App(rig, host=host, port=port, verbose=verbose)
    logger.info("supportless viewer at %s", app.url)
    if open_browser:
        import webbrowser

        webbrowser.open(app.url)
    if block:
        print(f"supportless: viewing {rig.name} at {app.url} (Ctrl-C to stop)", flush=True)
        try:
            while True:
                time.sleep(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            app.stop()
    return app
