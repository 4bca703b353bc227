"""The viewer's editing state (supportless.apps.ui.state) without a browser, a server or viser."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from supportless.apps.ui.state import EditorState
from supportless.base.errors import SupportlessError
from supportless.base.geometry import print_pose
from supportless.base.kinematics import euler_to_matrix
from supportless.files import posefile
from supportless.report.report import pose_measures
from supportless.search.answer import optimize
from supportless.search.orientation import print_direction, rotation_axis_angle, rotation_between
from supportless.search.settings import SearchSettings


@pytest.fixture()
def state(branch_rig, tmp_path):
    s = EditorState(branch_rig, workdir=tmp_path)
    yield s
    s.cancel_optimize()
    s.wait_optimize(60)


def _events(state):
    seen = []
    state.subscribe(lambda event, **info: seen.append((event, info)))
    return seen


def test_needs_no_viser():
    import subprocess
    import sys

    code = ("import sys; import supportless.apps.ui.state; "
            "assert 'viser' not in sys.modules, 'the editing state imported viser'")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_set_angles_and_select_bone(state, branch_rig):
    seen = _events(state)
    m = branch_rig.bone_count
    state.set_bone_angles(m - 1, [10.0, 0.0, -20.0])
    assert np.allclose(np.degrees(state.get_angles()[m - 1]), [10, 0, -20])
    assert np.allclose(state.get_angles()[: m - 1], 0.0)
    assert seen[-1] == ("pose", {"origin": None})
    state.get_angles()[:] = 1.0  # a copy: the state does not change
    assert np.allclose(state.get_angles()[: m - 1], 0.0)
    with pytest.raises(ValueError, match="the rig needs"):
        state.set_angles(np.zeros((m + 1, 3)))
    state.select_bone(m - 1)
    assert state.selected == m - 1 and seen[-1][0] == "selection"
    with pytest.raises(ValueError, match="not one of"):
        state.select_bone(m)


def test_undo_redo_reset(state, branch_rig):
    b = branch_rig.bone_count - 1
    assert not state.undo() and not state.redo()  # nothing yet
    state.set_bone_angles(b, [10.0, 0.0, 0.0], key="a")
    state.set_bone_angles(b, [10.0, 20.0, 0.0], key="b")  # another control: another step
    assert state.undo()
    assert np.allclose(np.degrees(state.get_angles()[b]), [10, 0, 0])
    assert state.undo()
    assert np.allclose(state.get_angles(), 0.0)
    assert not state.undo()
    assert state.redo()
    assert np.allclose(np.degrees(state.get_angles()[b]), [10, 0, 0])
    state.reset()
    assert np.allclose(state.get_angles(), 0.0)
    assert state.undo()  # reset is an undo step
    assert np.allclose(np.degrees(state.get_angles()[b]), [10, 0, 0])
    for v in range(11, 30):  # one slider dragged: one step
        state.set_bone_angles(b, [v, 0.0, 0.0], key=("slider", b, 0))
    assert state.undo()
    assert np.allclose(np.degrees(state.get_angles()[b]), [10, 0, 0])


def gizmo_turn(rig):
    """A child bone turned under a turned parent, as the gizmo would show it.

    Returns
    -------
    child : int
    before : (m, 3) float64
        The pose with the child not yet turned.
    target : (m, 3) float64
        The pose with it turned.
    world : (3, 3) float64
        The child's rotation in the world in ``target``.
    """
    child = int(np.flatnonzero(rig.parents >= 0)[-1])
    parent = int(rig.parents[child])
    target = np.zeros((rig.bone_count, 3))
    target[parent] = np.radians([10.0, -20.0, 15.0])
    target[child] = np.radians([25.0, 30.0, -40.0])
    before = np.where(np.arange(rig.bone_count)[:, None] == child, 0.0, target)
    world = rig.transforms(target)[parent][:, :3] @ euler_to_matrix(target[child])
    return child, before, target, world


def test_world_rotation_becomes_relative_euler_angles(state, branch_rig):
    child, before, target, world = gizmo_turn(branch_rig)
    state.set_angles(before)
    state.set_bone_rotation(child, world)
    assert np.allclose(state.get_angles(), target, atol=1e-12)


def test_save_then_load_a_pose_file(state, branch_rig, tmp_path):
    state.set_bone_angles(branch_rig.bone_count - 1, [5.0, -10.0, 25.0])
    target = state.get_angles()
    payload = state.pose_bytes()
    path = state.save_pose("pose.json")  # relative to the work folder
    assert path == tmp_path / "pose.json"
    data = json.loads(path.read_text())
    assert data["objective"] == pytest.approx(float(state.objective(target)))
    assert data["settings"]["overhang_angle"] == state.settings.overhang_angle
    state.reset()
    assert state.load_pose(path) == path
    assert np.array_equal(state.get_angles(), target)
    assert state.undo() and np.allclose(state.get_angles(), 0.0)  # loading is an undo step
    state.reset()
    state.load_pose_bytes("uploaded.json", payload)  # a file sent from the browser
    assert np.array_equal(state.get_angles(), target)


def test_bad_pose_files_raise_and_keep_the_pose(state, branch_rig, tmp_path):
    state.set_bone_angles(0, [0, 0, 5.0])
    before = state.get_angles()
    other = tmp_path / "other.json"
    posefile.write_pose(other, np.zeros((5, 3)), np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5]]))
    with pytest.raises(SupportlessError, match="skeleton"):
        state.load_pose(other)
    (tmp_path / "junk.json").write_text("{not json")
    with pytest.raises(SupportlessError, match="not a pose file"):
        state.load_pose("junk.json")
    with pytest.raises(SupportlessError, match="no such file"):
        state.load_pose("missing.json")
    with pytest.raises(ValueError):
        state.load_pose_bytes("x.json", b"\x00\x01")
    assert np.array_equal(state.get_angles(), before)


def test_export_mesh_file_and_bytes_on_the_plate(state, branch_rig, tmp_path):
    import trimesh

    state.set_bone_angles(0, [0, 0, 30.0])
    for ext in ("stl", "3mf", "obj"):
        p = state.export_mesh(tmp_path / f"posed.{ext}")
        m = trimesh.load(p, force="mesh")
        assert len(m.faces) == len(branch_rig.faces)
        assert float(m.vertices[:, 2].min()) == pytest.approx(0.0, abs=1e-5)  # a print file: +Z up, on the plate
    assert np.ptp(trimesh.load(tmp_path / "posed.obj", force="mesh").vertices[:, 2]) > 20  # millimetres
    assert np.allclose(state.print_frame.place(state.posed_on_plate()),
                       trimesh.load(tmp_path / "posed.obj", force="mesh", process=False).vertices, atol=1e-5)
    assert state.mesh_bytes("stl") == (tmp_path / "posed.stl").read_bytes()
    with pytest.raises(SupportlessError, match="unknown output format"):
        state.export_mesh(tmp_path / "posed.xyz")


def test_measures_follow_the_pose(state, branch_rig):
    rest = state.measure()
    assert rest["reduction"]["support_prism"] == pytest.approx(0.0, abs=1e-9)
    assert rest["risky"].shape == (len(branch_rig.faces),)
    assert rest["intersecting_face_pairs"] == len(rest["intersecting_faces"]) == 0
    state.set_bone_angles(branch_rig.bone_count - 1, [0.0, 0.0, 40.0])
    moved = state.measure()
    assert moved["objective"] != pytest.approx(rest["objective"])
    assert moved["terms"]["arap"] > rest["terms"]["arap"]
    assert moved["support_prism"] != pytest.approx(rest["support_prism"])
    assert moved["reduction"]["support_prism"] != pytest.approx(0.0)
    assert state.measure(exact=False)["intersecting_faces"] is None  # not checked


def test_measured_objective_is_the_one_the_search_minimises(state, branch_rig):
    """The panel's objective: SearchSettings(...).objective(rig), the value optimize reports for the pose."""
    rig = branch_rig
    state.set_bone_angles(rig.bone_count - 1, [10.0, -5.0, 35.0])
    pose = state.get_angles()
    for changes in ({}, {"w_overhang": 3.0, "overhang_angle": 50.0}, {"overhang_margin": 0.0, "w_arap": 0.5}):
        settings = SearchSettings(**changes)
        state.update_settings(**dataclasses.asdict(settings))
        assert state.settings == settings
        assert np.array_equal(state.get_rotation(), np.eye(3))  # printed as it stands
        expected = float(settings.objective(rig)(pose))
        measured = state.measure(pose)
        assert measured["objective"] == pytest.approx(expected, rel=1e-12)
        assert measured["overhang_angle"] == settings.overhang_angle  # supports at the printer's threshold
        assert state.objective.overhang_angle == settings.search_overhang_angle
        # the value the search reports for this very pose, printed as it stands (no bone free, no turn:
        # the start pose is the result)
        result = optimize(rig, settings.replace(orient="keep"), start=pose, fix="all", iterations=0)
        assert np.array_equal(result.angles, pose) and np.array_equal(result.rotation, np.eye(3))
        assert result.value == pytest.approx(measured["objective"], rel=1e-12)
        # searching the orientation too: the best of the turned starting particles, measured with its turn
        turned = optimize(rig, settings, start=pose, fix="all", iterations=0)
        assert np.array_equal(turned.angles, pose) and not np.allclose(turned.rotation, np.eye(3))
        measured = state.measure(pose, rotation=turned.rotation)
        assert turned.value == pytest.approx(measured["objective"], rel=1e-12)
        assert turned.value < result.value  # the turn is counted: printed on its side it needs less
        assert measured["objective"] == pytest.approx(
            float(settings.objective(rig)(pose, turned.rotation)), rel=1e-12)


