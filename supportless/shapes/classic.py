"""The first built-in figures: ``tpose``, ``branch`` and ``woody2d``.

``tpose`` and ``branch`` are smooth unions of capsules and ellipsoids meshed
with :func:`~supportless.shapes.sdf.mesh_from_sdf`; ``woody2d`` is a
constrained quality triangulation (Shewchuk's Triangle, through
:func:`supportless.copyleft.triangle.triangulate_planar`) of a stick-figure outline built
with :class:`manifold3d.CrossSection`, with vertices exactly at every joint and
at samples along every bone.
"""

from __future__ import annotations

import math

import numpy as np

from .sdf import compact, mesh_from_sdf

__all__ = ["branch", "tpose", "woody2d"]


# ---------------------------------------------------------------------------
# tpose
# ---------------------------------------------------------------------------

def tpose():
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
    V, F = mesh_from_sdf(parts, (-31, -3, -8, 31, 61, 10), 2.0)
    joints = np.array([J[n] for n in names], dtype=np.float64)
    bones = np.array([[names.index(a), names.index(b)] for a, b in bone_names],
                     dtype=np.int64)
    return V, F, joints, bones


# ---------------------------------------------------------------------------
# branch
# ---------------------------------------------------------------------------

def branch():
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
    V, F = mesh_from_sdf(parts, (-7, -3, -7, 21, 32, 7), 2.0)
    return V, F, joints, bones


# ---------------------------------------------------------------------------
# woody2d
# ---------------------------------------------------------------------------

def woody2d(samples_per_bone=5, max_area=1.5):
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
    import manifold3d

    from ..copyleft.triangle import triangulate_planar

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
    V, F = compact(V, F)
    # input vertices keep their positions; snap the joints exactly anyway
    for i, p in enumerate(joints):
        k = int(np.argmin(np.sum((V - p) ** 2, axis=1)))
        if np.linalg.norm(V[k] - p) > 1e-9:
            raise RuntimeError("triangulation lost a joint vertex")
        V[k] = p
    return V, F, joints, bones
