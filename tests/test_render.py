"""Headless pictures."""

import os

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.image import imread

import supportless as sl
from supportless.render import (plot_convergence, render_before_after,
                                render_mesh, view_bounds)
from supportless.shapes import demo_figure


@pytest.fixture(scope="module")
def branch():
    return sl.demo_figure("branch")


def red_pixels(img):
    rgb = img[..., :3]
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return int(np.sum((r > 0.25) & (r > 2.5 * g) & (r > 2.5 * b)))


def test_render_mesh_writes_a_png_of_the_requested_size(tmp_path, branch):
    V, F, J, B = branch
    out = render_mesh(tmp_path / "a.png", V, F, np.array([0.0, 1.0, 0.0]), J, B, size=(320, 240))
    img = mpimg.imread(out)
    assert img.shape[:2] == (240, 320)
    assert img[..., :3].std() > 0.05, "not blank"
    assert not list(tmp_path.glob(".*")), "no temporary files left"


def test_risky_faces_are_red_only_when_given(tmp_path, branch):
    V, F, J, B = branch
    up = np.array([0.0, 1.0, 0.0])
    plain = mpimg.imread(render_mesh(tmp_path / "plain.png", V, F, up, size=(300, 300)))
    risky = sl.risky_faces(V, F, up)
    assert risky.any()
    marked = mpimg.imread(render_mesh(tmp_path / "risky.png", V, F, up, risky=risky, size=(300, 300),
                                      camera=(25, -20)))
    assert red_pixels(plain) == 0
    assert red_pixels(marked) > 20


def test_before_after_and_2d(tmp_path, branch):
    V, F, J, B = branch
    up = np.array([0.0, 1.0, 0.0])
    out = render_before_after(tmp_path / "ba.png", (V, F), (V * 1.1, F), up, size=(600, 300))
    assert mpimg.imread(out).shape[:2] == (300, 600)
    V2, F2, J2, B2 = sl.demo_figure("woody2d")
    out2 = render_mesh(tmp_path / "w.png", V2, F2, np.array([0.0, 1.0]), J2, B2, size=(200, 200))
    assert mpimg.imread(out2)[..., :3].std() > 0.05


def test_convergence_plot(tmp_path):
    out = plot_convergence(tmp_path / "c.png", np.linspace(1, 0.3, 30),
                           terms={"overhang": np.linspace(1, 0.25, 30), "arap": np.linspace(0, 0.05, 30)},
                           size=(400, 300))
    img = mpimg.imread(out)
    assert img.shape[:2] == (300, 400) and img[..., :3].std() > 0.02


# --- further checks ---------------------------------------------------------


UP = np.array([0.0, 1.0, 0.0])


def _read(path, size):
    img = imread(path)
    assert img.shape[0] == size[1] and img.shape[1] == size[0]
    assert img.shape[2] in (3, 4)
    return img[..., :3].astype(np.float64)


def _red_pixels(img):
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return int(np.sum((r > 0.3) & (r > 2.0 * g) & (r > 2.0 * b)))


def _overhang_mask(V, F, y_min=1.0):
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    return (N @ UP < -0.7) & (V[F].mean(axis=1)[:, 1] > y_min)


@pytest.fixture(scope="module")
def tpose():
    return demo_figure("tpose")


