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
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..base.errors import InputError
from ..base.isolated import NativeFailure
from ..copyleft.cgal import intersecting_faces, self_union
from .simplify import simplify_surface

__all__ = ["united_surface", "BRIDGE_GAP", "ISLAND_MIN_VOLUME", "SHELL_MIN_VOLUME", "WINDING_CELLS", "winding_surface", "PrintBody", "print_body",
           "transfer_values"]

#: Closed shells below this fraction of the total volume are dropped (slivers,
#: flat single-sided pieces closed on themselves).
SHELL_MIN_VOLUME = 1e-4

#: Solids left apart after the union that come within this fraction of the
#: model's size of the largest solid are joined to it by a bridge (the convex
#: hull of the facing parts): a hand that misses its wrist by a hair.
BRIDGE_GAP = 0.01

#: Solids still apart after bridging below this fraction of the volume are
#: dropped (eyes floating in front of a face would print in the air); larger
#: ones are kept as separate pieces, with a warning.
ISLAND_MIN_VOLUME = 0.01

#: Vertices closer than this fraction of the model's size are welded.
WELD_TOLERANCE = 1e-6

#: Grid cells along the longest side for the winding-number surface that
#: replaces a body whose crossings an exact self-union cannot resolve (a cell
#: is 0.4 mm on a 60 mm print).
WINDING_CELLS = 160

#: The winding-number surface is simplified to at most this many triangles
#: (when the simplified one is closed and free of crossings).
WINDING_MAX_FACES = 40_000

#: After the union, edges shorter than this fraction of the size are collapsed:
#: the needle and zero-area triangles a boolean leaves, which TetGen cannot mesh.
SIMPLIFY_TOLERANCE = 1e-5


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


def _volume(V: np.ndarray, F: np.ndarray) -> float:
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _weld(V, F, values, tol):
    """Merge vertices within ``tol`` of each other; values averaged. Returns V, F, values, merged count."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    if len(V) == 0:
        return V, F, values, 0
    pairs = cKDTree(V).query_pairs(tol, output_type="ndarray")
    if len(pairs) == 0:
        return V, F, values, 0
    A = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(V), len(V)))
    k, inverse = connected_components(A, directed=False)
    first = np.arange(k)
    count = np.bincount(inverse, minlength=k).astype(np.float64)
    Vn = np.zeros((k, 3))
    np.add.at(Vn, inverse, V)
    Vn /= count[:, None]
    Wn = np.zeros((len(first), values.shape[1]))
    np.add.at(Wn, inverse, values)
    Wn /= count[:, None]
    return Vn, inverse[F], Wn, len(V) - len(first)


def _clean_faces(F: np.ndarray, V: np.ndarray, area_eps: float) -> tuple[np.ndarray, int, int]:
    """Drop faces with a repeated vertex or (almost) no area, and duplicates (any winding)."""
    repeated = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    degenerate = repeated | (area <= area_eps)
    F = F[~degenerate]
    _, first = np.unique(np.sort(F, axis=1), axis=0, return_index=True)
    dup = len(F) - len(first)
    return F[np.sort(first)], int(degenerate.sum()), dup


def _components(F: np.ndarray, n: int) -> np.ndarray:
    """(f,) int64: connected component (through shared vertices) of each face."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    f = len(F)
    rows = np.repeat(np.arange(f), 3)
    A = coo_matrix((np.ones(3 * f), (rows, F.ravel() + f)), shape=(f + n, f + n))
    _, labels = connected_components(A, directed=False)
    return np.unique(labels[:f], return_inverse=True)[1].ravel()


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


def united_surface(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict]:
    """One closed solid from a surface that presses into itself: its exact self-union (CGAL), else the surface
    of its winding number (as :func:`print_body`'s last step).

    A posed figure whose arm rests against its torso crosses itself there; what is printed is the solid the
    two parts make together.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
        Closed, outward oriented.

    Returns
    -------
    vertices : (n', 3) float64
    faces : (f', 3) int64
        The input when it does not cross itself.
    merged : dict
        ``pairs`` (crossing triangle pairs before), ``volume_before`` (the surface's enclosed volume, overlaps
        counted twice), ``volume`` (the solid's), ``merged_volume`` (their difference: the volume two parts
        shared), ``how`` ("none", "exact self-union" or "winding-number surface") and ``note`` (one line).
    """
    V, F = np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
    size = float(np.ptp(V, axis=0).max()) if len(V) else 1.0
    pairs = len(intersecting_faces(V, F))
    before = _volume(V, F)
    log: list[str] = []
    Vx, Fx, _ = _resolve_crossings(V, F, np.zeros((len(V), 0)), SIMPLIFY_TOLERANCE * size, log, pairs)
    if pairs and len(intersecting_faces(Vx.astype(np.float32).astype(np.float64), Fx)):  # as an STL stores it
        Vx, Fx = winding_surface(V, F, WINDING_CELLS)
        log = [f"{pairs} pairs of crossing triangles: the exact self-union crosses itself once stored in single "
               f"precision, so the body is the surface of its winding number on a {WINDING_CELLS}-cell grid"]
    after = _volume(Vx, Fx)
    how = "none" if not pairs else ("exact self-union" if "exact self-union" in log[0] else "winding-number surface")
    return Vx, Fx, {"pairs": pairs, "volume_before": before, "volume": after, "merged_volume": before - after,
                    "how": how, "note": log[0] if log else ""}


