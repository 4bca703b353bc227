"""Rigged glTF/GLB input (supportless.files.gltf, supportless.rig.load.load_rig) on small synthetic files, one per mess.

Every file is written here with pygltflib: a column of three stacked segments
along +Y (20 x 60 x 20 mm once read, the file's metres becoming millimetres),
each segment weighted to one joint of a chain J0 -> J1 -> J2, plus whatever a
test needs on top (seams, extra parts, a rigid part, helper joints, ...). The
posed files are checked against the glTF skinning formula evaluated here,
independently of the package's own accessor reader.
"""

from __future__ import annotations

import base64
import copy
import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import igl
import numpy as np
import pygltflib
import pytest
from click.testing import CliRunner
from meshes import box
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

import supportless as sl
from supportless.apps.cli import main
from supportless.base.errors import InputError
from supportless.base.geometry import signed_volume
from supportless.copyleft.cgal import intersecting_face_pairs
from supportless.files.gltf import posed_joint_transforms, read_gltf_skin, write_posed_gltf
from supportless.files.joints import skeleton_from_joints
from supportless.files.meshes import check_closed_surface
from supportless.files.printbody import WINDING_CELLS, print_body
from supportless.rig.load import load_rig
from supportless.search.settings import SearchSettings, resolve_fixed_bones

FLOAT, U8, U16, U32 = 5126, 5121, 5123, 5125

#: Half the width of the column (metres).
HALF = 0.01
#: Heights of the column's vertex rings (metres); ring r is weighted to joint r // 2.
RINGS = (0.0, 0.018, 0.022, 0.038, 0.042, 0.06)
#: Height of the column once read (millimetres).
HEIGHT_MM = 60.0


# --------------------------------------------------------------------------- #
# writing small glTF assets
# --------------------------------------------------------------------------- #
@dataclass
class Node:
    """One node of a synthetic asset (names are unique; ``parent`` is a name)."""

    name: str
    parent: str | None = None
    translation: tuple = (0.0, 0.0, 0.0)
    rotation: tuple = (0.0, 0.0, 0.0, 1.0)
    mesh: int | None = None
    skin: bool = False


@dataclass
class Prim:
    """One triangle primitive: positions (n, 3), faces (f, 3), and joints/weights (n, 4) when skinned."""

    positions: np.ndarray
    faces: np.ndarray
    joints: np.ndarray | None = None
    weights: np.ndarray | None = None


@dataclass
class Asset:
    """A synthetic rigged asset: nodes, meshes (lists of primitives) and the skin's joints (node names)."""

    nodes: list
    meshes: list
    skin: list
    notes: dict = field(default_factory=dict)

    def index(self, name: str) -> int:
        """The node index of a name."""
        return [n.name for n in self.nodes].index(name)


def _trs(node: Node) -> np.ndarray:
    """(4, 4) local transform of a :class:`Node`."""
    M = np.eye(4)
    M[:3, :3] = Rotation.from_quat(node.rotation).as_matrix()
    M[:3, 3] = node.translation
    return M


def asset_globals(asset: Asset) -> np.ndarray:
    """(N, 4, 4) global transforms of an asset's nodes as described (parents before children not required)."""
    out = {}

    def get(name):
        if name not in out:
            node = asset.nodes[asset.index(name)]
            out[name] = _trs(node) if node.parent is None else get(node.parent) @ _trs(node)
        return out[name]

    return np.array([get(n.name) for n in asset.nodes])


def write_gltf(asset: Asset, path, *, weights_type=FLOAT, joints_type=U16, sparse_rows=None, pose=None,
               extensions_used=(), extensions_required=(), with_skin=True, external_bin=False,
               materials=1, inverse_bind=True) -> Path:
    """Write a synthetic asset with pygltflib.

    Parameters
    ----------
    asset : Asset
    path : Path
        ``.glb`` (binary chunk) or ``.gltf`` (data URI, or an external ``.bin``
        with ``external_bin``).
    weights_type : int
        Component type of WEIGHTS_0: FLOAT, or normalised U8/U16 (each row
        rounded so that it sums to exactly the maximum).
    joints_type : int
        Component type of JOINTS_0 (U8 or U16).
    sparse_rows : array_like of int, optional
        Rows of the first primitive's POSITION written wrong in the dense data
        and substituted with the right values by a sparse accessor.
    pose : dict, optional
        ``{node name: quaternion}``: node rotations of the default pose, set
        after the inverse bind matrices are computed from the described pose.
    extensions_used, extensions_required : sequence of str
    with_skin : bool
        False: no skin at all (the mesh nodes are plain meshes).
    external_bin : bool
    materials : int
        How many (trivial) materials to write; every primitive uses the first.
    inverse_bind : bool
        False: the skin has no inverseBindMatrices (identity, by the spec).

    Returns
    -------
    path : Path
    """
    path = Path(path)
    blob = bytearray()
    doc = pygltflib.GLTF2(asset=pygltflib.Asset(version="2.0", generator="supportless tests"))

    def view(data: bytes) -> int:
        while len(blob) % 4:
            blob.append(0)
        doc.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(data)))
        blob.extend(data)
        return len(doc.bufferViews) - 1

    def accessor(values, component, kind, normalized=False, sparse=None) -> int:
        dtype = {FLOAT: np.float32, U8: np.uint8, U16: np.uint16, U32: np.uint32}[component]
        values = np.ascontiguousarray(values, dtype)
        acc = pygltflib.Accessor(bufferView=view(values.tobytes()), componentType=component, count=len(values),
                                 type=kind, normalized=normalized or None)
        if kind == "VEC3" and component == FLOAT:
            acc.min = values.min(0).astype(float).tolist()
            acc.max = values.max(0).astype(float).tolist()
        if sparse is not None:
            rows, good = sparse
            acc.sparse = pygltflib.Sparse(
                count=len(rows),
                indices=pygltflib.AccessorSparseIndices(bufferView=view(np.asarray(rows, np.uint16).tobytes()),
                                                        componentType=U16),
                values=pygltflib.AccessorSparseValues(bufferView=view(np.asarray(good, dtype).tobytes())))
        doc.accessors.append(acc)
        return len(doc.accessors) - 1

    nodes = [copy.copy(n) for n in asset.nodes]
    G = asset_globals(asset)
    for n in nodes:
        if pose and n.name in pose:
            n.rotation = tuple(pose[n.name])
    # the mesh node of the skin: the first skinned node; IBM_j = G_j^-1 G_mesh in the described (bind) pose
    skinned = [i for i, n in enumerate(nodes) if n.skin]
    mesh_global = G[skinned[0]] if skinned else np.eye(4)
    joint_ids = [asset.index(j) for j in asset.skin]
    for m, prims in enumerate(asset.meshes):
        out = []
        for p_idx, prim in enumerate(prims):
            X = np.asarray(prim.positions, np.float64)
            sparse = None
            if sparse_rows is not None and m == 0 and p_idx == 0:
                rows = np.asarray(sparse_rows)
                sparse = (rows, X[rows].astype(np.float32))
                X = X.copy()
                X[rows] += [0.5, -0.25, 0.125]  # wrong unless the substitution is applied
            attrs = pygltflib.Attributes(POSITION=accessor(X, FLOAT, "VEC3", sparse=sparse))
            if prim.joints is not None and with_skin:
                attrs.JOINTS_0 = accessor(prim.joints, joints_type, "VEC4")
                attrs.WEIGHTS_0 = accessor(quantise(prim.weights, weights_type), weights_type, "VEC4",
                                           normalized=weights_type != FLOAT)
            out.append(pygltflib.Primitive(attributes=attrs, indices=accessor(np.ravel(prim.faces), U32, "SCALAR"),
                                           material=0 if materials else None))
        doc.meshes.append(pygltflib.Mesh(name=f"mesh{m}" if m else "Body", primitives=out))
    for k in range(materials):
        doc.materials.append(pygltflib.Material(name=f"material{k}"))
    if with_skin:
        ibm = np.array([np.linalg.inv(G[j]) @ mesh_global for j in joint_ids])
        doc.skins.append(pygltflib.Skin(joints=joint_ids, name="Armature",
                                        inverseBindMatrices=accessor(ibm.transpose(0, 2, 1).reshape(-1, 16), FLOAT,
                                                                     "MAT4") if inverse_bind else None))
    for n in nodes:
        doc.nodes.append(pygltflib.Node(name=n.name, mesh=n.mesh, skin=0 if (n.skin and with_skin) else None,
                                        translation=list(map(float, n.translation)),
                                        rotation=list(map(float, n.rotation))))
    for i, n in enumerate(nodes):
        if n.parent is not None:
            doc.nodes[asset.index(n.parent)].children.append(i)
    doc.scenes = [pygltflib.Scene(nodes=[i for i, n in enumerate(nodes) if n.parent is None])]
    doc.scene = 0
    doc.extensionsUsed = list(extensions_used)
    doc.extensionsRequired = list(extensions_required)
    while len(blob) % 4:
        blob.append(0)
    if path.suffix == ".glb":
        doc.buffers = [pygltflib.Buffer(byteLength=len(blob))]
        doc.set_binary_blob(bytes(blob))
        doc.save_binary(str(path))
    else:
        if external_bin:
            bin_path = path.with_suffix(".bin")
            bin_path.write_bytes(bytes(blob))
            uri = bin_path.name
        else:
            uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()
        doc.buffers = [pygltflib.Buffer(byteLength=len(blob), uri=uri)]
        doc.save_json(str(path))
    return path


