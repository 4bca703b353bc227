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
