"""Print orientations: which way up a posed model needs the least support.

Turning a model on the plate is what a user does before posing it, and what
slicers' auto-orienters do: try a few dozen directions and keep the cheapest.
:func:`candidate_ups` proposes directions the way they do (the six axes, the
normals of the convex hull's faces — a hull face is a flat side the model can
rest on — and the area-weighted mean normals of the surface's main face
clusters); :func:`rank_ups` scores them with a support estimate, which takes
the printing direction as an argument, so nothing is rotated;
:func:`rotation_between` gives the rotation that turns one direction into
another, to write the mesh in the print orientation.

The pose search turns the model too (``SearchSettings.orient == "free"``).
Two frames: the *display frame* is the model as it stands, where contact,
balance and the pose prior are judged; the *print frame* is the posed model
turned by a rotation R, where support is counted (``R @ u == up`` for the
display-frame direction ``u`` that prints upwards). A turn about ``up``
changes no support, so R has ``d - 1`` degrees of freedom: the search
varies R's rotation vector in the plane orthogonal to ``up``
(:func:`rotations_from_params`, the exponential map; an angle in 2D), and
starts particles at the best-ranked candidate directions
(:func:`seed_params`).
"""

from __future__ import annotations

import numpy as np

from ..base.geometry import row_groups
from ..energies.overhang import overhang_energy
from ..files.printer import SEARCH_OVERHANG_ANGLE

__all__ = ["candidate_ups", "orientation_params", "print_direction", "rank_ups", "rotation_between",
           "rotation_axis_angle", "rotations_from_params", "seed_params", "tangent_basis"]


