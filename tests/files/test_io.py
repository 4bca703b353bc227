"""Readers and writers: meshes, TGF skeletons, .dmat, .mesh, poses, atomic writes."""

import json

import numpy as np
import pytest

import supportless as sl
from supportless.base.geometry import parse_up, signed_volume
from supportless.files import meshes as io
from supportless.files.objtext import rows_of_three

FORMATS = ["stl", "obj", "ply", "off", "3mf", "glb"]


# OBJ is written with 8 decimals and OFF with trimesh's default precision: a coordinate
# moves by up to 5e-9, a vertex by up to 8.7e-9 (7.7e-9 measured for OBJ, 7e-11 for OFF);
# STL, PLY, 3MF and GLB store the float32 test coordinates exactly.
TEXT_FORMAT_TOL = 1e-8


def _same_triangles(V2, F2, V, F, tol=TEXT_FORMAT_TOL):
    """Assert two meshes have the same oriented triangles, whatever the vertex numbering.

    Every vertex of the second mesh is matched to the nearest vertex of the
    first (within ``tol``); the triangles, as index triples started at their
    smallest index (a cyclic shift keeps the orientation), must be the same sets.
    """
    from scipy.spatial import cKDTree

    assert V2.shape == V.shape and F2.shape == F.shape
    dist, match = cKDTree(V).query(V2)
    assert dist.max() <= tol
    assert len(np.unique(match)) == len(V)

    def canonical(F):
        F = np.asarray(F)
        k = np.argmin(F, axis=1)
        rolled = np.stack([F[np.arange(len(F)), (k + i) % 3] for i in range(3)], axis=1)
        return rolled[np.lexsort(rolled.T[::-1])]

    np.testing.assert_array_equal(canonical(match[F2]), canonical(F))


@pytest.fixture(scope="module")
def branch_mesh():
    V, F, _, _ = sl.demo_figure("branch")
    # coordinates exactly representable in float32, as STL, GLB and 3MF store them
    return V.astype(np.float32).astype(np.float64), F


# ------------------------------------------------------------------------ meshes


@pytest.mark.parametrize("ext", FORMATS)
def test_mesh_round_trip(tmp_path, branch_mesh, ext):
    V, F = branch_mesh
    path = tmp_path / f"branch.{ext}"
    sl.write_mesh(path, V, F)
    V2, F2 = sl.read_mesh(path)
    assert V2.dtype == np.float64 and F2.dtype == np.int64
    _same_triangles(V2, F2, V, F)
    if ext in ("obj", "off"):  # moved vertices (above): 3e-10 relative volume change measured
        np.testing.assert_allclose(signed_volume(V2, F2), signed_volume(V, F), rtol=1e-8)
    else:
        np.testing.assert_array_equal(np.sort(V2, axis=0), np.sort(V, axis=0))
    io.check_closed_surface(F2, path)
    # nothing but the file itself is left in the folder
    assert [p.name for p in tmp_path.iterdir()] == [path.name]


def test_planar_mesh_is_written_with_z_zero(tmp_path):
    V, F, _, _ = sl.demo_figure("woody2d")
    sl.write_mesh(tmp_path / "w.obj", V, F)
    V2, F2 = sl.read_mesh(tmp_path / "w.obj")
    assert V2.shape == (len(V), 3) and np.all(V2[:, 2] == 0)
    _same_triangles(V2[:, :2], F2, V, F)


def test_stl_soup_is_welded(tmp_path, box_surface):
    V, F = box_surface((0, 0, 0), (1, 2, 3))
    sl.write_mesh(tmp_path / "box.stl", V, F)
    V2, F2 = sl.read_mesh(tmp_path / "box.stl")
    assert V2.shape == (8, 3) and F2.shape == (12, 3)
    io.check_closed_surface(F2)
    assert signed_volume(V2, F2) == 6.0  # integer corners: exact


def test_merge_duplicate_vertices_keeps_a_clean_mesh_unchanged(box_surface):
    V, F = box_surface()
    V2, F2 = io.merge_duplicate_vertices(V, F)
    assert V2 is V and F2 is F
    Vd = np.vstack([V, V[:1], [[9.0, 9.0, 9.0]]])  # a duplicate of vertex 0 and an unused vertex
    Fd = F.copy()
    r, c = np.argwhere(F == 0)[0]
    Fd[r, c] = 8  # one corner that used vertex 0 now uses its duplicate
    V3, F3 = io.merge_duplicate_vertices(Vd, Fd)
    np.testing.assert_array_equal(V3, V)
    np.testing.assert_array_equal(F3, F)