def test_settings_share_the_distortion_operators(state):
    arap = state.objective.arap_data
    state.update_settings(w_overhang=2.0, overhang_angle=40.0)
    assert state.objective.arap_data is arap
    same = state.objective
    state.update_settings(particles=7, seed=3)  # search-only settings keep the objective
    assert state.objective is same


def test_invalid_bone_list_is_a_clear_error(state, branch_rig):
    before = state.settings
    with pytest.raises(ValueError, match=r"bone 99 is out of range 1\.\.3"):
        state.update_settings(fix="99")
    with pytest.raises(ValueError, match="'hand' is not a bone number"):
        state.update_settings(free="1, hand")
    assert state.settings == before
    with pytest.raises(ValueError, match="out of range"):
        state.start_optimize(free="0")
    with pytest.raises(ValueError, match="every bone of .* is fixed"):
        state.start_optimize(fix="all", orient="keep")  # with orient="free" the search may still turn it
    assert not state.optimizing
    state.update_settings(fix="1", free="")
    assert state.fixed[0] and state.settings.fix == ("1",)


def test_search_streams_poses_and_is_one_undo_step(state, branch_rig):
    seen = _events(state)
    state.set_bone_angles(branch_rig.bone_count - 1, [0.0, 0.0, 10.0])
    start = state.get_angles()
    start_value = float(state.objective(start))
    assert state.start_optimize(particles=10, iterations=4, seed=2, choose=False)  # the search's own best
    assert not state.start_optimize()  # one search at a time
    assert state.wait_optimize(300)
    result = state.last_result
    assert result is not None and not result.interrupted
    assert result.value <= start_value + 1e-12  # never worse than where it started
    assert np.array_equal(state.get_angles(), result.angles)
    # orient="free" (the default): the pose-only phase and the turning phase, 4 iterations each; the branch has a
    # mirror plane, searched mirrored (SearchSettings.symmetric None) in that one search
    assert result.symmetry is not None and result.symmetry["kept"] == "mirrored"
    total = 2 * 4
    assert state.progress == {"iteration": total, "iterations": total, "value": result.value, "running": False,
                              "cancelled": False, "free_bones": int((~state.fixed).sum())}
    assert state.search_settings.particles == 10 and state.settings.particles == SearchSettings().particles
    events = [e for e, _ in seen]
    assert events[0] == "pose" and events[1] == "search_started" and events[-1] == "search_done"
    assert events.count("progress") == total
    assert ("pose", {"origin": "search"}) in seen
    assert state.undo()
    assert np.array_equal(state.get_angles(), start)
    # a long search stops when cancelled and keeps its best pose
    assert state.start_optimize(particles=8, iterations=100000)
    state.cancel_optimize()
    assert state.wait_optimize(120)
    assert state.last_result.interrupted and state.progress["cancelled"]


