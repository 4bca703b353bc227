"""A rig's tetrahedra posed and placed in the print frame: exactly where the printed surface goes."""

import numpy as np
import pytest
import skfem
from scipy.spatial.transform import Rotation

from supportless.base.geometry import print_pose
from supportless.energies.strength_fem import PLA_GRAVITY, elastic_solution, plate_nodes, section_stress
from supportless.files.printframe import print_frame
from supportless.rig.posed_volume import posed_tet_mesh
from supportless.rig.rig import Rig


@pytest.fixture(scope="module")
def column_rig() -> Rig:
    """A 4 x 20 x 4 column standing along +Y (as an OBJ stands), two bones up its axis, weights blended between.

    Built by hand (no TetGen): skfem's structured tetrahedra, the boundary vertices first (the surface), the
    four inner ones after.
    """
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, 4, 3), np.linspace(0, 20, 6), np.linspace(0, 4, 3))
    surface = np.zeros(mesh.nvertices, bool)
    surface[mesh.boundary_nodes()] = True
    order = np.concatenate([np.flatnonzero(surface), np.flatnonzero(~surface)])
    new = np.empty_like(order)
    new[order] = np.arange(len(order))
    V = mesh.p.T[order]
    faces = new[mesh.facets[:, mesh.boundary_facets()].T]
    upper = np.clip((V[:, 1] - 6.0) / 8.0, 0.0, 1.0)  # bone 2's share rises from y = 6 to y = 14
    joints = np.array([[2.0, 1.0, 2.0], [2.0, 10.0, 2.0], [2.0, 19.0, 2.0]])
    n = int(surface.sum())
    return Rig(V[:n], faces.astype(np.int64), joints, np.array([[0, 1], [1, 2]]), V, new[mesh.t.T].astype(np.int64),
               np.column_stack([1.0 - upper, upper]), np.array([0.0, 1.0, 0.0]), name="column")


def test_the_rest_pose_is_the_rest_tets_scaled_to_the_height_along_z(column_rig):
    nodes, tets = posed_tet_mesh(column_rig, np.zeros((2, 3)), None, height_mm=50.0)
    expected = print_frame(column_rig.vertices, column_rig.up, 50.0).place(column_rig.tet_vertices)
    assert nodes == pytest.approx(expected, abs=1e-9)
    assert nodes[:, 2].min() == pytest.approx(0.0, abs=1e-12) and np.ptp(nodes[:, 2]) == pytest.approx(50.0)
    assert np.ptp(nodes[:, 0]) == pytest.approx(10.0) and np.ptp(nodes[:, 1]) == pytest.approx(10.0)  # 4 x 4, x 2.5
    assert (tets == column_rig.tets).all()


def test_a_posed_and_turned_rig_puts_its_surface_where_the_printed_surface_goes(column_rig):
    angles = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.7]])  # the top bends 40 degrees about z
    R = Rotation.from_euler("xyz", [0.3, -0.2, 0.5]).as_matrix()
    nodes, tets = posed_tet_mesh(column_rig, angles, R, height_mm=60.0)
    n = len(column_rig.vertices)
    frame = print_frame(column_rig.vertices, column_rig.up, 60.0)
    printed = frame.place(print_pose(column_rig.pose(angles), R, column_rig.up))
    assert nodes[:n] == pytest.approx(printed, abs=1e-9)
    # the inner vertices follow the same map: blend the bones' transforms by hand, then the surface's affine map
    T = column_rig.transforms(angles)  # (m, 3, 4)
    Vh = np.column_stack([column_rig.tet_vertices, np.ones(len(column_rig.tet_vertices))])
    skinned = np.einsum("tm,mdk,tk->td", column_rig.tet_weights, T, Vh)
    A, *_ = np.linalg.lstsq(np.column_stack([skinned[:n], np.ones(n)]), nodes[:n], rcond=None)
    assert nodes[n:] == pytest.approx(np.column_stack([skinned[n:], np.ones(len(skinned) - n)]) @ A, abs=1e-9)
    # posing keeps every tetrahedron right side out
    def signed(P):
        return np.linalg.det(P[tets[:, 1:]] - P[tets[:, :1]])
    assert (np.sign(signed(nodes)) == np.sign(signed(column_rig.tet_vertices)) * np.sign(np.linalg.det(R))).all()


def test_a_posed_rig_stands_on_the_plate_and_carries_its_weight(column_rig):
    nodes, tets = posed_tet_mesh(column_rig, np.zeros((2, 3)), None, height_mm=40.0)  # 8 x 8 x 40 mm
    solution = elastic_solution(nodes, tets, plate_nodes(nodes), body_force=PLA_GRAVITY)
    centre = nodes[:, :2].mean(axis=0)
    section = section_stress(solution, [*centre, 20.0], [0, 0, 1])
    # the half above weighs rho g 20 mm per mm^2 of section
    assert np.median(section.normal_stress) == pytest.approx(PLA_GRAVITY[2] * 20.0, rel=0.05)


def test_a_prepared_rig_poses_its_tetrahedra_with_its_surface(branch_rig):
    angles = np.zeros((branch_rig.bone_count, 3))
    angles[-1] = [0.4, 0.0, 0.3]
    nodes, tets = posed_tet_mesh(branch_rig, angles, None, height_mm=60.0)
    printed = print_frame(branch_rig.vertices, branch_rig.up, 60.0).place(branch_rig.pose(angles))
    assert nodes[: len(branch_rig.vertices)] == pytest.approx(printed, abs=1e-9)
    assert nodes[:, 2].min() > -0.5 and len(tets) == len(branch_rig.tets)
