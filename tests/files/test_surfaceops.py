"""The closed-surface test and the flipped caps, against plain versions of the same rules."""

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from supportless.files.meshes import closes_up
from supportless.files.surfaceops import _flip_caps, _is_closed


def _closes_up_by_rows(E):
    """The rule as rows: no directed edge twice, every undirected edge twice (``np.unique(axis=0)``)."""
    if len(np.unique(E, axis=0)) != len(E):
        return False
    return bool(np.all(np.unique(np.sort(E, axis=1), axis=0, return_counts=True)[1] == 2))


def _flip_caps_by_dicts(V, F, tol, rounds=5):
    """The caps flipped with Python dictionaries of every edge, rebuilt each round."""
    F = F.copy()
    for _ in range(rounds):
        lengths, caps = [], []
        for f, corners in enumerate(V[F]):  # each triangle's sides and its height over the longest
            sides = [float(np.linalg.norm(corners[(i + 1) % 3] - corners[i])) for i in range(3)]
            twice_area = float(np.linalg.norm(np.cross(corners[1] - corners[0], corners[2] - corners[0])))
            lengths.append(sides)
            if twice_area / max(max(sides), 1e-300) < tol:
                caps.append(f)
        if not caps:
            break
        owner = {}
        for f, (x, y, z) in enumerate(F):
            owner[(x, y)], owner[(y, z)], owner[(z, x)] = f, f, f
        edges = {tuple(sorted(e)) for e in owner}
        touched = set()
        for f in caps:
            if f in touched:
                continue
            k = int(np.argmax(lengths[f]))
            p, q, r = (int(v) for v in np.roll(F[f], -k))
            g = owner.get((q, p))
            if g is None or g in touched:
                continue
            d = int(next(v for v in F[g] if v not in (p, q)))
            if tuple(sorted((r, d))) in edges or r == d:
                continue
            F[f] = (p, d, r)
            F[g] = (d, q, r)
            edges.add(tuple(sorted((r, d))))
            touched.update((f, g))
    return F


def _capped_sphere(seed, caps, subdivisions=3):
    """An icosphere with ``caps`` triangles flattened: a corner moved to the middle of its opposite edge."""
    rng = np.random.default_rng(seed)
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    V, F = m.vertices.copy(), m.faces.astype(np.int64)
    for f in rng.choice(len(F), caps, replace=False):
        a, b, c = F[f]
        V[c] = 0.5 * (V[a] + V[b]) + 1e-7 * rng.normal(size=3)
    return V, F


@pytest.mark.parametrize("seed, caps", [(0, 1), (1, 12), (2, 40), (3, 150)])
def test_caps_are_flipped_as_by_dictionaries(seed, caps):
    V, F = _capped_sphere(seed, caps)
    expected = _flip_caps_by_dicts(V, F, 1e-4)
    assert (expected != F).any(), "the case must flip something"
    np.testing.assert_array_equal(_flip_caps(V, F, 1e-4), expected)


def test_a_cap_across_a_repeated_edge_takes_its_last_triangle():
    # the edge (1, 0) is listed by two triangles (a non-manifold soup): both versions take the last one
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 1e-9, 0], [0.5, -1, 0], [0.5, -1, 1]])
    F = np.array([[0, 1, 2], [1, 0, 3], [1, 0, 4]], np.int64)
    np.testing.assert_array_equal(_flip_caps(V, F, 1e-6), _flip_caps_by_dicts(V, F, 1e-6))
    flipped = _flip_caps(V, F, 1e-6)
    np.testing.assert_array_equal(flipped, [[0, 4, 2], [1, 0, 3], [4, 1, 2]])  # with the last: its corner 4


def test_no_cap_changes_nothing():
    V, F = _capped_sphere(0, 0)
    np.testing.assert_array_equal(_flip_caps(V, F, 1e-4), F)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["closed", "drop", "repeat", "flip", "soup"]))
def test_closes_up_is_the_rule_by_rows(seed, change):
    rng = np.random.default_rng(seed)
    F = trimesh.creation.icosphere(subdivisions=1).faces.astype(np.int64)
    if change == "drop":
        F = np.delete(F, rng.integers(len(F)), axis=0)
    elif change == "repeat":
        F = np.r_[F, F[rng.integers(len(F))][None]]
    elif change == "flip":
        i = rng.integers(len(F))
        F[i] = F[i, ::-1]
    elif change == "soup":
        F = rng.integers(0, 8, (rng.integers(1, 12), 3))
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    assert closes_up(E) == _closes_up_by_rows(E) == _is_closed(F)
    if change == "closed":
        assert closes_up(E)
    elif change in ("drop", "repeat", "flip"):
        assert not closes_up(E)
