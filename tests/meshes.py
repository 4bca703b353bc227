"""Small test meshes shared by the energy tests (boxes, unions, planar grids)."""

import numpy as np
import trimesh


def box_mesh(lo, hi) -> trimesh.Trimesh:
    """Axis-aligned box from corner ``lo`` to corner ``hi``."""
    return trimesh.creation.box(bounds=[lo, hi])


def box(lo=(0.0, 0.0, 0.0), hi=(1.0, 1.0, 1.0)):
    """Axis-aligned box as ``(V (8, 3) float64, F (12, 3) int64)``."""
    m = box_mesh(lo, hi)
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


def union(*meshes):
    """Boolean union (manifold3d) of trimesh meshes or ``(V, F)`` pairs, as ``(V, F)``."""
    ms = [m if isinstance(m, trimesh.Trimesh) else trimesh.Trimesh(*m, process=False) for m in meshes]
    u = trimesh.boolean.union(ms, engine="manifold")
    assert u.is_watertight
    return np.asarray(u.vertices, float), np.asarray(u.faces, np.int64)


def t_shape():
    """Stem 1x1x3 on the plate (z up), arm 4x1x1 on top; arm undersides (area 3) at z=2."""
    return union(box([-0.5, -0.5, 0], [0.5, 0.5, 3]), box([-2, -0.5, 2], [2, 0.5, 3]))


def cells_mesh(cells):
    """2D counter-clockwise triangle mesh of unit grid cells ``(x, y)`` (welded)."""
    idx, verts, faces = {}, [], []

    def vid(p):
        if p not in idx:
            idx[p] = len(verts)
            verts.append(p)
        return idx[p]

    for x, y in cells:
        a, b, c, d = vid((x, y)), vid((x + 1, y)), vid((x + 1, y + 1)), vid((x, y + 1))
        faces += [(a, b, c), (a, c, d)]
    return np.array(verts, float), np.array(faces, np.int64)
