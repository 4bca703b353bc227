"""The fast (numba) and the plain numpy backends of the energies agree.

Both compute the same quantities with the same crossing rules, so they agree
to round-off: every raw term to a relative 1e-9, with an absolute floor of
1e-12 of the model's volume (the sums run in a different order). The poses
are random rotations of the free bones, up to 30 degrees (the search's
bound) and up to 75 degrees so that some poses self-intersect.
"""

from __future__ import annotations

import numpy as np
import pytest

import supportless as sl
from supportless.apps.bench import random_poses
from supportless.energies.intersection import self_intersection_volume
from supportless.energies.overhang import overhang_energy, risky_area, risky_faces
from supportless.energies.support import support_volume

#: Agreement of the two backends: relative, and absolute as a fraction of the volume.
RTOL = 1e-9
ATOL_VOLUME = 1e-12


def _poses(rig, count, seed):
    return np.concatenate([random_poses(rig, count, 30.0, seed), random_poses(rig, count, 75.0, seed + 1)])


def _compare(rig, A, overhang_model="prism"):
    fast = sl.Objective(rig, overhang_model=overhang_model, backend="fast")
    slow = sl.Objective(rig, overhang_model=overhang_model, backend="numpy")
    rf, rs = fast.raw_terms(A), slow.raw_terms(A)
    atol = ATOL_VOLUME * fast.volume
    for key in ("arap", "overhang", "intersection"):
        np.testing.assert_allclose(rf[key], rs[key], rtol=RTOL, atol=atol, err_msg=key)
    np.testing.assert_allclose(fast(A), slow(A), rtol=RTOL, atol=1e-12)
    return rf


@pytest.mark.slow
@pytest.mark.parametrize("overhang_model", ["prism", "column"])
def test_branch_backends_agree(branch_rig, overhang_model):
    raw = _compare(branch_rig, _poses(branch_rig, 6, 0), overhang_model)
    assert np.all(raw["overhang"] > 0)


@pytest.mark.slow
def test_tpose_backends_agree(tpose_rig):
    raw = _compare(tpose_rig, _poses(tpose_rig, 5, 10))
    assert np.any(raw["intersection"] > 0), "no self-intersecting pose: the comparison would be vacuous"


@pytest.mark.slow
def test_tpose_single_pose_and_column(tpose_rig):
    A = _poses(tpose_rig, 2, 20)
    _compare(tpose_rig, A[0])
    _compare(tpose_rig, A, overhang_model="column")


@pytest.mark.slow
def test_planar_figure_backends_agree(rig_cache_dir):
    rig = sl.load_rig("demo:woody2d", up="y", cache_dir=rig_cache_dir)
    _compare(rig, _poses(rig, 4, 30))
    _compare(rig, _poses(rig, 2, 40), overhang_model="column")


@pytest.mark.slow
def test_bunny_backends_agree(bunny_rig):
    raw = _compare(bunny_rig, _poses(bunny_rig, 3, 50))
    assert np.any(raw["intersection"] > 0), "no self-intersecting pose: the comparison would be vacuous"


def test_energy_functions_accept_backend(tpose_rig):
    V = tpose_rig.pose(_poses(tpose_rig, 2, 60))
    F, up = tpose_rig.faces, tpose_rig.up
    for fn in (overhang_energy, risky_area, self_intersection_volume, support_volume):
        np.testing.assert_allclose(fn(V, F, up, backend="fast"), fn(V, F, up, backend="numpy"), rtol=RTOL,
                                   atol=1e-15)
    np.testing.assert_array_equal(risky_faces(V, F, up, backend="fast"), risky_faces(V, F, up, backend="numpy"))


def test_unknown_backend_raises(branch_rig):
    with pytest.raises(ValueError, match="backend"):
        sl.Objective(branch_rig, backend="cuda")
    with pytest.raises(ValueError, match="backend"):
        overhang_energy(branch_rig.vertices, branch_rig.faces, branch_rig.up, backend="cuda")
    with pytest.raises(ValueError, match="backend"):
        self_intersection_volume(branch_rig.vertices, branch_rig.faces, branch_rig.up, backend="cuda")


@pytest.mark.slow
def test_short_search_same_on_both_backends(branch_rig):
    kw = dict(particles=12, iterations=3, seed=3, exact_intersections=False)
    fast = sl.optimize(branch_rig, objective=sl.Objective(branch_rig, backend="fast"), **kw)
    slow = sl.optimize(branch_rig, objective=sl.Objective(branch_rig, backend="numpy"), **kw)
    np.testing.assert_allclose(fast.angles, slow.angles, atol=1e-12)
    assert fast.value == pytest.approx(slow.value, rel=1e-9)


def test_fast_ray_grid_overflow_falls_back(monkeypatch):
    """A pose whose crossings overflow the fast kernel's buffers is recomputed by the general kernel."""
    from supportless.energies import _grid_fast, _grid_reference

    # 4 stacked, overlapping boxes: 8 crossings per ray
    F1 = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
                   [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]])
    boxes = []
    for k in range(4):
        lo, hi = np.array([0.0, 0.1 * k, 1.2 * k]), np.array([1.0, 1.0, 1.2 * k + 1.5])
        boxes.append(np.array([[(hi if (c >> a) & 1 else lo)[a] for a in range(3)] for c in range(8)]))
    V = np.stack([np.concatenate(boxes), np.concatenate(boxes) * 1.1])
    F = np.concatenate([F1 + 8 * k for k in range(4)])
    up = np.array([0.0, 0.2, 1.0])
    want_sup = support_volume(V, F, up, resolution=40, backend="numpy")
    want_int = self_intersection_volume(V, F, up, resolution=40, backend="numpy")
    calls = []
    general = _grid_reference.grid_batch

    def spy(*args):
        calls.append(len(args[0]))
        return general(*args)

    monkeypatch.setattr(_grid_reference, "grid_batch", spy)
    monkeypatch.setattr(_grid_fast, "_CROSSINGS_PER_PIXEL", 0)  # buffers of 1024 crossings: too small
    np.testing.assert_allclose(support_volume(V, F, up, resolution=40), want_sup, rtol=1e-12)
    np.testing.assert_allclose(self_intersection_volume(V, F, up, resolution=40), want_int, rtol=1e-12, atol=0)
    assert calls == [2, 2]
    assert np.all(want_sup > 0) and np.all(want_int > 0)
