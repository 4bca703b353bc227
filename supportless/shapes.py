"""Built-in rigged demo figures, generated procedurally (no files, no network).

Every figure is returned as ``(V, F, joints, bones)``:

* 3D figures are closed, outward-oriented, 2-manifold triangle meshes without
  self-intersections, built as the zero level set of a smooth signed distance
  field (smooth union of tapered capsules and ellipsoids) with
  :meth:`manifold3d.Manifold.level_set`, then cut flat at ``y = 0`` so the feet
  rest on the build plate.
* The 2D figure (``woody2d``) is a constrained quality triangulation (Shewchuk's
  Triangle, through :func:`igl.triangle.triangulate`) of a stick-figure outline
  built with :class:`manifold3d.CrossSection`, with vertices exactly at every
  joint and at samples along every bone.

Skeleton convention: ``joints`` is ``(j, d)`` float64; ``bones`` is ``(m, 2)``
int64, each row ``[root joint, tip joint]``; a bone rotates about its root
joint and its parent is the bone whose tip is its root.  The printing
direction is ``+Y``.
"""

from __future__ import annotations

import functools
import math

import numpy as np

__all__ = ["DEMO_FIGURES", "demo_figure"]

DEMO_FIGURES: tuple[str, ...] = ("tpose", "branch", "woody2d")


# ---------------------------------------------------------------------------
# scalar signed-distance primitives (negative inside)
# ---------------------------------------------------------------------------

def _sd_capsule(p, a, b, ra, rb):
    """Approximate signed distance to a tapered capsule (round cone).

    Parameters
    ----------
    p, a, b : tuple of float
        Query point and the two segment end points, each of length 3.
    ra, rb : float
        Radii at ``a`` and ``b``.

    Returns
    -------
    float
        Signed distance (negative inside).
    """
    bax, bay, baz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    pax, pay, paz = p[0] - a[0], p[1] - a[1], p[2] - a[2]
    h = (pax * bax + pay * bay + paz * baz) / (bax * bax + bay * bay + baz * baz)
    h = 0.0 if h < 0.0 else (1.0 if h > 1.0 else h)
    dx, dy, dz = pax - bax * h, pay - bay * h, paz - baz * h
    return math.sqrt(dx * dx + dy * dy + dz * dz) - (ra + (rb - ra) * h)


def _sd_ellipsoid(p, c, r):
    """Approximate signed distance to an axis-aligned ellipsoid.

    Parameters
    ----------
    p, c : tuple of float
        Query point and ellipsoid centre, each of length 3.
    r : tuple of float
        Semi-axes, length 3.

    Returns
    -------
    float
        Signed distance (negative inside); exact on the surface, a bound-like
        approximation elsewhere.
    """
    x, y, z = (p[0] - c[0]) / r[0], (p[1] - c[1]) / r[1], (p[2] - c[2]) / r[2]
    k0 = math.sqrt(x * x + y * y + z * z)
    x2, y2, z2 = x / r[0], y / r[1], z / r[2]
    k1 = math.sqrt(x2 * x2 + y2 * y2 + z2 * z2)
    if k1 == 0.0:
        return -min(r)
    return k0 * (k0 - 1.0) / k1


def _smin(a, b, k):
    """Polynomial smooth minimum of two distances.

    Parameters
    ----------
    a, b : float
        Signed distances.
    k : float
        Blend radius; 0 or less gives the plain minimum.

    Returns
    -------
    float
        At most ``min(a, b)``, by up to ``k / 4`` where ``|a - b| < k``.
    """
    if k <= 0.0:
        return min(a, b)
    h = max(k - abs(a - b), 0.0) / k
    return min(a, b) - h * h * k * 0.25


