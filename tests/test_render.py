"""Headless pictures."""

import matplotlib.image as mpimg
import numpy as np
import pytest

import supportless as sl
from supportless.render import plot_convergence, render_before_after, render_mesh


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
