"""A model of the support filament PrusaSlicer lays down, fitted to PrusaSlicer.

The slicer supports a downward face whose slope from the build plate is below
its threshold, with a dense *interface* of a few layers right under the face
and sparse *base* columns from there down to the plate, and it grows each
supported region by a fixed margin in millimetres (the contact area's
expansion), which costs most on thin parts. Three features of a pose in the
print frame, in millimetres at the printed size, follow that picture:

``interface`` (mm²)
    ``sum A_f |n_f . up| * min(h_f, H) / H`` over faces flatter than the
    effective threshold ``theta + DELTA``: the supported footprint, each face
    weighted by how much of the interface height ``H`` fits under it
    (``h_f`` is the height of its centroid above the plate).
``base`` (mm³)
    ``sum A_f |n_f . up| * max(h_f - H, 0)`` over the same faces: the
    column volume below the interface.
``rim`` (mm)
    ``sum L_e * min(h_e, H) / H`` over the edges between a supported and an
    unsupported face, ``L_e`` the edge's length seen from above (projected on
    the plate) and ``h_e`` the height of its midpoint: the outline of the
    supported regions, where the expansion adds support.

The predicted support filament in mm is ``c . features`` with the
coefficients :data:`COEFFICIENTS`. ``DELTA``, ``H`` and the coefficients were
fitted once against PrusaSlicer 2.5 (its default print settings, models 60 mm
tall) on the rest pose, random poses, random tilts and the found optima of
the built-in figures and the shared models, at PrusaSlicer's default profile
and at 30° and 60° profiles: ``DELTA`` and ``H`` on a grid, the coefficients'
ratios to make the worst error in the predicted reduction (rest -> found)
smallest, their scale by least squares of the relative filament error. The
command that refits them (and prints the table of
``benchmarks/RESULTS.md``) is::

    python benchmarks/estimators_vs_slicer.py --fit

The coefficients depend on PrusaSlicer's support settings (spacing,
interface layers, contact distance, expansion); the threshold comes from the
printer profile.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .surface import prepare

__all__ = ["COEFFICIENTS", "DELTA", "INTERFACE_MM", "FEATURES", "predicted_support_mm", "support_features"]

#: The names of the features, in the order of :func:`support_features`' columns.
FEATURES = ("interface", "base", "rim")

#: Degrees added to the profile's threshold: PrusaSlicer's layer-by-layer
#: overhang detection supports faces somewhat steeper than the nominal threshold.
DELTA = 3.0

#: Height of the dense interface under a supported face, mm.
INTERFACE_MM = 6.0

#: Filament mm per unit of each feature (:data:`FEATURES`), fitted on the
#: sliced poses of benchmarks/slicer_samples.jsonl.
COEFFICIENTS = (1.1617, 0.0596, 1.9044)


#: Poses x faces measured at once by :func:`predicted_support_mm` (bounds its memory).
_CHUNK_ELEMENTS = 1 << 20


#: Surfaces up to this many faces keep their edges (:func:`_edge_faces`) for the next call on them.
_KEPT_EDGES_FACES = 200_000


def _edge_faces(faces):
    """The two faces on each edge of a closed surface.

    ``faces`` (f, 3) int. Returns ``edges`` (e, 2) int64 vertex pairs and
    ``left``, ``right`` (e,) int64 the faces on either side (edges met more
    or fewer than twice, as on a surface that is not closed, are left out);
    read-only, kept for the last few surfaces (a pose edited in the browser
    app is measured on the same triangles again and again).
    """
    F = np.ascontiguousarray(faces, np.int64)
    if len(F) > _KEPT_EDGES_FACES:
        return _edges_of(F)
    return _kept_edges(F.tobytes(), len(F))


@lru_cache(maxsize=4)
def _kept_edges(raw: bytes, count: int):
    """:func:`_edges_of` the ``count`` faces whose int64 bytes are ``raw``, kept for the next call."""
    return _edges_of(np.frombuffer(raw, np.int64).reshape(count, 3))


def _edges_of(F):
    """:func:`_edge_faces` of (f, 3) int64 faces, computed."""
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(F)), 3)
    order = np.lexsort((E[:, 1], E[:, 0]))
    E, owner = E[order], owner[order]
    same = np.all(E[:-1] == E[1:], axis=1)
    # an edge shared by exactly two faces: equal to its successor, and neither to the one before nor after the pair
    before = np.r_[False, same[:-1]]
    after = np.r_[same[1:], False]
    pair = np.nonzero(same & ~before & ~after)[0]
    out = E[pair], owner[pair], owner[pair + 1]
    for x in out:
        x.flags.writeable = False
    return out


def support_features(vertices, faces, up, overhang_angle, scale=1.0, delta=DELTA, interface_mm=INTERFACE_MM):
    """The slicer model's features of posed surfaces.

    Parameters
    ----------
    vertices : (P, n, 3) or (n, 3) float64
        Posed closed surfaces in the print frame, model units.
    faces : (f, 3) int
        Consistently oriented triangles, either winding.
    up : str or (3,) array_like of float
        Printing direction (:func:`supportless.energies.surface.prepare`).
    overhang_angle : float
        The printer's threshold, degrees from the build plate (the profile's).
    scale : float
        Model units to millimetres at the printed size.
    delta, interface_mm : float
        :data:`DELTA` and :data:`INTERFACE_MM`.

    Returns
    -------
    features : (P, 3) or (3,) float64
        ``interface`` (mm²), ``base`` (mm³), ``rim`` (mm) per pose.
    """
    V, F, u, single = prepare(vertices, faces, up)
    if V.shape[-1] != 3:
        raise ValueError("the slicer model is for 3D surfaces")
    V = V * float(scale)
    a, b, c = V[:, F[:, 0]], V[:, F[:, 1]], V[:, F[:, 2]]
    scaled_normal = 0.5 * np.cross(b - a, c - a)  # (P, f, 3): area * unit normal
    signed_volume = np.einsum("pfi,pfi->p", a, np.cross(b, c))
    along = np.einsum("pfi,i->pf", scaled_normal, u) * np.sign(signed_volume)[:, None]  # outward
    area = np.linalg.norm(scaled_normal, axis=-1)
    heights = V @ u
    plate = heights.min(axis=1, keepdims=True)
    h = (a + b + c) @ u / 3.0 - plate
    tau = np.cos(np.radians(min(float(overhang_angle) + float(delta), 89.0)))
    risky = along < -tau * area
    proj = np.where(risky, -along, 0.0)
    H = float(interface_mm)
    edges, left, right = _edge_faces(F)
    p, e = np.nonzero(risky[:, left] != risky[:, right])  # the outlines' edges (a few of all), pose by pose
    ends = V[p[:, None], edges[e]]  # (k, 2, 3)
    step = ends[:, 1] - ends[:, 0]
    seen_from_above = np.linalg.norm(step - (step @ u)[:, None] * u, axis=-1)
    h_edge = ends.sum(axis=1) @ u / 2.0 - plate[p, 0]
    rim = np.zeros((len(V), len(edges)))  # summed over every edge, zero off the outline: the same sum as over all
    rim[p, e] = seen_from_above * np.minimum(h_edge, H)
    features = np.stack([(proj * np.minimum(h, H)).sum(1) / H,
                         (proj * np.maximum(h - H, 0.0)).sum(1),
                         rim.sum(1) / H], axis=1)
    return features[0] if single else features


def predicted_support_mm(vertices, faces, up, overhang_angle, scale=1.0, coefficients=COEFFICIENTS):
    """PrusaSlicer's support filament as the slicer model predicts it.

    Parameters
    ----------
    vertices : (P, n, 3) or (n, 3) float64
        Posed closed surfaces in the print frame, model units.
    faces : (f, 3) int
    up : str or (3,) array_like of float
    overhang_angle : float
        The printer's threshold, degrees.
    scale : float
        Model units to millimetres at the printed size.
    coefficients : (3,) float
        Filament mm per unit of each feature (default :data:`COEFFICIENTS`).

    Returns
    -------
    filament_mm : (P,) float64 or float
        Predicted support filament length, mm (1.75 mm filament).
    """
    V = np.asarray(vertices, np.float64)
    c = np.asarray(coefficients, np.float64)
    if V.ndim == 2:
        return float(support_features(V, faces, up, overhang_angle, scale) @ c)
    # poses in chunks: the corner arrays are (P, f, 3)
    chunk = max(1, _CHUNK_ELEMENTS // max(len(faces), 1))
    return np.concatenate([support_features(V[i:i + chunk], faces, up, overhang_angle, scale) @ c
                           for i in range(0, len(V), chunk)]) if len(V) else np.zeros(0)
