"""The browser app as a new user meets it, driven in Debian's Chromium through Playwright: an empty page,
a glTF character uploaded, a mesh and its skeleton dropped, a bad file, the support preview, the Slice
button (a stand-in slicer), a locked bone under Optimize, and every shared glTF character framed and readable.

The tests of this module share one app and one page, in order, but none relies on what an earlier one
opened: the Fox, the bunny and the glTF characters come from the shared test models (skipped without
them, failed under ``CI=true``), and the steps that need a model on screen (the bad file, the support
preview, Slice, the locked bone) each open the built-in ``tpose`` figure themselves (:func:`figure`),
so they run in a clone with no ``../shared`` beside it. Each step saves a screenshot to
``test-artifacts/ui-*.png`` for a person to look at.

No step waits a fixed time for the page: a step that needs the page to show what the app sent asks the page a
question behind it (:func:`_drawn`), and a measured view is taken once two screenshots in a row agree
(:func:`_view_shot`).
"""

from __future__ import annotations

import base64
import io
import re
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import unavailable
from conftest import until as _until
from slicers import fake_exe, stand_in_slicer

from supportless.apps.ui import App
from supportless.files.printframe import rig_print_frame
from supportless.rig.load import load_rig

ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"
#: The smallest share of the view a framed model covers (the Fox, the smallest, covers several percent).
MIN_MODEL_SHARE = 0.01
#: WCAG contrast ratio the model keeps against what is behind it (3:1 is the bar for graphics).
MIN_CONTRAST = 3.0

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    a = App(None, verbose=False, workdir=tmp_path_factory.mktemp("page-app"))
    yield a
    a.stop()


@pytest.fixture(scope="module")
def page(app, chromium):
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        unavailable("playwright is not installed: pip install playwright (no browser download needed)")
    errors: list[str] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=[
            "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
            "--disable-background-networking"])
        pg = browser.new_page(viewport={"width": 960, "height": 640})
        pg.on("pageerror", lambda e: errors.append(str(e)))
        pg.goto(app.url)
        pg.get_by_text("Status:").wait_for(timeout=60000)
        yield pg
        browser.close()
    assert not errors, errors


@pytest.fixture
def figure(app, page, tpose_rig):
    """The built-in ``tpose`` figure (no shared data needed), opened afresh for one test; the page shows it.

    Opening it resets the pose, the locks and the view. The page holds only the new model's panel, never a widget
    of the model shown before: its widgets are found by their ids (viser's uuids) once the page has applied what
    the app sent (:func:`_drawn`).
    """
    old = [h._impl.uuid for h in (app.panel.bone, app.panel.lock)] if app.rig is not None else []
    app.open_rig(tpose_rig, rig_print_frame(tpose_rig))
    assert app.wait_idle(60)
    _drawn(app)
    bones = page.locator(f"[id='{app.panel.bone._impl.uuid}']")  # the bone list of the new panel
    bones.wait_for(timeout=60000)
    assert all(page.locator(f"[id='{u}']").count() == 0 for u in old)  # the last model's panel is gone
    assert page.get_by_role("combobox").first.input_value() == tpose_rig.bone_names()[0]
    _close_notices(page)  # a reloaded page would have none: the last test's do not cover this one's controls
    return tpose_rig


def _status(page) -> str:
    return page.locator("body").inner_text()


def _wait_text(page, pattern: str, timeout: float = 120000) -> None:
    page.wait_for_function("p => new RegExp(p).test(document.body.innerText)", arg=pattern, timeout=timeout)


