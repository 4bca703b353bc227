"""Reports: measures of a pose, the rest-vs-found report, and the pictures."""

import json

import numpy as np
import pytest

import supportless as sl
from supportless.copyleft.cgal import intersecting_face_pairs
from supportless.report import render
from supportless.report import report as report_mod
from supportless.report.report import build_report, pose_measures, reduction, write_pictures
from supportless.report.weakness import WEAK_COLORS
from supportless.search.settings import SearchSettings


@pytest.fixture(scope="module")
def searched(branch_rig):
    # turned onto a side the plate touches at an edge: the footprint rule is not these tests' subject
    return sl.optimize(branch_rig, particles=10, iterations=4, seed=0, overhang_angle=40.0, footprint_mm2=0.0)


def test_reduction():
    assert reduction(200.0, 50.0) == 75.0
    assert reduction(100.0, 120.0) == pytest.approx(-20.0)
    assert reduction(0.0, 1.0) is None


def test_pose_measures_are_the_energies_at_the_given_threshold(branch_rig):
    rig = branch_rig
    obj = SearchSettings().objective(rig)
    angles = np.zeros((rig.bone_count, 3))
    angles[-1] = [0.2, -0.1, 0.4]
    V = rig.pose(angles)
    m = pose_measures(obj, angles, overhang_angle=35.0)
    assert m["overhang_angle"] == 35.0
    assert m["support_prism"] == sl.overhang_energy(V, rig.faces, rig.up, 35.0)
    assert m["support_column"] == sl.support_volume(V, rig.faces, rig.up, 35.0, obj.resolution)
    assert m["risky_area"] == sl.risky_area(V, rig.faces, rig.up, 35.0)
    assert m["self_intersection_volume"] == sl.self_intersection_volume(V, rig.faces, rig.up, obj.resolution)
    assert m["objective"] == float(obj(angles))
    assert m["intersecting_face_pairs"] == intersecting_face_pairs(V, rig.faces)
    # the objective's own threshold by default; the caller's vertices are used as given
    assert pose_measures(obj, angles, exact=False)["overhang_angle"] == obj.overhang_angle
    assert "intersecting_face_pairs" not in pose_measures(obj, angles, exact=False)
    assert pose_measures(obj, angles, exact=False, vertices=V) == pose_measures(obj, angles, exact=False)


def test_a_crossing_poses_overlap_is_the_objectives_own_measure_of_the_same_surface(branch_rig):
    rig = branch_rig
    obj = SearchSettings().objective(rig)
    angles = np.zeros((rig.bone_count, 3))
    angles[1, 2] = 1.5  # one branch folded into the other
    V = rig.pose(angles)
    overlap = sl.self_intersection_volume(V, rig.faces, rig.up, obj.resolution)
    assert overlap > 1.0
    for vertices in (None, V.copy()):  # posed here or given: the same surface, the objective's measure
        m = pose_measures(obj, angles, exact=False, vertices=vertices)
        assert m["self_intersection_volume"] == overlap
    larger = V * 1.01  # another surface than the pose's: measured as given
    m = pose_measures(obj, angles, exact=False, vertices=larger)
    assert m["self_intersection_volume"] == sl.self_intersection_volume(larger, rig.faces, rig.up, obj.resolution)
    assert m["self_intersection_volume"] == pytest.approx(1.01 ** 3 * overlap, rel=0.02)


