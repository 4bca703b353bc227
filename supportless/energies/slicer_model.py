"""A model of the support filament PrusaSlicer lays down, fitted to PrusaSlicer.

The slicer supports a downward face whose slope from the build plate is below
its threshold, with a dense *interface* of a few layers right under the face
and sparse *base* columns from there down to the plate. Small downward tips
(a vertex lower than all its neighbours, with no face flat enough to count)
get a thin tower of their own. Three features of a pose in the print frame, in
millimetres at the printed size, follow that picture:

``interface`` (mm²)
    ``sum A_f |n_f . up| * min(h_f, H) / H`` over faces flatter than the
    effective threshold ``theta + DELTA``: the supported footprint, each face
    weighted by how much of the interface height ``H`` fits under it
    (``h_f`` is the height of its centroid above the plate).
``base`` (mm³)
    ``sum A_f |n_f . up| * max(h_f - H, 0)`` over the same faces: the
    column volume below the interface.
``tips`` (mm)
    The summed heights of vertices lower than all their neighbours, more than ``TIP_MIN_MM``
    above the plate that lie on no face counted above.

The predicted support filament in mm is ``c . features`` with the
coefficients :data:`COEFFICIENTS`. ``DELTA``, ``H`` and the coefficients were
fitted once by non-negative least squares against PrusaSlicer 2.5 (its
default print settings, models 60 mm tall) on the rest pose, random poses,
random tilts and the found optima of every built-in figure and the shared
models; the command that refits them (and prints the table of
``benchmarks/RESULTS.md``) is::

    python benchmarks/estimators_vs_slicer.py --fit

The coefficients have a physical reading: ``base`` costs about a quarter of
its volume in filament (0.107 mm of 1.75 mm filament per mm³: a sparse fill),
``interface`` about 4 mm³ per mm² of footprint (a few dense layers and the
expansion of the contact area). They belong to PrusaSlicer's default support settings (spacing,
interface layers, contact distance); the threshold comes from the printer
profile.
"""

from __future__ import annotations

import numpy as np

from .surface import prepare

__all__ = ["COEFFICIENTS", "DELTA", "INTERFACE_MM", "TIP_MIN_MM", "FEATURES", "predicted_support_mm",
           "support_features"]

#: The names of the features, in the order of :func:`support_features`' columns.
FEATURES = ("interface", "base", "tips")

#: Degrees added to the profile's threshold: PrusaSlicer's layer-by-layer
#: overhang detection and the expansion of its contact areas support faces
#: somewhat steeper than the nominal threshold.
DELTA = 7.0

#: Height of the dense interface under a supported face, mm.
INTERFACE_MM = 3.0

#: A lowest vertex this far above the plate (mm) or more gets a tower.
TIP_MIN_MM = 0.5

#: Filament mm per unit of each feature (:data:`FEATURES`), fitted on 87
#: sliced poses of 11 models (benchmarks/slicer_samples.jsonl). The fit gives
#: the tips no weight: measured there, they add nothing the footprint does not.
COEFFICIENTS = (1.7488, 0.1069, 0.0)


def _tip_heights(H: np.ndarray, faces: np.ndarray, risky: np.ndarray) -> np.ndarray:
    """Summed heights of unsupported tips, per pose.

    ``H`` (P, n) float64 heights above the plate, mm; ``risky`` (P, f) bool,
    the supported faces. A tip is a vertex lower than all its neighbours, more than
    :data:`TIP_MIN_MM` above the plate and on no supported face (those are
    counted by the footprint). Returns (P,) float64.
    """
    E = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    a, b = E[:, 0], E[:, 1]
    out = np.zeros(len(H))
    for p in range(len(H)):
        h = H[p]
        not_tip = np.zeros(h.shape[0], bool)
        not_tip[a[h[b] <= h[a]]] = True
        not_tip[b[h[a] <= h[b]]] = True
        not_tip[faces[risky[p]].ravel()] = True
        tip = ~not_tip & (h > TIP_MIN_MM)
        out[p] = h[tip].sum()
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
        ``interface`` (mm²), ``base`` (mm³), ``tips`` (mm) per pose.
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
    features = np.stack([(proj * np.minimum(h, H)).sum(1) / H,
                         (proj * np.maximum(h - H, 0.0)).sum(1),
                         _tip_heights(heights - plate, F, risky)], axis=1)
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
    feats = support_features(vertices, faces, up, overhang_angle, scale)
    return feats @ np.asarray(coefficients, np.float64)