def test_planar_rig_turns_about_the_plane_normal(rig_cache_dir, tmp_path):
    from supportless.base.kinematics import planar_rotation
    from supportless.energies.surface import boundary_edges
    from supportless.rig.load import load_rig

    rig = load_rig("demo:woody2d", cache_dir=rig_cache_dir)
    state = EditorState(rig, workdir=tmp_path)
    child = int(np.flatnonzero(rig.parents >= 0)[-1])
    parent = int(rig.parents[child])
    target = np.zeros((rig.bone_count, 3))
    target[parent, 2], target[child, 2] = 0.4, -0.7
    world = np.eye(3)
    world[:2, :2] = rig.transforms(target)[parent][:, :2] @ planar_rotation(-0.7)
    state.set_angles(np.where(np.arange(rig.bone_count)[:, None] == child, 0.0, target))
    state.set_bone_rotation(child, world)
    assert np.allclose(state.get_angles(), target, atol=1e-12)
    m = state.measure()
    assert m["risky"].shape == (len(boundary_edges(rig.faces)),)  # one flag per boundary edge
    assert m["intersecting_faces"] is None and "intersecting_face_pairs" not in m
    assert state.export_mesh("flat.obj").is_file()
    # a planar print rotation: an angle, no axis
    R = np.array([[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]])
    state.set_rotation(R)
    m = state.measure(exact=False)
    assert m["turn_axis"] is None and m["turn_deg"] == pytest.approx(np.degrees(0.5))
    assert m["print_direction"].shape == (2,)
    assert np.allclose(state.printed_on_plate(), print_pose(rig.pose(state.get_angles()), R, rig.up))
    assert float((state.printed_on_plate() @ rig.up).min()) == pytest.approx(0.0, abs=1e-12)