def test_build_report_compares_rest_and_found_pose_at_the_printers_threshold(branch_rig, searched):
    rig = branch_rig
    rep = build_report(rig, searched)
    json.dumps(rep)  # JSON-ready
    assert rep["before"]["overhang_angle"] == rep["after"]["overhang_angle"] == 40.0
    rest = rig.pose(rig.rest_angles())  # linear blend skinning at rest: the rest surface to the last bits
    assert rep["before"]["support_prism"] == sl.overhang_energy(rest, rig.faces, rig.up, 40.0)
    # after: the print frame (the posed surface turned by R); after.upright: the same pose standing
    R = searched.rotation
    assert not np.allclose(R, np.eye(3))  # this search does turn the branch
    printed = rig.pose(searched.angles) @ R.T
    assert rep["after"]["support_prism"] == sl.overhang_energy(printed, rig.faces, rig.up, 40.0)
    assert rep["after"]["support_prism"] == pytest.approx(
        sl.overhang_energy(searched.print_vertices, rig.faces, rig.up, 40.0), rel=1e-9)
    assert rep["after"]["upright"]["support_prism"] == sl.overhang_energy(rig.pose(searched.angles), rig.faces,
                                                                          rig.up, 40.0)
    rot = rep["print_rotation"]
    np.testing.assert_allclose(rot["matrix"], R, atol=1e-12)
    from scipy.spatial.transform import Rotation
    np.testing.assert_allclose(np.radians(rot["angle_deg"]) * np.asarray(rot["axis"]),
                               Rotation.from_matrix(R).as_rotvec(), atol=1e-9)
    np.testing.assert_allclose(rot["printing_direction_in_model_frame"], R.T @ rig.up, atol=1e-12)
    assert rot["orient"] == "free" and set(rep["frames"]) == {"before", "after", "after.upright"}
    assert rep["reduction_percent"]["support_prism"] == reduction(rep["before"]["support_prism"],
                                                                   rep["after"]["support_prism"])
    assert rep["after"]["objective"] == pytest.approx(searched.value, rel=1e-12)
    assert rep["settings"]["overhang_angle"] == 40.0
    assert rep["settings"]["search_overhang_angle"] == 40.0 + SearchSettings().overhang_margin
    assert rep["settings"]["fixed_bones"] == [int(b) + 1 for b in np.flatnonzero(searched.fixed)]
    assert SearchSettings.from_dict(rep["settings"]) == searched.settings
    assert rep["history"] == [float(v) for v in searched.history]
    assert rep["after"]["intersecting_face_pairs"] == 0
    moved = np.linalg.norm(rig.pose(searched.angles) - rig.vertices, axis=1).max()
    assert rep["max_vertex_displacement"] == moved
    assert rep["runtime_seconds"] == searched.runtime_seconds


def test_pictures_colour_faces_past_the_printers_threshold(branch_rig, searched, tmp_path, monkeypatch):
    seen, first = {}, {}
    original = report_mod.render_before_after

    def spy(path, before, after, up, **kw):
        first.update(kw) if not first else None
        seen.update(kw)
        return original(path, before, after, up, **kw)

    monkeypatch.setattr(report_mod, "render_before_after", spy)
    written = write_pictures(tmp_path, branch_rig, searched, build_report(branch_rig, searched))
    assert [label for label, _ in written] == ["before/after picture", "print orientation picture",
                                                "convergence plot"]
    def red(colors):  # the faces drawn as needing support (those of weak sections are drawn over them)
        colors = np.asarray(colors)
        weak = np.any([np.all(np.isclose(colors, c), axis=1) for c in WEAK_COLORS.values()], axis=0)
        return np.all(np.isclose(colors, render._RISKY_COLOR), axis=1), weak

    # the print picture: the pose standing beside it turned onto the plate, risky faces of each frame
    drawn, weak = red(seen["face_colors"][1])
    np.testing.assert_array_equal(drawn, sl.risky_faces(searched.print_vertices, branch_rig.faces,
                                                        branch_rig.up, 40.0) & ~weak)
    assert "as printed" in seen["titles"][1]
    rest = sl.base.geometry.place_on_plate(branch_rig.vertices, branch_rig.up)
    expected = sl.risky_faces(rest, branch_rig.faces, branch_rig.up, 40.0)
    drawn, weak = red(first["face_colors"][0])
    np.testing.assert_array_equal(drawn, expected & ~weak)
    assert "> 40 deg" in first["suptitle"]
    # each panel's weakest section, from the report's strength: the rest pose, the answer as printed
    assert first["notes"][0].startswith("weakest: ") and seen["notes"][1].startswith("weakest as printed: ")


