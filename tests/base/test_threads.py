"""A kernel's loop split over threads (:mod:`supportless.base.threads`): every item once, the same bits as one
thread, errors raised to the caller, and a pool that survives a fork."""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st
from scipy.sparse import csr_matrix

from supportless.base import threads
from supportless.base.closest import nearest_other_face
from supportless.base.crossing_filter import possibly_crossing_faces
from supportless.base.kinematics import lbs_matrix, skin, weight_blocks
from supportless.energies import _grid_fast, arap, footprint, overhang, surface
from supportless.rig import balance


@given(st.integers(0, 500), st.integers(1, 16))
def test_ranges_cover_every_item_once_in_order_in_near_equal_parts(n, parts):
    got = threads.ranges(n, parts)
    assert len(got) == min(parts, n)
    assert [i for lo, hi in got for i in range(lo, hi)] == list(range(n))
    sizes = [hi - lo for lo, hi in got]
    assert not sizes or max(sizes) - min(sizes) <= 1


def test_split_runs_each_range_once_on_several_threads():
    seen, idents, lock = [], set(), threading.Lock()
    barrier = threading.Barrier(3, timeout=30)  # all three ranges run at once, or this times out

    def call(lo, hi, t):
        barrier.wait()
        with lock:
            seen.append((lo, hi, t))
            idents.add(threading.get_ident())

    threads.split(call, 10, threads=3)
    assert sorted(seen) == [(0, 3, 0), (3, 6, 1), (6, 10, 2)]
    assert len(idents) == 3 and threading.get_ident() in idents  # the last range in the calling thread


@pytest.mark.parametrize("failing", [0, 1])
def test_an_error_in_any_range_reaches_the_caller(failing):
    done = []

    def call(lo, hi, t):
        if t == failing:
            raise ValueError(f"range {t}")
        done.append(t)

    with pytest.raises(ValueError, match=f"range {failing}"):
        threads.split(call, 4, threads=2)
    assert done == [1 - failing]  # the other range ran to its end


def test_over_passes_the_arguments_then_the_range():
    seen = []
    threads.over(lambda a, b, lo, hi: seen.append((a, b, lo, hi)), 5, "x", 7)
    assert sorted(seen) == [("x", 7, lo, hi) for lo, hi in threads.ranges(5, threads.thread_count())]


def test_no_items_no_call_and_one_thread_runs_here():
    threads.split(lambda lo, hi, t: pytest.fail("called"), 0)
    idents = []
    threads.split(lambda lo, hi, t: idents.append((lo, hi, t, threading.get_ident())), 5, threads=1)
    assert idents == [(0, 5, 0, threading.get_ident())]


def test_a_forked_child_gets_a_pool_of_its_own():
    threads.split(lambda lo, hi, t: None, 4, threads=2)  # the parent's pool exists
    pid = os.fork()
    if pid == 0:  # the child: the parent's pool threads do not exist here
        out = []
        try:
            threads.split(lambda lo, hi, t: out.append(t), 4, threads=2)
            os._exit(0 if sorted(out) == [0, 1] else 1)
        except BaseException:  # noqa: BLE001 - any failure is the child's exit code
            os._exit(2)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0


@pytest.fixture
def poses():
    """A closed surface (an icosphere of 320 triangles) in 7 random poses: (P, n, 3) float64 and (f, 3) int64."""
    sphere = trimesh.creation.icosphere(2)
    rng = np.random.default_rng(3)
    V = sphere.vertices[None] * rng.uniform(0.5, 2.0, (7, 1, 3)) + rng.normal(0, 0.05, (7, len(sphere.vertices), 3))
    return np.ascontiguousarray(V), np.ascontiguousarray(sphere.faces, np.int64)


def test_every_split_kernel_gives_one_threads_bits_on_several(poses, monkeypatch):
    """Each pose (point, triangle, bucket) is computed by the same code whichever thread takes it."""
    V, F = poses
    rng = np.random.default_rng(4)
    up = np.tile([0.0, 0.0, 1.0], (len(V), 1))
    W = rng.random((V.shape[1], 2)) * (rng.random((V.shape[1], 2)) < 0.7)
    M = lbs_matrix(V[0], W)
    T = rng.normal(size=(len(V), 2, 3, 4))
    S = rng.normal(size=(len(V), 3, 5, 3))
    groups = rng.integers(0, 3, len(F))

    def everything():
        return [
            _grid_fast.ray_grid3_fast(V, F, np.array([0.0, 0.0, 1.0]), 24, 0.5, True),
            overhang.overhang_energy(V, F, up),
            footprint._sections(V, F, up, np.full(len(V), 0.1)),
            surface._signed_measure(V, F),
            balance._lowest(V, np.arange(0, V.shape[1], 3), np.array([0.0, 0.0, 1.0])),
            arap._rotation_terms(S),
            skin(M, T),  # dense
            skin(csr_matrix(M), T),  # sparse: (vertex, bone) blocks
            skin(weight_blocks(V[0], W), T),  # weight blocks
            nearest_other_face(V[0][::5], groups[: len(V[0][::5])] % 3, V[0], F, groups),
            possibly_crossing_faces(np.concatenate([V[0], V[1]]), np.concatenate([F, F + V.shape[1]])),
        ]

    monkeypatch.setattr(threads, "thread_count", lambda: 1)
    one = everything()
    monkeypatch.setattr(threads, "thread_count", lambda: 3)
    several = everything()
    for a, b in zip(one, several, strict=True):
        for x, y in zip(a if isinstance(a, tuple) else (a,), b if isinstance(b, tuple) else (b,), strict=True):
            np.testing.assert_array_equal(x, y)
    assert several[-1].any()  # two spheres through each other: some triangles are left to the exact test


def test_one_blas_thread_holds_blas_to_one_thread_within_the_block_only():
    from threadpoolctl import threadpool_info

    def blas_threads():
        return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]

    before = blas_threads()
    assert before, "NumPy's BLAS is not seen by threadpoolctl"
    with threads.one_blas_thread():
        assert blas_threads() == [1] * len(before)
        a = np.arange(12.0).reshape(3, 4)
        assert np.array_equal(a @ a.T, np.einsum("ik,jk->ij", a, a))
    assert blas_threads() == before