@pytest.mark.parametrize("ext", FORMATS)
def test_garbage_mesh_is_an_input_error(tmp_path, ext):
    path = tmp_path / f"garbage.{ext}"
    path.write_bytes(b"\x00\x01garbage\xff" * 50)
    with pytest.raises(sl.InputError) as info:
        sl.read_mesh(path)
    assert str(info.value).startswith(f"{path}: ")
    assert "\n" not in str(info.value)


def test_unknown_and_missing_mesh_files(tmp_path):
    (tmp_path / "model.xyz").write_text("1 2 3\n")
    with pytest.raises(sl.InputError, match=r"model\.xyz: unknown mesh format '\.xyz'"):
        sl.read_mesh(tmp_path / "model.xyz")
    with pytest.raises(sl.InputError, match=r"nope\.stl: no such file"):
        sl.read_mesh(tmp_path / "nope.stl")
    with pytest.raises(sl.InputError, match=r"out\.xyz: unknown output format"):
        sl.write_mesh(tmp_path / "out.xyz", np.eye(3), np.array([[0, 1, 2]]))
    assert not (tmp_path / "out.xyz").exists()


def test_check_closed_surface_messages(box_surface):
    V, F = box_surface()
    io.check_closed_surface(F)
    with pytest.raises(sl.InputError, match="box.obj: surface is not closed: 3 boundary edges"):
        io.check_closed_surface(F[1:], "box.obj")
    with pytest.raises(sl.InputError, match="not manifold"):
        io.check_closed_surface(np.vstack([F, F[:1]]))
    Fw = F.copy()
    Fw[0] = Fw[0, ::-1]
    with pytest.raises(sl.InputError, match="consistently oriented"):
        io.check_closed_surface(Fw)


# ---------------------------------------------------------------- atomic writes


def test_failed_write_mesh_leaves_nothing(tmp_path, monkeypatch, branch_mesh):
    import trimesh

    def broken_export(self, file_obj=None, file_type=None, **kwargs):
        with open(file_obj, "wb") as fh:
            fh.write(b"half a mesh")
        raise OSError("disk full")

    monkeypatch.setattr(trimesh.Trimesh, "export", broken_export)
    with pytest.raises(OSError, match="disk full"):
        sl.write_mesh(tmp_path / "out.stl", *branch_mesh)
    assert list(tmp_path.iterdir()) == []


def test_failed_write_keeps_the_previous_file(tmp_path, monkeypatch, branch_mesh):
    import trimesh

    path = tmp_path / "out.ply"
    sl.write_mesh(path, *branch_mesh)
    before = path.read_bytes()

    def broken_export(self, file_obj=None, file_type=None, **kwargs):
        raise RuntimeError("exporter crashed")

    monkeypatch.setattr(trimesh.Trimesh, "export", broken_export)
    with pytest.raises(RuntimeError):
        sl.write_mesh(path, *branch_mesh)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["out.ply"]


_TRI = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


@pytest.mark.parametrize("V, F, fragment", [
    (_TRI, [[0, 1, 3]], "face 0 (0 1 3) refers to a vertex out of range 0..2 (1 such faces)"),
    (_TRI, [[0, 1, 2], [0, -1, 2], [2, 1, -3]], "face 1 (0 -1 2) refers to a vertex out of range 0..2 (2 such"),
    (_TRI, [0, 1, 2], "faces must be an (f, 3) array of vertex indices, got shape (3,)"),
    (_TRI, [[0, 1, 2, 0]], "faces must be an (f, 3) array of vertex indices, got shape (1, 4)"),
    (_TRI, np.zeros((0, 3), np.int64), "got shape (0, 3)"),
    (_TRI, [[0, 1, 2], [0, 1]], "faces must be an (f, 3) array of vertex indices"),
    (_TRI, [[0, 1, 2.5]], "face indices must be integers, got float64"),
    (_TRI, [["a", "b", "c"]], "face indices must be integers"),
    (_TRI[:, 0], [[0, 1, 2]], "vertices must be an (n, 3) or (n, 2) array, got shape (3,)"),
    (np.zeros((3, 4)), [[0, 1, 2]], "got shape (3, 4)"),
    (np.zeros((0, 3)), [[0, 1, 2]], "got shape (0, 3)"),
    (_TRI * [1, 1, np.nan], [[0, 1, 2]], "vertex 0 has a NaN or infinite coordinate (3 such vertices)"),
    (_TRI + [[0, 0, 0], [0, np.inf, 0], [0, 0, 0]], [[0, 1, 2]], "vertex 1 has a NaN or infinite coordinate"),
    ([["x", 0, 0]] * 3, [[0, 1, 2]], "vertices must be an (n, 3) array of numbers"),
])
def test_write_mesh_rejects_bad_arrays_before_writing(tmp_path, V, F, fragment):
    target = tmp_path / "sub" / "out.stl"
    with pytest.raises(sl.InputError) as info:
        sl.write_mesh(target, V, F)
    message = str(info.value)
    assert message.startswith(f"{target}: ") and "\n" not in message
    assert fragment in message
    assert info.value.path == str(target)
    assert list(tmp_path.iterdir()) == []  # not even the folder


