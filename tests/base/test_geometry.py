"""The printing direction, enclosed volumes and placing on the plate."""

import numpy as np
import pytest
from meshes import box

from supportless.base.errors import InputError
from supportless.base.geometry import parse_up, place_on_plate, signed_volume


@pytest.mark.parametrize("up, expected", [("y", [0, 1, 0]), ("-z", [0, 0, -1]), ("X", [1, 0, 0]),
                                          ("0,0,2", [0, 0, 1]), ("3 4 0", [0.6, 0.8, 0]), ((0, -5, 0), [0, -1, 0])])
def test_parse_up(up, expected):
    np.testing.assert_allclose(parse_up(up), expected, atol=1e-15)


def test_parse_up_2d_and_errors():
    np.testing.assert_array_equal(parse_up("y", dim=2), [0, 1])
    np.testing.assert_array_equal(parse_up("1,0", dim=2), [1, 0])  # a planar figure: two numbers
    np.testing.assert_array_equal(parse_up((1, 0)), [1, 0, 0])  # an array of two: z = 0
    for bad in ("w", "0,0,0", "1,nan,0", "1,2,3,4", (0, 1, 0, 0)):
        with pytest.raises(InputError, match="up direction"):
            parse_up(bad)
    with pytest.raises(InputError, match="has 2 numbers; give three"):  # "0,1" for a 3D model: said
        parse_up("0,1")
    with pytest.raises(InputError, match="plane"):
        parse_up("z", dim=2)


def test_signed_volume_of_a_box_and_its_mirror():
    V, F = box((0, 0, 0), (1, 2, 3))
    assert signed_volume(V, F) == pytest.approx(6.0, abs=1e-12)
    assert signed_volume(V, F[:, ::-1]) == pytest.approx(-6.0, abs=1e-12)
    # a translated box encloses the same volume
    assert signed_volume(V + [5.0, -7.0, 2.0], F) == pytest.approx(6.0, abs=1e-12)


def test_signed_area_of_a_planar_square():
    V = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    assert signed_volume(V, F) == 4.0
    assert signed_volume(V, F[:, ::-1]) == -4.0


def test_place_on_plate_along_any_up():
    V = np.array([[0.0, 2.0, 0.0], [1.0, 5.0, 1.0]])
    np.testing.assert_allclose(place_on_plate(V, np.array([0.0, 1.0, 0.0]))[:, 1], [0.0, 3.0])
    up = np.array([0.0, 0.0, -1.0])
    out = place_on_plate(V, up)
    assert (out @ up).min() == 0.0
    np.testing.assert_array_equal(out[:, :2], V[:, :2])


def test_print_pose_is_a_rigid_turn_onto_the_plate():
    from scipy.spatial.transform import Rotation

    from supportless.base.geometry import print_pose, print_transform

    rng = np.random.default_rng(0)
    V = rng.normal(size=(40, 3)) + [5.0, 3.0, -2.0]
    R = Rotation.from_rotvec([0.4, -1.1, 0.3]).as_matrix()
    up = np.array([0.0, 1.0, 0.0])
    P = print_pose(V, R, up)
    np.testing.assert_allclose(P, V @ R.T + print_transform(V, R, up), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(P[:, None] - P[None], axis=-1),
                               np.linalg.norm(V[:, None] - V[None], axis=-1), atol=1e-10)  # rigid
    assert (P @ up).min() == pytest.approx(0.0, abs=1e-12)  # on the plate
    # turned about the bounding-box centre: it stays where it was across the plate
    centre = 0.5 * (V.min(0) + V.max(0))
    moved = (V - centre) @ R.T + centre
    np.testing.assert_allclose(P - moved, np.outer(np.ones(len(V)), (P - moved)[0]), atol=1e-12)
    assert abs((P - moved)[0] @ [1, 0, 0]) < 1e-12 and abs((P - moved)[0] @ [0, 0, 1]) < 1e-12


def test_a_surface_digest_changes_with_any_bit_and_only_then():
    from supportless.base.geometry import surface_digest

    V = np.random.default_rng(0).random((10, 3))
    F = np.array([[0, 1, 2], [2, 3, 4]])
    assert surface_digest(V, F) == surface_digest(V.copy(), F.copy())
    W = V.copy()
    W[3, 1] = np.nextafter(W[3, 1], 2.0)  # one bit
    assert surface_digest(W, F) != surface_digest(V, F)
    assert surface_digest(V, F[:, ::-1]) != surface_digest(V, F)
    assert surface_digest(V[:9], F) != surface_digest(V, F)
