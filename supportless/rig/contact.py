"""Contact a sculptor would make: where a posed body may press into itself, and where it may not.

A figure posed with its arms resting at its sides presses the upper arm into
the torso at the armpit; legs brought together press the thighs into each
other below the hips; a chin lowered meets the chest. Skinning cannot bend
skin around such a contact, so the posed surface crosses itself there; the
written print body is then the surface's union with itself
(:func:`supportless.files.printbody.resolved_crossings`), one closed solid.
What stays forbidden is a part passing through a part it is not jointed to
(a hand through the head, a foot through the other shin) and any overlap far
from the joint the two parts share.

The rules, from the rig alone:

* **parts**: each surface triangle belongs to the bone with the largest
  summed skinning weight on its corners (:attr:`BodyParts.face_bone`);
* **jointed**: two bones whose shortest path over shared joints passes
  through fewer than :data:`CONTACT_HOPS` other parts (bones that own no
  triangle, a glTF skeleton's helper bones, are not parts: they join what
  they touch). An upper arm and the chest bone it hangs from through the
  shoulder are 2 apart, the two thighs at the hips 1, a forearm and the chest
  3, a hand and the head or a foot and the other shin more;
* **near**: the crossing lies within :data:`CONTACT_REACH` times the longer
  of the two bones of a joint on that path;
* **shallow**: no vertex of one part lies deeper inside the other than
  :data:`CONTACT_DEPTH` times the thinner part's thickness (twice the median
  distance of its vertices from its bone at rest);
* **small**: the volume covered twice is at most :data:`CONTACT_VOLUME` of
  the body's (the ray grid of :mod:`supportless.energies.intersection`).

A crossing that breaks any rule makes the pose refused, as any crossing was
before. :func:`contact_verdict` says which rule, and names the contact regions
of an accepted one.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..base.closest import nearest_other_face

__all__ = ["CONTACT_DEPTH", "CONTACT_HOPS", "CONTACT_REACH", "CONTACT_VOLUME", "BodyParts", "ContactRules",
           "ContactVerdict", "RefusedCrossings", "contact_verdict", "refused_by_pairs"]

#: Parts at most this many steps apart are "jointed" (a step into a bone that owns no triangle is free): upper
#: arm and chest (through the shoulder) 2, the two thighs (at the hips) 1. A forearm and the chest are 3, a hand
#: and the head 6.
CONTACT_HOPS = 2

#: A crossing between jointed parts lies within this many times the longer bone's length of a joint on the path
#: between them (the upper arm resting along the torso down to the elbow).
CONTACT_REACH = 1.0

#: No vertex of one part deeper inside another than this share of the thinner part's thickness.
CONTACT_DEPTH = 0.5

#: The volume covered twice, at most this share of the body's.
CONTACT_VOLUME = 0.02

#: Vertices inside another part x triangles up to which the contact depth scans every triangle for each vertex
#: (compiled, :func:`~supportless.base.closest.nearest_other_face`) instead of building a distance tree per part:
#: the Xbot's search proxy, about 80 such vertices of 10 000 triangles, 0.16 s -> 0.02 s a check (2 cores, loaded).
SCAN_BUDGET = 20_000_000


@dataclass(frozen=True)
class ContactRules:
    """The bounds of :func:`contact_verdict` (:data:`CONTACT_HOPS` ...); ``hops=-1`` allows no contact at all."""

    hops: int = CONTACT_HOPS
    reach: float = CONTACT_REACH
    depth: float = CONTACT_DEPTH
    volume: float = CONTACT_VOLUME

    @property
    def allows_contact(self) -> bool:
        return self.hops >= 0

    def covers_too_much(self, overlap_volume: float | None, body_volume: float | None) -> bool:
        """The verdict's last rule: the volume covered twice is over ``volume`` of the body's (unchecked when
        either is None or the body's is 0)."""
        return overlap_volume is not None and bool(body_volume) and overlap_volume > self.volume * body_volume


@dataclass
class ContactVerdict:
    """What :func:`contact_verdict` found.

    Attributes
    ----------
    allowed : bool
        True when every crossing is a contact within the rules (or there is none).
    pairs : int
        Intersecting triangle pairs.
    reason : str
        Why not, in words ("" when allowed).
    regions : list of dict
        One per pair of bones in contact: ``bones`` (two indices, smaller first), ``pairs`` (triangle pairs
        between them), ``depth`` (deepest vertex, in the thinner part's thicknesses).
    overlap_volume : float
        The volume covered twice (model units cubed), when measured; else 0.
    """

    allowed: bool
    pairs: int
    reason: str = ""
    regions: list = field(default_factory=list)
    overlap_volume: float = 0.0


class BodyParts:
    """A rig's surface split into bone regions, and the skeleton's distances between them.

    Parameters
    ----------
    vertices : (n, 3) float64
        Rest surface.
    faces : (f, 3) int64
    weights : (n, m) float64 or scipy.sparse matrix
        Skinning weights of the surface vertices.
    joints : (j, 3) float64
        Rest joints.
    bones : (m, 2) int64
    names : list of str, optional
        Bone names, for the verdict's words.
    """

    def __init__(self, vertices, faces, weights, joints, bones, names=None):
        self.names = list(names) if names is not None else None
        self.vertices = np.asarray(vertices, np.float64)
        self.faces = np.asarray(faces, np.int64)
        W = weights.toarray() if hasattr(weights, "toarray") else np.asarray(weights, np.float64)
        self.joints = np.asarray(joints, np.float64)
        self.bones = np.asarray(bones, np.int64)
        self.vertex_bone = np.argmax(W, axis=1).astype(np.int64)
        face_weight = W[self.faces[:, 0]] + W[self.faces[:, 1]] + W[self.faces[:, 2]]
        self.face_bone = np.argmax(face_weight, axis=1).astype(np.int64)

    @cached_property
    def lengths(self) -> np.ndarray:
        """(m,) float64: bone lengths at rest."""
        return np.linalg.norm(self.joints[self.bones[:, 1]] - self.joints[self.bones[:, 0]], axis=1)

    @cached_property
    def thickness(self) -> np.ndarray:
        """(m,) float64: twice the median distance of each bone's vertices from its bone at rest (the median
        over bones for a bone with no vertex)."""
        a, b = self.joints[self.bones[self.vertex_bone, 0]], self.joints[self.bones[self.vertex_bone, 1]]
        d = _segment_distance(self.vertices, a, b)
        m = len(self.bones)
        out = np.full(m, np.nan)
        for k in range(m):
            mine = d[self.vertex_bone == k]
            if len(mine):
                out[k] = 2.0 * float(np.median(mine))
        fill = np.nanmedian(out) if np.any(np.isfinite(out)) else 1.0
        return np.where(np.isfinite(out) & (out > 0), out, fill)

    @cached_property
    def _paths(self) -> tuple[np.ndarray, np.ndarray]:
        """Steps between parts (m, m) int64 (a large number when unconnected) and predecessors (m, m) int64.

        Each bone is a node, bones sharing a joint are joined by an edge of half the sum of their costs (1 for a
        bone that owns triangles, ~0 for one that owns none): a path's length is the number of parts it passes
        through, plus one.
        """
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import shortest_path

        m = len(self.bones)
        share = np.zeros((m, m), bool)
        for k in range(2):
            for kk in range(2):
                share |= self.bones[:, k][:, None] == self.bones[:, kk][None, :]
        np.fill_diagonal(share, False)
        owns = np.bincount(self.face_bone, minlength=m) > 0
        cost = np.where(owns, 1.0, 1e-6)
        dist, pred = shortest_path(csr_matrix(share * (cost[:, None] + cost[None, :]) / 2), return_predecessors=True)
        hops = np.where(np.isfinite(dist), np.round(dist), 1e9).astype(np.int64)
        return hops, pred

    @property
    def hops(self) -> np.ndarray:
        """(m, m) int64: the fewest shared joints from one bone to another (0 on the diagonal)."""
        return self._paths[0]

    def path_joints(self, a: int, b: int) -> np.ndarray:
        """(k,) int64: the joints on the shortest path from bone ``a`` to bone ``b``: those shared by consecutive
        bones, and both bones' own joints."""
        pred = self._paths[1]
        found = set(self.bones[a].tolist()) | set(self.bones[b].tolist())
        node = b
        while node != a and pred[a, node] >= 0:
            found |= set(self.bones[node].tolist()) & set(self.bones[pred[a, node]].tolist())
            node = pred[a, node]
        return np.array(sorted(found), np.int64)


def _segment_distance(P, A, B) -> np.ndarray:
    """(n,) float64 distance of each point P[i] from the segment A[i]B[i]."""
    AB = B - A
    t = np.einsum("ij,ij->i", P - A, AB) / np.maximum(np.einsum("ij,ij->i", AB, AB), 1e-300)
    return np.linalg.norm(P - (A + np.clip(t, 0, 1)[:, None] * AB), axis=1)


def contact_verdict(parts: BodyParts, vertices: np.ndarray, posed_joints: np.ndarray, pairs: np.ndarray,
                    rules: ContactRules = ContactRules(), overlap_volume: float | None = None,
                    body_volume: float | None = None) -> ContactVerdict:
    """Whether the crossings of a posed surface are all contact within the rules (module docstring).

    Parameters
    ----------
    parts : BodyParts
        Of the rig whose surface is posed.
    vertices : (n, 3) float64
        The posed surface (any rigid placement, with ``posed_joints`` in the same one).
    posed_joints : (j, 3) float64
    pairs : (k, 2) int64
        Its intersecting triangle pairs (:func:`supportless.copyleft.cgal.intersecting_faces`).
    rules : ContactRules
    overlap_volume, body_volume : float, optional
        The volume covered twice and the body's, to bound their ratio (unchecked when either is None).

    Returns
    -------
    verdict : ContactVerdict
    """
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    k = len(pairs)
    volume = float(overlap_volume or 0.0)
    if k == 0:
        return ContactVerdict(True, 0, overlap_volume=volume)
    if not rules.allows_contact:
        return ContactVerdict(False, k, f"{k} pairs of triangles cross", overlap_volume=volume)
    V = np.asarray(vertices, np.float64)
    reason, regions = _pair_rules(parts, V, posed_joints, pairs, rules)
    if reason is not None:
        return ContactVerdict(False, k, reason, overlap_volume=volume)
    names = _name_of(parts)
    deepest = _deepest(parts, V, np.unique(parts.face_bone[pairs]))
    for region in regions:
        a, b = region["bones"]
        d = max(deepest.get((a, b), 0.0), deepest.get((b, a), 0.0))
        region["depth"] = d / float(min(parts.thickness[a], parts.thickness[b]))
    for vb, ob in deepest:  # a part pressed into one it does not share a crossing with (deep inside)
        if parts.hops[min(vb, ob), max(vb, ob)] > rules.hops:
            return ContactVerdict(False, k, f"{names(vb)} lies inside {names(ob)}, a part it is not jointed to",
                                  regions, volume)
        ratio = deepest[(vb, ob)] / float(min(parts.thickness[vb], parts.thickness[ob]))
        if ratio > rules.depth:
            return ContactVerdict(False, k, f"{names(vb)} presses {ratio:.2f} of its thickness into {names(ob)} "
                                  f"(at most {rules.depth:.2f})", regions, volume)
    if rules.covers_too_much(overlap_volume, body_volume):
        return ContactVerdict(False, k, f"the contact covers {overlap_volume / body_volume:.1%} of the body's "
                              f"volume twice (at most {rules.volume:.0%})", regions, volume)
    return ContactVerdict(True, k, "", regions, volume)


def _pair_rules(parts: BodyParts, V: np.ndarray, posed_joints: np.ndarray, pairs: np.ndarray,
                rules: ContactRules) -> tuple[str | None, list[dict]]:
    """The rules each crossing pair (k, 2) int64 keeps or breaks by itself: the two parts are jointed, and the
    crossing is near a joint between them. The first broken one's reason (None when none is), and the contact
    regions of the pairs (``{"bones", "pairs", "depth": 0.0}``; none when a rule is broken)."""
    k = len(pairs)
    ba, bb = parts.face_bone[pairs[:, 0]], parts.face_bone[pairs[:, 1]]
    lo, hi = np.minimum(ba, bb), np.maximum(ba, bb)
    names = _name_of(parts)
    far = np.flatnonzero(parts.hops[lo, hi] > rules.hops)
    if len(far):
        i = far[0]
        return f"{names(lo[i])} crosses {names(hi[i])}, a part it is not jointed to ({len(far)} of {k} pairs)", []
    where = V[parts.faces[pairs]].reshape(k, 6, 3).mean(axis=1)  # (k, 3) a point of each crossing
    regions = []
    for a, b in np.unique(np.stack([lo, hi], 1), axis=0):
        mine = np.flatnonzero((lo == a) & (hi == b))
        J = posed_joints[parts.path_joints(int(a), int(b))]
        reach = rules.reach * max(parts.lengths[a], parts.lengths[b], 1e-12)
        dist = np.min(np.linalg.norm(where[mine, None, :] - J[None, :, :], axis=2), axis=1)
        if np.any(dist > reach):
            return (f"{names(a)} and {names(b)} cross {dist.max() / reach:.1f}x farther from their shared joint "
                    "than a contact may"), []
        regions.append({"bones": [int(a), int(b)], "pairs": int(len(mine)), "depth": 0.0})
    return None, regions


def refused_by_pairs(parts: BodyParts, vertices: np.ndarray, posed_joints: np.ndarray, pairs: np.ndarray,
                     rules: ContactRules) -> bool:
    """Whether some of a posed surface's crossing pairs refuse it by themselves.

    They do when no contact is allowed, or when one of them joins parts that are not jointed or crosses too far
    from their joint (:func:`_pair_rules`). Each such rule judges a pair alone, so the surface is refused by
    :func:`contact_verdict` of all its pairs as well, whatever the others are.

    Parameters
    ----------
    parts : BodyParts
    vertices : (n, 3) float64
        The posed surface, with ``posed_joints`` (j, 3) float64 in the same placement.
    pairs : (k, 2) int64
        Some of its intersecting triangle pairs.
    rules : ContactRules

    Returns
    -------
    refused : bool
        False for no pairs.
    """
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    if not len(pairs):
        return False
    if not rules.allows_contact:
        return True
    return _pair_rules(parts, np.asarray(vertices, np.float64), posed_joints, pairs, rules)[0] is not None


class RefusedCrossings:
    """The triangles of the last refused pose's crossings, asked first about the next pose.

    A search keeps proposing poses near the one refused last (a forearm through the hips again), whose crossings
    are mostly among the same triangles. CGAL's pairs among some triangles are pairs of the whole surface, so
    when those refuse the pose by themselves (:func:`refused_by_pairs`), :func:`contact_verdict` of all its pairs
    refuses it too, and the exact test of the whole surface is not needed.
    """

    def __init__(self):
        self.faces: np.ndarray | None = None

    def refuse(self, parts: BodyParts, vertices: np.ndarray, posed_joints: np.ndarray, rules: ContactRules) -> bool:
        """Whether the remembered triangles' crossings in the posed ``vertices`` (n, 3) float64 refuse it by
        themselves (False when nothing is remembered)."""
        if self.faces is None:
            return False
        from ..copyleft.cgal import intersecting_faces

        pairs = intersecting_faces(vertices, parts.faces[self.faces])
        return refused_by_pairs(parts, vertices, posed_joints, self.faces[pairs], rules)

    def remember(self, pairs: np.ndarray) -> None:
        """Keep the triangles of a refused pose's crossing pairs (k, 2) int64."""
        self.faces = np.unique(np.asarray(pairs, np.int64))


def _deepest(parts: BodyParts, V: np.ndarray, bones: np.ndarray) -> dict:
    """``{(bone, other): depth}``: how deep the vertices of ``bones`` (m_i,) int64 lie inside the posed body's
    other parts (winding number above one), by distance to the nearest triangle of another part."""
    import igl

    F = parts.faces
    candidates = np.flatnonzero(np.isin(parts.vertex_bone, bones))
    if not len(candidates):
        return {}
    wn = igl.fast_winding_number(V, F, np.ascontiguousarray(V[candidates]))
    inside = candidates[np.asarray(wn) > 1.0]
    out: dict = {}
    if len(inside) * len(F) <= SCAN_BUDGET:  # a few vertices: one scan of the triangles beats a tree per part
        d2, nearest = nearest_other_face(V[inside], parts.vertex_bone[inside], V, F, parts.face_bone)
        found = nearest >= 0
        _deepest_per_pair(out, parts.vertex_bone[inside][found], parts.face_bone[nearest[found]], d2[found])
        return out
    for vb in np.unique(parts.vertex_bone[inside]):
        P = inside[parts.vertex_bone[inside] == vb]
        others = np.flatnonzero(parts.face_bone != vb)
        if not len(others):
            continue
        d2, nearest, _ = igl.point_mesh_squared_distance(np.ascontiguousarray(V[P]), V, F[others])
        ob = parts.face_bone[others[np.asarray(nearest, np.int64)]]
        _deepest_per_pair(out, np.full(len(P), vb), ob, np.asarray(d2))
    return out


def _deepest_per_pair(out: dict, vb: np.ndarray, ob: np.ndarray, d2: np.ndarray) -> None:
    """Into ``out``, ``{(bone, other): depth}``: the largest distance ``sqrt(d2)`` (k,) float64 over the vertices of
    ``bone`` (``vb`` (k,) int64) whose nearest triangle of another part is of ``other`` (``ob`` (k,) int64)."""
    d = np.sqrt(d2)
    for a, o in np.unique(np.stack([vb, ob], 1), axis=0):
        out[(int(a), int(o))] = float(d[(vb == a) & (ob == o)].max())


def _name_of(parts: BodyParts):
    names = parts.names
    return (lambda b: names[int(b)]) if names else (lambda b: f"bone {int(b) + 1}")