# --------------------------------------------------------------------------- #
# the print rotation
# --------------------------------------------------------------------------- #
def _assert_same_measures(got, expected, path=""):
    """Every entry of ``expected`` (a pose_measures dict) is in ``got`` with the same value."""
    for key, value in expected.items():
        assert key in got, f"{path}{key} missing"
        if isinstance(value, dict):
            _assert_same_measures(got[key], value, f"{path}{key}.")
        elif isinstance(value, (bool, np.bool_)):
            assert bool(got[key]) == bool(value), f"{path}{key}"
        else:
            assert np.allclose(got[key], value, rtol=1e-12, atol=1e-15), f"{path}{key}: {got[key]} != {value}"


def _turn(rig):
    """A print rotation laying the model on its side, (3, 3) float64."""
    return rotation_between(rig.up, np.array([1.0, 0.0, 0.0]))


def _is_rotation(R, d=3):
    return R.shape == (d, d) and np.allclose(R @ R.T, np.eye(d), atol=1e-12) and np.linalg.det(R) == pytest.approx(1.0)


def test_optimize_chooses_the_print_rotation_and_measures_use_it(state, branch_rig):
    rig = branch_rig
    assert np.array_equal(state.get_rotation(), np.eye(3))
    assert state.settings.orient == "free"
    start = state.get_angles()
    assert state.start_optimize(particles=10, iterations=4, seed=2)
    assert state.wait_optimize(300)
    result = state.last_result
    angles, R = state.get_pose()
    assert _is_rotation(R)
    assert np.array_equal(R, result.rotation) and np.array_equal(angles, result.angles)
    assert not np.allclose(R, np.eye(3))  # the branch needs less support on its side
    # the panel measures the pose as printed, as the report does
    m = state.measure(exact=False)
    expected = pose_measures(state.objective, angles, exact=False, overhang_angle=state.settings.overhang_angle,
                             rotation=R)
    _assert_same_measures(m, expected)
    assert m["objective"] == pytest.approx(result.value, rel=1e-12)
    assert m["support_prism"] < m["upright"]["support_prism"]  # the turn is what saves support
    assert np.array_equal(m["rotation"], R)
    assert m["turn_deg"] == pytest.approx(rotation_axis_angle(R)[1])
    assert np.allclose(m["print_direction"], print_direction(R, rig.up))
    assert np.allclose(m["print_direction"], R.T @ rig.up)
    # risky faces: as printed, and standing
    V = rig.pose(angles)
    from supportless.energies.overhang import risky_faces

    assert np.array_equal(m["risky"], risky_faces(V @ R.T, rig.faces, rig.up, state.settings.overhang_angle))
    assert np.array_equal(m["risky_standing"], risky_faces(V, rig.faces, rig.up, state.settings.overhang_angle))
    # editing a bone keeps the turn; undo goes back to the pose and rotation the search started from
    state.set_bone_angles(rig.bone_count - 1, [0.0, 0.0, 15.0])
    assert np.array_equal(state.get_rotation(), R)
    assert state.undo() and state.undo()
    assert np.array_equal(state.get_angles(), start) and np.array_equal(state.get_rotation(), np.eye(3))
    assert state.redo()
    assert np.array_equal(state.get_rotation(), R)
    state.reset()
    assert np.array_equal(state.get_rotation(), np.eye(3)) and np.allclose(state.get_angles(), 0.0)
    assert state.undo() and np.array_equal(state.get_rotation(), R)  # reset is an undo step


