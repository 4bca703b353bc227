"""Built-in demo figures: closed, clean, rigged."""

import numpy as np
import pytest

import supportless as sl
from supportless.io import edge_counts
from supportless.kinematics import bone_parents, topological_order
from supportless.rig import signed_volume


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
    assert np.isclose(V[:, 1].min(), 0.0, atol=1e-9), "stands on y = 0"
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


def test_figures_are_deterministic():
    a = sl.demo_figure("branch")
    b = sl.demo_figure("branch")
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
    with pytest.raises((KeyError, ValueError)):
        sl.demo_figure("no-such-figure")