def _close_notices(page) -> None:
    """Close the notices on the page (they cover the view, and the controls under them)."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    for close in page.locator(".mantine-Notification-root button").all():
        try:
            close.click(timeout=1000)
        except PlaywrightTimeout:  # closed by itself meanwhile
            pass


def _shot(page, name: str) -> bytes:
    """A screenshot (PNG bytes), also saved for a person to look at."""
    _close_notices(page)
    ARTIFACTS.mkdir(exist_ok=True)
    png = page.screenshot()
    (ARTIFACTS / f"ui-{name}.png").write_bytes(png)
    return png


def _pixels(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), np.float64)


def _luminance(rgb: np.ndarray) -> np.ndarray:
    """WCAG relative luminance of sRGB colours (..., 3) in 0-255."""
    c = rgb / 255.0
    c = np.where(c <= 0.03928, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return c @ np.array([0.2126, 0.7152, 0.0722])


def _drawn(app) -> None:
    """Wait until the page has applied all the app sent it so far (a wait for a state, not a delay).

    The page applies the app's messages in order, a frame's worth at a time, and applies a scene change in the
    frame that reads it; a read of its local storage is answered in turn, so its answer comes after the messages
    sent before it. (viser's ``get_render`` promises as much, but draws the view twice more, about a second a call here.)
    """
    for client in app.server.get_clients().values():
        client.local_storage.get_item("supportless-test-fence", timeout=120)


def _view_shot(page, app, clip: dict) -> np.ndarray:
    """The 3D view (``clip``: where it is on the page) once the page has drawn it and it stays still.

    After :func:`_drawn`, shots until two in a row are the same: the camera glides to a new model over a few
    frames, and the page draws only when something changed (viser renders on demand).
    """
    _drawn(app)
    end = time.monotonic() + 120  # a hang guard, not a verdict: a still view is the same shot twice
    last = page.screenshot(clip=clip)
    while time.monotonic() < end:
        png = page.screenshot(clip=clip)
        if png == last:
            return _pixels(png)
        last = png
    pytest.fail("the 3D view did not stay still for two screenshots in 120 s")


def model_on_screen(page, app, name: str) -> tuple[float, float]:
    """Where the model's surface is on screen: the view with it and without it, compared.

    Returns
    -------
    share : float
        Share of the page's pixels (the whole view, panel included) the surface covers.
    contrast : float
        WCAG contrast ratio of the surface's median luminance against what is behind it there.
    """
    _drawn(app)
    _shot(page, name)  # as the user sees it; measured without the support columns in front of the body
    box = page.locator("canvas").first.bounding_box()
    size = page.viewport_size
    clip = {"x": max(box["x"], 0), "y": max(box["y"], 0)}  # the 3D view: the rest of the page is the same in both
    clip |= {"width": min(box["x"] + box["width"], size["width"]) - clip["x"],
             "height": min(box["y"] + box["height"], size["height"]) - clip["y"]}
    shown = app.view["show_support"]
    app.set_view(show_support=False)
    assert app.wait_idle(60)
    with_model = _view_shot(page, app, clip)
    app.scene.h_mesh.visible = False
    try:
        without = _view_shot(page, app, clip)
    finally:
        app.scene.h_mesh.visible = True
        app.set_view(show_support=shown)
    mask = np.abs(with_model - without).sum(axis=-1) > 30
    if not mask.any():
        return 0.0, 1.0
    a = float(np.median(_luminance(with_model[mask])))
    b = float(np.median(_luminance(without[mask])))
    return float(mask.sum() / (size["width"] * size["height"])), (max(a, b) + 0.05) / (min(a, b) + 0.05)


def _drop(page, paths) -> None:
    """Drop files on the page as a user drags them from a file manager."""
    files = [{"name": Path(p).name, "b64": base64.b64encode(Path(p).read_bytes()).decode()} for p in paths]
    page.evaluate("""files => {
        const dt = new DataTransfer();
        for (const f of files) {
            const bin = Uint8Array.from(atob(f.b64), c => c.charCodeAt(0));
            dt.items.add(new File([bin], f.name));
        }
        document.querySelector('canvas').dispatchEvent(
            new DragEvent('drop', {dataTransfer: dt, bubbles: true, cancelable: true}));
    }""", files)


# --------------------------------------------------------------------------- #
def test_an_empty_page_invites_a_model(app, page):
    assert app.rig is None
    assert "Drop a model anywhere on this page" in _status(page)
    _shot(page, "1-empty")


def test_a_glb_uploaded_opens_framed_with_its_bones_and_figures(app, page, shared_file):
    fox = shared_file("gltf/Fox.glb")
    page.locator("input[type=file]").first.set_input_files(str(fox))
    _wait_text(page, "opened Fox")
    assert app.rig is not None and app.rig.name == "Fox" and app.rig.bone_count == 27
    assert app.wait_idle(60)
    _wait_text(page, r"Support filament, an estimate: [0-9,]+ mm ≈ [0-9.]+ g")
    bones = page.get_by_role("combobox").first  # the bone list is the fox's
    assert _until(lambda: bones.input_value() == app.rig.bone_names()[0], 30)
    share, contrast = model_on_screen(page, app, "2-fox-uploaded")
    assert share > MIN_MODEL_SHARE, f"the fox covers {share:.2%} of the view"
    assert contrast >= MIN_CONTRAST, f"the fox against its ground: contrast {contrast:.2f}"


def test_a_mesh_and_its_skeleton_dropped_together(app, page, shared_file):
    mesh, skeleton = shared_file("bunny.obj"), shared_file("bunny.tgf")
    _drop(page, [mesh, skeleton])  # the mesh first: the page sends the skeleton before it
    _wait_text(page, "opened bunny")
    assert app.rig.name == "bunny" and app.rig.bone_count == 11  # the skeleton's bones, not a built one
    assert not any("built" in w for w in app.rig.info.get("warnings", []))
    assert app.wait_idle(60)
    share, contrast = model_on_screen(page, app, "3-bunny-dropped")
    assert share > MIN_MODEL_SHARE and contrast >= MIN_CONTRAST


def test_a_bad_upload_is_one_line_and_the_app_keeps_working(app, page, figure, tmp_path):
    junk = tmp_path / "broken.glb"
    junk.write_bytes(b"not a glTF at all")
    page.locator("input[type=file]").first.set_input_files(str(junk))
    _wait_text(page, "Error:[^\\n]*cannot open broken.glb: not a readable glTF")
    notes = tmp_path / "notes.txt"
    notes.write_text("hello")
    page.locator("input[type=file]").first.set_input_files(str(notes))
    _wait_text(page, "notes.txt: not a model the app opens")
    line = next(t for t in _status(page).splitlines() if "notes.txt" in t)
    assert "Traceback" not in _status(page) and len(line) < 300
    assert app.rig is figure  # still there, still posable
    app.state.set_bone_angles(1, [0, 0, 20.0])
    assert app.wait_idle(60)
    assert np.degrees(app.state.get_angles()[1, 2]) == pytest.approx(20.0)
    _shot(page, "4-bad-upload")


def test_the_support_preview_toggles_and_follows_the_pose(app, page, figure):
    assert app.wait_idle(60)
    support = app.scene._overlays["support"]
    assert support.visible and len(support.vertices) > 0
    before = np.array(support.vertices)
    page.get_by_text("Show predicted support").click()
    assert _until(lambda: not app.view["show_support"]) and app.wait_idle(60)
    assert not support.visible
    page.get_by_text("Show predicted support").click()
    assert _until(lambda: app.view["show_support"]) and app.wait_idle(60)
    assert support.visible
    # a bone turned with its slider: the columns under it change
    bone = int(np.flatnonzero(~app.state.fixed)[-1])  # the last bone that is not kept on the plate
    page.get_by_role("combobox").first.click()
    page.get_by_role("option", name=app.rig.bone_names()[bone]).click()
    assert _until(lambda: app.state.selected == bone)
    slider = page.get_by_role("slider").nth(0)
    slider.focus()
    for _ in range(4):  # each press is a redraw of a software-rendered page: a few degrees are enough
        slider.press("ArrowRight")
    assert _until(lambda: abs(np.degrees(app.state.get_angles()[bone, 0]) - 4.0) < 1e-6) and app.wait_idle(60)
    after = np.array(support.vertices)
    assert before.shape != after.shape or not np.allclose(before, after)
    _shot(page, "5-support-preview")


def test_slice_shows_the_slicers_figures_before_and_after(app, page, figure, tmp_path, monkeypatch):
    app.set_view(show_support=False)  # this step clicks: a software-rendered page answers faster without it
    exe = fake_exe(tmp_path, "prusa-slicer", stand_in_slicer("float(len(rec['v'])) / 100"))
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", exe)
    page.get_by_text("Slice", exact=True).click()
    button = page.get_by_role("button", name="Slice rest pose and this pose")
    button.wait_for()
    button.click()
    _wait_text(page, r"stand-in\): ")
    text = _status(page)
    assert re.search(r"support filament\s+[0-9,]+ mm\s+[0-9,]+ mm", text), text
    assert re.search(r"support\s+[0-9.]+ g\s+[0-9.]+ g", text), text
    assert app.slice_report["before"]["support_mm"] == pytest.approx(len(app.rig.faces) / 100)
    _wait_text(page, r"Support filament, sliced by PrusaSlicer: [0-9,]+ mm ≈ [0-9.]+ g")  # it leads the energies
    page.get_by_role("cell", name="support filament").scroll_into_view_if_needed()  # the Slice folder's table
    _shot(page, "6-sliced")
    page.get_by_text("Slice", exact=True).click()


def test_a_locked_bone_is_kept_by_optimize(app, page, figure, tmp_path, monkeypatch):
    app.set_view(show_support=False)  # this step clicks: a software-rendered page answers faster without it
    monkeypatch.setenv("SUPPORTLESS_PRUSA_SLICER", fake_exe(tmp_path, "prusa-slicer", stand_in_slicer("1.0")))
    free = np.flatnonzero(~app.state.fixed)
    bone = int(free[-1])
    app.state.select_bone(bone)
    app.state.set_bone_angles(bone, [0, 0, 15.0])
    assert app.wait_idle(60)
    page.get_by_text("Lock this bone").click()
    assert _until(lambda: str(bone + 1) in app.state.settings.fix)
    assert app.wait_idle(60)
    assert app.locked()[bone] and app.state.fixed[bone]
    start = app.state.get_angles()
    # the print rotation kept: the search must pose the free bones (the figure laid on its back is its answer else)
    assert app.start_optimize(particles=8, iterations=4, orient="keep")
    assert app.state.wait_optimize(300) and app.wait_idle(60)
    done = app.state.get_angles()
    assert np.array_equal(done[bone], start[bone])
    assert app.state.last_result is not None and not np.allclose(done, start)  # the others moved
    assert "locked: kept as it is" in _status(page)
    # a lock travels with the pose file
    data = app.state.pose_bytes()
    assert f'"{bone + 1}"' in data.decode()
    app.lock_bone(bone, False)
    assert not app.locked()[bone]
    app.load_pose_bytes("with-lock.json", data)
    assert app.locked()[bone]
    _shot(page, "7-locked")
    assert app.rig is figure


@pytest.mark.parametrize("name", ["CesiumMan", "Fox", "Mannequin", "RobotExpressive", "Soldier", "Xbot",
                                  "quaternius/Adventurer", "quaternius/Character_HumanoidRig",
                                  "quaternius/Frog", "quaternius/Horse", "quaternius/Stegosaurus",
                                  "quaternius/Wasp", "quaternius/Wolf"])
def test_every_shared_gltf_character_is_framed_and_readable(app, page, shared_file, name):
    rig = load_rig(shared_file(f"gltf/{name}.glb"))  # the user's rig cache: prepared once per machine
    app.open_rig(rig, rig_print_frame(rig))
    # the support preview is another test's subject: drawn in software, a 40 000-triangle character's see-through
    # columns take seconds a frame (the framing is measured without them in any case)
    app.set_view(show_support=False)
    assert app.wait_idle(120)
    share, contrast = model_on_screen(page, app, f"gltf-{Path(name).name}")
    assert share > MIN_MODEL_SHARE, f"{name} covers {share:.2%} of the view"
    assert contrast >= MIN_CONTRAST, f"{name} against its ground: contrast {contrast:.2f}"