def test_keep_orientation_prints_as_it_stands(state, branch_rig):
    state.set_rotation(_turn(branch_rig))
    state.update_settings(orient="keep")
    assert state.settings.orient == "keep"
    assert state.start_optimize(particles=6, iterations=2, seed=1)
    assert state.wait_optimize(300)
    assert np.array_equal(state.get_rotation(), np.eye(3))
    with pytest.raises(ValueError, match="orient must be one of"):
        state.update_settings(orient="sideways")
    assert state.settings.orient == "keep"


def test_every_bone_fixed_still_turns_the_model(state, branch_rig):
    state.set_bone_angles(branch_rig.bone_count - 1, [0.0, 0.0, 20.0])
    pose = state.get_angles()
    assert state.start_optimize(fix="all", particles=6, iterations=2, footprint_mm2=0.0)  # its turns rest on edges
    assert state.wait_optimize(300)
    assert np.array_equal(state.get_angles(), pose)
    assert _is_rotation(state.get_rotation()) and not np.allclose(state.get_rotation(), np.eye(3))


def test_set_rotation_checks_and_is_an_undo_step(state, branch_rig):
    R = _turn(branch_rig)
    pose = state.get_angles()
    state.set_rotation(R)
    assert np.array_equal(state.get_rotation(), R) and np.array_equal(state.get_angles(), pose)
    for bad in (np.eye(2), 2 * np.eye(3), np.diag([1.0, 1.0, -1.0])):
        with pytest.raises(ValueError, match="rotation matrix"):
            state.set_rotation(bad)
    assert np.array_equal(state.get_rotation(), R)
    state.get_rotation()[:] = 0.0  # a copy
    assert np.array_equal(state.get_rotation(), R)
    assert state.undo() and np.array_equal(state.get_rotation(), np.eye(3))


def test_print_frame_is_the_turned_pose_on_the_plate(state, branch_rig, tmp_path):
    import trimesh

    rig = branch_rig
    state.set_bone_angles(rig.bone_count - 1, [0.0, 10.0, 30.0])
    R = _turn(rig)
    state.set_rotation(R)
    angles = state.get_angles()
    V = rig.pose(angles)
    Q, shift = state.frame_transform("print")
    expected = print_pose(V, R, rig.up)
    assert np.array_equal(Q, R)
    assert np.allclose(V @ Q.T + shift, expected, atol=1e-12)
    assert float((expected @ rig.up).min()) == pytest.approx(0.0, abs=1e-12)
    assert np.allclose(state.printed_on_plate(), expected, atol=1e-12)
    Q, shift = state.frame_transform("standing")
    assert np.array_equal(Q, np.eye(3)) and np.array_equal(shift, np.zeros(3))
    with pytest.raises(ValueError, match="frame must be one of"):
        state.frame_transform("sideways")
    # the exported mesh is the one to slice: as printed; standing on request
    printed = trimesh.load(state.export_mesh("printed.obj"), force="mesh", process=False)
    assert np.allclose(printed.vertices, state.print_frame.place(expected), atol=1e-5)
    standing = trimesh.load(state.export_mesh("standing.obj", frame="standing"), force="mesh", process=False)
    assert np.allclose(standing.vertices, state.print_frame.place(state.posed_on_plate()), atol=1e-5)
    assert not np.allclose(standing.vertices, printed.vertices, atol=1e-3)