def test_pose_measures_in_the_print_frame(branch_rig):
    """With a print rotation, support is counted on the turned surface; contact and distortion standing."""
    from scipy.spatial.transform import Rotation

    rig = branch_rig
    obj = SearchSettings().objective(rig)
    angles = rig.rest_angles().copy()
    angles[-1] = [0.1, 0.0, -0.3]
    R = Rotation.from_rotvec([0.0, 0.0, 1.2]).as_matrix()
    V = rig.pose(angles)
    m = pose_measures(obj, angles, exact=False, rotation=R)
    standing = pose_measures(obj, angles, exact=False)
    assert m["support_prism"] == pytest.approx(sl.overhang_energy(V @ R.T, rig.faces, rig.up, obj.overhang_angle))
    assert m["support_prism"] != pytest.approx(standing["support_prism"])
    assert m["upright"]["support_prism"] == standing["support_prism"]
    assert m["objective"] == pytest.approx(float(obj(angles, R)), rel=1e-12)
    for key in ("arap", "new_contact_vertices", "stability_margin", "self_intersection_volume"):
        assert m[key] == standing[key]


def test_report_predicts_the_slicers_support_at_60_mm(branch_rig, searched):
    from supportless.energies.slicer_model import predicted_support_mm

    rep = build_report(branch_rig, searched)
    p = rep["predicted_slicer"]
    assert p["height_mm"] == 60.0 and p["threshold_deg"] == searched.settings.overhang_angle
    # the rest pose scaled to 60 mm tall, the found pose by the same factor, each in its print frame
    scale = 60.0 / np.ptp(branch_rig.vertices @ branch_rig.up)
    rest = predicted_support_mm(branch_rig.vertices, branch_rig.faces, branch_rig.up, p["threshold_deg"], scale)
    found = predicted_support_mm(searched.print_vertices, branch_rig.faces, branch_rig.up, p["threshold_deg"], scale)
    assert p["before_mm"] == pytest.approx(rest) and p["after_mm"] == pytest.approx(found)
    assert p["before_mm"] > p["after_mm"] > 0  # the cantilever's support falls
    assert rep["predicted_slicer_reduction"] == pytest.approx(1 - found / rest)
    json.dumps(rep)


def test_one_writer_of_a_results_files_goes_on_past_a_file_it_cannot_write(branch_rig, searched, tmp_path):
    """write_result writes what is asked (the mesh in the print frame, the pose, the report) and names what failed."""
    from supportless.files.posefile import read_pose
    from supportless.files.printframe import rig_print_frame
    from supportless.report.outputs import write_result

    frame = rig_print_frame(branch_rig, None)
    report = build_report(branch_rig, searched, frame)
    (tmp_path / "taken").write_text("a file where a folder should be")
    written, failed = write_result(branch_rig, searched, report, frame, output=tmp_path / "p.stl",
                                   pose=tmp_path / "p.json", pictures=tmp_path / "taken" / "pics",
                                   report_path=tmp_path / "r.json")
    assert [what for what, _ in written] == ["posed mesh, as printed" if searched.rotation is not None
                                             and not np.allclose(searched.rotation, np.eye(3)) else "posed mesh",
                                             "pose", "report"]
    assert len(failed) == 1 and "taken" in failed[0][0] and isinstance(failed[0][1], OSError)
    V, _ = sl.read_mesh(tmp_path / "p.stl")
    assert V[:, 2].min() == pytest.approx(0.0, abs=1e-4)  # on the plate, +Z up
    assert V[:, 2].max() - V[:, 2].min() > 1.0  # millimetres, not the model's units
    np.testing.assert_allclose(read_pose(tmp_path / "p.json", branch_rig.bones, branch_rig.tree), searched.angles,
                               atol=1e-9)


def test_the_report_gives_the_naturalness_of_the_pose(branch_rig, searched):
    from supportless.search.naturalness import world_turn_deg

    n = build_report(branch_rig, searched)["naturalness"]
    assert n["largest_chain_turn_deg"] == pytest.approx(world_turn_deg(branch_rig, searched.angles)[n["chain_end"] - 1])
    assert 0.0 <= n["largest_chain_turn_deg"] <= n["largest_joint_deg"] <= 180.0


