"""Volume meshes for the rig: tetrahedra in 3D, a refined triangulation in 2D.

TetGen (AGPL) is reached through :mod:`supportless.copyleft.tetgen`; when it
cannot mesh a surface (real characters' shells cut each other), fTetWild
(``pytetwild``, MPL-2.0) meshes it within a small envelope. Both run in a
child process, so a crash of either is a message. Shewchuk's Triangle (free
for non-commercial use only) is called in :mod:`supportless.copyleft.triangle`
only; :func:`triangulate_planar` is importable here as before.
"""

from __future__ import annotations

import numpy as np

from ..base.errors import InputError
from ..base.isolated import NativeFailure, run_isolated
from ..copyleft.tetgen import tetgen_surface, tetgen_with_skeleton
from ..copyleft.triangle import triangulate_planar  # noqa: F401 (re-exported)

__all__ = ["FTETWILD_EDGE", "FTETWILD_ENVELOPE", "bone_samples", "ftetwild_volume", "refine_triangulation_with_points",
           "tetrahedralize_surface", "tetrahedralize_with_skeleton", "tetrahedralize_with_skeleton_or_remake",
           "triangulate_planar"]

#: TetGen switches: p = piecewise linear complex, q2 = quality bound, Y = keep
#: the surface unchanged (so surface vertices are the first rows), Q = quiet.
TETGEN_FLAGS = "pq2YQ"

#: fTetWild's envelope: the volume mesh's boundary stays within this fraction
#: of the bounding-box diagonal of the surface (its default, 1e-3, takes ten
#: times longer on a character's overlapping shells for a volume that only
#: carries the distortion energy).
FTETWILD_ENVELOPE = 5e-3

#: fTetWild's target edge length, a fraction of the bounding-box diagonal.
FTETWILD_EDGE = 0.05


