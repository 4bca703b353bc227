"""The exact (CGAL) self-intersection test, against cases whose answer is known."""

import numpy as np
import pytest
from meshes import box

from supportless.copyleft.cgal import intersecting_face_pairs, intersecting_faces, self_intersects


def test_a_closed_box_does_not_intersect_itself():
    V, F = box((0, 0, 0), (1, 1, 1))
    pairs = intersecting_faces(V, F)
    assert pairs.shape == (0, 2) and pairs.dtype == np.int64
    assert intersecting_face_pairs(V, F) == 0


def test_two_overlapping_boxes_intersect_on_the_crossing_faces():
    V1, F1 = box((0, 0, 0), (1, 1, 1))
    V2, F2 = box((0.5, 0.25, 0.25), (1.5, 0.75, 0.75))
    V = np.vstack([V1, V2])
    F = np.vstack([F1, F2 + len(V1)])
    pairs = intersecting_faces(V, F)
    assert len(pairs) > 0
    # every pair has one face of each box: neither box intersects itself
    first = pairs < len(F1)
    assert np.all(first[:, 0] != first[:, 1])
    # the second box pierces only the first box's x = 1 face (two triangles)
    crossed = np.unique(np.where(first, pairs, -1))
    crossed = crossed[crossed >= 0]
    centroids = V[F[crossed]].mean(axis=1)
    np.testing.assert_allclose(centroids[:, 0], 1.0)
    assert intersecting_face_pairs(V, F) == len(pairs)


def test_separate_boxes_do_not_intersect():
    V1, F1 = box((0, 0, 0), (1, 1, 1))
    V2, F2 = box((2, 0, 0), (3, 1, 1))
    assert intersecting_face_pairs(np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])) == 0


def test_planar_meshes_have_no_exact_test():
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    F = np.array([[0, 1, 2]])
    assert intersecting_face_pairs(V, F) == -1
    with pytest.raises(ValueError):
        intersecting_faces(V, F)


def test_self_intersects_agrees_with_the_pairs():
    """The first-pair test answers as the full list does: overlapping, separate, touching at a shared face."""
    V1, F1 = box((0, 0, 0), (1, 1, 1))
    for lo, hi, expected in (((0.5, 0.25, 0.25), (1.5, 0.75, 0.75), True), ((2, 0, 0), (3, 1, 1), False)):
        V2, F2 = box(lo, hi)
        V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
        assert self_intersects(V, F) is expected
        assert self_intersects(V, F) == (intersecting_face_pairs(V, F) > 0)
    assert self_intersects(V1, F1) is False
    with pytest.raises(ValueError):
        self_intersects(np.zeros((3, 2)), np.array([[0, 1, 2]]))


def _planted(seed):
    """Two subdivided spheres that overlap, one with vertices pushed through its own far side: many pairs."""
    import trimesh

    rng = np.random.default_rng(seed)
    a, b = trimesh.creation.icosphere(3), trimesh.creation.icosphere(3)
    Va, Vb = a.vertices.copy(), b.vertices + [1.3, 0.2, 0.1]
    pushed = rng.choice(len(Va), 6, replace=False)
    Va[pushed] *= -0.8  # through the sphere to its other side
    return np.vstack([Va, Vb]), np.vstack([a.faces, b.faces + len(Va)]).astype(np.int64)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_check_in_parts_finds_the_pairs_of_the_whole_surface(monkeypatch, seed):
    """A surface past PART_FACES is checked in slabs: the same pairs, the same first-pair verdict."""
    import supportless.copyleft.cgal as cgal

    V, F = _planted(seed)
    reported = intersecting_faces(V, F)
    whole = np.unique(np.sort(reported, axis=1), axis=0)
    assert len(whole) == len(reported) > 10  # each pair once: the count is the same
    monkeypatch.setattr(cgal, "PART_FACES", 400)  # 2560 triangles: 7 slabs
    assert len(cgal.face_parts(V, F, 7)) == 7
    np.testing.assert_array_equal(intersecting_faces(V, F), whole)
    assert self_intersects(V, F) is True
    import trimesh

    clean = trimesh.creation.icosphere(4)  # 5120 triangles, none crossing
    assert intersecting_faces(clean.vertices, clean.faces).shape == (0, 2)
    assert self_intersects(clean.vertices, clean.faces) is False


def test_a_large_surface_asked_again_is_answered_from_memory(monkeypatch):
    """The pairs of the same vertices and faces (the report's count of a pose the search checked) cost no
    second CGAL call; a moved vertex does."""
    import supportless.copyleft.cgal as cgal

    V, F = _planted(2)
    monkeypatch.setattr(cgal, "PART_FACES", 400)
    monkeypatch.setattr(cgal, "_answers", cgal.OrderedDict())
    calls = []
    real = cgal._cgal
    monkeypatch.setattr(cgal, "_cgal", lambda *a: calls.append(1) or real(*a))
    first = intersecting_faces(V, F)
    n = len(calls)
    assert self_intersects(V.copy(), F.copy()) and len(calls) == n
    np.testing.assert_array_equal(intersecting_faces(V, F), first)
    assert len(calls) == n
    W = V.copy()
    W[0] += 1e-9
    intersecting_faces(W, F)
    assert len(calls) > n
