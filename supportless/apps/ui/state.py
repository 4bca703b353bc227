"""The viewer's editing state, without a browser or a server.

:class:`EditorState` holds what the page edits and shows: the current pose and print rotation, the
selected bone, undo/redo, the search settings (one :class:`~supportless.search.settings.SearchSettings`), the
objective they define, the measures of a pose, pose and mesh files, and the pose search running in the
background. The web app (:mod:`supportless.apps.ui.app`) draws it and forwards the page's events to it.

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

import json
import logging
import threading
from pathlib import Path
from typing import Callable

import numpy as np

from ...base.errors import InputError
from ...base.geometry import place_on_plate, print_pose, print_transform
from ...base.kinematics import matrix_to_euler
from ...base.scratch import file_bytes, scratch_dir
from ...copyleft.cgal import intersecting_faces
from ...energies.overhang import risky_faces
from ...files import posefile
from ...files.meshes import write_mesh
from ...files.printframe import PrintFrame, rig_print_frame
from ...report.report import pose_measures, reduction
from ...search.objective import Objective
from ...search.optimizer import PoseResult, optimize
from ...search.orientation import print_direction, rotation_axis_angle
from ...search.settings import SearchSettings
from ...slicing.prusaslicer import find_prusa_slicer
from ...slicing.ranking import slice_choice_if_found
from .history import PoseHistory

__all__ = ["EditorState", "FRAMES", "REDUCED_MEASURES"]

logger = logging.getLogger("supportless.apps.ui")

#: Measures compared with the rest pose (``measures["reduction"]``, percent).
REDUCED_MEASURES = ("support_prism", "support_column", "risky_area")

#: The frames a pose is shown or written in: standing as the input stood, or as printed.
FRAMES = ("standing", "print")


def _check_rotation(rotation, dim: int) -> np.ndarray:
    """``rotation`` as a (dim, dim) float64 rotation matrix; ValueError otherwise."""
    R = np.array(rotation, np.float64)
    if R.shape != (dim, dim) or not np.allclose(R @ R.T, np.eye(dim), atol=1e-6) or np.linalg.det(R) < 0:
        raise ValueError(f"the print rotation must be a {dim}x{dim} rotation matrix")
    return R


def _check_frame(frame: str) -> str:
    if frame not in FRAMES:
        raise ValueError(f"frame must be one of {FRAMES}, not {frame!r}")
    return frame


class EditorState:
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

    # ----------------------------------------------------------------- pose
    def get_angles(self) -> np.ndarray:
        """A copy of the current pose.

        Returns
        -------
        angles : (m, 3) float64
            XYZ Euler angles per bone, radians.
        """
        with self._lock:
            return self._angles.copy()

    def get_rotation(self) -> np.ndarray:
        """A copy of the current print rotation R (the identity until a search turns the model).

        Returns
        -------
        rotation : (d, d) float64
            The pose is printed as ``vertices @ R.T``, then put on the plate.
        """
        with self._lock:
            return self._rotation.copy()

    def get_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The current pose and print rotation, read together (copies).

        Returns
        -------
        angles : (m, 3) float64
            Radians.
        rotation : (d, d) float64
            The print rotation R.
        """
        with self._lock:
            return self._angles.copy(), self._rotation.copy()

    @property
    def selected(self) -> int:
        """The bone the sliders and the gizmo act on (0-based)."""
        return self._selected

    def set_angles(self, angles, *, rotation=None, record: bool = True, key=None,
                   origin: str | None = None) -> None:
        """Replace the whole pose (the print rotation stays unless given).

        Parameters
        ----------
        angles : (m, 3) float64
            Radians.
        rotation : (d, d) float64, optional
            A new print rotation R (default: keep the current one).
        record : bool
            Make it an undo step.
        key : hashable, optional
            The control making the edit: edits of one control in a row are one
            undo step (see :class:`PoseHistory`).
        origin : str, optional
            Passed on to the listeners.

        Raises
        ------
        ValueError
            When ``angles`` is not one triple per bone, or ``rotation`` not a
            rotation of the rig's dimension.
        """
        angles = np.array(angles, np.float64)
        if angles.shape != self._angles.shape:
            raise ValueError(f"pose has shape {angles.shape}, the rig needs {self._angles.shape}")
        if not np.all(np.isfinite(angles)):
            raise ValueError("pose angles must be finite numbers")
        R = None if rotation is None else _check_rotation(rotation, self.rig.dim)
        with self._lock:
            if record:
                self.history.record((self._angles, self._rotation), key)
            self._angles = angles
            if R is not None:
                self._rotation = R
        self._notify("pose", origin=origin)

    def set_rotation(self, rotation, *, record: bool = True, origin: str | None = None) -> None:
        """Replace the print rotation R, keeping the angles (see :meth:`set_angles`).

        Parameters
        ----------
        rotation : (d, d) float64
        """
        with self._lock:
            angles = self._angles.copy()
        self.set_angles(angles, rotation=rotation, record=record, origin=origin)

    def set_bone_angles(self, bone: int, degrees, *, key=None, origin: str | None = None) -> None:
        """Set one bone's Euler angles.

        Parameters
        ----------
        bone : int
            0-based.
        degrees : (3,) float64
            XYZ Euler angles relative to the parent bone, degrees.
        key : hashable, optional
            Undo grouping (default: one step per call unless the same bone is
            edited again within a second).
        """
        bone = self._check_bone(bone)
        angles = self.get_angles()
        angles[bone] = np.radians(np.asarray(degrees, np.float64))
        self.set_angles(angles, key=("bone", bone) if key is None else key, origin=origin)

    def _check_bone(self, bone) -> int:
        """A 0-based bone index of the rig, or ValueError (a client may send anything)."""
        if isinstance(bone, bool) or not isinstance(bone, (int, np.integer)) or not 0 <= bone < self.rig.bone_count:
            raise ValueError(f"bone {bone!r} is not one of this rig's {self.rig.bone_count} bones")
        return int(bone)

    def set_bone_rotation(self, bone: int, rotation, *, record: bool = False, origin: str | None = "gizmo") -> None:
        """Turn a bone to a rotation given in world coordinates (what the gizmo shows).

        Parameters
        ----------
        bone : int
            0-based.
        rotation : (3, 3) float64
            The bone's rotation in the world; it becomes Euler angles relative
            to the parent bone. A planar rig keeps the angle about z.
        record : bool
            Make it an undo step (a drag records once, when it starts).
        """
        bone = self._check_bone(bone)
        R = np.asarray(rotation, np.float64)
        d = self.rig.dim
        if R.ndim != 2 or R.shape[0] != R.shape[1] or R.shape[0] < d or not np.all(np.isfinite(R)):
            raise ValueError("a bone's rotation must be a finite 3x3 matrix")
        angles = self.get_angles()
        parent = int(self.rig.parents[bone])
        local = R[:d, :d] if parent < 0 else self.rig.transforms(angles)[parent][:, :d].T @ R[:d, :d]
        angles[bone] = [0.0, 0.0, np.arctan2(local[1, 0], local[0, 0])] if d == 2 else matrix_to_euler(local)
        self.set_angles(angles, record=record, origin=origin)

    def select_bone(self, bone: int) -> None:
        """Select the bone the sliders and the gizmo act on (0-based).

        Raises
        ------
        ValueError
            For a bone number outside ``0..m-1``.
        """
        self._selected = self._check_bone(bone)
        self._notify("selection")

    def checkpoint(self) -> None:
        """Make the current pose an undo step (a drag calls it once, when it starts)."""
        with self._lock:
            self.history.record((self._angles, self._rotation))

    def _step(self, go: Callable[[tuple], tuple | None]) -> bool:
        with self._lock:
            pose = go((self._angles, self._rotation))
            if pose is None:
                return False
            self._angles, self._rotation = pose
        self._notify("pose", origin=None)
        return True

    def undo(self) -> bool:
        """Go back one edit; False when there is nothing to undo."""
        return self._step(self.history.undo)

    def redo(self) -> bool:
        """Redo the last undone edit; False when there is none."""
        return self._step(self.history.redo)

    def reset(self) -> None:
        """Back to the rest pose, printed as it stands (R = identity; undoable)."""
        self.set_angles(self.rig.rest_angles(), rotation=np.eye(self.rig.dim))

    # ---------------------------------------------------------------- files
    def resolve_path(self, path, *, new: bool = False) -> Path:
        """``path`` inside :attr:`workdir`, or :class:`~supportless.base.errors.InputError`.

        Relative to the folder, ``..`` and symbolic links resolved; one that leaves it (elsewhere, ``..``,
        ``~``, a link out, a sibling folder) is refused alike whether or not it exists. With ``new`` (a file
        to write) its folder must exist and a taken name becomes ``NAME-1.ext``, ...: nothing is overwritten.
        """
        text = str(path).strip()
        root = self.workdir.resolve()
        p = (root / text).resolve() if text and not text.startswith("~") else None
        if p is None or p == root or not p.is_relative_to(root):
            raise InputError(None, f"{text!r}: the app reads and writes files only inside {root}; give a name "
                                   "in that folder")
        if not new:
            return p
        if not p.parent.is_dir():
            raise InputError(None, f"{text!r}: the folder {p.parent} does not exist")
        candidate, k = p, 0
        while candidate.exists() or candidate.is_symlink():
            k += 1
            candidate = p.with_name(f"{p.stem}-{k}{p.suffix}")
        return candidate

    def save_pose(self, path) -> Path:
        """Write the current pose and print rotation as a pose JSON file (with its objective and the settings).

        Returns
        -------
        path : pathlib.Path
            Where it was written.
        """
        p = self.resolve_path(path, new=True)
        angles, R = self.get_pose()
        extra = {"objective": float(self.objective(angles, R)), "settings": self.settings.to_dict()}
        posefile.write_pose(p, angles, self.rig.bones, self.rig.joints, extra=extra | self._pose_extra(), rotation=R,
                            tree=self.rig.tree)
        return p

    def _pose_extra(self) -> dict:
        """What a pose file keeps beside the pose: the print frame and the locked bones (the search's ``fix``)."""
        return {"print_frame": self.print_frame.to_dict(), "locked": list(self.settings.fix)}

    def load_pose(self, path) -> Path:
        """Make a pose file written for this skeleton the current pose and print rotation (undoable).

        A file without a print rotation is printed as it stands (R = identity).

        Returns
        -------
        path : pathlib.Path
            The file read.

        Raises
        ------
        SupportlessError
            For a missing file, one that is not a pose, a pose of another
            skeleton, or a ``print_rotation`` that is not a rotation.
        """
        p = self.resolve_path(path)
        self._load_pose_file(p)
        return p

    def _load_pose_file(self, p: Path) -> None:
        angles = posefile.read_pose(p, self.rig.bones, tree=self.rig.tree, root_bone=self.rig.root_bone)
        rotation = posefile.read_print_rotation(p, self.rig.dim)
        if isinstance(locked := json.loads(p.read_text()).get("locked"), list):  # the bones locked when saved
            self.update_settings(fix=",".join(str(x) for x in locked))
        self.set_angles(angles, rotation=rotation)

    def load_pose_bytes(self, name: str, content: bytes) -> None:
        """Load an uploaded pose file's content (same checks as :meth:`load_pose`)."""
        with scratch_dir("supportless-ui-") as tmp:
            p = Path(tmp) / (Path(name).name or "pose.json")
            p.write_bytes(content)
            self._load_pose_file(p)

    def pose_bytes(self) -> bytes:
        """The current pose and print rotation as a pose JSON file's bytes."""
        angles, R = self.get_pose()
        return file_bytes("pose.json", lambda p: posefile.write_pose(p, angles, self.rig.bones, self.rig.joints,
                                                                 rotation=R, tree=self.rig.tree,
                                                                 extra=self._pose_extra()))

    def posed_on_plate(self) -> np.ndarray:
        """The current posed surface standing, its lowest point on the plate.

        Returns
        -------
        vertices : (n, d) float64
        """
        return place_on_plate(self.rig.pose(self.get_angles()), self.rig.up)

    def frame_transform(self, frame: str, vertices: np.ndarray | None = None,
                        rotation: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """How a standing surface is shown or written in a frame: ``shown = vertices @ Q.T + shift``.

        Parameters
        ----------
        frame : {"standing", "print"}
            ``standing``: as it is (Q = identity, no shift); ``print``: turned by
            the print rotation about its bounding-box centre, lowest point on
            the plate (:func:`supportless.base.geometry.print_transform`).
        vertices : (n, d) float64, optional
            The standing posed surface (default: that of the current pose).
        rotation : (d, d) float64, optional
            The print rotation (default: the current one).

        Returns
        -------
        Q : (d, d) float64
        shift : (d,) float64
            Apply them to the skeleton's joints too.
        """
        d = self.rig.dim
        if _check_frame(frame) == "standing":
            return np.eye(d), np.zeros(d)
        angles, R = self.get_pose()
        R = R if rotation is None else _check_rotation(rotation, d)
        V = self.rig.pose(angles) if vertices is None else np.asarray(vertices, np.float64)
        return R, print_transform(V, R, self.rig.up)

    def printed_on_plate(self) -> np.ndarray:
        """The current posed surface as printed: turned by R, its lowest point on the plate.

        Returns
        -------
        vertices : (n, d) float64
            ``print_pose(rig.pose(angles), R, up)``: the mesh to slice.
        """
        angles, R = self.get_pose()
        return print_pose(self.rig.pose(angles), R, self.rig.up)

    def _frame_vertices(self, frame: str) -> np.ndarray:
        return self.printed_on_plate() if _check_frame(frame) == "print" else self.posed_on_plate()

    def export_mesh(self, path, frame: str = "print") -> Path:
        """Write the posed mesh as STL, 3MF, OBJ or PLY, by the extension.

        Parameters
        ----------
        path : str or os.PathLike
        frame : {"print", "standing"}
            As printed (default, :meth:`printed_on_plate`: what to slice) or
            standing (:meth:`posed_on_plate`); on the plate either way, in
            the print frame (:attr:`print_frame`: +Z up, millimetres).

        Returns
        -------
        path : pathlib.Path
            Where it was written.
        """
        p = self.resolve_path(path, new=True)
        write_mesh(p, self.print_frame.place(self._frame_vertices(frame)), self.rig.faces)
        return p

    def mesh_bytes(self, fmt: str, frame: str = "print") -> bytes:
        """The posed mesh (on the plate, by default as printed) as a file's bytes, ``fmt`` in stl/3mf/obj/ply."""
        V = self.print_frame.place(self._frame_vertices(frame))
        return file_bytes(f"mesh.{fmt}", lambda p: write_mesh(p, V, self.rig.faces))

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
            pairs = intersecting_faces(V, rig.faces)
            out["intersecting_face_pairs"] = len(pairs)
            out["intersecting_faces"] = np.unique(pairs)
        if rest is not None:
            out["reduction"] = {k: reduction(rest[k], out[k]) for k in REDUCED_MEASURES}
        return out

    # ---------------------------------------------------------------- search
    @property
    def optimizing(self) -> bool:
        """True while a search runs."""
        t = self._search
        return t is not None and t.is_alive()

    def start_optimize(self, **overrides) -> bool:
        """Run :func:`supportless.search.optimizer.optimize` from the current pose in a background thread.

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
