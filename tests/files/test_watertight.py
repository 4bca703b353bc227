"""Written bodies read back closed: touching shells moved apart by a hair."""

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from supportless.files.watertight import HAIR, apart_by_a_hair, edge_counts, manifold_check


def _cubes_along_an_edge():
    """Two closed unit cubes that share one edge (positions equal, indices apart), as a union leaves them."""
    a = trimesh.creation.box([1, 1, 1])
    b = trimesh.creation.box([1, 1, 1])
    b.apply_translation([1, 1, 0])
    V = np.vstack([a.vertices, b.vertices])
    F = np.vstack([a.faces, b.faces + len(a.vertices)])
    return V, F


def test_shells_sharing_an_edge_read_back_with_four_triangles_on_it():
    V, F = _cubes_along_an_edge()
    assert np.all(edge_counts(F) == 2)  # by index: two closed cubes
    found = manifold_check(V, F)
    assert found == {"open_edges": 0, "shared_edges": 1, "closed": False}
    assert not trimesh.Trimesh(V, F).is_watertight  # as any reader welds them


def test_apart_by_a_hair_makes_every_edge_two_triangles_and_moves_only_the_shared_corners():
    V, F = _cubes_along_an_edge()
    W, moved = apart_by_a_hair(V, F)
    assert moved == 4  # two corners of each cube's shared edge
    assert manifold_check(W, F)["closed"]
    assert trimesh.Trimesh(W.astype(np.float32), F).is_watertight
    shift = np.linalg.norm(W - V, axis=1)
    assert np.count_nonzero(shift) == 4
    assert np.allclose(shift[shift > 0], HAIR * 2.0)  # the pair spans 2 units
    # each moved corner went into its own cube: the first cube's stay inside [-0.5, 0.5]^3
    first = W[: len(V) // 2]
    assert np.all(np.abs(first) <= 0.5 + 1e-12)


def test_a_closed_surface_and_a_seam_closed_only_by_position_are_left_as_they_are():
    box = trimesh.creation.box([1, 1, 1])
    W, moved = apart_by_a_hair(box.vertices, box.faces)
    assert moved == 0 and np.array_equal(W, box.vertices)
    # the same box with one corner split (a seam): open by index, closed once welded; moving it would open it
    V = np.vstack([box.vertices, box.vertices[:1]])
    F = box.faces.copy()
    F[np.flatnonzero((F == 0).any(axis=1))[0]] = np.where(F[np.flatnonzero((F == 0).any(axis=1))[0]] == 0, len(V) - 1,
                                                           F[np.flatnonzero((F == 0).any(axis=1))[0]])
    W, moved = apart_by_a_hair(V, F)
    assert moved == 0 and manifold_check(W, F)["closed"]


def _first_equal_rows(X):
    """Brute force: each row's first equal row (``==`` on every column: ``-0.0`` is ``0.0``, a NaN equals nothing)."""
    return np.array([next(j for j in range(i + 1) if np.all(X[j] == X[i]) or j == i) for i in range(len(X))])


def _check_groups(X, first, inverse, counts):
    assert np.array_equal(first[inverse], _first_equal_rows(X))
    assert np.all(np.diff(first) > 0) and first[0] == 0  # groups in the order of their first rows
    assert np.array_equal(counts, np.bincount(inverse, minlength=len(first)))


@given(st.integers(0, 2**32 - 1), st.integers(1, 60), st.integers(1, 4))
@settings(max_examples=40, deadline=None)
def test_row_groups_are_numpys_unique_rows(seed, rows, distinct):
    """Rows drawn from a few values (many repeats): the groups of ``np.unique``, renumbered by first row."""
    from supportless.base.geometry import row_groups

    rng = np.random.default_rng(seed)
    X = rng.integers(0, distinct, (rows, 3)).astype(np.float32) * np.float32(0.1)
    first, inverse, counts = row_groups(X)
    _, want_first, want_inverse, want_counts = np.unique(X, axis=0, return_index=True, return_inverse=True,
                                                         return_counts=True)
    assert np.array_equal(first[inverse], want_first[want_inverse.ravel()])
    assert sorted(counts) == sorted(want_counts)
    _check_groups(X, first, inverse, counts)


@pytest.mark.parametrize("kind", ["float32", "float64", "int64", "bool", "five columns"])
def test_row_groups_when_every_hash_collides(monkeypatch, kind):
    """With a hash that is the same for every row, the rows are still grouped by value (the collision path), as with
    the real hash."""
    import supportless.base.geometry as geometry

    rng = np.random.default_rng(3)
    X = rng.integers(0, 3, (200, 5 if kind == "five columns" else 3))
    X = X.astype(bool) if kind == "bool" else X.astype(np.float32 if kind == "five columns" else kind)
    real = geometry.row_groups(X)
    _check_groups(X, *real)
    monkeypatch.setattr(geometry, "_row_hash", lambda bits: np.zeros(len(bits), np.uint64))
    collided = geometry.row_groups(X)
    for a, b in zip(real, collided):
        assert np.array_equal(a, b)


def test_row_groups_signed_zero_and_nan():
    """``-0.0`` and ``0.0`` are one value; a NaN row equals no other row, even one with the same bits."""
    from supportless.base.geometry import row_groups

    X = np.array([[0.0, 1.0], [-0.0, 1.0], [np.nan, 1.0], [np.nan, 1.0], [0.0, -0.0], [1.0, 1.0]])
    first, inverse, counts = row_groups(X)
    assert list(first[inverse]) == [0, 0, 2, 3, 4, 5]
    _check_groups(X, first, inverse, counts)
    strings = np.array([["a", "b"], ["a", "b"], ["b", "a"]])  # no bits to hash: grouped by a lexsort
    assert list(row_groups(strings)[1]) == [0, 0, 1]
