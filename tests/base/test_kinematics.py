"""Forward kinematics, Euler angles and linear blend skinning (supportless.base.kinematics)."""

import igl
import numpy as np
import pytest
from scipy.spatial.distance import pdist
from scipy.spatial.transform import Rotation

import supportless as sl
from supportless.base import kinematics as kin


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _scipy_matrix(a):
    """Our convention built independently: intrinsic XYZ in scipy."""
    return Rotation.from_euler("XYZ", a).as_matrix()


# ------------------------------------------------------------------ Euler angles


def test_scipy_intrinsic_xyz_is_rx_ry_rz():
    """Check the reference itself: scipy's intrinsic 'XYZ' is Rx @ Ry @ Rz."""
    rng = np.random.default_rng(1)
    for a in rng.uniform(-np.pi, np.pi, (20, 3)):
        np.testing.assert_allclose(_scipy_matrix(a), _rx(a[0]) @ _ry(a[1]) @ _rz(a[2]), atol=1e-14)


def test_euler_matrix_is_a_rotation_matching_scipy():
    rng = np.random.default_rng(2)
    a = rng.uniform(-np.pi, np.pi, (50, 3))
    R = kin.euler_to_matrix(a)
    assert R.shape == (50, 3, 3)
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-13)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-13)
    np.testing.assert_allclose(R, Rotation.from_euler("XYZ", a).as_matrix(), atol=1e-14)
    # each angle alone is a rotation about its own axis
    np.testing.assert_allclose(kin.euler_to_matrix([0.3, 0, 0]), _rx(0.3), atol=1e-15)
    np.testing.assert_allclose(kin.euler_to_matrix([0, 0.3, 0]), _ry(0.3), atol=1e-15)
    np.testing.assert_allclose(kin.euler_to_matrix([0, 0, 0.3]), _rz(0.3), atol=1e-15)


def test_matrix_to_euler_inverts_euler_to_matrix_also_near_gimbal_lock():
    rng = np.random.default_rng(3)
    a = rng.uniform(-np.pi, np.pi, (200, 3))
    a[:, 1] = rng.uniform(-np.pi / 2, np.pi / 2, 200)
    # the middle angle at and near +-90 degrees (gimbal lock)
    near = np.pi / 2 - np.array([0.0, 1e-15, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 1e-1])
    a[: 2 * len(near), 1] = np.concatenate([near, -near])
    R = kin.euler_to_matrix(a)
    back = kin.matrix_to_euler(R)
    assert back.shape == a.shape
    # euler -> matrix -> euler -> matrix: the same rotation everywhere
    np.testing.assert_allclose(kin.euler_to_matrix(back), R, atol=1e-13)
    assert np.all(np.abs(back[:, 1]) <= np.pi / 2) and np.all(np.abs(back) <= np.pi)
    # away from gimbal lock the angles themselves come back
    far = np.cos(a[:, 1]) > 1e-3
    np.testing.assert_allclose(back[far], a[far], atol=1e-9)
    # at gimbal lock only a0 + a2 (a1 = +90) or a0 - a2 (a1 = -90) matters; a0 is set to 0
    locked = kin.matrix_to_euler(kin.euler_to_matrix([[0.3, np.pi / 2, 0.2], [0.3, -np.pi / 2, 0.2]]))
    np.testing.assert_allclose(locked, [[0.0, np.pi / 2, 0.5], [0.0, -np.pi / 2, -0.1]], atol=1e-12)
    # one matrix in, one angle triple out; a single axis is that axis
    np.testing.assert_allclose(kin.matrix_to_euler(_ry(0.4)), [0.0, 0.4, 0.0], atol=1e-15)


