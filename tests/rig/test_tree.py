"""A skeleton that never tears: one kinematic tree per connected skeleton, anchored bones that stay put.

Properties checked on every built-in figure, the shared rigs and generated
TGF forests (sibling root bones at one joint, reversed bones, several
skeletons, roots on a middle bone):

* every joint shared by several bones is mapped to one point under any pose;
* each bone hangs from a bone it shares its pivot joint with, and each
  connected skeleton has exactly one root;
* the anchored bones (the contact and the bones joining it) never move when
  the free bones turn;
* turning the root of a tree turns the whole tree rigidly.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import supportless as sl
from supportless.base import kinematics as kin
from supportless.shapes import DEMO_FIGURES


def components(bones: np.ndarray) -> np.ndarray:
    """(m,) int: the connected skeleton of each bone (bones are connected when they share a joint)."""
    m = len(bones)
    label = np.arange(m)

    def find(b):
        while label[b] != b:
            label[b] = label[label[b]]
            b = label[b]
        return b

    first_at: dict[int, int] = {}
    for b, joints in enumerate(bones):
        for j in joints:
            if int(j) in first_at:
                label[find(b)] = find(first_at[int(j)])
            else:
                first_at[int(j)] = b
    return np.array([find(b) for b in range(m)])


def torn_distance(joints, bones, transforms) -> float:
    """The largest distance between two bones' images of a joint they share, over poses."""
    T = transforms if transforms.ndim == 4 else transforms[None]
    worst = 0.0
    for j in np.unique(bones):
        at = np.flatnonzero((bones == j).any(axis=1))
        if len(at) < 2:
            continue
        images = np.stack([kin.transform_points(T[:, [b]], joints[[j]])[:, 0] for b in at], axis=1)  # (P, k, d)
        worst = max(worst, float(np.abs(images - images[:, :1]).max()))
    return worst


def check_tree_shape(bones, parents, pivots):
    """Each bone hangs from a bone sharing its pivot; one root per connected skeleton."""
    for b, p in enumerate(parents):
        assert pivots[b] in bones[b]
        if p >= 0:
            assert pivots[b] in bones[p], (b, p, pivots[b])
    comp = components(bones)
    roots = np.flatnonzero(parents < 0)
    assert sorted(comp[roots].tolist()) == sorted(set(comp.tolist()))
    kin.topological_order(parents)  # no cycle


# --------------------------------------------------------------------------- generated forests
@st.composite
def forests(draw):
    """A TGF-like forest: joints in one or more trees, bones in any order and direction, candidate roots."""
    n = draw(st.integers(2, 14))
    trees = draw(st.integers(1, 3))
    edges = []
    for i in range(1, n):
        if i < trees:
            continue  # joints 0..trees-1 start a tree each
        parent = draw(st.integers(0, i - 1))
        flip = draw(st.booleans())
        edges.append((i, parent) if flip else (parent, i))
    if not edges:
        edges = [(0, 1)]
    order = draw(st.permutations(range(len(edges))))
    bones = np.array([edges[k] for k in order], np.int64)
    joints = draw(st.lists(st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 3), min_size=n, max_size=n))
    roots = draw(st.lists(st.integers(0, len(bones) - 1), max_size=3))
    return np.array(joints, np.float64), bones, roots


@settings(max_examples=120, deadline=None)
@given(forests(), st.integers(0, 2 ** 31 - 1))
def test_generated_forests_never_tear_and_their_roots_turn_them_rigidly(forest, seed):
    joints, bones, roots = forest
    parents, pivots = kin.kinematic_tree(bones, roots)
    check_tree_shape(bones, parents, pivots)
    comp = components(bones)
    for r in roots:  # the first candidate root of each skeleton is its root
        first = next(c for c in roots if comp[c] == comp[r])
        assert parents[first] == -1
    order = kin.topological_order(parents)
    rng = np.random.default_rng(seed)
    angles = rng.uniform(-1.5, 1.5, (3, len(bones), 3))
    T = kin.forward_kinematics(joints, bones, angles, parents, order, pivots)
    assert torn_distance(joints, bones, T) < 1e-9
    # only the roots turn: every bone of a tree moves as its root does
    only = np.zeros_like(angles)
    tops = np.flatnonzero(parents < 0)
    only[:, tops] = angles[:, tops]
    T = kin.forward_kinematics(joints, bones, only, parents, order, pivots)
    for top in tops:
        same = comp == comp[top]
        np.testing.assert_allclose(T[:, same], np.broadcast_to(T[:, [top]], T[:, same].shape), atol=1e-12)


def test_sibling_root_bones_hang_from_the_bone_that_carries_their_joint():
    # two bones leave joint 0 (0-1 and 0-3), none arrives; re-rooted at the foot 3-4 (the bunny's case)
    joints = np.array([[0.0, 1, 0], [0, 2, 0], [0, 3, 0], [1, 0.5, 0], [1, 0, 0]])
    bones = np.array([[0, 1], [1, 2], [0, 3], [3, 4]])
    parents, pivots = kin.kinematic_tree(bones, [3])
    assert parents.tolist() == [2, 0, 3, -1]  # 0-1 hangs from 0-3, which carries joint 0 now
    assert pivots.tolist() == [0, 1, 3, 3]
    angles = np.zeros((1, 4, 3))
    angles[0, 2] = [0.0, 0.0, 0.7]  # turn 0-3 about joint 3
    T = kin.forward_kinematics(joints, bones, angles, parents, kin.topological_order(parents), pivots)
    assert torn_distance(joints, bones, T) < 1e-12
    # the tree of version 1 left 0-1 a root about joint 0, which moves with the reversed chain: it tore
    old, old_pivots = kin.reroot(bones, kin.bone_parents(bones), 3)
    assert old.tolist() == [-1, 0, 3, -1]
    T = kin.forward_kinematics(joints, bones, angles, old, kin.topological_order(old), old_pivots)
    assert torn_distance(joints, bones, T) > 0.5


