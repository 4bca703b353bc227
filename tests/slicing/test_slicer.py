"""Tests for supportless.slicing.prusaslicer (PrusaSlicer-based support measurement)."""

from __future__ import annotations

import json
import math
import textwrap

import numpy as np
import pytest
from slicers import fake_exe, stand_in_slicer

from supportless.base.errors import InputError, SupportlessError
from supportless.files.meshes import read_mesh
from supportless.report.report import reduction
from supportless.slicing import prusaslicer as sl
from supportless.slicing.prusaslicer import (
    SliceReport,
    SlicerError,
    SlicerNotFound,
    find_prusa_slicer,
    mm_to_cm3,
    parse_filament_used,
    place_vertices,
    rotation_to_z,
    scale_for_height,
    slice_check,
)

SAMPLE_GCODE = textwrap.dedent(
    """\
    G1 X10 Y10 E0.5
    M107
    ; filament used [mm] = 1491.16
    ; filament used [cm3] = 3.59
    ; total filament used [g] = 0.00
    ; total filament cost = 0.00
    ; estimated printing time (normal mode) = 12m 3s

    ; prusaslicer_config = begin
    ; layer_height = 0.2
    ; prusaslicer_config = end
    """
)


# ---------------------------------------------------------------------------
# Pure logic (always run)
# ---------------------------------------------------------------------------


def test_parse_filament_used():
    mm, cm3 = parse_filament_used(SAMPLE_GCODE)
    assert mm == 1491.16 and cm3 == 3.59  # float("1491.16"): parsed, not computed


def test_parse_filament_used_without_cm3_and_multi_extruder():
    mm, cm3 = parse_filament_used("; filament used [mm] = 10.5, 2.5\n")
    assert mm == 13.0  # 10.5 + 2.5 is exact in binary
    assert cm3 is None


def test_parse_filament_used_missing_line_is_slicer_error():
    with pytest.raises(SlicerError, match="filament used"):
        parse_filament_used("G1 X0\n; total filament used [g] = 1\n")


def test_rotation_to_z_is_proper_rotation():
    for up in [(0, 1, 0), (1, 0, 0), (0, 0, 1), (0, 0, -1), (0, -1, 0), (1, 2, 3)]:
        R = rotation_to_z(up)
        u = np.asarray(up, float) / np.linalg.norm(up)
        np.testing.assert_allclose(R @ u, [0, 0, 1], atol=1e-12)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    # up = +Y: +90 deg about X (y -> z, z -> -y)
    np.testing.assert_allclose(rotation_to_z((0, 1, 0)) @ [0, 0, 1], [0, -1, 0], atol=1e-12)
    with pytest.raises(ValueError):
        rotation_to_z((0, 0, 0))


def test_placement_up_y_gives_60mm_on_bed():
    rng = np.random.default_rng(0)
    # model units: 0.15 tall along y, offset away from the origin
    V = rng.uniform([-0.1, 0.03, -0.06], [0.06, 0.18, 0.06], size=(500, 3))
    s = scale_for_height(V, (0, 1, 0), 60.0)
    P = place_vertices(V, (0, 1, 0), s, center_xy=(125.0, 105.0))
    assert P[:, 2].min() == 0.0
    assert P[:, 2].max() == pytest.approx(60.0, abs=1e-9)
    lo, hi = P.min(axis=0), P.max(axis=0)
    assert 0.5 * (lo[0] + hi[0]) == pytest.approx(125.0, abs=1e-9)
    assert 0.5 * (lo[1] + hi[1]) == pytest.approx(105.0, abs=1e-9)
    # the model's y extent became the print's z extent
    assert np.ptp(V[:, 1]) * s == pytest.approx(60.0, abs=1e-9)
    # x is preserved (up to scale), model z maps to -y
    np.testing.assert_allclose(P[:, 0] - P[0, 0], (V[:, 0] - V[0, 0]) * s, rtol=0, atol=1e-9)
    np.testing.assert_allclose(P[:, 1] - P[0, 1], -(V[:, 2] - V[0, 2]) * s, rtol=0, atol=1e-9)