def test_planar_rotation_is_counter_clockwise():
    R = kin.planar_rotation(np.pi / 2)
    np.testing.assert_allclose(R @ [1.0, 0.0], [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(kin.planar_rotation(np.linspace(0, 6, 7))), 1.0, atol=1e-14)


# ------------------------------------------------------------ forward kinematics


def test_zero_angles_give_identity_and_rest_mesh(tpose_rig):
    rig = tpose_rig
    m, d = rig.bone_count, rig.dim
    T = rig.transforms(np.zeros((m, 3)))
    assert T.shape == (m, d, d + 1)
    assert np.array_equal(T, np.broadcast_to(np.hstack([np.eye(d), np.zeros((d, 1))]), T.shape))
    scale = np.ptp(rig.vertices, axis=0).max()
    np.testing.assert_allclose(rig.pose(rig.rest_angles()), rig.vertices, rtol=0, atol=1e-12 * scale)
    assert np.array_equal(rig.posed_joints(rig.rest_angles()), rig.joints)


def test_rotating_a_bone_leaves_unweighted_vertices_fixed(tpose_rig):
    rig = tpose_rig
    rng = np.random.default_rng(3)
    scale = np.ptp(rig.vertices, axis=0).max()
    for b in (4, 10, 1):  # left elbow bone, left knee bone, neck bone
        angles = rig.rest_angles()
        angles[b] = rng.uniform(-0.8, 0.8, 3)
        posed = rig.pose(angles)
        sub = kin.descendants(rig.parents, b)
        untouched = rig.weights[:, sub].sum(1) == 0
        assert untouched.sum() > len(rig.vertices) // 4
        np.testing.assert_allclose(posed[untouched], rig.vertices[untouched], rtol=0, atol=1e-12 * scale)
        # and the vertices carried by the subtree do move
        own = rig.weights[:, sub].sum(1) > 0.9
        assert own.any()
        assert np.linalg.norm(posed[own] - rig.vertices[own], axis=1).max() > 1e-2 * scale
        # transforms of bones outside the subtree stay the identity
        T = rig.transforms(angles)
        np.testing.assert_allclose(T[~sub][..., :3], np.broadcast_to(np.eye(3), T[~sub][..., :3].shape), atol=0)


def test_descendants_of_the_branch_root_are_all_bones(branch_rig):
    parents = branch_rig.parents
    assert parents.tolist() == [-1, 0, 0]
    assert kin.descendants(parents, 0).all()
    assert kin.descendants(parents, 1).tolist() == [False, True, False]


def test_child_joint_follows_parent_rotation(branch_rig):
    """Posed joints against an independent chain computation with scipy rotations."""
    rig = branch_rig
    J = rig.joints  # 0 base, 1 branching point, 2 arm tip, 3 post top; bones 0->1, 1->2, 1->3
    rng = np.random.default_rng(4)
    for _ in range(5):
        a = rng.uniform(-1.0, 1.0, (3, 3))
        R0, R1, R2 = (_scipy_matrix(x) for x in a)
        j1 = J[0] + R0 @ (J[1] - J[0])
        j2 = j1 + R0 @ R1 @ (J[2] - J[1])
        j3 = j1 + R0 @ R2 @ (J[3] - J[1])
        expected = np.array([J[0], j1, j2, j3])
        np.testing.assert_allclose(rig.posed_joints(a), expected, rtol=0, atol=1e-12)
    # the parent alone: the child's joint turns about the parent's root
    a = np.zeros((3, 3))
    a[0] = [0.2, -0.4, 0.7]
    R = _scipy_matrix(a[0])
    np.testing.assert_allclose(rig.posed_joints(a)[2], J[0] + R @ (J[2] - J[0]), atol=1e-12)


def test_transforms_fix_each_bones_root_joint(tpose_rig):
    rig = tpose_rig
    a = np.random.default_rng(5).uniform(-1, 1, (rig.bone_count, 3))
    T = rig.transforms(a)
    P = rig.posed_joints(a)
    roots = rig.bones[:, 0]
    # every bone maps its own root joint to the posed position of that joint
    np.testing.assert_allclose(kin.transform_points(T, rig.joints[roots]), P[roots], atol=1e-12)
    A = T[..., :3]
    np.testing.assert_allclose(np.linalg.det(A), 1.0, atol=1e-12)


def test_bones_in_any_order_give_the_same_pose(tpose_rig):
    rig = tpose_rig
    rng = np.random.default_rng(6)
    angles = rng.uniform(-0.7, 0.7, (3, rig.bone_count, 3))
    expected = rig.pose(angles)
    for perm in (np.arange(rig.bone_count)[::-1], rng.permutation(rig.bone_count)):
        bones = rig.bones[perm]
        new = np.argsort(perm)  # old bone index -> new
        parents = np.where(rig.parents[perm] < 0, -1, new[np.maximum(rig.parents[perm], 0)])
        T = kin.forward_kinematics(rig.joints, bones, angles[:, perm], parents, kin.topological_order(parents),
                                   rig.pivots[perm])
        posed = kin.skin(kin.lbs_matrix(rig.vertices, rig.weights[:, perm]), T)
        np.testing.assert_allclose(posed, expected, rtol=0, atol=1e-10)
        np.testing.assert_allclose(kin.posed_joints(rig.joints, bones, T), rig.posed_joints(angles), atol=1e-10)


def test_forest_of_two_root_bones():
    joints = np.array([[0.0, 0, 0], [0, 1, 0], [5, 0, 0], [5, 2, 0], [5, 3, 0]])
    bones = np.array([[2, 3], [0, 1], [3, 4]])  # tree {0 -> 2}, tree {1}
    parents = kin.bone_parents(bones)
    assert parents.tolist() == [-1, -1, 0]
    assert kin.descendants(parents, 0).tolist() == [True, False, True]
    a = np.zeros((3, 3))
    a[0] = [0, 0, np.pi / 2]  # first tree turns about (5, 0, 0)
    a[1] = [np.pi / 2, 0, 0]  # second tree turns about the origin
    P = kin.posed_joints(joints, bones, kin.forward_kinematics(joints, bones, a))
    np.testing.assert_allclose(P, [[0, 0, 0], [0, 0, 1], [5, 0, 0], [3, 0, 0], [2, 0, 0]], atol=1e-12)


def test_cycle_is_rejected():
    with pytest.raises(ValueError, match="cycle"):
        kin.topological_order(kin.bone_parents(np.array([[0, 1], [1, 0]])))


def test_wrong_number_of_angles_is_rejected(branch_rig):
    with pytest.raises(ValueError, match="skeleton has 3"):
        branch_rig.transforms(np.zeros((4, 3)))


# ---------------------------------------------------------------------- skinning


def test_one_rigid_transform_moves_the_mesh_rigidly(branch_rig):
    rig = branch_rig
    R = _scipy_matrix([0.4, -1.1, 2.0])
    t = np.array([3.0, -7.0, 11.0])
    T = np.broadcast_to(np.hstack([R, t[:, None]]), (rig.bone_count, 3, 4))
    posed = kin.skin(rig.lbs, T)
    np.testing.assert_allclose(pdist(posed), pdist(rig.vertices), rtol=0, atol=1e-9)
    np.testing.assert_allclose(posed, rig.vertices @ R.T + t, atol=1e-9)
    # the same through the angles: only the root bone turns
    a = rig.rest_angles()
    a[0] = [0.4, -1.1, 2.0]
    np.testing.assert_allclose(pdist(rig.pose(a)), pdist(rig.vertices), rtol=0, atol=1e-9)


def test_skin_equals_explicit_sum(branch_rig):
    rig = branch_rig
    a = np.random.default_rng(7).uniform(-1, 1, (rig.bone_count, 3))
    T = rig.transforms(a)
    V, W = rig.vertices, rig.weights
    expected = np.zeros_like(V)
    for i in range(len(V)):
        for j in range(rig.bone_count):
            expected[i] += W[i, j] * (T[j, :, :3] @ V[i] + T[j, :, 3])
    np.testing.assert_allclose(kin.skin(kin.lbs_matrix(V, W), T), expected, rtol=0, atol=1e-10)
    np.testing.assert_allclose(rig.pose(a), expected, rtol=0, atol=1e-10)


def test_lbs_matrix_matches_igl_layout():
    rng = np.random.default_rng(8)
    for d in (2, 3):
        V = rng.random((7, d))
        W = rng.random((7, 4))
        M = kin.lbs_matrix(V, W)
        assert M.shape == (7, 4 * (d + 1))
        np.testing.assert_allclose(M, igl.lbs_matrix(V, W), rtol=0, atol=1e-15)
        # explicit definition M[i, j*(d+1)+c] = w_ij [v_i, 1]_c
        Vh = np.column_stack([V, np.ones(7)])
        for j in range(4):
            for c in range(d + 1):
                np.testing.assert_allclose(M[:, j * (d + 1) + c], W[:, j] * Vh[:, c])


def test_batch_of_200_poses_equals_single_poses(tpose_rig):
    rig = tpose_rig
    angles = np.random.default_rng(9).uniform(-np.pi / 3, np.pi / 3, (200, rig.bone_count, 3))
    batch = rig.pose(angles)
    assert batch.shape == (200, len(rig.vertices), 3)
    single = np.stack([rig.pose(a) for a in angles])
    np.testing.assert_allclose(batch, single, rtol=0, atol=1e-12)
    joints = rig.posed_joints(angles)
    np.testing.assert_allclose(joints, np.stack([rig.posed_joints(a) for a in angles]), rtol=0, atol=1e-12)


def test_public_api_names():
    assert sl.forward_kinematics is kin.forward_kinematics
    assert sl.lbs_matrix is kin.lbs_matrix
    assert sl.skin is kin.skin


# ---------------------------------------------------------------- re-rooting
# a chain of joints 0-1-2-3 with a branch 1-4: bones 0 (0-1), 1 (1-2), 2 (2-3), 3 (1-4)
CHAIN_J = np.array([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 3.0, 0.0], [1.0, 1.0, 0.0]])
CHAIN_B = np.array([[0, 1], [1, 2], [2, 3], [1, 4]])


