"""Headless pictures."""

import os

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.image import imread

import supportless as sl
from supportless.report.render import plot_convergence, render_before_after, render_mesh, view_bounds
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


def green_pixels(img):
    rgb = img[..., :3]
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return int(np.sum((g > 0.3) & (g > 1.6 * r) & (g > 1.3 * b)))


def test_balance_marks_are_drawn_only_when_given(tmp_path, branch):
    """The support polygon (green) and the centre of mass appear in the panel that has them."""
    V, F, J, B = branch
    up = np.array([0.0, 1.0, 0.0])
    support = np.array([[-3.0, 0.0, -3.0], [3.0, 0.0, -3.0], [3.0, 0.0, 3.0], [-3.0, 0.0, 3.0]])
    out = render_before_after(tmp_path / "ba.png", (V, F), (V, F), up, size=(600, 300),
                              after_balance={"centre_of_mass": np.array([0.0, 12.0, 0.0]), "support": support})
    img = mpimg.imread(out)
    left, right = img[:, :300], img[:, 300:]
    assert green_pixels(left) == 0
    assert green_pixels(right) > 30


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


def _extent_px(mask):
    """(height, width) in pixels of the bounding box of the True pixels."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return rows[-1] - rows[0] + 1, cols[-1] - cols[0] + 1


def _green(img):
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (g > 0.3) & (g > 1.8 * r) & (g > 1.8 * b)


# The projection is orthographic and linear, so a figure scaled by 1.5 about the
# origin is exactly 1.5 times as tall and wide on screen when the framing is the
# same. On a ~130-pixel silhouette, rasterisation moves each edge by up to a pixel:
# the measured ratio is within 1.5 * 2 / 129 < 0.03 of the true one.
SCALE, RATIO_TOL = 1.5, 0.03


def test_shared_bounds_give_same_framing(tmp_path, tpose):
    V, F, _, _ = tpose
    bounds = view_bounds(V, V * SCALE)
    assert bounds.shape == (2, 3)
    np.testing.assert_array_equal(bounds, [V.min(0) * SCALE, V.max(0) * SCALE])  # min y is 0, min x, z < 0

    def extent(vertices, bounds):
        path = tmp_path / "frame.png"
        render_mesh(path, vertices, F, UP, face_colors=[0.1, 0.8, 0.1], bounds=bounds, size=(300, 300))
        return np.array(_extent_px(_green(_read(path, (300, 300)))))

    shared = extent(V * SCALE, bounds) / extent(V, bounds)
    np.testing.assert_allclose(shared, [SCALE, SCALE], rtol=0, atol=RATIO_TOL)
    # framed each on its own mesh, the scaled figure fills the picture the same way: the check above
    # tells the two apart
    own = extent(V * SCALE, None) / extent(V, None)
    np.testing.assert_allclose(own, [1.0, 1.0], rtol=0, atol=RATIO_TOL)


def test_before_after_panels_share_the_framing(tmp_path, tpose):
    V, F, _, _ = tpose
    everything = np.ones(len(F), bool)  # all red, to find each figure in its panel
    p = tmp_path / "ba.png"
    render_before_after(p, (V, F), (V * SCALE, F), UP, before_risky=everything, after_risky=everything,
                        size=(600, 300))
    img = _read(p, (600, 300))
    red = (img[..., 0] > 0.3) & (img[..., 0] > 2.0 * img[..., 1]) & (img[..., 0] > 2.0 * img[..., 2])
    ratio = np.array(_extent_px(red[:, 300:])) / np.array(_extent_px(red[:, :300]))
    np.testing.assert_allclose(ratio, [SCALE, SCALE], rtol=0, atol=RATIO_TOL)


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


def _drawn(tris, rgb, size=64):
    """RGB (size, size, 3) uint8 of flat triangles drawn on a white square of the unit box."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from supportless.report.render import _FlatTriangles

    fig = Figure(figsize=(1, 1), dpi=size, facecolor="white")
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.set_axis_off()
    ax.add_artist(_FlatTriangles(np.asarray(tris, np.float64), np.asarray(rgb, np.float64), zorder=2))
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3]


def test_flat_triangles_leave_no_seam_between_neighbours():
    # a square of two triangles of one colour: its shared diagonal is that colour too, nothing shows through
    grey = (0.5, 0.5, 0.5)
    img = _drawn([[(0.1, 0.1), (0.9, 0.1), (0.9, 0.9)], [(0.1, 0.1), (0.9, 0.9), (0.1, 0.9)]], [grey, grey])
    inside = img[10:54, 10:54].reshape(-1, 3)
    assert np.all(np.abs(inside.astype(int) - 128) <= 1), "a seam or a gap inside the square"
    assert np.all(img[:4, :] == 255) and np.all(img[:, :4] == 255), "drawn outside the triangles"


def test_flat_triangles_later_ones_cover_earlier_ones():
    red, blue = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)
    big = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
    small = [(0.1, 0.1), (0.4, 0.1), (0.1, 0.4)]
    for order, top in (((big, small), blue), ((small, big), red)):
        img = _drawn(order, [red, blue] if order[0] is big else [blue, red])
        centre = img[64 - 1 - 13, 13]  # (0.2, 0.2): inside both, row 0 at the top
        np.testing.assert_array_equal(centre, np.round(255 * np.array(top)).astype(np.uint8))
