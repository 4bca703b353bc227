"""Does a pose still stand, and does it touch the plate anywhere new?

Two checks of a posed model against its rest pose, both batched over poses:

* **New contacts** (:func:`new_contact_depth`): every part that stood clear of
  the build plate at rest must stay clear of it. A pose that puts a head, a
  knee or a tail down turns it into a new foot: the support estimate drops
  and the figure no longer looks like itself.
* **Balance** (:func:`stability_margin`): the centre of mass, projected along
  the printing direction, must lie inside the support polygon (the convex hull
  of the contact region), as in Prévost et al., *Make It Stand* (SIGGRAPH
  2013). The centre of mass of a skinned solid is linear in the bone
  transforms, so :func:`centre_of_mass_operator` precomputes it once per rig
  and :func:`centre_of_mass` costs one small product per pose.

In 2D the support polygon is an interval on the plate line.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..base.geometry import plane_basis
from ..base.threads import over

__all__ = ["centre_of_mass", "centre_of_mass_operator", "new_contact_depth", "stability_margin",
           "support_polygon"]


def centre_of_mass_operator(vertices: np.ndarray, elements: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per-bone moments that give the centre of mass of a skinned solid.

    With linear blend skinning every posed point is ``sum_b w_b T_b [x; 1]``,
    so the centre of mass of the posed solid (element centroids weighted by
    their rest volume) is ``sum_b T_b g_b`` with
    ``g_b = sum_i c_i w_ib [x_i; 1]`` and ``c_i`` the share of the volume
    carried by volume-mesh vertex ``i``.

    Parameters
    ----------
    vertices : (t, d) float64
        Volume-mesh vertices.
    elements : (k, d+1) int64
        Tetrahedra (triangles in 2D).
    weights : (t, m) float64
        Skinning weights of the volume-mesh vertices.

    Returns
    -------
    G : (m, d+1) float64
        ``centre_of_mass(transforms, G)`` is the posed centre of mass; at rest
        (identity transforms) it is the solid's centroid.
    """
    X = np.asarray(vertices, np.float64)
    E = np.asarray(elements, np.int64)
    d = X.shape[1]
    edges = X[E[:, 1:]] - X[E[:, :1]]  # (k, d, d)
    size = np.abs(np.linalg.det(edges))  # volume (area) times d!
    share = np.zeros(len(X))
    np.add.at(share, E.ravel(), np.repeat(size / (d + 1), d + 1))
    share /= size.sum()
    Xh = np.column_stack([X, np.ones(len(X))])  # (t, d+1)
    return np.asarray(weights, np.float64).T @ (share[:, None] * Xh)