def test_posed_mesh_uses_original_scale():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 1]], float)
    s = scale_for_height(V, (0, 1, 0), 60.0)
    assert s == 30.0
    posed = V * [1, 0.5, 1]  # posed mesh only 1 unit tall
    P = place_vertices(posed, (0, 1, 0), s)
    assert np.ptp(P[:, 2]) == pytest.approx(30.0, abs=1e-12)
    with pytest.raises(InputError, match="zero extent along the up direction"):
        scale_for_height(V * [1, 0, 1], (0, 1, 0), 60.0)


def test_volume_maths():
    assert mm_to_cm3(1000.0) == pytest.approx(math.pi * 0.875**2, rel=1e-15)
    assert mm_to_cm3(3360.0) == pytest.approx(3360.0 * math.pi * 0.875**2 / 1000.0, rel=1e-15)
    assert mm_to_cm3(100.0, diameter_mm=2.0) == pytest.approx(0.1 * math.pi, rel=1e-15)


def test_one_reduction_for_the_package():
    assert not hasattr(sl, "reduction_percent")
    assert sl.reduction is reduction
    assert reduction(3360.0, 840.0) == 75.0
    assert reduction(100.0, 150.0) == -50.0
    assert reduction(0.0, 0.0) is None


def test_errors_are_the_packages():
    assert issubclass(SlicerError, SupportlessError) and issubclass(SlicerNotFound, SlicerError)
    assert issubclass(SlicerError, RuntimeError)  # callers that caught RuntimeError still work
    msg = str(SlicerNotFound())
    assert "\n" not in msg and "apt-get install prusa-slicer" in msg and sl.ENV_VAR in msg


def test_last_error_line_strips_log_prefix():
    err = (
        "[2026-11-22 00:06:54.882778] [0x00007f64] [trace]   Initializing StaticPrintConfigs\n"
        "[2026-11-22 00:06:54.886943] [0x00007f64] [error]   stl_open: empty file\n"
        "bad.stl: Loading of a model file failed.\n\n"
    )
    assert sl._last_error_line(err) == "bad.stl: Loading of a model file failed."
    assert sl._last_error_line(err.rsplit("bad.stl", 1)[0]) == "stl_open: empty file"
    # an error about one object ends with the object's name: the error itself is the line before
    first_layer = "There is an object with no extrusions in the first layer.\nObject name: posed.stl\n"
    assert sl._last_error_line(first_layer) == ("There is an object with no extrusions in the first layer. "
                                                 "(Object name: posed.stl)")


def test_report_to_dict_is_json_ready():
    r = SliceReport(
        support_mm_before=np.float64(100.0),
        support_mm_after=25.0,
        support_cm3_before=mm_to_cm3(100.0),
        support_cm3_after=mm_to_cm3(25.0),
        reduction_percent=75.0,
        total_mm_before=1100.0,
        total_mm_after=1025.0,
        model_mm_before=1000.0,
        model_mm_after=1000.0,
        config=dict(sl.STANDARD_CONFIG),
    )
    r.total_cm3_after = float("nan")
    d = r.to_dict()
    assert json.loads(json.dumps(d)) == d
    assert d["after"]["total_cm3"] is None
    assert d["before"]["support_mm"] == 100.0 and d["after"]["support_mm"] == 25.0
    assert d["before"]["support_cm3"] == mm_to_cm3(100.0)
    assert d["after"]["model_mm"] == 1000.0 and d["before"]["total_mm"] == 1100.0
    assert d["reduction_percent"] == 75.0
    assert "support_mm_before" not in d
    assert d["config"]["support-material-threshold"] == "45"


