"""Which way is up in a file that does not say: the format's convention, or the flat base the model was cut to stand on.

Print files (STL, 3MF) are written +Z up by every slicer and model site;
graphics files (OBJ, OFF, PLY) and glTF are +Y up by convention. A figure
made to be printed often has a flat base — a plinth, the cut under a bust — and
a file may hold it in any direction: when the conventional bottom is no flat
base of its own and one plane of the convex hull carries a large share of the
surface (:data:`FLAT_BASE_SHARE`), clearly more than that bottom
(:data:`FLAT_BASE_LEAD` times), the model stands on that plane.
``--up`` always overrides the guess.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["CONVENTIONAL_UP", "FLAT_BASE_LEAD", "FLAT_BASE_SHARE", "contact_shares", "guess_up"]

#: Up direction each file format is written with, by suffix (lower case).
CONVENTIONAL_UP = {".stl": "z", ".3mf": "z", ".obj": "y", ".off": "y", ".ply": "y", ".glb": "y", ".gltf": "y",
                   ".mesh": "y"}
#: Share of the surface area a plane of the convex hull must carry to be read as a flat base (a bottom
#: carrying this much keeps the convention).
FLAT_BASE_SHARE = 0.05
#: A flat base replaces the convention's up only when it carries this many times the conventional bottom's share.
FLAT_BASE_LEAD = 2.0
#: A face lies on a hull plane when it is this close to it (share of the model's largest extent) ...
_PLANE_TOLERANCE = 0.005
#: ... and its normal is within about 18 degrees of the plane's outward normal.
_NORMAL_COS = 0.95
_AXIS_NAMES = {(1, 0, 0): "+X", (-1, 0, 0): "-X", (0, 1, 0): "+Y", (0, -1, 0): "-Y", (0, 0, 1): "+Z",
               (0, 0, -1): "-Z"}


def contact_shares(vertices: np.ndarray, faces: np.ndarray, min_share: float = 0.0,
                   chunk: int = 8192) -> tuple[np.ndarray, np.ndarray]:
    """The planes the model can rest on (its convex hull's faces) and the share of its surface lying on each.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    min_share : float
        Only hull planes whose own face (coplanar hull triangles merged) is at least this share of the
        model's surface area: a plane cannot carry more of the surface than its hull face's area.
    chunk : int
        Faces compared with the hull planes at a time (memory ``chunk`` x planes).

    Returns
    -------
    normals : (h, 3) float64
        Outward unit normals of the hull's planes, largest share first.
    shares : (h,) float64
        Area of the model's faces lying on each plane (within :data:`_PLANE_TOLERANCE` of the largest
        extent, facing out), over the whole surface area; every face counts for at most one plane.
    """
    V = np.asarray(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    T = V[F]
    n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    area = np.linalg.norm(n, axis=1) / 2
    total = area.sum()
    if not total > 0:
        return np.zeros((0, 3)), np.zeros(0)
    keep = area > 0
    normal = n[keep] / (2 * area[keep, None])
    center, area = T[keep].mean(axis=1), area[keep]
    N, d = _hull_planes(V, F, min_share * total)
    if len(N) == 0:
        return np.zeros((0, 3)), np.zeros(0)
    tol = _PLANE_TOLERANCE * float(np.ptp(V, axis=0).max())
    acc = np.zeros(len(N))
    for s in range(0, len(center), chunk):
        gap = d[None, :] - center[s:s + chunk] @ N.T  # >= 0 inside the hull
        gap[(gap > tol) | (normal[s:s + chunk] @ N.T < _NORMAL_COS)] = np.inf
        best = np.argmin(gap, axis=1)
        on = np.isfinite(gap[np.arange(len(best)), best])
        np.add.at(acc, best[on], area[s:s + chunk][on])
    order = np.argsort(-acc, kind="stable")
    return N[order], acc[order] / total


def _hull_planes(V: np.ndarray, F: np.ndarray, min_area: float) -> tuple[np.ndarray, np.ndarray]:
    """Outward normals ``(h, 3)`` and offsets ``(h,)`` of the convex hull's faces (coplanar triangles merged)
    of at least ``min_area``."""
    import trimesh

    hull = trimesh.Trimesh(V, F, process=False).convex_hull
    normals, offsets, areas = [], [], []
    grouped = np.zeros(len(hull.faces), bool)
    if len(hull.facets):  # trimesh gives None for the facets' normals when there are no facets
        for facet, normal, origin, a in zip(hull.facets, hull.facets_normal, hull.facets_origin, hull.facets_area):
            grouped[facet] = True
            normals.append(normal), offsets.append(origin @ normal), areas.append(a)
    lone = ~grouped
    normals += list(hull.face_normals[lone])
    offsets += list(np.einsum("ij,ij->i", hull.triangles_center[lone], hull.face_normals[lone]))
    areas += list(hull.area_faces[lone])
    big = np.asarray(areas) >= min_area
    return np.asarray(normals, np.float64).reshape(-1, 3)[big], np.asarray(offsets, np.float64)[big]


def guess_up(vertices: np.ndarray, faces: np.ndarray, path=None) -> tuple[np.ndarray, str]:
    """The printing direction of a model whose user gave none.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    path : str or os.PathLike, optional
        The file: its suffix gives the convention (:data:`CONVENTIONAL_UP`; +Y when unknown).

    Returns
    -------
    up : (3,) float64
        Unit vector.
    reason : str
        One line for the user: the direction and why, and how to choose another.
    """
    suffix = Path(str(path)).suffix.lower() if path is not None else ""
    axis = CONVENTIONAL_UP.get(suffix, "y")
    up = np.zeros(3)
    up["xyz".index(axis)] = 1.0
    kind = f"as {suffix[1:].upper()} files are written" if suffix in CONVENTIONAL_UP else "the usual convention"
    reason = f"printing direction {_name(up)} ({kind}; --up chooses another)"
    V = np.asarray(vertices, np.float64)
    if V.ndim != 2 or V.shape[1] != 3 or len(faces) == 0:
        return up, reason
    normals, shares = contact_shares(V, faces, FLAT_BASE_SHARE / FLAT_BASE_LEAD)
    if len(shares) == 0 or shares[0] < FLAT_BASE_SHARE:
        return up, reason
    below = shares[normals @ -up > 1 - 1e-3]
    conventional = float(below.max()) if len(below) else 0.0
    if conventional >= FLAT_BASE_SHARE or shares[0] < FLAT_BASE_LEAD * conventional:
        return up, reason  # it stands on a flat bottom as written, or no plane clearly beats that bottom
    base = -normals[0]
    tilt = np.degrees(np.arccos(np.clip(base @ up, -1, 1)))
    return base, (f"printing direction {_name(base)}, {tilt:.0f} degrees from {_name(up)}: the model stands on its "
                  f"flat base ({100 * shares[0]:.0f} % of its surface; --up chooses another)")


def _name(v: np.ndarray) -> str:
    """``+Z`` for an axis, ``(0.33, 0.94, 0.00)`` otherwise."""
    key = tuple(int(round(c)) for c in v)
    if np.allclose(v, key, atol=1e-9) and key in _AXIS_NAMES:
        return _AXIS_NAMES[key]
    return "(" + ", ".join(f"{c:.2f}" for c in v) + ")"
