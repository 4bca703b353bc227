"""The print body: one closed solid from the parts of a real character.

Real rigged assets are not one closed surface: vertices are split at texture
seams, a character is several overlapping parts (eyes, hair, armour, joint
pieces), some shells are open (a body cut at the neck, single-sided hair).
:func:`print_body` makes the closed, manifold solid that is posed, checked
and printed, step by step, and carries per-vertex values (skin weights) along:

1. weld the vertices at the same position within each part;
2. drop degenerate and duplicate triangles;
3. split each part into its shells and close each open shell on its own
   (every boundary loop filled with a fan about its centre); shells that
   cannot be made manifold, or enclose (almost) no volume, are dropped;
4. the union of all shells (manifold3d) — never a repair that keeps only the
   largest part; shells that stay apart are kept as islands, those below
   :data:`ISLAND_MIN_VOLUME` of the whole are dropped;
5. triangles that still cross (manifold3d's union is exact only for inputs
   that do not cut themselves, and a shell closed by a fan may) are resolved
   by an exact self-union (CGAL, :func:`supportless.copyleft.cgal.self_union`),
   else the body is remade as the surface of its winding number.

Each step reports one line with what it did and how the volume changed.
Step 5 is :mod:`supportless.files.crossings`' (also what is printed of a posed
figure whose parts press into each other); the small surface operations are
:mod:`supportless.files.surfaceops`'. Their public names are importable from
here too.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..base.errors import InputError
from .crossings import (
    ISLAND_MIN_VOLUME,
    SIMPLIFY_TOLERANCE,
    WINDING_CELLS,
    _resolve_crossings,
    united_surface,
    winding_surface,
)
from .surfaceops import _collapse_short_edges, _components, _flip_caps, _volume, _weld, transfer_values

__all__ = ["united_surface", "BRIDGE_GAP", "ISLAND_MIN_VOLUME", "SHELL_MIN_VOLUME", "WINDING_CELLS", "winding_surface", "PrintBody", "print_body",
           "transfer_values"]

#: Closed shells below this fraction of the total volume are dropped (slivers,
#: flat single-sided pieces closed on themselves).
SHELL_MIN_VOLUME = 1e-4

#: Solids left apart after the union that come within this fraction of the
#: model's size of the largest solid are joined to it by a bridge (the convex
#: hull of the facing parts): a hand that misses its wrist by a hair.
BRIDGE_GAP = 0.01

#: Vertices closer than this fraction of the model's size are welded.
WELD_TOLERANCE = 1e-6


@dataclass
class PrintBody:
    """A closed solid and the values carried onto its vertices.

    Attributes
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, 2-manifold, outward oriented.
    values : (n, k) float64
        The input's per-vertex values, interpolated.
    islands : int
        Connected solids kept.
    log : list of str
        One line per step.
    """

    vertices: np.ndarray
    faces: np.ndarray
    values: np.ndarray
    islands: int = 1
    log: list = field(default_factory=list)


def _clean_faces(F: np.ndarray, V: np.ndarray, area_eps: float) -> tuple[np.ndarray, int, int]:
    """Drop faces with a repeated vertex or (almost) no area, and duplicates (any winding)."""
    repeated = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    degenerate = repeated | (area <= area_eps)
    F = F[~degenerate]
    _, first = np.unique(np.sort(F, axis=1), axis=0, return_index=True)
    dup = len(F) - len(first)
    return F[np.sort(first)], int(degenerate.sum()), dup


def _boundary_loops(F: np.ndarray) -> list[list[int]]:
    """Loops of boundary edges (edges used by one face), following their direction."""
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    und = np.sort(directed, axis=1)
    _, inv, counts = np.unique(und, axis=0, return_inverse=True, return_counts=True)
    boundary = directed[counts[inv.ravel()] == 1]
    nxt: dict[int, list[int]] = {}
    for a, b in boundary:
        nxt.setdefault(int(a), []).append(int(b))
    loops = []
    while nxt:
        start = next(iter(nxt))
        loop, v = [start], start
        while True:
            outs = nxt.get(v)
            if not outs:
                break
            w = outs.pop()
            if not outs:
                del nxt[v]
            if w == start:
                break
            loop.append(w)
            v = w
            if len(loop) > len(boundary):
                break
        if len(loop) >= 3:
            loops.append(loop)
    return loops


def _close_shell(V, F, values):
    """Fill every boundary loop with a fan about its centre (a new vertex). Returns V, F, values, loops filled."""
    loops = _boundary_loops(F)
    if not loops:
        return V, F, values, 0
    newV, newW, newF = [V], [values], [F]
    n = len(V)
    for loop in loops:
        idx = np.asarray(loop, np.int64)
        c = n
        n += 1
        newV.append(V[idx].mean(0, keepdims=True))
        newW.append(values[idx].mean(0, keepdims=True))
        # the boundary edge a->b belongs to a face with a->b; the cap uses b->a
        newF.append(np.column_stack([np.roll(idx, -1), idx, np.full(len(idx), c)]))
    return np.vstack(newV), np.vstack(newF), np.vstack(newW), len(loops)


def print_body(vertices: np.ndarray, faces: np.ndarray, part: np.ndarray, values: np.ndarray,
               part_names: list | None = None) -> PrintBody:
    """Make the closed solid to print from the parts of an asset.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    part : (f,) int64
        The part (primitive) of each face; welding stays within a part.
    values : (n, k) float64
        Per-vertex values to carry (skin weights); interpolated linearly where
        new vertices are made.
    part_names : list of str, optional

    Returns
    -------
    body : PrintBody

    Raises
    ------
    InputError
        When nothing closed is left.
    """
    import manifold3d

    V = np.asarray(vertices, np.float64)
    F = np.asarray(faces, np.int64)
    part = np.asarray(part, np.int64)
    values = np.asarray(values, np.float64)
    size = float(np.ptp(V, axis=0).max()) if len(V) else 1.0
    tol = WELD_TOLERANCE * size
    log: list[str] = []

    # 1-3: per part, weld, clean, close each shell
    shells = []
    welded = degenerate = duplicate = 0
    loops_filled = shells_closed = 0
    dropped: list[str] = []
    remade: list[str] = []
    for p in np.unique(part):
        Fp = F[part == p]
        used = np.unique(Fp)
        remap = np.full(len(V), -1, np.int64)
        remap[used] = np.arange(len(used))
        Vp, Fp, Wp, merged = _weld(V[used], remap[Fp], values[used], tol)
        welded += merged
        Fp, deg, dup = _clean_faces(Fp, Vp, (tol * tol) * 1e-6)
        degenerate += deg
        duplicate += dup
        if len(Fp) == 0:
            continue
        comp = _components(Fp, len(Vp))
        for c in range(comp.max() + 1):
            Fc = Fp[comp == c]
            u = np.unique(Fc)
            r = np.full(len(Vp), -1, np.int64)
            r[u] = np.arange(len(u))
            Vc, Fc, Wc = Vp[u], r[Fc], Wp[u]
            Vc, Fc, Wc, k = _close_shell(Vc, Fc, Wc)
            loops_filled += k
            shells_closed += k > 0
            vol = _volume(Vc, Fc)
            if vol < 0:
                Fc = Fc[:, ::-1]
            name = part_names[p] if part_names is not None and p < len(part_names) else f"part {p}"
            mesh = manifold3d.Mesh64(vert_properties=np.ascontiguousarray(np.hstack([Vc, Wc]), np.float64),
                                     tri_verts=np.ascontiguousarray(Fc, np.uint64))
            solid = manifold3d.Manifold(mesh)
            if solid.status() != manifold3d.Error.NoError or solid.is_empty():
                # closing cannot make it manifold (edges of three faces, folds): the winding number takes it below
                solid = None
                remade.append(name)
            shells.append((name, solid, abs(vol), (Vc, Fc, Wc)))
    log.append(f"welded {welded} seam-split vertices; dropped {degenerate} degenerate and {duplicate} duplicate "
               f"triangles")
    if not shells:
        raise InputError(None, "no part of the model can be closed into a solid; "
                         "export it as one closed mesh (or fix its open shells) and try again")
    total = sum(v for _, _, v, _ in shells)
    keep = [(n, s, v, g) for n, s, v, g in shells if v >= SHELL_MIN_VOLUME * total]
    dropped += [f"{n} (encloses {v / total:.1e} of the volume)" for n, s, v, g in shells
                if v < SHELL_MIN_VOLUME * total]
    remade = [n for n, s, _, _ in keep if s is None]
    closed_volume = sum(v for _, _, v, _ in keep)
    log.append(f"{len(shells) + len([d for d in dropped if 'not manifold' in d])} shells: closed {loops_filled} "
               f"holes in {shells_closed} open shells; {len(keep)} kept"
               + (f", {len(remade)} of them not manifold after closing ({_grouped(remade)})" if remade else "")
               + (f", dropped {len(dropped)}: " + _grouped(dropped) if dropped else "")
               + f" (volume of the closed shells {closed_volume:.4g}, input units³)")

    # 4: the union of all shells
    if remade:  # the union of everything by winding number: one surface, closed and clean, whatever the shells
        union = _winding_union([g for _, _, _, g in keep], log)
    else:
        union = manifold3d.Manifold.batch_boolean([s for _, s, _, _ in keep], manifold3d.OpType.Add) \
            if len(keep) > 1 else keep[0][1]
    union, bridged = _bridge(union, BRIDGE_GAP * size)
    parts = union.decompose()
    vols = np.array([q.volume() for q in parts])
    small = vols < ISLAND_MIN_VOLUME * vols.sum()
    if np.any(small):
        union = manifold3d.Manifold.compose([q for q, s in zip(parts, small) if not s])
    islands = int((~small).sum())
    mesh = union.to_mesh64()
    props = np.asarray(mesh.vert_properties, np.float64)
    Fu = np.asarray(mesh.tri_verts, np.int64)
    # manifold splits vertices where properties differ; its merge vectors say which are one
    target = np.arange(len(props))
    target[np.asarray(mesh.merge_from_vert, np.int64)] = np.asarray(mesh.merge_to_vert, np.int64)
    Fu = target[Fu]
    used = np.unique(Fu)
    remap = np.full(len(props), -1, np.int64)
    remap[used] = np.arange(len(used))
    Fu = remap[Fu]
    Vu, Wu = props[used, :3], props[used, 3:]
    Vu, Fu, Wu = _collapse_short_edges(Vu, Fu, Wu, SIMPLIFY_TOLERANCE * size)
    Fu = _flip_caps(Vu, Fu, SIMPLIFY_TOLERANCE * size)
    lost = Wu.sum(1) < 0.5  # bridge vertices carry no values: take them from the nearest input surface
    if np.any(lost):
        Wu[lost] = transfer_values(Vu[lost], V, F, values)
    union_volume = _volume(Vu, Fu)
    log.append(f"union of {len(keep)} shells: {islands} solid(s), volume {union_volume:.4g} "
               f"({(union_volume / closed_volume - 1) * 100:+.1f} % against the closed shells, overlaps removed)"
               + (f"; bridged {bridged} gap(s) under {BRIDGE_GAP:.0%} of the size" if bridged else "")
               + (f"; dropped {int(small.sum())} floating piece(s) under {ISLAND_MIN_VOLUME:.0%} of the volume "
                  f"({vols[small].sum() / vols.sum():.2%})" if np.any(small) else ""))
    Vu, Fu, Wu = _resolve_crossings(Vu, Fu, Wu, SIMPLIFY_TOLERANCE * size, log)
    if islands > 1:
        log.append(f"warning: the print body is {islands} separate solids; they print as separate pieces")
    return PrintBody(Vu, Fu, Wu, islands, log)


def _winding_union(pieces, log):
    """The union of shells (some not manifold) as one winding-number surface, a manifold3d solid carrying values."""
    offsets = np.cumsum([0] + [len(V) for V, _, _ in pieces])
    V = np.vstack([V for V, _, _ in pieces])
    F = np.vstack([F + o for (_, F, _), o in zip(pieces, offsets)])
    W = np.vstack([W for _, _, W in pieces])
    Vw, Fw = winding_surface(V, F, WINDING_CELLS)
    solid = _manifold(Vw, Fw, transfer_values(Vw, V, F, W))
    if solid is None:
        raise InputError(None, "no part of the model can be closed into a solid; "
                         "export it as one closed mesh (or fix its open shells) and try again")
    log.append(f"shells that closing cannot make manifold: the union of all {len(pieces)} made as the surface of "
               f"their winding number on a {WINDING_CELLS}-cell grid ({len(F)} -> {len(Fw)} triangles)")
    return solid


def _manifold(V, F, values):
    """A manifold3d solid of (V, F) carrying ``values`` (n, k), or None when it is not manifold."""
    import manifold3d

    solid = manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=np.ascontiguousarray(np.hstack([V, values]), np.float64),
        tri_verts=np.ascontiguousarray(F, np.uint64)))
    return None if solid.status() != manifold3d.Error.NoError or solid.is_empty() else solid


def _grouped(items: list[str]) -> str:
    """``"a (x) ×3; b (y)"``: repeated entries counted, at most six kinds shown."""
    from collections import Counter

    counts = Counter(items)
    text = "; ".join(f"{k}" + (f" ×{n}" if n > 1 else "") for k, n in list(counts.items())[:6])
    return text + (" ..." if len(counts) > 6 else "")


def _bridge(solid, gap: float):
    """Join solids that come within ``gap`` of the largest one by the hull of their facing parts.

    Distances are to the largest solid's surface, not its vertices (a
    low-poly body's vertices lie far apart where its faces nearly touch): the
    bridge is the hull of the other solid's vertices within reach and their
    closest points on the largest. Returns the new solid and how many bridges
    were made.
    """
    import igl
    import manifold3d
    from scipy.spatial import cKDTree

    parts = sorted(solid.decompose(), key=lambda q: -q.volume())
    if len(parts) < 2:
        return solid, 0
    mesh = parts[0].to_mesh64()
    main_V = np.asarray(mesh.vert_properties, np.float64)[:, :3]
    main_F = np.asarray(mesh.tri_verts, np.int64)
    bridges = []
    for q in parts[1:]:
        pts = np.asarray(q.to_mesh64().vert_properties, np.float64)[:, :3]
        d2, _, closest = igl.point_mesh_squared_distance(pts, main_V, main_F)
        d = np.sqrt(d2)
        if d.min() > gap:
            continue
        reach = d.min() + gap
        near = d <= reach
        # the facing vertices of both solids and the closest points between: a bridge as thick as the gap allows
        facing = main_V[np.unique(np.concatenate(cKDTree(main_V).query_ball_point(pts[near], reach)).astype(np.int64))]
        cloud = np.vstack([pts[near], closest[near], facing])
        if len(cloud) < 4 or np.linalg.matrix_rank(cloud - cloud.mean(0), tol=1e-9 * gap) < 3:
            continue
        hull = _hull(cloud)
        if hull is not None:
            bridges.append(hull)
    if not bridges:
        return solid, 0
    return manifold3d.Manifold.batch_boolean([solid] + bridges, manifold3d.OpType.Add), len(bridges)


def _hull(points: np.ndarray):
    """The convex hull of points as a manifold, in float64 (float32 rounding could open the gap again)."""
    import manifold3d
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(points)
    except QhullError:
        return None
    F = hull.simplices.astype(np.int64)
    centre = points[hull.vertices].mean(0)
    a, b, c = points[F[:, 0]], points[F[:, 1]], points[F[:, 2]]
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), a - centre) < 0
    F[inward] = F[inward][:, ::-1]
    used = np.unique(F)
    remap = np.full(len(points), -1, np.int64)
    remap[used] = np.arange(len(used))
    solid = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.ascontiguousarray(points[used], np.float64),
                                                  tri_verts=np.ascontiguousarray(remap[F], np.uint64)))
    return None if solid.status() != manifold3d.Error.NoError or solid.is_empty() else solid


