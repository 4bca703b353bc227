"""The compiled pose kernels against the numpy expressions they replace, and an analytic chain."""

import numpy as np
import pytest

from supportless.base.chain import chain_transforms3, euler_matrices
from supportless.base.kinematics import kinematic_tree, topological_order


def numpy_euler(a):
    """``Rx(a0) @ Ry(a1) @ Rz(a2)`` as three numpy matrix products, (q, 3, 3)."""
    c, s = np.cos(a), np.sin(a)
    one, zero = np.ones(len(a)), np.zeros(len(a))
    Rx = np.stack([one, zero, zero, zero, c[:, 0], -s[:, 0], zero, s[:, 0], c[:, 0]], 1).reshape(-1, 3, 3)
    Ry = np.stack([c[:, 1], zero, s[:, 1], zero, one, zero, -s[:, 1], zero, c[:, 1]], 1).reshape(-1, 3, 3)
    Rz = np.stack([c[:, 2], -s[:, 2], zero, s[:, 2], c[:, 2], zero, zero, zero, one], 1).reshape(-1, 3, 3)
    return Rx @ Ry @ Rz


def numpy_chain(dQ, roots, parents, order):
    """The chain composed by numpy, pose batch at a time (P, m, 3, 4)."""
    P, m = dQ.shape[:2]
    Q, t = np.empty((P, m, 3, 3)), np.empty((P, m, 3))
    for b in order:
        r, p = roots[b], parents[b]
        if p < 0:
            Q[:, b], t[:, b] = dQ[:, b], r - dQ[:, b] @ r
        else:
            Q[:, b] = Q[:, p] @ dQ[:, b]
            t[:, b] = Q[:, p] @ r + t[:, p] - Q[:, b] @ r
    return np.concatenate([Q, t[..., None]], axis=-1)


@pytest.mark.parametrize("scale", [0.01, 1.0, 10.0])
def test_euler_matrices_are_the_three_axis_rotations(scale):
    a = np.random.default_rng(0).normal(0.0, scale, (500, 3))
    R = euler_matrices(a)
    np.testing.assert_allclose(R, numpy_euler(a), rtol=0, atol=1e-14)
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-14)


def random_tree(rng, m):
    """A random skeleton of ``m`` bones: joints (m + 1, 3), bones (m, 2), each bone starting at an earlier tip."""
    joints = rng.normal(size=(m + 1, 3))
    bones = np.array([[rng.integers(0, b + 1), b + 1] for b in range(m)], np.int64)
    return joints, bones


@pytest.mark.parametrize("seed", range(4))
def test_chain_is_numpys_composition_and_keeps_every_joint_one_point(seed):
    rng = np.random.default_rng(seed)
    joints, bones = random_tree(rng, 9)
    parents, pivots = kinematic_tree(bones)
    order = topological_order(parents)
    dQ = euler_matrices(rng.normal(0.0, 1.0, (7 * 9, 3))).reshape(7, 9, 3, 3)
    roots = np.ascontiguousarray(joints[pivots])
    T = chain_transforms3(dQ, roots, parents, order)
    np.testing.assert_allclose(T, numpy_chain(dQ, roots, parents, order), rtol=1e-13, atol=1e-13)
    for b, p in enumerate(parents):
        if p >= 0:  # the joint the child turns about goes where its parent takes it
            np.testing.assert_allclose(T[:, b, :, :3] @ roots[b] + T[:, b, :, 3],
                                       T[:, p, :, :3] @ roots[b] + T[:, p, :, 3], atol=1e-12)


def test_two_quarter_turns_down_a_chain():
    # bone 0 from the origin along x, bone 1 on from (1, 0, 0); each turns 90 degrees about z
    dQ = euler_matrices(np.array([[0.0, 0.0, np.pi / 2]] * 2)).reshape(1, 2, 3, 3)
    roots = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    T = chain_transforms3(dQ, roots, np.array([-1, 0]), np.array([0, 1]))
    tip = T[0, 1, :, :3] @ np.array([2.0, 0.0, 0.0]) + T[0, 1, :, 3]  # the second bone's tip, (2, 0, 0) at rest
    np.testing.assert_allclose(tip, [-1.0, 1.0, 0.0], atol=1e-15)
