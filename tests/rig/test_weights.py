"""Bounded biharmonic weights (:mod:`supportless.rig.weights`) on a bar with two bones."""

from __future__ import annotations

import numpy as np
from meshes import box

from supportless.rig.tetmesh import tetrahedralize_with_skeleton
from supportless.rig.weights import compute_weights


def test_weights_are_a_partition_of_unity_fixed_on_the_bones_and_change_along_the_bar():
    V, F = box((0, 0, 0), (4, 1, 1))
    J = np.array([[0.2, 0.5, 0.5], [2.0, 0.5, 0.5], [3.8, 0.5, 0.5]])
    B = np.array([[0, 1], [1, 2]])
    TV, TT = tetrahedralize_with_skeleton(V, F, J, B, samples_per_bone=8)
    W = compute_weights(TV, TT, J, B)
    assert W.shape == (len(TV), 2)
    assert W.min() >= 0.0 and W.max() <= 1.0
    np.testing.assert_allclose(W.sum(1), 1.0, atol=1e-9)
    # on the first bone's inner samples the first bone has it all, on the second's the second
    on_first = (np.abs(TV[:, 1] - 0.5) < 1e-9) & (np.abs(TV[:, 2] - 0.5) < 1e-9) & (TV[:, 0] > 0.3) & (TV[:, 0] < 1.8)
    on_second = (np.abs(TV[:, 1] - 0.5) < 1e-9) & (np.abs(TV[:, 2] - 0.5) < 1e-9) & (TV[:, 0] > 2.2) & (TV[:, 0] < 3.7)
    assert on_first.any() and on_second.any()
    np.testing.assert_allclose(W[on_first, 0], 1.0, atol=1e-6)
    np.testing.assert_allclose(W[on_second, 1], 1.0, atol=1e-6)
    # the surface ends belong to their bones
    assert W[TV[:, 0] < 0.01, 0].min() > 0.9
    assert W[TV[:, 0] > 3.99, 1].min() > 0.9


def test_one_bone_has_all_the_weight():
    V, F = box((0, 0, 0), (2, 1, 1))
    J = np.array([[0.2, 0.5, 0.5], [1.8, 0.5, 0.5]])
    B = np.array([[0, 1]])
    TV, TT = tetrahedralize_with_skeleton(V, F, J, B, samples_per_bone=4)
    np.testing.assert_array_equal(compute_weights(TV, TT, J, B), np.ones((len(TV), 1)))


def test_a_part_with_no_bone_follows_the_nearest_bone_and_is_named():
    """The bar with two bones and a separate cube beyond its second end (issue 18: bbw used to fail)."""
    bar_V, bar_F = box((0, 0, 0), (4, 1, 1))
    cube_V, cube_F = box((6, 0, 0), (7, 1, 1))
    V, F = np.vstack([bar_V, cube_V]), np.vstack([bar_F, cube_F + len(bar_V)])
    J = np.array([[0.2, 0.5, 0.5], [2.0, 0.5, 0.5], [3.8, 0.5, 0.5]])
    B = np.array([[0, 1], [1, 2]])
    TV, TT = tetrahedralize_with_skeleton(V, F, J, B, samples_per_bone=8)
    notes = []
    W = compute_weights(TV, TT, J, B, notes=notes)
    cube = TV[:, 0] > 5.0
    np.testing.assert_array_equal(W[cube], np.tile([0.0, 1.0], (cube.sum(), 1)))  # bone 2 is the nearest
    np.testing.assert_allclose(W.sum(1), 1.0, atol=1e-9)
    assert len(notes) == 1 and "no bone in it" in notes[0] and "follows bone 2" in notes[0]
    # the bar's weights are those of the bar alone
    bar_TV, bar_TT = tetrahedralize_with_skeleton(bar_V, bar_F, J, B, samples_per_bone=8)
    alone = compute_weights(bar_TV, bar_TT, J, B)
    assert W[~cube][TV[~cube, 0] < 0.01, 0].min() > 0.9 and alone[bar_TV[:, 0] < 0.01, 0].min() > 0.9


def test_given_weights_are_checked_and_named():
    import pytest

    from supportless.base.errors import InputError
    from supportless.rig.weights import check_weights

    W = np.array([[0.25, 0.75], [1.0, 0.0], [0.5, 0.5]])
    np.testing.assert_array_equal(check_weights(W), W)  # good rows come back as given
    notes = []
    np.testing.assert_allclose(check_weights(W * [[2.0], [1.0], [1.0]], notes), W)
    assert notes == ["1 rows of the given weights did not sum to 1 and were scaled to 1"]
    for bad, words in ((np.array([[np.nan, 1.0]]), "vertex 0 on bone 1 is nan"),
                       (np.array([[1.0, 0.0], [1.5, -0.5]]), "vertex 1 on bone 2 is -0.5"),
                       (np.array([[0.0, 0.0]]), "vertex 0 has no weight on any bone")):
        with pytest.raises(InputError, match=words):
            check_weights(bad)


def test_a_crash_in_the_weight_solver_is_one_line_not_a_dead_process(monkeypatch):
    """A stand-in solver that aborts (as a native library does on bad input): the caller gets one InputError."""
    import os

    import pytest

    import supportless as sl
    import supportless.rig.weights as weights
    from supportless.base.errors import InputError

    def aborts(*args):
        os.abort()

    monkeypatch.setattr(weights, "_bbw", aborts)
    V, F, J, B = sl.demo_figure("branch")[:4]
    TV, TT = tetrahedralize_with_skeleton(V, F, J, B)[:2]
    with pytest.raises(InputError) as err:
        weights.compute_weights(TV, TT, J, B)
    message = str(err.value)
    assert "skinning weights" in message and "crashed" in message and "SIGABRT" in message and "\n" not in message
