"""The files of a pose: pose files saved and loaded, the posed mesh exported, in the frame it is shown in.

:class:`PoseFiles` is the part of :class:`~supportless.apps.ui.state.EditorState`
that reads and writes: only inside its working folder (:meth:`PoseFiles.resolve_path`),
never over a file, a pose file with its print rotation, print frame and locked
bones, a mesh standing or as printed (:data:`FRAMES`), to a path or as the
bytes of a download.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...base.errors import InputError
from ...base.geometry import place_on_plate, print_pose, print_transform
from ...base.scratch import file_bytes, scratch_dir
from ...files import posefile
from ...files.meshes import write_mesh
from .editing import _check_rotation

__all__ = ["FRAMES", "PoseFiles"]

#: The frames a pose is shown or written in: standing as the input stood, or as printed.
FRAMES = ("standing", "print")


def _check_frame(frame: str) -> str:
    if frame not in FRAMES:
        raise ValueError(f"frame must be one of {FRAMES}, not {frame!r}")
    return frame


class PoseFiles:
    """Pose files and posed meshes of the current pose, inside the working folder.

    A mixin of :class:`~supportless.apps.ui.state.EditorState`, which sets what
    it works on: ``rig``, ``workdir``, ``print_frame`` (how meshes are
    written), ``settings`` and ``objective`` (saved with a pose), and the pose
    (``get_pose``, ``get_angles``, ``set_angles``: :class:`~supportless.apps.ui.editing.PoseEditing`),
    ``update_settings`` (a loaded pose's locked bones).
    """

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
