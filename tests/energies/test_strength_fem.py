"""The finite-element strength reference against beam theory, statics and its own pieces checked by hand.

Every mesh is a box of skfem's structured tetrahedra (``MeshTet.init_tensor``), 1 mm apart; PLA's Young's
modulus 3500 MPa and Poisson's ratio 0.35. Beam theory (Euler-Bernoulli) is exact for the normal stress of a
slender prismatic beam away from its ends (Saint-Venant), which is where the sections are taken.
"""

import numpy as np
import pytest
import skfem

from supportless.energies import elasticity, multigrid
from supportless.energies.strength_fem import (PLA_GRAVITY, elastic_solution, plate_nodes, section_normal_stress,
                                               section_stress, stress_at)

B = 4.0  # the beams' square cross-section, mm
I_SECTION = B ** 4 / 12.0  # its second moment of area, mm^4
L = 40.0  # their length, mm


def box(size, step=1.0, at=(0.0, 0.0, 0.0)):
    """((t, 3) float64, (k, 4) int64): a box ``size`` (mm) from ``at`` in tetrahedra about ``step`` apart."""
    axes = [np.linspace(a, a + s, int(round(s / step)) + 1) for a, s in zip(at, size)]
    mesh = skfem.MeshTet.init_tensor(*axes)
    return mesh.p.T.copy(), mesh.t.T.astype(np.int64)


@pytest.fixture(scope="module")
def column():
    """A 4 x 4 x 40 mm column standing on the plate."""
    return box((B, B, L))


@pytest.fixture(scope="module")
def beam():
    """A 40 x 4 x 4 mm beam along x, held at its x = 0 end face."""
    return box((L, B, B))


def test_a_vertical_cantilever_bends_as_beam_theory_says(column):
    nodes, tets = column
    F = 2.0
    solution = elastic_solution(nodes, tets, plate_nodes(nodes), load_points=[[B / 2, B / 2, L]],
                                load_forces=[[F, 0.0, 0.0]])
    expected = F * (L - L / 2) * (B / 2) / I_SECTION  # M c / I at mid-height, 3.75 MPa
    section = section_stress(solution, [B / 2, B / 2, L / 2], [0, 0, 1])
    assert section.max == pytest.approx(expected, rel=0.05)
    assert section.where[0] == pytest.approx(0.0, abs=1e-9)  # the force pulls to +x: the x = 0 side stretches
    assert section.normal_stress.min() == pytest.approx(-expected, rel=0.05)
    sigma = stress_at(solution, [[0.0, B / 2, L / 2], [B, B / 2, L / 2], [B / 2, B / 2, L / 2]])[:, 2, 2]
    assert sigma == pytest.approx([expected, -expected, 0.0], rel=0.05, abs=0.02 * expected)
    assert solution.info["solver"] == "multigrid-cg" and solution.info["residual"] <= 1e-6
    # the tip moves as far as the cantilever's F L^3 / (3 E I) (shear adds a few per mille)
    tip = solution.node_displacement[nodes[:, 2] == L, 0].mean()
    assert tip == pytest.approx(F * L ** 3 / (3 * 3500.0 * I_SECTION), rel=0.03)


def test_a_horizontal_cantilever_bends_and_stretches_as_beam_theory_says(beam):
    nodes, tets = beam
    held = nodes[:, 0] == 0.0
    tip = [[L, B / 2, B / 2]]
    bent = elastic_solution(nodes, tets, held, load_points=tip, load_forces=[[0.0, 0.0, -1.0]])
    expected = 1.0 * (L / 2) * (B / 2) / I_SECTION  # 1.875 MPa, the top fibre in tension
    section = section_stress(bent, [L / 2, B / 2, B / 2], [1, 0, 0])
    assert section.max == pytest.approx(expected, rel=0.05)
    assert section.where[2] == pytest.approx(B, abs=1e-9)
    assert stress_at(bent, [[L / 2, B / 2, B]])[0, 0, 0] == pytest.approx(expected, rel=0.05)

    pulled = elastic_solution(nodes, tets, held, load_points=tip, load_forces=[[10.0, 0.0, 0.0]])
    axial = section_stress(pulled, [L / 2, B / 2, B / 2], [1, 0, 0])
    assert axial.normal_stress == pytest.approx(np.full(len(axial.points), 10.0 / B ** 2), rel=0.02)


