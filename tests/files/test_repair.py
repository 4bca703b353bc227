"""Degenerate triangles removed without changing the surface's shape (issue 18, item 5)."""

import numpy as np
import pytest
import trimesh

import supportless as sl
from supportless.base.geometry import signed_volume
from supportless.files.meshes import check_closed_surface, edge_counts
from supportless.files.repair import degenerate_faces, repair_degenerate_faces


def _sphere():
    m = trimesh.creation.icosphere(subdivisions=2, radius=10.0)
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


def _cap(V, F, f=0):
    """Move corner 2 of face ``f`` onto the middle of its opposite edge: a zero-area cap."""
    V = V.copy()
    V[F[f, 2]] = 0.5 * (V[F[f, 0]] + V[F[f, 1]])
    return V


def test_a_clean_surface_comes_back_unchanged():
    V, F = _sphere()
    V2, F2, n = repair_degenerate_faces(V, F)
    assert n == 0 and V2 is V and np.array_equal(F2, F)


def test_a_cap_is_flipped_away_and_no_vertex_moves():
    V, F = _sphere()
    Vc = _cap(V, F)
    assert degenerate_faces(Vc, F).tolist() == [0]
    V2, F2, n = repair_degenerate_faces(Vc, F)
    assert n == 1 and np.array_equal(V2, Vc) and len(F2) == len(F)
    assert len(degenerate_faces(V2, F2)) == 0
    check_closed_surface(F2)  # closed, manifold, consistently oriented
    # flipping an edge between coplanar triangles keeps the enclosed volume (the cap had no area)
    assert signed_volume(V2, F2) == pytest.approx(signed_volume(Vc, F), rel=1e-12)


def test_a_needle_is_collapsed_and_two_triangles_go():
    V, F = _sphere()
    a, b = F[5, 0], F[5, 1]
    Vn = V.copy()
    Vn[b] = Vn[a] + 1e-9  # two corners (nearly) at one place
    assert set(degenerate_faces(Vn, F)) >= {5}
    V2, F2, n = repair_degenerate_faces(Vn, F)
    assert n == 2 and len(V2) == len(V) - 1 and len(F2) == len(F) - 2
    check_closed_surface(F2)
    assert len(degenerate_faces(V2, F2)) == 0
    _, counts = edge_counts(F2)
    assert np.all(counts == 2)


def test_thin_but_real_triangles_are_kept():
    # a long, thin triangle (1e-4 of the size thick) is a real feature, not a degenerate one
    V, F = _sphere()
    Vt = V.copy()
    f = F[0]
    mid = 0.5 * (V[f[0]] + V[f[1]])
    Vt[f[2]] = mid + 1e-3 * (V[f[2]] - mid) / np.linalg.norm(V[f[2]] - mid)
    assert 0 not in degenerate_faces(Vt, F)


def test_a_rig_is_prepared_from_a_surface_with_a_degenerate_triangle_and_says_so(tmp_path):
    V, F, J, B = sl.demo_figure("branch")[:4]
    V = _cap(np.asarray(V, float), np.asarray(F, np.int64), f=20)
    path = tmp_path / "sliver.obj"
    sl.write_mesh(path, V, F)
    sl.write_tgf(tmp_path / "sliver.tgf", J, B)
    rig = sl.load_rig(path, cache=False)
    assert len(rig.faces) == len(F) and len(degenerate_faces(rig.vertices, rig.faces)) == 0
    assert any("1 degenerate triangle" in w for w in rig.info["warnings"])
