"""The strength of a printed body against beam theory on bodies whose sections are known exactly."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from supportless.energies.materials import MATERIALS, Material, effective_strength, material_of
from supportless.energies.sections import section_moments
from supportless.energies.strength import GRAVITY, analyse_strength, chain_ends
from supportless.files.printer import PrinterProfile

PLA = MATERIALS["PLA"]
#: No weight: the grip alone, for closed forms.
WEIGHTLESS = Material("weightless", 0.0, 50.0, 0.5, 3500.0)


def box(extents, centre) -> trimesh.Trimesh:
    m = trimesh.creation.box(extents=extents)
    m.apply_translation(centre)
    return m


def union(*meshes) -> trimesh.Trimesh:
    out = trimesh.boolean.union(list(meshes), engine="manifold")
    assert out.is_watertight
    return out


def square_grip(lever: float, side: float, force: float = 2.0) -> float:
    """The largest stress of a grip in its worst direction on a square section of ``side``, the grip ``lever``
    away along the section's normal: at a corner, ``F sqrt(2 (lever c / I)² + 1/A²)``."""
    A, I, c = side ** 2, side ** 4 / 12.0, side / 2.0
    return force * np.sqrt(2.0 * (lever * c / I) ** 2 + 1.0 / A ** 2)


def test_section_moments_of_a_square_less_a_square_hole_are_exact():
    outer = np.array([[0, 0], [4, 0], [4, 4], [0, 4]], float)
    hole = np.array([[1, 1], [1, 3], [3, 3], [3, 1]], float)  # clockwise
    first = np.concatenate([outer, hole])
    second = np.concatenate([np.roll(outer, -1, axis=0), np.roll(hole, -1, axis=0)])
    m = section_moments(first, second, np.zeros(8, np.int64), 1)[0]
    assert m[0] == pytest.approx(16 - 4)
    assert m[1] / m[0] == pytest.approx(2.0) and m[2] / m[0] == pytest.approx(2.0)
    # ∫x² about x = 2: 4^4/12 - 2^4/12
    assert m[3] - m[0] * 4.0 == pytest.approx((4 ** 4 - 2 ** 4) / 12.0)
    assert m[5] - m[0] * 4.0 == pytest.approx(0.0, abs=1e-12)  # symmetric: no product moment


def test_section_moments_match_sampling_of_a_triangle():
    rng = np.random.default_rng(0)
    P = np.array([[0.3, 0.1], [5.0, 1.0], [2.0, 4.5]])
    m = section_moments(P, np.roll(P, -1, axis=0), np.zeros(3, np.int64), 1)[0]
    u, v = rng.random(400_000), rng.random(400_000)
    flip = u + v > 1
    u, v = np.where(flip, 1 - u, u), np.where(flip, 1 - v, v)
    q = P[0] + u[:, None] * (P[1] - P[0]) + v[:, None] * (P[2] - P[0])
    d1, d2 = P[1] - P[0], P[2] - P[0]
    area = 0.5 * abs(d1[0] * d2[1] - d1[1] * d2[0])
    expected = area * np.array([1.0, q[:, 0].mean(), q[:, 1].mean(), (q[:, 0] ** 2).mean(), (q[:, 1] ** 2).mean(),
                                (q[:, 0] * q[:, 1]).mean()])
    assert m == pytest.approx(expected, rel=5e-3)


def test_a_vertical_cantilever_is_bent_as_beam_theory_says():
    m = box((4, 4, 40), (0, 0, 20))
    J = np.array([[0, 0, 0], [0, 0, 30.0], [0, 0, 50.0]])  # the leaf bone's middle, where it is gripped: the top
    s = analyse_strength(m.vertices, m.faces, J, np.array([[0, 1], [1, 2]]), material=WEIGHTLESS, held_mm=1.0)
    layers = [x for x in s.sections if x.kind == "layer"]
    for x in layers[::25]:
        assert x.across and x.stress_mpa == pytest.approx(square_grip(40.0 - x.height_mm, 4.0), rel=1e-6)
        assert x.breaks_at_n == pytest.approx(2.0 * WEIGHTLESS.across_mpa / x.stress_mpa, rel=1e-6)
    # the weakest is at the foot of the column, where the lever is longest
    assert s.weakest.height_mm == pytest.approx(1.0, abs=0.3)
    assert s.safety_factor == pytest.approx(WEIGHTLESS.across_mpa / square_grip(39.0, 4.0), rel=1e-3)


def test_its_own_weight_compresses_a_column():
    m = box((4, 4, 40), (0, 0, 20))
    s = analyse_strength(m.vertices, m.faces, np.array([[0, 0, 0], [0, 0, 40.0]]), np.array([[0, 1]]),
                         material=PLA, load_n=0.0, held_mm=1.0)
    assert all(x.stress_mpa <= 1e-9 for x in s.sections)  # compression only: nothing pulls
    assert s.safety_factor == np.inf