def _resolve_crossings(V, F, values, tol, log, before=None):
    """Remove crossing triangles: CGAL's exact self-union, else the winding-number surface.

    The self-union keeps every detail; the slivers it leaves are collapsed
    (and flattened caps flipped, unless that makes triangles cross again).
    When it leaves crossings (also once rescaled: points left exactly on a
    face) or edges shared by four triangles (parts that touch along an
    edge), the body is remade from its winding number (:func:`winding_surface`):
    closed, free of crossings, true to a grid cell of :data:`WINDING_CELLS`.
    Returns the surface and its values (carried from the surface before by
    closest point); ``log`` gets a line when there were crossings, and says
    how many remain. ``before``: the crossing pairs, when counted already.
    """
    before = len(intersecting_faces(V, F)) if before is None else before
    if before == 0:
        return V, F, values
    try:
        Vx, Fx = self_union(V, F)
        Vx, Fx, _, _ = _weld(Vx, Fx, np.zeros((len(Vx), 0)), tol * 1e-3)
        Vx, Fx, _ = _collapse_short_edges(Vx, Fx, np.zeros((len(Vx), 0)), tol)
        flipped = _flip_caps(Vx, Fx, tol)
        if len(intersecting_faces(Vx, flipped)) == 0:
            Fx = flipped
        if len(Fx) and _is_closed(Fx) and not _touches_itself(Vx, Fx):
            log.append(f"resolved {before} pairs of crossing triangles by an exact self-union "
                       f"(volume {(_volume(Vx, Fx) / _volume(V, F) - 1) * 100:+.2f} %)")
            return Vx, Fx, transfer_values(Vx, V, F, values)
    except NativeFailure:
        pass
    Vx, Fx = winding_surface(V, F, WINDING_CELLS)
    after = len(intersecting_faces(Vx, Fx))
    log.append(f"{before} pairs of crossing triangles that an exact self-union could not resolve cleanly: the "
               f"body remade as the surface of its winding number on a {WINDING_CELLS}-cell grid, {len(F)} -> "
               f"{len(Fx)} triangles (volume {(_volume(Vx, Fx) / _volume(V, F) - 1) * 100:+.1f} %)"
               + (f"; warning: {after} remain" if after else ""))
    return Vx, Fx, transfer_values(Vx, V, F, values)


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


def _touches_itself(V, F) -> bool:
    """Whether triangles cross, as given or rescaled (points a union leaves exactly on a face cross once rounded)."""
    return any(len(intersecting_faces(V * k, F)) for k in (1.0, 1000.0 / np.sqrt(2.0), 1.0 / np.pi))


def winding_surface(V, F, cells: int = WINDING_CELLS):
    """The outer surface of (V, F) remade by marching cubes: inside by winding number, placed by distance.

    Inside is where the shells wind around a point at least half a turn
    (libigl's fast winding number), so overlapping and crossing shells are
    one solid; the field marching cubes meets is that sign times the
    distance to the surface (computed at the grid points next to a change of
    sign: the others only need their sign), so the surface is as smooth as
    the input, not a staircase of cells. On a grid of ``cells`` along the
    longest side; closed, manifold, never crossing itself. Deterministic.

    Returns vertices (k, 3) float64 and outward faces (g, 3) int64.
    """
    import igl

    lo, hi = V.min(0), V.max(0)
    h = float((hi - lo).max()) / cells
    lo, hi = lo - 2 * h, hi + 2 * h
    nx, ny, nz = (np.ceil((hi - lo) / h).astype(np.int64) + 1).tolist()
    axes = [lo[i] + h * np.arange(n) for i, n in enumerate((nx, ny, nz))]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).transpose(2, 1, 0, 3).reshape(-1, 3)  # x fastest
    inside = (igl.fast_winding_number(V, F, np.ascontiguousarray(grid)) > 0.5).reshape(nz, ny, nx)
    near = np.zeros_like(inside)
    for axis in range(3):  # grid points with a neighbour across the surface
        change = np.diff(inside, axis=axis)
        lower = [slice(None)] * 3
        upper = [slice(None)] * 3
        lower[axis], upper[axis] = slice(0, -1), slice(1, None)
        near[tuple(lower)] |= change
        near[tuple(upper)] |= change
    field = np.full(inside.shape, 2.0 * h)
    d2 = igl.point_mesh_squared_distance(np.ascontiguousarray(grid[near.ravel()]), V, F)[0]
    field[near] = np.minimum(np.sqrt(d2), 2.0 * h)
    # no grid point exactly on the surface: marching cubes would put a vertex on it, shared by needle triangles
    field = np.maximum(field, 1e-2 * h)
    field = np.where(inside, -field, field).ravel()
    out = igl.marching_cubes(np.ascontiguousarray(field), grid, nx, ny, nz, 0.0)
    Vs, Fs = np.asarray(out[0], np.float64), np.asarray(out[1], np.int64)
    if len(Fs) and _volume(Vs, Fs) < 0:
        Fs = Fs[:, ::-1]
    # pockets the winding number left inside (closed voids) and crumbs go: a print body is solid
    comp = _components(Fs, len(Vs))
    vols = np.array([_volume(Vs, Fs[comp == c]) for c in range(comp.max() + 1)]) if len(Fs) else np.zeros(0)
    Fs = Fs[vols[comp] >= ISLAND_MIN_VOLUME * vols[vols > 0].sum()] if len(Fs) else Fs
    used = np.unique(Fs)
    remap = np.full(len(Vs), -1, np.int64)
    remap[used] = np.arange(len(used))
    Vs, Fs = Vs[used], remap[Fs]
    if len(Fs) > WINDING_MAX_FACES:  # cells smaller than the details of a low-poly body: fewer, larger triangles
        simpler = simplify_surface(Vs, Fs, WINDING_MAX_FACES)
        if simpler is not None and not _touches_itself(*simpler):
            Vs, Fs = simpler
    return Vs, Fs