def test_standard_config_is_explicit():
    cfg = sl.STANDARD_CONFIG
    assert cfg["layer-height"] == "0.2"
    assert cfg["perimeters"] == "2"
    assert cfg["fill-density"] == "15%"
    assert cfg["support-material-threshold"] == "45"
    assert cfg["filament-diameter"] == "1.75"
    assert sl.SUPPORT_OPTIONS == ("--support-material", "--support-material-auto")



def test_the_default_config_is_prusaslicers_defaults_from_the_one_table():
    """DEFAULT_CONFIG is the default preset's; its values are files/printer's PRUSA_DEFAULTS, which profiles read."""
    from supportless.files.printer import PRUSA_DEFAULTS, default_profile

    assert sl.DEFAULT_CONFIG is sl.PRESETS[sl.DEFAULT_PRESET] is sl.PRUSA_DEFAULTS_CONFIG
    assert sl.PRESETS["standard"] is sl.STANDARD_CONFIG and sl.STANDARD_CONFIG["support-material-threshold"] == "45"
    for key, value in sl.PRUSA_DEFAULTS_CONFIG.items():
        assert PRUSA_DEFAULTS[key.replace("-", "_")] == value, key
    profile = default_profile()
    assert (profile.layer_height, profile.first_layer_height, profile.support_threshold) == (
        float(sl.DEFAULT_CONFIG["layer-height"]), float(sl.DEFAULT_CONFIG["first-layer-height"]),
        float(sl.DEFAULT_CONFIG["support-material-threshold"]))


# --- finding the slicer and error handling, with fake executables ----------


def _box_vf():
    import trimesh

    b = trimesh.creation.box((10, 10, 10))
    return np.asarray(b.vertices), np.asarray(b.faces)


def test_find_prusa_slicer_env_var(tmp_path, monkeypatch):
    exe = fake_exe(tmp_path, "my-slicer", "print('hi')\n")
    monkeypatch.setenv(sl.ENV_VAR, exe)
    assert find_prusa_slicer() == exe
    monkeypatch.setenv(sl.ENV_VAR, str(tmp_path / "does-not-exist"))
    assert find_prusa_slicer() is None


def test_slicer_not_found_message(monkeypatch, tmp_path):
    monkeypatch.setenv(sl.ENV_VAR, str(tmp_path / "nope"))
    with pytest.raises(SlicerNotFound) as ei:
        slice_check(_box_vf(), _box_vf())
    msg = str(ei.value)
    assert "PrusaSlicer" in msg and "apt-get install prusa-slicer" in msg
    assert isinstance(ei.value, SlicerError)


def test_slicer_failure_is_one_line_error(tmp_path, monkeypatch):
    exe = fake_exe(
        tmp_path,
        "failing-slicer",
        """\
        import sys
        if "--help" in sys.argv:
            print("PrusaSlicer-0.0 fake"); sys.exit(0)
        sys.stderr.write("[2026] [0x1] [trace] Initializing StaticPrintConfigs\\n")
        sys.stderr.write("something went wrong\\nObject too tall to print.\\n")
        sys.exit(3)
        """,
    )
    monkeypatch.setenv(sl.ENV_VAR, exe)
    with pytest.raises(SlicerError) as ei:
        slice_check(_box_vf(), _box_vf(), timeout=30)
    msg = str(ei.value)
    assert "\n" not in msg
    assert msg.endswith("Object too tall to print.")
    assert "exit 3" in msg


def test_slicer_timeout_is_clear_error(tmp_path, monkeypatch):
    exe = fake_exe(tmp_path, "slow-slicer", "import time\ntime.sleep(30)\n")
    with pytest.raises(SlicerError, match="timed out after 0.5 s"):
        slice_check(_box_vf(), _box_vf(), timeout=0.5, slicer=exe)


def test_unknown_preset(tmp_path):
    exe = fake_exe(tmp_path, "x", "pass\n")
    with pytest.raises(ValueError, match="preset"):
        slice_check(_box_vf(), _box_vf(), config="nope", slicer=exe)


