"""Built-in demo figures: closed, clean, rigged."""

import igl
import igl.copyleft.cgal
import numpy as np
import pytest
import trimesh

import supportless as sl
from supportless.io import edge_counts
from supportless.kinematics import bone_parents, topological_order
from supportless.geometry import signed_volume
from supportless import shapes
from supportless.shapes import DEMO_FIGURES, demo_figure


@pytest.mark.parametrize("name", ["tpose", "branch"])
def test_3d_figures_are_closed_manifold_outward_and_clean(name):
    import igl
    import igl.copyleft.cgal  # noqa: F401

    V, F, J, B = sl.demo_figure(name)
    _, counts = edge_counts(F)
    assert np.all(counts == 2), "every edge shared by exactly two faces"
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed), "consistent winding"
    assert signed_volume(V, F) > 0, "outward orientation"
    IF = igl.copyleft.cgal.remesh_self_intersections(V, F, detect_only=True)[2]
    assert len(IF) == 0, "no self-intersections"
    wn = igl.winding_number(V, F, J)
    assert np.all(wn > 0.99), "every joint inside"
    assert V[:, 1].min() == 0.0, "stands on y = 0"
    assert len(F) <= (4000 if name == "tpose" else 1500)


@pytest.mark.parametrize("name", ["tpose", "branch", "woody2d"])
def test_skeletons_are_trees_with_valid_indices(name):
    V, F, J, B = sl.demo_figure(name)
    assert B.min() >= 0 and B.max() < len(J)
    parents = bone_parents(B)
    topological_order(parents)  # raises on a cycle
    # each joint is the tip of at most one bone: a tree (or forest)
    assert len(np.unique(B[:, 1])) == len(B)


def test_tpose_arms_are_horizontal_overhangs():
    V, F, J, B = sl.demo_figure("tpose")
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    height = V[:, 1].max()
    centroid_y = (a + b + c)[:, 1] / 3
    downward_high = (n[:, 1] < -0.7) & (centroid_y > 0.5 * height)
    assert downward_high.sum() > 20
    # some bones are nearly horizontal (the arms)
    d = J[B[:, 1]] - J[B[:, 0]]
    horizontal = np.abs(d[:, 1]) < 0.2 * np.linalg.norm(d, axis=1)
    assert horizontal.sum() >= 4


def test_woody2d_is_a_ccw_planar_mesh_with_one_boundary_loop_and_bone_vertices():
    V, F, J, B = sl.demo_figure("woody2d")
    assert V.shape[1] == 2 and J.shape[1] == 2
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    assert np.all(area > 0)
    E, counts = edge_counts(F)
    boundary = E[counts == 1]
    assert np.all(counts <= 2)
    # one closed loop: every boundary vertex has two boundary edges and the loop is connected
    verts, deg = np.unique(boundary, return_counts=True)
    assert np.all(deg == 2)
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    A = sp.coo_matrix((np.ones(len(boundary)), (boundary[:, 0], boundary[:, 1])), shape=(len(V), len(V)))
    n_comp, labels = connected_components(A, directed=False)
    assert len(np.unique(labels[verts])) == 1
    # a vertex exactly at every joint
    d = np.linalg.norm(V[None] - J[:, None], axis=2).min(1)
    assert np.all(d < 1e-9)


@pytest.mark.parametrize("name", DEMO_FIGURES)
def test_figures_are_deterministic(name):
    # two real builds (the builders, not demo_figure's cache), and the cached copy
    first, second = shapes._BUILDERS[name](), shapes._BUILDERS[name]()
    cached = sl.demo_figure(name)
    for x, y, z in zip(first, second, cached):
        assert x is not y
        np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(x, z)
    with pytest.raises((KeyError, ValueError)):
        sl.demo_figure("no-such-figure")


# --- further checks ---------------------------------------------------------


UP3 = np.array([0.0, 1.0, 0.0])
FIG3 = ["tpose", "branch"]


