"""Rig preparation: volume mesh, bounded biharmonic weights, validation, cache, 2D rigs."""

import dataclasses
import shutil

import igl
import numpy as np
import pytest

import supportless as sl
from supportless.base import kinematics as kin
from supportless.base.errors import InputError
from supportless.base.geometry import signed_volume
from supportless.files.meshes import write_dmat, write_tet_mesh
from supportless.rig import rig as rig_mod
from supportless.search import answer as answer_mod
from supportless.search import optimizer as search_mod


@pytest.fixture(scope="module")
def woody_rig():
    return sl.prepare_rig(*sl.demo_figure("woody2d"), up="y", name="woody2d")


@pytest.fixture(params=["branch", "tpose", "woody2d", "bunny"])
def any_rig(request):
    return request.getfixturevalue({"branch": "branch_rig", "tpose": "tpose_rig", "woody2d": "woody_rig",
                                    "bunny": "bunny_rig"}[request.param])


def _bone_samples(rig, tol=1e-9):
    """{bone: indices of tet vertices on its segment}, without joints shared with other bones."""
    TV, J, B = rig.tet_vertices, rig.joints, rig.bones
    scale = np.ptp(TV, axis=0).max()
    uses = np.bincount(B.ravel(), minlength=len(J))
    shared = J[uses > 1]
    out = {}
    for b, (i, j) in enumerate(B):
        a, e = J[i], J[j]
        t = np.clip((TV - a) @ (e - a) / ((e - a) @ (e - a)), 0.0, 1.0)
        on = np.linalg.norm(TV - (a + t[:, None] * (e - a)), axis=1) <= tol * scale
        near_shared = (np.linalg.norm(TV[:, None, :] - shared[None], axis=2) <= tol * scale).any(1)
        out[b] = np.flatnonzero(on & ~near_shared)
    return out


# ---------------------------------------------------------------------- weights


def test_weights_are_a_partition_of_unity_in_0_1(any_rig):
    W = any_rig.tet_weights
    assert W.shape == (len(any_rig.tet_vertices), any_rig.bone_count)
    assert W.min() >= -1e-9 and W.max() <= 1 + 1e-9
    np.testing.assert_allclose(W.sum(1), 1.0, rtol=0, atol=1e-9)
    assert any_rig.weights.shape == (len(any_rig.vertices), any_rig.bone_count)


def test_each_bone_has_weight_one_on_its_samples(any_rig):
    W = any_rig.tet_weights
    for b, idx in _bone_samples(any_rig).items():
        assert len(idx) >= 3, f"bone {b} has only {len(idx)} samples in the volume mesh"
        np.testing.assert_allclose(W[idx, b], 1.0, rtol=0, atol=1e-9, err_msg=f"bone {b}")


def test_volume_mesh_fills_the_surface(any_rig):
    rig = any_rig
    n = len(rig.vertices)
    assert np.array_equal(rig.tet_vertices[:n], rig.vertices)
    assert rig.tets.min() >= 0 and rig.tets.max() < len(rig.tet_vertices)
    enclosed = signed_volume(rig.vertices, rig.faces)
    assert enclosed > 0
    if rig.dim == 3:
        vol = np.asarray(igl.volume(rig.tet_vertices, rig.tets)).ravel()
        assert np.all(vol > 0)
        assert abs(vol.sum() - enclosed) <= 1e-9 * enclosed  # the tets fill the surface exactly: rounding only
    else:
        area = signed_volume(rig.tet_vertices, rig.tets)  # sum of signed triangle areas
        assert abs(area - enclosed) <= 1e-9 * enclosed


def test_prepared_rig_shapes(tpose_rig):
    rig = tpose_rig
    assert rig.dim == 3 and rig.bone_count == 15 and rig.joints.shape == (16, 3)
    assert rig.tets.shape[1] == 4 and rig.faces.dtype == np.int64
    np.testing.assert_array_equal(rig.up, [0.0, 1.0, 0.0])
    assert rig.lbs.shape == (len(rig.vertices), 15 * 4)


# ----------------------------------------------------------- forests and order


def test_forest_rig(branch_files):
    """Two separate root bones: the post (with its top) and a free-standing arm bone."""
    V, F, J = branch_files["V"], branch_files["F"], branch_files["joints"]
    joints = np.vstack([J, [[2.0, 20.0, 0.0]]])  # 4: start of the arm, not connected to the post
    bones = np.array([[0, 1], [1, 3], [4, 2]])
    rig = sl.prepare_rig(V, F, joints, bones, up="y")
    assert rig.parents.tolist() == [-1, 0, -1]
    np.testing.assert_allclose(rig.tet_weights.sum(1), 1.0, atol=1e-9)
    a = rig.rest_angles()
    a[2] = [0.0, 0.0, 0.5]  # lift the arm about its own root
    posed = rig.pose(a)
    P = rig.posed_joints(a)
    np.testing.assert_allclose(P[[0, 1, 3, 4]], joints[[0, 1, 3, 4]], atol=1e-12)
    assert P[2, 1] > joints[2, 1] + 5
    post = rig.weights[:, 2] == 0
    np.testing.assert_allclose(posed[post], rig.vertices[post], atol=1e-12)