def test_a_horizontal_cantilever_is_bent_along_its_layers():
    m = union(box((4, 4, 20), (0, 0, 10)), box((32, 4, 4), (16, 0, 18)))
    J = np.array([[0, 0, 0], [0, 0, 18.0], [28, 0, 18], [36, 0, 18]])  # gripped at (32, 0, 18), the tip
    s = analyse_strength(m.vertices, m.faces, J, np.array([[0, 1], [1, 2], [2, 3]]), material=WEIGHTLESS)
    beam = [x for x in s.sections if x.kind == "bone" and x.bone == 1]
    assert len(beam) == 3
    for x in beam:
        assert not x.across  # a horizontal beam bends along its lines
        assert x.strength_mpa == pytest.approx(WEIGHTLESS.along_mpa)
        assert x.stress_mpa == pytest.approx(square_grip(32.0 - x.centre[0], 4.0), rel=1e-6)


def test_two_posts_in_one_layer_each_carry_their_own_grip():
    """A U: two posts of different sections on a base; the grip at each post's top is carried by that post."""
    m = union(box((30, 6, 4), (0, 0, 2)), box((4, 4, 30), (-12, 0, 19)), box((2, 2, 30), (12, 0, 19)))
    J = np.array([[0, 0, 2.0], [-12, 0, 2], [-12, 0, 66], [12, 0, 2], [12, 0, 66]])  # gripped at the tops
    B = np.array([[0, 1], [1, 2], [0, 3], [3, 4]])
    s = analyse_strength(m.vertices, m.faces, J, B, material=WEIGHTLESS, held_mm=2.0)
    layers = [x for x in s.sections if x.kind == "layer"]
    nearest = min(abs(x.height_mm - 20.0) for x in layers)
    at_20 = [x for x in layers if abs(x.height_mm - 20.0) == nearest]
    assert len(at_20) == 2  # two separate sections in one layer
    for x in at_20:
        side = 4.0 if x.centre[0] < 0 else 2.0
        assert x.area_mm2 == pytest.approx(side ** 2)
        assert x.stress_mpa == pytest.approx(square_grip(34.0 - x.centre[2], side), rel=1e-6)
        assert x.chain_end == (2 if x.centre[0] < 0 else 4)
    assert s.weakest.centre[0] > 0  # the thin post breaks first


def test_a_part_with_nothing_above_it_carries_no_load():
    """The U's right post without a chain end, and no weight: nothing loads its sections."""
    m = union(box((30, 6, 4), (0, 0, 2)), box((4, 4, 30), (-12, 0, 19)), box((2, 2, 30), (12, 0, 19)))
    J = np.array([[0, 0, 2.0], [-12, 0, 2], [-12, 0, 66], [12, 0, 2], [12, 0, 66]])  # gripped at the tops
    B = np.array([[0, 1], [1, 2], [0, 3], [3, 4]])
    s = analyse_strength(m.vertices, m.faces, J, B, material=WEIGHTLESS, held_mm=2.0, ends=np.array([2]))
    right = [x for x in s.sections if x.kind == "layer" and x.centre[0] > 6 and x.height_mm > 5]
    assert right and all(x.safety_factor == np.inf and x.chain_end == -1 for x in right)
    left = [x for x in s.sections if x.kind == "layer" and x.centre[0] < -6 and x.height_mm > 5]
    assert left and all(np.isfinite(x.safety_factor) for x in left)


def test_a_hanging_part_pulls_on_its_sections():
    """A gallows: a post, a beam, and a part hanging from the beam's end; the hanging part's weight is tension."""
    m = union(box((4, 4, 40), (0, 0, 20)), box((24, 4, 4), (10, 0, 38)), box((4, 4, 20), (20, 0, 26)))
    J = np.array([[0, 0, 0], [0, 0, 38.0], [20, 0, 38], [20, 0, 16]])
    B = np.array([[0, 1], [1, 2], [2, 3]])
    s = analyse_strength(m.vertices, m.faces, J, B, material=PLA, load_n=0.0, held_mm=1.0)
    hanging = [x for x in s.sections if x.kind == "layer" and x.centre[0] > 15 and 18 < x.height_mm < 34]
    assert hanging
    w = PLA.density * GRAVITY * 1e-6  # N/mm³
    for x in hanging:
        below = 16.0 * (x.height_mm - 16.0)  # the hanging part's volume under the section, mm³
        assert x.stress_mpa == pytest.approx(w * below / 16.0, rel=0.05)


def test_a_thin_neck_is_the_weakest_section_at_the_necks_height():
    body = trimesh.creation.cylinder(radius=10, height=40, sections=48)
    body.apply_translation((0, 0, 20))
    neck = trimesh.creation.cylinder(radius=1.6, height=6, sections=32)
    neck.apply_translation((0, 0, 42))
    head = trimesh.creation.icosphere(subdivisions=3, radius=7)
    head.apply_translation((0, 0, 51))
    m = union(body, neck, head)
    J = np.array([[0, 0, 0], [0, 0, 40.0], [0, 0, 45], [0, 0, 58]])
    B = np.array([[0, 1], [1, 2], [2, 3]])
    s = analyse_strength(m.vertices, m.faces, J, B, material=PLA)
    assert m.bounds[1, 2] == pytest.approx(58.0, abs=0.1)  # about 60 mm tall
    assert s.weakest.height_mm == pytest.approx(42.0, abs=2.0)
    assert s.weakest.across and s.weakest.bone in (1, 2)


