"""TetGen (AGPL, through ``igl.copyleft.tetgen``): volume meshes of a closed surface.

Each call runs in a child process (:func:`supportless.base.isolated.run_isolated`):
TetGen aborts or segfaults on some surfaces that cut themselves, prints
even when asked to be quiet, and writes ``tetgen-tmpfile_skipped.*`` files
into the working folder; in the child all three stay there.
"""

from __future__ import annotations

import numpy as np

from ..base.isolated import run_isolated

__all__ = ["tetgen_surface", "tetgen_with_skeleton"]


def tetgen_surface(vertices: np.ndarray, faces: np.ndarray, flags: str) -> tuple[np.ndarray, np.ndarray]:
    """TetGen's volume mesh of a closed surface.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    flags : str
        TetGen switches ("pq2YQ").

    Returns
    -------
    tet_vertices : (t, 3) float64
    tets : (k, 4) int64

    Raises
    ------
    supportless.base.isolated.NativeFailure
        When TetGen fails, crashes or makes no tetrahedra.
    """
    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    return run_isolated(_surface, V, F, flags, what="TetGen")


def tetgen_with_skeleton(vertices: np.ndarray, faces: np.ndarray, joints: np.ndarray, bones: np.ndarray,
                         samples_per_bone: int, flags: str) -> tuple[np.ndarray, np.ndarray]:
    """TetGen's volume mesh of a closed surface with points along the bones inside.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    joints : (j, 3) float64
    bones : (m, 2) int64
    samples_per_bone : int
    flags : str

    Returns
    -------
    tet_vertices : (t, 3) float64
    tets : (k, 4) int64

    Raises
    ------
    supportless.base.isolated.NativeFailure
    """
    args = (np.ascontiguousarray(vertices, np.float64), np.ascontiguousarray(faces, np.int64),
            np.ascontiguousarray(joints, np.float64), np.ascontiguousarray(bones, np.int64), int(samples_per_bone),
            flags)
    return run_isolated(_with_skeleton, *args, what="TetGen")


def _surface(V, F, flags):
    import igl
    import igl.copyleft.tetgen  # noqa: F401  (registers the submodule)

    out = igl.copyleft.tetgen.tetrahedralize(V, F, flags=flags)
    TV, TT = np.asarray(out[0], np.float64), np.asarray(out[1], np.int64)
    if len(TT) == 0:
        raise RuntimeError("no tetrahedra")
    return TV, TT


def _with_skeleton(V, F, C, BE, samples, flags):
    import igl
    import igl.copyleft.tetgen  # noqa: F401

    TV, TT, _ = igl.copyleft.tetgen.mesh_with_skeleton(V, F, C, np.zeros(0, np.int64), BE,
                                                       np.zeros((0, 2), np.int64), samples, flags)
    return np.asarray(TV, np.float64), np.asarray(TT, np.int64)