def quantise(weights: np.ndarray, component: int) -> np.ndarray:
    """Weights in a component type: floats as they are, U8/U16 rows rounded to sum exactly to 255/65535.

    Largest-remainder rounding, so that each entry is within one step of the float.
    """
    W = np.asarray(weights, np.float64)
    if component == FLOAT:
        return W
    top = {U8: 255, U16: 65535}[component]
    scaled = W / W.sum(1, keepdims=True) * top
    out = np.floor(scaled).astype(np.int64)
    short = top - out.sum(1)
    order = np.argsort(-(scaled - out), axis=1)
    for i, k in enumerate(short):
        out[i, order[i, :k]] += 1
    return out


def column():
    """The column's closed surface: (V (24, 3), F (44, 3) outward, ring (24,) of each vertex)."""
    corners = [(-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF)]
    V = np.array([(x, y, z) for y in RINGS for x, z in corners])
    ring = np.repeat(np.arange(len(RINGS)), 4)
    F = []
    for r in range(len(RINGS) - 1):
        for c in range(4):
            a, b = 4 * r + c, 4 * r + (c + 1) % 4
            F += [(a, b, b + 4), (a, b + 4, a + 4)]
    top = 4 * (len(RINGS) - 1)
    F += [(0, 1, 2), (0, 2, 3), (top, top + 1, top + 2), (top, top + 2, top + 3)]
    F = np.array(F)
    # orient outward: sides away from the axis, caps along -y / +y
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    c = V[F].mean(1)
    out = np.where(np.abs(n[:, 1])[:, None] > 1e-12, np.sign(c[:, 1] - 0.03)[:, None] * [0, 1, 0],
                   c * [1, 0, 1])
    flip = np.einsum("ij,ij->i", n, out) < 0
    F[flip] = F[flip][:, ::-1]
    return V, F, ring


def one_hot(n: int, joint: int):
    """(joints, weights), both (n, 4): every vertex fully on ``joint``."""
    J = np.zeros((n, 4), np.int64)
    J[:, 0] = joint
    W = np.zeros((n, 4))
    W[:, 0] = 1.0
    return J, W


def box_prim(lo, hi, joint: int | None) -> Prim:
    """A closed box primitive, weighted fully to skin joint index ``joint`` (None: not skinned)."""
    V, F = box(lo, hi)
    J, W = one_hot(len(V), joint) if joint is not None else (None, None)
    return Prim(V, F, J, W)


def seam_split(prim: Prim) -> Prim:
    """The same primitive with its own three vertices per face (as at texture seams)."""
    F = np.asarray(prim.faces)
    return Prim(prim.positions[F].reshape(-1, 3), np.arange(F.size).reshape(-1, 3),
                None if prim.joints is None else prim.joints[F].reshape(-1, 4),
                None if prim.weights is None else prim.weights[F].reshape(-1, 4))


def character(*, helpers=False, root_below=False, rigid_hat=False, extra_parts=False, z_up=False,
              split=False, weights=None) -> Asset:
    """The synthetic character: a column of three segments on the joint chain J0 -> J1 -> J2.

    Parameters
    ----------
    helpers : bool
        Two unweighted root joints above J0 (RootA -> RootB), an unweighted IK
        target joint and a ``J2_end`` leaf referenced with zero weight.
    root_below : bool
        J0 a third of the height below the floor (outside the skin).
    rigid_hat : bool
        A box mesh node (not skinned) under J2, overlapping the column's top.
    extra_parts : bool
        A second primitive (an arm on J2) in the body mesh, and a second
        skinned mesh node (an arm on J1).
    z_up : bool
        Everything stored Z-up under a root node turned -90 degrees about X.
    split : bool
        Seam-split the column (three vertices of its own per face).
    weights : (joints (24, 4), weights (24, 4)), optional
        The column's weights over the skin joints J0, J1, J2 (default: ring r on joint r // 2).

    Returns
    -------
    asset : Asset
    """
    V, F, ring = column()
    J, W = weights if weights is not None else one_hot(len(V), 0)
    if weights is None:
        J[:, 0] = ring // 2
    skin = ["J0", "J1", "J2"]
    nodes = [Node("Armature"), Node("Body", "Armature", mesh=0, skin=True)]
    y0 = -0.02 if root_below else 0.0
    if helpers:
        nodes += [Node("RootA", "Armature", (0, -0.01, 0)), Node("RootB", "RootA", (0, 0.004, 0)),
                  Node("J0", "RootB", (0, y0 + 0.006, 0)), Node("IK_target", "RootA", (0.04, 0.05, 0.0))]
    else:
        nodes += [Node("J0", "Armature", (0, y0, 0))]
    nodes += [Node("J1", "J0", (0, 0.02 - y0, 0)), Node("J2", "J1", (0, 0.02, 0))]
    if helpers:
        nodes.append(Node("J2_end", "J2", (0, 0.02, 0)))
        skin = ["RootA", "RootB", "J0", "J1", "J2", "IK_target", "J2_end"]
        J = J + 2  # J0 is skin joint 2 now
        J[:, 1] = 6  # the *_end leaf is referenced, with zero weight
        W = W.copy()
        W[:, 1] = 0.0
    body = Prim(V, F, J, W)
    meshes = [[seam_split(body) if split else body]]
    first = 2 if helpers else 0
    if extra_parts:
        meshes[0].append(box_prim((0.005, 0.045, -0.005), (0.03, 0.055, 0.005), first + 2))
        meshes.append([box_prim((-0.03, 0.025, -0.005), (-0.005, 0.035, 0.005), first + 1)])
        nodes.append(Node("Left", "Armature", mesh=len(meshes) - 1, skin=True))
    if rigid_hat:
        meshes.append([box_prim((-0.005, 0.005, -0.005), (0.005, 0.02, 0.005), None)])
        nodes.append(Node("Hat", "J2", (0, 0.01, 0), mesh=len(meshes) - 1))
    asset = Asset(nodes, meshes, skin)
    if z_up:  # stored Z-up: positions and translations R^-1 x, the root turns them upright
        R = Rotation.from_euler("x", -90, degrees=True)
        for n in asset.nodes[1:]:
            n.translation = tuple(R.inv().apply(n.translation))
        asset.nodes[0].rotation = tuple(R.as_quat())
        for prims in asset.meshes:
            for p in prims:
                p.positions = R.inv().apply(p.positions)
    return asset


