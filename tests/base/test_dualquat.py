"""Dual quaternion skinning against independent computations, and against LBS on a bent cylinder's volume."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from supportless.base import kinematics as kin
from supportless.base.dualquat import (
    dual_quaternion_skin,
    dual_quaternion_to_transforms,
    matrix_to_quaternion,
    transforms_to_dual_quaternions,
)
from supportless.base.geometry import signed_volume


def _rigid(rng, shape, scale=1.0):
    """Random rigid transforms (shape..., 3, 4) from scipy's uniform rotations."""
    R = Rotation.random(int(np.prod(shape)), random_state=rng).as_matrix().reshape(shape + (3, 3))
    t = scale * rng.normal(size=shape + (3, 1))
    return np.concatenate([R, t], axis=-1)


def _weights(rng, n, m, zeros=0.5):
    W = rng.random((n, m)) * (rng.random((n, m)) > zeros)
    W[np.arange(n), rng.integers(0, m, n)] += 0.1
    return W / W.sum(axis=1, keepdims=True)


def _hamilton(a, b):
    """Quaternion product (w, x, y, z) by the left-multiplication matrix of ``a``."""
    w, x, y, z = a
    L = np.array([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]])
    return L @ b


def _reference_skin(V, W, T):
    """Kavan et al.'s algorithm vertex by vertex, quaternions from scipy, the pivot the heaviest bone."""
    xyzw = Rotation.from_matrix(T[:, :, :3]).as_quat()
    qr = np.column_stack([xyzw[:, 3], xyzw[:, :3]])
    qd = np.array([0.5 * _hamilton(np.r_[0.0, T[j, :, 3]], qr[j]) for j in range(len(T))])
    out = np.empty_like(V)
    for i, v in enumerate(V):
        k = np.argmax(W[i])
        br, bd = np.zeros(4), np.zeros(4)
        for j in range(len(T)):
            s = 1.0 if qr[j] @ qr[k] >= 0 else -1.0
            br += s * W[i, j] * qr[j]
            bd += s * W[i, j] * qd[j]
        norm = np.linalg.norm(br)
        br, bd = br / norm, bd / norm
        conj = br * np.array([1, -1, -1, -1])
        turned = _hamilton(_hamilton(br, np.r_[0.0, v]), conj)[1:]
        out[i] = turned + 2 * _hamilton(bd, conj)[1:]
    return out


def test_quaternions_match_scipy_and_round_trip():
    rng = np.random.default_rng(0)
    T = _rigid(rng, (200,), 3.0)
    q = matrix_to_quaternion(T[..., :3])
    xyzw = Rotation.from_matrix(T[..., :3]).as_quat()
    ref = np.column_stack([xyzw[:, 3], xyzw[:, :3]])
    ref[ref[:, 0] < 0] *= -1
    np.testing.assert_allclose(q, ref, rtol=0, atol=1e-14)
    half_turns = np.array([np.diag([1.0, -1, -1]), np.diag([-1.0, 1, -1]), np.diag([-1.0, -1, 1])])
    np.testing.assert_allclose(np.abs(matrix_to_quaternion(half_turns)), np.eye(4)[1:], atol=0)
    dq = transforms_to_dual_quaternions(T)
    assert dq.shape == (200, 8)
    np.testing.assert_allclose(np.linalg.norm(dq[:, :4], axis=1), 1, atol=1e-15)
    np.testing.assert_allclose(np.sum(dq[:, :4] * dq[:, 4:], axis=1), 0, atol=1e-14)  # unit: q_r . q_d = 0
    np.testing.assert_allclose(dual_quaternion_to_transforms(dq), T, rtol=0, atol=1e-13)


def test_a_scale_or_a_mirror_is_refused():
    T = np.zeros((2, 3, 4))
    T[:, :, :3] = np.eye(3)
    T[1, :, :3] *= 1.1
    with pytest.raises(ValueError, match="no rotation"):
        transforms_to_dual_quaternions(T)
    T[1, :, :3] = np.diag([1.0, 1, -1])
    with pytest.raises(ValueError, match="det"):
        dual_quaternion_skin(np.zeros((1, 3)), np.ones((1, 2)), T)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_blend_matches_a_vertex_by_vertex_reference(seed):
    rng = np.random.default_rng(seed)
    V, W = rng.normal(size=(60, 3)), _weights(rng, 60, 5)
    T = _rigid(rng, (5,), 2.0)  # random rotations: many pairs of bones more than 180 degrees apart
    np.testing.assert_allclose(dual_quaternion_skin(V, W, T), _reference_skin(V, W, T), rtol=0, atol=1e-12)