def test_bad_faces_leave_the_previous_file(tmp_path, branch_mesh):
    V, F = branch_mesh
    path = tmp_path / "out.stl"
    sl.write_mesh(path, V, F)
    before = path.read_bytes()
    with pytest.raises(sl.InputError, match="refers to a vertex out of range"):
        sl.write_mesh(path, V, F + len(V))
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["out.stl"]


def test_check_mesh_arrays_converts_and_keeps_2d():
    V, F = io.check_mesh_arrays([[0, 0], [1, 0], [0, 1]], [[0.0, 1.0, 2.0]])
    assert V.dtype == np.float64 and V.shape == (3, 2)
    assert F.dtype == np.int64 and F.tolist() == [[0, 1, 2]]
    with pytest.raises(sl.InputError) as info:
        io.check_mesh_arrays(_TRI, [[0, 1, 7]])
    assert info.value.path is None and str(info.value).startswith("face 0 (0 1 7)")


def test_atomic_path_creates_the_folder(tmp_path):
    target = tmp_path / "a" / "b" / "c.txt"
    io.write_text(target, "hello")
    assert target.read_text() == "hello"
    assert [p.name for p in target.parent.iterdir()] == ["c.txt"]


# ------------------------------------------------------------------------- TGF


def test_tgf_round_trip(tmp_path):
    J, B = sl.demo_figure("tpose")[2:]
    sl.write_tgf(tmp_path / "s.tgf", J, B)
    J2, B2 = sl.read_tgf(tmp_path / "s.tgf")
    assert J2.dtype == np.float64 and B2.dtype == np.int64
    np.testing.assert_array_equal(J2, J)  # %.17g is exact
    np.testing.assert_array_equal(B2, B)
    # 2D joints come back with z = 0
    J, B = sl.demo_figure("woody2d")[2:]
    sl.write_tgf(tmp_path / "w.tgf", J, B)
    J2, B2 = sl.read_tgf(tmp_path / "w.tgf")
    np.testing.assert_array_equal(J2[:, :2], J)
    assert np.all(J2[:, 2] == 0)
    np.testing.assert_array_equal(B2, B)


def test_tgf_with_extra_columns(tmp_path):
    text = (
        "   1 0.5 1.5 -2 0 0 0 1\n"
        "   2 0.5 3.5 -2 1 2\n"
        "   3 1e-1 4 5.25\n"
        "#\n"
        "   1    2 1 0 0\n"
        "   2    3 0 1 0 0 0 0\n"
        "#\n"
    )
    (tmp_path / "x.tgf").write_text(text)
    J, B = sl.read_tgf(tmp_path / "x.tgf")
    np.testing.assert_array_equal(J, [[0.5, 1.5, -2], [0.5, 3.5, -2], [0.1, 4, 5.25]])
    np.testing.assert_array_equal(B, [[0, 1], [1, 2]])


def test_tgf_without_final_hash_and_with_blank_lines(tmp_path):
    (tmp_path / "x.tgf").write_text("1 0 0 0\n\n2 0 1 0\n#\n1 2\n")
    J, B = sl.read_tgf(tmp_path / "x.tgf")
    assert J.shape == (2, 3) and B.tolist() == [[0, 1]]


def test_tgf_bones_in_any_order(tmp_path):
    # children listed before their parents: file order is kept, the hierarchy is still found
    (tmp_path / "x.tgf").write_text("1 0 0 0\n2 0 1 0\n3 0 2 0\n4 1 2 0\n#\n3 4\n2 3\n1 2\n#\n")
    J, B = sl.read_tgf(tmp_path / "x.tgf")
    assert B.tolist() == [[2, 3], [1, 2], [0, 1]]
    assert sl.base.kinematics.bone_parents(B).tolist() == [1, 2, -1]