def _is_forest(n_joints, bones):
    """Each joint is the tip of at most one bone and there are no cycles."""
    tips = bones[:, 1]
    if len(np.unique(tips)) != len(tips):
        return False
    parent = {int(t): int(r) for r, t in bones}
    for j in range(n_joints):
        seen = set()
        while j in parent:
            if j in seen:
                return False
            seen.add(j)
            j = parent[j]
    return True


def test_names():
    assert set(DEMO_FIGURES) == {"tpose", "branch", "woody2d"}
    assert set(shapes._BUILDERS) == set(DEMO_FIGURES)
    with pytest.raises(KeyError):
        demo_figure("nope")


@pytest.mark.parametrize("name", DEMO_FIGURES)
def test_dtypes_and_skeleton(name):
    V, F, J, B = demo_figure(name)
    d = 2 if name == "woody2d" else 3
    assert V.dtype == np.float64 and V.ndim == 2 and V.shape[1] == d
    assert F.dtype == np.int64 and F.shape[1] == 3
    assert J.dtype == np.float64 and J.shape[1] == d
    assert B.dtype == np.int64 and B.shape[1] == 2
    assert F.min() >= 0 and F.max() < len(V)
    assert len(np.unique(F)) == len(V)  # no unreferenced vertices
    assert B.min() >= 0 and B.max() < len(J)
    assert np.all(B[:, 0] != B[:, 1])
    assert set(np.unique(B).tolist()) == set(range(len(J)))
    assert _is_forest(len(J), B)
    # feet rest on the plate (cut exactly at y = 0)
    assert V[:, 1].min() == 0.0
    assert np.all(J[:, 1] > 0)


def test_returns_fresh_copies():
    V, F, J, B = demo_figure("branch")
    V[:] = 0
    V2, _, _, _ = demo_figure("branch")
    assert np.ptp(V2[:, 1]) > 1


@pytest.mark.parametrize("name", FIG3)
def test_closed_manifold_surface(name):
    V, F, J, B = demo_figure(name)
    mesh = trimesh.Trimesh(V, F, process=False)
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.is_volume
    assert mesh.volume > 0  # outward orientation
    assert mesh.euler_number == 2  # a single sphere-like surface
    # every edge shared by exactly two faces (2-manifold)
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, counts = np.unique(E, axis=0, return_counts=True)
    assert np.all(counts == 2)
    # no degenerate faces
    assert mesh.area_faces.min() > 1e-8


@pytest.mark.parametrize("name", FIG3)
def test_no_self_intersections(name):
    V, F, _, _ = demo_figure(name)
    IF = igl.copyleft.cgal.remesh_self_intersections(V, F, detect_only=True)[2]
    assert len(IF) == 0


@pytest.mark.parametrize("name", FIG3)
def test_joints_inside(name):
    V, F, J, _ = demo_figure(name)
    w = igl.winding_number(V, F, J)
    # a sum of solid angles over a closed surface: exactly 1 inside up to rounding (4e-16 measured)
    assert np.all(np.abs(w - 1.0) < 1e-12)
    # strictly inside: some clearance to the surface
    sqd = igl.point_mesh_squared_distance(J, V, F)[0]
    assert np.sqrt(sqd).min() > 0.5


def test_face_budgets():
    assert 2000 <= len(demo_figure("tpose")[1]) <= 4000
    assert len(demo_figure("branch")[1]) <= 1500
    assert len(demo_figure("woody2d")[1]) <= 4000


def test_tpose_skeleton_and_overhang():
    V, F, J, B = demo_figure("tpose")
    assert 12 <= len(B) <= 15
    # one tree: all parentless bones hang off the same (hips) root joint
    roots = set(B[_roots_mask(B), 0].tolist())
    assert len(roots) == 1
    np.testing.assert_array_equal(J[roots.pop()], [0.0, 30.0, 0.0])  # the hips
    # arms: the horizontal chains of bones at shoulder height
    d = J[B[:, 1]] - J[B[:, 0]]
    horizontal = np.abs(d[:, 1]) < 1e-9
    assert horizontal.sum() >= 4
    assert (J[B[horizontal, 1], 0] > 0).any() and (J[B[horizontal, 1], 0] < 0).any()
    # legs reach down near the plate, head is the top
    assert J[:, 1].min() < 5
    assert J[:, 1].max() > 50
    # feet flat on the plate: many vertices exactly at y = 0
    assert np.sum(np.abs(V[:, 1]) < 1e-9) >= 10
    # the arms' undersides create overhangs well above the ground
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    c = V[F].mean(axis=1)
    risky = (N @ UP3 < -0.7) & (c[:, 1] > 35)
    assert risky.sum() >= 30
    assert np.abs(c[risky, 0]).max() > 15  # out along the arms


