"""Sections of a closed surface by planes: outlines, their areas and moments, and the parts between planes.

A closed, outward oriented surface cut by a plane leaves closed outlines whose segments are the crossings of its
triangles with the plane; run with the outside on their right (seen from the plane's normal) they go
counter-clockwise round the material and clockwise round holes, so Green's theorem sums the area and moments of
the section over the segments in any order (:func:`section_moments`). :func:`layer_sections` cuts by many
horizontal planes at once and also splits the surface between each two planes into its connected parts, which is
how :mod:`supportless.energies.strength` knows which part of a body hangs on which section.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.graph import edge_components

__all__ = ["LayerSections", "central_moments", "group_by", "layer_sections", "mesh_edges", "outline_around",
           "plane_frame", "section_moments"]


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


def central_moments(moments: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A (s,), centroid (s, 2), J (s, 2, 2))``: second moments about each region's centroid."""
    A = moments[:, 0]
    safe = np.where(np.abs(A) > 0, A, 1.0)
    c = moments[:, 1:3] / safe[:, None]
    J = np.empty((len(A), 2, 2))
    J[:, 0, 0] = moments[:, 3] - A * c[:, 0] ** 2
    J[:, 1, 1] = moments[:, 4] - A * c[:, 1] ** 2
    J[:, 0, 1] = J[:, 1, 0] = moments[:, 5] - A * c[:, 0] * c[:, 1]
    return A, c, J


def mesh_edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


def winding_numbers(points: np.ndarray, first: np.ndarray, second: np.ndarray, group: np.ndarray, count: int) -> np.ndarray:
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
    edges, face_edges = mesh_edges(F)
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
    n_loops, loop_of = edge_components(N, n1, n2)
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
            w = winding_numbers(rel[first_node[hs]], rel[n1[mask]], rel[n2[mask]], local, len(os_))
            area = loop_m[os_, 0]
            for j, h in enumerate(hs):
                inside = np.flatnonzero(w[:, j] != 0)
                if len(inside):
                    section_of_loop[h] = section_of_loop[os_[inside[np.argmin(area[inside])]]]
    S = len(outer)
    kept = section_of_loop >= 0
    sec_m = np.zeros((S, 6))
    np.add.at(sec_m, section_of_loop[kept], loop_m[kept])
    area, centroid, J = central_moments(sec_m)
    layer = loop_layer[outer]
    centroid = centroid + origin[layer]
    node_section = section_of_loop[loop_of]
    good = node_section >= 0
    seg_section = section_of_loop[seg_loop]
    section_faces = group_by(seg_face[seg_section >= 0], seg_section[seg_section >= 0], S)

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
    n_parts, part_of = edge_components(total, r, c)
    part_slab = np.full(n_parts, -2, np.int64)
    part_slab[part_of[bottom]] = node_layer
    part_slab[part_of[top]] = node_layer - 1
    part_slab[part_of[vert]] = vertex_slab
    # each section's parts above (its plane's slab) and below
    above = [sorted(set(x)) for x in group_by(part_of[bottom[good]], node_section[good], S)]
    below = [sorted(set(x)) for x in group_by(part_of[top[good]], node_section[good], S)]
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
    part_points = group_by(np.concatenate([node_xyz, node_xyz]), np.concatenate([part_of[bottom], part_of[top]]),
                         n_parts)
    points = rel[good] + origin[node_layer[good]]
    return LayerSections(p, layer, area, centroid, J, points, node_section[good], above, below, part_slab,
                         part_volume, part_centroid, part_points, section_faces)


def group_by(values: np.ndarray, keys: np.ndarray, count: int) -> list:
    """``values`` grouped by ``keys`` (0..count-1) into a list of arrays."""
    order = np.argsort(keys, kind="stable")
    bounds = np.searchsorted(keys[order], np.arange(count + 1))
    v = values[order]
    return [v[bounds[i]:bounds[i + 1]] for i in range(count)]


def outline_around(V, F, edges, face_edges, origin, basis, faces=None, along=None):
    """The outline round ``origin`` of the section of a closed surface by the plane through it square to
    ``basis[2]``: ``(points (q, 2), area, J (2, 2), centroid (3,), faces)`` in the basis's ``(e1, e2)`` about the
    centroid; None where no closed outline encloses ``origin``. Only ``faces`` (indices) are cut when given: an
    outline they leave open is not one. ``along``, ``V @ basis[2]`` when known (several planes of one normal)."""
    d = (V @ basis[2] if along is None else along) - origin @ basis[2]
    below = d < 0
    candidates = np.arange(len(F)) if faces is None else faces
    fb = below[F[candidates]]
    cut_faces = candidates[(fb[:, 0] != fb[:, 1]) | (fb[:, 1] != fb[:, 2])]  # corners on both sides
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
    n_loops, loop_of = edge_components(len(ce), n1, n2)
    seg_loop = loop_of[n1]
    degree = np.bincount(n1, minlength=len(ce)) + np.bincount(n2, minlength=len(ce))
    open_ = np.zeros(n_loops, bool)
    open_[loop_of[crossing & (degree != 2)]] = True
    m = section_moments(xy[n1], xy[n2], seg_loop, n_loops)
    w = winding_numbers(np.zeros((1, 2)), xy[n1], xy[n2], seg_loop, n_loops)[:, 0]
    enclosing = np.flatnonzero((w != 0) & (m[:, 0] > 0) & ~open_)
    if not len(enclosing):
        return None
    loop = enclosing[np.argmin(m[enclosing, 0])]
    A, c, J = central_moments(m[loop:loop + 1])
    pts = xy[crossing & (loop_of == loop)] - c[0]
    centroid = origin + c[0] @ basis[:2]
    return pts, float(A[0]), J[0], centroid, cut_faces[seg_loop == loop]


def plane_frame(n):
    """(3, 3) float64: rows ``e1, e2, n`` right-handed (``e1 × e2 = n``)."""
    helper = np.zeros(3)
    helper[np.argmin(np.abs(n))] = 1.0
    e1 = np.cross(helper, n)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(n, e1), n])