@pytest.mark.parametrize("name, joints, bones", [("bunny", 12, 11), ("bb-bunny", 13, 12), ("woody", 9, 8)])
def test_shared_tgf_files(shared_file, name, joints, bones):
    J, B = sl.read_tgf(shared_file(f"{name}.tgf"))
    assert J.shape == (joints, 3) and B.shape == (bones, 2)
    assert B.min() >= 0 and B.max() < joints
    assert (sl.base.kinematics.bone_parents(B) < 0).sum() >= 1


@pytest.mark.parametrize("text, fragments", [
    ("1 0 0\n#\n", ["line 1", "joint 'index x y z'"]),
    ("1 0 0 0\n2 0 1 0\n#\n1 x\n", ["line 4", "bone 'i j'"]),
    ("1 0 0 0\n2 0 1 0\n#\n1 3\n", ["bone 1 (1 3)", "out of range 1..2"]),
    ("1 0 0 0\n2 0 1 0\n#\n0 1\n", ["out of range 1..2"]),
    ("1 0 0 0\n2 0 1 0\n#\n2 2\n", ["bone 1 joins joint 2 to itself"]),
    ("1 0 0 0\n2 0 1 0\n#\n", ["no bones"]),
    ("", ["no joints"]),
    ("1 0 nan 0\n2 0 1 0\n#\n1 2\n", ["NaN"]),
    # not a tree (issue 18: a cycle used to hang the search)
    ("1 0 0 0\n2 0 1 0\n3 1 1 0\n#\n1 2\n2 3\n3 1\n", ["bones", "form a cycle"]),
    ("1 0 0 0\n2 0 1 0\n3 1 1 0\n#\n1 3\n2 3\n", ["joint 3 is the tip of bones 1 and 2"]),
    ("1 0 0 0\n2 0 1 0\n3 1 1 0\n#\n1 2\n2 1\n", ["bones 1 and 2 both join joints"]),
    ("1 0 0 0\n2 0 0 0\n3 1 1 0\n#\n1 2\n2 3\n", ["bone 1 has zero length", "joints 1 and 2"]),
    ("1 0 0 0\n2 0 1 0\n3 0 1 0\n4 1 1 0\n#\n1 2\n3 4\n", ["joints 2 and 3 are at the same place"]),
    # the index column
    ("1 0 0 0\n1 0 1 0\n#\n1 2\n", ["joint index 1 appears on lines 1 and 2"]),
    ("1 0 0 0\n5 0 1 0\n#\n1 2\n", ["line 2: joint index 5 is not within 1..2"]),
])
def test_bad_tgf(tmp_path, text, fragments):
    path = tmp_path / "bad.tgf"
    path.write_text(text)
    with pytest.raises(sl.InputError) as info:
        sl.read_tgf(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and "\n" not in message
    for fragment in fragments:
        assert fragment in message


def test_tgf_joints_are_placed_by_their_index_column(tmp_path):
    (tmp_path / "x.tgf").write_text("2 0 1 0\n3 0 2 0\n1 0 0 0\n#\n1 2\n2 3\n")
    J, B = sl.read_tgf(tmp_path / "x.tgf")
    np.testing.assert_array_equal(J, [[0, 0, 0], [0, 1, 0], [0, 2, 0]])
    (tmp_path / "z.tgf").write_text("1 0 1 0\n0 0 0 0\n2 0 2 0\n#\n1 2\n2 3\n")  # numbered from 0
    np.testing.assert_array_equal(sl.read_tgf(tmp_path / "z.tgf")[0], J)


def test_tgf_with_a_byte_order_mark_reads_as_without(tmp_path):
    text = "1 0.5 0 0\n2 0.5 1 0\n#\n1 2\n"
    (tmp_path / "plain.tgf").write_text(text, encoding="utf-8")
    (tmp_path / "bom.tgf").write_text(text, encoding="utf-8-sig")
    assert (tmp_path / "bom.tgf").read_bytes().startswith(b"\xef\xbb\xbf")
    for a, b in zip(sl.read_tgf(tmp_path / "plain.tgf"), sl.read_tgf(tmp_path / "bom.tgf")):
        np.testing.assert_array_equal(a, b)
    assert sl.read_tgf(tmp_path / "bom.tgf")[0][0].tolist() == [0.5, 0.0, 0.0]


def test_a_rig_built_from_arrays_refuses_a_cyclic_skeleton():
    V, F = sl.demo_figure("branch")[:2]
    J = np.array([[0.0, 0, 0], [0, 1, 0], [1, 1, 0]])
    with pytest.raises(sl.InputError, match="form a cycle"):
        sl.prepare_rig(V, F, J, np.array([[0, 1], [1, 2], [2, 0]]), up="y")


def test_missing_tgf(tmp_path):
    with pytest.raises(sl.InputError, match="none.tgf: no such file"):
        sl.read_tgf(tmp_path / "none.tgf")


# ---------------------------------------------------------------- .dmat, .mesh


def test_dmat_round_trip(tmp_path):
    M = np.random.default_rng(0).random((7, 3))
    io.write_dmat(tmp_path / "m.dmat", M)
    np.testing.assert_array_equal(io.read_dmat(tmp_path / "m.dmat"), M)
    np.testing.assert_array_equal(io.read_dmat(tmp_path / "m.dmat", (7, None)), M)
    np.testing.assert_array_equal(io.read_dmat(tmp_path / "m.dmat", (None, 3)), M)


def test_dmat_is_column_major_like_libigl(tmp_path):
    (tmp_path / "m.dmat").write_text("3 2\n1 2 3 4 5 6\n")  # cols rows, then column by column
    np.testing.assert_array_equal(io.read_dmat(tmp_path / "m.dmat"), [[1, 3, 5], [2, 4, 6]])


def test_bad_dmat(tmp_path):
    io.write_dmat(tmp_path / "m.dmat", np.ones((4, 2)))
    with pytest.raises(sl.InputError, match=r"m\.dmat: matrix is 4x2 but 4x3 was expected \(one column per bone\)"):
        io.read_dmat(tmp_path / "m.dmat", (4, 3))
    with pytest.raises(sl.InputError, match="one row per vertex"):
        io.read_dmat(tmp_path / "m.dmat", (5, 2))
    (tmp_path / "short.dmat").write_text("2 2\n1 2 3\n")
    with pytest.raises(sl.InputError, match=r"short\.dmat: not an ASCII \.dmat"):
        io.read_dmat(tmp_path / "short.dmat")
    (tmp_path / "text.dmat").write_text("hello\n")
    with pytest.raises(sl.InputError, match=r"text\.dmat: not an ASCII \.dmat"):
        io.read_dmat(tmp_path / "text.dmat")
    with pytest.raises(sl.InputError, match="no such file"):
        io.read_dmat(tmp_path / "none.dmat")


def test_tet_mesh_round_trip(tmp_path, branch_rig):
    io.write_tet_mesh(tmp_path / "t.mesh", branch_rig.tet_vertices, branch_rig.tets)
    TV, TT = io.read_tet_mesh(tmp_path / "t.mesh")
    np.testing.assert_array_equal(TV, branch_rig.tet_vertices)
    np.testing.assert_array_equal(TT, branch_rig.tets)


def test_bad_tet_mesh(tmp_path):
    with pytest.raises(sl.InputError, match="no such file"):
        io.read_tet_mesh(tmp_path / "none.mesh")
    (tmp_path / "bad.mesh").write_text("this is not a mesh\n")
    with pytest.raises(sl.InputError, match=r"bad\.mesh: "):
        io.read_tet_mesh(tmp_path / "bad.mesh")


# ------------------------------------------------------------------------ poses


def test_pose_round_trip(tmp_path):
    J, B = sl.demo_figure("tpose")[2:]
    angles = np.random.default_rng(1).uniform(-np.pi, np.pi, (len(B), 3))
    sl.write_pose(tmp_path / "p.json", angles, B, J, extra={"objective": 0.25})
    np.testing.assert_array_equal(sl.read_pose(tmp_path / "p.json"), angles)
    np.testing.assert_array_equal(sl.read_pose(tmp_path / "p.json", B), angles)
    data = json.loads((tmp_path / "p.json").read_text())
    assert data["format"] == "supportless-pose" and data["objective"] == 0.25
    # degrees rounded to 6 decimals: off by at most 5e-7 deg = 8.7e-9 rad
    np.testing.assert_allclose(np.radians(data["angles_deg"]), angles, rtol=0, atol=8.8e-9)
    assert data["bones"] == B.tolist()


def test_pose_for_another_skeleton_is_rejected(tmp_path):
    B = sl.demo_figure("branch")[3]
    sl.write_pose(tmp_path / "p.json", np.zeros((len(B), 3)), B)
    other = sl.demo_figure("tpose")[3]
    with pytest.raises(sl.InputError, match=r"p\.json: pose is for a skeleton with 3 bones, not this one with 15"):
        sl.read_pose(tmp_path / "p.json", other)
    # same number of bones, other connectivity
    with pytest.raises(sl.InputError, match="another skeleton with as many bones: its bone 1 joins joints") as info:
        sl.read_pose(tmp_path / "p.json", B[[1, 0, 2]])
    assert "use the skeleton the pose was made with" in str(info.value)


def test_a_pose_with_nan_names_the_bone_not_a_shape(tmp_path):
    B = sl.demo_figure("branch")[3]
    A = np.zeros((len(B), 3))
    A[1, 2] = np.nan
    sl.write_pose(tmp_path / "p.json", A, B)
    with pytest.raises(sl.InputError, match="the angles of bone 2 are not finite numbers"):
        sl.read_pose(tmp_path / "p.json", B)


@pytest.mark.parametrize("text", ["not json", '{"bones": []}', '{"angles": [[1, 2]]}', '{"angles": "x"}',
                                  '[1, 2, 3]'])
def test_bad_pose_file(tmp_path, text):
    path = tmp_path / "p.json"
    path.write_text(text)
    with pytest.raises(sl.InputError) as info:
        sl.read_pose(path)
    assert str(info.value).startswith(f"{path}: ")


# --------------------------------------------------------------------- up vector


@pytest.mark.parametrize("up, expected", [("y", [0, 1, 0]), ("-Z", [0, 0, -1]), ("+x", [1, 0, 0]),
                                          ("0,2,0", [0, 1, 0]), ("1 1 0", [2 ** -0.5, 2 ** -0.5, 0]),
                                          ((0, 0, 3), [0, 0, 1])])
def test_parse_up(up, expected):
    np.testing.assert_allclose(parse_up(up), expected, atol=1e-15)


def test_written_files_respect_the_umask(tmp_path, branch_mesh):
    """Atomic writes must give the permissions a plain open() would (0666 & ~umask), not mkstemp's 0600."""
    import os
    import stat

    old = os.umask(0o022)
    try:
        sl.write_mesh(tmp_path / "m.stl", *branch_mesh)
        io.write_text(tmp_path / "t.txt", "x")
    finally:
        os.umask(old)
    for name in ("m.stl", "t.txt"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o644, name


@pytest.mark.parametrize("text, fragment", [
    ('{"angles": ' + "[" * 100000 + "]" * 100000 + ', "bones": []}', "not a pose file"),
    ('{"angles": [[0, 0, 0]], "bones": [[0, 1e30]]}', "pose"),
    ('{"angles": [[0, 0, 0]], "bones": [[0, ' + "1" + "0" * 30 + "]]}", "pose"),
], ids=["nested-100000-deep", "index-1e30", "index-10**30"])
def test_a_pose_file_no_tool_wrote_is_one_line(tmp_path, text, fragment):
    path = tmp_path / "pose.json"
    path.write_text(text)
    with pytest.raises(sl.InputError, match=fragment) as info:
        sl.read_pose(path, np.array([[0, 1]]))
    assert "\n" not in str(info.value)
    from supportless.files.posefile import read_pose_print_frame, read_print_rotation

    for read in (read_pose_print_frame, read_print_rotation):  # the other readers of the same file
        try:
            read(path)
        except sl.InputError as exc:
            assert "\n" not in str(exc)


def test_a_tgf_index_of_31_digits_is_one_line(tmp_path):
    path = tmp_path / "big.tgf"
    path.write_text("1 0 0 0\n2 0 1 0\n#\n1 " + "9" * 31 + "\n")
    with pytest.raises(sl.InputError, match=r"line 4 is not a bone 'i j' line"):
        sl.read_tgf(path)


def _dead_pid() -> int:
    """A process id no process has (a child that has ended)."""
    import subprocess
    import sys

    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_a_killed_writes_temporary_file_is_removed_by_the_next_write_a_live_ones_is_not(tmp_path):
    """A temporary file names its owner: a dead process's goes at once, a live one's stays, an hour-old goes."""
    import os
    import time

    from supportless.base.scratch import STALE_SECONDS, _host, owner_tag
    from supportless.files.meshes import atomic_path

    dead = tmp_path / f".pose.{_host()}-{_dead_pid()}-k3j_x9ab.json"  # a killed run's, a second old
    live = tmp_path / f".pose.{owner_tag()}-q1w2e3r4.json"  # this process's own write under way
    old = tmp_path / ".pose.z9y8x7w6.json"  # an owner-less name an hour old (or another host's)
    other = tmp_path / f".poses.{_host()}-{_dead_pid()}-k3j_x9ab.json"  # another destination's
    for f in (dead, live, old, other):
        f.write_text("{}")
    past = time.time() - STALE_SECONDS - 60
    os.utime(old, (past, past))
    with atomic_path(tmp_path / "pose.json") as tmp:
        assert owner_tag() in tmp.name
        tmp.write_text("{}")
    assert not dead.exists() and not old.exists() and live.exists() and other.exists()
    assert (tmp_path / "pose.json").read_text() == "{}"


def test_a_rig_cache_entry_left_half_written_by_a_kill_is_removed_by_the_next_write(tmp_path):
    import supportless as sl
    from supportless.base.scratch import _host

    sl.load_rig("demo:branch", cache_dir=tmp_path)
    entry = next(tmp_path.glob("*.npz"))
    leftover = tmp_path / f".{entry.stem}.{_host()}-{_dead_pid()}-abcd1234.npz"
    leftover.write_bytes(b"half")
    entry.unlink()  # the rerun writes the entry again
    sl.load_rig("demo:branch", cache_dir=tmp_path)
    assert not leftover.exists() and entry.exists()


def test_every_kind_of_scratch_a_killed_run_leaves_is_removed_by_the_next_run(tmp_path, monkeypatch):
    """The scratch names the tool makes, each left by a dead process, and what removes it on the next run."""
    import tempfile

    from supportless.base.isolated import run_isolated
    from supportless.base.scratch import _host, scratch_dir

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # the system temporary folder, for this test
    tag = f"{_host()}-{_dead_pid()}-"
    left = {"native": tmp_path / f"supportless-native-{tag}a1b2c3d4",  # a native call's (TetGen, CGAL, BBW)
            "slice": tmp_path / f"supportless-slice-{tag}e5f6g7h8",  # a PrusaSlicer run's
            "ui": tmp_path / f"supportless-ui-{tag}i9j0k1l2"}  # the browser app's export folder
    for path in left.values():
        path.mkdir()
        (path / "half").write_bytes(b"x")
    assert run_isolated(sum, [1, 2]) == 3  # a native call clears its kind
    assert not left["native"].exists() and left["slice"].exists()
    with scratch_dir("supportless-slice-") as mine:  # what slice_support uses
        assert mine.exists() and not left["slice"].exists()
    assert not mine.exists()
    with scratch_dir("supportless-ui-"):
        pass
    assert not left["ui"].exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith("supportless-")]


@pytest.mark.parametrize("squash, fragment", [((0, 0, 0), "has no size"), ((1, 1, 0), "is flat (no volume)"),
                                              ((0, 1, 1), "is flat (no volume)"), ((1, 0, 0), "is flat (no volume)")],
                         ids=["point", "onto-z0", "onto-x0", "onto-a-line"])
def test_a_collapsed_mesh_is_one_line_naming_the_file(tmp_path, squash, fragment):
    """All vertices on a point, a plane or a line: one line, not a traceback or a misleading joint message."""
    import supportless as sl
    from supportless.base.errors import InputError

    V, F, J, B = sl.demo_figure("branch")[:4]
    sl.write_mesh(tmp_path / "m.obj", V * np.asarray(squash, float), F)
    sl.write_tgf(tmp_path / "m.tgf", J, B)
    with pytest.raises(InputError) as err:
        sl.load_rig(tmp_path / "m.obj", tmp_path / "m.tgf", cache=False)
    message = str(err.value)
    assert fragment in message and str(tmp_path / "m.obj") in message and "\n" not in message


def test_check_not_flat_accepts_a_thin_but_real_solid():
    from supportless.files.meshes import check_not_flat

    V, F = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1e-3]], float), np.array([[0, 2, 1], [0, 1, 3],
                                                                                          [1, 2, 3], [0, 3, 2]])
    check_not_flat(V, F)  # a sliver 1/1000 as thick as wide still encloses volume


