"""Files that print as written: +Z up, millimetres, on the plate; a 3MF a strict reader accepts; one support figure."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

import supportless as sl
from supportless.apps.cli import main
from supportless.base.geometry import signed_volume
from supportless.files.printframe import REFERENCE_HEIGHT_MM, print_frame, rotation_to_z


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)


def tilted_box(up):
    """A closed box 3 x 1 x 2 (tall along ``up``) and the unit up vector."""
    import trimesh

    up = np.asarray(up, np.float64) / np.linalg.norm(up)
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))  # tallest along its own z
    R = np.linalg.inv(rotation_to_z(up))  # its z goes to up
    return box.vertices @ R.T + [5.0, -2.0, 7.0], np.asarray(box.faces), up


@pytest.mark.parametrize("up", [(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, -1, 0), (0, 0, -1), (0.3, 0.8, -0.5)])
def test_the_print_frame_has_up_along_z_in_mm_on_the_plate_centred(up):
    V, F, u = tilted_box(up)
    frame = print_frame(V, u)
    P = frame.place(V)
    assert P[:, 2].min() == pytest.approx(0.0, abs=1e-12)
    assert np.ptp(P[:, 2]) == pytest.approx(REFERENCE_HEIGHT_MM)  # the box's height along up is 60 mm
    np.testing.assert_allclose(0.5 * (P[:, :2].min(axis=0) + P[:, :2].max(axis=0)), 0.0, atol=1e-9)
    # a proper rotation and a uniform scale: no mirror, volumes scale by the cube of the factor
    assert signed_volume(P, F) == pytest.approx(signed_volume(V, F) * frame.scale ** 3)
    np.testing.assert_allclose(rotation_to_z(u) @ u, [0, 0, 1], atol=1e-12)
    # distances scale uniformly: the frame is a similarity
    i, j = 0, 5
    assert np.linalg.norm(P[i] - P[j]) == pytest.approx(frame.scale * np.linalg.norm(V[i] - V[j]))


def test_y_up_goes_to_z_up_with_the_front_towards_minus_y():
    V = np.array([[0.0, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]])
    P = print_frame(V, (0, 1, 0), height_mm=10.0).place(V)
    # y (up) -> z, z (the model's front) -> -y, x stays
    np.testing.assert_allclose(P[1] - P[0], [0, 0, 10], atol=1e-12)
    np.testing.assert_allclose(P[2] - P[0], [0, -10, 0], atol=1e-12)
    np.testing.assert_allclose(P[3] - P[0], [10, 0, 0], atol=1e-12)


def test_keep_units_and_height_and_the_notes():
    V, F, u = tilted_box((0, 1, 0))
    assert print_frame(V, u, keep_units=True).scale == 1.0
    assert print_frame(V, u, height_mm=120.0).height_mm == 120.0
    assert print_frame(V * 0.001, u).scale == pytest.approx(20000.0)
    with pytest.raises(sl.InputError, match="--keep-units and --height-mm"):
        print_frame(V, u, height_mm=10.0, keep_units=True)
    with pytest.raises(sl.InputError, match="no height"):
        print_frame(V * [1, 0, 1], u)
    assert "printed 60 mm tall" in print_frame(V * 0.05, u).note()
    assert "0.15 units" in print_frame(V * 0.05, u).note()
    assert print_frame(V * 0.05, u).unusual() is None  # 60 mm is a figure
    tiny = print_frame(V * 0.001, u, keep_units=True)
    assert "0.003 mm" in tiny.unusual() and "--height-mm" in tiny.unusual()
    assert print_frame(V * 1000, u, keep_units=True).unusual() is not None  # 3 m
    assert print_frame(V * 10, u, keep_units=True).unusual() is None  # 30 mm


def test_gltf_frame_is_y_up_in_metres():
    V, F, u = tilted_box((0, 0, 1))
    frame = print_frame(V, u, height_mm=60.0)
    G = frame.to_gltf(V)
    assert np.ptp(G[:, 1]) == pytest.approx(0.060)
    assert G[:, 1].min() == pytest.approx(0.0, abs=1e-12)
    assert signed_volume(G, F) == pytest.approx(signed_volume(frame.place(V), F) * 1e-9)


# --------------------------------------------------------------------- 3MF


def test_the_3mf_passes_the_reference_reader_in_strict_mode(tmp_path):
    import lib3mf  # the 3MF Consortium's reference reader (a test dependency)

    V, F, u = tilted_box((0, 1, 0))
    P = print_frame(V, u).place(V)
    sl.write_mesh(tmp_path / "box.3mf", P, F)
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    reader = model.QueryReader("3mf")
    reader.SetStrictModeActive(True)
    reader.ReadFromFile(str(tmp_path / "box.3mf"))
    assert reader.GetWarningCount() == 0
    assert model.GetUnit() == lib3mf.ModelUnit.MilliMeter
    items = model.GetBuildItems()
    assert items.Count() == 1 and items.MoveNext()
    item = items.GetCurrent()
    assert not item.HasObjectTransform()  # a slicer places it where its coordinates say
    mesh = model.GetMeshObjectByID(item.GetObjectResourceID())
    assert (mesh.GetVertexCount(), mesh.GetTriangleCount()) == (len(V), len(F))
    got = np.array([mesh.GetVertex(i).Coordinates[:] for i in range(len(V))])
    np.testing.assert_allclose(got, P, atol=1e-5)
    tri = np.array([mesh.GetTriangle(i).Indices[:] for i in range(len(F))])
    np.testing.assert_array_equal(tri, F)


def test_a_3mf_reads_back_with_trimesh_as_written(tmp_path):
    V, F, u = tilted_box((0, 1, 0))
    P = print_frame(V, u).place(V)
    sl.write_mesh(tmp_path / "box.3mf", P, F)
    W, G = sl.read_mesh(tmp_path / "box.3mf")
    assert len(G) == len(F)
    np.testing.assert_allclose(np.sort(W, axis=0), np.sort(P, axis=0), atol=1e-5)


# --------------------------------------------------------------------- the commands


@pytest.fixture(scope="module")
def tiny_files(tmp_path_factory):
    """The branch figure as a tiny Y-up OBJ (0.06 units tall) and as a Z-up STL, with their TGFs."""
    folder = tmp_path_factory.mktemp("tiny")
    V, F, J, B = sl.demo_figure("branch")
    s = 0.06 / np.ptp(V[:, 1])
    files = {}
    for name, turn in (("yup.obj", np.eye(3)), ("zup.stl", rotation_to_z((0, 1, 0)))):
        mesh = folder / name
        sl.write_mesh(mesh, (V * s) @ turn.T, F)
        sl.write_tgf(mesh.with_suffix(".tgf"), (J * s) @ turn.T, B)
        files[name] = mesh
    return folder, files


@pytest.mark.slow
@pytest.mark.parametrize("name,up", [("yup.obj", "y"), ("zup.stl", "z")])
def test_optimize_and_apply_write_z_up_millimetre_files_at_the_default_size(tiny_files, name, up, tmp_path, no_slicer):
    folder, files = tiny_files
    out = tmp_path / "out"
    cache = folder / "cache"
    res = run("optimize", files[name], "--up", up, "--cache-dir", cache, "--particles", 8, "--iterations", 3,
              "--seed", 1, "-o", out / "posed.stl", "--upright-out", out / "standing.obj",
              "--pose", out / "pose.json", "--report", out / "report.json")
    assert res.exit_code == 0, (res.output, res.exception)
    assert "printed 60 mm tall" in res.stderr and "--keep-units" in res.stderr
    for f in ("posed.stl", "standing.obj"):
        P, _ = sl.read_mesh(out / f)
        assert P[:, 2].min() == pytest.approx(0.0, abs=0.01)
        np.testing.assert_allclose(0.5 * (P[:, :2].min(axis=0) + P[:, :2].max(axis=0)), 0.0, atol=0.01)
        assert 20.0 < np.ptp(P[:, 2]) < 300.0
    report = json.loads((out / "report.json").read_text())
    assert report["print_frame"]["height_mm"] == REFERENCE_HEIGHT_MM
    assert report["predicted_slicer"]["height_mm"] == REFERENCE_HEIGHT_MM
    # the rest pose (all angles zero) written by apply is the rest pose, 60 mm tall
    pose = json.loads((out / "pose.json").read_text())
    zero = tmp_path / "zero.json"
    sl.write_pose(zero, np.zeros_like(np.asarray(pose["angles"])), np.asarray(pose["bones"]),
                  extra={"print_frame": pose["print_frame"]})
    res = run("apply", files[name], "--up", up, "--cache-dir", cache, "--pose", zero, "-o", tmp_path / "rest.3mf")
    assert res.exit_code == 0, res.output
    R, _ = sl.read_mesh(tmp_path / "rest.3mf")
    assert np.ptp(R[:, 2]) == pytest.approx(60.0, abs=1e-3) and R[:, 2].min() == pytest.approx(0.0, abs=1e-4)
    # apply with the saved pose writes the same geometry as optimize did
    res = run("apply", files[name], "--up", up, "--cache-dir", cache, "--pose", out / "pose.json",
              "-o", tmp_path / "again.stl")
    assert res.exit_code == 0, res.output
    np.testing.assert_array_equal(sl.read_mesh(tmp_path / "again.stl")[0], sl.read_mesh(out / "posed.stl")[0])


def test_a_y_up_and_a_z_up_copy_of_one_model_print_the_same(tiny_files, tmp_path):
    folder, files = tiny_files
    written = []
    for name, up in (("yup.obj", "y"), ("zup.stl", "z")):
        zero = tmp_path / f"{name}.json"
        rig = sl.load_rig(files[name], up=up, cache_dir=folder / "cache")
        sl.write_pose(zero, rig.rest_angles(), rig.bones)
        res = run("apply", files[name], "--up", up, "--cache-dir", folder / "cache", "--pose", zero,
                  "-o", tmp_path / f"{name}.stl")
        assert res.exit_code == 0, res.output
        written.append(sl.read_mesh(tmp_path / f"{name}.stl")[0])
    np.testing.assert_allclose(written[0], written[1], atol=1e-3)


def test_height_and_keep_units_choose_the_printed_size(tiny_files, tmp_path):
    folder, files = tiny_files
    rig = sl.load_rig(files["yup.obj"], cache_dir=folder / "cache")
    zero = tmp_path / "zero.json"
    sl.write_pose(zero, rig.rest_angles(), rig.bones)
    common = ("apply", files["yup.obj"], "--cache-dir", folder / "cache", "--pose", zero)
    res = run(*common, "--height-mm", 120, "-o", tmp_path / "tall.stl")
    assert res.exit_code == 0, res.output
    assert np.ptp(sl.read_mesh(tmp_path / "tall.stl")[0][:, 2]) == pytest.approx(120.0, abs=1e-3)
    res = run(*common, "--keep-units", "-o", tmp_path / "own.stl")
    assert res.exit_code == 0, res.output
    assert np.ptp(sl.read_mesh(tmp_path / "own.stl")[0][:, 2]) == pytest.approx(0.06, rel=1e-4)
    assert "warning" in res.stderr and "far outside" in res.stderr  # 0.06 mm is said, never silent
    res = run(*common, "--keep-units", "--height-mm", 50, "-o", tmp_path / "both.stl")
    assert res.exit_code == 2 and "do not go together" in res.stderr
    assert not (tmp_path / "both.stl").exists()


@pytest.mark.slow
def test_the_summary_leads_with_the_reports_support_line(tpose_rig, tmp_path, no_slicer):
    res = run("optimize", "demo:tpose", "--particles", 8, "--iterations", 3, "--seed", 0, "-q",
              "-o", tmp_path / "t.stl", "--report", tmp_path / "r.json")
    assert res.exit_code == 0, (res.output, res.exception)
    report = json.loads((tmp_path / "r.json").read_text())
    line = report["support"]["line"]
    assert any(t.startswith("support ") for t in res.stdout.splitlines())
    assert " ".join(res.stdout.split()).startswith(" ".join(line.split()))
    assert " g (" in line and "estimate" in line
    assert "e+0" not in res.stdout  # figures in human units
    assert "prism" not in res.stdout  # the estimates only with --verbose
    verbose = run("optimize", "demo:tpose", "--particles", 8, "--iterations", 3, "--seed", 0, "-q", "-v",
                  "-o", tmp_path / "t2.stl")
    assert verbose.exit_code == 0 and "estimate:" in verbose.stdout and "(prisms)" in verbose.stdout
    assert "cm3" in verbose.stdout


def test_the_progress_total_never_changes(tpose_rig):
    seen = []
    sl.optimize(tpose_rig, particles=6, iterations=3, seed=0, orient="free",
                callback=lambda it, info: seen.append((it, info["iterations"], info["phase"])))
    totals = {t for _, t, _ in seen}
    assert len(totals) == 1
    assert [it for it, _, _ in seen] == list(range(1, len(seen) + 1))
    assert seen[-1][0] == totals.pop()
    # the tpose has a mirror plane: one mirrored search, its two phases counted as one
    assert seen[0][2] == "pose" and seen[-1][2] == "pose and turn" and len(seen) == 2 * 3


@pytest.mark.slow
def test_slice_check_measures_the_written_file_itself(prusa_slicer, tiny_files, tmp_path):
    from supportless.slicing.prusaslicer import slice_support

    folder, files = tiny_files
    out = tmp_path / "posed.stl"
    # the slicer measures the written file; choosing among answers by slicing them is another test's subject
    res = run("optimize", files["yup.obj"], "--cache-dir", folder / "cache", "--particles", 8, "--iterations", 3,
              "--seed", 2, "-q", "--slice-rank", 0, "-o", out, "--report", tmp_path / "r.json", "--slice-check")
    assert res.exit_code == 0, (res.output, res.exception)
    report = json.loads((tmp_path / "r.json").read_text())
    by_hand = slice_support([out], up=(0, 0, 1), scale=1.0, by_feature=True).support_mm[0]
    assert report["slice_check"]["after"]["support_mm"] == pytest.approx(by_hand, rel=2e-3, abs=1.0)
    assert report["slice_check"]["sliced_file"] == str(out)
    assert report["support"]["source"] == "PrusaSlicer"
    assert report["support"]["after_mm"] == report["slice_check"]["after"]["support_mm"]
    first = next(t for t in res.stdout.splitlines() if t.startswith("support "))
    assert "PrusaSlicer" in " ".join(res.stdout.split()) and first.split(" -> ")[0] in report["support"]["line"]
    assert report["slice_check"]["height_mm"] == pytest.approx(60.0, abs=1e-3)


@pytest.mark.parametrize("height_mm, warned", [(79_000.0, True), (12_000.0, True), (0.5, True), (3.2, False),
                                               (1_800.0, False), (400.0, False)])
def test_a_file_size_no_figure_has_is_one_warning_naming_height_mm(height_mm, warned):
    """A glTF says metres: a 79 m fox or a 0.5 mm person means wrong units; 3.2 mm to 1.8 m are believed."""
    V = np.array([[0.0, 0.0, 0.0], [0.3, height_mm, 0.2], [0.1, height_mm / 2, 0.4]]) * [height_mm / 10, 1, 1]
    frame = print_frame(V, (0.0, 1.0, 0.0), unit="mm")
    assert frame.height_mm == REFERENCE_HEIGHT_MM
    message = frame.unusual()
    assert (message is not None) == warned
    if warned:
        assert "--height-mm" in message and "units may be wrong" in message
    # a file of unknown units (OBJ) says nothing about its own size
    assert print_frame(V, (0.0, 1.0, 0.0)).unusual() is None