def test_without_roots_each_skeleton_hangs_from_its_first_root_bone():
    bones = np.array([[0, 1], [0, 2], [5, 6], [2, 3]])  # two bones leave joint 0; a second skeleton 5-6
    parents, pivots = kin.kinematic_tree(bones)
    assert parents.tolist() == [-1, 0, -1, 1]
    assert pivots.tolist() == [0, 0, 5, 2]


# --------------------------------------------------------------------------- rigs
FIGURES = [name for name in DEMO_FIGURES]


@pytest.fixture(scope="module", params=FIGURES + ["bunny", "bb-bunny"])
def any_rig(request, rig_cache_dir, shared_file):
    if request.param in DEMO_FIGURES:
        return sl.load_rig(f"demo:{request.param}", cache_dir=rig_cache_dir)
    shared_file(f"{request.param}.tgf")
    return sl.load_rig(shared_file(f"{request.param}.obj"))  # the user's cache: prepared once per machine


def test_rigs_never_tear_and_anchored_bones_stay(any_rig):
    rig = any_rig
    check_tree_shape(rig.bones, rig.parents, rig.pivots)
    fixed = sl.SearchSettings().fixed_bones(rig)
    assert np.all(fixed[rig.anchored_bones])
    rng = np.random.default_rng(7)
    angles = rng.uniform(-0.4, 0.4, (5, rig.bone_count, 3))
    angles[:, fixed] = 0.0
    T = rig.transforms(angles)
    height = float(np.ptp(rig.vertices @ rig.up))
    assert torn_distance(rig.joints, rig.bones, T) < 1e-9 * height
    identity = np.concatenate([np.eye(rig.dim), np.zeros((rig.dim, 1))], axis=1)
    np.testing.assert_allclose(T[:, rig.anchored_bones], np.broadcast_to(identity, T[:, rig.anchored_bones].shape),
                               atol=1e-12)
    # every bone free: still one point per joint
    free = rng.uniform(-0.6, 0.6, (3, rig.bone_count, 3))
    assert torn_distance(rig.joints, rig.bones, rig.transforms(free)) < 1e-9 * height


def test_turning_a_rigs_root_is_rigid(any_rig):
    rig = any_rig
    roots = np.flatnonzero(rig.parents < 0)
    angles = rig.rest_angles()
    angles[roots] = [0.3, -0.2, 0.5]
    V = rig.pose(angles)
    # every vertex follows the one rigid motion: pairwise distances are kept
    rng = np.random.default_rng(3)
    i, j = rng.integers(0, len(V), (2, 400))
    d0 = np.linalg.norm(rig.vertices[i] - rig.vertices[j], axis=1)
    d1 = np.linalg.norm(V[i] - V[j], axis=1)
    np.testing.assert_allclose(d1, d0, atol=1e-9 * np.ptp(rig.vertices))
    if rig.dim == 3:
        arap = sl.SearchSettings().objective(rig).terms(angles[None])["arap"]
        assert float(arap[0]) == pytest.approx(0.0, abs=1e-9)


def test_a_pose_of_the_old_torn_tree_is_refused(bunny_rig, tmp_path):
    from supportless.files.posefile import read_pose, write_pose

    rig = bunny_rig
    old = kin.reroot(rig.bones, kin.bone_parents(rig.bones), rig.root_bone)
    assert not all(np.array_equal(a, b) for a, b in zip(old, rig.tree))  # the bunny's tree changed
    write_pose(tmp_path / "v1.json", rig.rest_angles(), rig.bones)  # a version-1 file: no tree
    with pytest.raises(sl.InputError, match="run optimize again"):
        read_pose(tmp_path / "v1.json", rig.bones, tree=rig.tree, root_bone=rig.root_bone)
    write_pose(tmp_path / "v2.json", rig.rest_angles(), rig.bones, tree=rig.tree)
    assert read_pose(tmp_path / "v2.json", rig.bones, tree=rig.tree, root_bone=rig.root_bone).shape == (rig.bone_count, 3)
    other = (np.roll(rig.parents, 1), rig.pivots)
    write_pose(tmp_path / "other.json", rig.rest_angles(), rig.bones, tree=other)
    with pytest.raises(sl.InputError, match="another kinematic tree"):
        read_pose(tmp_path / "other.json", rig.bones, tree=rig.tree, root_bone=rig.root_bone)


def test_a_version_1_pose_of_an_unchanged_tree_is_read(branch_rig, tmp_path):
    from supportless.files.posefile import read_pose, write_pose

    rig = branch_rig
    old = kin.reroot(rig.bones, kin.bone_parents(rig.bones), rig.root_bone)
    assert all(np.array_equal(a, b) for a, b in zip(old, rig.tree))
    write_pose(tmp_path / "v1.json", rig.rest_angles() + 0.1, rig.bones)
    np.testing.assert_array_equal(read_pose(tmp_path / "v1.json", rig.bones, tree=rig.tree,
                                            root_bone=rig.root_bone), rig.rest_angles() + 0.1)