OBJ_PLAIN = """# a tetrahedron as a sculpting tool writes it
mtllib t.mtl
o tetra
v 0 0 0
v 1.5 0 0\r
v 0 1 0
v 0 0 1e0
vt 0.1 0.1
vt 0.9 0.1
vt 0.1 0.9
vt 0.9 0.9
vn 0 0 1
g body
usemtl skin
s 1
f 1/1/1 3/3/1 2/2/1
f 1/1/1 2/2/1 4/4/1
f 2/2/1 3/3/1 4/4/1
f 1/1/1  4/4/1 3/3/1
"""


def test_obj_rows_are_kept_when_every_one_holds_three_words_as_split_counts_them():
    rng = np.random.default_rng(0)
    words, blanks = [b"1", b"-2.5e3", b"7/7/1"], [b"", b" ", b"  "]

    def row():  # usually three words, with any spacing around them
        count = rng.choice([0, 2, 3, 3, 3, 3, 4])
        gaps = [blanks[i] for i in rng.integers(0, 3, count + 1)]
        gaps[1:-1] = [gap or b" " for gap in gaps[1:-1]]
        return gaps[0] + b"".join(words[rng.integers(3)] + gap for gap in gaps[1:]) if count else gaps[0]

    verdicts = []
    for _ in range(300):
        rows = [row() for _ in range(rng.integers(1, 4))]
        verdicts.append(all(len(r.split()) == 3 for r in rows))
        text = b"".join(b"v " + r + b"\n" for r in rows)
        chars = np.frombuffer(text, np.uint8)
        ends = np.flatnonzero(chars == ord("\n"))
        kept = rows_of_three(chars, np.r_[0, ends[:-1] + 1], ends)
        assert kept == (b"".join(r + b"\n" for r in rows) if verdicts[-1] else None), rows
    assert 50 < sum(verdicts) < 250  # both verdicts are tried


