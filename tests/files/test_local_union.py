"""The self-union made where a surface crosses itself (supportless.files.crossings.local_union).

Each case is checked against CGAL's exact self-union of the whole surface (a second method): the same enclosed
volume, a closed surface free of crossings (also once stored in single precision), and every triangle away from
the crossings as it was.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

import supportless.files.crossings as crossings
import supportless.files.gridsurface as gridsurface
from supportless.base.geometry import signed_volume
from supportless.base.kinematics import matrix_to_euler
from supportless.copyleft.cgal import intersecting_faces, self_union
from supportless.files.meshes import check_closed_surface


def sunk_rod():
    """A unit sphere and a rod sunk 0.6 into it, as one surface: the rod's tip is wholly inside, far from any crossing."""
    sphere = trimesh.creation.icosphere(4, 1.0)
    rod = trimesh.creation.cylinder(0.2, 1.6, sections=32).subdivide().subdivide()
    rod.apply_translation([0, 0, 1.2])
    V = np.vstack([sphere.vertices, rod.vertices])
    F = np.vstack([sphere.faces, rod.faces + len(sphere.vertices)]).astype(np.int64)
    return V, F


def folded_sphere():
    """A sphere one of whose points is pushed along the surface past its neighbour: its fan folds over itself
    (the crossing triangles share corners)."""
    sphere = trimesh.creation.icosphere(3, 1.0)
    V = sphere.vertices.copy()
    neighbour = sphere.vertex_neighbors[10][0]
    V[10] += 1.8 * (V[neighbour] - V[10])
    return V, sphere.faces.astype(np.int64)


def arm_down(rig):
    """The tpose figure's left upper arm let down 70 degrees against its chest (the arm presses into the torso)."""
    A = np.zeros((rig.bone_count, 3))
    A[4] = matrix_to_euler(Rotation.from_rotvec([0, 0, -np.radians(70)]).as_matrix())
    return rig.pose(A), rig.faces


def check_against_the_whole_union(V, F):
    """The local union of (V, F), checked against CGAL's whole self-union; returns (vertices, faces, source)."""
    pairs = intersecting_faces(V, F)
    assert len(pairs) > 0
    size = float(np.ptp(V, axis=0).max())
    found = crossings.local_union(V, F, pairs, crossings.SIMPLIFY_TOLERANCE * size, np.float32)
    assert found is not None
    Vx, Fx, source = found
    Vw, Fw = self_union(V, F)
    check_closed_surface(Fx)
    assert len(intersecting_faces(Vx, Fx)) == 0
    assert len(intersecting_faces(Vx.astype(np.float32).astype(np.float64), Fx)) == 0
    np.testing.assert_allclose(signed_volume(Vx, Fx), signed_volume(Vw, Fw), rtol=1e-9)
    # the input's points are the input's, where they were; the others lie on the crossing curves
    assert np.array_equal(Vx[source >= 0], V[source[source >= 0]])
    assert np.any(source < 0)
    # every triangle two rings away from a crossing is kept as it was
    near = np.zeros(len(F), bool)
    near[np.unique(pairs)] = True
    for _ in range(crossings.LOCAL_RINGS):
        corner = np.zeros(len(V), bool)
        corner[F[near]] = True
        near |= corner[F].any(axis=1)
    kept = {tuple(f) for f in np.sort(np.where(source[Fx] >= 0, source[Fx], -1), axis=1).tolist()}
    away = np.sort(F[~near], axis=1).tolist()
    inside = sum(tuple(f) not in kept for f in away)
    return Vx, Fx, source, inside


def test_a_rod_sunk_into_a_sphere_keeps_the_union_and_drops_its_swallowed_tip():
    V, F = sunk_rod()
    Vx, Fx, source, inside = check_against_the_whole_union(V, F)
    assert inside > 0  # the rod's tip and the sphere's cap under it went, though no triangle there crosses
    assert np.linalg.norm(Vx, axis=1).min() > 0.99  # nothing left inside the sphere (its points are on it)
    assert Vx[:, 2].max() == pytest.approx(2.0)  # the rod's free end is the top


def test_a_fold_is_united_as_the_whole_union_unites_it():
    V, F = folded_sphere()
    check_against_the_whole_union(V, F)


def test_an_arm_pressed_into_the_torso_is_united_as_the_whole_union_unites_it(tpose_rig):
    V, F = arm_down(tpose_rig)
    _, _, _, inside = check_against_the_whole_union(V, F)
    assert inside == 0  # a shallow press: only the crossing triangles' pieces inside go


def test_a_large_surface_is_united_where_it_crosses_and_a_small_one_whole(tpose_rig, monkeypatch):
    V, F = arm_down(tpose_rig)
    whole = crossings.united_surface(V, F)
    assert len(F) < crossings.LOCAL_FACES and crossings.LOCALLY not in whole[2]["note"]
    monkeypatch.setattr(crossings, "LOCAL_FACES", 0)  # as for a sculpt
    local = crossings.united_surface(V, F)
    assert local[2]["how"] == "exact self-union" and crossings.LOCALLY in local[2]["note"]
    assert local[2]["pairs"] == whole[2]["pairs"]
    assert local[2]["volume"] == pytest.approx(whole[2]["volume"], rel=1e-9)


