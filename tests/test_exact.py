"""The exact (CGAL) self-intersection test, against cases whose answer is known."""

import numpy as np
import pytest

from supportless.energies.exact import intersecting_face_pairs, intersecting_faces, self_intersects

from meshes import box


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


# --------------------------------------------------------------------------- #
# the broad phase of rigid parts
# --------------------------------------------------------------------------- #
def _parts(rng):
    """Five boxes: four rigid on bones 0-3, one blending bones 0 and 1; random moves of the bones."""
    Vs, Fs, W = [], [], []
    for i in range(5):
        V, F = box((2.0 * i, 0, 0), (2.0 * i + 1.5, 1, 1))
        Fs.append(F + sum(len(v) for v in Vs))
        Vs.append(V)
        w = np.zeros((len(V), 4))
        if i < 4:
            w[:, i] = 1.0
        else:
            w[:, :2] = 0.5
        W.append(w)
    return np.vstack(Vs), np.vstack(Fs), np.vstack(W)


def test_the_rigid_parts_broad_phase_gives_the_full_answer():
    from supportless.energies.exact import broad_phase_groups, faces_that_can_meet, rigid_face_groups

    rng = np.random.default_rng(0)
    V, F, W = _parts(rng)
    groups = rigid_face_groups(W, F)
    np.testing.assert_array_equal(groups, np.repeat([0, 1, 2, 3, -1], 12))
    np.testing.assert_array_equal(broad_phase_groups(V, F, W), groups)  # clean at rest: worth using
    answers = []
    for _ in range(150):
        moved = V + W @ rng.normal(0.0, 1.2, (4, 3))  # each bone shifts its part; the blend follows both
        kept = faces_that_can_meet(moved, F, groups)
        answers.append(self_intersects(moved, F))
        assert self_intersects(moved, F, groups) == answers[-1]
        assert np.all(np.isin(np.flatnonzero(groups < 0), kept))  # blending faces are always checked
        pairs = intersecting_faces(moved, F)
        assert np.all(np.isin(pairs, kept))  # every intersecting pair passes the broad phase
    assert 20 < sum(answers) < 130  # both answers occur


def test_no_broad_phase_when_it_cannot_help():
    from supportless.energies.exact import broad_phase_groups

    V, F, W = _parts(np.random.default_rng(0))
    assert broad_phase_groups(V, F, np.full_like(W, 0.25)) is None  # everything blends
    overlap = V.copy()
    overlap[:8] += [1.0, 0.0, 0.0]  # ...or the rest pose intersects itself: box 0 pushed into box 1
    assert self_intersects(overlap, F) and broad_phase_groups(overlap, F, W) is None


def test_the_robots_poses_get_the_same_exact_answer_through_the_broad_phase(shared_file):
    import supportless as sl
    from supportless.bench import random_poses
    from supportless.energies.exact import broad_phase_groups, faces_that_can_meet

    rig = sl.load_rig(shared_file("gltf/RobotExpressive.glb"))
    groups = broad_phase_groups(rig.vertices, rig.faces, rig.weights)
    assert groups is not None and np.mean(groups >= 0) > 0.5  # mostly rigid parts
    answers = []
    rng = np.random.default_rng(4)
    for angles in random_poses(rig, 24, max_angle=40.0, seed=4):  # one bone at a time: its parts meet in seams
        angles[np.arange(rig.bone_count) != rng.integers(rig.bone_count)] = 0.0
        V = rig.pose(angles)
        answers.append(self_intersects(V, rig.faces))
        assert self_intersects(V, rig.faces, groups) == answers[-1]
        assert len(faces_that_can_meet(V, rig.faces, groups)) < len(rig.faces)
    assert any(answers) and not all(answers)
