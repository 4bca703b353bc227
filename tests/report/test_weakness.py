"""Weak sections on the pictures (supportless.report.weakness): a thin neck drawn in the weakness colours."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import supportless as sl
from supportless.energies.materials import MATERIALS
from supportless.energies.strength import analyse_strength
from supportless.report import render
from supportless.report.report import write_pictures
from supportless.report.weakness import (BREAKS_BELOW, LEGEND, MARGINAL_BELOW, WEAK_COLORS, weak_face_colors,
                                         weakest_caption, weakness_levels)

#: The neck: a 1 mm radius post between z = 39 and 45 (a 2 N grip at the head snaps it, safety about 0.5 in PLA).
NECK = (39.0, 45.0, 1.0)
JOINTS = np.array([[0, 0, 0.5], [0, 0, 40.0], [0, 0, 45], [0, 0, 57.5]])
BONES = np.array([[0, 1], [1, 2], [2, 3]])


def thin_neck() -> trimesh.Trimesh:
    """A 40 mm tall drum, a thin neck and a round head: about 58 mm tall, standing on z = 0."""
    body = trimesh.creation.cylinder(radius=10, height=40, sections=48)
    body.apply_translation((0, 0, 20))
    neck = trimesh.creation.cylinder(radius=NECK[2], height=NECK[1] - NECK[0], sections=32)
    neck.apply_translation((0, 0, 0.5 * (NECK[0] + NECK[1])))
    head = trimesh.creation.icosphere(subdivisions=3, radius=7)
    head.apply_translation((0, 0, 51))
    out = trimesh.boolean.union([body, neck, head], engine="manifold")
    assert out.is_watertight
    return out


def neck_faces(V, F) -> np.ndarray:
    """(f,) bool: the faces of the neck's side (between the drum's top and the head, close to the axis)."""
    c = V[F].mean(axis=1)
    return (c[:, 2] > NECK[0] + 1.0) & (c[:, 2] < NECK[1] - 1.5) & (np.hypot(c[:, 0], c[:, 1]) < 1.5 * NECK[2])


@pytest.fixture(scope="module")
def neck_body():
    m = thin_neck()
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


def test_levels_and_colours_follow_the_thresholds():
    safety = np.array([0.3, BREAKS_BELOW, 1.5, MARGINAL_BELOW, 7.0, np.inf])
    np.testing.assert_array_equal(weakness_levels(safety), [2, 1, 1, 0, 0, 0])
    risky = np.array([True, False, True, True, False, False])
    colors = weak_face_colors(safety, risky)
    assert colors.shape == (6, 3)
    np.testing.assert_allclose(colors[0], WEAK_COLORS[2])  # weakness is drawn over the support red
    np.testing.assert_allclose(colors[[1, 2]], [WEAK_COLORS[1]] * 2)
    np.testing.assert_allclose(colors[3], render._RISKY_COLOR)  # sound and risky: red as before
    np.testing.assert_allclose(colors[[4, 5]], [render._BASE_COLOR] * 2)
    assert "cyan" in LEGEND and "pale cyan" in LEGEND


def test_the_caption_names_the_weakest_section():
    entry = {"safety_factor": 0.45, "weakest": {"bone": "mixamorig:LeftLeg", "height_mm": 8.2, "breaks_at_n": 0.91}}
    assert weakest_caption(entry) == "weakest: LeftLeg 8 mm up, breaks at 0.9 N (safety 0.45)"
    assert weakest_caption({"safety_factor": 348.0, "weakest": entry["weakest"]}, "weakest as printed") == (
        "weakest as printed: LeftLeg 8 mm up, breaks at 0.9 N (safety 348)")
    assert weakest_caption({"safety_factor": None, "weakest": None}) == "weakest: none under load"
    assert weakest_caption(None) is None


def test_a_thin_necks_faces_are_drawn_weak_in_the_picture(neck_body, tmp_path, monkeypatch):
    V, F = neck_body
    strength = analyse_strength(V, F, JOINTS, BONES, material=MATERIALS["PLA"])
    assert strength.safety_factor < BREAKS_BELOW and strength.weakest.height_mm == pytest.approx(42.0, abs=3.0)
    neck = neck_faces(V, F)
    assert neck.sum() > 20
    # what the drawing computes: the base colour of every face of each panel, and the figure it saves
    computed, figures = [], []
    base_colors, save = render._face_base_colors, render._save_atomic
    monkeypatch.setattr(render, "_face_base_colors", lambda *a: computed.append(base_colors(*a)) or computed[-1])
    monkeypatch.setattr(render, "_save_atomic", lambda fig, path: figures.append(fig) or save(fig, path))
    sound = np.full(len(F), np.inf)  # the after panel: nothing weak
    caption = "weakest: neck 42 mm up, breaks at 1.1 N (safety 0.54)"
    out = render.render_before_after(tmp_path / "ba.png", (V, F), (V, F), (0, 0, 1), size=(600, 300),
                                     face_colors=(weak_face_colors(strength.face_safety), weak_face_colors(sound)),
                                     notes=(caption, None))
    assert (tmp_path / "ba.png").stat().st_size > 0 and out == str(tmp_path / "ba.png")
    before, after = computed
    weak_color = np.asarray(WEAK_COLORS[2])
    is_weak = np.all(np.isclose(before, weak_color), axis=1)
    assert is_weak[neck].mean() > 0.8  # the neck's faces are drawn as breaking ...
    c = V[F].mean(axis=1)
    assert not is_weak[(c[:, 2] < 30.0) | (c[:, 2] > 50.0)].any()  # ... and the drum's and the head's are not
    assert not np.all(np.isclose(after, weak_color), axis=1).any()
    texts = [t.get_text() for ax in figures[0].axes for t in ax.texts]
    assert texts == [caption]


@pytest.fixture(scope="module")
def neck_rig(neck_body):
    V, F = neck_body
    return sl.prepare_rig(V, F, JOINTS, BONES, up="z", name="neck")


def test_write_pictures_colours_the_rest_poses_neck(neck_rig, tmp_path, monkeypatch):
    """The whole way: the rig's rest pose as printed (60 mm tall) snaps at the neck; its panel says so."""
    from supportless.report import report as report_mod

    rig = neck_rig
    result = sl.optimize(rig, particles=4, iterations=1, seed=0, orient="keep")
    seen = {}
    original = report_mod.render_before_after

    def spy(path, before, after, up, **kw):
        seen.setdefault("first", kw)
        return original(path, before, after, up, **kw)

    monkeypatch.setattr(report_mod, "render_before_after", spy)
    write_pictures(tmp_path, rig, result)
    kw = seen["first"]
    rest_colors, _ = kw["face_colors"]
    assert "before_risky" not in kw  # the support red is in the face colours, under the weakness
    rest = sl.base.geometry.place_on_plate(rig.vertices, rig.up)
    neck = neck_faces(rig.vertices, rig.faces)
    is_weak = np.all(np.isclose(rest_colors, WEAK_COLORS[2]), axis=1)
    assert is_weak[neck].mean() > 0.8 and is_weak.sum() < 2 * neck.sum()
    red = sl.risky_faces(rest, rig.faces, rig.up, result.settings.overhang_angle)
    np.testing.assert_allclose(rest_colors[red & ~is_weak], np.tile(render._RISKY_COLOR, ((red & ~is_weak).sum(), 1)))
    assert kw["notes"][0].startswith("weakest: bone 2") and "breaks at" in kw["notes"][0]
    assert LEGEND in kw["suptitle"]