# --- the whole pipeline, with a stand-in slicer -----------------------------

# Reads the binary STL it is given and reports 10 mm of support filament per mm
# of height on the bed (none without --support-material), on top of 1000 mm.
STAND_IN_SLICER = stand_in_slicer("10.0 * float(rec['v'][..., 2].max())")


def test_slice_check_pipeline_with_a_stand_in_slicer(tmp_path):
    exe = fake_exe(tmp_path, "stand-in-slicer", STAND_IN_SLICER)
    V, F = _box_vf()  # a 10-unit cube about the origin
    keep = tmp_path / "keep"
    r = slice_check((V, F), (V * [1.0, 0.5, 1.0], F), up=(0, 1, 0), height_mm=30.0, slicer=exe, keep_dir=keep)
    # the original is 30 mm tall, the posed one (half as tall, same scale) 15 mm; STL stores
    # float32, so heights carry up to ~2e-6 mm of rounding, 2e-5 mm of support filament
    assert r.support_mm_before == pytest.approx(300.0, abs=1e-4)
    assert r.support_mm_after == pytest.approx(150.0, abs=1e-4)
    assert r.reduction_percent == pytest.approx(50.0, abs=1e-4)
    assert r.model_mm_before == pytest.approx(1000.0) and r.total_cm3_before == 2.5  # total minus support
    assert r.support_cm3_before == mm_to_cm3(r.support_mm_before)
    assert r.scale == 3.0
    np.testing.assert_allclose(r.size_mm_before, [30.0, 30.0, 30.0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(r.size_mm_after, [30.0, 30.0, 15.0], rtol=0, atol=1e-9)
    assert r.slicer == exe and r.slicer_version == "PrusaSlicer-0.0 stand-in"
    assert sorted(r.slices) == ["original-support", "posed-support"]  # one slice per mesh, with supports
    assert r.support_time_s_before is None and not list(keep.glob("*nosupport*"))
    assert r.config["bed-shape"] == "0x0,250x0,250x210,0x210"
    assert r.config["support-material-threshold"] == sl.PRUSA_DEFAULTS_CONFIG["support-material-threshold"]
    # the meshes went to PrusaSlicer on the bed: lowest point at z = 0, centred on the 250 x 210 bed
    for name, height in (("original", 30.0), ("posed", 15.0)):
        P, _ = read_mesh(keep / f"{name}.stl")
        assert P[:, 2].min() == 0.0
        assert P[:, 2].max() == pytest.approx(height, abs=2e-6)  # float32
        np.testing.assert_allclose(0.5 * (P.min(0) + P.max(0))[:2], [125.0, 105.0], rtol=0, atol=2e-5)


def test_slice_check_reads_mesh_files_through_io(tmp_path):
    import supportless

    exe = fake_exe(tmp_path, "stand-in-slicer", STAND_IN_SLICER)
    V, F = _box_vf()
    supportless.write_mesh(tmp_path / "box.obj", V, F)
    r = slice_check(tmp_path / "box.obj", str(tmp_path / "box.obj"), up=(0, 0, 1), height_mm=20.0, slicer=exe)
    assert r.support_mm_before == r.support_mm_after == pytest.approx(200.0, abs=1e-4)  # float32 STL
    with pytest.raises(InputError, match=r"nope\.stl: no such file"):
        slice_check(tmp_path / "nope.stl", (V, F), slicer=exe)


@pytest.mark.parametrize("posed, fragment", [
    ("bad faces", "posed mesh: face 0 (1 3 0) refers to a vertex out of range 0..1 (12 such faces)"),
    ("nan", "posed mesh: vertex 0 has a NaN or infinite coordinate"),
    ("2d", "posed mesh: only 3D meshes can be sliced"),
])
def test_bad_mesh_arrays_are_input_errors_before_slicing(tmp_path, posed, fragment):
    exe = fake_exe(tmp_path, "never-run", "import sys\nsys.exit(99)\n")
    V, F = _box_vf()
    bad = {"bad faces": (V[:2], F), "nan": (V * np.nan, F), "2d": (V[:, :2], F)}[posed]
    with pytest.raises(InputError) as info:
        slice_check((V, F), bad, slicer=exe)
    assert fragment in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(TypeError, match="a file path or a \\(V, F\\) pair"):
        slice_check((V, F), 42, slicer=exe)


# ---------------------------------------------------------------------------
# With PrusaSlicer
# ---------------------------------------------------------------------------


def _gamma_mesh():
    """A post (along +Y) with a horizontal arm at the top sticking out along +X."""
    import trimesh

    post = trimesh.creation.box((8, 30, 8))
    post.apply_translation((0, 15, 0))
    arm = trimesh.creation.box((20, 6, 8))
    arm.apply_translation((4 + 10 - 1, 27, 0))  # overlaps the post by 1 unit
    try:
        m = trimesh.boolean.union([post, arm], engine="manifold")
    except Exception:  # manifold3d missing: overlapping boxes slice fine too
        m = trimesh.util.concatenate([post, arm])
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)


def test_arm_up_needs_less_support_than_arm_out(prusa_slicer):
    V, F = _gamma_mesh()
    # +90 deg about Z: the arm (+X) now points up (+Y), the post lies on the bed
    Rz = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    posed = (V @ Rz.T, F)
    r = slice_check((V, F), posed, up=(0, 1, 0), height_mm=30.0, config="fast", timeout=120)
    assert r.support_mm_before > 50.0, r.to_dict()
    assert r.support_mm_after < 0.25 * r.support_mm_before, r.to_dict()
    assert r.reduction_percent is not None and r.reduction_percent > 75.0
    assert r.size_mm_before[2] == pytest.approx(30.0, abs=1e-9)
    assert r.config["layer-height"] == "0.3"
    assert r.slicer_version.startswith("PrusaSlicer")
    d = json.loads(json.dumps(r.to_dict()))
    assert d["before"]["support_mm"] == pytest.approx(r.support_mm_before)


def test_plain_box_needs_no_support(prusa_slicer):
    box = _box_vf()
    r = slice_check(box, box, up=(0, 0, 1), height_mm=15.0, config="fast", timeout=120)
    assert r.model_mm_before > 100.0
    # no overhang: no support, up to PrusaSlicer's run-to-run noise (~0.01 % of the filament; 0.0 measured)
    assert abs(r.support_mm_before) <= 1e-3 * r.model_mm_before, r.to_dict()
    assert abs(r.support_mm_after) <= 1e-3 * r.model_mm_before, r.to_dict()


def test_accepts_mesh_paths(prusa_slicer, tmp_path):
    import supportless

    V, F = _gamma_mesh()
    path = tmp_path / "gamma.stl"
    supportless.write_mesh(path, V, F)
    r = slice_check(str(path), (V, F), height_mm=20.0, config="fast", timeout=120)
    # identical geometry: identical support, up to PrusaSlicer's run-to-run noise (~0.01 %; 0 measured)
    assert r.support_mm_before > 20.0
    assert r.support_mm_after == pytest.approx(r.support_mm_before, rel=1e-3)


# --- the command line, on the built-in demo figure -------------------------


def _demo_meshes(tmp_path):
    import supportless

    rig = supportless.load_rig("demo:branch", cache_dir=tmp_path / "cache")
    res = supportless.optimize(rig, particles=12, iterations=6, seed=0, orient="keep")  # a new pose, standing
    supportless.write_mesh(tmp_path / "rest.stl", rig.vertices, rig.faces)
    supportless.write_mesh(tmp_path / "posed.stl", res.vertices, rig.faces)
    return tmp_path / "rest.stl", tmp_path / "posed.stl"


@pytest.mark.slow
def test_cli_slice_check_on_the_demo_figure(prusa_slicer, tmp_path):
    from click.testing import CliRunner

    from supportless.apps.cli import main

    rest, posed = _demo_meshes(tmp_path)
    out = CliRunner().invoke(main, ["slice-check", str(rest), str(posed), "--up", "y", "--posed-as", "original",
                                     "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    assert data["before"]["support_mm"] > 0
    assert data["after"]["support_mm"] < data["before"]["support_mm"]
    assert data["reduction_percent"] > 0
    assert data["before"]["support_g"] == pytest.approx(data["before"]["support_cm3"] * 1.24)
    assert data["before"]["support_time_s"] is None and data["after"]["total_time_s"] > 0  # one slice per mesh
    text = CliRunner().invoke(main, ["slice-check", str(rest), str(posed), "--posed-as", "original"])
    assert text.exit_code == 0 and "reduction" in text.output
    assert " g)" in text.output and "printing time of the supports" not in text.output


def test_cli_slice_check_without_prusaslicer_says_how_to_install(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from supportless.apps.cli import main

    rest, posed = _demo_meshes(tmp_path)
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", str(tmp_path / "no-such-slicer"))
    monkeypatch.setenv("SUPPORTLESS_CURA_ENGINE", str(tmp_path / "no-cura"))  # no slicer at all
    out = CliRunner().invoke(main, ["slice-check", str(rest), str(posed)])
    assert out.exit_code == 2
    assert "apt-get install prusa-slicer" in out.output
    assert "Traceback" not in out.output


def test_parse_print_time():
    from supportless.slicing.prusaslicer import parse_print_time

    assert parse_print_time("; estimated printing time (normal mode) = 1h 1m 31s\n") == 3691.0
    assert parse_print_time("x\n; estimated printing time (normal mode) = 2d 0h 0m 5s\n") == 2 * 86400 + 5.0
    assert parse_print_time("; estimated printing time (normal mode) = 42s") == 42.0
    assert parse_print_time("; filament used [mm] = 3\n") is None
    assert parse_print_time("; estimated printing time (normal mode) = soon\n") is None


# Like STAND_IN_SLICER, and also records its arguments, and prints 100 s per mm of support filament
STAND_IN_WITH_TIME = STAND_IN_SLICER.replace(
    'open(out, "w").write(',
    'open(out + ".args", "w").write("\\n".join(args))\n'
    't = 600 + 100 * support\n'
    'open(out, "w").write(f"; estimated printing time (normal mode) = {int(t // 3600)}h {int(t % 3600 // 60)}m '
    '{int(t % 60)}s\\n" + ')


def test_slice_check_with_a_profile_loads_it_and_reports_grams_and_time(tmp_path):
    from supportless.files.printer import read_printer_profile

    exe = fake_exe(tmp_path, "stand-in-slicer", STAND_IN_WITH_TIME)
    ini = tmp_path / "petg.ini"
    ini.write_text("filament_density = 1.27\nfilament_diameter = 2.85\nsupport_material_threshold = 40\n")
    profile = read_printer_profile(ini)
    keep = tmp_path / "keep"
    V, F = _box_vf()
    r = slice_check((V, F), (V * [1.0, 0.5, 1.0], F), up=(0, 1, 0), height_mm=3.0, slicer=exe, keep_dir=keep,
                    profile=profile)
    args = (keep / "original-support.gcode.args").read_text().splitlines()
    assert args[args.index("--load") + 1] == str(profile.path)
    assert "--support-material-threshold=0" not in args  # the built-in preset is not passed over the file
    assert r.support_mm_before == pytest.approx(30.0, abs=1e-4)
    assert r.support_cm3_before == pytest.approx(mm_to_cm3(30.0, 2.85))
    assert r.support_g_before == pytest.approx(mm_to_cm3(30.0, 2.85) * 1.27)
    # the whole print's time with supports; the supports' own time is not measured
    assert r.total_time_s_before == 3600.0 and r.total_time_s_after == 2100.0 and r.support_time_s_after is None
    assert r.config == profile.raw and r.profile == profile.path
    d = r.to_dict()
    assert d["before"]["support_g"] == r.support_g_before and d["after"]["total_time_s"] == 2100.0
    assert d["after"]["support_time_s"] is None


def test_feature_filament_counts_extrusion_per_feature_absolute_and_relative():
    """Hand-counted G-code: retractions and their undoing, travel and resets are not filament laid down."""
    from supportless.slicing.gcode import feature_filament

    absolute = ("M82\nG92 E0\nG1 X0 Y0 E2.0\n;TYPE:Perimeter\nG1 X1 Y0 E5.0\nG1 E4.2 ; retract\n"
                "G1 X5 Y5 F9000\nG1 E5.0 ; unretract\n;TYPE:Support material\nG1 X2 Y2 E7.5\n"
                "G92 E0\nG1 X3 Y3 E1.25 ; after a reset\n;TYPE:Support material interface\nG1 Y4 E2.0\n")
    got = feature_filament(absolute)
    assert got == pytest.approx({"": 2.0, "Perimeter": 3.0, "Support material": 3.75,
                                 "Support material interface": 0.75})
    relative = ("M83\n;TYPE:Perimeter\nG1 X1 Y0 E3.0\nG1 E-0.8\nG1 E0.8\n;TYPE:Support material\n"
                "G1 X2 Y2 E2.5 ; comment E9\nG1 X3 E1.25\n")
    assert feature_filament(relative) == pytest.approx({"Perimeter": 3.0, "Support material": 3.75})
    assert feature_filament("; no moves\n") == {}


def test_slice_check_agrees_with_the_difference_of_two_slices(prusa_slicer):
    """The support features of one slice against with-minus-without supports: apart by the skirt's few mm."""
    from supportless.slicing.prusaslicer import slice_support

    V, F = _gamma_mesh()  # the arm out: it needs support
    r = slice_check((V, F), (V, F), up=(0, 1, 0), height_mm=30.0, timeout=120)  # the default preset: a skirt
    (two,) = slice_support([(V, F)], (0, 1, 0), r.scale, timeout=120).meshes  # the old way
    assert two["support_mm"] > 50.0
    assert r.support_mm_before == pytest.approx(two["support_mm"], rel=0.03, abs=5.0)  # 537 against 542 mm
    assert r.model_mm_before == pytest.approx(two["nosupport"]["filament_mm"], rel=0.01)
    assert r.total_mm_before == pytest.approx(two["support"]["filament_mm"], rel=1e-3)
    assert r.total_time_s_before == pytest.approx(two["support"]["print_seconds"], rel=0.01)


def _octahedron_on_its_apex():
    """A regular octahedron, 20 units tall along +Z: it touches the plate at one point."""
    import trimesh

    V = 10.0 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    return V, np.asarray(trimesh.convex.convex_hull(V).faces, np.int64)


def test_a_print_on_a_tip_gets_a_figure(prusa_slicer):
    """PrusaSlicer refuses a print touching the plate at a tip without supports; with them, its support is measured."""
    from supportless.slicing.prusaslicer import slice_support

    tip = _octahedron_on_its_apex()
    with pytest.raises(SlicerError, match="no extrusions in the first layer"):  # the old way: no figure
        slice_support([tip], (0, 0, 1), 1.0, config="fast", timeout=120)
    r = slice_check(tip, _box_vf(), up=(0, 0, 1), height_mm=20.0, config="fast", timeout=120)
    assert r.support_mm_before > 100.0 and r.support_mm_after == 0.0 and r.reduction_percent == 100.0
    assert 0.0 < r.model_mm_before < r.total_mm_before and r.total_time_s_before > 0