def test_reroot_reverses_the_path_to_the_old_root():
    parents = kin.bone_parents(CHAIN_B)
    np.testing.assert_array_equal(parents, [-1, 0, 1, 0])
    new, pivots = kin.reroot(CHAIN_B, parents, 2)
    np.testing.assert_array_equal(new, [1, 2, -1, 0])
    np.testing.assert_array_equal(pivots, [1, 2, 2, 1])  # reversed bones turn about their tips
    same, pivots0 = kin.reroot(CHAIN_B, parents, 0)  # re-rooting at the root changes nothing
    np.testing.assert_array_equal(same, parents)
    np.testing.assert_array_equal(pivots0, CHAIN_B[:, 0])


def test_rerooted_kinematics_turns_the_chain_about_the_anchor():
    """With bone 2 as the root, turning bone 1 swings bones 0 and 3 about joint 2; bone 2 stays."""
    parents, pivots = kin.reroot(CHAIN_B, kin.bone_parents(CHAIN_B), 2)
    order = kin.topological_order(parents)
    A = np.zeros((4, 3))
    A[1] = [0.0, 0.0, np.pi / 2]
    T = kin.forward_kinematics(CHAIN_J, CHAIN_B, A, parents, order, pivots)
    np.testing.assert_allclose(T[2], np.hstack([np.eye(3), np.zeros((3, 1))]), atol=1e-15)
    J = kin.posed_joints(CHAIN_J, CHAIN_B, T)
    np.testing.assert_allclose(J[2:4], CHAIN_J[2:4], atol=1e-12)  # the anchor bone's joints stay
    # joint 1 swings a quarter turn about joint 2 (0, 2, 0): from (0, 1, 0) to (1, 2, 0)
    np.testing.assert_allclose(J[1], [1.0, 2.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(J[0] - J[1]), 1.0, atol=1e-12)  # bones keep their length
    # every bone moves its joints as a rigid body: each shared joint agrees between the bones that hold it
    for b in range(4):
        for c in range(4):
            for joint in set(CHAIN_B[b]) & set(CHAIN_B[c]):
                p = CHAIN_J[joint]
                np.testing.assert_allclose(T[b, :, :3] @ p + T[b, :, 3], T[c, :, :3] @ p + T[c, :, 3], atol=1e-12)


def test_connecting_bones_is_the_chain_between_the_contacts():
    np.testing.assert_array_equal(kin.connecting_bones(CHAIN_B, np.array([0, 0, 1, 1], bool)), [0, 1, 1, 1])
    np.testing.assert_array_equal(kin.connecting_bones(CHAIN_B, np.array([1, 0, 0, 0], bool)), [1, 0, 0, 0])
    np.testing.assert_array_equal(kin.connecting_bones(CHAIN_B, np.array([1, 0, 0, 1], bool)), [1, 0, 0, 1])
    # two separate skeletons (a forest) are not joined
    forest = np.array([[0, 1], [2, 3]])
    np.testing.assert_array_equal(kin.connecting_bones(forest, np.array([1, 1], bool)), [1, 1])


def test_sparse_skinning_equals_the_dense_product():
    """The compiled loop over a sparse LBS matrix gives ``M @ T`` (batch and single pose)."""
    from scipy.sparse import csr_matrix

    from supportless.base.kinematics import lbs_matrix, lbs_operator, skin, stack_transforms

    rng = np.random.default_rng(5)
    V = rng.normal(size=(50, 3))
    W = rng.random((50, 6)) * (rng.random((50, 6)) < 0.15)
    W[W.sum(1) == 0, 0] = 1.0
    W /= W.sum(1, keepdims=True)
    T = rng.normal(size=(7, 6, 3, 4))
    dense = lbs_matrix(V, W)
    assert hasattr(lbs_operator(V, W), "indptr")  # few non-zeros: kept sparse
    expected = np.matmul(dense, stack_transforms(T))
    np.testing.assert_allclose(skin(csr_matrix(dense), T), expected, atol=1e-12)
    np.testing.assert_allclose(skin(csr_matrix(dense), T[3]), expected[3], atol=1e-12)
    np.testing.assert_allclose(skin(dense, T), expected, atol=1e-12)


def test_sparse_skinning_of_a_planar_rig_equals_the_dense_product():
    from scipy.sparse import csr_matrix

    from supportless.base.kinematics import lbs_matrix, skin, stack_transforms

    rng = np.random.default_rng(6)
    V = rng.normal(size=(30, 2))
    W = rng.random((30, 4))
    W /= W.sum(1, keepdims=True)
    T = rng.normal(size=(5, 4, 2, 3))
    dense = lbs_matrix(V, W)
    out = skin(csr_matrix(dense), T)
    assert out.shape == (5, 30, 2)
    np.testing.assert_allclose(out, np.matmul(dense, stack_transforms(T)), atol=1e-12)


def test_pruned_weights_drop_the_tail_and_keep_each_row_sum():
    from supportless.base.kinematics import pruned_weights

    W = np.array([[0.7, 0.29995, 5e-5, 0.0], [0.25, 0.25, 0.25, 0.25], [5e-5, 5e-5, 5e-5, 5e-5]])
    P = pruned_weights(W, 1e-4)
    np.testing.assert_allclose(P.sum(1), W.sum(1), rtol=1e-15)
    np.testing.assert_allclose(P[0], [0.7 / 0.99995 * 1.0, 0.29995 / 0.99995, 0.0, 0.0], rtol=1e-15)
    np.testing.assert_array_equal(P[1], W[1])  # nothing below the floor: unchanged
    np.testing.assert_allclose(P[2], W[2])  # every entry is the row's largest: kept, none left empty


def test_the_search_skinning_moves_no_vertex_further_than_its_stated_bound():
    """SEARCH_WEIGHT_FLOOR's promise (0.012 % of the height measured; asserted with room: 0.03 %), and rest stays rest."""
    from supportless.apps.bench import random_poses
    from supportless.search.objective import Objective

    for name in ("tpose", "hand", "dragon"):
        rig = sl.load_rig(f"demo:{name}")
        objective = Objective(rig)
        A = random_poses(rig, 40, max_angle=40.0, seed=2)
        T = rig.transforms(A)
        moved = np.linalg.norm(kin.skin(objective.search_lbs, T) - kin.skin(rig.lbs, T), axis=-1).max()
        assert 0 < moved < 3e-4 * np.ptp(rig.vertices @ rig.up), name
        np.testing.assert_allclose(kin.skin(objective.search_lbs, rig.transforms(rig.rest_angles())), rig.vertices,
                                   atol=1e-12)


def test_skinning_by_bone_blocks_adds_exactly_as_a_loop_over_the_nonzeros():
    """The compiled kernel runs over (vertex, bone) blocks; its sums are the plain loop's, bit for bit."""
    from scipy.sparse import csr_matrix

    from supportless.base.kinematics import bone_blocks, lbs_matrix, skin, stack_transforms

    rng = np.random.default_rng(7)
    V = rng.normal(size=(40, 3))
    V[::5, 1] = 0.0  # a zero coordinate: a non-zero fewer in the CSR, a 0 in its block
    W = rng.random((40, 7)) * (rng.random((40, 7)) < 0.4)
    W[W.sum(1) == 0, 2] = 1.0
    W /= W.sum(1, keepdims=True)
    M = csr_matrix(lbs_matrix(V, W))
    start, bone, coef = bone_blocks(M, 4)
    assert np.all(np.diff(start) == np.count_nonzero(W, axis=1)) and coef.shape == (start[-1], 4)
    transforms = rng.normal(size=(3, 7, 3, 4))
    T = stack_transforms(transforms)
    got = skin(M, transforms)
    for p in range(3):
        for i in range(40):
            acc = [0.0, 0.0, 0.0]
            for k in range(M.indptr[i], M.indptr[i + 1]):
                for c in range(3):
                    acc[c] += float(M.data[k]) * float(T[p, M.indices[k], c])
            assert got[p, i].tolist() == acc
