"""Joints posed by their whole ancestry: nodes above the skeleton turn, scale and move the rest pose read.

The glTF specification poses a joint by all of its ancestors (the scene graph,
non-joint nodes above the skeleton's root included) and ignores only the
skinned mesh node's own transform and its ancestors:
``v' = Σ_j w_j G_j IBM_j v``. Each file here is a column of three stacked
segments on the joint chain J0 -> J1 -> J2, stored in the skeleton's own frame
(Z-up, centimetres, ... as an exporter leaves it), with the inverse bind
matrices of that frame, and hung under the nodes a test names. The expected
vertices and joints are computed by hand from those nodes, independently of
the reader.
"""

from __future__ import annotations

import numpy as np
import pygltflib
import pytest
from test_gltf import HALF, RINGS, column, pose_and_check, skinned_positions

from supportless.files.gltf import read_gltf_skin
from supportless.files.meshes import read_mesh
from supportless.files.upaxis import guess_up
from supportless.rig.load import load_rig

FLOAT, U16, U32 = 5126, 5123, 5125

#: Sin / cos of 45 degrees: the quaternion of a quarter turn.
H = np.sqrt(0.5)
#: Quaternion (x, y, z, w) of -90 degrees about X: what turns a Z-up export upright (+Y up).
Z_UP_TO_Y_UP = (-H, 0.0, 0.0, H)
#: Joint heights of the chain J0 -> J1 -> J2 along the column (metres, upright).
JOINT_HEIGHTS = (0.0, 0.02, 0.04)


def z_up(X) -> np.ndarray:
    """(n, 3): points of the upright (+Y up) column as a Z-up export stores them: (x, y, z) -> (x, -z, y)."""
    X = np.asarray(X, np.float64)
    return np.column_stack([X[:, 0], -X[:, 2], X[:, 1]])


def stood_up(X) -> np.ndarray:
    """(n, 3): what -90 degrees about X makes of stored points: (x, y, z) -> (x, z, -y)."""
    X = np.asarray(X, np.float64)
    return np.column_stack([X[:, 0], X[:, 2], -X[:, 1]])