def _is_closed(F: np.ndarray) -> bool:
    """Every edge has exactly two faces, in opposite directions."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    directed = np.unique(E, axis=0)
    if len(directed) != len(E):
        return False
    undirected, counts = np.unique(np.sort(E, axis=1), axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def _collapse_short_edges(V, F, values, tol):
    """Merge the ends of edges shorter than ``tol``; drop the faces that vanish.

    A face left with a repeated vertex is dropped, and so is a pair of faces
    on the same three vertices (a collapsed sliver of volume).
    """
    for _ in range(3):
        E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
        short = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1) < tol
        if not np.any(short):
            break
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        S = E[short]
        k, label = connected_components(coo_matrix((np.ones(len(S)), (S[:, 0], S[:, 1])), shape=(len(V),) * 2),
                                        directed=False)
        count = np.bincount(label, minlength=k).astype(np.float64)[:, None]
        Vn = np.zeros((k, 3))
        np.add.at(Vn, label, V)
        Wn = np.zeros((k, values.shape[1]))
        np.add.at(Wn, label, values)
        V, values, F = Vn / count, Wn / count, label[F]
        F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])]
        key = np.sort(F, axis=1)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        F = F[cnt[inv.ravel()] == 1]
        used = np.unique(F)
        remap = np.full(len(V), -1, np.int64)
        remap[used] = np.arange(len(used))
        V, values, F = V[used], values[used], remap[F]
    return V, F, values


def _flip_caps(V, F, tol, rounds: int = 5):
    """Flip the longest edge of each cap (a triangle flatter than ``tol``) with its neighbour's."""
    F = F.copy()
    for _ in range(rounds):
        a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        lengths = np.column_stack([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                                   np.linalg.norm(a - c, axis=1)])
        height = np.linalg.norm(np.cross(b - a, c - a), axis=1) / np.maximum(lengths.max(1), 1e-300)
        caps = np.flatnonzero(height < tol)
        if len(caps) == 0:
            break
        owner = {}
        for f, (x, y, z) in enumerate(F):
            owner[(x, y)], owner[(y, z)], owner[(z, x)] = f, f, f
        edges = {tuple(sorted(e)) for e in owner}
        touched = set()
        for f in caps:
            if f in touched:
                continue
            k = int(np.argmax(lengths[f]))
            p, q, r = (int(v) for v in np.roll(F[f], -k))  # longest edge p->q, r opposite
            g = owner.get((q, p))
            if g is None or g in touched:
                continue
            d = int(next(v for v in F[g] if v not in (p, q)))
            if tuple(sorted((r, d))) in edges or r == d:
                continue
            F[f] = (p, d, r)
            F[g] = (d, q, r)
            edges.add(tuple(sorted((r, d))))
            touched.update((f, g))
    return F


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


def transfer_values(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Values at points from the closest point of a surface (barycentric interpolation).

    Parameters
    ----------
    points : (p, 3) float64
    vertices : (n, 3) float64
    faces : (f, 3) int64
    values : (n, k) float64

    Returns
    -------
    out : (p, k) float64
    """
    import igl

    P = np.ascontiguousarray(points, np.float64)
    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    _, I, C = igl.point_mesh_squared_distance(P, V, F)
    I = np.asarray(I, np.int64).ravel()
    C = np.asarray(C, np.float64)
    tri = F[I]
    bary = _barycentric(C, V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]])
    return np.einsum("pk,pkc->pc", bary, values[tri])


def _barycentric(p, a, b, c) -> np.ndarray:
    v0, v1, v2 = b - a, c - a, p - a
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    den = d00 * d11 - d01 * d01
    den = np.where(np.abs(den) > 1e-300, den, 1.0)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    out = np.column_stack([1 - v - w, v, w])
    out = np.clip(out, 0.0, None)
    return out / np.maximum(out.sum(1, keepdims=True), 1e-300)
