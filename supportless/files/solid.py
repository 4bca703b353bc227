"""The solid a surface stands for: an open or non-manifold surface (a scan, a sculpt) closed into one to print."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..base.errors import InputError
from .meshes import check_closed_surface, check_not_flat
from .printbody import print_body

__all__ = ["closed_solid"]


def closed_solid(V: np.ndarray, F: np.ndarray, path, notes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """A 3D surface that is not closed (a scan or sculpt with holes, shells through each other) made into the
    closed solid to print (:func:`~supportless.files.printbody.print_body`), with one line appended to ``notes``; others as they are.

    Parameters
    ----------
    V : (n, d) float64
    F : (f, 3) int64
    path : str or os.PathLike
        The file, named in errors.
    notes : list of str
        Gains one line when the surface was closed.

    Returns
    -------
    V, F : the closed surface (the input when it was closed already, planar or flat).

    Raises
    ------
    InputError
        A flat mesh (:func:`~supportless.files.meshes.check_not_flat`), or one that cannot be closed.
    """
    if V.shape[1] != 3 or np.all(V[:, 2] == 0):
        return V, F
    check_not_flat(V, F, path)
    try:
        check_closed_surface(F)
        return V, F
    except InputError as exc:
        reason = exc.reason
    try:
        body = print_body(V, F, np.zeros(len(F), np.int64), np.ones((len(V), 1)), [Path(path).stem])
    except InputError:
        raise InputError(path, f"{reason}; it could not be closed into a solid either") from None
    notes.append(f"the surface was not closed ({reason.split(';')[0]}): made a closed solid of it ("
                 + "; ".join(line for line in body.log if not line.startswith("warning")) + ")")
    return body.vertices, body.faces
