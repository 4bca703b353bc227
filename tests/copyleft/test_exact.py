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
    np.testing.assert_array_equal(intersecting_faces(V, F), whole)  # (the triangles the filter leaves)
    assert self_intersects(V, F) is True
    monkeypatch.setattr(cgal, "_answers", cgal.OrderedDict())
    monkeypatch.setattr(cgal, "possibly_crossing_faces", lambda V, F: np.ones(len(F), bool))  # every slab
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


def _normal(pairs):
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    return np.unique(np.sort(pairs, axis=1), axis=0) if len(pairs) else np.zeros((0, 2), np.int64)


def test_pairs_since_an_earlier_pose_are_the_whole_surfaces_pairs(tpose_rig, monkeypatch):
    """One limb moved after another: the pairs found from the last pose's pairs are those of a whole check."""
    from supportless.copyleft import cgal
    from supportless.copyleft.cgal import intersecting_faces, intersecting_faces_since

    rig = tpose_rig
    asked = []
    real = cgal._cgal
    monkeypatch.setattr(cgal, "_cgal", lambda V, F, first: asked.append(len(F)) or real(V, F, first))
    rng = np.random.default_rng(3)
    angles = rig.rest_angles().copy()
    V0 = rig.pose(angles)
    pairs = _normal(intersecting_faces(V0, rig.faces))
    crossed = 0
    for step in range(6):
        bone = [4, 5, 7, 8, 11, 14][step]  # arms and legs, one at a time
        angles[bone] = rng.uniform(-1.6, 1.6, 3)
        V1 = rig.pose(angles)
        asked.clear()
        since = intersecting_faces_since(V1, rig.faces, V0, pairs)
        partial = sum(asked)
        whole = _normal(intersecting_faces(V1, rig.faces))
        np.testing.assert_array_equal(since, whole)
        assert partial <= len(rig.faces)
        crossed += len(whole) > 0
        V0, pairs = V1, since
    assert crossed  # some of these poses cross themselves, so kept and new pairs are both tested
    # nothing moved: the earlier pairs, no CGAL call
    asked.clear()
    np.testing.assert_array_equal(intersecting_faces_since(V0, rig.faces, V0.copy(), pairs), pairs)
    assert not asked


def test_pairs_since_ask_only_about_what_moved_and_what_its_box_meets(monkeypatch):
    """Four boxes in a row; the last one moved into the third: CGAL is asked about those two only, and the
    pairs of the first two (crossing each other, not moved) are kept."""
    from supportless.copyleft import cgal
    from supportless.copyleft.cgal import intersecting_faces, intersecting_faces_since

    boxes = [box((0, 0, 0), (1, 1, 1)), box((0.5, 0.2, 0.2), (1.5, 0.8, 0.8)), box((3, 0, 0), (4, 1, 1)),
             box((6, 0, 0), (7, 1, 1))]
    V0 = np.vstack([v for v, _ in boxes])
    F = np.vstack([f + 8 * i for i, (_, f) in enumerate(boxes)])
    before = _normal(intersecting_faces(V0, F))
    assert len(before) and before.max() < 24  # the first two cross
    V1 = V0.copy()
    V1[24:] -= [2.5, 0.0, 0.0]  # the fourth box into the third
    asked = []
    real = cgal._cgal
    monkeypatch.setattr(cgal, "_cgal", lambda V, F, first: asked.append(len(F)) or real(V, F, first))
    since = intersecting_faces_since(V1, F, V0, before)
    # one call: the fourth box's 12 triangles and the third's that its box meets (all but the two at x = 3)
    assert asked == [22]
    np.testing.assert_array_equal(since, _normal(intersecting_faces(V1, F)))
    assert (since < 24).all(axis=1).any() and (since >= 24).any()  # kept pairs and new ones
