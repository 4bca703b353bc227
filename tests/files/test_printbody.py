"""The print body (supportless.files.printbody): analytic checks on boxes.

Volumes are exact for unions of axis-aligned boxes, and a linear function of
position carried as the per-vertex values must come out as the same linear
function at every output vertex (welding averages, fans about loop centres,
intersection vertices and edge collapses all interpolate linearly).
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from meshes import box

from supportless.base.geometry import signed_volume
from supportless.copyleft.cgal import intersecting_face_pairs
from supportless.files.meshes import check_closed_surface
from supportless.files.printbody import BRIDGE_GAP, ISLAND_MIN_VOLUME, SHELL_MIN_VOLUME, print_body, transfer_values

#: Coefficients of the linear values: column k is ``OFFSET[k] + x · GRADIENT[:, k]``.
GRADIENT = np.array([[1.0, -0.5], [2.0, 0.25], [-3.0, 1.5]])
OFFSET = np.array([10.0, 4.0])  # rows sum well above 0.5, like skin weights


def linear(X: np.ndarray) -> np.ndarray:
    """(n, 2) float64: the linear test values at points ``X`` (n, 3)."""
    return OFFSET + np.asarray(X) @ GRADIENT


def boxes(*corners):
    """Several boxes as one input: ``(V, F, part)``, one part per box given as ``(lo, hi)``."""
    Vs, Fs, parts = [], [], []
    offset = 0
    for k, (lo, hi) in enumerate(corners):
        V, F = box(lo, hi)
        Vs.append(V)
        Fs.append(F + offset)
        parts.append(np.full(len(F), k))
        offset += len(V)
    return np.vstack(Vs), np.vstack(Fs), np.concatenate(parts)


def body_of(V, F, part, values=None):
    """``print_body`` with the linear values (default) and checks every body must pass.

    Returns the body; asserts it is closed, manifold, outward, free of
    self-intersections, and that it carries the linear values at its vertices.
    """
    body = print_body(V, F, part, linear(V) if values is None else values)
    check_closed_surface(body.faces)
    assert signed_volume(body.vertices, body.faces) > 0
    assert intersecting_face_pairs(body.vertices, body.faces) == 0
    if values is None:
        np.testing.assert_allclose(body.values, linear(body.vertices), rtol=0, atol=1e-6)
    return body


def line(body, start: str) -> str:
    """The one log line of a body that starts with ``start``."""
    found = [x for x in body.log if x.startswith(start)]
    assert len(found) == 1, body.log
    return found[0]


def volume(body) -> float:
    """Enclosed volume of a body."""
    return signed_volume(body.vertices, body.faces)


def test_two_overlapping_cubes_are_one_solid_of_the_union_volume():
    V, F, part = boxes(((0, 0, 0), (1, 1, 1)), ((0.5, 0.25, 0.3), (1.5, 1.25, 1.3)))
    body = body_of(V, F, part)
    overlap = 0.5 * 0.75 * 0.7
    assert volume(body) == pytest.approx(2.0 - overlap, rel=1e-6)
    assert body.islands == 1
    mesh = trimesh.Trimesh(body.vertices, body.faces, process=False)
    assert len(mesh.split(only_watertight=False)) == 1
    union = line(body, "union of 2 shells")
    assert "1 solid(s)" in union and "(-13.1 % against the closed shells" in union  # the overlap 0.2625 of 2


def test_seam_split_faces_are_welded_and_degenerate_and_duplicate_faces_dropped():
    V, F = box((0, 0, 0), (2, 1, 1))
    Vs, Fs = V[F].reshape(-1, 3), np.arange(F.size).reshape(-1, 3)  # three vertices of its own per face
    Fs = np.vstack([Fs, Fs[:1, ::-1], [[0, 0, 1]]])  # a duplicate (reversed) and a degenerate face
    body = body_of(Vs, Fs, np.zeros(len(Fs), np.int64))
    assert len(body.vertices) == 8 and len(body.faces) == 12
    assert volume(body) == pytest.approx(2.0, rel=1e-12)
    assert "welded 28 seam-split vertices; dropped 1 degenerate and 1 duplicate triangles" in line(body, "welded")


def test_an_open_box_is_closed_to_the_full_box():
    V, F = box((0, 0, 0), (1, 2, 3))
    top = np.flatnonzero(np.all(V[F][:, :, 1] == 2.0, axis=1))
    assert len(top) == 2
    F = np.delete(F, top, axis=0)
    body = body_of(V, F, np.zeros(len(F), np.int64))
    assert volume(body) == pytest.approx(6.0, rel=1e-6)
    assert "closed 1 holes in 1 open shells" in line(body, "1 shells")
    # the cap's centre carries the mean of its loop, the linear value there
    centre = np.flatnonzero(np.all(np.isclose(body.vertices, [0.5, 2.0, 1.5]), axis=1))
    assert len(centre) == 1
    np.testing.assert_allclose(body.values[centre], linear([[0.5, 2.0, 1.5]]), atol=1e-12)


@pytest.mark.parametrize("gap", [
    0.0125,  # float32(1 + gap) rounds outward, into the far cube
    0.01,  # float32(1 + gap) would round inward: the hull is built in float64
], ids=["rounds-outward", "rounds-inward"])
def test_cubes_a_small_gap_apart_are_bridged_into_one_solid(gap):
    size = 2.0 + gap
    assert gap < BRIDGE_GAP * size
    V, F, part = boxes(((0, 0, 0), (1, 1, 1)), ((1 + gap, 0, 0), (2 + gap, 1, 1)))
    body = print_body(V, F, part, linear(V))
    assert "bridged 1 gap(s)" in line(body, "union of 2 shells")
    assert body.islands == 1, body.log
    check_closed_surface(body.faces)
    # the bridge is the box between the facing sides: the hull of their corners
    assert volume(body) == pytest.approx(2.0 + gap, rel=1e-6)
    np.testing.assert_allclose(body.values, linear(body.vertices), rtol=0, atol=1e-5)


def test_a_small_cube_far_away_is_dropped_and_said():
    side = 0.1
    assert side**3 < ISLAND_MIN_VOLUME * (1 + side**3) and side**3 > SHELL_MIN_VOLUME * (1 + side**3)
    V, F, part = boxes(((0, 0, 0), (1, 1, 1)), ((5, 5, 5), (5 + side, 5 + side, 5 + side)))
    body = body_of(V, F, part)
    assert body.islands == 1
    assert volume(body) == pytest.approx(1.0, rel=1e-9)
    assert body.vertices.max() <= 1.0 + 1e-12
    assert "dropped 1 floating piece(s) under 1% of the volume (0.10%)" in line(body, "union of 2 shells")
    assert not any(line.startswith("warning") for line in body.log)


def test_a_large_separate_cube_is_kept_as_a_second_island_with_a_warning():
    V, F, part = boxes(((0, 0, 0), (1, 1, 1)), ((3, 0, 0), (3.8, 0.8, 0.8)))
    body = body_of(V, F, part)
    assert body.islands == 2
    assert volume(body) == pytest.approx(1.0 + 0.8**3, rel=1e-9)
    assert body.log[-1] == "warning: the print body is 2 separate solids; they print as separate pieces"
    union = line(body, "union of 2 shells")
    assert "2 solid(s)" in union and "dropped" not in union


def test_nothing_closable_is_an_input_error():
    from supportless.base.errors import InputError

    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(InputError, match="no part of the model can be closed"):
        print_body(V, np.array([[0, 1, 2]]), np.zeros(1, np.int64), np.ones((3, 1)))


def test_transfer_values_reproduces_a_linear_function_on_and_near_a_surface():
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=2.0)
    V, F = np.asarray(sphere.vertices), np.asarray(sphere.faces, np.int64)
    rng = np.random.default_rng(0)
    f = rng.integers(0, len(F), 400)
    bary = rng.dirichlet([1.0, 1.0, 1.0], len(f))
    on = np.einsum("pk,pkc->pc", bary, V[F[f]])
    normal = np.asarray(sphere.face_normals)[f]
    near = on + rng.uniform(0.0, 0.05, (len(f), 1)) * normal  # outside a convex surface: the foot is the closest point
    values = linear(V)
    np.testing.assert_allclose(transfer_values(on, V, F, values), linear(on), rtol=0, atol=1e-9)
    np.testing.assert_allclose(transfer_values(near, V, F, values), linear(on), rtol=0, atol=1e-9)
    np.testing.assert_allclose(transfer_values(V, V, F, values), values, rtol=0, atol=1e-9)


def crossing_boxes():
    """A 2x1x1 box and a 1x2x0.5 box through it, as one surface: their union's volume is 2 + 1 - 0.5 = 2.5."""
    V1, F1 = box((0, 0, 0), (2, 1, 1))
    V2, F2 = box((0.5, -0.5, 0.25), (1.5, 1.5, 0.75))
    return np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])


