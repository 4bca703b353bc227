"""The browser app's parts that need no browser: uploads checked as the CLI checks files, the support preview's
boxes, the figures in human units, the support filament the panel leads with, the rule a pose breaks in words, and
the Slice button's background run."""

from __future__ import annotations

import time

import numpy as np
import pytest
from slicers import fake_exe, stand_in_slicer

from supportless.apps.ui import opener
from supportless.apps.ui.filament import support_lead
from supportless.apps.ui.panel import lead_markdown
from supportless.apps.ui.readout import broken_rules, filament_text, grams, volume_text
from supportless.apps.ui.columns import column_boxes, column_shell
from supportless.apps.ui.slicerun import SliceRun, slice_markdown
from supportless.apps.ui.state import EditorState
from supportless.base.errors import InputError
from supportless.energies.support import support_columns, support_volume
from supportless.slicing.choice import SlicerChoice


# --------------------------------------------------------------------------- #
# uploads
# --------------------------------------------------------------------------- #
@pytest.fixture
def uploads():
    u = opener.Uploads()
    yield u
    u.close()
    assert not u.folder.exists()


def test_a_skeleton_waits_for_its_mesh_and_a_gltf_needs_none(uploads):
    assert uploads.receive("figure.tgf", b"1 0 0 0\n2 0 1 0\n#\n1 2\n") is None
    mesh = uploads.receive("figure.obj", b"v 0 0 0\n")
    assert mesh.parent == uploads.folder and mesh.read_bytes() == b"v 0 0 0\n"
    assert uploads.skeleton_for(mesh).name == "figure.tgf"
    assert uploads.skeleton_for(mesh) is None  # used once
    uploads.receive("figure.tgf", b"x")
    assert uploads.skeleton_for(uploads.receive("Fox.glb", b"glTF")) is None  # a glTF has its own skeleton


@pytest.mark.parametrize("name, content, words", [
    ("notes.txt", b"hello", "notes.txt: not a model the app opens"),
    ("empty.stl", b"", "empty.stl: the file is empty"),
])
def test_a_bad_upload_is_one_line_naming_the_file(uploads, name, content, words):
    with pytest.raises(InputError) as e:
        uploads.receive(name, content)
    assert str(e.value).startswith(words) and "\n" not in str(e.value)
    assert list(uploads.folder.iterdir()) == []


def test_an_upload_over_the_limit_is_refused(uploads, monkeypatch):
    monkeypatch.setattr(opener, "MAX_UPLOAD_BYTES", 10)
    with pytest.raises(InputError, match="big.stl: 0 MB is more than the 0 MB a page may send"):
        uploads.receive("big.stl", b"x" * 11)


def test_an_upload_never_leaves_the_folder(uploads):
    for name in ("../../evil.obj", "/etc/passwd.stl", "..\\..\\win.glb", ".hidden.obj"):
        path = uploads.receive(name, b"data")
        assert path.parent == uploads.folder and not path.name.startswith(".")


# --------------------------------------------------------------------------- #
# support preview
# --------------------------------------------------------------------------- #
def test_support_columns_are_the_columns_the_estimate_sums(tpose_rig):
    rig = tpose_rig
    V = rig.pose(rig.rest_angles())
    bottoms, heights, cell, basis = support_columns(V, rig.faces, rig.up, 45.0, 48)
    assert len(heights) > 0 and np.all(heights > 0)
    assert np.allclose(basis @ basis.T, np.eye(3)) and np.allclose(basis[2], rig.up)
    expected = support_volume(V, rig.faces, rig.up, 45.0, 48, backend="numpy")
    assert float((heights * cell ** 2).sum()) == pytest.approx(expected, rel=1e-12)
    # every column's foot stands on the plate or on the body below, never under the plate
    assert (bottoms @ rig.up).min() >= (V @ rig.up).min() - 1e-9


def test_column_boxes_are_closed_boxes_of_the_columns_volume():
    import trimesh

    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    basis = Q * np.sign(np.linalg.det(Q))  # a right-handed frame
    bottoms, heights = rng.normal(size=(4, 3)) * 10, rng.uniform(0.5, 3.0, 4)
    V, F = column_boxes(bottoms, heights, 0.7, basis)
    assert V.shape == (32, 3) and F.shape == (48, 3)
    for k in range(4):
        box = trimesh.Trimesh(V[8 * k:8 * k + 8], F[12 * k:12 * k + 12] - 8 * k, process=False)
        assert box.is_watertight and box.volume == pytest.approx(heights[k] * 0.49)  # outward: positive
        assert np.allclose(box.vertices.mean(axis=0), bottoms[k] + heights[k] / 2 * basis[2])