def write_skinned_column(path, *, above=(), stored=lambda X: np.asarray(X, np.float64), units=1.0,
                         mesh_node=None, mesh_above=()) -> tuple:
    """Write the three-segment column, skinned, with its skeleton hung under ``above``.

    Parameters
    ----------
    path : Path
        ``.glb``.
    above : sequence of dict
        pygltflib ``Node`` keywords (translation, rotation, scale or matrix), outermost first: a chain of
        non-joint nodes whose last is the skeleton root's parent.
    stored : callable
        (n, 3) float64 upright metres -> (n, 3) float64 as the file stores them (before ``units``).
    units : float
        File units per metre of the stored column (100: centimetres).
    mesh_node : dict, optional
        Keywords of the skinned mesh node's own transform (the specification says to ignore it).
    mesh_above : sequence of dict
        Non-joint nodes above the skinned mesh node, outermost first (ignored as well).

    Returns
    -------
    positions : (24, 3) float64
        The column's vertices as stored.
    joints : (3, 3) float64
        J0, J1, J2 as stored (the skeleton root's parent's frame).
    """
    V, F, ring = column()
    X = stored(V) * units
    P = stored(np.array([[0.0, h, 0.0] for h in JOINT_HEIGHTS])) * units
    blob = bytearray()
    doc = pygltflib.GLTF2(asset=pygltflib.Asset(version="2.0"))

    def accessor(values, component, kind) -> int:
        data = np.ascontiguousarray(values, {FLOAT: np.float32, U16: np.uint16, U32: np.uint32}[component]).tobytes()
        blob.extend(b"\0" * (-len(blob) % 4))
        doc.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(data)))
        blob.extend(data)
        doc.accessors.append(pygltflib.Accessor(bufferView=len(doc.bufferViews) - 1, componentType=component,
                                                count=len(values), type=kind))
        return len(doc.accessors) - 1

    J = np.zeros((len(X), 4), np.int64)
    J[:, 0] = ring // 2
    W = np.zeros((len(X), 4))
    W[:, 0] = 1.0
    attrs = pygltflib.Attributes(POSITION=accessor(X, FLOAT, "VEC3"), JOINTS_0=accessor(J, U16, "VEC4"),
                                 WEIGHTS_0=accessor(W, FLOAT, "VEC4"))
    doc.meshes.append(pygltflib.Mesh(name="Body", primitives=[
        pygltflib.Primitive(attributes=attrs, indices=accessor(F.ravel(), U32, "SCALAR"))]))

    def chain(kinds: list) -> int:
        """Append nodes each the child of the one before; the index of the last (-1 for none)."""
        last = -1
        for kind in kinds:
            doc.nodes.append(pygltflib.Node(**kind))
            if last >= 0:
                doc.nodes[last].children.append(len(doc.nodes) - 1)
            else:
                doc.scenes[0].nodes.append(len(doc.nodes) - 1)
            last = len(doc.nodes) - 1
        return last

    doc.scenes = [pygltflib.Scene(nodes=[])]
    doc.scene = 0
    parent = chain([dict(name=f"Above{k}", **kind) for k, kind in enumerate(above)])
    joints = []
    for k, t in enumerate(np.diff(np.vstack([[0.0, 0.0, 0.0], P]), axis=0)):
        doc.nodes.append(pygltflib.Node(name=f"J{k}", translation=t.tolist()))
        if parent >= 0:
            doc.nodes[parent].children.append(len(doc.nodes) - 1)
        else:
            doc.scenes[0].nodes.append(len(doc.nodes) - 1)
        parent = len(doc.nodes) - 1
        joints.append(parent)
    # vertices in the skeleton's frame: IBM_j = (J_j's transform within it)^-1, a translation
    ibm = np.tile(np.eye(4), (3, 1, 1))
    ibm[:, :3, 3] = -P
    doc.skins.append(pygltflib.Skin(joints=joints, inverseBindMatrices=accessor(
        ibm.transpose(0, 2, 1).reshape(-1, 16), FLOAT, "MAT4")))
    holder = chain([dict(name=f"MeshAbove{k}", **kind) for k, kind in enumerate(mesh_above)])
    doc.nodes.append(pygltflib.Node(name="Body", mesh=0, skin=0, **(mesh_node or {})))
    if holder >= 0:
        doc.nodes[holder].children.append(len(doc.nodes) - 1)
    else:
        doc.scenes[0].nodes.append(len(doc.nodes) - 1)
    blob.extend(b"\0" * (-len(blob) % 4))
    doc.buffers = [pygltflib.Buffer(byteLength=len(blob))]
    doc.set_binary_blob(bytes(blob))
    doc.save_binary(str(path))
    return X, P


def upright_column() -> tuple[np.ndarray, np.ndarray]:
    """The column's vertices (24, 3) and joints (3, 3) upright, in metres: what a viewer shows."""
    V, _, _ = column()
    return V, np.array([[0.0, h, 0.0] for h in JOINT_HEIGHTS])


def assert_read(path, vertices, joints) -> None:
    """The rest pose read is ``vertices`` and ``joints`` (file units), and the skinning formula's."""
    skin = read_gltf_skin(path)
    np.testing.assert_allclose(skin.vertices, vertices, atol=1e-7)
    np.testing.assert_allclose(skin.joint_positions, joints, atol=1e-7)
    np.testing.assert_allclose(skin.vertices, skinned_positions(path), atol=1e-7)


# --------------------------------------------------------------------------- #
# one ancestor per test
# --------------------------------------------------------------------------- #
def test_a_z_up_skeleton_under_a_node_turned_minus_90_about_x_reads_standing(tmp_path):
    path = tmp_path / "zup.glb"
    X, P = write_skinned_column(path, above=[dict(rotation=list(Z_UP_TO_Y_UP))], stored=z_up)
    assert np.ptp(X[:, 2]) == pytest.approx(0.06) and np.ptp(X[:, 1]) == pytest.approx(0.02)  # lying as stored
    V, J = upright_column()
    np.testing.assert_allclose(stood_up(X), V, atol=1e-7)  # the hand computation: (x, y, z) -> (x, z, -y)
    assert_read(path, V, J)
    skin = read_gltf_skin(path)
    np.testing.assert_allclose(np.ptp(skin.vertices, 0), [2 * HALF, RINGS[-1], 2 * HALF], atol=1e-7)  # tall along +Y


