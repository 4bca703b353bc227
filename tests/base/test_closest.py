"""The nearest triangle of another group (supportless.base.closest) against libigl's distance queries."""

import igl
import numpy as np
import pytest
import trimesh

from supportless.base.closest import nearest_other_face, point_triangle_distance2


def test_the_distance_to_a_triangle_is_libigls_in_every_voronoi_region():
    rng = np.random.default_rng(0)
    for _ in range(20):
        T = rng.normal(size=(3, 3))
        P = rng.normal(scale=2.0, size=(200, 3))  # points near each vertex, edge and the inside
        expected, _, _ = igl.point_mesh_squared_distance(P, T, np.array([[0, 1, 2]]))
        got = [point_triangle_distance2(*p, *T[0], *T[1], *T[2]) for p in P]
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-12)


def test_a_right_triangle_in_closed_form():
    a, b, c = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    assert point_triangle_distance2(0.2, 0.2, 3.0, *a, *b, *c) == pytest.approx(9.0)  # over the inside
    assert point_triangle_distance2(-1.0, -1.0, 0.0, *a, *b, *c) == pytest.approx(2.0)  # vertex a
    assert point_triangle_distance2(1.0, 1.0, 0.0, *a, *b, *c) == pytest.approx(0.5)  # edge bc


def test_the_nearest_triangle_of_another_group_is_a_tree_per_group():
    sphere = trimesh.creation.icosphere(3, radius=1.0)
    V, F = sphere.vertices, sphere.faces
    face_group = (V[F].mean(axis=1)[:, 0] > 0).astype(np.int64) + 2 * (V[F].mean(axis=1)[:, 2] > 0.5)
    rng = np.random.default_rng(1)
    P = rng.normal(scale=0.7, size=(60, 3))
    group = rng.integers(0, 3, 60)
    d2, nearest = nearest_other_face(P, group, V, F, face_group)
    for g in range(3):
        mine = group == g
        others = np.flatnonzero(face_group != g)
        expected, at, _ = igl.point_mesh_squared_distance(P[mine], V, F[others])
        np.testing.assert_allclose(d2[mine], expected, rtol=1e-9, atol=1e-12)
        assert np.all(face_group[nearest[mine]] != g)
        # the triangle found is at that distance (another at a tie is as good)
        np.testing.assert_allclose(d2[mine], [point_triangle_distance2(*p, *V[F[f, 0]], *V[F[f, 1]], *V[F[f, 2]])
                                              for p, f in zip(P[mine], nearest[mine])], rtol=1e-12)


def test_a_point_whose_group_owns_every_triangle_has_none():
    V = np.eye(3)
    d2, nearest = nearest_other_face(np.zeros((1, 3)), np.array([0]), V, np.array([[0, 1, 2]]), np.array([0]))
    assert d2[0] == np.inf and nearest[0] == -1