def test_a_column_under_its_own_weight_carries_rho_g_h_at_its_base(column):
    nodes, tets = column
    solution = elastic_solution(nodes, tets, plate_nodes(nodes), body_force=PLA_GRAVITY)
    rho_g = -PLA_GRAVITY[2]
    grid = np.linspace(0.05, B - 0.05, 40)  # cell centres of a 40 x 40 grid over the section
    X, Y = np.meshgrid(grid, grid)

    def mean_sigma_zz(z):
        return stress_at(solution, np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)]))[:, 2, 2].mean()

    # the base carries the whole weight, rho g h (4.9e-4 MPa), in compression; the held base keeps the first
    # layer from narrowing, so the stress is even over the section only away from it
    assert mean_sigma_zz(0.0) == pytest.approx(-rho_g * L, rel=0.05)
    assert section_stress(solution, [B / 2, B / 2, 0.0], [0, 0, 1]).max < 0
    for z in (10.0, 20.0, 30.0):  # each height carries the weight above it, evenly
        assert stress_at(solution, [[B / 2, B / 2, z]])[0, 2, 2] == pytest.approx(-rho_g * (L - z), rel=0.01)


def test_p1_agrees_where_it_is_exact_and_lu_agrees_with_multigrid(column, monkeypatch):
    nodes, tets = column
    pulled = dict(load_points=[[B / 2, B / 2, L]], load_forces=[[0.0, 0.0, 5.0]])
    p1 = elastic_solution(nodes, tets, plate_nodes(nodes), order=1, **pulled)
    assert section_stress(p1, [B / 2, B / 2, L / 2], [0, 0, 1]).normal_stress == pytest.approx(5.0 / B ** 2, rel=0.02)
    small_nodes, small_tets = box((2.0, 2.0, 6.0))
    args = (small_nodes, small_tets, plate_nodes(small_nodes), [[1.0, 1.0, 6.0]], [[1.0, 0.5, -1.0]], PLA_GRAVITY)
    for order, levels in ((2, 3), (1, 2)):  # P2, P1, aggregates; P1, aggregates
        monkeypatch.setattr(multigrid, "DIRECT_DOFS", 10 ** 9)
        lu = elastic_solution(*args, order=order)
        monkeypatch.setattr(multigrid, "DIRECT_DOFS", 0)
        monkeypatch.setattr(multigrid, "COARSE_DOFS", 100)
        mg = elastic_solution(*args, order=order)
        assert lu.info["solver"] == "lu" and mg.info["solver"] == "multigrid-cg" and len(mg.info["levels"]) == levels
        assert mg.displacement == pytest.approx(lu.displacement, rel=1e-6, abs=1e-7 * np.abs(lu.displacement).max())


def test_a_point_load_keeps_its_resultant_and_moment(column):
    nodes, tets = column
    basis = elasticity.scalar_basis(nodes, tets, 2)
    point, force = np.array([1.3, 2.9, 39.6]), np.array([0.4, -1.0, 2.0])
    density = elasticity.body_force_density(basis, None, [point], [force], None)
    x, dx = np.asarray(basis.global_coordinates()), basis.dx
    assert np.einsum("ceq,eq->c", density, dx) == pytest.approx(force)
    moment = np.einsum("ceq,eq->c", np.cross(x, density, axis=0), dx)
    assert moment == pytest.approx(np.cross(point, force))
    patch = elasticity.load_patch(nodes, tets, point)
    assert 1 < len(patch) < 60 and np.linalg.norm(nodes[tets[patch]].mean(axis=(0, 1)) - point) < 1.5
    # the consistent nodal loads add up to the force and the body force over the volume (160 mm^3)
    f = elasticity.load_vector(basis, elasticity.body_force_density(basis, PLA_GRAVITY, [point], [force], None))
    assert f.reshape(-1, 3).sum(axis=0) == pytest.approx(force + PLA_GRAVITY * B * B * L)


