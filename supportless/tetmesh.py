"""Volume meshes for the rig: tetrahedra in 3D, a refined triangulation in 2D.

Every call to TetGen (AGPL-licensed, reached through ``igl.copyleft.tetgen``)
and to Shewchuk's Triangle (free for non-commercial use only, reached through
``igl.triangle``) lives in this module and nowhere else, so the licence
questions and a possible replacement stay in one place.
"""

from __future__ import annotations

import os
import sys

import numpy as np

from .errors import InputError

__all__ = ["bone_samples", "refine_triangulation_with_points", "tetrahedralize_surface", "tetrahedralize_with_skeleton",
           "triangulate_planar"]

#: TetGen switches: p = piecewise linear complex, q2 = quality bound, Y = keep
#: the surface unchanged (so surface vertices are the first rows), Q = quiet.
TETGEN_FLAGS = "pq2YQ"


class _quiet_scratch:
    """Run TetGen quietly in a scratch folder.

    TetGen prints to the C-level stdout and stderr even with ``Q`` when it
    fails, and writes ``tetgen-tmpfile_skipped.*`` into the working folder: both
    are redirected (to /dev/null, to a temporary folder removed afterwards), so
    a failure reaches the user as one line and leaves no files behind.
    """

    def __enter__(self):
        import tempfile

        sys.stdout.flush()
        sys.stderr.flush()
        self._saved = [os.dup(1), os.dup(2)]
        self._null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self._null, 1)
        os.dup2(self._null, 2)
        self._cwd = os.getcwd()
        self._tmp = tempfile.TemporaryDirectory(prefix="supportless-tetgen-")
        os.chdir(self._tmp.name)
        return self

    def __exit__(self, *exc):
        os.chdir(self._cwd)
        self._tmp.cleanup()
        sys.stdout.flush()
        sys.stderr.flush()
        for fd, saved in zip((1, 2), self._saved):
            os.dup2(saved, fd)
            os.close(saved)
        os.close(self._null)
        return False


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
    import igl
    import igl.copyleft.tetgen  # noqa: F401  (registers the submodule)

    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)
    C = np.ascontiguousarray(joints, np.float64)
    BE = np.ascontiguousarray(bones, np.int64)
    try:
        with _quiet_scratch():
            TV, TT, _ = igl.copyleft.tetgen.mesh_with_skeleton(
                V, F, C, np.zeros(0, np.int64), BE, np.zeros((0, 2), np.int64), samples_per_bone, flags
            )
    except RuntimeError as exc:
        raise InputError(None, f"TetGen could not tetrahedralise the surface ({exc}); "
                         "check it is closed and free of self-intersections") from None
    TV = np.asarray(TV, np.float64)
    TT = np.asarray(TT, np.int64)
    if len(TV) < len(V) or not np.array_equal(TV[: len(V)], V):
        raise InputError(None, "TetGen changed the surface vertices; the surface may self-intersect")
    return TV, TT


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
    vertices are put first as vertices of no tetrahedron.

    Parameters
    ----------
    vertices : (n, 3) float64
        Closed, manifold, outward-oriented surface (several solids allowed).
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
    """
    import igl
    import igl.copyleft.tetgen  # noqa: F401  (registers the submodule)

    V = np.ascontiguousarray(vertices, np.float64)
    F = np.ascontiguousarray(faces, np.int64)

    def run(switches):
        try:
            with _quiet_scratch():
                out = igl.copyleft.tetgen.tetrahedralize(V, F, flags=switches)
        except RuntimeError:
            return None
        TV, TT = np.asarray(out[0], np.float64), np.asarray(out[1], np.int64)
        return (TV, TT) if len(TT) else None

    first = run(flags)
    if first is not None and len(first[0]) >= len(V) and np.array_equal(first[0][: len(V)], V):
        return first[0], first[1], True
    # TetGen dropped or moved points (it ignores points it takes as coincident), or failed: use its
    # volume mesh as it is, else try with the surface free to split, then without quality refinement
    free = first or run(flags.replace("Y", "")) or run("pQ")
    if free is None:
        raise InputError(None, "TetGen could not tetrahedralise the surface; check it is closed and free of "
                         "self-intersections")
    TV, TT = free
    return np.vstack([V, TV]), TT + len(V), False


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


def triangulate_planar(points: np.ndarray, segments: np.ndarray, max_area: float,
                       min_angle: float = 28.0) -> tuple[np.ndarray, np.ndarray]:
    """Quality triangulation of a planar straight-line graph (Triangle).

    Parameters
    ----------
    points : (k, 2) float64
        Outline and interior points; all are kept as vertices.
    segments : (s, 2) int64
        Edges that must appear (the outline, the bones), not split.
    max_area : float
        Largest triangle area.
    min_angle : float
        Smallest angle in degrees.

    Returns
    -------
    vertices : (n, 2) float64
    faces : (f, 3) int64
    """
    import igl.triangle

    V, F, _, _, _ = igl.triangle.triangulate(np.asarray(points, np.float64), np.asarray(segments, np.int64),
                                             flags=f"pq{min_angle:g}a{max_area:g}YQ")
    return np.asarray(V, np.float64), np.asarray(F, np.int64)
