"""A skeleton from the shape: simple solids whose skeleton is known, the bone range, joints inside, the TGF round trip."""

import numpy as np
import pytest

import supportless as sl
from supportless.base.kinematics import bone_parents
from supportless.rig.autoskeleton import BONE_RANGE, auto_skeleton, bones_from_tree
from supportless.shapes.sdf import Body, cap

UP = np.array([0.0, 1.0, 0.0])


def _solid(*capsules, edge=0.8):
    """A closed surface of capsules ``(a, b, radius)`` blended together."""
    body = Body()
    body.add(*[cap(np.asarray(a, float), np.asarray(b, float), r, r, 1.0) for a, b, r in capsules])
    V, F = sl.shapes.sdf.mesh_from_sdf(body.parts, body.bounds(2 * edge), edge, cut_floor=False)
    return V, F


def _tips_and_junctions(J, B):
    degree = np.bincount(B.ravel(), minlength=len(J))
    return np.flatnonzero(degree == 1), np.flatnonzero(degree > 2)


def _inside(V, F, points):
    import igl

    return igl.fast_winding_number(np.asarray(V, np.float64), np.asarray(F, np.int64), np.asarray(points)) > 0.5


def test_a_capsule_is_one_chain_along_its_axis():
    V, F = _solid(((0, 4, 0), (0, 36, 0), 4.0))
    J, B = auto_skeleton(V, F, UP, bones=(1, 6))
    tips, junctions = _tips_and_junctions(J, B)
    assert len(junctions) == 0 and len(tips) == 2  # one chain
    assert np.abs(J[:, [0, 2]]).max() < 1.0  # on the axis
    assert np.ptp(J[:, 1]) > 0.6 * 32  # along most of its length


@pytest.mark.parametrize("arms", [3, 4])
def test_a_star_is_a_root_with_a_branch_per_arm(arms):
    """A Y (three arms) has one branch point; a plus (four) a root with four branches."""
    centre = np.array([0.0, 30.0, 0.0])
    angles = np.linspace(0, 2 * np.pi, arms, endpoint=False) + 0.3
    ends = [centre + 22 * np.array([np.cos(a), np.sin(a), 0.0]) for a in angles]
    V, F = _solid(*[(centre, e, 3.5) for e in ends])
    J, B = auto_skeleton(V, F, UP, bones=(arms, 4 * arms))
    tips, junctions = _tips_and_junctions(J, B)
    assert len(tips) == arms
    assert len(junctions) == 1 and np.linalg.norm(J[junctions[0]] - centre) < 5.0
    for e in ends:  # every arm reaches near its end
        assert np.linalg.norm(J[tips] - e, axis=1).min() < 6.0
    # a tree written root -> tip: every joint ends at most one bone, one root
    assert np.bincount(B[:, 1], minlength=len(J)).max() == 1
    assert (bone_parents(B) < 0).sum() == arms  # the root's bones start at the junction


def test_pruning_keeps_every_limb_longer_than_the_threshold():
    """A chain with a short twig (3 % of the height) and a long branch (30 %): the twig goes, the branch stays."""
    nodes = np.array([[0, 0, 0], [0, 10, 0], [0, 20, 0], [0, 30, 0], [0, 40, 0], [0, 50, 0],  # trunk 0-5
                      [1.5, 20, 0],                                                       # twig off node 2
                      [5, 30, 0], [10, 30, 0], [15, 30, 0]], float)                       # branch off node 3
    tree = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [2, 6], [3, 7], [7, 8], [8, 9]])
    J, B = bones_from_tree(nodes, tree, height=50.0, bones=(2, 20))
    kept = {tuple(p) for p in J.round(6)}
    assert (1.5, 20.0, 0.0) not in kept and (15.0, 30.0, 0.0) in kept
    assert (0.0, 0.0, 0.0) in kept and (0.0, 50.0, 0.0) in kept


@pytest.mark.parametrize("wanted", [None, 12, (3, 5)])
def test_the_bone_count_stays_in_range_and_joints_lie_inside(tpose_rig, wanted):
    V, F = tpose_rig.vertices, tpose_rig.faces
    J, B = auto_skeleton(V, F, tpose_rig.up, bones=wanted)
    if wanted == (3, 5):  # fewer than the figure's 6 branches (head, arms, legs, trunk): one bone each
        assert len(B) == 6
    else:
        low, high = BONE_RANGE if wanted is None else (9, 15)
        assert low <= len(B) <= high
    assert _inside(V, F, J).all()
    assert len(_tips_and_junctions(J, B)[0]) >= 5  # head, two hands, two feet


