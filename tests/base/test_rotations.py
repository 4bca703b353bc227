"""Quaternions of rotation matrices (:mod:`supportless.base.rotations`) against analytic cases and SciPy."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from supportless.base.rotations import matrix_to_quaternion


def _same_rotation(q, r):
    """q and r (..., 4) are the same rotation: equal up to sign."""
    return np.minimum(np.abs(q - r).max(axis=-1), np.abs(q + r).max(axis=-1))


def test_analytic_turns_about_each_axis_and_the_half_turns():
    for axis in range(3):
        for angle in (0.0, 0.3, np.pi / 2, 2.0, np.pi):  # pi: the trace is -1, a diagonal entry is chosen
            c, s = np.cos(angle), np.sin(angle)
            i, j = (axis + 1) % 3, (axis + 2) % 3
            R = np.eye(3)
            R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
            expected = np.zeros(4)
            expected[axis], expected[3] = np.sin(angle / 2), np.cos(angle / 2)
            assert _same_rotation(matrix_to_quaternion(R), expected) < 1e-15


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40))
def test_agrees_with_scipy_and_gives_back_the_matrix(seed, n):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3)) * rng.uniform(0.0, np.pi, (n, 1))
    v[: n // 4] *= 1e-7  # near the identity
    R = Rotation.from_rotvec(v).as_matrix()
    q = matrix_to_quaternion(R)
    assert np.abs(np.linalg.norm(q, axis=-1) - 1.0).max() < 1e-15
    assert _same_rotation(q, Rotation.from_matrix(R).as_quat()).max() < 1e-15
    assert np.abs(Rotation.from_quat(q).as_matrix() - R).max() < 1e-14


def test_a_batch_of_any_shape_is_its_single_calls():
    R = Rotation.random(24, random_state=4).as_matrix().reshape(2, 3, 4, 3, 3)
    q = matrix_to_quaternion(R)
    assert q.shape == (2, 3, 4, 4)
    for index in np.ndindex(2, 3, 4):
        assert np.array_equal(q[index], matrix_to_quaternion(R[index]))
