"""The browser app's strength overlay (supportless.apps.ui.strength): the weak sections follow the pose."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from conftest import until

from supportless.apps.ui.state import EditorState
from supportless.apps.ui.strength import WEAK_RGB, StrengthOverlay, analyse_pose
from supportless.report.weakness import WEAK_COLORS
from supportless.search.sturdiness import pose_strength

#: The tpose figure's last bone turned 60° about z: a limb whose sections hold a grip less than twice over.
BONE, TURN = 14, [0.0, 0.0, 60.0]


class Ready:
    """``on_ready`` of a headless overlay: counts the analyses and wakes the test."""

    def __init__(self):
        self.calls, self.event = 0, threading.Event()

    def __call__(self):
        self.calls += 1
        self.event.set()


def analysed(overlay, ready, state):
    """The overlay's analysis of the state's pose, waiting for the thread when it is not done yet."""
    (angles, R), frame = state.get_pose(), state.print_frame
    view = overlay.request(state.rig, angles, R, frame.height_mm, state.settings.material)
    if view is None:
        assert ready.event.wait(120)
        ready.event.clear()
        assert overlay.wait(120)
        view = overlay.request(state.rig, angles, R, frame.height_mm, state.settings.material)
    assert view is not None
    return view


def test_the_colours_and_the_line_follow_a_bone_edit(tpose_rig, tmp_path):
    state = EditorState(tpose_rig, workdir=tmp_path)
    ready = Ready()
    overlay = StrengthOverlay(ready)
    rest = analysed(overlay, ready, state)
    assert ready.calls == 1
    assert analysed(overlay, ready, state) is rest and ready.calls == 1  # the same pose is not analysed again
    assert rest.levels.shape == (len(tpose_rig.faces),) and not rest.levels.any()  # the rest pose holds twice over
    assert "weakest: " in rest.line and "2 N grip, PLA" in rest.line and "cyan" not in rest.line
    state.set_bone_angles(BONE, TURN)
    edited = analysed(overlay, ready, state)
    assert ready.calls == 2
    assert edited.safety_factor < min(2.0, rest.safety_factor)
    assert np.sum(edited.levels == 1) > 10 and edited.line != rest.line and "marginal (pale cyan)" in edited.line
    # the analysis is the pose's as printed, at the print height
    angles, R = state.get_pose()
    expected = pose_strength(tpose_rig, angles, R, state.print_frame.height_mm)
    np.testing.assert_array_equal(edited.face_safety, expected.face_safety)
    assert edited.safety_factor == expected.safety_factor
    state.undo()
    assert analysed(overlay, ready, state).line == rest.line


def test_a_turned_print_is_said_as_printed(tpose_rig):
    from supportless.search.orientation import rotation_between

    R = rotation_between(tpose_rig.up, np.array([0.0, 0.0, 1.0]))  # lying on its back
    view = analyse_pose(tpose_rig, tpose_rig.rest_angles(), R, 60.0)
    assert view.line.startswith("- Strength (2 N grip, PLA): weakest as printed: ")
    assert WEAK_RGB == {k: tuple(round(255 * c) for c in v) for k, v in WEAK_COLORS.items()}


@pytest.fixture()
def tpose_app(tpose_rig, tmp_path):
    from supportless.apps.ui import App

    app = App(tpose_rig, verbose=False, workdir=tmp_path)
    assert app.wait_idle(60)
    yield app
    app.stop()


def settled(app, angles) -> bool:
    """The overlay's analysis is of ``angles`` and the page drew it (no timing asserted)."""
    app.strength.wait(120)
    current = app.strength.current
    return (current is not None and app.wait_idle(60) and current.key[1] == np.asarray(angles, np.float64).tobytes()
            and "updating" not in app.panel.measures.content)


def test_the_app_overlay_follows_the_pose(tpose_app, tpose_rig):
    app = tpose_app
    assert "Strength" not in app.panel.measures.content  # off by default
    app.set_view(show_strength=True)
    assert until(lambda: settled(app, app.state.get_angles()), 300)
    rest_text = app.panel.measures.content
    assert "- Strength (2 N grip, PLA): weakest: " in rest_text
    overlays = app.scene._overlays
    assert all(not overlays[k].visible for k in ("weak1", "weak2") if k in overlays)  # nothing weak at rest
    app.state.set_bone_angles(BONE, TURN)
    assert until(lambda: settled(app, app.state.get_angles()), 300)
    levels = app.strength.current.levels
    marginal = overlays["weak1"]
    assert marginal.visible and len(marginal.vertices) == 3 * np.sum(levels == 1) > 0
    assert tuple(marginal.color) == WEAK_RGB[1]
    assert app.panel.measures.content != rest_text and "marginal (pale cyan)" in app.panel.measures.content
    # the overlay lies on the surface as drawn: each coloured triangle just off its face
    F = tpose_rig.faces[levels == 1]
    drawn = app.scene.scale * app.shown_vertices[F].reshape(-1, 3)
    assert np.abs(np.asarray(marginal.vertices) - drawn).max() < 0.01 * app.scene.size
    app.set_view(show_strength=False)
    assert app.wait_idle(60)
    assert not marginal.visible and "Strength" not in app.panel.measures.content