def test_pose_files_keep_the_print_rotation(state, branch_rig, tmp_path):
    rig = branch_rig
    state.set_bone_angles(rig.bone_count - 1, [5.0, -10.0, 25.0])
    R = _turn(rig)
    state.set_rotation(R)
    target = state.get_angles()
    path = state.save_pose("turned.json")
    data = json.loads(path.read_text())
    assert np.allclose(data["print_rotation"], R)
    assert data["objective"] == pytest.approx(float(state.objective(target, R)))
    assert np.allclose(posefile.read_print_rotation(path, 3), R)
    payload = state.pose_bytes()
    state.reset()
    assert np.array_equal(state.get_rotation(), np.eye(3))
    state.load_pose(path)
    assert np.array_equal(state.get_angles(), target) and np.allclose(state.get_rotation(), R, atol=1e-15)
    assert state.undo() and np.array_equal(state.get_rotation(), np.eye(3))  # loading is an undo step
    state.load_pose_bytes("uploaded.json", payload)
    assert np.allclose(state.get_rotation(), R, atol=1e-15)
    # a pose file without a print rotation prints as it stands
    plain = tmp_path / "plain.json"
    posefile.write_pose(plain, target, rig.bones, rig.joints)
    state.load_pose(plain)
    assert np.array_equal(state.get_rotation(), np.eye(3))
    # a broken print rotation is refused, the state stays
    state.set_rotation(R)
    broken = json.loads(path.read_text())
    broken["print_rotation"] = [[2.0, 0, 0], [0, 1, 0], [0, 0, 1]]
    (tmp_path / "broken.json").write_text(json.dumps(broken))
    with pytest.raises(SupportlessError, match="print_rotation"):
        state.load_pose("broken.json")
    assert np.allclose(state.get_rotation(), R)


# ------------------------------------------------------------------ the front (issue 16)


def test_the_front_slider_sets_the_pose_and_rotation(tpose_rig, tmp_path):
    """Headless: find a front in the background, then each slider position shows its pose (an undo step each)."""
    from supportless.apps.ui.front import FrontBrowser

    state = EditorState(tpose_rig, settings=SearchSettings(particles=24, iterations=8, seed=3), workdir=tmp_path)
    state.history.merge_seconds = 0.0  # each show its own undo step, however fast the shows follow each other
    seen = _events(state)
    browser = FrontBrowser(state)
    with pytest.raises(ValueError, match="no front yet"):
        browser.show(0)
    assert browser.start(3)
    assert not browser.start(3)  # one at a time
    assert browser.wait(300)
    done = [info for event, info in seen if event == "front_done"]
    assert len(done) == 1 and "error" not in done[0]
    front = done[0]["front"]
    assert front is browser.front and 1 <= len(front.poses) <= 3
    for k, pose in enumerate(front.poses):
        measures = browser.show(k)
        np.testing.assert_array_equal(state.get_angles(), pose.result.angles)
        np.testing.assert_array_equal(state.get_rotation(), pose.result.rotation)
        assert browser.shown == k and measures["support"] == pose.support
    assert seen[-1][0] == "pose" and seen[-1][1]["origin"] == "front"
    state.undo()
    if len(front.poses) > 1:  # one undo step back to the previous front pose
        np.testing.assert_array_equal(state.get_angles(), front.poses[-2].result.angles)
    with pytest.raises(ValueError, match="not within"):
        browser.show(len(front.poses))


@pytest.mark.parametrize("slicer", [True, False])
def test_optimize_makes_the_command_line_choice(state, tmp_path, monkeypatch, slicer):
    """The panel's Optimize weighs the same answers as ``supportless optimize``: PrusaSlicer chooses when found."""
    from slicers import fake_exe, stand_in_slicer

    exe = fake_exe(tmp_path, "stand-in-slicer", stand_in_slicer("float(np.ptp(rec['v'][..., 0]))")) if slicer \
        else str(tmp_path / "missing")
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", exe)
    assert state.start_optimize(particles=10, iterations=4, seed=2)
    assert state.wait_optimize(300)
    result = state.last_result
    assert result.choice is not None and result.choice.by == ("slicer" if slicer else "model")
    chosen = result.choice.candidates[result.choice.chosen].result
    angles, R = state.get_pose()
    assert np.array_equal(angles, chosen.angles) and np.array_equal(R, chosen.rotation)
    assert any(c.sliced_mm is not None for c in result.choice.candidates) == slicer