# --------------------------------------------------------------------------- #
# reading the written files back, independently of supportless.files.gltf
# --------------------------------------------------------------------------- #
def _blob(doc, path: Path) -> bytes:
    """The bytes of buffer 0 of a pygltflib document (GLB chunk or data URI)."""
    uri = doc.buffers[0].uri
    if uri is None:
        return doc.binary_blob()
    if uri.startswith("data:"):
        return base64.b64decode(uri.split(",", 1)[1])
    return (path.parent / uri).read_bytes()


def _values(doc, blob: bytes, index: int) -> np.ndarray:
    """(count, width) float64 values of a dense accessor (normalised integers mapped to [0, 1])."""
    acc = doc.accessors[index]
    assert acc.sparse is None
    view = doc.bufferViews[acc.bufferView]
    dtype = np.dtype({5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32,
                      5126: np.float32}[acc.componentType])
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[acc.type]
    stride = view.byteStride or dtype.itemsize * width
    X = np.ndarray((acc.count, width), dtype, buffer=blob, offset=(view.byteOffset or 0) + (acc.byteOffset or 0),
                   strides=(stride, dtype.itemsize)).astype(np.float64)
    if acc.normalized:
        X /= {5121: 255.0, 5123: 65535.0}[acc.componentType]
    return X


def glb_json(path) -> dict:
    """The JSON chunk of a .glb file (quicker than a full pygltflib load)."""
    data = Path(path).read_bytes()
    length = int.from_bytes(data[12:16], "little")
    assert data[:4] == b"glTF" and data[16:20] == b"JSON"
    return json.loads(data[20:20 + length])


def _node_globals(doc) -> np.ndarray:
    """(N, 4, 4) global transforms of a pygltflib document's nodes."""
    parent = {c: i for i, n in enumerate(doc.nodes) for c in (n.children or [])}

    def local(n):
        if n.matrix is not None:
            return np.asarray(n.matrix, float).reshape(4, 4).T
        M = np.eye(4)
        M[:3, :3] = Rotation.from_quat(n.rotation or (0, 0, 0, 1)).as_matrix() @ np.diag(n.scale or (1, 1, 1))
        M[:3, 3] = n.translation or (0, 0, 0)
        return M

    def glob(i):
        return local(doc.nodes[i]) if i not in parent else glob(parent[i]) @ local(doc.nodes[i])

    return np.array([glob(i) for i in range(len(doc.nodes))])


def skinned_positions(path, normalise: bool = False, doc=None) -> np.ndarray:
    """All vertices of a glTF file as its nodes pose them: ``Σ w_j G_j IBM_j v``, rigid meshes ``G_node v``.

    Nodes in file order, primitives in mesh order (the order of
    :attr:`supportless.files.gltf.GltfSkin.vertices`). With ``normalise``, each
    vertex's weights are divided by their sum first (as three.js does).
    ``doc`` is the file already loaded with pygltflib, if it is.
    """
    path = Path(path)
    doc = doc if doc is not None else pygltflib.GLTF2().load(str(path))
    blob = _blob(doc, path)
    G = _node_globals(doc)
    out = []
    for i, node in enumerate(doc.nodes):
        if node.mesh is None:
            continue
        for prim in doc.meshes[node.mesh].primitives:
            X = _values(doc, blob, prim.attributes.POSITION)
            Xh = np.column_stack([X, np.ones(len(X))])
            if node.skin is None:
                out.append(Xh @ G[i].T[:, :3])
                continue
            skin = doc.skins[node.skin]
            ibm = (np.tile(np.eye(4), (len(skin.joints), 1, 1)) if skin.inverseBindMatrices is None  # the spec's default
                   else _values(doc, blob, skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1))
            M = np.array([G[j] for j in skin.joints]) @ ibm
            Y, total = np.zeros((len(X), 3)), np.zeros((len(X), 1))
            for js, ws in (("JOINTS_0", "WEIGHTS_0"), ("JOINTS_1", "WEIGHTS_1")):
                ja, wa = getattr(prim.attributes, js, None), getattr(prim.attributes, ws, None)
                if ja is None:
                    continue
                jv, wv = _values(doc, blob, ja).astype(np.int64), _values(doc, blob, wa)
                for k in range(jv.shape[1]):
                    Y += wv[:, k, None] * np.einsum("nij,nj->ni", M[jv[:, k]], Xh)[:, :3]
                total += wv.sum(1, keepdims=True)
            out.append(Y / total if normalise else Y)
    return np.vstack(out)


def check_posed_file(rig, written, angles, source_path, normalise: bool = False, skin=None, doc=None) -> int:
    """Check a posed file against ``rig.pose(angles)`` at every source vertex that lies on the print body.

    A position shared by source vertices of different weights (two rigid
    parts meeting) has a single weight on the body and is left out. ``skin``
    (of the source) and ``doc`` (the written file) save reading them again.

    Returns how many vertices were compared.
    """
    scale = rig.info["gltf"]["scale"]
    skin = skin if skin is not None else read_gltf_skin(source_path)
    bind = skin.vertices * scale
    posed = skinned_positions(written, normalise, doc) * scale
    assert posed.shape == bind.shape
    height = float(np.ptp(rig.vertices[:, 1]))
    tol = 1e-6 * height
    dist, idx = cKDTree(rig.vertices).query(bind)
    pairs = cKDTree(bind).query_pairs(tol, output_type="ndarray").reshape(-1, 2)
    differ = np.abs(skin.weights[pairs[:, 0]] - skin.weights[pairs[:, 1]]).max(1, initial=0) > 1e-6
    ambiguous = np.zeros(len(bind), bool)
    ambiguous[pairs[differ].ravel()] = True
    on = (dist <= tol) & ~ambiguous
    np.testing.assert_allclose(posed[on], rig.pose(angles)[idx[on]], rtol=0, atol=1e-5 * height)
    return int(on.sum())