def _right_handed(seed):
    Q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return Q * np.sign(np.linalg.det(Q))


def test_the_column_shell_of_a_block_is_its_outside_only():
    """Four equal columns on a 2 x 2 grid: one closed box of 8 top and foot triangles and 16 outer wall ones."""
    import trimesh

    basis, cell = _right_handed(4), 0.5
    feet = np.c_[np.array([[0, 0], [1, 0], [0, 1], [1, 1]]) * cell + 3.0, np.zeros(4)] @ basis
    V, F = column_shell(feet, np.full(4, 2.0), cell, basis)
    block = trimesh.Trimesh(V, F)  # welded
    assert len(F) == 32 and block.is_watertight and block.volume == pytest.approx(4 * 2.0 * cell ** 2)
    assert block.area == pytest.approx(2 * (2 * cell) ** 2 + 4 * (2 * cell) * 2.0)  # a 1 x 1 x 2 box's


def test_the_column_shell_encloses_the_columns_volume_and_is_seen_from_outside():
    """Random columns (feet at different heights, cells holding two columns, empty cells): the shell's signed
    volume is the columns' (its walls face out, the inner ones cancel or are gone), it never has more triangles
    than the boxes, and a point inside a column is inside it (winding number 1), one beside all is outside."""
    import igl

    rng, basis, cell = np.random.default_rng(5), _right_handed(6), 0.4
    ij = np.array([(i, j) for i in range(12) for j in range(12) if rng.random() < 0.7], np.float64)
    twice = ij[rng.random(len(ij)) < 0.25]
    ij = np.r_[ij, twice]
    foot = np.r_[rng.uniform(0, 1, len(ij) - len(twice)), rng.uniform(5, 6, len(twice))]
    heights = np.r_[rng.uniform(0.1, 3, len(ij) - len(twice)), rng.uniform(0.1, 1, len(twice))]
    feet = np.c_[ij * cell - 2.0, foot] @ basis
    V, F = column_shell(feet, heights, cell, basis)
    Vb, Fb = column_boxes(feet, heights, cell, basis)
    assert len(F) <= len(Fb)
    signed = np.einsum("ij,ij->i", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])).sum() / 6
    assert signed == pytest.approx(heights.sum() * cell ** 2, rel=1e-12)
    centres = feet + heights[:, None] / 2 * basis[2]
    outside = np.array([[-20.0, 0.0, 0.0]]) @ basis
    w = igl.winding_number(V, F, np.r_[centres, outside])  # exact: the sum of solid angles
    assert np.allclose(w[:-1], 1.0, atol=1e-6) and abs(w[-1]) < 1e-6
    area = lambda V, F: np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum() / 2
    assert area(V, F) < area(Vb, Fb)  # less to blend through


# --------------------------------------------------------------------------- #
# figures in words and human units
# --------------------------------------------------------------------------- #
def test_volumes_read_in_printed_millimetres_and_grams():
    assert grams(1000.0) == pytest.approx(1.24)  # 1 cm³ of PLA
    assert volume_text(9.48, 10.0) == "9,480 mm³ ≈ 11.8 g"  # 9.48 units³ at 10 mm per unit
    assert volume_text(0.5, 1.0) == "0.5 mm³ ≈ 0.00 g"
    assert volume_text(None, 1.0) == "n/a"
    assert volume_text(9.48, 10.0, with_grams=False) == "9,480 mm³"
    assert filament_text(4685.2, 13.97) == "4,685 mm ≈ 14.0 g" and filament_text(4685.2, None) == "4,685 mm"


# --------------------------------------------------------------------------- #
# the support figure the panel leads with
# --------------------------------------------------------------------------- #
@pytest.fixture(scope="module")
def summarised(tmp_path_factory, branch_files):
    """``supportless optimize`` of the branch figure with no slicer (the slicer model chooses a turned answer): its
    printed summary, pose file and report."""
    import json

    from click.testing import CliRunner

    from supportless.apps.cli import main

    out = tmp_path_factory.mktemp("summarised")
    result = CliRunner().invoke(main, [str(a) for a in (
        "optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 10, "--iterations",
        4, "--seed", 2, "-q", "-o", out / "printed.stl", "--pose", out / "pose.json", "--report", out / "report.json")],
        env={"SUPPORTLESS_PRUSA_SLICER": str(out / "no-such-slicer"), "SUPPORTLESS_CURA_ENGINE": str(out / "none")})
    assert result.exit_code == 0, result.output
    return out, result.stdout, json.loads((out / "report.json").read_text())