def _mesh_from_sdf(parts, bounds, edge_length, cut_floor=True):
    """Mesh the smooth union of primitives with manifold3d's level set.

    Parameters
    ----------
    parts : list of tuple
        Each item is ``("cap", a, b, ra, rb, k)`` or ``("ell", c, r, k)`` where
        ``k`` is the smooth-union blend radius used when adding that part.
    bounds : sequence of float
        ``[xmin, ymin, zmin, xmax, ymax, zmax]`` of the sampling box.
    edge_length : float
        Target edge length of the marching-tetrahedra grid.
    cut_floor : bool
        If true, keep only the part with ``y >= 0`` (flat feet).

    Returns
    -------
    V : numpy.ndarray, shape (n, 3), dtype float64
        Vertex positions.
    F : numpy.ndarray, shape (f, 3), dtype int64
        Outward-oriented triangles.
    """
    import manifold3d

    def sdf(x, y, z):
        p = (x, y, z)
        d = 1e9
        for part in parts:
            if part[0] == "cap":
                _, a, b, ra, rb, k = part
                d = _smin(d, _sd_capsule(p, a, b, ra, rb), k)
            else:
                _, c, r, k = part
                d = _smin(d, _sd_ellipsoid(p, c, r), k)
        return -d  # manifold3d: positive inside

    solid = manifold3d.Manifold.level_set(sdf, list(bounds), edge_length)
    if cut_floor:
        solid = solid.trim_by_plane((0.0, 1.0, 0.0), 0.0)
    mesh = solid.to_mesh()
    V = np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3].copy()
    F = np.asarray(mesh.tri_verts, dtype=np.int64).copy()
    V, F = _compact(V, F)
    return V, F


def _compact(V, F):
    """Drop unreferenced vertices.

    Parameters
    ----------
    V : numpy.ndarray, shape (n, d), dtype float64
    F : numpy.ndarray, shape (f, 3), dtype int64

    Returns
    -------
    V2 : numpy.ndarray, shape (n2, d), dtype float64
    F2 : numpy.ndarray, shape (f, 3), dtype int64
    """
    used = np.unique(F)
    remap = np.full(len(V), -1, dtype=np.int64)
    remap[used] = np.arange(len(used), dtype=np.int64)
    return np.ascontiguousarray(V[used]), remap[F]


# ---------------------------------------------------------------------------
# tpose
# ---------------------------------------------------------------------------

