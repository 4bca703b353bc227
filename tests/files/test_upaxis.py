"""Which way is up when the user does not say (supportless.files.upaxis): the format's convention, or a flat base."""

import numpy as np
import pytest
import trimesh

import supportless as sl
from supportless.files.printframe import rotation_to_z
from supportless.files.upaxis import FLAT_BASE_SHARE, contact_shares, guess_up


def figure_on_plinth(up):
    """A ball standing on a wide flat disc, the disc's bottom facing ``-up``: a figure cut to stand on a base."""
    ball = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    ball.apply_translation([0, 0, 1.15])
    disc = trimesh.creation.cylinder(radius=1.5, height=0.3, sections=64)  # a flat bottom at z = -0.15
    body = trimesh.util.concatenate([ball, disc])
    R = np.linalg.inv(rotation_to_z(up))
    return body.vertices @ R.T + [3.0, -1.0, 2.0], np.asarray(body.faces)


def test_a_box_rests_on_each_face_with_its_share_of_the_area():
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    normals, shares = contact_shares(box.vertices, box.faces)
    assert len(shares) == 6 and shares.sum() == pytest.approx(1.0)
    areas = {(1, 0, 0): 6, (0, 1, 0): 3, (0, 0, 1): 2}  # the face of normal +x is 2 x 3
    for n, share in zip(normals, shares):
        key = tuple(int(round(abs(c))) for c in n)
        assert share == pytest.approx(areas[key] / 22.0)
    # the planes whose hull face is too small are left out when asked
    normals, shares = contact_shares(box.vertices, box.faces, min_share=5 / 22)
    assert len(shares) == 2 and np.allclose(np.abs(normals[:, 0]), 1)


@pytest.mark.parametrize("suffix, axis", [(".stl", 2), (".3mf", 2), (".obj", 1), (".off", 1), (".ply", 1),
                                          (".xyz", 1), (None, 1)])
def test_a_model_with_no_flat_base_keeps_its_formats_convention(suffix, axis):
    ball = trimesh.creation.icosphere(subdivisions=3)
    up, reason = guess_up(ball.vertices, ball.faces, None if suffix is None else f"figure{suffix}")
    assert np.array_equal(up, np.eye(3)[axis])
    assert "--up" in reason and f"+{'XYZ'[axis]}" in reason


@pytest.mark.parametrize("direction", [(0.3, 0.2, 0.93), (1, 0, 0), (0, 0, -1), (-0.5, 0.5, 0.1)])
def test_a_figure_on_a_plinth_stands_on_it_whatever_the_file_holds(direction):
    direction = np.asarray(direction) / np.linalg.norm(direction)
    V, F = figure_on_plinth(direction)
    normals, shares = contact_shares(V, F)
    assert shares[0] >= FLAT_BASE_SHARE and normals[0] @ -direction > 0.999
    for suffix in (".obj", ".stl"):
        up, reason = guess_up(V, F, f"figure{suffix}")
        assert up @ direction > 0.999, (suffix, up)
        assert "flat base" in reason


@pytest.mark.parametrize("suffix, axis", [(".obj", 1), (".stl", 2)])
def test_a_model_standing_on_its_base_as_written_keeps_the_convention(suffix, axis):
    V, F = figure_on_plinth(np.eye(3)[axis])
    up, reason = guess_up(V, F, f"figure{suffix}")
    assert np.array_equal(up, np.eye(3)[axis]) and "flat base" not in reason
    # a tall box stands on its end as written, though its sides are larger planes
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    box.vertices[:, axis] *= 3
    up, _ = guess_up(box.vertices, box.faces, f"column{suffix}")
    assert np.array_equal(up, np.eye(3)[axis])


def test_load_rig_reads_an_stl_z_up_and_an_obj_y_up(tmp_path):
    """One figure written +Y up in an OBJ and turned +Z up in an STL: the same rig, each read its own way."""
    V, F, J, B = sl.demo_figure("branch")
    R = rotation_to_z([0, 1, 0])  # +Y to +Z
    sl.write_mesh(tmp_path / "y.obj", V, F), sl.write_tgf(tmp_path / "y.tgf", J, B)
    sl.write_mesh(tmp_path / "z.stl", V @ R.T, F), sl.write_tgf(tmp_path / "z.tgf", J @ R.T, B)
    y = sl.load_rig(tmp_path / "y.obj", cache=False)
    z = sl.load_rig(tmp_path / "z.stl", cache=False)
    assert np.allclose(y.up, [0, 1, 0]) and np.allclose(z.up, [0, 0, 1])
    assert "+Y" in y.info["up"] and "OBJ" in y.info["up"] and "+Z" in z.info["up"] and "STL" in z.info["up"]
    turned = y.vertices @ R.T  # (the STL's vertices come in another order)
    assert np.allclose(z.vertices.min(0), turned.min(0), atol=1e-5)
    assert np.allclose(z.vertices.max(0), turned.max(0), atol=1e-5)


def test_an_explicit_up_is_kept_and_says_nothing(branch_files):
    rig = sl.load_rig(branch_files["mesh"], branch_files["skeleton"], up="z", cache=False)
    assert np.allclose(rig.up, [0, 0, 1]) and rig.info["up"] is None


def test_the_fertility_sculpture_stands_on_its_flat_base(shared_file):
    """A real sculpture whose base is tilted 19 degrees from +Y in its file."""
    path = shared_file("unrigged/fertility.off")
    V, F = sl.read_mesh(path)
    up, reason = guess_up(V, F, path)
    assert 15 < np.degrees(np.arccos(up[1])) < 25 and "flat base" in reason
    for name in ("bunny.obj", "libigl/elephant.obj", "unrigged/armadillo.obj"):
        V, F = sl.read_mesh(shared_file(name))
        assert np.array_equal(guess_up(V, F, name)[0], [0, 1, 0]), name


def test_prepare_names_the_direction_it_chose(tmp_path):
    from click.testing import CliRunner

    from supportless.apps.cli import main

    V, F, J, B = sl.demo_figure("branch")
    R = rotation_to_z([0, 1, 0])
    sl.write_mesh(tmp_path / "z.stl", V @ R.T, F), sl.write_tgf(tmp_path / "z.tgf", J @ R.T, B)
    r = CliRunner().invoke(main, ["prepare", str(tmp_path / "z.stl"), "--cache-dir", str(tmp_path / "cache")])
    assert r.exit_code == 0, r.output
    assert "printing direction +Z (as STL files are written; --up chooses another)" in r.stdout
    r = CliRunner().invoke(main, ["prepare", str(tmp_path / "z.stl"), "--up", "z", "--cache-dir", str(tmp_path / "cache")])
    assert r.exit_code == 0 and "printing direction" not in r.output
