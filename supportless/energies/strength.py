"""The strength of a printed body: the stress across and along its layers under its weight and a grip.

A layered print is weakest between its layers: the bond across them holds about half of what a line holds along
its length (PLA; :data:`MATERIALS`). A pose that saves support can leave an ankle, a wrist or a tail whose layers
run across it, and the figure snaps there when it is picked up. This module finds the weakest section of a body
as printed (+Z up, millimetres, the plate at its lowest point) with beam theory on its cross-sections, as
cross-sectional structural analysis does:

- **Layer sections** (:func:`layer_sections`): the body cut by horizontal planes. Each connected section (an
  outer outline less its holes) gets its area, centroid and second moments by Green's theorem over the cut
  segments. The body above and below each plane splits into connected parts; the parts that reach the plate are
  held, every other part is free, and a free part's loads reach the held ones through the sections between them
  (shared by parallel sections in proportion to their areas). The normal stress of a section is
  ``N/A + M·c/I`` (its bending about both axes), across the layers.
- **Bone sections**: the body cut square to each bone, at a few points along it; the section is the outline
  round the bone. The bones on the far side from the plate (and the chain ends on them) are the free part. The
  stress runs along the bone; its share across the layers (``cos² θ`` of the bone's tilt from the vertical) is
  held by the bond between layers, the rest by the lines (:func:`effective_strength`).

The loads are the free part's own weight and one handling load (:data:`HANDLING_LOAD_N`) at one chain end at a
time, in the direction that stresses the section most: for a unit force the stress at a point of the section is
``g(q) · u``, at most ``|g(q)|`` over directions ``u`` (:func:`grip_stress`). The safety factor of a section is
its strength over its largest stress; the breaking load is the grip at which that stress reaches the strength.

The sections are taken as solid (a thin part, where a figure breaks, is all perimeters); shear and torsion are
left out. :mod:`supportless.energies.strength_fem` solves the same loads by finite elements, to check this.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..files.printer import PrinterProfile

__all__ = ["BONE_SAMPLES", "DEFAULT_MATERIAL", "GRAVITY", "HANDLING_LOAD_N", "HELD_SHARE", "MATERIALS", "MAX_PLANES", "Material",
           "Section", "Strength", "analyse_strength", "chain_ends", "effective_strength", "grip_stress",
           "layer_sections", "material_of", "section_moments"]

#: The handling load at a chain end (a hand, the head, a tail), N: about the force of two fingers holding it.
HANDLING_LOAD_N = 2.0
#: Standard gravity, m/s² (a density in g/cm³ times this, times 1e-6, is a weight in N/mm³).
GRAVITY = 9.81
#: Horizontal planes cut at most: the layers are analysed every ``height / MAX_PLANES`` when that is thicker than
#: a printed layer.
MAX_PLANES = 240
#: The part of the body within this share of its height over the plate is held (the feet of a standing figure,
#: the back of one lying down): a hand holds a figure by what it stands on, not by its first layer alone.
HELD_SHARE = 0.05
#: Where each bone is cut square to itself, as fractions of its length from its first joint.
BONE_SAMPLES = (0.15, 0.5, 0.85)
#: A chain's end is its branching joint when the branch is this close (a share of the body's height) to each of
#: its leaves: a hand of fingers is gripped at the hand.
CHAIN_REACH = 0.12


@dataclass(frozen=True)
class Material:
    """A filament's figures for the strength analysis.

    Attributes
    ----------
    name : str
    density : float
        g/cm³.
    along_mpa : float
        Tensile strength along the printed lines, MPa.
    interlayer : float
        The bond between layers as a share of ``along_mpa``.
    young_mpa : float
        Young's modulus, MPa (the finite element reference).
    poisson : float
    """

    name: str
    density: float
    along_mpa: float
    interlayer: float
    young_mpa: float
    poisson: float = 0.35

    @property
    def across_mpa(self) -> float:
        """Tensile strength across the layers, MPa."""
        return self.along_mpa * self.interlayer

    def to_dict(self) -> dict:
        return {"name": self.name, "density_g_cm3": self.density, "along_mpa": self.along_mpa,
                "across_mpa": round(self.across_mpa, 2), "interlayer": self.interlayer}


#: Common filaments as printed (typical published test figures of printed bars, not of the raw resin): tensile
#: strength along the lines and the share the layers' bond keeps (FDM interlayer strength is commonly 50–90 % of
#: in-plane; PLA at the lower end).
MATERIALS = {
    "PLA": Material("PLA", 1.24, 50.0, 0.5, 3500.0),
    "PETG": Material("PETG", 1.27, 45.0, 0.7, 2100.0),
    "ABS": Material("ABS", 1.04, 35.0, 0.6, 2200.0),
}
#: The filament when the printer profile names none of :data:`MATERIALS`.
DEFAULT_MATERIAL = "PLA"


def material_of(profile: PrinterProfile | None) -> Material:
    """The filament of a printer profile (PrusaSlicer's ``filament_type``, Cura's ``material_type``), its density
    from the profile when it gives one; :data:`DEFAULT_MATERIAL` otherwise."""
    base = MATERIALS[DEFAULT_MATERIAL]
    if profile is None:
        return base
    raw = getattr(profile, "raw", {}) or {}
    named = str(raw.get("filament_type") or raw.get("material_type") or "").strip().strip('"').upper()
    base = MATERIALS.get(named, base)
    density = float(getattr(profile, "filament_density", 0.0) or 0.0)
    if "filament_density" in raw and density > 0 and abs(density - base.density) > 1e-9:
        base = Material(base.name, density, base.along_mpa, base.interlayer, base.young_mpa, base.poisson)
    return base


def effective_strength(material: Material, normal_z: np.ndarray | float) -> np.ndarray:
    """The uniaxial strength along a direction whose vertical component is ``normal_z``, MPa.

    A stress ``σ`` along a unit direction ``n`` puts ``σ n_z²`` across the layers (held by the bond) and
    ``σ (1 - n_z²)`` along them (held by the lines); it breaks at the first to give way:
    ``1 / max(n_z² / S_across, (1 - n_z²) / S_along)``.

    Parameters
    ----------
    material : Material
    normal_z : float or (s,) float64

    Returns
    -------
    strength : float or (s,) float64
    """
    c2 = np.asarray(normal_z, np.float64) ** 2
    return 1.0 / np.maximum(c2 / material.across_mpa, (1.0 - c2) / material.along_mpa)


# ----------------------------------------------------------------------------------------------- cut sections

def section_moments(first: np.ndarray, second: np.ndarray, group: np.ndarray, count: int) -> np.ndarray:
    """Area and first and second moments of closed outlines given as directed segments (Green's theorem).

    Parameters
    ----------
    first, second : (s, 2) float64
        Each segment's start and end, every outline run counter-clockwise (holes clockwise).
    group : (s,) int64
        The outline (or section) each segment belongs to.
    count : int

    Returns
    -------
    moments : (count, 6) float64
        ``A, ∫x, ∫y, ∫x², ∫y², ∫xy`` over each group's region, about the coordinates' origin.
    """
    x0, y0, x1, y1 = first[:, 0], first[:, 1], second[:, 0], second[:, 1]
    cross = x0 * y1 - x1 * y0
    terms = (cross / 2.0, (x0 + x1) * cross / 6.0, (y0 + y1) * cross / 6.0,
             (x0 * x0 + x0 * x1 + x1 * x1) * cross / 12.0, (y0 * y0 + y0 * y1 + y1 * y1) * cross / 12.0,
             (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * cross / 24.0)
    return np.stack([np.bincount(group, weights=t, minlength=count) for t in terms], axis=1)


def _central(moments: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A (s,), centroid (s, 2), J (s, 2, 2))``: second moments about each region's centroid."""
    A = moments[:, 0]
    safe = np.where(np.abs(A) > 0, A, 1.0)
    c = moments[:, 1:3] / safe[:, None]
    J = np.empty((len(A), 2, 2))
    J[:, 0, 0] = moments[:, 3] - A * c[:, 0] ** 2
    J[:, 1, 1] = moments[:, 4] - A * c[:, 1] ** 2
    J[:, 0, 1] = J[:, 1, 0] = moments[:, 5] - A * c[:, 0] * c[:, 1]
    return A, c, J


def _edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(edges (e, 2) int64, face_edges (f, 3) int64)``: the unique edges and each face's edges (v0v1, v1v2, v2v0)."""
    F = np.asarray(faces, np.int64)
    a = np.stack([F[:, 0], F[:, 1], F[:, 2]], axis=1).ravel()
    b = np.stack([F[:, 1], F[:, 2], F[:, 0]], axis=1).ravel()
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    keys, inverse = np.unique(lo * (int(F.max()) + 1) + hi, return_inverse=True)
    n = int(F.max()) + 1
    return np.stack([keys // n, keys % n], axis=1), inverse.reshape(-1, 3)


def _two_of_three(crosses: np.ndarray) -> np.ndarray:
    """(k, 2) int64: the positions of the two True of each row of ``crosses (k, 3) bool`` (exactly two each)."""
    return np.stack([np.where(crosses[:, 0], 0, 1), np.where(crosses[:, 2], 2, 1)], axis=1)


def _winding(points: np.ndarray, first: np.ndarray, second: np.ndarray, group: np.ndarray, count: int) -> np.ndarray:
    """(count, p) int: winding numbers of 2D points about closed outlines given as directed segments."""
    out = np.zeros((count, len(points)), np.int64)
    for j, q in enumerate(points):
        ya, yb = first[:, 1] - q[1], second[:, 1] - q[1]
        up_, down = (ya <= 0) & (yb > 0), (ya > 0) & (yb <= 0)
        side = (first[:, 0] - q[0]) * yb - (second[:, 0] - q[0]) * ya  # > 0: q left of the segment
        w = np.where(up_ & (side > 0), 1, 0) - np.where(down & (side < 0), 1, 0)
        out[:, j] = np.bincount(group, weights=w, minlength=count).astype(np.int64)
    return out


@dataclass
class LayerSections:
    """The body cut by horizontal planes (:func:`layer_sections`).

    Attributes
    ----------
    planes : (L,) float64
        Heights of the planes, mm, ascending.
    layer : (s,) int64
        Each section's plane.
    area : (s,) float64
        mm².
    centroid : (s, 2) float64
        mm.
    J : (s, 2, 2) float64
        ``∫ x x^T dA`` about the centroid, mm⁴.
    points : (p, 2) float64
        The outlines' corners (where the stress is largest), with ``point_section (p,) int64``.
    above, below : list of (s,) lists of int
        The connected parts of the slab just above (below) each section's plane that its outlines bound.
    part_slab : (c,) int64
        Each part's slab: ``k`` between planes ``k`` and ``k+1``; -1 under the first plane (held by the plate).
    part_volume : (c,) float64
        mm³.
    part_centroid : (c, 3) float64
    part_points : (c,) list of (·, 3) float64
        Points of the outlines bounding each part (to find the part a chain end is in).
    section_faces : (s,) list of (·,) int64
        The faces each section's outlines cut.
    """

    planes: np.ndarray
    layer: np.ndarray
    area: np.ndarray
    centroid: np.ndarray
    J: np.ndarray
    points: np.ndarray
    point_section: np.ndarray
    above: list
    below: list
    part_slab: np.ndarray
    part_volume: np.ndarray
    part_centroid: np.ndarray
    part_points: list
    section_faces: list


def layer_sections(vertices: np.ndarray, faces: np.ndarray, planes: np.ndarray) -> LayerSections:
    """Cut a closed, outward oriented surface by horizontal planes into sections and the parts between them.

    Parameters
    ----------
    vertices : (n, 3) float64
        +Z up, mm.
    faces : (f, 3) int64
    planes : (L,) float64
        Ascending heights; a point is below a plane when ``z < plane``.

    Returns
    -------
    LayerSections
    """
    V = np.asarray(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    p = np.asarray(planes, np.float64)
    L = len(p)
    z = V[:, 2]
    edges, face_edges = _edges(F)
    lo, hi = np.minimum(z[edges[:, 0]], z[edges[:, 1]]), np.maximum(z[edges[:, 0]], z[edges[:, 1]])
    k0, k1 = np.searchsorted(p, lo, "right"), np.searchsorted(p, hi, "right")  # edge e crosses planes k0..k1-1
    count = k1 - k0
    offset = np.concatenate([[0], np.cumsum(count)[:-1]])
    N = int(count.sum())
    node_edge = np.repeat(np.arange(len(edges)), count)
    node_layer = k0[node_edge] + np.arange(N) - offset[node_edge]
    a, b = V[edges[node_edge, 0]], V[edges[node_edge, 1]]
    t = (p[node_layer] - a[:, 2]) / np.where(b[:, 2] != a[:, 2], b[:, 2] - a[:, 2], 1.0)
    node_xy = a[:, :2] + t[:, None] * (b[:, :2] - a[:, :2])

    # segments: each face crossing plane k has exactly two edges crossing it
    fz = z[F]
    f0, f1 = np.searchsorted(p, fz.min(axis=1), "right"), np.searchsorted(p, fz.max(axis=1), "right")
    seg_face = np.repeat(np.arange(len(F)), f1 - f0)
    seg_offset = np.concatenate([[0], np.cumsum(f1 - f0)[:-1]])
    seg_layer = f0[seg_face] + np.arange(len(seg_face)) - seg_offset[seg_face]
    fe = face_edges[seg_face]  # (S, 3)
    crosses = (k0[fe] <= seg_layer[:, None]) & (seg_layer[:, None] < k1[fe])
    pick = np.take_along_axis(fe, _two_of_three(crosses), axis=1)
    ends = offset[pick] + seg_layer[:, None] - k0[pick]  # (S, 2) node ids
    n1, n2 = ends[:, 0], ends[:, 1]
    normal = np.cross(V[F[seg_face, 1]] - V[F[seg_face, 0]], V[F[seg_face, 2]] - V[F[seg_face, 0]])
    d = node_xy[n2] - node_xy[n1]
    flip = d[:, 0] * -normal[:, 1] + d[:, 1] * normal[:, 0] < 0  # counter-clockwise: the outside on the right
    n1, n2 = np.where(flip, n2, n1), np.where(flip, n1, n2)

    # outlines (loops) and their moments about each layer's own origin
    graph = sp.coo_matrix((np.ones(len(n1)), (n1, n2)), shape=(N, N))
    n_loops, loop_of = connected_components(graph, directed=False)
    loop_layer = np.zeros(n_loops, np.int64)
    loop_layer[loop_of] = node_layer
    origin = np.zeros((L, 2))
    per_layer = np.bincount(node_layer, minlength=L)
    for axis in range(2):
        origin[:, axis] = np.bincount(node_layer, weights=node_xy[:, axis], minlength=L) / np.maximum(per_layer, 1)
    rel = node_xy - origin[node_layer]
    seg_loop = loop_of[n1]
    loop_m = section_moments(rel[n1], rel[n2], seg_loop, n_loops)

    # sections: an outline (positive area) less the holes (negative) inside it
    section_of_loop = np.full(n_loops, -1, np.int64)
    outer = np.flatnonzero(loop_m[:, 0] > 0)
    section_of_loop[outer] = np.arange(len(outer))
    holes = np.flatnonzero(loop_m[:, 0] <= 0)
    if len(holes):
        first_node = np.full(n_loops, -1, np.int64)
        first_node[loop_of[::-1]] = np.arange(N)[::-1]
        for layer_k in np.unique(loop_layer[holes]):
            hs = holes[loop_layer[holes] == layer_k]
            os_ = outer[loop_layer[outer] == layer_k]
            if not len(os_):
                continue
            mask = np.isin(seg_loop, os_)
            local = np.searchsorted(os_, seg_loop[mask])
            w = _winding(rel[first_node[hs]], rel[n1[mask]], rel[n2[mask]], local, len(os_))
            area = loop_m[os_, 0]
            for j, h in enumerate(hs):
                inside = np.flatnonzero(w[:, j] != 0)
                if len(inside):
                    section_of_loop[h] = section_of_loop[os_[inside[np.argmin(area[inside])]]]
    S = len(outer)
    kept = section_of_loop >= 0
    sec_m = np.zeros((S, 6))
    np.add.at(sec_m, section_of_loop[kept], loop_m[kept])
    area, centroid, J = _central(sec_m)
    layer = loop_layer[outer]
    centroid = centroid + origin[layer]
    node_section = section_of_loop[loop_of]
    good = node_section >= 0
    seg_section = section_of_loop[seg_loop]
    section_faces = _split(seg_face[seg_section >= 0], seg_section[seg_section >= 0], S)

    # the parts of the slabs between planes: the surface between two planes, connected
    vertex_slab = np.searchsorted(p, z, "right") - 1
    n = len(V)
    bottom, top, vert = np.arange(N), N + np.arange(N), 2 * N + np.arange(n)  # node copies: in slab k, in slab k-1
    e_lo = np.where(z[edges[:, 0]] <= z[edges[:, 1]], edges[:, 0], edges[:, 1])
    e_hi = np.where(z[edges[:, 0]] <= z[edges[:, 1]], edges[:, 1], edges[:, 0])
    up_v, lo_v = e_hi[node_edge], e_lo[node_edge]
    reaches = vertex_slab[up_v] == node_layer  # the upper end lies before the next plane
    last_of_edge = np.arange(N) == offset[node_edge] + count[node_edge] - 1
    rows = [bottom[n1], top[n1], bottom[reaches], bottom[~reaches & ~last_of_edge]]
    cols = [bottom[n2], top[n2], vert[up_v[reaches]], top[np.flatnonzero(~reaches & ~last_of_edge) + 1]]
    low_in = vertex_slab[lo_v] == node_layer - 1
    rows.append(top[low_in])
    cols.append(vert[lo_v[low_in]])
    flat = count == 0
    rows.append(vert[edges[flat, 0]])
    cols.append(vert[edges[flat, 1]])
    r, c = np.concatenate(rows), np.concatenate(cols)
    total = 2 * N + n
    n_parts, part_of = connected_components(sp.coo_matrix((np.ones(len(r)), (r, c)), shape=(total, total)),
                                            directed=False)
    part_slab = np.full(n_parts, -2, np.int64)
    part_slab[part_of[bottom]] = node_layer
    part_slab[part_of[top]] = node_layer - 1
    part_slab[part_of[vert]] = vertex_slab
    # each section's parts above (its plane's slab) and below
    above = [sorted(set(x)) for x in _split(part_of[bottom[good]], node_section[good], S)]
    below = [sorted(set(x)) for x in _split(part_of[top[good]], node_section[good], S)]
    # a part's volume: its slab's thickness times the mean of the areas bounding it below and above
    thick = np.diff(np.concatenate([[z.min()], p, [z.max()]]))  # slab -1 .. L-1
    loop_area = loop_m[:, 0]
    loop_c = (loop_m[:, 1:3] / np.where(loop_area != 0, loop_area, 1.0)[:, None]) + origin[loop_layer]
    first_bottom = np.full(n_loops, -1, np.int64)
    first_bottom[loop_of] = np.arange(N)
    loop_part_above, loop_part_below = part_of[bottom[first_bottom]], part_of[top[first_bottom]]
    part_area = np.zeros(n_parts)
    part_moment = np.zeros((n_parts, 2))
    for parts in (loop_part_above, loop_part_below):
        part_area += 0.5 * np.bincount(parts, weights=loop_area, minlength=n_parts)
        for axis in range(2):
            part_moment[:, axis] += 0.5 * np.bincount(parts, weights=loop_area * loop_c[:, axis], minlength=n_parts)
    slab = np.clip(part_slab, -1, L - 1)
    part_volume = np.maximum(part_area, 0.0) * thick[slab + 1]
    part_centroid = np.zeros((n_parts, 3))
    part_centroid[:, :2] = part_moment / np.where(np.abs(part_area) > 0, part_area, 1.0)[:, None]
    mid = np.concatenate([[z.min()], p, [z.max()]])
    part_centroid[:, 2] = 0.5 * (mid[slab + 1] + mid[slab + 2])
    node_xyz = np.column_stack([node_xy, p[node_layer]])
    part_points = _split(np.concatenate([node_xyz, node_xyz]), np.concatenate([part_of[bottom], part_of[top]]),
                         n_parts)
    points = rel[good] + origin[node_layer[good]]
    return LayerSections(p, layer, area, centroid, J, points, node_section[good], above, below, part_slab,
                         part_volume, part_centroid, part_points, section_faces)


def _split(values: np.ndarray, keys: np.ndarray, count: int) -> list:
    """``values`` grouped by ``keys`` (0..count-1) into a list of arrays."""
    order = np.argsort(keys, kind="stable")
    bounds = np.searchsorted(keys[order], np.arange(count + 1))
    v = values[order]
    return [v[bounds[i]:bounds[i + 1]] for i in range(count)]


# --------------------------------------------------------------------------------------------------- the loads

def grip_stress(points: np.ndarray, area: float, J: np.ndarray, lever: np.ndarray, sign: float) -> np.ndarray:
    """The normal stress a unit force puts on a section, per direction: ``σ(q) = g(q) · u``.

    The section lies in a plane with right-handed axes ``(e1, e2, n)``; the free part is on the ``sign · n``
    side. A force ``u`` on the free part at ``lever`` from the section's centroid gives the axial force
    ``u_n`` and the moment ``lever × u``; their stress is ``N/A + (J⁻¹ [-M_2, M_1]) · q`` (tension positive).

    Parameters
    ----------
    points : (q, 2) float64
        Points of the section, relative to its centroid, in ``(e1, e2)``.
    area : float
    J : (2, 2) float64
        ``∫ q q^T dA`` about the centroid.
    lever : (3,) float64
        The force's point relative to the centroid, in ``(e1, e2, n)``.
    sign : float
        +1: the free part is on the ``+n`` side; -1: on the ``-n`` side.

    Returns
    -------
    g : (q, 3) float64
        MPa per N.
    """
    rx, ry, rz = lever
    R = np.array([[-rz, 0.0, rx], [0.0, -rz, ry]])  # [-M_2, M_1] = R u
    k = np.linalg.solve(J + 1e-12 * np.trace(J) * np.eye(2), R) if np.trace(J) > 0 else np.zeros((2, 3))
    g = points @ k
    g[:, 2] += 1.0 / area
    return sign * g


@dataclass
class Section:
    """One section's verdict.

    Attributes
    ----------
    kind : {"layer", "bone"}
    height_mm : float
        Its centroid's height over the plate.
    centre : (3,) float64
        Its centroid, mm.
    bone : int
        The bone it cuts (most of its faces').
    across : bool
        Whether the bond between layers gives way first (else the lines).
    safety_factor : float
        Strength over the largest stress under the weight and the grip (inf: nothing pulls it).
    stress_mpa : float
    strength_mpa : float
    breaks_at_n : float
        The grip (with the weight) that breaks it, N (inf: none).
    chain_end : int
        The chain end whose grip is worst (-1: none loads it).
    area_mm2 : float
    faces : (·,) int64
        Faces the section cuts.
    """

    kind: str
    height_mm: float
    centre: np.ndarray
    bone: int
    across: bool
    safety_factor: float
    stress_mpa: float
    strength_mpa: float
    breaks_at_n: float
    chain_end: int
    area_mm2: float
    faces: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, np.int64))


def _verdict(points, area, J, sign, weight_force, weight_lever, grips, strength, load_n):
    """``(safety, stress, breaks_at, chain_end)`` of a section under its free part's weight and grips.

    ``grips`` is a list of ``(chain_end, share, lever (3,))``; the rest as :func:`grip_stress`."""
    sigma_w = grip_stress(points, area, J, weight_lever, sign) @ weight_force if weight_force is not None else \
        np.zeros(len(points))
    worst = np.zeros(len(points))
    which = np.full(len(points), -1)
    for end, share, lever in grips:
        g = share * np.linalg.norm(grip_stress(points, area, J, lever, sign), axis=1)
        better = g > worst
        worst = np.where(better, g, worst)
        which = np.where(better, end, which)
    total = sigma_w + load_n * worst
    i = int(np.argmax(total))
    stress = float(total[i])
    safety = strength / stress if stress > 0 else np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        breaks = np.where(worst > 0, (strength - sigma_w) / worst, np.inf)
    breaks = float(max(breaks.min(), 0.0))
    return safety, stress, breaks, int(which[i])


# ------------------------------------------------------------------------------------------------- the skeleton

def chain_ends(joints: np.ndarray, bones: np.ndarray, reach: float) -> np.ndarray:
    """The joints a figure is gripped by: its chains' ends (hands, head, tail, ears, wing tips).

    A leaf joint, or the joint where its chain branches when the branch is within ``reach`` of the leaf (the
    fingers' leaves give the hand).

    Parameters
    ----------
    joints : (j, 3) float64
    bones : (m, 2) int64
    reach : float
        In the joints' units.

    Returns
    -------
    ends : (e,) int64
        Joint indices, sorted, each once.
    """
    B = np.asarray(bones, np.int64)
    neighbours: dict[int, list[int]] = {}
    for a, b in B:
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    ends = set()
    for leaf, nb in neighbours.items():
        if len(nb) != 1:
            continue
        previous, here, walked, end = leaf, nb[0], 0.0, leaf
        walked += float(np.linalg.norm(joints[here] - joints[leaf]))
        while walked <= reach:
            if len(neighbours[here]) >= 3:
                end = here
                break
            nxt = [j for j in neighbours[here] if j != previous]
            if len(nxt) != 1:
                break
            previous, here = here, nxt[0]
            walked += float(np.linalg.norm(joints[here] - joints[previous]))
        ends.add(end)
    return np.array(sorted(ends), np.int64)


def _face_bones(vertices, faces, joints, bones):
    """(f,) int64: the bone nearest each face's centroid (when no skinning weights are given)."""
    c = vertices[faces].mean(axis=1)
    a, b = joints[bones[:, 0]], joints[bones[:, 1]]
    ab = b - a
    t = np.clip(np.einsum("fbk,bk->fb", c[:, None] - a[None], ab) / np.maximum((ab * ab).sum(1), 1e-300), 0, 1)
    d = np.linalg.norm(c[:, None] - (a[None] + t[..., None] * ab[None]), axis=2)
    return np.argmin(d, axis=1)


# ------------------------------------------------------------------------------------------------ the analysis

@dataclass
class Strength:
    """The strength of a body as printed (:func:`analyse_strength`).

    Attributes
    ----------
    sections : list of Section
        Every section analysed, weakest first.
    material : Material
    load_n : float
        The grip, N.
    face_safety : (f,) float64
        The least safety factor of the sections cutting each face (inf: none), for pictures.
    """

    sections: list
    material: Material
    load_n: float
    face_safety: np.ndarray

    @property
    def weakest(self) -> Section | None:
        return self.sections[0] if self.sections else None

    @property
    def safety_factor(self) -> float:
        return self.sections[0].safety_factor if self.sections else float("inf")


def analyse_strength(vertices: np.ndarray, faces: np.ndarray, joints: np.ndarray, bones: np.ndarray,
                     face_bones: np.ndarray | None = None, material: Material | None = None,
                     load_n: float = HANDLING_LOAD_N, layer_mm: float = 0.2, max_planes: int = MAX_PLANES,
                     ends: np.ndarray | None = None, held_mm: float | None = None) -> Strength:
    """The weakest sections of a closed body as printed, under its weight and a grip at one chain end at a time.

    Parameters
    ----------
    vertices : (n, 3) float64
        +Z up, mm; the plate under the lowest point.
    faces : (f, 3) int64
        Closed, outward oriented.
    joints : (j, 3) float64
        The skeleton posed as the body, mm.
    bones : (m, 2) int64
    face_bones : (f,) int64, optional
        The bone each face follows (most skinning weight); the nearest bone when not given.
    material : Material, optional
        :data:`DEFAULT_MATERIAL` when not given.
    load_n : float
        The grip at a chain end, N.
    layer_mm : float
        The printed layer: planes are never closer.
    held_mm : float, optional
        The part within this height of the plate is held; :data:`HELD_SHARE` of the height when not given.
    max_planes : int
        Horizontal planes at most.
    ends : (e,) int64, optional
        The joints gripped; :func:`chain_ends` when not given.

    Returns
    -------
    Strength
    """
    V = np.asarray(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    Jt = np.asarray(joints, np.float64)
    B = np.asarray(bones, np.int64)
    mat = material or MATERIALS[DEFAULT_MATERIAL]
    labels = _face_bones(V, F, Jt, B) if face_bones is None else np.asarray(face_bones, np.int64)
    z0, z1 = float(V[:, 2].min()), float(V[:, 2].max())
    height = z1 - z0
    ends = chain_ends(Jt, B, CHAIN_REACH * height) if ends is None else np.asarray(ends, np.int64)
    weight_per_mm3 = mat.density * GRAVITY * 1e-6  # N/mm³
    face_safety = np.full(len(F), np.inf)
    sections = []
    held = max(float(layer_mm), HELD_SHARE * height) if held_mm is None else float(held_mm)
    spacing = max(float(layer_mm), height / max(int(max_planes), 1))
    planes = np.arange(z0 + held, z1, spacing)
    if len(planes):
        sections += _layer_verdicts(V, layer_sections(V, F, planes), labels, ends, Jt[ends], mat,
                                    weight_per_mm3, load_n)
    sections += _bone_verdicts(V, F, Jt, B, labels, ends, mat, weight_per_mm3, load_n, z0 + held)
    sections.sort(key=lambda s: s.safety_factor)
    for s in sections:
        face_safety[s.faces] = np.minimum(face_safety[s.faces], s.safety_factor)
    return Strength(sections, mat, float(load_n), face_safety)


class _Parts:
    """Union-find over the slab parts, each root carrying its parts' volume, first moment, grips and hold."""

    def __init__(self, volume, centroid, grips, held):
        self.parent = np.arange(len(volume))
        self.volume = volume.copy()
        self.moment = centroid * volume[:, None]
        self.grips = [set(g) for g in grips]
        self.held = held.copy()

    def find(self, i):
        root = i
        while self.parent[root] != root:
            root = self.parent[root]
        while self.parent[i] != root:
            self.parent[i], i = root, self.parent[i]
        return root

    def union(self, i, j):
        a, b = self.find(i), self.find(j)
        if a == b:
            return a
        if len(self.grips[a]) < len(self.grips[b]):
            a, b = b, a
        self.parent[b] = a
        self.volume[a] += self.volume[b]
        self.moment[a] += self.moment[b]
        self.grips[a] |= self.grips[b]
        self.held[a] |= self.held[b]
        return a

    def load(self, i):
        r = self.find(i)
        return self.volume[r], self.moment[r].copy(), dict.fromkeys(self.grips[r], 1.0), bool(self.held[r])


def _sweep(cut: LayerSections, grips, held, downward: bool):
    """Each section's connected part of the body above (``downward``: planes from the top) or below its plane.

    Returns ``(root (s,) int64, loads dict root -> (volume, moment (3,), {end: 1.0}, held))``; roots are
    distinct per part at one plane."""
    L = len(cut.planes)
    parts = _Parts(cut.part_volume, cut.part_centroid, grips, held)
    own = cut.above if downward else cut.below
    by_layer = [np.flatnonzero(cut.layer == k) for k in range(L)]
    root = np.full(len(cut.layer), -1, np.int64)
    loads = {}
    for k in (range(L - 1, -1, -1) if downward else range(L)):
        passed = k + 1 if downward else k - 1  # the plane just crossed: its sections join both its sides
        if 0 <= passed < L:
            for s in by_layer[passed]:
                touching = cut.above[s] + cut.below[s]
                for x in touching[1:]:
                    parts.union(touching[0], x)
        for s in by_layer[k]:
            if not own[s]:
                continue
            for x in own[s][1:]:
                parts.union(own[s][0], x)
        for s in by_layer[k]:
            if own[s]:
                r = parts.find(own[s][0])
                root[s] = r
                if (k, r) not in loads:
                    loads[(k, r)] = parts.load(r)
    return root, loads


def _carry(sections, area, above_root, below_root, loads_above, loads_below):
    """The loads each section of one plane carries: the free parts' loads passed towards the held ones.

    Parameters: the plane's sections, their areas, their parts above and below (roots) and those parts' loads
    (``(volume, moment, {end: share}, held)``). Parallel sections share a part's loads in proportion to area.

    Returns
    -------
    list of ``(section, sign, (volume, moment (3,), {end: share}))``: sign +1 where the free part is above.
    """
    nodes = {}
    for s in sections:
        if above_root[s] < 0 or below_root[s] < 0 or area[s] <= 0:
            continue
        a = ("A", above_root[s])
        lb = loads_below[below_root[s]]
        b = "G" if lb[3] else ("B", below_root[s])
        nodes.setdefault(a, []).append((s, b))
        nodes.setdefault(b, []).append((s, a))
    if "G" not in nodes:
        return []
    distance = {"G": 0}
    frontier = ["G"]
    while frontier:
        nxt = []
        for u in frontier:
            for _, v in nodes[u]:
                if v not in distance:
                    distance[v] = distance[u] + 1
                    nxt.append(v)
        frontier = nxt
    carried = {u: (0.0, np.zeros(3), {}) for u in distance}
    out = []
    for u in sorted((u for u in distance if u != "G"), key=lambda u: -distance[u]):
        own = loads_above[u[1]] if u[0] == "A" else loads_below[u[1]]
        vol, mom, shares = carried[u]
        vol, mom = vol + own[0], mom + own[1]
        shares = dict(shares)
        for e, w in own[2].items():
            shares[e] = shares.get(e, 0.0) + w
        toward = [(s, v) for s, v in nodes[u] if distance[v] == distance[u] - 1]
        total = sum(area[s] for s, _ in toward)
        for s, v in toward:
            w = area[s] / total
            part = (vol * w, mom * w, {e: x * w for e, x in shares.items()})
            out.append((s, 1.0 if u[0] == "A" else -1.0, part))
            pv, pm, ps = carried[v]
            for e, x in part[2].items():
                ps[e] = ps.get(e, 0.0) + x
            carried[v] = (pv + part[0], pm + part[1], ps)
    return out


def _layer_verdicts(V, cut: LayerSections, labels, ends, end_points, mat, weight_per_mm3, load_n):
    """Every layer section's :class:`Section` (across the layers)."""
    n_parts = len(cut.part_slab)
    grips = [[] for _ in range(n_parts)]  # each chain end is in the part of its slab whose outlines pass nearest
    slab_of_end = np.searchsorted(cut.planes, end_points[:, 2], "right") - 1
    for e, (point, slab) in enumerate(zip(end_points, slab_of_end)):
        candidates = [c for c in np.flatnonzero(cut.part_slab == slab) if len(cut.part_points[c])]
        if slab >= 0 and candidates:
            grips[min(candidates, key=lambda c: np.min(np.linalg.norm(cut.part_points[c] - point, axis=1)))].append(e)
    held = cut.part_slab == -1
    above_root, loads_above = _sweep(cut, grips, held, downward=True)
    below_root, loads_below = _sweep(cut, grips, held, downward=False)
    z0 = float(V[:, 2].min())
    out = []
    la_k, lb_k = [{} for _ in cut.planes], [{} for _ in cut.planes]
    for (kk, r), v in loads_above.items():
        la_k[kk][r] = v
    for (kk, r), v in loads_below.items():
        lb_k[kk][r] = v
    for k in range(len(cut.planes)):
        sections = np.flatnonzero(cut.layer == k)
        la, lb = la_k[k], lb_k[k]
        for s, sign, (volume, moment, shares) in _carry(sections, cut.area, above_root, below_root, la, lb):
            c3 = np.array([cut.centroid[s, 0], cut.centroid[s, 1], cut.planes[k]])
            weight = np.array([0.0, 0.0, -weight_per_mm3 * volume]) if volume > 0 else None
            lever = moment / volume - c3 if volume > 0 else np.zeros(3)
            pts = cut.points[cut.point_section == s] - cut.centroid[s]
            gl = [(int(ends[e]), share, end_points[e] - c3) for e, share in shares.items()]
            safety, stress, breaks, end = _verdict(pts, cut.area[s], cut.J[s], sign, weight, lever, gl,
                                                   mat.across_mpa, load_n)
            faces = cut.section_faces[s]
            bone = int(np.bincount(labels[faces]).argmax()) if len(faces) else -1
            out.append(Section("layer", float(cut.planes[k] - z0), c3, bone, True, float(safety), stress,
                               mat.across_mpa, breaks, end, float(cut.area[s]), faces))
    return out


def _plane_outline(V, F, edges, face_edges, origin, basis, faces=None):
    """The outline round ``origin`` of the section of a closed surface by the plane through it square to
    ``basis[2]``: ``(points (q, 2), area, J (2, 2), centroid (3,), faces)`` in the basis's ``(e1, e2)`` about the
    centroid; None where no closed outline encloses ``origin``. Only ``faces`` (indices) are cut when given: an
    outline they leave open is not one."""
    d = (V - origin) @ basis[2]
    below = d < 0
    candidates = np.arange(len(F)) if faces is None else faces
    fb = below[F[candidates]]
    cut_faces = candidates[fb.any(axis=1) & ~fb.all(axis=1)]
    if not len(cut_faces):
        return None
    fe = face_edges[cut_faces]
    ce, local = np.unique(fe, return_inverse=True)
    local = local.reshape(-1, 3)
    crossing = below[edges[ce, 0]] != below[edges[ce, 1]]
    a, b = V[edges[ce, 0]], V[edges[ce, 1]]
    da, db = d[edges[ce, 0]], d[edges[ce, 1]]
    t = np.where(crossing, da / np.where(crossing, da - db, 1.0), 0.0)
    xy = (a + t[:, None] * (b - a) - origin) @ basis[:2].T
    pick = np.take_along_axis(local, _two_of_three(crossing[local]), axis=1)
    n1, n2 = pick[:, 0], pick[:, 1]
    normal = np.cross(V[F[cut_faces, 1]] - V[F[cut_faces, 0]], V[F[cut_faces, 2]] - V[F[cut_faces, 0]])
    along = np.cross(basis[2], normal) @ basis[:2].T
    flip = ((xy[n2] - xy[n1]) * along).sum(axis=1) < 0
    n1, n2 = np.where(flip, n2, n1), np.where(flip, n1, n2)
    n_loops, loop_of = connected_components(sp.coo_matrix((np.ones(len(n1)), (n1, n2)), shape=(len(ce),) * 2),
                                            directed=False)
    seg_loop = loop_of[n1]
    degree = np.bincount(n1, minlength=len(ce)) + np.bincount(n2, minlength=len(ce))
    open_ = np.zeros(n_loops, bool)
    open_[loop_of[crossing & (degree != 2)]] = True
    m = section_moments(xy[n1], xy[n2], seg_loop, n_loops)
    w = _winding(np.zeros((1, 2)), xy[n1], xy[n2], seg_loop, n_loops)[:, 0]
    enclosing = np.flatnonzero((w != 0) & (m[:, 0] > 0) & ~open_)
    if not len(enclosing):
        return None
    loop = enclosing[np.argmin(m[enclosing, 0])]
    A, c, J = _central(m[loop:loop + 1])
    pts = xy[crossing & (loop_of == loop)] - c[0]
    centroid = origin + c[0] @ basis[:2]
    return pts, float(A[0]), J[0], centroid, cut_faces[seg_loop == loop]


def _bone_verdicts(V, F, Jt, B, labels, ends, mat, weight_per_mm3, load_n, held_below):
    """Every bone section's :class:`Section`: cut square to the bones whose far side from the plate is free."""
    m = len(B)
    held_bones = set(np.unique(labels[V[F][:, :, 2].min(axis=1) < held_below]).tolist())
    # each face's cone from its bone: the body's volume split among the bones
    a, b = Jt[B[labels, 0]], Jt[B[labels, 1]]
    corners = V[F]
    c = corners.mean(axis=1)
    ab = b - a
    t = np.clip(((c - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
    apex = a + t[:, None] * ab
    rel = corners - apex[:, None]
    volume = np.einsum("fi,fi->f", rel[:, 0], np.cross(rel[:, 1], rel[:, 2])) / 6.0
    cone_centroid = (apex + corners.sum(axis=1)) / 4.0
    bone_volume = np.bincount(labels, weights=volume, minlength=m)
    bone_moment = np.stack([np.bincount(labels, weights=volume * cone_centroid[:, k], minlength=m)
                            for k in range(3)], axis=1)
    adjacency: dict[int, list[tuple[int, int]]] = {}
    for i, (ja, jb) in enumerate(B):
        adjacency.setdefault(int(ja), []).append((i, int(jb)))
        adjacency.setdefault(int(jb), []).append((i, int(ja)))
    edges, face_edges = _edges(F)
    by_bone = _split(np.arange(len(F)), labels, m)
    z0 = float(V[:, 2].min())
    out = []
    for i, (ja, jb) in enumerate(B):
        length = float(np.linalg.norm(Jt[jb] - Jt[ja]))
        if i in held_bones or length <= 1e-9:
            continue
        sides = {}
        for start in (int(ja), int(jb)):
            seen_b, seen_j, stack = set(), {start}, [start]
            while stack:
                j = stack.pop()
                for bone, other in adjacency.get(j, []):
                    if bone != i and bone not in seen_b:
                        seen_b.add(bone)
                        if other not in seen_j:
                            seen_j.add(other)
                            stack.append(other)
            sides[start] = (seen_b, seen_j)
        held_a, held_b = bool(sides[int(ja)][0] & held_bones), bool(sides[int(jb)][0] & held_bones)
        if held_a == held_b:
            continue  # held on both sides (not a cantilever) or on neither
        near, far = (int(ja), int(jb)) if held_a else (int(jb), int(ja))
        free_bones, free_joints = sides[far]
        n = (Jt[far] - Jt[near]) / length
        basis = _basis(n)
        gripped = [e for e in range(len(ends)) if int(ends[e]) in free_joints]
        free_list = np.array(sorted(free_bones), np.int64)
        base_volume = bone_volume[free_list].sum() if len(free_list) else 0.0
        base_moment = bone_moment[free_list].sum(axis=0) if len(free_list) else np.zeros(3)
        own = by_bone[i]
        ring = {i}
        for _ in range(2):  # the bones within two joints: a limb's outline lies on their faces
            ring |= {bone for k in ring for j in B[k] for bone, _ in adjacency.get(int(j), [])}
        nearby = np.concatenate([by_bone[k] for k in sorted(ring)])
        for frac in BONE_SAMPLES:
            origin = Jt[near] + frac * (Jt[far] - Jt[near])
            outline = _plane_outline(V, F, edges, face_edges, origin, basis, nearby)
            if outline is None:
                outline = _plane_outline(V, F, edges, face_edges, origin, basis)
            if outline is None:
                continue
            pts, area, J2, centroid, faces = outline
            beyond = own[(cone_centroid[own] - origin) @ n > 0]
            vol = base_volume + volume[beyond].sum()
            mom = base_moment + (volume[beyond, None] * cone_centroid[beyond]).sum(axis=0)
            local = lambda v: basis @ v  # noqa: E731 - world to (e1, e2, n)
            weight = local(np.array([0.0, 0.0, -weight_per_mm3 * vol])) if vol > 0 else None
            lever = local(mom / vol - centroid) if vol > 0 else np.zeros(3)
            gl = [(int(ends[e]), 1.0, local(Jt[ends[e]] - centroid)) for e in gripped]
            strength = float(effective_strength(mat, n[2]))
            safety, stress, breaks, end = _verdict(pts, area, J2, 1.0, weight, lever, gl, strength, load_n)
            across = n[2] ** 2 / mat.across_mpa >= (1.0 - n[2] ** 2) / mat.along_mpa
            out.append(Section("bone", float(centroid[2] - z0), centroid, i, bool(across), float(safety), stress,
                               strength, breaks, end, area, faces))
    return out


def _basis(n):
    """(3, 3) float64: rows ``e1, e2, n`` right-handed (``e1 × e2 = n``)."""
    helper = np.zeros(3)
    helper[np.argmin(np.abs(n))] = 1.0
    e1 = np.cross(helper, n)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(n, e1), n])
