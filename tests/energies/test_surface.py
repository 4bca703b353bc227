"""Tests of the surface helpers (supportless.energies.surface) and of ``up`` given by name."""

import numpy as np
import pytest
from meshes import box, cells_mesh

from supportless.base.errors import InputError
from supportless.energies.intersection import self_intersection_volume
from supportless.energies.overhang import overhang_energy, projected_risky_area, risky_area, risky_faces
from supportless.energies.support import support_volume
from supportless.energies.surface import (
    boundary_edges,
    frame_matrix,
    orientation_sign,
    plane_basis,
    prepare,
    signed_area2,
    signed_volume3,
    to_frame,
)

ENERGIES = [overhang_energy, risky_faces, risky_area, projected_risky_area, self_intersection_volume,
            support_volume]


def tumbled_boxes():
    """Two overlapping boxes in one face list, in two tumbled poses: (2, 16, 3), (24, 3).

    Tumbled so that every axis direction sees overhangs, overlaps and supports.
    """
    V1, F1 = box([0, 0, 0], [2, 1, 1])
    V2, F2 = box([1, 0.2, 0.5], [2.5, 0.8, 2])
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    poses = []
    for a, b in ((0.3, 0.3), (0.5, 0.4)):
        Rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
        poses.append(V @ (Ry @ Rx).T)
    return np.stack(poses), F


def overlapping_squares():
    """Two overlapping unit-cell squares (2D), turned by 0.3 rad: (n, 2), (f, 3)."""
    V1, F1 = cells_mesh([(0, 0), (1, 0), (0, 1), (1, 1)])
    V2, F2 = cells_mesh([(1, 1), (2, 1), (1, 2), (2, 2)])
    c, s = np.cos(0.3), np.sin(0.3)
    return np.vstack([V1, V2]) @ np.array([[c, -s], [s, c]]).T, np.vstack([F1, F2 + len(V1)])


AXES3 = {"x": [1, 0, 0], "y": [0, 1, 0], "z": [0, 0, 1], "-x": [-1, 0, 0], "-y": [0, -1, 0], "-z": [0, 0, -1],
         "+z": [0, 0, 1], " Y ": [0, 1, 0], "0,1,0": [0, 1, 0], "0 0 -1": [0, 0, -1], "1,2,2": [1, 2, 2],
         "1, -1, 0.5": [1, -1, 0.5]}
AXES2 = {"x": [1, 0], "y": [0, 1], "-x": [-1, 0], "-y": [0, -1], "0,1": [0, 1], "0,-1,0": [0, -1]}


@pytest.mark.parametrize("name", AXES3)
def test_up_names_are_the_vectors_3d(name):
    V, F = tumbled_boxes()
    vec = np.array(AXES3[name], float)
    np.testing.assert_array_equal(prepare(V, F, name)[2], vec / np.linalg.norm(vec))
    for fn in ENERGIES:
        np.testing.assert_array_equal(fn(V, F, name), fn(V, F, vec), err_msg=fn.__name__)
        np.testing.assert_array_equal(fn(V[0], F, name), fn(V[0], F, vec), err_msg=fn.__name__)


@pytest.mark.parametrize("name", AXES2)
def test_up_names_are_the_vectors_2d(name):
    V, F = overlapping_squares()
    vec = np.array(AXES2[name], float)
    for fn in ENERGIES:
        np.testing.assert_array_equal(fn(V, F, name), fn(V, F, vec), err_msg=fn.__name__)


def test_the_energies_are_not_vacuous_along_the_axes():
    V, F = tumbled_boxes()
    for name in ("x", "y", "z", "-x", "-y", "-z"):
        assert np.all(overhang_energy(V, F, name) > 0)
        assert np.all(support_volume(V, F, name) > 0)
        assert np.all(self_intersection_volume(V, F, name) > 0)
    V2, F2 = overlapping_squares()
    assert self_intersection_volume(V2, F2, "y") > 0 and support_volume(V2, F2, "-x") > 0