def test_the_best_standing_answer_is_reported_and_written_beside_a_turned_one(branch_rig, tmp_path):
    """With the print orientation free, the report gives the best answer printed as it stands beside the answer,
    and --standing-out writes that one standing: +Z up, on the plate, untouched by the print rotation."""
    from supportless.files.printframe import rig_print_frame
    from supportless.report.outputs import write_result
    from supportless.search.choice import best_standing

    found = sl.optimize(branch_rig, particles=10, iterations=4, seed=2)
    report = build_report(branch_rig, found)
    standing = report["standing"]
    assert standing is not None and found.choice is not None
    index = best_standing(found.choice)
    assert standing["index"] == index and standing["is_answer"] == (index == found.choice.chosen)
    pick = found.choice.candidates[index]
    assert pick.kind == "pose" or np.allclose(pick.result.rotation, np.eye(3))
    others = [c.predicted_mm for c in found.choice.candidates
              if c.kind == "pose" or np.allclose(c.result.rotation, np.eye(3))]
    assert standing["standing_mm"] == pytest.approx(min(others))
    assert standing["answer_turned_deg"] >= 0.0
    frame = rig_print_frame(branch_rig)
    written, failed = write_result(branch_rig, found, report, frame, standing=tmp_path / "standing.stl")
    assert not failed and written[0][1] == tmp_path / "standing.stl"
    V, _ = sl.read_mesh(tmp_path / "standing.stl")  # an STL's vertices come back merged, in another order
    expected = frame.place(pick.result.vertices if not standing["is_answer"] else found.vertices)
    np.testing.assert_allclose(np.sort(V, axis=0), np.sort(expected, axis=0), atol=1e-3)
    assert V[:, 2].min() == pytest.approx(0.0, abs=1e-5)


@pytest.mark.slow
def test_a_character_of_touching_skins_is_written_a_closed_solid(shared_file, tmp_path):
    """The shared modular character's skins touch along edges (28 edges of four triangles once welded, as an STL
    reader welds them): the posed mesh written is read back with every edge in exactly two triangles."""
    import trimesh

    from supportless.files.printframe import rig_print_frame
    from supportless.files.watertight import manifold_check
    from supportless.report.outputs import write_posed

    rig = sl.load_rig(shared_file("gltf/quaternius/Character_HumanoidRig.glb"))
    rest = rig.rest_angles()
    V = rig.pose(rest)
    frame = rig_print_frame(rig)
    assert manifold_check(frame.place(V), rig.faces)["shared_edges"] > 0  # as the skins touch
    for name in ("posed.stl", "posed.3mf"):
        kind = write_posed(tmp_path / name, rig, rest, V, V, frame)
        assert "moved apart by a hair" in kind and "warning" not in kind
        mesh = trimesh.load(tmp_path / name, force="mesh")
        assert mesh.is_watertight, name
        assert intersecting_face_pairs(mesh.vertices, mesh.faces) == 0


def test_the_report_says_what_the_rest_pose_and_the_answer_rest_on(branch_rig, searched):
    from supportless.energies.footprint import footprint_area

    fp = build_report(branch_rig, searched)["footprint"]
    scale = 60.0 / np.ptp(branch_rig.vertices @ branch_rig.up)
    assert fp["answer_mm2"] == pytest.approx(footprint_area(searched.print_vertices, branch_rig.faces, branch_rig.up,
                                                            scale), abs=0.01)
    assert fp["rest_mm2"] == pytest.approx(footprint_area(branch_rig.vertices, branch_rig.faces, branch_rig.up,
                                                          scale), abs=0.01)
    assert fp["rest_mm2"] > 0 and fp["bound_mm2"] == 0.0 and fp["height_mm"] == 60.0


def test_the_report_says_how_strong_the_rest_pose_and_the_answer_are(branch_rig, searched):
    from supportless.report.report import strength_line
    from supportless.search.sturdiness import pose_strength

    report = build_report(branch_rig, searched)
    s = report["strength"]
    assert set(s) == {"rest", "answer", "floor", "material", "load_n"}
    assert s["material"]["name"] == "PLA" and s["floor"] == searched.settings.min_safety and s["load_n"] == 2.0
    height = report["print_frame"]["height_mm"]
    for part, angles, rotation in (("rest", branch_rig.rest_angles(), np.eye(3)),
                                   ("answer", searched.angles, searched.rotation)):
        expected = pose_strength(branch_rig, angles, rotation, height)  # the same analysis, done again
        assert s[part]["safety_factor"] == pytest.approx(expected.safety_factor, rel=1e-3)
        w = s[part]["weakest"]
        assert w["direction"] in ("across", "along") and w["bone"] in branch_rig.bone_names()
        assert 0.0 <= w["height_mm"] <= height + 1e-6 and w["breaks_at_n"] > 0
    line = strength_line(s)
    assert line.startswith("weakest: ") and "the layers" in line and " N" in line
