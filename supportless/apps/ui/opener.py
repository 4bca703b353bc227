"""Models opened from the page: uploaded files, checked and kept, then prepared as the CLI prepares them.

A page sends one file at a time (the upload button, or each file of a drop).
:class:`Uploads` keeps them in a folder of its own (never the user's folder):
a skeleton (``.tgf``) waits for the mesh it belongs to; a mesh or a glTF asset
is a model to open. Every file is checked as the command line checks a path
(its kind by extension, its size, a name without folders) and a bad one is a
:class:`~supportless.base.errors.InputError` of one line.

:func:`prepare_model` reads and prepares the rig exactly as ``supportless view
MODEL`` does (:func:`supportless.rig.load.load_rig`, then the print frame).
"""

from __future__ import annotations

import re
import shutil
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ...base.errors import InputError

__all__ = ["MAX_UPLOAD_BYTES", "MODEL_SUFFIXES", "OpenOptions", "SKELETON_SUFFIXES", "Uploads", "prepare_model"]

#: Files a page may open as a model: rigged glTF, or a surface mesh (its skeleton uploaded with it, or built).
MODEL_SUFFIXES = (".glb", ".gltf", ".obj", ".stl", ".ply", ".off", ".3mf")
#: Skeleton files, kept for the mesh uploaded with them.
SKELETON_SUFFIXES = (".tgf",)
#: The largest file a page may send (a 5-million-triangle binary STL is 250 MB).
MAX_UPLOAD_BYTES = 512 * 1024 * 1024


@dataclass(frozen=True)
class OpenOptions:
    """How a model opened from the page is read: the options the ``view`` command was given.

    Attributes
    ----------
    up : str
        Printing direction (``"auto"``: the file's convention or its flat base).
    height_mm : float or None
        Printed height of the rest pose (None: the default).
    keep_units : bool
        Print at the file's own size.
    cache : bool
        Read and write the rig cache.
    cache_dir : str or None
    """

    up: str = "auto"
    height_mm: float | None = None
    keep_units: bool = False
    cache: bool = True
    cache_dir: str | None = None


def _safe_name(name: str) -> str:
    """The file name of an upload, folders and unusual characters dropped (``../a b.obj`` -> ``a_b.obj``)."""
    base = re.split(r"[\\/]", str(name))[-1]
    base = re.sub(r"[^A-Za-z0-9._-]+", "_", base).lstrip(".")
    return base[:120] or "upload"


@dataclass
class Uploads:
    """Files uploaded from the page, kept in a private temporary folder.

    Attributes
    ----------
    folder : pathlib.Path
        Where they are kept (removed by :meth:`close`).
    skeleton : pathlib.Path or None
        The last skeleton uploaded, waiting for its mesh.
    """

    folder: Path = field(default_factory=lambda: Path(tempfile.mkdtemp(prefix="supportless-uploads-")))
    skeleton: Path | None = None
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def receive(self, name: str, content: bytes) -> Path | None:
        """Check and keep one uploaded file.

        Parameters
        ----------
        name : str
            The file's name as the page sent it.
        content : bytes

        Returns
        -------
        model : pathlib.Path or None
            The kept file when it is a model to open; None for a skeleton
            (kept as :attr:`skeleton` for the next mesh).

        Raises
        ------
        InputError
            An unknown kind of file, an empty or too large one (one line: which file, what is wrong, what to do).
        """
        safe = _safe_name(name)
        suffix = Path(safe).suffix.lower()
        if suffix not in MODEL_SUFFIXES + SKELETON_SUFFIXES:
            raise InputError(None, f"{name}: not a model the app opens; send a rigged glTF (.glb, .gltf) or a mesh "
                             f"({', '.join(MODEL_SUFFIXES[2:])}) with its .tgf skeleton")
        if not content:
            raise InputError(None, f"{name}: the file is empty; send the file again")
        if len(content) > MAX_UPLOAD_BYTES:
            raise InputError(None, f"{name}: {len(content) / 2**20:.0f} MB is more than the "
                             f"{MAX_UPLOAD_BYTES // 2**20} MB a page may send; open it with `supportless view FILE`")
        with self._lock:
            path = self.folder / safe
            partial = path.with_name(path.name + ".part")
            partial.write_bytes(content)
            partial.replace(path)  # never a half-written file under the model's name
            if suffix in SKELETON_SUFFIXES:
                self.skeleton = path
                return None
            return path

    def skeleton_for(self, model: Path) -> Path | None:
        """The skeleton to open ``model`` with: the one uploaded before it (then forgotten), None for glTF."""
        with self._lock:
            if model.suffix.lower() in (".glb", ".gltf"):
                return None
            skeleton, self.skeleton = self.skeleton, None
            return skeleton

    def close(self) -> None:
        """Remove the folder and every file in it."""
        shutil.rmtree(self.folder, ignore_errors=True)


def prepare_model(model: Path, skeleton: Path | None, options: OpenOptions,
                  progress: Callable[[str], None] | None = None):
    """Read and prepare a model as ``supportless view MODEL`` does.

    Parameters
    ----------
    model : pathlib.Path
    skeleton : pathlib.Path or None
        Its TGF skeleton; None: the model's own (glTF) or one built from the shape.
    options : OpenOptions
    progress : callable(str), optional
        Told each step of the preparation.

    Returns
    -------
    rig : supportless.rig.rig.Rig
    frame : supportless.files.printframe.PrintFrame
        How the model is printed (its height in millimetres).

    Raises
    ------
    supportless.base.errors.SupportlessError
        A bad file, said in one line.
    """
    from ...files.printframe import rig_print_frame
    from ...rig.load import load_rig

    rig = load_rig(model, skeleton, options.up, cache=options.cache, cache_dir=options.cache_dir, progress=progress)
    return rig, rig_print_frame(rig, options.height_mm, options.keep_units)