@pytest.mark.parametrize("text, plain", [
    (OBJ_PLAIN, True),
    (OBJ_PLAIN.replace("/", "//", 1).replace("//", "/", 1), True),
    (OBJ_PLAIN.replace("f 2/2/1 3/3/1 4/4/1", "f 2/2/1 3/3/1 4/4/1 2/2/1"), False),  # a polygon: trimesh's reader
    (OBJ_PLAIN.replace("f 2/2/1 3/3/1 4/4/1", "f -3/2/1 -2/3/1 -1/4/1"), False),  # relative indices: trimesh's
    (OBJ_PLAIN.replace("v 0 1 0", "v 0 1 0 0.5 0.5 0.5"), False),  # vertex colours: trimesh's reader
    (OBJ_PLAIN.replace("s 1", "curv 0 1"), False),  # a line it does not know
])
def test_a_plain_obj_is_read_in_one_pass_as_trimesh_reads_it(tmp_path, monkeypatch, text, plain):
    path = tmp_path / "t.obj"
    path.write_bytes(text.encode())
    assert (io._read_plain_obj(path) is not None) == plain
    V, F = io.read_mesh(path)
    monkeypatch.setattr(io, "_read_plain_obj", lambda p: None)
    V2, F2 = io.read_mesh(path)
    np.testing.assert_array_equal(V, V2)
    np.testing.assert_array_equal(F, F2)
    if plain:
        np.testing.assert_array_equal(V, [[0, 0, 0], [1.5, 0, 0], [0, 1, 0], [0, 0, 1]])
        np.testing.assert_array_equal(F, [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def test_a_bad_vertex_line_of_an_otherwise_plain_obj_still_names_its_line(tmp_path):
    path = tmp_path / "t.obj"
    path.write_text(OBJ_PLAIN.replace("v 0 1 0", "v 0 one 0"))
    with pytest.raises(sl.InputError, match="line 6 is not a vertex"):
        io.read_mesh(path)


@pytest.mark.parametrize("kind", ["binary", "ascii", "two solids"])
def test_stl_read_as_trimesh_reads_it(tmp_path, kind):
    # binary and single-solid ASCII STL go through trimesh's STL reader alone; several solids through trimesh.load:
    # either way the mesh trimesh.load gives, welded
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=2)
    path = tmp_path / "m.stl"
    if kind == "binary":
        mesh.export(path, file_type="stl")
    else:
        text = trimesh.exchange.stl.export_stl_ascii(mesh)
        path.write_text(text if kind == "ascii" else text + text.replace("solid", "solid other", 1))
    assert (io._read_stl(path) is None) == (kind == "two solids")
    loaded = trimesh.load(str(path), file_type="stl", process=False, force="mesh")
    expected = io.merge_duplicate_vertices(np.asarray(loaded.vertices, np.float64), np.asarray(loaded.faces, np.int64))
    V, F = sl.read_mesh(path)
    np.testing.assert_array_equal(V, expected[0])
    np.testing.assert_array_equal(F, expected[1])
    assert len(F) == len(mesh.faces) * (2 if kind == "two solids" else 1)