def _roots_mask(B):
    tips = set(B[:, 1].tolist())
    return np.array([int(r) not in tips for r in B[:, 0]])


def test_branch_cantilever():
    V, F, J, B = demo_figure("branch")
    assert 2 <= len(B) <= 3
    d = J[B[:, 1]] - J[B[:, 0]]
    assert np.any((np.abs(d[:, 1]) < 1e-9) & (np.abs(d[:, 0]) > 5))
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    c = V[F].mean(axis=1)
    assert np.sum((N @ UP3 < -0.7) & (c[:, 1] > 10)) > 5


def _signed_areas(V, F):
    e1 = V[F[:, 1]] - V[F[:, 0]]
    e2 = V[F[:, 2]] - V[F[:, 0]]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def _boundary_edges(F):
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return E[counts[inv] == 1], counts


def test_woody2d_mesh():
    V, F, J, B = demo_figure("woody2d")
    a = _signed_areas(V, F)
    assert np.all(a > 1e-6)  # all CCW, no slivers of zero area
    bnd, counts = _boundary_edges(F)
    assert counts.max() <= 2  # manifold
    loops = igl.boundary_loop_all(F)
    assert len(loops) == 1  # one closed outline, no holes
    assert len(loops[0]) == len(bnd)
    # the oriented boundary edges form one CCW cycle
    nxt = dict(zip(bnd[:, 0].tolist(), bnd[:, 1].tolist()))
    assert len(nxt) == len(bnd)
    start = int(bnd[0, 0])
    k, steps = nxt[start], 1
    while k != start:
        k, steps = nxt[k], steps + 1
    assert steps == len(bnd)
    loop = V[loops[0]]
    area = 0.5 * np.sum(loop[:, 0] * np.roll(loop[:, 1], -1) - np.roll(loop[:, 0], -1) * loop[:, 1])
    assert abs(area) == pytest.approx(a.sum(), rel=1e-9)
    # Euler characteristic of a disk
    E = len(np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0))
    assert len(V) - E + len(F) == 1
    # arms held out horizontally
    d = J[B[:, 1]] - J[B[:, 0]]
    arm = (np.abs(d[:, 1]) < 1e-9) & (np.abs(d[:, 0]) > 5)
    assert arm.sum() >= 2


def test_woody2d_vertices_on_joints_and_bones():
    V, F, J, B = demo_figure("woody2d")
    # a vertex exactly at each joint, not on the boundary
    bverts = set(np.unique(_boundary_edges(F)[0]).tolist())
    for p in J:
        dist = np.linalg.norm(V - p, axis=1)
        k = int(np.argmin(dist))
        assert dist[k] == 0.0
        assert k not in bverts
    # at least 5 interior samples along every bone
    for a, b in B:
        pa, pb = J[a], J[b]
        t = (V - pa) @ (pb - pa) / ((pb - pa) @ (pb - pa))
        off = np.linalg.norm(V - (pa + t[:, None] * (pb - pa)), axis=1)
        on = (off < 1e-9) & (t > 1e-9) & (t < 1 - 1e-9)
        assert on.sum() >= 5
    # usable for bounded biharmonic weights (libigl's check runs in 3D)
    V3 = np.c_[V, np.zeros(len(V))]
    J3 = np.c_[J, np.zeros(len(J))]
    b, bc = igl.boundary_conditions(V3, F, J3, np.zeros(0, dtype=np.int64), B)
    assert bc.shape[1] == len(B)
    assert len(b) >= len(J) + 5 * len(B)