def test_the_lead_is_the_command_lines_predicted_filament(summarised, branch_files):
    import supportless as sl

    out, stdout, report = summarised
    summary = report["support"]  # the line the summary prints first
    printed = " ".join(stdout.split())  # as printed, rich's wrapping undone
    assert summary["source"] == "predicted" and summary["line"] in printed
    assert not np.allclose(report["print_rotation"]["matrix"], np.eye(3))  # turned: counted as printed
    # the same pose of the same model in the app
    state = EditorState(sl.load_rig(branch_files["mesh"], cache_dir=branch_files["cache"]), workdir=out)
    state.load_pose(out / "pose.json")
    np.testing.assert_allclose(state.get_rotation(), report["print_rotation"]["matrix"], atol=1e-12)
    lead = support_lead(state, *state.get_pose())
    assert lead["source"] == "estimate" and lead["estimate"] is None and not lead["other_slice"]
    for key, theirs in (("mm", "after_mm"), ("g", "after_g"), ("rest_mm", "before_mm"), ("rest_g", "before_g"),
                        ("reduction_percent", "reduction_percent"), ("height_mm", "height_mm")):
        assert lead[key] == pytest.approx(summary[theirs], rel=1e-9), key
    # said alike, labelled an estimate in both
    line, = lead_markdown(lead)
    assert f"**{summary['after_mm']:,.0f} mm ≈ {summary['after_g']:.1f} g**" in line
    assert f"{summary['after_g']:.1f} g ({summary['after_mm']:,.0f} mm)" in printed
    assert "estimate" in line and "predicted for PrusaSlicer, an estimate" in printed


def _sliced(angles, R, before_mm, after_mm):
    return {"before": {"support_mm": before_mm, "support_g": before_mm / 300}, "engine": "cura", "support": "tree",
            "after": {"support_mm": after_mm, "support_g": after_mm / 300}, "height_mm": 60.0, "pose": (angles, R)}


def test_a_slice_of_this_pose_leads_and_the_columns_follow(branch_rig, tmp_path):
    from supportless.apps.ui.panel import measures_markdown

    state = EditorState(branch_rig, workdir=tmp_path)
    state.set_bone_angles(branch_rig.bone_count - 1, [0.0, 0.0, 30.0])
    angles, R = state.get_pose()
    estimate = support_lead(state, angles, R)
    lead = support_lead(state, angles, R, slice_report=_sliced(angles, R, 3000.0, 1200.0))
    assert lead["source"] == "Cura, tree supports" and lead["mm"] == 1200.0 and lead["g"] == pytest.approx(4.0)
    assert lead["reduction_percent"] == pytest.approx(60.0) and lead["estimate"]["mm"] == estimate["mm"]
    text = measures_markdown(state.measure(exact=False), state.settings, {}, 3, state.print_frame.scale, [], lead)
    first, second = text.splitlines()[:2]
    assert first.startswith("- Support filament, sliced by Cura, tree supports: **1,200 mm ≈ 4.0 g** (60.0 % less")
    assert f"the estimate: {filament_text(estimate['mm'], estimate['g'])}" in first
    # the preview's column volume: its own line after it, no grams beside the slicer's
    assert second.startswith("- Support columns (the preview's, solid, as printed): ") and " g" not in second
    # a slice of another pose (or turn) does not lead: the estimate does, and says the slice is not of this pose
    other = _sliced(angles + 0.1, R, 3000.0, 1200.0)
    lead = support_lead(state, angles, R, slice_report=other)
    assert lead["source"] == "estimate" and lead["mm"] == estimate["mm"] and lead["other_slice"]
    assert "the last Slice was of another pose" in lead_markdown(lead)[0]
    assert support_lead(state, angles, np.eye(3)[[1, 0, 2]] * [1, 1, -1], slice_report=_sliced(
        angles, R, 3000.0, 1200.0))["source"] == "estimate"


def test_a_pose_past_a_joint_limit_is_named(tpose_rig):
    from supportless.search.settings import SearchSettings

    rig = tpose_rig
    objective = SearchSettings(joint_limit=45.0).objective(rig)
    angles = rig.rest_angles()
    assert broken_rules(objective, angles) == []
    b = rig.bone_count - 1
    angles[b, 2] = np.radians(60.0)
    rules = broken_rules(objective, angles)
    assert any(f"bone {b + 1} ({rig.bone_names()[b]}) turns 60° at its joint, past its 45° joint limit" in r
               for r in rules), rules
    assert objective(angles) > 1000  # what the words explain