@pytest.mark.slow
def test_the_winding_number_surface_of_crossing_shells_is_their_union_closed_and_clean():
    from supportless.files.crossings import WINDING_MAX_FACES
    from supportless.files.printbody import WINDING_CELLS, winding_surface

    V, F = crossing_boxes()
    assert intersecting_face_pairs(V, F) > 0
    cells = WINDING_CELLS * 5 // 8  # fewer cells than a body gets, still more triangles than the body keeps: simplified
    Vs, Fs = winding_surface(V, F, cells)
    assert len(Fs) == WINDING_MAX_FACES
    check_closed_surface(Fs)
    assert intersecting_face_pairs(Vs, Fs) == 0
    # placed by distance, not by cells: the flat faces stay where they were (to float noise), the volume too
    np.testing.assert_allclose(Vs.min(0), V.min(0), atol=1e-3 * 2.5)
    np.testing.assert_allclose(Vs.max(0), V.max(0), atol=1e-3 * 2.5)
    np.testing.assert_allclose(signed_volume(Vs, Fs), 2.5, rtol=0.01)
    again = winding_surface(V, F, cells)
    np.testing.assert_array_equal(again[0], Vs)  # deterministic


def test_crossing_triangles_left_by_the_union_are_resolved_with_the_values_carried():
    from supportless.files.printbody import SIMPLIFY_TOLERANCE, _resolve_crossings

    V, F = crossing_boxes()
    values = np.column_stack([V[:, 0] / 2, 1 - V[:, 0] / 2])  # linear in x: carried exactly by closest point
    log = []
    Vx, Fx, Wx = _resolve_crossings(V, F, values, SIMPLIFY_TOLERANCE * 2.5, log)
    assert intersecting_face_pairs(Vx, Fx) == 0
    check_closed_surface(Fx)
    np.testing.assert_allclose(signed_volume(Vx, Fx), 2.5, rtol=0.01)
    np.testing.assert_allclose(Wx[:, 0], np.clip(Vx[:, 0] / 2, 0, 1), atol=0.01)
    assert len(log) == 1 and "crossing triangles" in log[0]


