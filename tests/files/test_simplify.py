"""Simplified surfaces (supportless.files.simplify): a surface simplified by libigl stays closed, uncrossed and
near its volume; poses reduced alike stay poses of one mesh."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from supportless.base.geometry import signed_volume
from supportless.copyleft.cgal import intersecting_faces
from supportless.files import simplify
from supportless.files.meshes import check_closed_surface


def icosphere(subdivisions: int):
    """(V, F) of a sphere of radius 10: 20 480 triangles at 5 subdivisions, 81 920 at 6."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=10.0)
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


@pytest.fixture
def sphere():
    return icosphere(5)


def test_a_closed_surface_is_simplified_closed_and_uncrossed(sphere):
    V, F = sphere
    U, G = simplify.simplify_surface(V, F, 150)
    assert len(G) <= 150
    check_closed_surface(G)
    assert len(intersecting_faces(U, G)) == 0
    assert signed_volume(U, G) == pytest.approx(4 / 3 * np.pi * 1000, rel=0.2)  # midpoint collapses shrink it


def test_poses_reduced_alike_share_their_faces_and_follow_their_pose(sphere):
    V, F = sphere
    R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    moved = V @ R.T + [5.0, 0, 0]  # a rigid motion of the whole surface
    (a, b), G = simplify.reduced_alike([V, moved], F, 2000)
    assert len(G) <= 2000 and a.shape == b.shape
    check_closed_surface(G)
    assert np.allclose(b, a @ R.T + [5.0, 0, 0], atol=1e-9)  # the same collapses, replayed on the moved pose
    # every reduced vertex is a vertex of its pose, even where a pose bends the surface
    bent = V.copy()
    bent[V[:, 2] > 0, 0] += 3.0 * V[V[:, 2] > 0, 2]
    (c, d), _ = simplify.reduced_alike([V, bent], F, 2000)
    assert {tuple(p) for p in d} <= {tuple(p) for p in bent}
    assert np.ptp(d, axis=0).max() <= np.ptp(bent, axis=0).max()
    same, H = simplify.reduced_alike([V], F, len(F))  # small enough: as it is
    assert np.array_equal(same[0], V) and np.array_equal(H, F)


@pytest.fixture(scope="module")
def fine_sphere():
    return icosphere(6)


def test_a_quick_reduction_is_closed_uncrossed_and_has_no_tiny_edges(fine_sphere):
    V, F = fine_sphere
    U, G = simplify.quickly_reduced(V, F, 4000)
    assert len(G) <= 4000
    check_closed_surface(G)
    assert len(intersecting_faces(U, G)) == 0
    assert signed_volume(U, G) == pytest.approx(4 / 3 * np.pi * 1000, rel=0.02)  # quadric placement: on the body
    E = np.unique(np.sort(np.concatenate([G[:, [0, 1]], G[:, [1, 2]], G[:, [2, 0]]]), axis=1), axis=0)
    length = np.linalg.norm(U[E[:, 0]] - U[E[:, 1]], axis=1)
    assert length.min() >= simplify.WELD_FRACTION * np.median(length)
    assert np.allclose(np.linalg.norm(U, axis=1), 10.0, atol=0.05)


def test_past_the_threshold_the_fast_reduction_comes_first_and_a_bad_one_is_passed_over(fine_sphere, monkeypatch):
    V, F = fine_sphere
    monkeypatch.setattr(simplify, "FAST_FIRST_FACES", 20_000)
    monkeypatch.setattr(simplify, "FAST_FIRST_TARGET", 8_000)
    monkeypatch.setattr(simplify, "PROXY_CELLS", 60)  # the route is the subject, not the grid's fineness (200: 10 s)
    seen = []
    quick = simplify.quickly_reduced

    def spy(V, F, n):
        seen.append((len(F), n))
        return quick(V, F, n)

    monkeypatch.setattr(simplify, "quickly_reduced", spy)
    gridded = []
    from supportless.files import gridsurface

    remade = gridsurface.grid_surface
    monkeypatch.setattr(gridsurface, "grid_surface",
                        lambda V, F, cells, closed: gridded.append((cells, closed)) or remade(V, F, cells, closed))
    U, G = simplify.simplify_surface(V, F, 500)
    assert seen == [(len(F), 8_000)] and len(G) <= 500
    assert gridded == [(simplify.PROXY_CELLS, True)]  # a proxy: collapsed from the quick reduction's grid surface
    check_closed_surface(G)
    assert len(intersecting_faces(U, G)) == 0
    assert len(simplify.folded_pairs(U, G)) == 0
    assert signed_volume(U, G) == pytest.approx(4 / 3 * np.pi * 1000, rel=0.2)
    # the grid's surface is collapsed without refusing collapses, and again refusing them when that is not clean
    import igl

    blocks, decimate = [], igl.decimate
    monkeypatch.setattr(igl, "decimate", lambda *a: blocks.append(a[3]) or decimate(*a))
    simplify.simplify_surface(V, F, 500)
    monkeypatch.setattr(simplify, "_clean", lambda U, G: False)
    U1, G1 = simplify.simplify_surface(V, F, 500)
    assert blocks == [False, False, True] and len(intersecting_faces(U1, G1)) == 0
    monkeypatch.setattr(igl, "decimate", decimate)
    # the slow way: asked for, or when the quick reduction is not clean (None)
    seen.clear()
    U2, G2 = simplify.simplify_surface(V, F, 500, fast_first=False)
    assert seen == [] and len(G2) <= 500
    monkeypatch.setattr(simplify, "quickly_reduced", lambda V, F, n: seen.append(n))
    U3, G3 = simplify.simplify_surface(V, F, 500)
    assert seen == [8_000] and np.array_equal(G3, G2) and np.array_equal(U3, U2)
    # a surface under the threshold is simplified the slow way, as always
    seen.clear()
    simplify.simplify_surface(*icosphere(4), 300)
    assert seen == []


def test_folded_pairs_are_the_adjacent_triangles_whose_normals_are_opposite():
    """A regular-ish tetrahedron has none; a sliver tetrahedron (a corner a hair above the opposite face) has its
    two triangles on the long edge folded onto each other."""
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    assert len(simplify.folded_pairs(V, F)) == 0
    # triangles 0 and 1 share edge 0-1; corner 3 lies a hair above triangle 0, so triangle 1 folds back over it
    W = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 0.9, 1e-6]])
    G = np.array([[0, 1, 2], [1, 0, 3], [0, 2, 3], [1, 3, 2]])  # a closed sliver tetrahedron
    pairs = simplify.folded_pairs(W, G)
    assert {tuple(sorted(p)) for p in pairs.tolist()} >= {(0, 1)}