def test_render_mesh_png(tmp_path, tpose):
    V, F, J, B = tpose
    path = tmp_path / "sub" / "tpose.png"
    out = render_mesh(path, V, F, UP, joints=J, bones=B, title="tpose",
                      size=(400, 300))
    assert os.path.samefile(out, path)
    with open(path, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    img = _read(path, (400, 300))
    assert img.var() > 1e-3
    assert _red_pixels(img) == 0
    # no temporary files left behind
    assert os.listdir(path.parent) == ["tpose.png"]


def test_risky_faces_are_red(tmp_path, tpose):
    V, F, J, B = tpose
    risky = _overhang_mask(V, F)
    assert risky.any()
    p1 = tmp_path / "risky.png"
    # look from below the arms so the undersides face the camera
    render_mesh(p1, V, F, UP, risky=risky, camera=(0.0, -20.0), size=(300, 300))
    assert _red_pixels(_read(p1, (300, 300))) > 50
    p2 = tmp_path / "plain.png"
    render_mesh(p2, V, F, UP, camera=(0.0, -20.0), size=(300, 300))
    assert _red_pixels(_read(p2, (300, 300))) == 0
    # default camera still shows some red for an all-risky mesh
    p3 = tmp_path / "all.png"
    render_mesh(p3, V, F, UP, risky=np.ones(len(F), bool), size=(300, 300))
    assert _red_pixels(_read(p3, (300, 300))) > 1000


def test_face_colors_and_camera_dict(tmp_path):
    V, F, J, B = demo_figure("branch")
    colors = np.tile([0.2, 0.8, 0.2], (len(F), 1))
    p = tmp_path / "green.png"
    render_mesh(p, V, F, UP, face_colors=colors,
                camera={"azimuth": 90, "elevation": 30}, size=(200, 250))
    img = _read(p, (200, 250))
    g = (img[..., 1] > 0.3) & (img[..., 1] > 1.8 * img[..., 0])
    assert g.sum() > 100


def test_render_2d(tmp_path):
    V, F, J, B = demo_figure("woody2d")
    p = tmp_path / "woody.png"
    render_mesh(p, V, F, UP[:2], joints=J, bones=B, size=(300, 320))
    img = _read(p, (300, 320))
    assert img.var() > 1e-3
    assert _red_pixels(img) == 0
    risky = V[F].mean(axis=1)[:, 1] > 40
    p2 = tmp_path / "woody_risky.png"
    render_mesh(p2, V, F, UP[:2], risky=risky, size=(300, 320))
    assert _red_pixels(_read(p2, (300, 320))) > 50


def test_shared_bounds_give_same_framing(tmp_path, tpose):
    V, F, _, _ = tpose
    bounds = view_bounds(V, V * 1.1)
    assert bounds.shape == (2, 3)
    p1, p2 = tmp_path / "a.png", tmp_path / "b.png"
    render_mesh(p1, V, F, UP, bounds=bounds, size=(200, 200))
    render_mesh(p2, V, F, UP, bounds=bounds, size=(200, 200))
    assert np.array_equal(_read(p1, (200, 200)), _read(p2, (200, 200)))


def test_other_up_axis(tmp_path, tpose):
    V, F, _, _ = tpose
    R = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # +Y -> +Z
    p = tmp_path / "zup.png"
    render_mesh(p, V @ R.T, F, [0, 0, 1], size=(200, 200))
    assert _read(p, (200, 200)).var() > 1e-3


def test_before_after(tmp_path, tpose):
    V, F, J, B = tpose
    V2 = V * np.array([1.0, 0.8, 1.0])
    J2 = J * np.array([1.0, 0.8, 1.0])
    p = tmp_path / "ba.png"
    render_before_after(p, (V, F), (V2, F), UP, before_skeleton=(J, B),
                        after_skeleton=(J2, B),
                        before_risky=_overhang_mask(V, F),
                        camera=(0.0, -20.0), suptitle="tpose", size=(500, 250))
    img = _read(p, (500, 250))
    left, right = img[:, :250], img[:, 250:]
    assert left.var() > 1e-3 and right.var() > 1e-3
    assert _red_pixels(left) > 20
    assert _red_pixels(right) == 0


def test_plot_convergence(tmp_path):
    k = np.arange(60)
    hist = 100 * np.exp(-k / 10) + 1
    p = tmp_path / "conv.png"
    plot_convergence(p, hist, terms={"overhang": 50 * np.exp(-k / 8),
                                     "arap": np.linspace(0, 2, 60)},
                     size=(400, 300))
    assert _read(p, (400, 300)).var() > 1e-3
    p2 = tmp_path / "conv1.png"
    plot_convergence(p2, [3.0, 2.0, 2.0, 1.5], size=(300, 200))
    assert _read(p2, (300, 200)).var() > 1e-3
    with pytest.raises(ValueError):
        plot_convergence(tmp_path / "x.png", [])
    assert not (tmp_path / "x.png").exists()


def test_bad_inputs(tmp_path):
    V, F, _, _ = demo_figure("branch")
    with pytest.raises(ValueError):
        render_mesh(tmp_path / "x.png", V, F, [0, 0, 0])
    with pytest.raises(ValueError):
        render_mesh(tmp_path / "x.png", V, F, UP, risky=np.ones(3, bool))
    assert list(tmp_path.iterdir()) == []