def _unit_rows(X: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(X, axis=1, keepdims=True)
    return X[n[:, 0] > 0] / n[n[:, 0] > 0]


def _dedupe(U: np.ndarray, min_angle_deg: float) -> np.ndarray:
    """Keep directions at least ``min_angle_deg`` apart, first come first kept."""
    cos = np.cos(np.radians(min_angle_deg))
    kept: list[np.ndarray] = []
    for u in U:
        if all(u @ k < cos for k in kept):
            kept.append(u)
    return np.array(kept)


def candidate_ups(vertices: np.ndarray, faces: np.ndarray, hull_faces: int = 24, clusters: int = 12,
                  min_angle_deg: float = 10.0, rng: np.random.Generator | None = None) -> np.ndarray:
    """Printing directions worth trying for a closed surface.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    hull_faces : int
        The largest convex-hull faces taken (resting on one means printing
        along minus its outward normal).
    clusters : int
        Main face-normal clusters (k-means on area-weighted normals); each
        cluster's flat region printed facing down gives a candidate.
    min_angle_deg : float
        Candidates closer than this are merged (the first is kept).
    rng : numpy.random.Generator, optional
        For the clustering (default: ``default_rng(0)``).

    Returns
    -------
    ups : (k, 3) float64
        Unit directions, the six axes first (``+y`` first of all).
    """
    from scipy.cluster.vq import kmeans2
    from scipy.spatial import ConvexHull

    V = np.asarray(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    axes = np.array([[0, 1, 0], [0, -1, 0], [1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, 0, -1]], float)
    hull = ConvexHull(V)
    tri = V[hull.simplices]
    N = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(N, axis=1)
    centre = V.mean(axis=0)
    outward = np.sign(np.einsum("ij,ij->i", N, tri.mean(axis=1) - centre))
    hull_down = _unit_rows(N * outward[:, None])[np.argsort(-area[area > 0])][:hull_faces]
    Nf = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    weight = np.linalg.norm(Nf, axis=1)
    unit = Nf / np.where(weight > 0, weight, 1.0)[:, None]
    # a boxy model has fewer distinct normals than clusters: k-means would leave clusters empty (and say so on the
    # user's terminal), so it asks for at most as many as there are
    k = min(clusters, len(row_groups(np.round(unit, 12))[0]))
    centroids, labels = kmeans2(unit, k, seed=rng if rng is not None else np.random.default_rng(0),
                                minit="++")
    cluster_down = _unit_rows(np.array([(unit[labels == c] * weight[labels == c, None]).sum(axis=0)
                                        for c in range(k)]))
    # a face printed facing down rests on the plate: the printing direction is minus its normal
    return _dedupe(np.vstack([axes, -hull_down, -cluster_down]), min_angle_deg)


def rank_ups(vertices: np.ndarray, faces: np.ndarray, ups: np.ndarray, overhang_angle: float = SEARCH_OVERHANG_ANGLE) -> np.ndarray:
    """Support estimate of a surface printed along each direction.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    ups : (k, 3) float64
        Unit printing directions.
    overhang_angle : float
        Threshold, degrees from the plate.

    Returns
    -------
    support : (k,) float64
        The prism estimate (:func:`~supportless.energies.overhang.overhang_energy`)
        with the plate under the lowest point along each direction.
    """
    V = np.ascontiguousarray(vertices, np.float64)
    return np.array([overhang_energy(V, faces, u, overhang_angle) for u in np.asarray(ups, np.float64)])


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit vector ``a`` to unit vector ``b``.

    Parameters
    ----------
    a, b : (3,) float64

    Returns
    -------
    R : (3, 3) float64
        ``R @ a == b``; a half turn about an axis orthogonal to ``a`` when
        ``b == -a``.
    """
    a = np.asarray(a, np.float64) / np.linalg.norm(a)
    b = np.asarray(b, np.float64) / np.linalg.norm(b)
    v = np.cross(a, b)
    c = float(a @ b)
    if c < -1.0 + 1e-12:  # opposite: half turn about any axis orthogonal to a
        axis = np.cross(a, np.eye(3)[np.argmin(np.abs(a))])
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def tangent_basis(up: np.ndarray) -> np.ndarray:
    """Orthonormal directions orthogonal to ``up``.

    Parameters
    ----------
    up : (d,) float64
        Unit vector, d = 2 or 3.

    Returns
    -------
    basis : (d - 1, d) float64
        Rows orthogonal to ``up`` and to each other (in 3D ``basis[0] x
        basis[1] == up``).
    """
    up = np.asarray(up, np.float64)
    if up.shape == (2,):
        return np.array([[up[1], -up[0]]])
    a = np.cross(up, np.eye(3)[np.argmin(np.abs(up))])
    a /= np.linalg.norm(a)
    return np.stack([a, np.cross(up, a)])


def rotations_from_params(X: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Print rotations from the search's orientation variables.

    Parameters
    ----------
    X : (P, d - 1) float64
        3D: the rotation vector's coordinates in :func:`tangent_basis` (radians;
        a rotation vector orthogonal to ``up`` reaches every printing
        direction within length pi). 2D: the angle, counter-clockwise.
    up : (d,) float64

    Returns
    -------
    R : (P, d, d) float64
        Rotation matrices (the identity for ``X == 0``).
    """
    X = np.atleast_2d(np.asarray(X, np.float64))
    up = np.asarray(up, np.float64)
    if up.shape == (2,):
        c, s = np.cos(X[:, 0]), np.sin(X[:, 0])
        return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], 1)
    w = X @ tangent_basis(up)                                    # (P, 3) rotation vectors
    theta = np.linalg.norm(w, axis=1)
    k = w / np.where(theta > 0, theta, 1.0)[:, None]
    K = np.zeros((len(X), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    K -= K.transpose(0, 2, 1)
    s, c = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def orientation_params(R: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The orientation variables of a print rotation (inverse of :func:`rotations_from_params`).

    Parameters
    ----------
    R : (d, d) float64
        A rotation; in 3D its turn about ``up`` is dropped (the smallest
        rotation taking the same direction up is used).
    up : (d,) float64

    Returns
    -------
    x : (d - 1,) float64
    """
    R = np.asarray(R, np.float64)
    up = np.asarray(up, np.float64)
    if up.shape == (2,):
        return np.array([np.arctan2(R[1, 0], R[0, 0])])
    u = R.T @ up                                   # the display direction printed upwards
    c = float(np.clip(u @ up, -1.0, 1.0))
    axis = np.cross(u, up)
    n = np.linalg.norm(axis)
    basis = tangent_basis(up)
    if n < 1e-12:
        return np.zeros(2) if c > 0 else np.array([np.pi, 0.0])
    return np.arccos(c) * (basis @ (axis / n))


def print_direction(R: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The display-frame direction a print rotation turns upwards: ``R.T @ up``, (d,) float64."""
    return np.asarray(R, np.float64).T @ np.asarray(up, np.float64)


def rotation_axis_angle(R: np.ndarray) -> tuple[np.ndarray | None, float]:
    """Axis and angle (degrees) of a rotation; the axis is None in 2D (the angle is counter-clockwise)."""
    R = np.asarray(R, np.float64)
    if R.shape == (2, 2):
        return None, float(np.degrees(np.arctan2(R[1, 0], R[0, 0])))
    from scipy.spatial.transform import Rotation

    w = Rotation.from_matrix(R).as_rotvec()
    angle = float(np.linalg.norm(w))
    return (w / angle if angle > 0 else np.array([0.0, 0.0, 1.0])), float(np.degrees(angle))


def seed_params(vertices: np.ndarray, faces: np.ndarray, up: np.ndarray, count: int,
                overhang_angle: float = SEARCH_OVERHANG_ANGLE) -> np.ndarray:
    """Orientation variables of the ``count`` best candidate directions at a pose.

    Parameters
    ----------
    vertices : (n, d) float64
    faces : (f, 3) int64
        Triangles (3D) or the triangulated area (2D).
    up : (d,) float64
    count : int
    overhang_angle : float

    Returns
    -------
    X : (k, d - 1) float64
        ``k <= count`` rows, cheapest (by the prism estimate) first; upright
        (the zero row) is left out, the search starts there anyway.
        3D candidates come from :func:`candidate_ups`; 2D ones every 15 degrees.
    """
    up = np.asarray(up, np.float64)
    if count <= 0:
        return np.zeros((0, len(up) - 1))
    if len(up) == 2:
        X = np.radians(np.arange(15.0, 360.0, 15.0))[:, None]
        X = np.where(X > np.pi, X - 2 * np.pi, X)
        ups = np.einsum("pji,j->pi", rotations_from_params(X, up), up)
    else:
        ups = candidate_ups(vertices, faces)
        ups = ups[ups @ up < 1.0 - 1e-9]
        X = np.array([orientation_params(rotation_between(u, up), up) for u in ups]).reshape(-1, 2)
    order = np.argsort(rank_ups(vertices, faces, ups, overhang_angle), kind="stable")[:count]
    return X[order]
