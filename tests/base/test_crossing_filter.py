"""The floating-point filter in front of CGAL's exact self-intersection test: it never drops a crossing pair.

Checked against CGAL alone (``supportless.copyleft.cgal._cgal``, the whole surface at once) on surfaces with
corners on a small integer grid, where exact touching, shared planes and straight angles are the rule, on the
shared bunny posed at random, and on the cases each proof is for.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from supportless.base.crossing_filter import possibly_crossing_faces
from supportless.copyleft import cgal


def cgal_alone(V, F):
    """Every intersecting pair by one CGAL call on the whole surface, each pair (smaller, larger), sorted."""
    return cgal._normalised(cgal._cgal(np.asarray(V, np.float64), np.asarray(F, np.int64), False))


def filtered(V, F):
    return cgal._normalised(cgal._filtered(np.asarray(V, np.float64), np.asarray(F, np.int64), False))


def marked_pairs_hold_every_crossing(V, F):
    pairs = cgal_alone(V, F)
    maybe = possibly_crossing_faces(V, F)
    assert maybe[pairs.ravel()].all()  # both triangles of every crossing pair are left to the exact test
    np.testing.assert_array_equal(filtered(V, F), pairs)
    return pairs, maybe


@settings(max_examples=150, deadline=None)
@given(st.integers(4, 9).flatmap(lambda n: st.tuples(
    st.lists(st.tuples(*[st.integers(0, 3)] * 3), min_size=n, max_size=n),
    st.lists(st.tuples(*[st.integers(0, n - 1)] * 3), min_size=2, max_size=12))))
def test_the_filter_keeps_every_pair_cgal_finds_on_a_grid_of_corners(case):
    corners, triangles = case
    V = np.asarray(corners, np.float64) * 0.1  # a tenth: not exact in binary, the rounding the bound is for
    F = np.asarray([t for t in triangles if len(set(t)) == 3], np.int64).reshape(-1, 3)
    if len(F) < 2:
        return
    marked_pairs_hold_every_crossing(V, F)


def test_the_filter_keeps_every_pair_cgal_finds_on_a_posed_bunny(bunny_rig):
    rng = np.random.default_rng(0)
    seen = 0
    for spread in (0.0, 0.3, 0.6, 1.0, 1.5):
        for _ in range(3):
            V = bunny_rig.pose(rng.normal(0, spread, (bunny_rig.bone_count, 3)))
            pairs, maybe = marked_pairs_hold_every_crossing(V, bunny_rig.faces)
            seen += len(pairs)
            if spread == 0.0:
                assert not maybe.any()  # the closed rest surface: every pair proven apart, CGAL not asked
    assert seen > 100  # the wilder poses cross themselves


def tetra(V):
    return np.asarray(V, np.float64), np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def test_each_proof_on_its_case():
    # two triangles of one plane, sharing an edge: apart when on either side of it, overlapping when folded flat
    V = np.array([[0, 0, 0], [1, 0, 0], [0.3, 1, 0], [0.3, -1, 0], [0.6, 0.5, 0]], float)
    assert not possibly_crossing_faces(V, np.array([[0, 1, 2], [1, 0, 3]])).any()
    assert possibly_crossing_faces(V, np.array([[0, 1, 2], [1, 0, 4]])).all()
    # sharing a corner in one plane: straight angles at the corner (a subdivided flat patch) are apart
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [-1, 0, 0], [-0.5, -1, 0], [1, 0.2, 0], [0.2, 1, 0]], float)
    assert not possibly_crossing_faces(V, np.array([[0, 1, 2], [0, 3, 4]])).any()
    assert possibly_crossing_faces(V, np.array([[0, 1, 2], [0, 5, 6]])).all()  # the wedges overlap
    # sharing a corner, not in one plane: apart, and crossing through each other
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1], [0.2, 0.2, -1]], float)
    assert not possibly_crossing_faces(V, np.array([[0, 1, 2], [0, 3, 1]])).any()
    assert possibly_crossing_faces(V, np.array([[0, 1, 2], [0, 3, 4]])).all()
    # sharing nothing: a tetrahedron apart from another, touching it at a corner, and crossing it
    V, F = tetra([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    for shift in (2.0, 1.0, 0.25):  # apart, touching corner to corner (not a crossing to CGAL), crossing
        W, G = np.vstack([V, V + shift * np.array([1, 0, 0])]), np.vstack([F, F + 4])
        pairs, maybe = marked_pairs_hold_every_crossing(W, G)
        assert (len(pairs) > 0) == (shift < 1) and maybe.any() == (shift <= 1)
    # a triangle with no area, and two triangles on the same three corners: left to the exact test
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], float)
    assert possibly_crossing_faces(V, np.array([[0, 1, 2], [0, 1, 3]])).all()
    assert possibly_crossing_faces(V, np.array([[0, 1, 3], [3, 1, 0]])).all()


def test_a_grid_too_large_leaves_every_triangle_to_the_exact_test(monkeypatch):
    from supportless.base import crossing_filter

    V, F = tetra([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    W, G = np.vstack([V, V + [0.25, 0, 0], V + [3, 0, 0]]), np.vstack([F, F + 4, F + 8])
    maybe = possibly_crossing_faces(W, G)
    assert maybe[:8].any() and not maybe[8:].any()  # of the two tetrahedra that cross, not the third
    monkeypatch.setattr(crossing_filter, "MAX_ENTRIES_PER_FACE", 0)
    assert possibly_crossing_faces(W, G).all()
    marked_pairs_hold_every_crossing(W, G)


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="need"):
        possibly_crossing_faces(np.zeros((3, 2)), np.array([[0, 1, 2]]))