def tetrahedralize_with_skeleton(vertices: np.ndarray, faces: np.ndarray, joints: np.ndarray,
                                 bones: np.ndarray, samples_per_bone: int = 10,
                                 flags: str = TETGEN_FLAGS) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedralise a closed surface with the skeleton's bones sampled inside.

    Parameters
    ----------
    vertices : (n, 3) float64
        Closed, manifold, outward-oriented surface.
    faces : (f, 3) int64
    joints : (j, 3) float64
    bones : (m, 2) int64
    samples_per_bone : int
        Points inserted along each bone, so weights can be fixed on the bones.
    flags : str
        TetGen switches; ``Y`` must stay so the surface is kept as given.

    Returns
    -------
    tet_vertices : (t, 3) float64
        The first ``n`` rows are ``vertices`` unchanged.
    tets : (k, 4) int64
    """
    V = np.ascontiguousarray(vertices, np.float64)
    try:
        TV, TT = tetgen_with_skeleton(V, faces, joints, bones, samples_per_bone, flags)
    except NativeFailure as exc:
        raise InputError(None, f"{exc}: the surface could not be tetrahedralised with its skeleton inside; "
                         "check it is closed and free of self-intersections") from None
    if len(TV) < len(V) or not np.array_equal(TV[: len(V)], V):
        raise InputError(None, "TetGen changed the surface vertices; the surface may self-intersect")
    return TV, TT


def tetrahedralize_with_skeleton_or_remake(vertices: np.ndarray, faces: np.ndarray, joints: np.ndarray,
                                           bones: np.ndarray, samples_per_bone: int = 10):
    """:func:`tetrahedralize_with_skeleton`; when TetGen refuses the surface, its winding-number surface.

    A surface that crosses itself (a sculpt's overlapping parts, shells
    pushed through each other) is remade as the surface of its generalized
    winding number (:func:`supportless.files.printbody.winding_surface`): closed,
    free of crossings, the same solid to a grid cell; TetGen meshes that.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64
    joints : (j, 3) float64
        Inside the solid.
    bones : (m, 2) int64
    samples_per_bone : int

    Returns
    -------
    vertices : (n', 3) float64
        The surface meshed: ``vertices`` or the remade one.
    faces : (f', 3) int64
    tet_vertices : (t, 3) float64
        The first ``n'`` rows are the returned ``vertices``.
    tets : (k, 4) int64
    note : str or None
        One line when the surface was remade.

    Raises
    ------
    InputError
        When TetGen refuses the remade surface too.
    """
    try:
        return (vertices, faces, *tetrahedralize_with_skeleton(vertices, faces, joints, bones, samples_per_bone), None)
    except InputError as first:
        from ..copyleft.cgal import intersecting_faces
        from ..files.printbody import WINDING_CELLS, winding_surface

        crossing = len(intersecting_faces(vertices, faces))
        if crossing == 0:
            raise first from None
    V, F = winding_surface(np.asarray(vertices, np.float64), np.asarray(faces, np.int64), WINDING_CELLS)
    TV, TT = tetrahedralize_with_skeleton(V, F, joints, bones, samples_per_bone)
    note = (f"the surface crosses itself ({crossing} pairs of triangles) and TetGen could not mesh it: remade as the "
            f"surface of its winding number on a {WINDING_CELLS}-cell grid ({len(faces)} -> {len(F)} triangles); "
            "outputs are that surface")
    return V, F, TV, TT, note


def tetrahedralize_surface(vertices: np.ndarray, faces: np.ndarray,
                           flags: str = TETGEN_FLAGS) -> tuple[np.ndarray, np.ndarray, bool]:
    """Tetrahedralise the inside of a closed surface (no bones inside).

    For rigs whose weights come with the model (a glTF skin): the bones only
    give pivots and need not lie inside, and the weights of the volume come
    from the surface, so the volume mesh need not share the surface's
    vertices. TetGen is first asked to keep the surface as it is; when it
    cannot (points of a boolean union closer than its tolerance, nearly
    overlapping segments), its volume mesh is used as it came (or the surface
    is meshed free to split, then without quality refinement), and the surface
    vertices are put first as vertices of no tetrahedron. When TetGen fails or
    crashes on every try (shells that cut each other), fTetWild meshes the
    surface within :data:`FTETWILD_ENVELOPE` (:func:`ftetwild_volume`), the
    same way.

    Parameters
    ----------
    vertices : (n, 3) float64
        Closed, outward-oriented surface (several solids allowed; may cut
        itself).
    faces : (f, 3) int64
    flags : str
        TetGen switches of the first try; ``Y`` must stay.

    Returns
    -------
    tet_vertices : (t, 3) float64
        The first ``n`` rows are ``vertices`` unchanged.
    tets : (k, 4) int64
    conforming : bool
        Whether the tetrahedra have the surface's vertices and faces (the first
        try worked).

    Raises
    ------
    InputError
        When neither TetGen nor fTetWild can mesh the surface.
    """
    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    failures: list[NativeFailure] = []

    def run(switches):
        try:
            return tetgen_surface(V, F, switches)
        except NativeFailure as exc:
            failures.append(exc)
            return None

    first = run(flags)
    if first is not None and len(first[0]) >= len(V) and np.array_equal(first[0][: len(V)], V):
        return first[0], first[1], True
    # TetGen dropped or moved points (it ignores points it takes as coincident), or failed: use its
    # volume mesh as it is, else try with the surface free to split, then without quality refinement
    # (not after a crash: the same surface crashes it again), then fTetWild
    crashed = any(f.crashed for f in failures)
    free = first or (None if crashed else run(flags.replace("Y", "")) or run("pQ"))
    if free is None:
        try:
            free = ftetwild_volume(V, F)
        except NativeFailure as exc:
            raise InputError(None, f"neither TetGen ({failures[-1]}) nor fTetWild ({exc}) could tetrahedralise "
                             "the surface; check it is closed") from None
    TV, TT = free
    return np.vstack([V, TV]), TT + len(V), False


def ftetwild_volume(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """fTetWild's volume mesh of a surface that may cut itself or have gaps.

    The inside is decided by winding number, so overlapping shells become
    one solid; the boundary stays within :data:`FTETWILD_ENVELOPE` of the
    surface. Runs in a child process. Its result varies from run to run
    (it seeds itself from ``std::random_device``, on one thread as on many),
    so it is the last resort after TetGen.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (f, 3) int64

    Returns
    -------
    tet_vertices : (t, 3) float64
        Not the surface's vertices.
    tets : (k, 4) int64
        Positively oriented.

    Raises
    ------
    NativeFailure
        When fTetWild is not installed, fails, crashes or makes nothing.
    """
    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int32)
    return run_isolated(_ftetwild, V, F, what="fTetWild")


def _ftetwild(V, F):
    try:
        import pytetwild
    except ImportError:
        raise RuntimeError("pytetwild is not installed (pip install 'pytetwild>=0.2.3,<0.3')") from None
    TV, TT = pytetwild.tetrahedralize(V, F, edge_length_fac=FTETWILD_EDGE, epsilon=FTETWILD_ENVELOPE,
                                      stop_energy=50.0, num_opt_iter=20, quiet=True)
    TV, TT = np.asarray(TV, np.float64), np.asarray(TT, np.int64)
    if len(TT) == 0:
        raise RuntimeError("no tetrahedra")
    # orient every tetrahedron positively, as TetGen's are
    a, b, c, d = (TV[TT[:, i]] for i in range(4))
    negative = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) < 0
    TT[negative] = TT[negative][:, [0, 2, 1, 3]]
    return TV, TT


def refine_triangulation_with_points(vertices: np.ndarray, faces: np.ndarray,
                                     points: np.ndarray, tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Insert points into a 2D triangulation (split the triangle or edge they fall on).

    Used in 2D, where the rig's "volume" mesh is the triangle mesh itself, to put
    vertices exactly on the bones for the weights' boundary conditions.

    Parameters
    ----------
    vertices : (n, 2) float64
    faces : (f, 3) int64
        Counter-clockwise triangles.
    points : (k, 2) float64
        Points inside the mesh. A point within ``tol`` (relative to the mesh
        size) of an existing vertex is not inserted again.
    tol : float

    Returns
    -------
    vertices : (n', 2) float64
        The first ``n`` rows are the input vertices.
    faces : (f', 3) int64
    """
    V = [tuple(v) for v in np.asarray(vertices, np.float64)]
    F = [list(f) for f in np.asarray(faces, np.int64)]
    scale = float(np.ptp(np.asarray(vertices), axis=0).max()) or 1.0
    eps = tol * scale
    for q in np.asarray(points, np.float64):
        Varr = np.asarray(V)
        if np.min(np.linalg.norm(Varr - q, axis=1)) <= eps:
            continue
        Farr = np.asarray(F)
        a, b, c = Varr[Farr[:, 0]], Varr[Farr[:, 1]], Varr[Farr[:, 2]]
        area = _cross2(b - a, c - a)
        l0 = _cross2(c - b, q - b) / area  # weight of a
        l1 = _cross2(a - c, q - c) / area  # weight of b
        l2 = 1.0 - l0 - l1
        lam = np.stack([l0, l1, l2], 1)
        inside = np.flatnonzero(lam.min(1) >= -1e-12)
        if len(inside) == 0:
            raise InputError(None, f"skeleton point {q.tolist()} lies outside the planar mesh")
        t = inside[np.argmax(lam[inside].min(1))]
        k = len(V)
        V.append(tuple(q))
        i, j, l = F[t]
        on_edge = np.flatnonzero(np.abs(lam[t]) <= 1e-9)
        if len(on_edge) == 0:
            F[t] = [i, j, k]
            F.append([j, l, k])
            F.append([l, i, k])
            continue
        # the point lies on the edge opposite the vanishing barycentric weight
        opp = int(on_edge[0])
        tri = F[t]
        e0, e1 = tri[(opp + 1) % 3], tri[(opp + 2) % 3]
        apex = tri[opp]
        F[t] = [apex, e0, k]
        F.append([apex, k, e1])
        for s, other in enumerate(F[:-1]):
            if s == t:
                continue
            for r in range(3):
                if other[r] == e1 and other[(r + 1) % 3] == e0:
                    apex2 = other[(r + 2) % 3]
                    F[s] = [apex2, e1, k]
                    F.append([apex2, k, e0])
                    break
            else:
                continue
            break
    return np.asarray(V, np.float64), np.asarray(F, np.int64)


def _cross2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def bone_samples(joints: np.ndarray, bones: np.ndarray, samples_per_bone: int) -> np.ndarray:
    """Evenly spaced points on every bone, joints included.

    Parameters
    ----------
    joints : (j, d) float64
    bones : (m, 2) int64
    samples_per_bone : int
        Interior samples per bone.

    Returns
    -------
    points : (q, d) float64
    """
    t = np.linspace(0.0, 1.0, samples_per_bone + 2)[1:-1]
    a, b = joints[bones[:, 0]], joints[bones[:, 1]]
    inner = (a[:, None, :] * (1 - t)[None, :, None] + b[:, None, :] * t[None, :, None]).reshape(-1, joints.shape[1])
    return np.concatenate([joints, inner])