def test_turning_or_moving_a_body_on_the_plate_changes_nothing():
    m = union(box((4, 4, 20), (0, 0, 10)), box((32, 4, 4), (16, 0, 18)))
    J = np.array([[0, 0, 0], [0, 0, 18.0], [32, 0, 18]])
    B = np.array([[0, 1], [1, 2]])
    a = analyse_strength(m.vertices, m.faces, J, B)
    R = trimesh.transformations.rotation_matrix(0.7, (0, 0, 1))[:3, :3]
    shift = np.array([13.0, -4.0, 2.5])
    b = analyse_strength(m.vertices @ R.T + shift, m.faces, J @ R.T + shift, B)
    assert b.safety_factor == pytest.approx(a.safety_factor, rel=1e-3)  # the planes fall alike up to rounding
    assert [x.kind for x in b.sections[:5]] == [x.kind for x in a.sections[:5]]


def test_fingers_are_gripped_at_the_hand_and_a_long_tail_at_its_tip():
    hand = np.array([0.0, 0, 0])
    joints = [np.zeros(3), np.array([0, 0, 10.0])]  # 0: body, 1: hand
    bones = [[0, 1]]
    for k in range(3):  # three fingers of two bones, 1.5 long
        a, b = len(joints), len(joints) + 1
        joints += [np.array([k - 1.0, 0, 10.8]), np.array([k - 1.0, 0, 11.5])]
        bones += [[1, a], [a, b]]
    tail0 = len(joints)
    joints += [np.array([0, 5.0, 0]), np.array([0, 10.0, 0]), np.array([0, 15.0, 0])]
    bones += [[0, tail0], [tail0, tail0 + 1], [tail0 + 1, tail0 + 2]]
    ends = chain_ends(np.array(joints) + hand, np.array(bones), reach=3.0)
    assert ends.tolist() == [1, tail0 + 2]


def test_a_leaf_is_gripped_halfway_along_its_bone_and_a_branch_at_itself():
    from supportless.energies.strength import grip_points

    joints = np.array([[0, 0, 0], [0, 0, 10.0], [0, 0, 14.0], [3, 0, 10]])
    bones = np.array([[0, 1], [1, 2], [1, 3]])
    assert grip_points(joints, bones, np.array([2, 1])).tolist() == [[0, 0, 12.0], [0, 0, 10.0]]


def test_strength_across_and_along_the_layers():
    assert effective_strength(PLA, 1.0) == pytest.approx(PLA.across_mpa)
    assert effective_strength(PLA, 0.0) == pytest.approx(PLA.along_mpa)
    tilt = effective_strength(PLA, np.cos(np.radians(np.linspace(0, 90, 19))))
    assert np.all(np.diff(tilt) > 0)  # the flatter, the stronger
    assert np.all((tilt >= PLA.across_mpa - 1e-9) & (tilt <= PLA.along_mpa + 1e-9))  # never outside the two


def test_the_profiles_filament_is_the_material():
    assert material_of(None).name == "PLA"
    assert material_of(PrinterProfile(raw={"filament_type": "PETG"})).name == "PETG"
    assert material_of(PrinterProfile(raw={"filament_type": "NYLON"})).name == "PLA"  # unknown: the default


def test_the_worst_grip_on_a_square_column_pulls_along_a_diagonal():
    """Its corner fibre is stretched most by a grip across the diagonal, tilted up by the axial share."""
    m = box((4, 4, 40), (0, 0, 20))
    s = analyse_strength(m.vertices, m.faces, np.array([[0, 0, 0], [0, 0, 30.0], [0, 0, 50.0]]),
                         np.array([[0, 1], [1, 2]]), material=WEIGHTLESS, held_mm=1.0)
    u = s.weakest.grip
    assert np.linalg.norm(u) == pytest.approx(1.0)
    assert abs(u[0]) == pytest.approx(abs(u[1]), rel=1e-6) and abs(u[2]) < 0.05
    # the stress of that grip at its worst corner, by M·c/I about both axes and F/A: the section's stress
    lever = 40.0 - s.weakest.height_mm
    I, c = 4 ** 4 / 12.0, 2.0
    corner = np.array([np.sign(-u[0]) * c, np.sign(-u[1]) * c])  # where a grip this way pulls
    M = np.cross([0, 0, lever], 2.0 * u)
    sigma = 2.0 * u[2] / 16.0 + (M[0] * corner[1] - M[1] * corner[0]) / I
    assert abs(sigma) == pytest.approx(s.weakest.stress_mpa, rel=1e-6)