def test_a_shell_closing_cannot_make_manifold_is_kept_through_its_winding_number():
    """A box with a wall inside on its diagonal (two edges of three triangles) and a box through it: kept, not dropped."""
    V, F, part = boxes(((0, 0, 0), (2, 1, 1)), ((1.5, 0.2, 0.2), (3, 0.8, 0.8)))
    at = {tuple(v): i for i, v in enumerate(V[:8])}
    a, b, c, d = at[(0, 0, 0)], at[(0, 0, 1)], at[(2, 1, 0)], at[(2, 1, 1)]
    F = np.vstack([F, [[a, b, d], [a, d, c]]])
    part = np.concatenate([part, [0, 0]])
    body = print_body(V, F, part, linear(V))
    check_closed_surface(body.faces)
    assert intersecting_face_pairs(body.vertices, body.faces) == 0
    union = 2.0 + 1.5 * 0.6 * 0.6 - 0.5 * 0.6 * 0.6  # the boxes overlap over 0.5 x 0.6 x 0.6
    np.testing.assert_allclose(signed_volume(body.vertices, body.faces), union, rtol=0.03)
    assert any("not manifold after closing" in line for line in body.log), body.log
    assert any("winding number" in line for line in body.log), body.log
    np.testing.assert_allclose(body.values, linear(body.vertices), atol=0.05 * np.abs(GRADIENT).max())