def test_one_bone_or_one_motion_for_all_moves_exactly_as_the_affine():
    rng = np.random.default_rng(2)
    n, m = 500, 6
    V = 10 * rng.normal(size=(n, 3))
    T = _rigid(rng, (4, m), 5.0)
    bone = rng.integers(0, m, n)
    W = np.zeros((n, m))
    W[np.arange(n), bone] = 1.0
    posed = dual_quaternion_skin(V, W, T)
    expected = np.einsum("pnij,nj->pni", T[:, bone][..., :3], V) + T[:, bone][..., 3]
    np.testing.assert_allclose(posed, expected, rtol=0, atol=1e-12)
    same = np.repeat(T[:, :1], m, axis=1)  # every bone the first one's motion, any weights
    posed = dual_quaternion_skin(V, _weights(rng, n, m), same)
    np.testing.assert_allclose(posed, V @ same[:, 0, :, :3].transpose(0, 2, 1) + same[:, :1, :, 3], rtol=0,
                               atol=1e-12)


def test_identity_transforms_leave_the_vertices_and_a_batch_is_its_single_poses():
    rng = np.random.default_rng(3)
    V, W = rng.normal(size=(300, 3)), _weights(rng, 300, 7)
    identity = np.zeros((7, 3, 4))
    identity[:, :, :3] = np.eye(3)
    np.testing.assert_allclose(dual_quaternion_skin(V, W, identity), V, rtol=0, atol=1e-15)
    T = _rigid(rng, (9, 7))
    batch = dual_quaternion_skin(V, W, T)
    assert batch.shape == (9, 300, 3)
    for p in range(9):
        np.testing.assert_array_equal(dual_quaternion_skin(V, W, T[p]), batch[p])


def test_sparse_weights_and_a_planar_rig():
    from scipy.sparse import csr_matrix

    rng = np.random.default_rng(4)
    V, W = rng.normal(size=(200, 3)), _weights(rng, 200, 12, zeros=0.9)
    T = _rigid(rng, (3, 12))
    dense = dual_quaternion_skin(V, W, T)
    np.testing.assert_allclose(dual_quaternion_skin(V, csr_matrix(W), T), dense, rtol=0, atol=1e-14)
    # a planar rig turns about z: the same as the 3D rig of its transforms
    angles = rng.uniform(-np.pi, np.pi, (3, 12))
    T2 = np.concatenate([kin.planar_rotation(angles), rng.normal(size=(3, 12, 2, 1))], axis=-1)
    T3 = np.zeros((3, 12, 3, 4))
    T3[..., :2, :2], T3[..., :2, 3], T3[..., 2, 2] = T2[..., :2], T2[..., 2], 1.0
    V2 = V[:, :2]
    flat = dual_quaternion_skin(V2, W, T2)
    assert flat.shape == (3, 200, 2)
    np.testing.assert_allclose(flat, dual_quaternion_skin(np.column_stack([V2, np.zeros(200)]), W, T3)[..., :2],
                               rtol=0, atol=1e-14)


def test_a_vertex_without_weight_stays():
    W = np.array([[0.0, 0.0], [0.0, 1.0]])
    T = np.zeros((2, 3, 4))
    T[:, :, :3] = np.eye(3)
    T[:, :, 3] = 1.0
    np.testing.assert_array_equal(dual_quaternion_skin(np.ones((2, 3)), W, T), [[1, 1, 1], [2, 2, 2]])


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), flip=st.integers(0, 4))
def test_a_rigid_motion_after_the_bones_moves_the_skin_rigidly(seed, flip):
    """DQS(G o T_j) = G o DQS(T_j) for any rigid G, and the sign of a bone's dual quaternion does not count."""
    rng = np.random.default_rng(seed)
    V, W = rng.normal(size=(40, 3)), _weights(rng, 40, 5)
    T = _rigid(rng, (5,), 3.0)
    G = _rigid(rng, (), 3.0)
    GT = np.concatenate([G[:, :3] @ T[..., :3], (G[:, :3] @ T[..., 3:]) + G[:, 3:]], axis=-1)
    posed = dual_quaternion_skin(V, W, T)
    np.testing.assert_allclose(dual_quaternion_skin(V, W, GT), posed @ G[:, :3].T + G[:, 3], rtol=0, atol=1e-11)
    dq = transforms_to_dual_quaternions(T)
    dq[flip] *= -1  # the same motion from the other hemisphere
    np.testing.assert_allclose(dual_quaternion_to_transforms(dq), T, rtol=0, atol=1e-13)


