"""Simplified surfaces (supportless.files.simplify): a sculpt reduced fast, then carefully, stays closed and
uncrossed; a fast reduction that would cross itself is not used."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from supportless.base.geometry import signed_volume
from supportless.copyleft.cgal import intersecting_faces
from supportless.files import simplify
from supportless.files.meshes import check_closed_surface


@pytest.fixture
def sphere():
    m = trimesh.creation.icosphere(subdivisions=5, radius=10.0)  # 20 480 triangles
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


def test_a_dense_surface_is_reduced_fast_then_carefully(sphere, monkeypatch):
    monkeypatch.setattr(simplify, "PRE_REDUCTION_FACES", 4000)
    V, F = sphere
    U, G = simplify._pre_reduced(V, F, 150)
    assert 3900 <= len(G) <= 4000  # the fast stage stops at max(PRE_REDUCTION_FACES, 20 x target)
    out = simplify.simplify_surface(V, F, 150)
    assert out is not None
    U, G = out
    assert len(G) <= 150
    check_closed_surface(G)
    assert len(intersecting_faces(U, G)) == 0
    monkeypatch.setattr(simplify, "PRE_REDUCTION_FACES", 10 ** 9)  # libigl alone, from the whole surface
    direct = simplify.simplify_surface(V, F, 150)
    assert signed_volume(U, G) == pytest.approx(signed_volume(*direct), rel=0.03)


def test_a_fast_reduction_that_crosses_itself_is_not_used(sphere, monkeypatch):
    import fast_simplification

    monkeypatch.setattr(simplify, "PRE_REDUCTION_FACES", 4000)
    V, F = sphere

    def crossing(points, faces, target_count):  # two copies of a box, the second inside the first's wall
        box = trimesh.creation.box((2, 2, 2))
        P = np.vstack([box.vertices, box.vertices + 0.5])
        T = np.vstack([box.faces, box.faces + 8])
        return P, T

    monkeypatch.setattr(fast_simplification, "simplify", crossing)
    U, G = simplify._pre_reduced(V, F, 150)
    assert U is V and G is F


def test_a_figure_of_the_zoo_is_not_pre_reduced(sphere):
    V, F = sphere  # 20 480 triangles: well under PRE_REDUCTION_FACES
    U, G = simplify._pre_reduced(V, F, 10000)
    assert U is V and G is F


def test_poses_reduced_alike_share_their_faces_and_follow_their_pose(sphere):
    V, F = sphere
    R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    moved = V @ R.T + [5.0, 0, 0]  # a rigid motion of the whole surface
    (a, b), G = simplify.reduced_alike([V, moved], F, 2000)
    assert len(G) <= 2000 and a.shape == b.shape
    check_closed_surface(G)
    assert np.allclose(b, a @ R.T + [5.0, 0, 0], atol=1e-4)  # the same collapses, replayed on the moved pose
    same, H = simplify.reduced_alike([V], F, len(F))  # small enough: as it is
    assert np.array_equal(same[0], V) and np.array_equal(H, F)