def test_bones_in_any_order_in_prepare_rig(branch_files, branch_rig):
    """A shuffled skeleton gives the same weights, column-permuted (the same tet mesh is used)."""
    perm = np.array([2, 0, 1])
    rig = sl.prepare_rig(branch_files["V"], branch_files["F"], branch_files["joints"], branch_files["bones"][perm],
                         up="y", tet_mesh=(branch_rig.tet_vertices, branch_rig.tets))
    # the same solve with the bones permuted: rounding differences only (2e-16 and 1e-14 measured)
    np.testing.assert_allclose(rig.tet_weights, branch_rig.tet_weights[:, perm], rtol=0, atol=1e-12)
    a = np.random.default_rng(0).uniform(-0.5, 0.5, (3, 3))
    np.testing.assert_allclose(rig.pose(a[perm]), branch_rig.pose(a), rtol=0, atol=1e-12)


# ------------------------------------------------------------ precomputed input


def test_precomputed_tets_and_weights(tmp_path, branch_files, branch_rig):
    tets, weights = tmp_path / "branch.mesh", tmp_path / "branch.dmat"
    write_tet_mesh(tets, branch_rig.tet_vertices, branch_rig.tets)
    write_dmat(weights, branch_rig.tet_weights)
    rig = sl.load_rig(branch_files["mesh"], branch_files["skeleton"], tets=tets, weights=weights,
                      cache_dir=tmp_path / "cache")
    # the STL may list vertices in another order: match them by position
    order = np.lexsort(rig.vertices.T)
    ref = np.lexsort(branch_rig.vertices.T)
    # STL stores float32: coordinates below 32 round by at most 9.5e-7 (0 measured: manifold3d's are float32)
    np.testing.assert_allclose(rig.vertices[order], branch_rig.vertices[ref], rtol=0, atol=9.6e-7)
    np.testing.assert_array_equal(rig.weights[order], branch_rig.weights[ref])  # .dmat is written with %.17g
    assert len(rig.tets) == len(branch_rig.tets)


def test_weights_without_tets_are_rejected(tmp_path, branch_files, branch_rig):
    weights = tmp_path / "w.dmat"
    write_dmat(weights, branch_rig.tet_weights)
    with pytest.raises(sl.InputError, match="--tets"):
        sl.load_rig(branch_files["mesh"], branch_files["skeleton"], weights=weights, cache=False)


# ------------------------------------------------------------------ bad inputs