def _cylinder(radius=0.25, half_length=1.0, around=64, sections=80):
    """A closed cylinder along x (outward triangles): rings of ``around`` vertices, a fan at each end."""
    x = np.linspace(-half_length, half_length, sections + 1)
    a = 2 * np.pi * np.arange(around) / around
    ring = np.column_stack([np.zeros(around), radius * np.cos(a), radius * np.sin(a)])
    V = np.concatenate([ring + [xi, 0, 0] for xi in x] + [[[-half_length, 0, 0], [half_length, 0, 0]]])
    i = np.arange(around)
    j = (i + 1) % around
    F = []
    for s in range(sections):
        lo, hi = s * around, (s + 1) * around
        F += [np.column_stack([lo + i, lo + j, hi + j]), np.column_stack([lo + i, hi + j, hi + i])]
    first, last = len(V) - 2, len(V) - 1
    F += [np.column_stack([np.full(around, first), j, i]),  # the x = -L cap, facing -x
          np.column_stack([np.full(around, last), sections * around + i, sections * around + j])]
    return V, np.concatenate(F).astype(np.int64)


def test_a_bent_cylinder_keeps_its_volume_better_than_under_lbs():
    V, F = _cylinder()
    rest = signed_volume(V, F)
    assert rest == pytest.approx(np.pi * 0.25**2 * 2 * (np.sin(2 * np.pi / 64) * 64 / (2 * np.pi)), rel=1e-12)
    # two bones along x meeting at the origin; the weight goes from one to the other over |x| < 0.3
    s = np.clip((V[:, 0] + 0.3) / 0.6, 0, 1)
    w1 = s * s * (3 - 2 * s)
    W = np.column_stack([1 - w1, w1])
    joints, bones = np.array([[-1.0, 0, 0], [0, 0, 0], [1, 0, 0]]), np.array([[0, 1], [1, 2]])
    angles = np.zeros((2, 3))
    angles[1, 2] = np.pi / 2  # bend the second bone 90 degrees about z at the middle joint
    T = kin.forward_kinematics(joints, bones, angles)
    lbs = signed_volume(kin.skin(kin.lbs_matrix(V, W), T), F) - rest
    dqs = signed_volume(dual_quaternion_skin(V, W, T), F) - rest
    message = f"rest volume {rest:.6f}: LBS changes it by {lbs:+.6f} ({lbs / rest:+.2%}), DQS by {dqs:+.6f} " \
              f"({dqs / rest:+.2%})"
    print(message)
    assert abs(dqs) < abs(lbs), message
    assert lbs < 0, message  # LBS collapses the inside of the bend


def test_the_blend_takes_the_short_way_between_bones_far_apart():
    """Bones turned +120 and -120 degrees about z are 120 degrees apart the short way (through 180), 240 the
    long way (through 0). Their quaternions, both with w >= 0, have a negative dot: without the antipodality
    fix the even blend would be the identity; with it the vertex turns half a turn."""
    T = np.zeros((2, 3, 4))
    T[:, :, :3] = Rotation.from_euler("z", [[120], [-120]], degrees=True).as_matrix()
    V, W = np.array([[1.0, 0, 0]]), np.array([[0.5, 0.5]])
    for pivot in (0, 1):
        np.testing.assert_allclose(dual_quaternion_skin(V, W, T, pivots=np.array([pivot])), [[-1, 0, 0]],
                                   atol=1e-15)
    with pytest.raises(ValueError, match="pivots"):
        dual_quaternion_skin(V, W, T, pivots=np.array([2]))