def test_when_the_local_union_fails_the_whole_surface_is_united(tpose_rig, monkeypatch):
    V, F = arm_down(tpose_rig)
    monkeypatch.setattr(crossings, "LOCAL_FACES", 0)
    monkeypatch.setattr(crossings, "local_union", lambda *args: None)
    Vx, Fx, merged = crossings.united_surface(V, F)
    assert merged["how"] == "exact self-union" and crossings.LOCALLY not in merged["note"]
    check_closed_surface(Fx)
    assert len(intersecting_faces(Vx, Fx)) == 0


def test_the_ways_of_keeping_pieces_start_with_the_vote_and_turn_the_smallest_first():
    vote = np.array([True, True, False])
    ways = [w.tolist() for w in crossings._choices(vote, np.array([100, 3, 5]))]
    assert ways == [[True, True, False], [True, False, False], [True, True, True], [True, False, True]]
    assert len(list(crossings._choices(np.ones(12, bool), np.arange(1, 13)))) == crossings.LOCAL_CHOICES


@pytest.mark.parametrize("shape", ["annulus", "rod and sphere apart", "rod sunk into a sphere",
                                   "turned inside out inside another"])
def test_the_winding_number_counted_along_columns_is_libigls(shape):
    """A ring (a hole through it), two separate solids, two crossing shells (the overlap wound twice) and a shell
    turned inside out within another (wound 0 there, -1 where it sticks out): on a grid, the count along the
    columns is libigl's generalized winding number rounded, at every point."""
    import igl

    turn = trimesh.transformations.rotation_matrix(0.4, [1, 1, 0])  # no face square to the columns
    if shape == "annulus":
        m = trimesh.creation.annulus(0.5, 1.0, 0.6, sections=48)
        m.apply_transform(turn)
        V, F = np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)
    elif shape == "turned inside out inside another":
        outer = trimesh.creation.icosphere(3, 1.0)
        inner = trimesh.creation.box([0.8, 0.8, 2.6])
        inner.apply_transform(turn)
        V = np.vstack([outer.vertices, inner.vertices])
        F = np.vstack([outer.faces, inner.faces[:, ::-1] + len(outer.vertices)]).astype(np.int64)
    else:
        V, F = sunk_rod()
        if shape == "rod and sphere apart":
            V[len(trimesh.creation.icosphere(4, 1.0).vertices):, 2] += 1.0  # the rod lifted clear of the sphere
    assert (len(intersecting_faces(V, F)) == 0) == (shape in ("annulus", "rod and sphere apart"))
    lo, hi = V.min(0) - 0.1, V.max(0) + 0.1
    h = float((hi - lo).max()) / 40
    axes = [lo[i] + h * np.arange(int(np.ceil((hi[i] - lo[i]) / h)) + 1) for i in range(3)]
    counted = gridsurface.winding_by_columns(V, F, axes)
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).transpose(2, 1, 0, 3).reshape(-1, 3)
    winding = igl.fast_winding_number(V, F, np.ascontiguousarray(grid)).reshape(counted.shape)
    assert (counted > 0).sum() > 100
    # away from the surface libigl's is within a hair of an integer; at the few points next to it, it is not
    settled = np.abs(winding - np.round(winding)) < 0.05
    assert settled.mean() > 0.97
    assert np.array_equal(counted[settled], np.round(winding[settled]).astype(np.int64))
    expected = {"rod sunk into a sphere": 2, "turned inside out inside another": -1}.get(shape)
    if expected is not None:
        assert expected in counted


@pytest.mark.parametrize("shape", ["rod sunk into a sphere", "two boxes sharing a wall on the grid's points"])
def test_the_grid_surface_counted_along_columns_is_libigls(shape):
    """grid_surface counts a closed surface's winding number along columns (libigl's for the few points within a
    hair of the surface), and uses libigl's at every point when told the surface is not closed: the same surface
    both ways, for crossing shells and for two boxes whose shared wall holds a plane of grid points."""
    if shape == "rod sunk into a sphere":
        V, F = sunk_rod()
    else:
        a, b = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]), trimesh.creation.box(bounds=[[1, 0, 0], [2, 1, 1]])
        V = np.vstack([a.vertices, b.vertices])
        F = np.vstack([a.faces, b.faces + len(a.vertices)]).astype(np.int64)
    assert gridsurface._is_closed(F)
    counted = gridsurface.grid_surface(V, F, 40)
    generalized = gridsurface.grid_surface(V, F, 40, closed=False)
    check_closed_surface(counted[1])
    assert len(intersecting_faces(*counted)) == 0
    np.testing.assert_array_equal(counted[1], generalized[1])
    np.testing.assert_array_equal(counted[0], generalized[0])
