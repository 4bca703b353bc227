"""CuraEngine as the slicer (supportless.slicing.cura): the real engine on boxes, Cura profiles, the error paths."""

import json

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from slicers import fake_exe

from supportless.apps.cli import main
from supportless.base.errors import InputError, SlicerError
from supportless.files.printer import cura_default_profile, read_printer_profile, search_angle
from supportless.slicing.choice import SlicerChoice, choose_slicer
from supportless.slicing.cura import (
    DEFINITIONS_ENV_VAR,
    ENGINE_ENV_VAR,
    CuraNotFound,
    cura_command,
    find_cura_definitions,
    read_cura_log,
    slice_with_cura,
)
from supportless.slicing.prusaslicer import slice_check, slice_support


def _shelf():
    """A 10 mm cube with a 10 x 10 x 3 mm shelf out of its top: 10 mm of overhang over the plate."""
    cube = trimesh.creation.box((10, 10, 10))
    shelf = trimesh.creation.box((10, 10, 3))
    shelf.apply_translation([10, 0, 3.5])
    body = trimesh.boolean.union([cube, shelf], engine="manifold")
    return np.asarray(body.vertices), np.asarray(body.faces)


def _cube():
    cube = trimesh.creation.box((10, 10, 10))
    return np.asarray(cube.vertices), np.asarray(cube.faces)


@pytest.mark.parametrize("support", ["grid", "tree"])
def test_cura_supports_an_overhang_and_not_a_cube(cura_engine, support):
    exe, folder = cura_engine
    sliced = slice_support([_shelf(), _cube()], (0, 0, 1), 1.0, choice=SlicerChoice("cura", support, str(folder)),
                           names=["shelf", "cube"])
    shelf, cube = sliced.meshes
    assert shelf["support_mm"] > 50.0  # a 10 x 10 x 10 mm space under the shelf
    assert cube["support_mm"] == 0.0  # nothing to hold up (within CuraEngine's rounding)
    assert shelf["support"]["print_seconds"] > shelf["nosupport"]["print_seconds"]
    assert sliced.config["support_structure"] == ("tree" if support == "tree" else "normal")
    assert sliced.slicer == exe


def test_a_cura_slice_check_reports_the_same_fields_as_prusaslicers(cura_engine):
    report = slice_check(_shelf(), _cube(), up=(0, 0, 1), height_mm=None,
                         choice=SlicerChoice("cura", "grid")).to_dict()
    assert report["engine"] == "cura" and report["support"] == "grid" and "4." in report["slicer_version"]
    b, a = report["before"], report["after"]
    assert b["support_mm"] > 50 and a["support_mm"] == 0 and report["reduction_percent"] == pytest.approx(100)
    assert b["support_cm3"] == pytest.approx(b["support_mm"] * np.pi * 0.875 ** 2 / 1000)
    assert b["support_g"] == pytest.approx(b["support_cm3"] * 1.24) and b["support_time_s"] is None
    assert b["total_time_s"] > 0 and b["model_mm"] == pytest.approx(b["total_mm"] - b["support_mm"])
    assert sorted(report["slices"]) == ["original-support", "posed-support"]  # one slice per mesh


def test_cura_is_used_for_tree_supports_and_prusaslicer_refuses_them():
    assert choose_slicer(None, "tree").engine == "cura"
    with pytest.raises(InputError, match="--support tree needs --slicer cura"):
        SlicerChoice("prusa", "tree")
    r = CliRunner().invoke(main, ["slice-check", "a.stl", "b.stl", "--slicer", "prusa", "--support", "tree"])
    assert r.exit_code != 0 and "--support tree needs --slicer cura" in r.output


