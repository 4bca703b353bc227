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

This is the first piece of searching the orientation with the pose (the
search itself does not use it yet).
"""

from __future__ import annotations

import numpy as np

from .energies.overhang import overhang_energy

__all__ = ["candidate_ups", "rank_ups", "rotation_between"]


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
    k = min(clusters, len(F))
    centroids, labels = kmeans2(unit, k, seed=rng if rng is not None else np.random.default_rng(0),
                                minit="++")
    cluster_down = _unit_rows(np.array([(unit[labels == c] * weight[labels == c, None]).sum(axis=0)
                                        for c in range(k)]))
    # a face printed facing down rests on the plate: the printing direction is minus its normal
    return _dedupe(np.vstack([axes, -hull_down, -cluster_down]), min_angle_deg)


def rank_ups(vertices: np.ndarray, faces: np.ndarray, ups: np.ndarray, overhang_angle: float = 45.0) -> np.ndarray:
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