# --------------------------------------------------------------------------- #
# the Slice button's run
# --------------------------------------------------------------------------- #
def _box_mesh(h):
    import trimesh

    m = trimesh.creation.box((10, 10, h))
    return m.vertices + [0, 0, h / 2], m.faces


def test_slice_run_reports_the_slicers_figures(tmp_path, monkeypatch):
    exe = fake_exe(tmp_path, "prusa-slicer", stand_in_slicer("float(rec['v'][:, :, 2].max())"))
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", exe)
    done = []
    run = SliceRun(lambda report, error: done.append((report, error)))
    assert run.start(_box_mesh(20.0), _box_mesh(5.0), SlicerChoice("prusa"))
    assert not run.start(_box_mesh(20.0), _box_mesh(5.0), SlicerChoice("prusa"))  # one at a time
    assert run.wait(120)
    (report, error), = done
    assert error is None
    assert report["before"]["support_mm"] == pytest.approx(20.0) and report["after"]["support_mm"] == pytest.approx(5.0)
    assert report["reduction_percent"] == pytest.approx(75.0)
    text = slice_markdown(report)
    assert "**75.0 % less support** than the rest pose" in text and "| support filament | 20 mm | 5 mm |" in text


def test_slice_run_says_a_failing_slicer_in_one_line_and_cancel_stops_it(tmp_path, monkeypatch):
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", fake_exe(tmp_path, "broken", """\
        import sys
        if "--help" in sys.argv: print("PrusaSlicer-0.0"); sys.exit(0)
        print("error: the model is outside the bed", file=sys.stderr); sys.exit(1)
        """))
    done = []
    run = SliceRun(lambda report, error: done.append((report, error)))
    run.start(_box_mesh(20.0), _box_mesh(5.0), SlicerChoice("prusa"))
    assert run.wait(120)
    (report, error), = done
    assert report is None and "outside the bed" in error and "\n" not in error
    # a slicer that hangs: cancel kills it and says nothing after
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", fake_exe(tmp_path, "slow", """\
        import sys, time
        if "--help" in sys.argv: print("PrusaSlicer-0.0"); sys.exit(0)
        time.sleep(600)
        """))
    done.clear()
    run.start(_box_mesh(20.0), _box_mesh(5.0), SlicerChoice("prusa"))
    assert run.running
    time.sleep(1.0)  # let it start its slicers: cancel must stop those too
    assert run.cancel()
    assert run.wait(30) and done == []
    import subprocess

    assert subprocess.run(["pgrep", "-f", str(tmp_path / "slow")], capture_output=True).returncode == 1  # none left


def test_a_poses_bone_frames_turn_into_quaternions_at_once_as_one_by_one():
    from supportless.apps.ui.scene import matrix_from_quat, quat_from_matrix

    rng = np.random.default_rng(5)
    R = np.stack([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(40)])
    R[np.linalg.det(R) < 0] *= -1.0  # rotations, not reflections
    R[:4] = [np.eye(3), np.diag([1.0, -1, -1]), np.diag([-1.0, 1, -1]), np.diag([-1.0, -1, 1])]  # each of the branches
    q = quat_from_matrix(R)
    assert q.shape == (40, 4)
    assert np.array_equal(q, np.stack([quat_from_matrix(r) for r in R]))
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    assert np.allclose(np.stack([matrix_from_quat(x) for x in q]), R, atol=1e-12)


def test_support_levels_are_thirds_of_the_largest_need_among_the_risky_faces():
    from supportless.apps.ui.scene import support_levels

    rng = np.random.default_rng(2)
    V = rng.normal(size=(60, 3)) * [3.0, 3.0, 8.0]
    F = rng.integers(0, 60, size=(90, 3))
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    up = np.array([0.0, 0.0, 1.0])
    risky = rng.random(len(F)) < 0.4
    levels = support_levels(V, F, up, risky)
    h = [V[f].mean(axis=0) @ up for f in F]  # each face on its own: steepness times height over the lowest face
    need = []
    for f, height in zip(F, h):
        n = np.cross(V[f[1]] - V[f[0]], V[f[2]] - V[f[0]])
        need.append(abs(n @ up) / np.linalg.norm(n) * (height - min(h)))
    top = max(need[i] for i in np.flatnonzero(risky))
    expected = [(0 if x < top / 3 else 1 if x < 2 * top / 3 else 2) if r else 0 for x, r in zip(need, risky)]
    assert levels.tolist() == expected and set(expected) == {0, 1, 2}
    assert not support_levels(V, F, up, np.zeros(len(F), bool)).any()