def pose_and_check(rig, source_path, out, seed: int, spread: float) -> int:
    """Write ``source_path`` posed by random angles (uniform in ±``spread`` rad, generator ``seed``) to ``out``.

    The joints get the rig's transforms (:func:`posed_joint_transforms`); returns :func:`check_posed_file` of
    the written file against ``rig.pose`` of those angles (how many vertices were compared).
    """
    source = rig.info["gltf"]
    angles = np.random.default_rng(seed).uniform(-spread, spread, (rig.bone_count, 3))
    write_posed_gltf(source_path, out, posed_joint_transforms(rig.transforms(angles), source["driver"],
                                                              source["scale"]), source["joint_nodes"])
    return check_posed_file(rig, out, angles, source_path)


def check_posed_surface(rig, written, angles, skin, doc, normalise: bool = True) -> float:
    """Check a posed file against ``rig.pose(angles)`` where the print body was remade (no shared vertices).

    Source vertices within a grid cell of the rest body must, posed by the
    file's skin, lie within two cells of the posed body. Returns the fraction
    of source vertices compared.
    """
    import igl

    scale = rig.info["gltf"]["scale"]
    cell = float(np.ptp(rig.vertices, axis=0).max()) / WINDING_CELLS
    rest = skin.vertices * scale
    near = np.sqrt(igl.point_mesh_squared_distance(rest, rig.vertices, rig.faces)[0]) < cell
    posed = skinned_positions(written, normalise, doc)[near] * scale
    gap = np.sqrt(igl.point_mesh_squared_distance(posed, rig.pose(angles), rig.faces)[0])
    assert np.quantile(gap, 0.99) < 2 * cell, np.quantile(gap, [0.5, 0.99, 1.0])
    return float(near.mean())


# --------------------------------------------------------------------------- #
# fixtures
# --------------------------------------------------------------------------- #
@pytest.fixture
def cache(tmp_path) -> Path:
    """A rig cache folder private to the test."""
    return tmp_path / "cache"


def load(path, cache, **kwargs):
    """``load_rig`` of a synthetic file into the test's cache."""
    return load_rig(path, cache_dir=cache, **kwargs)


def column_rig(cache, tmp_path):
    """The plain column as a .glb, loaded."""
    return load(write_gltf(character(), tmp_path / "column.glb"), cache)


def body_extent(rig) -> np.ndarray:
    """(2, 3): the print body's lowest and highest corner."""
    return np.array([rig.vertices.min(0), rig.vertices.max(0)])


def column_extent(top=HEIGHT_MM) -> np.ndarray:
    """(2, 3): the column's box in millimetres."""
    return np.array([[-10.0, 0.0, -10.0], [10.0, top, 10.0]])


# --------------------------------------------------------------------------- #
# one mess per test
# --------------------------------------------------------------------------- #
def test_plain_column_reads_in_millimetres_with_bones_on_the_joints(tmp_path, cache):
    rig = column_rig(cache, tmp_path)
    np.testing.assert_allclose(body_extent(rig), column_extent(), atol=1e-5)
    assert rig.bone_count == 3 and rig.labels == ["J0", "J1", "J2"]
    np.testing.assert_allclose(rig.joints[rig.bones[:2, 0]], [[0, 0, 0], [0, 20, 0]], atol=1e-5)
    # every column vertex carries the joint of its ring, in millimetres
    dominant = np.argmax(rig.weights, axis=1)
    np.testing.assert_array_equal(dominant, np.searchsorted([20, 40], rig.vertices[:, 1]))
    assert signed_volume(rig.vertices, rig.faces) == pytest.approx(20 * 60 * 20, rel=1e-5)
    assert rig.info["gltf"]["scale"] == 1000.0


def test_seam_split_vertices_are_welded_into_a_closed_body(tmp_path, cache):
    asset = character(split=True)
    path = write_gltf(asset, tmp_path / "split.glb")
    skin = read_gltf_skin(path)
    assert len(skin.vertices) == 3 * 44  # as stored: three per face
    rig = load(path, cache)
    check_closed_surface(rig.faces)
    assert len(rig.vertices) == 24  # the column's unique positions
    assert len(np.unique(np.round(rig.vertices, 6), axis=0)) == 24
    assert len(rig.faces) == 44
    assert any("welded 108 seam-split vertices" in line for line in rig.info["gltf"]["log"])
    np.testing.assert_allclose(body_extent(rig), column_extent(), atol=1e-5)


def test_every_primitive_and_mesh_node_is_in_the_body(tmp_path, cache):
    path = write_gltf(character(extra_parts=True), tmp_path / "parts.glb")
    skin = read_gltf_skin(path)
    assert skin.part_names == ["Body#0", "Body#1", "mesh1"]
    rig = load(path, cache)
    check_closed_surface(rig.faces)
    # the right arm (primitive 2 of the body mesh) reaches x = 30, the left arm (a second node) x = -30
    np.testing.assert_allclose(body_extent(rig), [[-30, 0, -10], [30, 60, 10]], atol=1e-5)
    column_v, arm_outside = 20 * 60 * 20, 20 * 10 * 10
    assert signed_volume(rig.vertices, rig.faces) == pytest.approx(column_v + 2 * arm_outside, rel=1e-5)
    # the arms carry the weights of their joints: the right arm J2, the left arm J1
    right = rig.vertices[:, 0] > 10 + 1e-6
    left = rig.vertices[:, 0] < -10 - 1e-6
    assert right.sum() == 4 and left.sum() == 4  # the far ends of the arms
    np.testing.assert_allclose(rig.weights[right], np.tile([0, 0, 1], (right.sum(), 1)), atol=1e-9)
    np.testing.assert_allclose(rig.weights[left], np.tile([0, 1, 0], (left.sum(), 1)), atol=1e-9)


def test_a_body_split_into_open_primitives_along_a_seam_is_one_closed_body(tmp_path, cache):
    V, F, ring = column()
    J, W = one_hot(len(V), 0)
    J[:, 0] = ring // 2
    asset = character()
    halves = []
    for mask in (ring[F].min(1) < 3, ring[F].min(1) >= 3):  # two materials meeting at ring 3: two open tubes
        used = np.unique(F[mask])
        remap = np.full(len(V), -1)
        remap[used] = np.arange(len(used))
        halves.append(Prim(V[used], remap[F[mask]], J[used], W[used]))
    asset.meshes[0] = halves
    rig = load(write_gltf(asset, tmp_path / "halves.glb"), cache)
    check_closed_surface(rig.faces)
    assert len(rig.vertices) == 24  # the two caps at the seam cancel in the union
    assert signed_volume(rig.vertices, rig.faces) == pytest.approx(20 * 60 * 20, rel=1e-5)
    assert any("closed 2 holes in 2 open shells" in x for x in rig.info["gltf"]["log"])


def test_a_z_up_scene_turned_by_a_node_stands_upright(tmp_path, cache):
    upright = load(write_gltf(character(), tmp_path / "yup.glb"), cache)
    turned = load(write_gltf(character(z_up=True), tmp_path / "zup.gltf"), cache)
    stored = read_gltf_skin(tmp_path / "zup.gltf")
    assert np.ptp(stored.vertices[:, 1]) == pytest.approx(0.06, rel=1e-6)  # read through the root's rotation
    np.testing.assert_allclose(body_extent(turned), column_extent(), atol=1e-5)
    np.testing.assert_allclose(np.sort(turned.vertices, axis=0), np.sort(upright.vertices, axis=0), atol=1e-5)
    np.testing.assert_allclose(turned.joints[turned.bones[:, 0]], upright.joints[upright.bones[:, 0]], atol=1e-5)