def test_bad_input_raises_a_clear_input_error(bad_case):
    model, kwargs, culprit, fragments = bad_case
    with pytest.raises(sl.InputError) as info:
        sl.load_rig(model, up="y", cache=False, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{culprit}: "), message
    for fragment in fragments:
        assert fragment in message, message


def test_prepare_rig_rejects_bad_arrays(branch_files):
    V, F, J, B = (branch_files[k] for k in ("V", "F", "joints", "bones"))
    with pytest.raises(sl.InputError, match="no bones"):
        sl.prepare_rig(V, F, J, np.zeros((0, 2), np.int64))
    with pytest.raises(sl.InputError, match="out of range"):
        sl.prepare_rig(V, F, J, np.array([[0, 7]]))
    with pytest.raises(sl.InputError, match="3 boundary edges"):
        sl.prepare_rig(V, F[1:], J, B)
    with pytest.raises(sl.InputError, match="up direction"):
        sl.prepare_rig(V, F, J, B, up="sideways")


def test_inward_surface_is_flipped(branch_files, branch_rig):
    V, F, J, B = (branch_files[k] for k in ("V", "F", "joints", "bones"))
    rig = sl.prepare_rig(V, F[:, ::-1], J, B, tet_mesh=(branch_rig.tet_vertices, branch_rig.tets),
                         tet_weights=branch_rig.tet_weights)
    assert signed_volume(rig.vertices, rig.faces) > 0


# ------------------------------------------------------------------------ cache


def test_second_load_comes_from_the_cache(tmp_path, monkeypatch):
    first = sl.load_rig("demo:branch", up="y", cache_dir=tmp_path)
    import supportless.rig.load as rig_module

    def no_preparation(*args, **kwargs):  # the second load must not prepare: it reads the entry
        raise AssertionError("the rig was prepared again")

    monkeypatch.setattr(rig_module, "prepare_rig", no_preparation)
    second = sl.load_rig("demo:branch", up="y", cache_dir=tmp_path)
    assert first.info["from_cache"] is False and second.info["from_cache"] is True
    for name in ("vertices", "faces", "joints", "bones", "tet_vertices", "tets", "tet_weights", "up"):
        a, b = getattr(first, name), getattr(second, name)
        assert a.dtype == b.dtype and np.array_equal(a, b), name
    # one finished cache file, no temporary leftovers
    assert [p.suffix for p in tmp_path.iterdir()] == [".npz"]
    assert second.name == "branch"


def test_changed_input_misses_the_cache(tmp_path, branch_files):
    mesh = tmp_path / "branch.stl"
    shutil.copy(branch_files["mesh"], mesh)
    sl.write_tgf(tmp_path / "branch.tgf", branch_files["joints"], branch_files["bones"])
    cache = tmp_path / "cache"
    assert sl.load_rig(mesh, cache_dir=cache).info["from_cache"] is False
    assert sl.load_rig(mesh, cache_dir=cache).info["from_cache"] is True
    moved = branch_files["joints"].copy()
    moved[3, 1] -= 1.0  # post top one unit lower
    sl.write_tgf(tmp_path / "branch.tgf", moved, branch_files["bones"])
    rig = sl.load_rig(mesh, cache_dir=cache)
    assert rig.info["from_cache"] is False
    np.testing.assert_array_equal(rig.joints, moved)
    # another printing direction is another rig too
    assert sl.load_rig(mesh, up="z", cache_dir=cache).info["from_cache"] is False
    assert len(list(cache.glob("*.npz"))) == 3


@pytest.mark.parametrize("damage", ["garbage", "truncated"])
def test_damaged_cache_entry_is_rebuilt_with_a_warning(tmp_path, damage):
    first = sl.load_rig("demo:branch", cache_dir=tmp_path)
    (entry,) = tmp_path.glob("*.npz")
    whole = entry.read_bytes()
    entry.write_bytes(b"not an npz file" if damage == "garbage" else whole[: len(whole) // 2])  # a full disk
    rig = sl.load_rig("demo:branch", cache_dir=tmp_path)
    assert rig.info["from_cache"] is False
    said = [w for w in rig.info["warnings"] if "was damaged" in w]
    assert len(said) == 1 and str(entry) in said[0]
    again = sl.load_rig("demo:branch", cache_dir=tmp_path)
    assert again.info["from_cache"] is True and not [w for w in again.info["warnings"] if "damaged" in w]
    np.testing.assert_array_equal(again.tet_weights, first.tet_weights)


_PREPARE = """
import sys, numpy as np, supportless as sl
rig = sl.load_rig(sys.argv[1], sys.argv[2], cache_dir=sys.argv[3])
np.save(sys.argv[4], rig.tet_weights)
print(rig.info["from_cache"])
"""


def test_four_processes_preparing_one_model_at_once_share_the_cache_safely(tmp_path, branch_files):
    """Each process prepares or reads the rig; none reads a half-written entry; one entry stays, no leftovers."""
    import subprocess
    import sys

    cache = tmp_path / "shared-cache"
    procs = [subprocess.Popen([sys.executable, "-c", _PREPARE, str(branch_files["mesh"]), str(branch_files["skeleton"]),
                               str(cache), str(tmp_path / f"w{i}.npy")], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for i in range(4)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert all(p.returncode == 0 for p in procs), [e for _, e in outs]
    weights = [np.load(tmp_path / f"w{i}.npy") for i in range(4)]
    for w in weights[1:]:
        np.testing.assert_array_equal(w, weights[0])
    assert [p.name for p in cache.iterdir()] == [next(cache.glob("rig-*.npz")).name]  # one entry, no temporaries
    assert sl.load_rig(branch_files["mesh"], branch_files["skeleton"], cache_dir=cache).info["from_cache"] is True


def test_a_cache_that_cannot_be_written_is_said_once_and_the_rig_still_loads(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    rig = sl.load_rig("demo:branch", cache_dir=blocker / "cache")
    assert rig.info["from_cache"] is False and rig.info["cache"] is None
    said = [w for w in rig.info["warnings"] if "cannot be written" in w]
    assert len(said) == 1 and str(blocker / "cache") in said[0] and "--cache-dir" in said[0]


def test_no_cache_writes_nothing(tmp_path):
    rig = sl.load_rig("demo:branch", cache=False, cache_dir=tmp_path / "c")
    assert rig.info["from_cache"] is False
    assert not (tmp_path / "c").exists()


# --------------------------------------------------------------------------- 2D


def test_woody2d_is_a_2d_rig(woody_rig):
    rig = woody_rig
    assert rig.dim == 2
    assert rig.vertices.shape[1] == 2 and rig.joints.shape == (12, 2) and rig.tet_vertices.shape[1] == 2
    assert rig.tets.shape[1] == 3
    np.testing.assert_array_equal(rig.up, [0.0, 1.0])
    T = rig.transforms(rig.rest_angles())
    assert T.shape == (11, 2, 3)


def test_woody2d_poses_rotate_in_the_plane(woody_rig):
    rig = woody_rig
    b = 3  # chest -> left elbow
    root, tip = rig.bones[b]
    a = rig.rest_angles()
    a[b, 2] = np.pi / 2
    P = rig.posed_joints(a)
    d = rig.joints[tip] - rig.joints[root]
    np.testing.assert_allclose(P[tip], rig.joints[root] + [-d[1], d[0]], atol=1e-12)  # counter-clockwise
    posed = rig.pose(a)
    assert posed.shape == rig.vertices.shape
    # the first two angles do nothing in 2D
    a2 = a.copy()
    a2[:, :2] = np.random.default_rng(0).uniform(-1, 1, (rig.bone_count, 2))
    np.testing.assert_array_equal(rig.pose(a2), posed)
    # one tree: turning its root turns the figure rigidly about the root's pivot
    roots = np.flatnonzero(rig.parents < 0)
    assert len(roots) == 1
    a3 = rig.rest_angles()
    a3[roots, 2] = 0.3
    R = kin.planar_rotation(0.3)
    pivot = rig.joints[rig.pivots[roots[0]]]
    np.testing.assert_allclose(rig.pose(a3), (rig.vertices - pivot) @ R.T + pivot, atol=1e-9)


def test_changed_tet_mesh_misses_the_cache(tmp_path, branch_files, branch_rig):
    """Moving an interior vertex of a precomputed tet mesh must give another rig, not the cached one."""
    tets = tmp_path / "branch.mesh"
    write_tet_mesh(tets, branch_rig.tet_vertices, branch_rig.tets)
    cache = tmp_path / "cache"
    first = sl.load_rig(branch_files["mesh"], branch_files["skeleton"], tets=tets, cache_dir=cache)
    TV = branch_rig.tet_vertices.copy()
    TV[len(branch_rig.vertices) + 20] += [0.3, 0.2, 0.1]  # an interior vertex, same connectivity
    write_tet_mesh(tets, TV, branch_rig.tets)
    second = sl.load_rig(branch_files["mesh"], branch_files["skeleton"], tets=tets, cache_dir=cache)
    assert second.info["from_cache"] is False
    assert not np.array_equal(second.tet_vertices, first.tet_vertices)


# ------------------------------------------------------------- joints on the skin
def _branch_with_tip(offset_fraction):
    """The branch figure with its head-tip joint put ``offset_fraction`` of the height above the top."""
    V, F, J, B = sl.demo_figure("branch")
    height = np.ptp(V[:, 1])
    J = J.copy()
    J[3] = [0.0, V[:, 1].max() + offset_fraction * height, 0.0]
    return V, F, J, B, height


def test_a_joint_just_outside_is_moved_inside_with_a_warning():
    import igl

    V, F, J, B, height = _branch_with_tip(0.01)
    rig = sl.prepare_rig(V, F, J, B, up="y")
    assert len(rig.info["warnings"]) == 1
    warning = rig.info["warnings"][0]
    assert warning.startswith("joint 4 lay 1.00 % of the model's height outside") and "bone 3" in warning
    depth = -igl.signed_distance(rig.joints[3:4], rig.vertices, rig.faces)[0][0]
    assert depth >= rig_mod.JOINT_INSIDE_MARGIN * height  # inside by the margin
    # moved along its bone, towards the joint it connects to
    along = (rig.joints[3] - J[1]) / np.linalg.norm(J[3] - J[1])
    np.testing.assert_allclose(along / np.linalg.norm(along), (J[3] - J[1]) / np.linalg.norm(J[3] - J[1]), atol=1e-12)
    np.testing.assert_array_equal(rig.joints[:3], J[:3])  # the others stay


def test_a_joint_far_outside_is_refused():
    V, F, J, B, _ = _branch_with_tip(0.10)
    with pytest.raises(InputError, match=r"joint 4 .* 10\.0 % of the model's height outside"):
        sl.prepare_rig(V, F, J, B, up="y")


def test_a_tip_whose_bone_enters_past_its_middle_moves_only_with_a_longer_reach():
    """A proxy's thinned fingertip: the bone's first half lies outside, so the default reach refuses the joint;
    ``reach`` 0.9 moves it on along the bone to the first point the margin deep; a bone entering in its first half
    gets the same point whatever the reach."""
    import trimesh

    from supportless.files.joints import pull_joints_inside

    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    V, F = np.asarray(box.vertices, np.float64), np.asarray(box.faces, np.int64)
    J = np.array([[0.0, 0.49, 0.0], [0.0, 0.52, 0.0]])  # the tip 2 % of the height over the top; the bone 0.03 long
    B = np.array([[0, 1]])
    with pytest.raises(InputError, match="does not enter it"):
        pull_joints_inside(V, F, J, B, "y")
    moved, warnings = pull_joints_inside(V, F, J, B, "y", reach=0.9)
    assert len(warnings) == 1 and warnings[0].startswith("joint 2 lay 2.00 %")
    np.testing.assert_array_equal(moved[0], J[0])
    assert moved[1][0] == 0.0 and moved[1][2] == 0.0
    depth = 0.5 - moved[1][1]
    assert rig_mod.JOINT_INSIDE_MARGIN <= depth < rig_mod.JOINT_INSIDE_MARGIN + 0.03 / 50  # the first such point
    assert (0.52 - moved[1][1]) / 0.03 > 0.5  # past the bone's middle
    V2, F2, J2, B2, _ = _branch_with_tip(0.01)
    np.testing.assert_array_equal(pull_joints_inside(V2, F2, J2, B2, "y", reach=0.9)[0],
                                  pull_joints_inside(V2, F2, J2, B2, "y")[0])


def test_moved_joints_and_their_warning_survive_the_cache(tmp_path):
    V, F, J, B, _ = _branch_with_tip(0.01)
    sl.write_mesh(tmp_path / "b.stl", V, F)
    sl.write_tgf(tmp_path / "b.tgf", J, B)
    first = sl.load_rig(tmp_path / "b.stl", cache_dir=tmp_path / "cache")
    second = sl.load_rig(tmp_path / "b.stl", cache_dir=tmp_path / "cache")
    assert second.info["from_cache"]
    assert second.info["warnings"] == first.info["warnings"] and len(first.info["warnings"]) == 1
    np.testing.assert_array_equal(second.joints, first.joints)


# ------------------------------------------------------------------ contact
def _tipped_branch():
    """The branch figure turned so only the arm's end rests on the plate (a chain lying on its hand)."""
    V, F, J, B = sl.demo_figure("branch")
    a = np.radians(-110.0)
    R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    V, J = V @ R.T, J @ R.T
    lift = V[:, 1].min()
    return V - [0.0, lift, 0.0], F, J - [0.0, lift, 0.0], B


def test_a_chain_resting_on_its_end_hangs_from_that_end():
    rig = sl.prepare_rig(*_tipped_branch(), up="y")
    np.testing.assert_array_equal(rig.contact_bones, [False, True, False])  # the arm's end is the contact
    np.testing.assert_array_equal(rig.anchored_bones, [False, True, False])
    assert rig.root_bone == 1
    # the arm carries the joint the three bones share: the stem and the head hang from it
    np.testing.assert_array_equal(rig.parents, [1, -1, 1])
    np.testing.assert_array_equal(rig.pivots, [1, 1, 1])
    # turning the stem moves it about the shared joint; the arm and its contact stay
    angles = np.zeros((3, 3))
    angles[0] = [0.0, 0.0, 0.3]
    V = rig.pose(angles)
    on_plate = rig.contact_vertices
    # contact vertices carry a trace of the stem's weight (bounded biharmonic weights are smooth): they move
    # by 4e-7 of the height here, measured
    np.testing.assert_allclose(V[on_plate], rig.vertices[on_plate], atol=1e-5 * np.ptp(rig.vertices))
    assert np.abs(V - rig.vertices).max() > 1.0


def test_default_search_moves_a_chain_resting_on_its_end():
    rig = sl.prepare_rig(*_tipped_branch(), up="y")
    fixed = sl.SearchSettings().fixed_bones(rig)
    np.testing.assert_array_equal(fixed, [False, True, False])
    result = sl.optimize(rig, particles=40, iterations=20, seed=0, orient="keep")  # the pose, not the turn
    assert np.abs(result.angles[~fixed]).max() > 0.1  # the free bones moved
    assert result.value < float(result.objective(rig.rest_angles()))


def test_a_bone_that_leaves_the_solid_keeps_only_its_samples_inside():
    """A bone from the arm's tip to inside the head crosses open air: its samples outside are dropped."""
    import igl

    V, F, J, B = sl.demo_figure("branch")
    J = np.vstack([J, [[1.0, 26.0, 0.0]]])
    B = np.vstack([B, [[2, 4]]])
    rig = sl.prepare_rig(V, F, J, B, up="y")
    inner = rig.tet_vertices[len(rig.vertices):]
    assert np.all(igl.winding_number(rig.vertices, rig.faces, inner) > 0.5)  # no tet vertex outside
    assert rig.weights[:, 3].max() > 0.99  # the bone still drives the skin near its inside ends


# --------------------------------------------------------------------------- #
# a dense surface: volume mesh, weights and search on a simplified proxy
# --------------------------------------------------------------------------- #
# the dense_branch fixture (rig, proxy target) is in conftest.py
def test_a_dense_surface_is_meshed_and_weighted_through_its_simplified_proxy(dense_branch):
    rig, target = dense_branch
    assert rig.coarse_faces is not None
    coarse = rig.coarse_rig()
    assert len(coarse.faces) <= target
    # the proxy is a closed surface of the same solid, its rows the first of the volume mesh
    sl.files.meshes.check_closed_surface(coarse.faces)
    assert abs(signed_volume(coarse.vertices, coarse.faces) / signed_volume(rig.vertices, rig.faces) - 1) < 0.05
    np.testing.assert_array_equal(coarse.tet_vertices[: len(coarse.vertices)], coarse.vertices)
    # full-resolution weights: a partition of unity taken from the proxy's surface
    np.testing.assert_allclose(rig.weights.sum(1), 1.0, atol=1e-9)
    assert rig.weights.shape == (len(rig.vertices), rig.bone_count)
    # posing the full surface and the proxy moves them together
    angles = np.zeros((rig.bone_count, 3))
    angles[-1] = [0.0, 0.0, 0.6]
    full, proxy = rig.pose(angles), coarse.pose(angles)
    d = np.sqrt(igl.point_mesh_squared_distance(proxy, full, rig.faces)[0])
    assert d.max() < 0.05 * np.ptp(rig.vertices, axis=0).max()


def test_the_proxy_survives_the_cache(tmp_path, dense_branch):
    rig, _ = dense_branch
    file = tmp_path / "rig.npz"
    from supportless.rig.cache import read_entry, write_entry

    write_entry(file, rig)
    back = rig_mod.Rig(**read_entry(file), name="dense")
    np.testing.assert_array_equal(back.coarse_faces, rig.coarse_faces)


@pytest.mark.slow
def test_the_search_runs_on_the_proxy_and_answers_at_full_resolution(dense_branch):
    rig, _ = dense_branch
    result = sl.optimize(rig, particles=12, iterations=4, orient="keep", polish=2)  # a short polish
    assert result.full_surface.proxy_faces == len(rig.coarse_rig().faces)
    assert result.vertices.shape == rig.vertices.shape
    # the value and terms are those of the full surface at the found pose
    objective = result.objective
    assert objective.rig is rig
    np.testing.assert_allclose(result.value, float(objective(result.angles)), rtol=1e-12)
    np.testing.assert_allclose(result.vertices, sl.base.geometry.place_on_plate(rig.pose(result.angles), rig.up))


#: What the proxy's terms may differ from the full surface's, as benchmarks/RESULTS.md states it (measured on
#: the 68-bone character and the 111k-triangle bunny, 30 random poses within 20° of rest: 0.034 and 0.054 of the
#: overhang term, 1.0e-3 and 0.8e-3 of the volume): the overhang term (support over the rest pose's) and the
#: self-intersection term (a share of the volume) within these, the distortion term the same (one volume mesh).
PROXY_BOUND = {"overhang": 0.06, "intersection": 2e-3}


def test_the_proxy_and_the_full_surface_agree_within_the_stated_bound(dense_branch):
    rig, _ = dense_branch
    coarse = rig.coarse_rig()
    settings = sl.SearchSettings()
    A = np.zeros((6, rig.bone_count, 3))
    A[1:, -1, 2] = [0.3, 0.6, -0.4, 0.9, -1.0]  # the arm swung up and down, down into the post at the end
    A[3:, -1, 0] = [0.5, -0.3, 0.2]
    full = settings.objective(rig)
    proxy = settings.objective(coarse, full.arap_data, full.volume).terms(A)  # as the search measures the proxy
    full = full.terms(A)
    np.testing.assert_array_less(np.abs(proxy["overhang"] - full["overhang"]), PROXY_BOUND["overhang"])
    assert np.ptp(full["overhang"]) > 5 * PROXY_BOUND["overhang"]  # poses that differ more than the bound
    np.testing.assert_array_less(np.abs(proxy["intersection"] - full["intersection"]), PROXY_BOUND["intersection"])
    assert full["intersection"].max() > 0  # the last pose does overlap: the check compares something
    np.testing.assert_allclose(proxy["arap"], full["arap"], rtol=1e-9, atol=1e-15)


def test_a_proxy_pose_whose_full_surface_touches_itself_gives_way_to_the_next_clear_one(dense_branch, monkeypatch):
    rig, _ = dense_branch
    real = sl.Rig.self_intersects
    seen = []

    def full_surface(touching):  # the exact check: on the full surface, True for the first ``touching`` calls
        def check(self, angles):
            if self is not rig:
                return real(self, angles)
            seen.append(self.pose(angles))
            return len(seen) <= touching
        return check

    monkeypatch.setattr(sl.Rig, "self_intersects", full_surface(0))  # the full-surface check of the proxy's answers
    monkeypatch.setattr(answer_mod, "as_written", lambda rig, found: found)  # the real last gate would see the fake
    clear = sl.optimize(rig, particles=12, iterations=4, orient="keep", polish=0, contact=False)  # before any polish
    assert clear.full_surface.full_exact_calls == 1
    np.testing.assert_allclose(seen[0], rig.pose(clear.angles))  # the proxy's answer, checked on the full surface
    seen.clear()
    monkeypatch.setattr(sl.Rig, "self_intersects", full_surface(1))
    result = sl.optimize(rig, particles=12, iterations=4, orient="keep", polish=0, contact=False)
    assert result.full_surface.full_exact_calls == 2
    assert not np.allclose(result.angles, clear.angles)  # the next candidate, measured on the full surface
    np.testing.assert_allclose(seen[1], rig.pose(result.angles))
    np.testing.assert_allclose(result.value, float(result.objective(result.angles)), rtol=1e-12)


def test_the_proxys_candidates_are_rescored_on_the_full_surface(dense_branch):
    rig, _ = dense_branch
    result = sl.optimize(rig, particles=12, iterations=4, orient="keep", exact_intersections=False, polish=0)
    c = result.candidates  # the proxy's good poses, with the proxy's values
    full = np.asarray(result.objective(c["angles"], c["rotations"]))
    assert result.full_surface.full_rescored >= 2
    assert result.value == pytest.approx(full.min(), rel=1e-12)  # the best of them on the full surface
    assert result.value <= float(result.objective(c["angles"][0])) + 1e-12  # never worse than the proxy's best


def test_after_the_proxy_the_polish_runs_on_the_full_surface(dense_branch, monkeypatch):
    rig, _ = dense_branch
    chosen = sl.optimize(rig, particles=12, iterations=4, orient="keep", symmetric=False, polish=0)
    seen = []
    result = sl.optimize(rig, particles=12, iterations=4, orient="keep", symmetric=False, polish=3,
                         callback=lambda it, info: seen.append((it, info["iterations"])))
    assert result.full_surface.full_polish_evaluations == 1 + 3 * search_mod.POLISH_SAMPLES
    assert result.value <= chosen.value  # it starts at the chosen pose and keeps it unless it finds better
    np.testing.assert_allclose(result.value, float(result.objective(result.angles)), rtol=1e-12)  # full surface
    assert result.objective.rig is rig and not result.objective.forbidden(result.angles)
    # the progress counts the proxy's 4 iterations and the polish's 3 as one search of 7
    assert seen == [(it, 7) for it in range(1, 8)]
    assert len(result.history) == len(chosen.history) + 3
    # by default the polish's generations follow the surface's size (about the same cost at any density)
    monkeypatch.setattr(answer_mod, "PROXY_POLISH_BUDGET", 2 * len(rig.faces))
    default = sl.optimize(rig, particles=12, iterations=4, orient="keep", symmetric=False)
    assert default.full_surface.full_polish_evaluations == 1 + 2 * search_mod.POLISH_SAMPLES


@pytest.mark.parametrize("sizes", [5e4, 1e5])
def test_a_model_far_from_the_origin_poses_as_it_does_at_the_origin(sizes):
    """Coordinates 1e5 times the model's size: moved to the origin first, said, and searched as at the origin."""
    V, F, J, B = sl.demo_figure("branch")[:4]
    size = np.ptp(V, axis=0).max()
    offset = np.array([1.0, -0.5, 0.3]) * sizes * size
    near = sl.prepare_rig(V, F, J, B, up="y")
    far = sl.prepare_rig(V + offset, F, J + offset, B, up="y")
    assert "moved_by" not in near.info
    np.testing.assert_allclose(far.info["moved_by"], -(V + offset).min(0) / 2 - (V + offset).max(0) / 2)
    assert any("times its size from the origin" in w for w in far.info["warnings"])
    assert far.tet_weights.shape[1] == near.tet_weights.shape[1]  # TetGen may place a point more or less
    a = sl.optimize(near, particles=20, iterations=6, seed=0, orient="keep", symmetric=False)
    b = sl.optimize(far, particles=20, iterations=6, seed=0, orient="keep", symmetric=False)
    np.testing.assert_allclose(b.angles, a.angles, atol=1e-6)
    # the input's far coordinates kept only ~1e-11 of the model's size: TetGen meshes the inside a little
    # differently, so the weights, and a posed surface's measures, differ by a few %; the rest pose's are equal
    assert b.value == pytest.approx(a.value, rel=0.05)
    rest = np.zeros((1, len(B), 3))
    near_terms, far_terms = a.objective.terms(rest), b.objective.terms(rest)
    for key in ("overhang", "intersection"):
        assert float(far_terms[key][0]) == pytest.approx(float(near_terms[key][0]), rel=1e-6, abs=1e-12)


def test_an_open_surface_is_made_a_closed_solid(bad_inputs, tmp_path):
    """A surface with a hole: closed into the solid to print, said in one note. Two boxes that share only an
    edge stay an error of one line (their union is not a solid TetGen can fill)."""
    from supportless.base.geometry import signed_volume
    from supportless.files.meshes import check_closed_surface

    model, kwargs, _, fragments = bad_inputs["not closed"]
    rig = sl.load_rig(model, up="y", cache_dir=tmp_path, **kwargs)
    check_closed_surface(rig.faces)
    note = [w for w in rig.info["warnings"] if w.startswith("the surface was not closed")]
    assert len(note) == 1 and fragments[0] in note[0] and "made a closed solid" in note[0]
    assert signed_volume(rig.vertices, rig.faces) > 0
    model, kwargs, _, _ = bad_inputs["not manifold"]
    with pytest.raises(sl.InputError):
        sl.load_rig(model, up="y", cache_dir=tmp_path, **kwargs)


# --------------------------------------------------------------------------- #
# a sculpt: measured on its quickly reduced surface, answered at full resolution
# --------------------------------------------------------------------------- #
@pytest.fixture(scope="module")
def sculpt_branch():
    """The branch figure subdivided twice, prepared and searched as a sculpt (the thresholds of the proxy and of
    the measuring surface lowered to its size, for the module)."""
    from supportless.files import simplify

    V, F, J, B = sl.demo_figure("branch")
    V2, F2 = igl.upsample(V, F.astype(np.int64), 2)
    mp = pytest.MonkeyPatch()
    mp.setattr(rig_mod, "PROXY_FACES", len(F2) - 1)
    mp.setattr(rig_mod, "PROXY_TARGET", len(F2) // 8)
    mp.setattr(simplify, "FAST_FIRST_FACES", len(F2) - 1)
    mp.setattr(simplify, "FAST_FIRST_TARGET", len(F2) // 2)
    mp.setattr(simplify, "PROXY_CELLS", 60)  # the proxy's grid as coarse as this small figure allows
    try:
        yield sl.prepare_rig(V2, F2, J, B, "y", name="sculpt")
    finally:
        mp.undo()


def test_a_sculpt_is_measured_on_its_quickly_reduced_surface(sculpt_branch, dense_branch):
    rig = sculpt_branch
    measure = rig.measure_rig()
    assert measure is rig.measure_rig()  # made once
    assert len(measure.faces) <= len(rig.faces) // 2
    sl.files.meshes.check_closed_surface(measure.faces)
    assert len(sl.copyleft.cgal.intersecting_faces(measure.vertices, measure.faces)) == 0
    np.testing.assert_array_equal(measure.joints, rig.joints)
    # the same proxy and volume mesh, so the same search; weights a partition of unity
    coarse, mine = rig.coarse_rig(), measure.coarse_rig()
    np.testing.assert_array_equal(mine.vertices, coarse.vertices)
    np.testing.assert_array_equal(mine.faces, coarse.faces)
    np.testing.assert_array_equal(mine.tet_weights, coarse.tet_weights)
    np.testing.assert_allclose(measure.weights.sum(1), 1.0, atol=1e-9)
    # posed, it stays on the posed full surface
    angles = np.zeros((rig.bone_count, 3))
    angles[-1] = [0.2, 0.0, 0.7]
    d = np.sqrt(igl.point_mesh_squared_distance(measure.pose(angles), rig.pose(angles), rig.faces)[0])
    assert d.max() < 0.01 * np.ptp(rig.vertices, axis=0).max()
    from supportless.files import simplify

    dense = dataclasses.replace(dense_branch[0])
    with pytest.MonkeyPatch.context() as mp:  # as many triangles as the threshold: not a sculpt
        mp.setattr(simplify, "FAST_FIRST_FACES", len(dense.faces))
        assert dense.measure_rig() is None


@pytest.mark.slow
def test_a_sculpt_is_searched_on_the_reduced_surface_and_answered_at_full_resolution(sculpt_branch):
    rig = sculpt_branch
    result = sl.optimize(rig, particles=12, iterations=4, polish=4)  # a short polish: its length is not the subject
    assert result.measured_faces == len(rig.measure_rig().faces)
    assert result.objective.rig is rig.measure_rig()
    np.testing.assert_allclose(result.vertices, sl.base.geometry.place_on_plate(rig.pose(result.angles), rig.up))
    assert result.print_vertices.shape == rig.vertices.shape
    # the answer as written was checked exactly at full resolution
    pairs = len(sl.copyleft.cgal.intersecting_faces(result.print_vertices, rig.faces))
    assert result.written.written_pairs == pairs
    assert pairs == 0 or result.written.contacts  # crossings only where jointed parts press together
    # the answers weighed carry the reduced surface; the slicer's copies take its faces
    if result.choice is not None:
        answer = result.choice.candidates[0].result
        assert sl.search.result.faces_of(rig, answer) is rig.measure_rig().faces
    assert sl.search.result.faces_of(rig, result) is rig.faces
    # the report: measures on the reduced surface, exact counts of the full one as written
    from supportless.report.report import build_report

    report = build_report(rig, result)
    assert report["faces"] == len(rig.faces) and report["measured_faces"] == len(rig.measure_rig().faces)
    assert report["after"]["intersecting_face_pairs"] == result.written.written_pairs
    assert report["before"]["intersecting_face_pairs"] == result.written.rest_pairs == 0
    # its predicted support, taken on the reduced surface, is the full surface's within the model's noise
    from supportless.report.report import predicted_slicer

    full = predicted_slicer(rig, result, report["predicted_slicer"]["height_mm"])
    for key in ("before_mm", "after_mm"):
        assert report["predicted_slicer"][key] == pytest.approx(full[key], rel=0.05, abs=1.0)
    # and so is its strength (the weakest sections as the choice weighed them, not a full-resolution analysis)
    from supportless.files.printframe import rig_print_frame
    from supportless.report.report import strength_summary

    whole = strength_summary(rig, result, rig_print_frame(rig))
    for key in ("rest", "answer"):
        assert report["strength"][key]["safety_factor"] == pytest.approx(whole[key]["safety_factor"], rel=0.1)