def test_a_skeleton_under_a_node_scaled_by_one_hundredth_reads_in_metres(tmp_path):
    path = tmp_path / "cm.glb"
    X, P = write_skinned_column(path, above=[dict(scale=[0.01, 0.01, 0.01])], units=100.0)
    assert np.ptp(X[:, 1]) == pytest.approx(6.0)  # centimetres as stored
    assert_read(path, 0.01 * X, 0.01 * P)
    assert_read(path, *upright_column())


def test_a_skeleton_under_a_translated_node_is_moved_by_it(tmp_path):
    path = tmp_path / "moved.glb"
    t = np.array([0.5, 0.25, -1.0])
    write_skinned_column(path, above=[dict(translation=t.tolist())])
    V, J = upright_column()
    assert_read(path, V + t, J + t)


def test_every_ancestor_counts_as_an_fbx_converter_nests_them(tmp_path):
    """Sketchfab / FBX2glTF: a Z-up root turned upright (a matrix), a centimetre armature scaled 0.01, an offset."""
    path = tmp_path / "nested.glb"
    turn = np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]], np.float64)  # -90 about X
    X, P = write_skinned_column(path, units=100.0, stored=z_up, above=[
        dict(matrix=turn.T.ravel().tolist()),  # column-major, as glTF stores it
        dict(translation=[0.0, 0.0, 0.5]),  # metres in the Z-up frame: 0.5 up once turned
        dict(scale=[0.01, 0.01, 0.01])])
    V, J = upright_column()
    offset = np.array([0.0, 0.5, 0.0])
    np.testing.assert_allclose(stood_up(0.01 * X + [0.0, 0.0, 0.5]), V + offset, atol=1e-7)
    assert_read(path, V + offset, J + offset)


def test_the_skinned_mesh_node_and_its_ancestors_stay_ignored(tmp_path):
    plain, turned = tmp_path / "plain.glb", tmp_path / "mesh-moved.glb"
    write_skinned_column(plain, above=[dict(rotation=list(Z_UP_TO_Y_UP))], stored=z_up)
    write_skinned_column(turned, above=[dict(rotation=list(Z_UP_TO_Y_UP))], stored=z_up,
                         mesh_node=dict(translation=[5.0, 0.0, 0.0], rotation=[0.0, 0.0, H, H], scale=[100.0] * 3),
                         mesh_above=[dict(translation=[-3.0, 2.0, 1.0]), dict(rotation=[H, 0.0, 0.0, H])])
    assert_read(turned, *upright_column())
    np.testing.assert_array_equal(read_gltf_skin(turned).vertices, read_gltf_skin(plain).vertices)


# --------------------------------------------------------------------------- #
# through the loader and back out
# --------------------------------------------------------------------------- #
def test_a_turned_and_scaled_skeleton_loads_standing_in_millimetres_and_poses_back(tmp_path):
    path = tmp_path / "nested.glb"
    write_skinned_column(path, units=100.0, stored=z_up,
                         above=[dict(rotation=list(Z_UP_TO_Y_UP)), dict(scale=[0.01, 0.01, 0.01])])
    rig = load_rig(path, cache_dir=tmp_path / "cache")
    np.testing.assert_allclose([rig.vertices.min(0), rig.vertices.max(0)], [[-10, 0, -10], [10, 60, 10]], atol=1e-4)
    np.testing.assert_allclose(rig.joints[rig.bones[:, 0]], [[0, 0, 0], [0, 20, 0], [0, 40, 0]], atol=1e-4)
    # the posed file, skinned as glTF says, is the rig's pose: the joints' new locals undo the ancestors
    assert pose_and_check(rig, path, tmp_path / "posed.glb", seed=7, spread=0.6) == 24


def test_the_plain_mesh_reader_reads_a_rigged_glb_standing_and_up_stays_plus_y(tmp_path):
    """``--skeleton auto`` and ``slice-check`` read a .glb as a mesh: its skin poses it there, not its bare nodes."""
    path = tmp_path / "zup.glb"
    write_skinned_column(path, above=[dict(rotation=list(Z_UP_TO_Y_UP))], stored=z_up)  # the mesh node at the root
    V, F = read_mesh(path)
    np.testing.assert_allclose([V.min(0), V.max(0)], [[-HALF, 0, -HALF], [HALF, RINGS[-1], HALF]], atol=1e-7)
    assert len(V) == 24 and len(F) == 44
    up, reason = guess_up(V, F, path)
    np.testing.assert_array_equal(up, [0.0, 1.0, 0.0])
    assert reason.startswith("printing direction +Y (as GLB files are written")
