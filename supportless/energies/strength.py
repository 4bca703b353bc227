"""The strength of a printed body: the stress across and along its layers under its weight and a grip.

A layered print is weakest between its layers: the bond across them holds about half of what a line holds along
its length (PLA; :data:`~supportless.energies.materials.MATERIALS`). A pose that saves support can leave an ankle, a wrist or a tail whose layers
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
  held by the bond between layers, the rest by the lines (:func:`~supportless.energies.materials.effective_strength`).

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

from ..base.graph import edge_components
from .materials import DEFAULT_MATERIAL, MATERIALS, Material, effective_strength, mostly_across
from .sections import LayerSections, group_by, layer_sections, mesh_edges, outline_around, plane_frame

__all__ = ["BONE_SAMPLES", "CHAIN_REACH", "GRAVITY", "HANDLING_LOAD_N", "HELD_SHARE", "MAX_PLANES", "Section",
           "Strength", "analyse_strength", "chain_ends", "grip_points", "grip_stress"]

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
#: A chain's end is its branching joint when the branch is this close (a share of the body's largest extent) to
#: each of its leaves: a hand of fingers is gripped at the hand.
CHAIN_REACH = 0.12


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
    lever : (3,) or (E, 3) float64
        The force's point relative to the centroid, in ``(e1, e2, n)`` (several forces: one each).
    sign : float
        +1: the free part is on the ``+n`` side; -1: on the ``-n`` side.

    Returns
    -------
    g : (q, 3) or (E, q, 3) float64
        MPa per N.
    """
    r = np.asarray(lever, np.float64)
    single = r.ndim == 1
    r = np.atleast_2d(r)
    R = np.zeros((len(r), 2, 3))  # [-M_2, M_1] = R u
    R[:, 0, 0] = R[:, 1, 1] = -r[:, 2]
    R[:, 0, 2] = r[:, 0]
    R[:, 1, 2] = r[:, 1]
    a, b, c, d = (float(x) for x in np.ravel(J))
    eps = 1e-12 * (a + d)
    det = (a + eps) * (d + eps) - b * c
    # the 2 x 2 inverse in closed form (a section's second moments: symmetric, positive unless degenerate)
    Jinv = np.array([[d + eps, -b], [-c, a + eps]]) / det if a + d > 0 and det != 0 else np.zeros((2, 2))
    g = (points @ Jinv) @ R  # (E, q, 3)
    g[..., 2] += 1.0 / area
    g *= sign
    return g[0] if single else g


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
    normal : (3,) float64
        The section's plane's unit normal, towards the free part for a bone section (+Z for a layer's).
    grip : (3,) float64
        The worst grip's unit direction on the free part (zero when no grip loads the section).
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
    normal: np.ndarray = field(repr=False, default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    grip: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(3))


def _verdict(points, area, J, sign, weight_force, weight_lever, grips, strength, load_n):
    """``(safety, stress, breaks_at, chain_end, grip)`` of a section under its free part's weight and grips.

    ``grips`` is a list of ``(chain_end, share, lever (3,))``; ``grip (3,)`` is the worst grip's unit direction
    in the section's axes (zero when none loads it); the rest as :func:`grip_stress`."""
    sigma_w = grip_stress(points, area, J, weight_lever, sign) @ weight_force if weight_force is not None else \
        np.zeros(len(points))
    worst = np.zeros(len(points))
    which = np.full(len(points), -1)
    g = None
    if grips:
        ends = np.array([e for e, _, _ in grips])
        shares = np.array([w for _, w, _ in grips])
        g = shares[:, None, None] * grip_stress(points, area, J, np.array([x for _, _, x in grips]), sign)
        size = np.linalg.norm(g, axis=2)  # (E, q)
        best = np.argmax(size, axis=0)
        worst = size[best, np.arange(len(points))]
        which = np.where(worst > 0, ends[best], -1)
    total = sigma_w + load_n * worst
    i = int(np.argmax(total))
    stress = float(total[i])
    safety = strength / stress if stress > 0 else np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        breaks = np.where(worst > 0, (strength - sigma_w) / worst, np.inf)
    breaks = float(max(breaks.min(), 0.0))
    grip = np.zeros(3) if g is None or worst[i] <= 0 else g[best[i], i] / worst[i]
    return safety, stress, breaks, int(which[i]), grip


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


def grip_points(joints: np.ndarray, bones: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Where each chain end is gripped: a branching joint (a hand of fingers) at itself, a leaf (a paw, an ear,
    the top of a head) halfway along its bone: fingers hold a part, not its very tip, where a tapering limb is
    thinnest.

    Parameters
    ----------
    joints : (j, 3) float64
    bones : (m, 2) int64
    ends : (e,) int64

    Returns
    -------
    points : (e, 3) float64
    """
    B = np.asarray(bones, np.int64)
    degree = np.bincount(B.ravel(), minlength=len(joints))
    points = np.asarray(joints, np.float64)[ends].copy()
    for k, j in enumerate(ends):
        if degree[j] == 1:
            a, b = B[np.flatnonzero((B == j).any(axis=1))[0]]
            points[k] = 0.5 * (joints[a] + joints[b])
    return points


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
    size = float(np.ptp(V, axis=0).max())  # the figure's size, however it lies
    ends = chain_ends(Jt, B, CHAIN_REACH * size) if ends is None else np.asarray(ends, np.int64)
    grips = grip_points(Jt, B, ends)
    weight_per_mm3 = mat.density * GRAVITY * 1e-6  # N/mm³
    face_safety = np.full(len(F), np.inf)
    sections = []
    held = max(float(layer_mm), HELD_SHARE * height) if held_mm is None else float(held_mm)
    spacing = max(float(layer_mm), height / max(int(max_planes), 1))
    planes = np.arange(z0 + held, z1, spacing)
    if len(planes):
        sections += _layer_verdicts(V, layer_sections(V, F, planes), labels, ends, grips, mat,
                                    weight_per_mm3, load_n)
    sections += _bone_verdicts(V, F, Jt, B, labels, ends, grips, mat, weight_per_mm3, load_n, z0 + held)
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
    (``(volume, moment, {end: share}, held)``). The sections through which one free part rests on the parts
    nearer the plate carry its loads together, as one section (the part joins them rigidly: two legs under a
    pelvis bend as a frame, pushing and pulling); what they pass on is shared in proportion to their areas.

    Returns
    -------
    list of ``(sections, sign, (volume, moment (3,), {end: share}))``: sign +1 where the free part is above.
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
        out.append(([s for s, _ in toward], 1.0 if u[0] == "A" else -1.0, (vol, mom, shares)))
        for s, v in toward:
            w = area[s] / total
            part = (vol * w, mom * w, {e: x * w for e, x in shares.items()})
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
    points = group_by(cut.points, cut.point_section, len(cut.layer))
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
        for group, sign, (volume, moment, shares) in _carry(sections, cut.area, above_root, below_root, la, lb):
            A = cut.area[group].sum()  # the group's sections as one: area, centroid, second moments
            c = (cut.area[group, None] * cut.centroid[group]).sum(axis=0) / A
            d = cut.centroid[group] - c
            J = (cut.J[group] + cut.area[group, None, None] * d[:, :, None] * d[:, None, :]).sum(axis=0)
            c3 = np.array([c[0], c[1], cut.planes[k]])
            weight = np.array([0.0, 0.0, -weight_per_mm3 * volume]) if volume > 0 else None
            lever = moment / volume - c3 if volume > 0 else np.zeros(3)
            gl = [(int(ends[e]), share, end_points[e] - c3) for e, share in shares.items()]
            for s in group:
                safety, stress, breaks, end, grip = _verdict(points[s] - c, A, J, sign, weight, lever, gl,
                                                             mat.across_mpa, load_n)
                faces = cut.section_faces[s]
                bone = int(np.bincount(labels[faces]).argmax()) if len(faces) else -1
                centre = np.array([cut.centroid[s, 0], cut.centroid[s, 1], cut.planes[k]])
                out.append(Section("layer", float(cut.planes[k] - z0), centre, bone, True, float(safety), stress,
                                   mat.across_mpa, breaks, end, float(cut.area[s]), faces,
                                   np.array([0.0, 0.0, 1.0]), grip))
    return out


def _hangs_free(V, F, edges, faces, origin, normal, held_below) -> bool:
    """Whether the surface beyond a section (reached from its outline's ``faces`` without crossing the plane
    through ``origin`` square to ``normal``) stays clear of the held part (``z < held_below``)."""
    beyond = (V - origin) @ normal > 0
    inner = beyond[edges[:, 0]] & beyond[edges[:, 1]]
    _, label = edge_components(len(V), edges[inner, 0], edges[inner, 1])
    start = np.unique(F[faces].ravel())
    start = start[beyond[start]]
    reached = np.isin(label, np.unique(label[start]))
    return not bool(np.any(reached & beyond & (V[:, 2] < held_below)))


def _bone_verdicts(V, F, Jt, B, labels, ends, grip_at, mat, weight_per_mm3, load_n, held_below):
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
    edges, face_edges = mesh_edges(F)
    by_bone = group_by(np.arange(len(F)), labels, m)
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
        basis = plane_frame(n)
        gripped = [e for e in range(len(ends)) if int(ends[e]) in free_joints]
        free_list = np.array(sorted(free_bones), np.int64)
        base_volume = bone_volume[free_list].sum() if len(free_list) else 0.0
        base_moment = bone_moment[free_list].sum(axis=0) if len(free_list) else np.zeros(3)
        own = by_bone[i]
        ring = {i}
        for _ in range(2):  # the bones within two joints: a limb's outline lies on their faces
            ring |= {bone for k in ring for j in B[k] for bone, _ in adjacency.get(int(j), [])}
        nearby = np.concatenate([by_bone[k] for k in sorted(ring)])
        checked = False
        along = V @ n  # the planes of one bone share their normal
        for frac in BONE_SAMPLES:
            origin = Jt[near] + frac * (Jt[far] - Jt[near])
            outline = outline_around(V, F, edges, face_edges, origin, basis, nearby, along)
            if outline is None:
                outline = outline_around(V, F, edges, face_edges, origin, basis, along=along)
            if outline is None:
                continue
            pts, area, J2, centroid, faces = outline
            if centroid[2] < held_below:  # in the hand that holds the figure
                continue
            if not checked:  # a limb whose far side rests on the plate too (a staff) is no cantilever
                if not _hangs_free(V, F, edges, faces, origin, n, held_below):
                    break
                checked = True
            beyond = own[(cone_centroid[own] - origin) @ n > 0]
            vol = base_volume + volume[beyond].sum()
            mom = base_moment + (volume[beyond, None] * cone_centroid[beyond]).sum(axis=0)
            local = lambda v: basis @ v  # noqa: E731 - world to (e1, e2, n)
            weight = local(np.array([0.0, 0.0, -weight_per_mm3 * vol])) if vol > 0 else None
            lever = local(mom / vol - centroid) if vol > 0 else np.zeros(3)
            gl = [(int(ends[e]), 1.0, local(grip_at[e] - centroid)) for e in gripped
                  if (grip_at[e] - origin) @ n > 0]  # a grip nearer the plate than the section does not load it
            strength = float(effective_strength(mat, n[2]))
            safety, stress, breaks, end, grip = _verdict(pts, area, J2, 1.0, weight, lever, gl, strength, load_n)
            across = mostly_across(mat, n[2])
            out.append(Section("bone", float(centroid[2] - z0), centroid, i, bool(across), float(safety), stress,
                               strength, breaks, end, area, faces, n, basis.T @ grip))
    return out
