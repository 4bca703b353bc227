"""Written bodies read back closed: touching shells moved apart by a hair."""

import numpy as np
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


@given(st.integers(0, 2**32 - 1), st.integers(1, 60), st.integers(1, 4))
@settings(max_examples=40, deadline=None)
def test_row_groups_are_numpys_unique_rows(seed, rows, distinct):
    """Rows drawn from a few values (many repeats): the same groups, first rows and counts as ``np.unique``."""
    from supportless.base.geometry import row_groups

    rng = np.random.default_rng(seed)
    X = rng.integers(0, distinct, (rows, 3)).astype(np.float32) * np.float32(0.1)
    first, inverse, counts = row_groups(X)
    _, want_first, want_inverse, want_counts = np.unique(X, axis=0, return_index=True, return_inverse=True,
                                                         return_counts=True)
    assert np.array_equal(first, want_first)
    assert np.array_equal(inverse, want_inverse.ravel())
    assert np.array_equal(counts, want_counts)
