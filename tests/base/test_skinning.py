"""Skinning a dense surface from its weights (WeightBlocks) against the skinning matrix."""

import numpy as np
import pytest

from supportless.base import kinematics as kin
from supportless.base.skinning import WeightBlocks, weight_blocks


def _case(seed, n=3000, m=7, zeros=0.5):
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(n, 3))
    W = rng.random((n, m)) * (rng.random((n, m)) > zeros)  # about half the weights 0, as a skin's
    W[np.arange(n), rng.integers(0, m, n)] += 0.1  # no row all 0
    W /= W.sum(axis=1, keepdims=True)
    A = rng.normal(size=(5, m, 3, 3))
    t = rng.normal(size=(5, m, 3, 1))
    return V, W, np.concatenate([A, t], axis=-1)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_weight_blocks_pose_to_the_bits_of_the_sparse_matrix_and_as_the_dense_one(seed):
    from scipy.sparse import csr_matrix

    V, W, T = _case(seed)
    blocks = weight_blocks(V, W, chunk=700)  # several chunks
    M = kin.lbs_matrix(V, W)
    sparse = kin.skin(csr_matrix(M), T)
    streamed = kin.skin(blocks, T)
    np.testing.assert_array_equal(streamed, sparse)
    np.testing.assert_allclose(streamed, kin.skin(M, T), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(kin.skin(blocks, T[0]), streamed[0])  # one pose, (n, 3)
    assert blocks.shape == M.shape and blocks.nbytes < M.nbytes / 2


def test_a_large_surface_is_skinned_without_its_matrix(monkeypatch):
    V, W, T = _case(3)
    assert not isinstance(kin.lbs_operator(V, W), WeightBlocks)
    monkeypatch.setattr(kin, "LBS_MATRIX_BYTES", V.shape[0] * W.shape[1] * 4 * 8 - 1)
    op = kin.lbs_operator(V, W)
    assert isinstance(op, WeightBlocks)
    np.testing.assert_allclose(kin.skin(op, T), kin.skin(kin.lbs_matrix(V, W), T), rtol=0, atol=1e-12)
    assert not isinstance(kin.lbs_operator(V[:, :2], W), WeightBlocks)  # a planar rig keeps its matrix


def test_dense_skinning_is_the_matrix_product_and_keeps_one_transpose_per_live_matrix():
    import gc

    from supportless.base import skinning

    rng = np.random.default_rng(3)
    T = rng.normal(size=(5, 8, 3))
    first = rng.normal(size=(40, 8))
    for _ in range(2):  # the second call uses the kept transpose
        np.testing.assert_allclose(skinning.skin_dense(first, T), np.matmul(first, T), rtol=1e-13, atol=1e-13)
    assert skinning._TRANSPOSES[id(first)][1].shape == (8, 40)
    key = id(first)
    del first
    gc.collect()
    assert key not in skinning._TRANSPOSES  # dropped with its matrix
    for _ in range(3):  # new matrices (perhaps at a freed address) are never given an old transpose
        M = rng.normal(size=(40, 8))
        np.testing.assert_allclose(skinning.skin_dense(M, T), np.matmul(M, T), rtol=1e-13, atol=1e-13)
        del M