def test_a_model_without_a_skeleton_gets_one_and_the_written_tgf_gives_the_same_rig(tmp_path):
    V, F = sl.demo_figure("tpose")[:2]
    sl.write_mesh(tmp_path / "figure.obj", V, F)
    out = tmp_path / "figure-skeleton.tgf"
    rig = sl.load_rig(tmp_path / "figure.obj", up="y", cache_dir=tmp_path / "cache", skeleton_out=out)
    assert any("built one from the shape" in w and f"{rig.bone_count} bones" in w for w in rig.info["warnings"])
    J, B = sl.read_tgf(out)
    np.testing.assert_allclose(J, rig.joints)
    np.testing.assert_array_equal(B, rig.bones)
    again = sl.load_rig(tmp_path / "figure.obj", out, up="y", cache_dir=tmp_path / "cache")
    np.testing.assert_array_equal(again.bones, rig.bones)
    np.testing.assert_allclose(again.tet_weights, rig.tet_weights)  # the same rig: the same cache entry
    assert again.info.get("from_cache")
    # the builder is randomised: loading the model again keeps the skeleton it got, and its rig
    third = sl.load_rig(tmp_path / "figure.obj", up="y", cache_dir=tmp_path / "cache")
    np.testing.assert_array_equal(third.joints, rig.joints)
    assert third.info.get("from_cache")


def test_joints_outside_move_in_along_their_bone_and_a_tip_with_nothing_inside_goes():
    from supportless.rig.autoskeleton import inside_joints

    V, F = _solid(((0, 4, 0), (0, 36, 0), 4.0))
    J = np.array([[0, 20, 0], [0, 43.0, 0], [0, 10, 0], [30, 10, 0], [40, 10, 0]], float)
    B = np.array([[0, 1], [0, 2], [2, 3], [3, 4]])  # a tip just past the top; a side branch wholly outside
    J2, B2 = inside_joints(V, F, J, B)
    assert _inside(V, F, J2).all()
    assert len(B2) == 3 and len(J2) == 4  # the branch's tip is gone, its other joint moved in to the skin
    assert np.linalg.norm(J2[:, [0, 2]], axis=1).max() < 5.0
    top = J2[np.argmax(J2[:, 1])]
    assert 38.0 < top[1] < 40.5 and abs(top[0]) < 1e-9  # moved down its bone, just inside the cap at 40


def _plus_region(arm=20, width=4, cell=1.0):
    """A flat plus sign (z = 0), arms ``arm`` long and ``width`` wide, as a triangulated grid."""
    n = int(round((2 * arm + width) / cell))
    xs = (np.arange(n + 1) * cell) - (arm + width / 2)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    V = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    centres = (xs[:-1] + xs[1:]) / 2
    keep = (np.abs(centres)[:, None] < width / 2) | (np.abs(centres)[None, :] < width / 2)
    i, j = np.nonzero(keep)
    a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
    F = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    used = np.unique(F)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def test_a_flat_plus_gets_a_planar_skeleton_with_a_branch_per_arm():
    from supportless.base.geometry import points_in_triangles
    from supportless.rig.autoskeleton import planar_skeleton

    V, F = _plus_region()
    J, B = planar_skeleton(V, F, UP)
    assert J.shape[1] == 3 and np.all(J[:, 2] == 0)  # on the plane
    tips, junctions = _tips_and_junctions(J, B)
    assert len(tips) == 4 and len(junctions) >= 1
    assert np.linalg.norm(J[junctions, :2], axis=1).min() < 4.0  # the branch point at the centre
    assert sorted(np.sign(J[tips, :2][np.argmax(np.abs(J[tips, :2]), axis=1) == 0, 0])) == [-1, 1]
    assert np.abs(J[tips, :2]).max(axis=1).min() > 12.0  # every tip well out along its arm
    assert np.all(points_in_triangles(V[:, :2], F, J[:, :2]))  # inside the figure
    assert set(B.ravel()) == set(range(len(J))) and len(B) == len(J) - 1  # one tree


def test_a_planar_model_without_a_skeleton_becomes_a_2d_rig(tmp_path):
    V, F = _plus_region(arm=10, width=4)
    sl.write_mesh(tmp_path / "plus.obj", V, F)
    rig = sl.load_rig(tmp_path / "plus.obj", cache=False, skeleton_out=tmp_path / "plus.tgf")
    assert rig.vertices.shape[1] == 2 and rig.bone_count >= 4
    assert any("built one from the shape" in w for w in rig.info["warnings"])
    J, B = sl.read_tgf(tmp_path / "plus.tgf")
    assert np.all(J[:, 2] == 0) and len(B) == rig.bone_count


def test_the_app_draws_a_skeleton_built_from_the_shape(tmp_path):
    """A figure without a skeleton opens in the browser app with its built skeleton drawn, joint by joint."""
    from supportless.apps.ui import App

    V, F = _solid(((0, 4, 0), (0, 30, 0), 4.0), ((-14, 22, 0), (14, 22, 0), 3.0), edge=1.0)
    sl.write_mesh(tmp_path / "cross.obj", V, F)
    rig = sl.load_rig(tmp_path / "cross.obj", cache=False)
    app = App(rig, verbose=False, workdir=tmp_path / "work")
    try:
        assert app.wait_idle(60)
        joints = np.array([h.position for h in app.scene.h_joints])
        assert len(joints) == len(rig.joints) and rig.bone_count >= 3
        assert np.asarray(app.scene.h_bones.points).shape == (rig.bone_count, 2, 3)
    finally:
        app.stop()
