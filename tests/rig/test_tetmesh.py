"""Volume meshes (:mod:`supportless.rig.tetmesh`): a failure is one error, with nothing printed or left behind; fTetWild takes surfaces TetGen cannot."""

from __future__ import annotations

import numpy as np
import pytest
from meshes import box

from supportless.base.errors import InputError
from supportless.rig.tetmesh import ftetwild_volume, tetrahedralize_surface, tetrahedralize_with_skeleton


def crossing_boxes():
    """Two boxes through each other as one surface: TetGen refuses it."""
    V1, F1 = box((0, 0, 0), (2, 1, 1))
    V2, F2 = box((0.5, -0.5, 0.25), (1.5, 1.5, 0.75))
    return np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])


def test_a_failing_tetgen_says_one_line_and_leaves_no_files(tmp_path, monkeypatch, capfd):
    monkeypatch.chdir(tmp_path)
    V, F = crossing_boxes()
    J = np.array([[0.2, 0.5, 0.5], [1.8, 0.5, 0.5]])
    with pytest.raises(InputError, match="TetGen failed.*could not be tetrahedralised"):
        tetrahedralize_with_skeleton(V, F, J, np.array([[0, 1]]))
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert list(tmp_path.iterdir()) == []


def test_a_closed_surface_is_meshed_keeping_its_vertices_first(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    V, F = box((0, 0, 0), (2, 1, 1))
    TV, TT, conforming = tetrahedralize_surface(V, F)
    assert conforming
    np.testing.assert_array_equal(TV[: len(V)], V)
    a, b, c, d = (TV[TT[:, i]] for i in range(4))
    volume = np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))).sum() / 6
    np.testing.assert_allclose(volume, 2.0)
    assert list(tmp_path.iterdir()) == []


def tet_volumes(TV, TT):
    a, b, c, d = (TV[TT[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6


def test_ftetwild_meshes_crossing_shells_as_their_union(tmp_path, monkeypatch):
    """Box 2x1x1 and box 1x2x0.5 crossing it: the union's volume is 2 + 1 - 0.5 = 2.5."""
    monkeypatch.chdir(tmp_path)
    TV, TT = ftetwild_volume(*crossing_boxes())
    vol = tet_volumes(TV, TT)
    assert np.all(vol > 0)
    np.testing.assert_allclose(vol.sum(), 2.5, rtol=0.03)
    assert list(tmp_path.iterdir()) == []


def test_a_surface_that_cuts_itself_still_gets_a_volume_mesh_with_its_vertices_first():
    V, F = crossing_boxes()
    TV, TT, conforming = tetrahedralize_surface(V, F)
    assert not conforming
    np.testing.assert_array_equal(TV[: len(V)], V)
    assert TT.min() >= len(V)  # the surface's vertices are in no tetrahedron
    vol = tet_volumes(TV, TT)
    assert np.all(vol > 0)
    np.testing.assert_allclose(vol.sum(), 2.5, rtol=0.03)


@pytest.mark.slow
def test_a_surface_that_crosses_itself_is_remade_for_tetgen_with_its_skeleton(monkeypatch):
    """OBJ + TGF of two boxes pushed through each other: TetGen refuses, the winding-number surface is meshed."""
    from supportless.files import printbody

    monkeypatch.setattr(printbody, "WINDING_CELLS", 60)  # the remaking is the subject, not the grid's fineness
    from supportless.copyleft.cgal import intersecting_face_pairs
    from supportless.files.meshes import check_closed_surface
    from supportless.rig.tetmesh import tetrahedralize_with_skeleton_or_remake

    V, F = crossing_boxes()
    J = np.array([[0.2, 0.5, 0.5], [1.8, 0.5, 0.5]])
    Vs, Fs, TV, TT, note = tetrahedralize_with_skeleton_or_remake(V, F, J, np.array([[0, 1]]))
    assert note is not None and "crosses itself" in note and "winding number" in note
    check_closed_surface(Fs)
    assert intersecting_face_pairs(Vs, Fs) == 0
    np.testing.assert_array_equal(TV[: len(Vs)], Vs)
    np.testing.assert_allclose(tet_volumes(TV, TT).sum(), 2.5, rtol=0.02)
    # a clean surface goes through untouched
    Vb, Fb = box((0, 0, 0), (2, 1, 1))
    same = tetrahedralize_with_skeleton_or_remake(Vb, Fb, J, np.array([[0, 1]]))
    assert same[0] is Vb and same[4] is None


@pytest.mark.slow
def test_prepare_rig_of_a_crossing_surface_says_so_and_is_clean(monkeypatch):
    import supportless as sl
    from supportless.files import printbody

    monkeypatch.setattr(printbody, "WINDING_CELLS", 60)  # the remaking is the subject, not the grid's fineness
    from supportless.copyleft.cgal import intersecting_face_pairs

    V, F = crossing_boxes()
    rig = sl.prepare_rig(V, F, np.array([[0.2, 0.5, 0.5], [1.8, 0.5, 0.5]]), np.array([[0, 1]]), up="z")
    assert any("winding number" in w for w in rig.info["warnings"])
    assert intersecting_face_pairs(rig.vertices, rig.faces) == 0