@pytest.mark.parametrize("content, angle", [
    ({"overrides": {"support_angle": {"default_value": 60}}}, 30.0),  # a printer definition
    ({"support_angle": 35, "layer_height": 0.2}, 55.0),  # a flat override of settings
    ({"overrides": {"support_angle": {"value": "machine_x * 2"}}}, 40.0),  # a formula: Cura's default stands
    ({}, 40.0),
])
def test_the_overhang_threshold_follows_a_cura_profile(tmp_path, content, angle):
    path = tmp_path / "printer.json"
    path.write_text(json.dumps(content))
    profile = read_printer_profile(path)
    assert profile.slicer == "cura" and profile.overhang_angle == pytest.approx(angle)
    assert search_angle(profile.overhang_angle) == pytest.approx(angle + 2.0)
    assert cura_default_profile().overhang_angle == 40.0  # fdmprinter: 50 degrees off the vertical


@pytest.mark.parametrize("content, message", [
    ("{not json", "not JSON"), ("[1, 2]", "not an object"), ('{"support_angle": "steep"}', "not a number"),
    ('{"support_angle": 120}', "0..90"), ('{"layer_height": 0}', "above 0"),
])
def test_a_bad_cura_profile_is_one_line(tmp_path, content, message):
    path = tmp_path / "printer.json"
    path.write_text(content)
    with pytest.raises(InputError, match=message) as info:
        read_printer_profile(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_a_profile_of_the_other_slicer_is_refused(tmp_path):
    cura, prusa = tmp_path / "cura.json", tmp_path / "prusa.ini"
    cura.write_text('{"support_angle": 45}')
    prusa.write_text("layer_height = 0.2\n")
    r = CliRunner().invoke(main, ["slice-check", "a.stl", "b.stl", "--slicer", "prusa", "--printer-profile", str(cura)])
    assert r.exit_code != 0 and "goes with --slicer cura" in r.output
    r = CliRunner().invoke(main, ["slice-check", "a.stl", "b.stl", "--slicer", "cura", "--printer-profile", str(prusa)])
    assert r.exit_code != 0 and "goes with --slicer prusa" in r.output


def test_the_command_gives_machine_and_extruder_settings_in_their_place(tmp_path):
    cmd = cura_command("CuraEngine", tmp_path, tmp_path / "m.stl", tmp_path / "m.gcode", True, "tree",
                       {"layer_height": "0.2", "material_diameter": "2.85"}, (300.0, 250.0, 200.0))
    first, second = cmd.index("-e0"), len(cmd) - 1 - cmd[::-1].index("-e0")
    machine, extruder = cmd[:first], cmd[first:second]
    assert "support_structure=tree" in machine and "support_enable=true" in machine and "layer_height=0.2" in machine
    assert "machine_width=300" in machine and "material_diameter=2.85" in extruder
    assert cmd[second:] == ["-e0", "-l", str(tmp_path / "m.stl"), "-o", str(tmp_path / "m.gcode")]
    with pytest.raises(ValueError):
        cura_command("CuraEngine", tmp_path, tmp_path / "m.stl", tmp_path / "m.gcode", True, "lattice")


def test_the_log_gives_the_last_volume_and_time():
    text = "[INFO] Print time (s): 12\nFilament (mm^3): 100\n...\nPrint time (s): 3376\nFilament (mm^3): 5738\n"
    assert read_cura_log(text) == (5738.0, 3376.0)
    with pytest.raises(SlicerError, match="no filament volume"):
        read_cura_log("[ERROR] nothing sliced")


def test_definitions_are_looked_for_where_asked_first(tmp_path, monkeypatch):
    (tmp_path / "fdmprinter.def.json").write_text("{}")
    (tmp_path / "fdmextruder.def.json").write_text("{}")
    assert find_cura_definitions(tmp_path) == tmp_path
    assert find_cura_definitions(tmp_path / "elsewhere") is None  # never another folder instead
    monkeypatch.setenv(DEFINITIONS_ENV_VAR, str(tmp_path))
    assert find_cura_definitions() == tmp_path


def _stand_in(tmp_path, body):
    folder = tmp_path / "definitions"
    folder.mkdir(exist_ok=True)
    for name in ("fdmprinter.def.json", "fdmextruder.def.json"):
        (folder / name).write_text("{}")
    return fake_exe(tmp_path, "CuraEngine", body), folder


def test_an_engine_that_fails_is_one_line_naming_its_error(tmp_path):
    exe, folder = _stand_in(tmp_path, """\
        import sys
        sys.stderr.write('[WARNING] -s a="1" -s b="2"\\n[ERROR] Failed loading model file: m.stl\\n')
        sys.exit(1)
        """)
    with pytest.raises(SlicerError) as info:
        slice_with_cura([_cube()], ["cube"], engine=exe, definitions=folder)
    message = str(info.value)
    assert "CuraEngine failed slicing cube mesh" in message and "Failed loading model file" in message
    assert "\n" not in message and "-s a=" not in message


def test_an_engine_that_hangs_is_stopped(tmp_path):
    exe, folder = _stand_in(tmp_path, "import time\ntime.sleep(30)\n")
    with pytest.raises(SlicerError, match="CuraEngine timed out after 0.5 s"):
        slice_with_cura([_cube()], ["cube"], engine=exe, definitions=folder, timeout=0.5)


def test_a_stand_in_engine_gives_the_support_as_the_difference(tmp_path):
    exe, folder = _stand_in(tmp_path, """\
        import sys
        args = sys.argv
        out = args[args.index("-o") + 1]
        support = "support_enable=true" in args
        open(out, "w").write(";FLAVOR:Marlin\\n")
        sys.stderr.write(f"Print time (s): {200 if support else 100}\\nFilament (mm^3): {1500 if support else 1000}\\n")
        """)
    (cube,) = slice_with_cura([_cube()], ["cube"], engine=exe, definitions=folder)[0]
    assert cube["support_mm"] == pytest.approx(500 / (np.pi * 0.875 ** 2))
    assert cube["support"]["print_seconds"] - cube["nosupport"]["print_seconds"] == 100


def test_a_missing_engine_says_how_to_install_it(tmp_path, monkeypatch):
    monkeypatch.setenv(ENGINE_ENV_VAR, str(tmp_path / "nope"))
    with pytest.raises(CuraNotFound, match="apt-get install cura-engine"):
        slice_with_cura([_cube()], ["cube"])
    r = CliRunner().invoke(main, ["slice-check", "a.stl", "b.stl", "--slicer", "cura"])
    assert r.exit_code != 0


def test_support_read_from_the_gcode_matches_the_difference_but_the_brim(cura_engine):
    """One slice per answer when comparing them: the G-code's support extrusions against with-minus-without."""
    exe, folder = cura_engine
    both = slice_with_cura([_shelf()], ["shelf"], engine=exe, definitions=folder)[0][0]
    once = slice_with_cura([_shelf()], ["shelf"], engine=exe, definitions=folder, by_feature=True)[0][0]
    assert "nosupport" not in once and once["support_mm"] > 0
    # the difference also counts what the supports add to the brim around them: most of this small shelf's
    # (the 60 mm bunny: 1942 against 2162 mm)
    assert 0.3 * both["support_mm"] < once["support_mm"] <= both["support_mm"] + 1.0


def test_optimize_with_cura_checks_and_chooses_with_cura(cura_engine, branch_files, tmp_path):
    r = CliRunner().invoke(main, [str(a) for a in (
        "optimize", branch_files["mesh"], "--cache-dir", branch_files["cache"], "--particles", 6, "--iterations", 2,
        "-q", "-o", tmp_path / "posed.stl", "--report", tmp_path / "report.json", "--slicer", "cura",
        "--support", "tree", "--slice-check", "--slice-rank", 2)])
    assert r.exit_code == 0, r.output
    report = json.loads((tmp_path / "report.json").read_text())
    sliced = report["slice_check"]
    assert sliced["engine"] == "cura" and sliced["support"] == "tree" and sliced["sliced_file"].endswith("posed.stl")
    assert report["support"]["source"] == "Cura, tree supports" and "(Cura, tree supports;" in report["support"]["line"]
    assert report["printer_profile"]["slicer"] == "cura" and report["printer_profile"]["overhang_angle"] == 40.0
    assert report["settings"]["overhang_angle"] == 40.0  # the search's threshold is Cura's
    assert "Cura, tree supports" in r.output