def centre_of_mass(transforms: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Centre of mass of posed solids.

    Parameters
    ----------
    transforms : (P, m, d, d+1) or (m, d, d+1) float64
        Bone transforms.
    G : (m, d+1) float64
        From :func:`centre_of_mass_operator`.

    Returns
    -------
    com : (P, d) or (d,) float64
    """
    return np.einsum("...bij,bj->...i", transforms, G)


def support_polygon(points: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The support polygon of contact points: their convex hull seen along ``up``.

    Parameters
    ----------
    points : (c, d) float64
        The contact region (surface vertices on the plate).
    up : (d,) float64
        Unit printing direction.

    Returns
    -------
    polygon : (q, d-1) float64
        Hull corners in plate coordinates (``plane_basis(up)``),
        counter-clockwise in 3D; in 2D the two ends of the interval. A single
        point or a segment in 3D has ``q`` = 1 or 2.
    """
    B = plane_basis(np.asarray(up, np.float64))
    Q = np.asarray(points, np.float64) @ B.T
    if Q.shape[1] == 1:
        return np.array([[Q.min()], [Q.max()]])
    Q = np.unique(np.round(Q, 12), axis=0)
    if len(Q) < 3:
        return Q
    from scipy.spatial import ConvexHull, QhullError

    try:
        return Q[ConvexHull(Q).vertices]
    except QhullError:  # collinear contacts: the two extreme points
        axis = Q[np.argmax(np.linalg.norm(Q - Q[0], axis=1))] - Q[0]
        t = (Q - Q[0]) @ axis
        return Q[[np.argmin(t), np.argmax(t)]]


def stability_margin(com: np.ndarray, polygon: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Signed distance of the projected centre of mass to the support polygon's boundary.

    Parameters
    ----------
    com : (P, d) or (d,) float64
        Centres of mass.
    polygon : (q, d-1) float64
        From :func:`support_polygon`.
    up : (d,) float64
        Unit printing direction.

    Returns
    -------
    margin : (P,) float64 or float
        Positive inside (the model stands; larger is steadier), negative
        outside (it falls over), in the model's units. A polygon of one or two
        points has no inside: the margin is minus the distance to it.
    """
    com = np.asarray(com, np.float64)
    single = com.ndim == 1
    C = np.atleast_2d(com) @ plane_basis(np.asarray(up, np.float64)).T  # (P, d-1)
    poly = np.asarray(polygon, np.float64)
    if poly.shape[1] == 1:  # 2D: an interval
        out = np.minimum(C[:, 0] - poly[:, 0].min(), poly[:, 0].max() - C[:, 0])
    elif len(poly) == 1:
        out = -np.linalg.norm(C - poly[0], axis=1)
    else:
        a = poly
        b = np.roll(poly, -1, axis=0)
        if len(poly) == 2:
            a, b = poly[:1], poly[1:]
        ab = b - a  # (q, 2)
        ap = C[:, None, :] - a[None]  # (P, q, 2)
        t = np.clip(np.einsum("pqk,qk->pq", ap, ab) / np.einsum("qk,qk->q", ab, ab), 0.0, 1.0)
        dist = np.linalg.norm(ap - t[..., None] * ab[None], axis=2).min(axis=1)
        if len(poly) == 2:
            out = -dist
        else:  # counter-clockwise hull: inside is left of every edge
            cross = ab[None, :, 0] * ap[..., 1] - ab[None, :, 1] * ap[..., 0]
            out = np.where((cross >= 0).all(axis=1), dist, -dist)
    return float(out[0]) if single else out


def new_contact_depth(vertices: np.ndarray, up: np.ndarray, clear: np.ndarray, level: float) -> np.ndarray:
    """How far parts that stood clear of the plate come down to it.

    Parameters
    ----------
    vertices : (P, n, d) or (n, d) float64
        Posed surfaces, in the rest pose's frame (not re-placed on the plate).
    up : (d,) float64
        Unit printing direction.
    clear : (n,) bool
        The vertices that must stay clear (stood clear at rest).
    level : float
        The lowest height along ``up`` they may reach.

    Returns
    -------
    depth : (P,) float64 or float
        ``max(0, level - lowest clear vertex)``: 0 when nothing new touches.
    """
    V = np.asarray(vertices, np.float64)
    index = np.flatnonzero(clear)
    if V.ndim == 3 and V.shape[-1] == 3 and len(index):  # a batch: one compiled pass, no (P, n) heights
        return np.maximum(0.0, level - _lowest(V, index, np.ascontiguousarray(up, np.float64)))
    # heights first, then the clear ones: a mask on (P, n, d) would copy every clear vertex
    h = np.take(V @ np.asarray(up, np.float64), index, axis=-1)
    if h.shape[-1] == 0:
        out = np.zeros(h.shape[:-1])
    else:
        out = np.maximum(0.0, level - h.min(axis=-1))
    return float(out) if np.ndim(out) == 0 else out


def _lowest(V, index, up):
    """(P,) float64: the least height along ``up`` of the vertices ``index`` of each pose of ``V`` (P, n, 3)."""
    out = np.empty(V.shape[0])
    over(_lowest_of, V.shape[0], V, index, up, out)
    return out


@njit(cache=True, nogil=True)
def _lowest_of(V, index, up, out, lo, hi):  # pragma: no cover - compiled
    # fill out at the poses lo:hi (the same products and sums as ``V @ up``: x u0 + y u1 + z u2)
    for p in range(lo, hi):
        low = np.inf
        for k in range(index.shape[0]):
            i = index[k]
            low = min(low, V[p, i, 0] * up[0] + V[p, i, 1] * up[1] + V[p, i, 2] * up[2])
        out[p] = low