def test_a_rigid_part_under_a_joint_is_weighted_to_it_and_follows_it(tmp_path, cache):
    path = write_gltf(character(rigid_hat=True), tmp_path / "hat.glb")
    skin = read_gltf_skin(path)
    hat = np.unique(skin.faces[skin.part == skin.part_names.index("mesh1")])
    assert len(hat) == 8
    np.testing.assert_array_equal(skin.weights[hat], np.tile([0.0, 0.0, 1.0], (8, 1)))
    # placed where the bind pose puts J2 (y = 0.04) plus the node's own 0.01
    np.testing.assert_allclose(skin.vertices[hat, 1].min(), 0.055, atol=1e-7)
    np.testing.assert_allclose(skin.vertices[hat, 1].max(), 0.07, atol=1e-7)
    rig = load(path, cache)
    check_closed_surface(rig.faces)
    top = rig.vertices[:, 1] > HEIGHT_MM + 1e-6
    assert top.sum() >= 4
    np.testing.assert_allclose(rig.weights[top], np.tile([0, 0, 1], (top.sum(), 1)), atol=1e-9)
    angles = np.random.default_rng(1).uniform(-0.7, 0.7, (rig.bone_count, 3))
    T = rig.transforms(angles)
    np.testing.assert_allclose(rig.pose(angles)[top], rig.vertices[top] @ T[2, :, :3].T + T[2, :, 3], atol=1e-9)
    # the written asset moves the hat's node with J2
    out = tmp_path / "posed.glb"
    source = rig.info["gltf"]
    write_posed_gltf(path, out, posed_joint_transforms(T, source["driver"], source["scale"]), source["joint_nodes"])
    posed = skinned_positions(out) * source["scale"]
    np.testing.assert_allclose(posed[hat], skin.vertices[hat] * source["scale"] @ T[2, :, :3].T + T[2, :, 3],
                               atol=1e-6)
    assert check_posed_file(rig, out, angles, path) >= 24