def _tpose():
    """Humanoid standing upright with both arms held out horizontally.

    Returns
    -------
    V : numpy.ndarray, shape (n, 3), dtype float64
    F : numpy.ndarray, shape (f, 3), dtype int64
    joints : numpy.ndarray, shape (16, 3), dtype float64
    bones : numpy.ndarray, shape (15, 2), dtype int64
    """
    J = {
        "hips": (0.0, 30.0, 0.0),
        "chest": (0.0, 40.0, 0.0),
        "neck": (0.0, 48.0, 0.0),
        "head": (0.0, 56.0, 0.0),
        "l_shoulder": (7.5, 46.0, 0.0),
        "l_elbow": (16.5, 46.0, 0.0),
        "l_wrist": (25.0, 46.0, 0.0),
        "r_shoulder": (-7.5, 46.0, 0.0),
        "r_elbow": (-16.5, 46.0, 0.0),
        "r_wrist": (-25.0, 46.0, 0.0),
        "l_hip": (4.0, 28.0, 0.0),
        "l_knee": (4.5, 15.5, 0.5),
        "l_ankle": (5.0, 3.5, 0.0),
        "r_hip": (-4.0, 28.0, 0.0),
        "r_knee": (-4.5, 15.5, 0.5),
        "r_ankle": (-5.0, 3.5, 0.0),
    }
    names = list(J)
    bone_names = [
        ("hips", "chest"), ("chest", "neck"), ("neck", "head"),
        ("chest", "l_shoulder"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"),
        ("chest", "r_shoulder"), ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"),
        ("hips", "l_hip"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"),
        ("hips", "r_hip"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"),
    ]
    parts = [
        # pelvis and torso
        ("ell", (0.0, 29.5, 0.0), (7.2, 4.5, 4.4), 0.0),
        ("ell", (0.0, 35.0, 0.0), (6.2, 5.5, 3.9), 2.5),
        ("ell", (0.0, 41.5, 0.2), (7.6, 5.5, 4.3), 2.5),
        ("cap", (-5.5, 45.6, 0.0), (5.5, 45.6, 0.0), 2.9, 2.9, 2.0),
        # neck and head
        ("cap", (0.0, 46.0, 0.0), (0.0, 50.5, 0.3), 2.1, 2.0, 1.5),
        ("ell", (0.0, 54.3, 0.6), (4.0, 4.8, 4.3), 1.2),
        ("ell", (0.0, 53.2, 3.9), (0.9, 1.3, 1.1), 0.4),  # nose
    ]
    for s in (1.0, -1.0):
        parts += [
            # arms: upper arm, forearm, hand
            ("cap", (s * 7.0, 46.0, 0.0), (s * 16.5, 46.0, 0.0), 2.7, 2.1, 1.8),
            ("cap", (s * 16.5, 46.0, 0.0), (s * 24.5, 46.0, 0.0), 2.1, 1.7, 0.8),
            ("ell", (s * 26.5, 46.0, 0.3), (2.9, 1.4, 2.2), 1.0),
            # legs: thigh, shin, foot
            ("cap", (s * 4.0, 28.0, 0.0), (s * 4.5, 15.5, 0.5), 3.8, 2.9, 2.0),
            ("cap", (s * 4.5, 15.5, 0.5), (s * 5.0, 3.5, 0.0), 2.9, 2.1, 1.0),
            ("cap", (s * 5.0, 1.2, -1.0), (s * 5.4, 1.2, 5.0), 2.5, 2.2, 2.0),
        ]
    V, F = _mesh_from_sdf(parts, (-31, -3, -8, 31, 61, 10), 2.0)
    joints = np.array([J[n] for n in names], dtype=np.float64)
    bones = np.array([[names.index(a), names.index(b)] for a, b in bone_names],
                     dtype=np.int64)
    return V, F, joints, bones


# ---------------------------------------------------------------------------
# branch
# ---------------------------------------------------------------------------

def _branch():
    """Upright post on a round foot with one horizontal cantilevered arm.

    Returns
    -------
    V : numpy.ndarray, shape (n, 3), dtype float64
    F : numpy.ndarray, shape (f, 3), dtype int64
    joints : numpy.ndarray, shape (4, 3), dtype float64
    bones : numpy.ndarray, shape (3, 2), dtype int64
    """
    joints = np.array([
        [0.0, 2.0, 0.0],    # 0 base (root)
        [0.0, 20.0, 0.0],   # 1 branching point
        [16.0, 20.0, 0.0],  # 2 arm tip
        [0.0, 28.0, 0.0],   # 3 post top
    ], dtype=np.float64)
    bones = np.array([[0, 1], [1, 2], [1, 3]], dtype=np.int64)
    parts = [
        ("cap", (0.0, 0.0, 0.0), (0.0, 0.5, 0.0), 5.0, 4.5, 0.0),  # foot
        ("cap", (0.0, 0.0, 0.0), (0.0, 28.0, 0.0), 3.0, 2.6, 2.0),  # post
        ("cap", (0.0, 20.0, 0.0), (17.0, 20.0, 0.0), 2.6, 2.2, 2.0),  # arm
    ]
    V, F = _mesh_from_sdf(parts, (-7, -3, -7, 21, 32, 7), 2.0)
    return V, F, joints, bones


# ---------------------------------------------------------------------------
# woody2d
# ---------------------------------------------------------------------------

def _woody2d(samples_per_bone=5, max_area=1.5):
    """Planar stick figure triangulated with vertices on every bone.

    Parameters
    ----------
    samples_per_bone : int
        Interior vertices forced onto each bone.
    max_area : float
        Largest triangle area.

    Returns
    -------
    V : numpy.ndarray, shape (n, 2), dtype float64
    F : numpy.ndarray, shape (f, 3), dtype int64
        Counter-clockwise triangles.
    joints : numpy.ndarray, shape (12, 2), dtype float64
    bones : numpy.ndarray, shape (11, 2), dtype int64
    """
    from .tetmesh import triangulate_planar
    import manifold3d

    joints = np.array([
        [0.0, 30.0],    # 0 hips (root)
        [0.0, 40.0],    # 1 chest
        [0.0, 46.0],    # 2 neck
        [0.0, 53.0],    # 3 head
        [16.0, 42.0],   # 4 l elbow
        [26.0, 42.0],   # 5 l wrist
        [-16.0, 42.0],  # 6 r elbow
        [-26.0, 42.0],  # 7 r wrist
        [5.0, 16.0],    # 8 l knee
        [5.5, 3.0],     # 9 l ankle
        [-5.0, 16.0],   # 10 r knee
        [-5.5, 3.0],    # 11 r ankle
    ], dtype=np.float64)
    bones = np.array([
        [0, 1], [1, 2], [2, 3],
        [1, 4], [4, 5], [1, 6], [6, 7],
        [0, 8], [8, 9], [0, 10], [10, 11],
    ], dtype=np.int64)

    segs = 64
    CS = manifold3d.CrossSection

    def capsule(a, b, ra, rb):
        ca = CS.circle(ra, segs).translate(tuple(a))
        cb = CS.circle(rb, segs).translate(tuple(b))
        return CS.batch_hull([ca, cb])

    parts = [
        capsule((0.0, 29.0), (0.0, 42.0), 6.5, 7.0),          # torso
        capsule((0.0, 44.0), (0.0, 48.0), 2.2, 2.2),          # neck
        CS.circle(5.5, segs).translate((0.0, 53.0)),          # head
        capsule((0.0, 42.0), (16.0, 42.0), 2.8, 2.4),         # arms
        capsule((16.0, 42.0), (27.5, 42.0), 2.4, 2.1),
        capsule((0.0, 42.0), (-16.0, 42.0), 2.8, 2.4),
        capsule((-16.0, 42.0), (-27.5, 42.0), 2.4, 2.1),
        capsule((4.0, 28.0), (5.0, 16.0), 3.6, 3.0),          # legs
        capsule((5.0, 16.0), (5.5, 2.0), 3.0, 2.4),
        capsule((-4.0, 28.0), (-5.0, 16.0), 3.6, 3.0),
        capsule((-5.0, 16.0), (-5.5, 2.0), 3.0, 2.4),
        capsule((4.0, 1.6), (9.5, 1.6), 1.6, 1.6),            # feet
        capsule((-4.0, 1.6), (-9.5, 1.6), 1.6, 1.6),
    ]
    shape = CS.batch_boolean(parts, manifold3d.OpType.Add)
    # soften the concave creases, then cut the feet flat at y = 0
    shape = shape.offset(1.0, manifold3d.JoinType.Round, 2.0, segs) \
                 .offset(-1.0, manifold3d.JoinType.Round, 2.0, segs)
    plate = CS.square((200.0, 200.0)).translate((-100.0, 0.0))
    shape = CS.batch_boolean([shape, plate], manifold3d.OpType.Intersect)
    shape = shape.simplify(0.02)
    polys = shape.to_polygons()
    if len(polys) != 1:
        raise RuntimeError("woody2d outline is not a single simple polygon")
    outline = np.asarray(polys[0], dtype=np.float64)
    # resample the outline so no boundary edge is much longer than ~1.2
    pts = []
    n_out = len(outline)
    for i in range(n_out):
        a, b = outline[i], outline[(i + 1) % n_out]
        k = max(1, int(math.ceil(np.linalg.norm(b - a) / 1.2)))
        for t in range(k):
            pts.append(a + (b - a) * (t / k))
    outline = np.asarray(pts, dtype=np.float64)
    nb = len(outline)
    boundary_edges = np.stack([np.arange(nb), (np.arange(nb) + 1) % nb], axis=1)

    # joints and bone samples become input vertices joined by constraint edges
    nj = len(joints)
    bone_pts = []
    bone_edges = []
    for a, b in bones:
        chain = [nb + a]
        for t in range(1, samples_per_bone + 1):
            s = t / (samples_per_bone + 1)
            bone_pts.append(joints[a] * (1.0 - s) + joints[b] * s)
            chain.append(nb + nj + len(bone_pts) - 1)
        chain.append(nb + b)
        bone_edges += [[chain[i], chain[i + 1]] for i in range(len(chain) - 1)]
    Vin = np.vstack([outline, joints, np.asarray(bone_pts)])
    Ein = np.vstack([boundary_edges, np.asarray(bone_edges, dtype=np.int64)])
    # p: PSLG, q: min angle, a: max area, Y: no Steiner points on segments,
    # Q: quiet
    V, F = triangulate_planar(Vin, Ein, max_area=max_area, min_angle=28)
    # make every triangle counter-clockwise
    e1 = V[F[:, 1]] - V[F[:, 0]]
    e2 = V[F[:, 2]] - V[F[:, 0]]
    cw = (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) < 0
    F[cw] = F[cw][:, ::-1]
    V, F = _compact(V, F)
    # input vertices keep their positions; snap the joints exactly anyway
    for i, p in enumerate(joints):
        k = int(np.argmin(np.sum((V - p) ** 2, axis=1)))
        if np.linalg.norm(V[k] - p) > 1e-9:
            raise RuntimeError("triangulation lost a joint vertex")
        V[k] = p
    return V, F, joints, bones


_BUILDERS = {"tpose": _tpose, "branch": _branch, "woody2d": _woody2d}


@functools.lru_cache(maxsize=None)
def _cached(name):
    """The built figure ``name``, built once per process, as read-only arrays."""
    V, F, joints, bones = _BUILDERS[name]()
    for a in (V, F, joints, bones):
        a.setflags(write=False)
    return V, F, joints, bones


def demo_figure(name):
    """Build one of the built-in rigged demo figures.

    Parameters
    ----------
    name : str
        One of :data:`DEMO_FIGURES`:

        ``"tpose"``
            A humanoid standing on flat feet at ``y = 0`` with both arms held
            out horizontally (lots of overhang under the arms when printed
            along ``+Y``); 16 joints, 15 bones (hips root, spine, neck/head,
            clavicle-shoulder-elbow-wrist, pelvis-hip-knee-ankle); about
            3000 faces.
        ``"branch"``
            An upright post with one horizontal cantilevered arm; 4 joints,
            3 bones; under 1500 faces.
        ``"woody2d"``
            A planar stick figure (body, head, horizontal arms, legs) as a 2D
            triangle mesh with counter-clockwise triangles and vertices exactly
            at every joint and at 5 interior samples along every bone; 12
            joints, 11 bones.

    Returns
    -------
    V : numpy.ndarray, shape (n, d), dtype float64
        Vertex positions, ``d = 3`` (or ``d = 2`` for ``woody2d``); ``+Y`` is up
        and the lowest point is at ``y = 0``.
    F : numpy.ndarray, shape (f, 3), dtype int64
        Triangles: outward-oriented closed surface in 3D, counter-clockwise
        triangles in 2D.
    joints : numpy.ndarray, shape (j, d), dtype float64
        Joint positions, all strictly inside the shape.
    bones : numpy.ndarray, shape (m, 2), dtype int64
        ``[root joint, tip joint]`` per bone; the bones form a tree.

    Raises
    ------
    KeyError
        If ``name`` is not a known figure.

    Notes
    -----
    Generation is deterministic; results are cached and fresh writable copies
    are returned on every call.
    """
    if name not in _BUILDERS:
        raise KeyError(f"unknown demo figure {name!r}; choose from {DEMO_FIGURES}")
    return tuple(np.array(a, copy=True) for a in _cached(name))
