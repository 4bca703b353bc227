"""Bones from a joint hierarchy (:mod:`supportless.files.joints`), on hand-made hierarchies."""

from __future__ import annotations

import numpy as np
import pytest

from supportless.base.errors import InputError
from supportless.files.joints import LEAF_REACH, joint_order, skeleton_from_joints


def hip_with_four_children():
    """A hip (0) with a spine (1 -> 2), a tail (3) and two legs (4, 5), under an unweighted root chain (6 -> 7).

    Returns positions (8, 3), parents (8,), names, and a vertex cloud with one
    blob of vertices around each weighted joint and its weights (one joint each).
    """
    P = np.array([[0, 1, 0], [0, 2, 0], [0, 3, 0], [0, 1, -1], [-0.5, 0, 0], [0.5, 0, 0], [0, -1, 0], [0, -0.5, 0.0]])
    parents = np.array([7, 0, 1, 0, 0, 0, -1, 6])
    names = ["hip", "spine", "head", "tail", "legL", "legR", "root", "armature"]
    rng = np.random.default_rng(0)
    blobs = {0: [0, 1.3, 0], 1: [0, 2.5, 0], 2: [0, 3.4, 0], 3: [0, 1, -1.5], 4: [-0.5, -0.3, 0], 5: [0.5, -0.3, 0]}
    X, W = [], []
    for j, c in blobs.items():
        X.append(np.asarray(c) + 0.05 * rng.standard_normal((20, 3)))
        w = np.zeros((20, len(P)))
        w[:, j] = 1.0
        W.append(w)
    return P.astype(float), parents, names, np.vstack(X), np.vstack(W)


def test_unweighted_roots_are_pruned_and_every_weighted_joint_has_a_bone():
    P, parents, names, X, W = hip_with_four_children()
    sk = skeleton_from_joints(P, parents, W, names, X)
    assert sorted(sk.pruned) == ["armature", "root"]
    # the bones carrying weight are named after their joints; each weighted joint's weight moved onto one bone
    carried = [n for n in sk.names if ">" not in n]
    assert sorted(carried) == sorted(["hip", "spine", "head", "tail", "legL", "legR"])
    np.testing.assert_allclose(sk.weights.sum(1), 1.0)
    for name in carried:
        b = sk.names.index(name)
        j = names.index(name)
        np.testing.assert_array_equal(sk.weights[:, b], W[:, j])


def test_the_hip_weight_goes_to_the_child_bone_nearest_its_skin():
    P, parents, names, X, W = hip_with_four_children()
    sk = skeleton_from_joints(P, parents, W, names, X)
    hip = sk.names.index("hip")
    # the hip's skin sits above the hip joint, along the spine: the hip->spine bone carries it
    tip = sk.joint_of[sk.bones[hip, 1]]
    assert names[tip] == "spine"
    # the other bones from the hip carry nothing and say so in their names
    for child in ("tail", "legL", "legR"):
        b = sk.names.index(f"hip>{child}")
        assert sk.weights[:, b].max() == 0.0


def test_a_weighted_leaf_gets_a_bone_nearly_as_long_as_its_skin_reaches():
    P, parents, names, X, W = hip_with_four_children()
    sk = skeleton_from_joints(P, parents, W, names, X)
    head = sk.names.index("head")
    a, b = sk.bones[head]
    assert sk.joint_of[b] == -1  # an added tip
    region = X[W[:, 2] > 0]
    direction = (sk.joints[b] - sk.joints[a]) / np.linalg.norm(sk.joints[b] - sk.joints[a])
    np.testing.assert_allclose(LEAF_REACH * np.max((region - P[2]) @ direction), np.linalg.norm(sk.joints[b] - sk.joints[a]))


def test_every_joint_has_a_driver_bone_and_pruned_tips_follow_their_parent():
    P, parents, names, X, W = hip_with_four_children()
    P = np.vstack([P, [0, 3.6, 0]])  # an unweighted "head_end"
    parents = np.append(parents, 2)
    names = names + ["head_end"]
    W = np.column_stack([W, np.zeros(len(W))])
    sk = skeleton_from_joints(P, parents, W, names, X)
    assert "head_end" in sk.pruned
    assert sk.driver[8] == sk.driver[2] == sk.names.index("head")
    assert sk.driver[6] == -1  # a pruned root follows nothing


def test_a_skin_with_no_weight_is_an_error():
    P, parents, names, X, W = hip_with_four_children()
    with pytest.raises(InputError, match="no bone that carries weight"):
        skeleton_from_joints(P, parents, np.zeros_like(W), names, X)


def test_joint_order_puts_parents_first():
    parents = np.array([3, 0, 1, -1, 3])
    order = list(joint_order(parents))
    for j, p in enumerate(parents):
        if p >= 0:
            assert order.index(p) < order.index(j)


def test_several_weighted_roots_make_a_forest():
    """Two unconnected chains (a character and a separate prop): both keep their bones."""
    P = np.array([[0, 0, 0], [0, 1, 0], [3, 0, 0], [3, 1, 0.0]])
    parents = np.array([-1, 0, -1, 2])
    names = ["a0", "a1", "b0", "b1"]
    X = np.array([[0, 0.5, 0], [0, 1.5, 0], [3, 0.5, 0], [3, 1.5, 0.0]])
    W = np.eye(4)
    sk = skeleton_from_joints(P, parents, W, names, X)
    assert sk.pruned == []
    assert sorted(n for n in sk.names if ">" not in n) == names
    roots = {tuple(sk.joints[a]) for a, _ in sk.bones} - {tuple(sk.joints[b]) for _, b in sk.bones}
    assert roots == {(0.0, 0.0, 0.0), (3.0, 0.0, 0.0)}


def test_depth_below_a_surface_by_the_tree_agrees_with_the_exact_signed_distance(monkeypatch):
    import trimesh

    from supportless.files import joints as joints_mod

    m = trimesh.creation.icosphere(subdivisions=4, radius=2.0)
    V, F = np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)
    rng = np.random.default_rng(3)
    P = rng.normal(size=(60, 3))
    P *= rng.uniform(0.0, 3.0, size=(60, 1)) / np.linalg.norm(P, axis=1, keepdims=True)
    P = P[np.abs(np.linalg.norm(P, axis=1) - 2.0) > 0.05]  # clear of the surface: the sign is not in doubt
    exact = joints_mod.depth_below(V, F)(P)
    monkeypatch.setattr(joints_mod, "TREE_FACES", 0)
    by_tree = joints_mod.depth_below(V, F)(P)
    np.testing.assert_allclose(by_tree, exact, atol=1e-12)
    np.testing.assert_allclose(exact, 2.0 - np.linalg.norm(P, axis=1), atol=0.02)  # the facets lie within 0.02


def test_winding_numbers_of_a_surface_are_libigls_fast_ones_with_one_tree():
    import igl
    import trimesh

    from supportless.files.joints import winding_numbers_of

    sphere = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    V, F = np.asarray(sphere.vertices), np.asarray(sphere.faces, np.int64)
    P = np.random.default_rng(4).uniform(-3.0, 3.0, size=(400, 3))
    winding = winding_numbers_of(V, F)
    assert np.array_equal(winding(P), igl.fast_winding_number(V, F, P))
    inside = np.linalg.norm(P, axis=1) < 1.9
    outside = np.linalg.norm(P, axis=1) > 2.1
    assert np.all(winding(P)[inside] > 0.9) and np.all(np.abs(winding(P)[outside]) < 0.1)
    assert winding(P[0]).shape == (1,)  # one point asked on its own