def test_weights_that_do_not_sum_to_one_are_normalised_and_said(tmp_path, cache):
    V, _, ring = column()
    J, W = one_hot(len(V), 0)
    J[:, 0] = ring // 2
    J[:, 1] = np.minimum(ring // 2 + 1, 2)
    W[:, 0], W[:, 1] = 1.4, 0.35  # sums to 1.75, as FBX2glTF writes
    path = write_gltf(character(weights=(J, W)), tmp_path / "heavy.glb")
    skin = read_gltf_skin(path)
    np.testing.assert_allclose(skin.weights.sum(1), 1.0, atol=1e-12)
    expected = np.zeros((len(V), 3))
    np.add.at(expected, (np.arange(len(V)), J[:, 0]), 0.8)
    np.add.at(expected, (np.arange(len(V)), J[:, 1]), 0.2)
    np.testing.assert_allclose(skin.weights, expected, atol=1e-6)
    note = [n for n in skin.notes if "did not sum to 1" in n]
    assert note == ["skin weights of 24 vertices did not sum to 1 (up to 1.75); normalised"]
    rig = load(path, cache)
    np.testing.assert_allclose(rig.weights.sum(1), 1.0, atol=1e-12)
    assert any("did not sum to 1" in line for line in rig.info["gltf"]["log"])


def test_helper_joints_and_unweighted_roots_are_pruned(tmp_path, cache):
    path = write_gltf(character(helpers=True), tmp_path / "helpers.glb")
    skin = read_gltf_skin(path)
    assert skin.joint_names == ["RootA", "RootB", "J0", "J1", "J2", "IK_target", "J2_end"]
    sk = skeleton_from_joints(skin.joint_positions, skin.joint_parents, skin.weights, skin.joint_names, skin.vertices)
    assert sorted(sk.pruned) == sorted(["RootA", "RootB", "IK_target", "J2_end"])
    assert sk.names == ["J0", "J1", "J2"]
    np.testing.assert_array_equal(sk.joint_of[:3], [2, 3, 4])
    rig = load(path, cache)
    assert rig.labels == ["J0", "J1", "J2"]
    np.testing.assert_allclose(rig.joints[rig.bones[:2, 0]], [[0, 0, 0], [0, 20, 0]], atol=1e-5)
    assert any("pruned 4 without weight" in line for line in rig.info["gltf"]["log"])
    # the pruned joints still follow the bones when the asset is posed: J2_end with J2, the roots stay
    angles = np.random.default_rng(2).uniform(-0.5, 0.5, (3, 3))
    T = posed_joint_transforms(rig.transforms(angles), rig.info["gltf"]["driver"], rig.info["gltf"]["scale"])
    np.testing.assert_allclose(T[6], T[4])
    np.testing.assert_allclose(T[[0, 1, 5]], np.tile(np.eye(4), (3, 1, 1)))


def test_a_weighted_joint_outside_the_skin_is_only_a_pivot(tmp_path, cache):
    rig = load(write_gltf(character(root_below=True), tmp_path / "below.glb"), cache)
    check_closed_surface(rig.faces)
    np.testing.assert_allclose(body_extent(rig), column_extent(), atol=1e-5)
    # J0 stays a third of the height below the floor: not pulled inside as a TGF joint would be
    np.testing.assert_allclose(rig.joints[rig.bones[0]], [[0, -20, 0], [0, 20, 0]], atol=1e-5)
    angles = np.zeros((3, 3))
    angles[0, 2] = 0.3
    posed = rig.pose(angles)
    centre = np.array([0.0, -20.0, 0.0])  # the whole body turns about the joint below the floor
    np.testing.assert_allclose(np.linalg.norm(posed - centre, axis=1), np.linalg.norm(rig.vertices - centre, axis=1),
                               atol=1e-9)


def test_a_sparse_position_accessor_is_substituted(tmp_path, cache):
    rows = [0, 5, 6, 13, 23]
    dense = write_gltf(character(), tmp_path / "dense.glb")
    sparse = write_gltf(character(), tmp_path / "sparse.gltf", sparse_rows=rows)
    a, b = read_gltf_skin(dense), read_gltf_skin(sparse)
    np.testing.assert_array_equal(b.vertices, a.vertices)
    doc = pygltflib.GLTF2().load(str(sparse))
    assert doc.accessors[doc.meshes[0].primitives[0].attributes.POSITION].sparse.count == len(rows)
    np.testing.assert_array_equal(load(sparse, cache).vertices, load(dense, cache).vertices)


@pytest.mark.slow
def test_a_stored_pose_unlike_the_bind_pose_is_the_rest_pose_a_viewer_shows(tmp_path, cache):
    pose = {"J0": Rotation.from_euler("x", 20, degrees=True).as_quat(),
            "J1": Rotation.from_euler("z", 40, degrees=True).as_quat(),
            "J2": Rotation.from_euler("xy", [-30, 25], degrees=True).as_quat()}
    bound = write_gltf(character(rigid_hat=True), tmp_path / "bind.glb")
    animated = write_gltf(character(rigid_hat=True), tmp_path / "animated.glb", pose=pose)
    a, b = read_gltf_skin(bound), read_gltf_skin(animated)
    assert not np.allclose(a.rest_globals, b.rest_globals)
    # the glTF skinning formula, evaluated independently, on the stored nodes
    np.testing.assert_allclose(b.vertices, skinned_positions(animated), atol=1e-6)
    np.testing.assert_allclose(a.vertices, skinned_positions(bound), atol=1e-6)
    assert np.abs(b.vertices - a.vertices).max() > 0.01
    G = _node_globals(pygltflib.GLTF2().load(str(animated)))
    np.testing.assert_allclose(b.joint_positions, G[b.joint_nodes, :3, 3], atol=1e-7)
    # posed, the column's parts cut each other: the print body resolves them, true to a grid cell
    ra = load(animated, cache)
    np.testing.assert_allclose(np.ptp(ra.vertices, 0).max(), np.ptp(b.vertices, 0).max() * 1000,
                               rtol=2.0 / WINDING_CELLS)
    check_closed_surface(ra.faces)
    assert intersecting_face_pairs(ra.vertices, ra.faces) == 0


def test_the_skinned_node_transform_is_ignored_and_an_armature_scale_is_not(tmp_path):
    """The glTF rule: a skinned mesh's own node transform does not move it; the joints' globals do."""
    asset = character()
    path = write_gltf(asset, tmp_path / "plain.glb")
    doc = pygltflib.GLTF2().load(str(path))
    body = next(i for i, n in enumerate(doc.nodes) if n.skin is not None)
    doc.nodes[body].scale = [100.0, 100.0, 100.0]  # what FBX exports leave, and what the spec says to ignore
    doc.nodes[body].translation = [5.0, 0.0, 0.0]
    doc.save_binary(str(tmp_path / "mesh-scaled.glb"))
    np.testing.assert_allclose(read_gltf_skin(tmp_path / "mesh-scaled.glb").vertices, read_gltf_skin(path).vertices,
                               atol=1e-7)
    # an armature scaled 0.01 over vertices and inverse bind matrices in centimetres: metres again
    doc = pygltflib.GLTF2().load(str(path))
    arm = next(n for n in doc.nodes if n.name == "Armature")
    arm.scale = [0.01, 0.01, 0.01]
    for j in doc.skins[0].joints:  # the joints' offsets in centimetres too
        doc.nodes[j].translation = [100.0 * t for t in (doc.nodes[j].translation or [0.0, 0.0, 0.0])]
    blob = bytearray(doc.binary_blob())
    for acc_index in {p.attributes.POSITION for m in doc.meshes for p in m.primitives}:
        acc = doc.accessors[acc_index]
        view = doc.bufferViews[acc.bufferView]
        X = np.frombuffer(bytes(blob[view.byteOffset:view.byteOffset + view.byteLength]), np.float32).copy() * 100
        blob[view.byteOffset:view.byteOffset + view.byteLength] = X.tobytes()
        acc.min, acc.max = [v * 100 for v in acc.min], [v * 100 for v in acc.max]
    skin = doc.skins[0]
    view = doc.bufferViews[doc.accessors[skin.inverseBindMatrices].bufferView]
    ibm = np.frombuffer(bytes(blob[view.byteOffset:view.byteOffset + view.byteLength]), np.float32).reshape(-1, 4, 4)
    ibm = ibm.transpose(0, 2, 1) @ np.diag([0.01, 0.01, 0.01, 1.0])  # the centimetre joints' IBMs: (0.01 G_j)^-1 · 100
    ibm = np.diag([100.0, 100.0, 100.0, 1.0]) @ ibm
    blob[view.byteOffset:view.byteOffset + view.byteLength] = np.ascontiguousarray(
        ibm.transpose(0, 2, 1), np.float32).tobytes()
    doc.set_binary_blob(bytes(blob))
    doc.save_binary(str(tmp_path / "cm.glb"))
    cm = read_gltf_skin(tmp_path / "cm.glb")
    np.testing.assert_allclose(cm.vertices, skinned_positions(tmp_path / "cm.glb"), atol=1e-6)
    np.testing.assert_allclose(np.ptp(cm.vertices, 0), np.ptp(read_gltf_skin(path).vertices, 0), rtol=1e-5)


@pytest.mark.parametrize("weights_type, step", [(U8, 1 / 255), (U16, 1 / 65535)], ids=["ubyte", "ushort"])
def test_normalised_integer_weights_read_like_floats(tmp_path, weights_type, step):
    V, _, _ = column()
    rng = np.random.default_rng(3)
    J = np.tile([0, 1, 2, 0], (len(V), 1))
    W = np.column_stack([rng.dirichlet([1.0, 1.0, 1.0], len(V)), np.zeros(len(V))])
    asset = character(weights=(J, W))
    exact = read_gltf_skin(write_gltf(asset, tmp_path / "float.glb"))
    quantised = read_gltf_skin(write_gltf(asset, tmp_path / "int.glb", weights_type=weights_type, joints_type=U8))
    doc = pygltflib.GLTF2().load(str(tmp_path / "int.glb"))
    attrs = doc.meshes[0].primitives[0].attributes
    assert doc.accessors[attrs.WEIGHTS_0].componentType == weights_type and doc.accessors[attrs.WEIGHTS_0].normalized
    assert doc.accessors[attrs.JOINTS_0].componentType == U8
    np.testing.assert_allclose(quantised.weights, exact.weights, rtol=0, atol=step)
    assert np.abs(quantised.weights - exact.weights).max() > 0  # really quantised
    np.testing.assert_allclose(quantised.weights.sum(1), 1.0, atol=1e-12)
    assert not any("did not sum to 1" in n for n in quantised.notes)


def test_bones_are_named_after_joints_and_fix_accepts_the_names(tmp_path, cache):
    rig = column_rig(cache, tmp_path)
    assert rig.bone_names() == ["J0", "J1", "J2"]
    default = resolve_fixed_bones(rig)
    np.testing.assert_array_equal(default, [True, False, False])  # J0 rests on the plate
    np.testing.assert_array_equal(resolve_fixed_bones(rig, fix=["J2"]), [True, False, True])
    np.testing.assert_array_equal(resolve_fixed_bones(rig, free=["J0"]), [False, False, False])
    np.testing.assert_array_equal(SearchSettings(fix=["J1"]).fixed_bones(rig), [True, True, False])
    np.testing.assert_array_equal(SearchSettings(fix="J1, 3").fixed_bones(rig), [True, True, True])
    np.testing.assert_array_equal(SearchSettings(limits=["J2=0"]).fixed_bones(rig), [True, False, True])
    with pytest.raises(ValueError, match="'Spine' is not a bone name"):
        resolve_fixed_bones(rig, fix=["Spine"])
    with pytest.raises(ValueError, match="did you mean J1"):
        SearchSettings(fix=["j1"]).fixed_bones(rig)
    with pytest.raises(ValueError):
        SearchSettings(free=["nope"]).fixed_bones(rig)


def test_posing_round_trip_through_the_written_asset(tmp_path, cache):
    path = write_gltf(character(extra_parts=True, rigid_hat=True, helpers=True), tmp_path / "full.glb", materials=2)
    rig = load(path, cache, height_mm=90)  # the 70 mm tall file (with its hat) 90 mm tall
    source = rig.info["gltf"]
    assert source["scale"] == pytest.approx(1000.0 * 90 / 70)
    angles = np.random.default_rng(4).uniform(-0.8, 0.8, (rig.bone_count, 3))
    T = posed_joint_transforms(rig.transforms(angles), source["driver"], source["scale"])
    out = tmp_path / "posed.glb"
    write_posed_gltf(path, out, T, source["joint_nodes"])
    # on the body: the column's 24, the arms' far ends (4 + 4) and the hat's top (4)
    assert check_posed_file(rig, out, angles, path) == 36
    before, after = pygltflib.GLTF2().load(str(path)), pygltflib.GLTF2().load(str(out))
    assert len(after.meshes) == len(before.meshes) == 3
    assert [len(m.primitives) for m in after.meshes] == [2, 1, 1]
    assert len(after.materials) == len(before.materials) == 2
    assert len(after.skins) == 1
    assert [after.nodes[j].name for j in after.skins[0].joints] == [before.nodes[j].name for j in before.skins[0].joints]
    # the joint nodes moved, by the bones' transforms: G_j' = T_j G_j
    bind = read_gltf_skin(path).rest_globals
    G = _node_globals(after)
    nodes = np.asarray(source["joint_nodes"])
    np.testing.assert_allclose(G[nodes], T @ bind[nodes], atol=1e-9)
    assert not np.allclose(G[nodes], bind[nodes])
    # the written .gltf (data URI) says the same
    out_gltf = tmp_path / "posed.gltf"
    write_posed_gltf(path, out_gltf, T, source["joint_nodes"])
    np.testing.assert_allclose(skinned_positions(out_gltf), skinned_positions(out), atol=1e-12)


def test_a_skin_without_inverse_bind_matrices_round_trips(tmp_path, cache):
    path = write_gltf(character(), tmp_path / "no-ibm.glb", inverse_bind=False)
    rig = load(path, cache)
    assert pose_and_check(rig, path, tmp_path / "posed.glb", seed=6, spread=0.5) == 24


# --------------------------------------------------------------------------- #
# bad input: one InputError line, naming the file first
# --------------------------------------------------------------------------- #
def assert_input_error(path, cache, *fragments):
    """``load_rig(path)`` raises one InputError whose message starts with the path."""
    with pytest.raises(InputError) as info:
        load(path, cache)
    message = str(info.value)
    assert message.startswith(f"{path}: "), message
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, message
    return message


def test_a_gltf_without_a_skin_is_refused(tmp_path, cache):
    path = write_gltf(character(), tmp_path / "static.glb", with_skin=False)
    assert_input_error(path, cache, "has no skin")


@pytest.mark.parametrize("keep, fragment", [(0.05, "not a readable glTF file"), (0.5, "not a readable glTF file"),
                                            (0.9, "the file is truncated"), (-1, "the file is truncated")],
                         ids=["header", "in-json", "in-bin", "last-byte"])
def test_a_truncated_glb_is_refused(tmp_path, cache, keep, fragment):
    whole = write_gltf(character(), tmp_path / "whole.glb").read_bytes()
    path = tmp_path / "cut.glb"
    path.write_bytes(whole[: int(len(whole) * keep) if keep > 0 else keep])
    assert_input_error(path, cache, fragment)


def test_a_required_extension_it_does_not_read_is_refused_by_name(tmp_path, cache):
    """The glTF specification: a loader refuses an asset requiring an extension it does not know."""
    path = write_gltf(character(), tmp_path / "future.glb", extensions_used=("EXT_future_geometry",),
                      extensions_required=("EXT_future_geometry",))
    assert_input_error(path, cache, "requires the glTF extension EXT_future_geometry")
    # only used, or required but about materials: read as before
    used = write_gltf(character(), tmp_path / "used.glb", extensions_used=("EXT_future_geometry",))
    assert load(used, cache).bone_count == 3
    looks = write_gltf(character(), tmp_path / "looks.glb", extensions_used=("KHR_materials_unlit",),
                       extensions_required=("KHR_materials_unlit",))
    assert load(looks, cache).bone_count == 3


def test_a_gltf_whose_bin_is_missing_is_refused(tmp_path, cache):
    path = write_gltf(character(), tmp_path / "external.gltf", external_bin=True)
    assert load(path, cache).bone_count == 3  # readable with its .bin
    path.with_suffix(".bin").unlink()
    assert_input_error(path, tmp_path / "cache2", "external.bin")


@pytest.mark.parametrize("content", [b"solid box\nendsolid box\n", bytes(range(256)) * 8, b""],
                         ids=["ascii-stl", "binary", "empty"])
def test_a_non_gltf_file_named_glb_is_refused(tmp_path, cache, content):
    path = tmp_path / "fake.glb"
    path.write_bytes(content)
    assert_input_error(path, cache, "not a readable glTF file")


# --------------------------------------------------------------------------- #
# the command line
# --------------------------------------------------------------------------- #
def test_cli_optimize_and_apply_a_glb(tmp_path):
    tiny = write_gltf(character(split=True, rigid_hat=True), tmp_path / "tiny.glb")
    common = [tiny, "--cache-dir", tmp_path / "cache"]
    run = CliRunner().invoke
    result = run(main, [str(a) for a in ["optimize", *common, "-o", tmp_path / "out.stl", "--upright-out",
                                         tmp_path / "out.glb", "--pose", tmp_path / "p.json", "--particles", 8,
                                         "--iterations", 2, "-q"]])
    assert result.exit_code == 0, (result.output, result.exception)
    for name in ("out.stl", "out.glb", "p.json"):
        assert (tmp_path / name).is_file(), name
    pose = json.loads((tmp_path / "p.json").read_text())
    assert pose["bone_names"] == ["J0", "J1", "J2"]
    # the STL is a print file: +Z up, on the plate, at the default printed size (the rest pose 60 mm tall)
    assert pose["print_frame"]["height_mm"] == 60.0
    printed = sl.read_mesh(tmp_path / "out.stl")[0]
    assert printed[:, 2].min() == pytest.approx(0.0, abs=1e-4)
    assert 20.0 < np.ptp(printed, axis=0).max() < 300.0
    again = run(main, [str(a) for a in ["apply", *common, "--pose", tmp_path / "p.json", "-o",
                                        tmp_path / "again.stl"]])
    assert again.exit_code == 0, (again.output, again.exception)
    np.testing.assert_allclose(sl.read_mesh(tmp_path / "again.stl")[0], sl.read_mesh(tmp_path / "out.stl")[0],
                               atol=1e-6)
    # the standing asset: the pose on its joints, placed on the plate
    rig = load_rig(tiny, cache_dir=tmp_path / "cache")
    angles = sl.read_pose(tmp_path / "p.json", rig.bones)
    posed = skinned_positions(tmp_path / "out.glb") * rig.info["gltf"]["scale"]
    assert posed[:, 1].min() == pytest.approx(0.0, abs=1e-4)
    standing = sl.base.geometry.place_on_plate(rig.pose(angles), rig.up)
    bind = read_gltf_skin(tiny).vertices * rig.info["gltf"]["scale"]
    dist, idx = cKDTree(rig.vertices).query(bind)
    on = dist < 1e-6 * HEIGHT_MM
    np.testing.assert_allclose(posed[on], standing[idx[on]], atol=1e-4)


# --------------------------------------------------------------------------- #
# the shared real assets
# --------------------------------------------------------------------------- #
@pytest.mark.parametrize("name, bones, pruned, on_body", [
    # Fox: 22 kept joints (21 parent-child bones) + 6 weighted leaves (head, hands, tail, feet);
    # every one of its 1728 vertices lies on the welded body
    ("Fox.glb", 27, ["_rootJoint", "b_Root_00"], 1.0),
    # Robot: 41 kept joints, of which the three palm joints at each wrist are one (4 folded), and
    # weighted leaves; the IK pole targets carry no weight; its parts cut each other in the stored pose
    # (the body is remade from its winding number) and hide many vertices inside
    ("RobotExpressive.glb", 49, ["PoleTarget.L", "PoleTarget.R"], 0.3),
])
@pytest.mark.slow
def test_shared_asset(shared_file, tmp_path, name, bones, pruned, on_body):
    path = shared_file(f"gltf/{name}")
    rig = load_rig(path, height_mm=60, cache_dir=tmp_path / "cache")
    assert np.ptp(rig.vertices[:, 1]) == pytest.approx(60.0, rel=1e-9)
    check_closed_surface(rig.faces)
    assert signed_volume(rig.vertices, rig.faces) > 0
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    f = rig.faces
    adjacency = coo_matrix((np.ones(2 * f.size), (np.concatenate([f.ravel(), np.roll(f, 1, axis=1).ravel()]),
                                                   np.concatenate([np.roll(f, 1, axis=1).ravel(), f.ravel()]))),
                           shape=(len(rig.vertices),) * 2)
    assert connected_components(adjacency, directed=False)[0] == 1  # one solid
    assert intersecting_face_pairs(rig.vertices, rig.faces) == 0
    assert rig.bone_count == bones
    skin = read_gltf_skin(path)
    body = print_body(skin.vertices, skin.faces, skin.part, skin.weights, skin.part_names)
    sk = skeleton_from_joints(skin.joint_positions, skin.joint_parents, body.values, skin.joint_names, body.vertices)
    assert sorted(sk.pruned) == sorted(pruned)
    assert rig.labels == sk.names
    # a posed asset re-reads with the same joints and the pose on its nodes
    angles = np.random.default_rng(5).uniform(-0.4, 0.4, (rig.bone_count, 3))
    source = rig.info["gltf"]
    T = posed_joint_transforms(rig.transforms(angles), source["driver"], source["scale"])
    out = tmp_path / "posed.glb"
    write_posed_gltf(path, out, T, source["joint_nodes"])
    before, after = glb_json(path), pygltflib.GLTF2().load(str(out))
    assert [[after.nodes[j].name for j in s.joints] for s in after.skins] == \
        [[before["nodes"][j].get("name") for j in s["joints"]] for s in before["skins"]]
    assert len(after.meshes) == len(before["meshes"]) and len(after.materials) == len(before.get("materials", []))
    nodes = np.asarray(source["joint_nodes"])
    # (to float32 noise in the stored transforms)
    np.testing.assert_allclose(_node_globals(after)[nodes], T @ skin.rest_globals[nodes],
                               atol=1e-5 * np.abs(skin.rest_globals[nodes]).max())
    # the skinning formula (weights normalised, the robot's sum to 1.75) poses the file as the rig poses the body
    if any("winding number" in line for line in source["log"]):  # remade: no vertex shared with the file
        assert check_posed_surface(rig, out, angles, skin, after) >= on_body
    else:
        compared = check_posed_file(rig, out, angles, path, normalise=True, skin=skin, doc=after)
        assert compared >= on_body * len(skin.vertices)


def test_weights_bbw_recomputes_weights_on_the_derived_bones(tmp_path, cache):
    """``--weights bbw``: bounded biharmonic weights instead of the file's (the column's joints are inside)."""
    path = write_gltf(character(), tmp_path / "column.glb")
    skin = load(path, cache)
    bbw = load(path, cache, weights="bbw")
    assert skin.info["weights"] == "skin" and bbw.info["weights"] == "bbw"
    np.testing.assert_array_equal(bbw.bones, skin.bones)
    np.testing.assert_allclose(bbw.weights.sum(1), 1.0)
    # the file's weights are rigid per segment; bounded biharmonic weights blend across the joints
    assert ((skin.weights > 0) & (skin.weights < 1)).sum() < ((bbw.weights > 1e-3) & (bbw.weights < 1 - 1e-3)).sum()



def test_a_gltf_with_an_external_bin_is_posed_into_a_glb(tmp_path, cache):
    """A .gltf whose buffer is a separate .bin file: the posed .glb carries the data and poses like the rig."""
    path = write_gltf(character(), tmp_path / "split.gltf", external_bin=True)
    rig = load(path, cache)
    source = rig.info["gltf"]
    angles = np.random.default_rng(7).uniform(-0.6, 0.6, (rig.bone_count, 3))
    T = posed_joint_transforms(rig.transforms(angles), source["driver"], source["scale"])
    out = tmp_path / "out" / "posed.glb"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "orphaned .bin" warning reaches the user
        write_posed_gltf(path, out, T, source["joint_nodes"])
    assert check_posed_file(rig, out, angles, path) > 0


@pytest.mark.slow
def test_a_dense_skinned_body_is_searched_through_its_proxy(tmp_path, cache, monkeypatch):
    """Over the proxy threshold a glTF rig gets a simplified volume and search surface; answers stay full size."""
    from supportless.rig import rig as rig_mod
    from supportless.search.answer import optimize

    path = write_gltf(character(), tmp_path / "column.glb")
    plain = load(path, cache)
    V, F = plain.vertices, plain.faces
    V2, F2 = igl.upsample(V, F, 2)  # a denser print body of the same column
    monkeypatch.setattr(rig_mod, "PROXY_FACES", len(F2) - 1)
    monkeypatch.setattr(rig_mod, "PROXY_TARGET", len(F2) // 4)
    from supportless.files.printbody import transfer_values

    dense = rig_mod.prepare_rig(V2, F2, plain.joints, plain.bones, "y",
                                surface_weights=transfer_values(V2, V, F, plain.weights))
    assert dense.coarse_faces is not None
    coarse = dense.coarse_rig()
    assert len(coarse.faces) <= len(F2) // 4
    np.testing.assert_allclose(dense.weights.sum(1), 1.0, atol=1e-9)
    result = optimize(dense, particles=8, iterations=2, orient="keep", polish=2)  # the polish is not the subject
    assert result.vertices.shape == V2.shape and result.full_surface.proxy_faces == len(coarse.faces)


def test_a_cached_glb_rig_skips_the_print_body_and_follows_a_moved_file(tmp_path, cache):
    """The second load comes from the cache keyed by the file's bytes, with what writing the posed asset needs."""
    path = write_gltf(character(helpers=True), tmp_path / "a.glb")
    first = load(path, cache)
    steps = []
    moved = tmp_path / "elsewhere" / "b.glb"
    moved.parent.mkdir()
    path.rename(moved)
    second = load(moved, cache, progress=steps.append)
    assert not first.info["from_cache"] and second.info["from_cache"]
    assert steps == []  # neither the skin nor the print body was made again
    assert second.info["gltf"]["path"] == str(moved)
    assert second.info["gltf"]["driver"] == first.info["gltf"]["driver"]
    assert second.labels == first.labels
    np.testing.assert_array_equal(second.tet_weights, first.tet_weights)
    # another setting is another entry
    assert not load(moved, cache, height_mm=50).info["from_cache"]