@pytest.mark.parametrize("fn", ENERGIES)
def test_bad_up_raises(fn):
    V, F = tumbled_boxes()
    for bad in ("up", "w", "", "0,0,0", "1,2,3,4", "x,y,z"):
        with pytest.raises(InputError, match="up direction"):
            fn(V, F, bad)
    # a planar figure's up lies in its plane
    V2, F2 = overlapping_squares()
    with pytest.raises(InputError, match="plane"):
        fn(V2, F2, "z")
    # vectors: as before, a ValueError for a zero, infinite or wrong-length one
    for bad in ([0.0, 0.0, 0.0], [0.0, np.inf, 1.0], [0.0, 1.0]):
        with pytest.raises(ValueError, match="up must be"):
            fn(V, F, bad)


def test_prepare_batches_and_normalises():
    V, F = box()
    Vb, Fb, up, single = prepare(V.tolist(), F.astype(np.int32), [0.0, 0.0, 2.0])
    assert Vb.shape == (1, 8, 3) and Vb.dtype == np.float64 and Vb.flags.c_contiguous and single
    assert Fb.dtype == np.int64 and Fb.flags.c_contiguous
    np.testing.assert_array_equal(up, [0.0, 0.0, 1.0])
    assert not prepare(np.stack([V, V]), F, "z")[3]
    with pytest.raises(ValueError, match="vertices"):
        prepare(np.zeros((2, 3, 4)), F, "z")


# ------------------------------------------------------------- orientation


def test_signed_volume_and_area_and_orientation():
    V, F = box([0, 0, 0], [1, 2, 3])
    assert signed_volume3(V, F) == 6.0
    assert signed_volume3(V, F[:, ::-1]) == -6.0
    V2, F2 = cells_mesh([(0, 0), (1, 0), (2, 0), (1, 1)])
    assert signed_area2(V2, F2) == 4.0
    assert signed_area2(V2, F2[:, ::-1]) == -4.0
    for backend in ("fast", "numpy"):
        np.testing.assert_array_equal(orientation_sign(np.stack([V, V]), F, backend), [1.0, 1.0])
        np.testing.assert_array_equal(orientation_sign(V[None], F[:, ::-1], backend), [-1.0])
        np.testing.assert_array_equal(orientation_sign(np.stack([V2, -V2[:, ::-1]]), F2, backend), [1.0, -1.0])


def test_boundary_edges_square():
    V, F = cells_mesh([(0, 0)])
    E = boundary_edges(F)
    assert E.shape == (4, 2) and E.dtype == np.int64
    # counter-clockwise: the region is on the left of every edge
    c = V.mean(axis=0)
    for a, b in E:
        t = V[b] - V[a]
        assert t[0] * (c - V[a])[1] - t[1] * (c - V[a])[0] > 0
    # clockwise input is re-oriented when vertices are given
    E2 = boundary_edges(F[:, ::-1], V)
    for a, b in E2:
        t = V[b] - V[a]
        assert t[0] * (c - V[a])[1] - t[1] * (c - V[a])[0] > 0
    # interior diagonal excluded
    assert not any({a, b} == {0, 2} for a, b in E)


def test_boundary_edges_of_a_grid_form_its_outline():
    V, F = cells_mesh([(0, 0), (1, 0), (2, 0), (1, 1)])
    E = boundary_edges(F)
    assert len(E) == 10  # perimeter of the T in unit edges
    # a closed loop: every vertex on it starts one edge and ends one
    np.testing.assert_array_equal(np.sort(E[:, 0]), np.sort(E[:, 1]))
    assert np.sum(np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1)) == 10.0


# ------------------------------------------------------------------- frame


@pytest.mark.parametrize("up", [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0.3, -0.5, 0.8], [0, 1], [-0.6, 0.8]])
def test_frame_is_right_handed_with_up_last(up):
    up = np.asarray(up, float) / np.linalg.norm(up)
    d = len(up)
    B = plane_basis(up)
    assert B.shape == (d - 1, d)
    R = frame_matrix(up)
    np.testing.assert_array_equal(R[-1], up)
    np.testing.assert_allclose(R @ R.T, np.eye(d), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-15)
    V = np.random.default_rng(0).normal(size=(2, 5, d))
    np.testing.assert_allclose(to_frame(V, up), V @ R.T, atol=1e-15)