def test_the_section_picks_one_limb_and_points_outside_take_the_nearest_tet():
    left, left_tets = box((2.0, 2.0, 8.0))
    right, right_tets = box((2.0, 2.0, 8.0), at=(6.0, 0.0, 0.0))
    nodes = np.concatenate([left, right])
    tets = np.concatenate([left_tets, right_tets + len(left)])
    solution = elastic_solution(nodes, tets, plate_nodes(nodes), load_points=[[1.0, 1.0, 8.0], [7.0, 1.0, 8.0]],
                                load_forces=[[0.0, 0.0, 1.0], [0.0, 0.0, 3.0]])
    both = section_stress(solution, [0.0, 0.0, 4.0], [0, 0, 2])
    assert both.max == pytest.approx(3.0 / 4.0, rel=0.02) and both.where[0] > 5.0
    one = section_stress(solution, [0.0, 0.0, 4.0], [0, 0, 1], near=[0.0, 0.0, 4.5])
    assert (one.points[:, 0] <= 2.0).all() and one.max == pytest.approx(1.0 / 4.0, rel=0.02)
    assert section_normal_stress(solution, [0, 0, 4.0], [0, 0, 1], near=[7.0, 1.0, 4.0], radius=0.5) == \
        pytest.approx(3.0 / 4.0, rel=0.02)
    with pytest.raises(ValueError, match="misses"):
        section_stress(solution, [0.0, 0.0, 9.0], [0, 0, 1])
    outside = stress_at(solution, [[1.0, -3.0, 4.0], [7.0, 1.0, 4.0]])  # 3 mm off the left column, inside the right
    assert outside[:, 2, 2] == pytest.approx([0.25, 0.75], rel=0.02)


def test_nothing_held_or_a_line_held_is_refused(column):
    nodes, tets = column
    with pytest.raises(ValueError, match="no node is fixed"):
        elastic_solution(nodes, tets, np.zeros(len(nodes), bool), body_force=PLA_GRAVITY)
    line = (nodes[:, 0] == 0.0) & (nodes[:, 1] == 0.0)  # one vertical edge: the column could turn about it
    with pytest.raises(ValueError, match="one line"):
        elastic_solution(nodes, tets, line, body_force=PLA_GRAVITY)


def test_plate_nodes_are_the_first_layer():
    nodes = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 1.15], [0.0, 1.0, 1.3], [0.0, 0.0, 5.0]])
    assert plate_nodes(nodes).tolist() == [True, True, False, False]
    assert plate_nodes(nodes, tolerance_mm=0.5).tolist() == [True, True, True, False]


@pytest.mark.parametrize("neighbours", [16, 1])  # 1: most points found by the bounding boxes' fallback
def test_points_are_located_in_the_tetrahedron_skfem_finds(column, neighbours):
    nodes, tets = column
    points = np.random.default_rng(3).uniform([0.1, 0.1, 0.1], [B - 0.1, B - 0.1, L - 0.1], size=(200, 3))
    cells, where = elasticity.locate(nodes, tets, points, neighbours=neighbours)
    finder = skfem.MeshTet(nodes.T.copy(), tets.T.copy()).element_finder()
    assert (cells == finder(*points.T)).all() and (where == points).all()
    outside, moved = elasticity.locate(nodes, tets, [[B + 1.0, 1.0, 5.0]])
    assert moved[0] == pytest.approx([B, 1.0, 5.0])  # onto the nearest face, in the tetrahedron of that face
    assert elasticity.barycentric(nodes, tets, outside, moved).min() >= -1e-9
