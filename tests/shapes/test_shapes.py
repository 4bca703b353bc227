"""Built-in demo figures: closed, clean, rigged, resting on the plate, deterministic."""

import inspect

import igl
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

import supportless as sl
from supportless import shapes
from supportless.base.geometry import signed_volume
from supportless.base.kinematics import bone_parents, topological_order
from supportless.copyleft.cgal import intersecting_face_pairs
from supportless.files.meshes import edge_counts
from supportless.shapes import DEMO_FIGURES, demo_figure

UP3 = np.array([0.0, 1.0, 0.0])
FIG3 = [n for n in DEMO_FIGURES if n != "woody2d"]
#: Figures whose builder takes a seed that varies the proportions.
SEEDED = [n for n in FIG3 if "seed" in inspect.signature(shapes._BUILDERS[n]).parameters]

#: The bones nearest to each flat patch of the surface on the plate, by figure:
#: what a person expects to touch it.
PLATE_BONES = {
    "tpose": [11, 14],  # the shins (feet)
    "apose": [11, 14],
    "staff": [11, 14],
    "branch": [0],  # the post's foot
    "quadruped": [3, 6, 9, 12],  # the four lower legs (paws)
    "dragon": [3, 6, 9, 12],
    "bird": [6, 13],  # the two lower legs (feet)
    "lying": [0],  # the spine (the back)
    "seated": [0, 12, 15],  # the block and the shins (feet)
    "arm": [2, 3],  # the palm and the fingers (the hand), with the thumb
    "tree": [0],  # the trunk
    "hand": [0],  # the forearm stub
    "tentacle": [0],  # the base
}

#: Handles of each surface: the staff and the arms holding it make a loop.
GENUS = {"staff": 1}


def _is_forest(n_joints, bones):
    """Each joint is the tip of at most one bone and there are no cycles."""
    tips = bones[:, 1]
    if len(np.unique(tips)) != len(tips):
        return False
    parent = {int(t): int(r) for r, t in bones}
    for j in range(n_joints):
        seen = set()
        while j in parent:
            if j in seen:
                return False
            seen.add(j)
            j = parent[j]
    return True


def _normals(V, F):
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    return N / np.linalg.norm(N, axis=1, keepdims=True)


def _bone_points(J, B, n=21):
    """(m * n, 3) points evenly along every bone, ends included."""
    t = np.linspace(0.0, 1.0, n)[None, :, None]
    return (J[B[:, 0]][:, None] * (1.0 - t) + J[B[:, 1]][:, None] * t).reshape(-1, J.shape[1])


def _segment_distance(p, a, b):
    ab = b - a
    t = np.clip((p - a) @ ab / (ab @ ab), 0.0, 1.0)
    return float(np.linalg.norm(p - (a + t * ab)))


def _check_surface(V, F, J, B, genus=0, clearance=0.5):
    """The geometric promises of a 3D figure (``clearance``: the least distance of a joint to the skin)."""
    _, counts = edge_counts(F)
    assert np.all(counts == 2), "every edge shared by exactly two faces"
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed), "consistent winding"
    assert signed_volume(V, F) > 0, "outward orientation"
    assert len(np.unique(V, axis=0)) == len(V), "no two vertices at one place"
    n_edges = len(directed) // 2
    assert len(V) - n_edges + len(F) == 2 - 2 * genus, "one surface of the expected genus"
    A = sp.coo_matrix((np.ones(len(directed)), (directed[:, 0], directed[:, 1])), shape=(len(V), len(V)))
    assert connected_components(A, directed=False)[0] == 1, "one piece"
    assert np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).min() > 1e-8
    assert intersecting_face_pairs(V, F) == 0, "no self-intersections"
    # a sum of solid angles over a closed surface: 1 inside up to rounding (4e-16 measured)
    assert np.all(np.abs(igl.winding_number(V, F, J) - 1.0) < 1e-9), "every joint inside"
    assert np.sqrt(igl.point_mesh_squared_distance(J, V, F)[0]).min() > clearance, "joints clear of the skin"
    assert np.all(np.abs(igl.winding_number(V, F, _bone_points(J, B)) - 1.0) < 1e-9), "bones inside"
    assert V[:, 1].min() == 0.0, "rests on y = 0"


# --- every figure -------------------------------------------------------------


def test_names():
    assert set(DEMO_FIGURES) >= {"tpose", "branch", "woody2d", "apose", "quadruped", "lying", "seated", "arm",
                                 "tree", "hand", "bird", "tentacle", "dragon", "staff"}
    assert set(shapes._BUILDERS) == set(DEMO_FIGURES)
    assert set(PLATE_BONES) == set(FIG3)
    with pytest.raises(KeyError):
        demo_figure("nope")


@pytest.mark.parametrize("name", DEMO_FIGURES)
def test_arrays_and_skeleton(name):
    V, F, J, B = demo_figure(name)
    d = 2 if name == "woody2d" else 3
    assert V.dtype == np.float64 and V.ndim == 2 and V.shape[1] == d
    assert F.dtype == np.int64 and F.shape[1] == 3
    assert J.dtype == np.float64 and J.shape[1] == d
    assert B.dtype == np.int64 and B.shape[1] == 2
    assert F.min() >= 0 and F.max() < len(V)
    assert len(np.unique(F)) == len(V)  # no unreferenced vertices
    assert B.min() >= 0 and B.max() < len(J)
    assert np.all(B[:, 0] != B[:, 1])
    assert set(np.unique(B).tolist()) == set(range(len(J)))  # every joint on a bone
    # a tree or forest: each joint the tip of at most one bone, no cycles
    assert _is_forest(len(J), B)
    topological_order(bone_parents(B))  # raises on a cycle
    assert V[:, 1].min() == 0.0 and np.all(J[:, 1] > 0)
    # small: quick to prepare and to search
    assert len(B) <= 25
    assert len(F) <= 6000


@pytest.mark.parametrize("name", FIG3)
def test_closed_clean_surface_with_the_skeleton_inside(name):
    _check_surface(*demo_figure(name), genus=GENUS.get(name, 0))


@pytest.mark.parametrize("name", FIG3)
def test_rests_on_the_plate_with_the_expected_parts(name):
    V, F, J, B = demo_figure(name)
    flat = F[np.all(V[F][:, :, 1] == 0.0, axis=1)]
    A = sp.coo_matrix((np.ones(flat.size), (flat.ravel(), np.roll(flat, 1, axis=1).ravel())), shape=(len(V),) * 2)
    labels = connected_components(A, directed=False)[1]
    nearest = []
    for patch in np.unique(labels[np.unique(flat)]):
        centre = V[labels == patch].mean(axis=0)
        nearest.append(int(np.argmin([_segment_distance(centre, J[a], J[b]) for a, b in B])))
    assert sorted(nearest) == PLATE_BONES[name]


@pytest.mark.parametrize("name", FIG3)
def test_real_overhangs_above_the_plate(name):
    """Downward faces well above the plate (arms, wings, tails, heads...) that posing could turn."""
    V, F, _, _ = demo_figure(name)
    N, c = _normals(V, F), V[F].mean(axis=1)
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    risky = (N @ UP3 < -np.cos(np.radians(45.0))) & (c[:, 1] > 0.15 * V[:, 1].max())
    assert area[risky].sum() > 0.02 * area.sum()


@pytest.mark.parametrize("name", DEMO_FIGURES)
def test_figures_are_deterministic(name):
    # two real builds (the builders, not demo_figure's cache), and the cached copy
    first, second = shapes._BUILDERS[name](), shapes._BUILDERS[name]()
    cached = sl.demo_figure(name)
    for x, y, z in zip(first, second, cached):
        assert x is not y
        np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(x, z)


@pytest.mark.parametrize("name", SEEDED)
def test_a_seed_varies_the_proportions_and_keeps_the_promises(name):
    V, F, J, B = shapes._BUILDERS[name](seed=1)
    V0, _, J0, B0 = demo_figure(name)
    np.testing.assert_array_equal(B, B0)  # the same skeleton ...
    assert not np.array_equal(J, J0)  # ... in other proportions
    _check_surface(V, F, J, B, genus=GENUS.get(name, 0))
    assert len(F) <= 6500
    np.testing.assert_array_equal(shapes._BUILDERS[name](seed=None)[0], V0)


def test_returns_fresh_copies():
    V, F, J, B = demo_figure("branch")
    V[:] = 0
    V2, _, _, _ = demo_figure("branch")
    assert np.ptp(V2[:, 1]) > 1


def test_at_least_thirteen_3d_figures():
    assert len(FIG3) >= 13
    for name in FIG3:
        assert demo_figure(name)[0].shape[1] == 3


# --- particular figures -------------------------------------------------------


def test_face_budgets():
    assert 2000 <= len(demo_figure("tpose")[1]) <= 4000
    assert len(demo_figure("branch")[1]) <= 1500
    assert len(demo_figure("woody2d")[1]) <= 4000


def _roots(B):
    tips = set(B[:, 1].tolist())
    return set(int(r) for r in B[:, 0] if int(r) not in tips)


def test_tpose_skeleton_and_overhang():
    V, F, J, B = demo_figure("tpose")
    assert 12 <= len(B) <= 15
    roots = _roots(B)  # one tree hanging off the hips
    assert len(roots) == 1
    np.testing.assert_array_equal(J[roots.pop()], [0.0, 30.0, 0.0])
    # arms: the horizontal chains of bones at shoulder height
    d = J[B[:, 1]] - J[B[:, 0]]
    horizontal = np.abs(d[:, 1]) < 1e-9
    assert horizontal.sum() >= 4
    assert (J[B[horizontal, 1], 0] > 0).any() and (J[B[horizontal, 1], 0] < 0).any()
    assert J[:, 1].min() < 5 and J[:, 1].max() > 50
    assert np.sum(np.abs(V[:, 1]) < 1e-9) >= 10  # feet flat on the plate
    # the arms' undersides create overhangs well above the ground
    c = V[F].mean(axis=1)
    risky = (_normals(V, F) @ UP3 < -0.7) & (c[:, 1] > 35)
    assert risky.sum() >= 30
    assert np.abs(c[risky, 0]).max() > 15  # out along the arms


def test_every_new_skeleton_is_one_tree():
    for name in SEEDED:
        assert len(_roots(demo_figure(name)[3])) == 1, name


def test_apose_arms_slope_down_and_staff_is_horizontal():
    _, _, J, B = demo_figure("apose")
    d = J[B[:, 1]] - J[B[:, 0]]
    slope = np.degrees(np.arctan2(-d[:, 1], np.linalg.norm(d[:, [0, 2]], axis=1)))
    assert np.sum(np.abs(slope - 35.0) < 1.0) == 4  # upper arms and forearms
    _, _, J, B = demo_figure("staff")
    d = J[B[:, 1]] - J[B[:, 0]]
    staff = (np.abs(d[:, 1]) < 1e-9) & (np.abs(d[:, 2]) < 1e-9) & (np.abs(d[:, 0]) > 20)
    assert staff.sum() == 2 and len(set(B[staff, 0].tolist())) == 1  # two halves from one grip


def test_arm_is_a_chain_of_four_bones_from_the_hand_on_the_plate_to_a_raised_shoulder():
    _, _, J, B = demo_figure("arm")
    assert len(B) == 4
    assert all(B[i, 1] == B[i + 1, 0] for i in range(3))
    assert J[B[0, 0], 1] > 20 and J[B[-1, 1], 1] < 2.5  # shoulder up, fingertips down


def test_tentacle_makes_an_s_curve():
    _, _, J, B = demo_figure("tentacle")
    d = J[B[:, 1]] - J[B[:, 0]]
    lean = np.sign(d[np.abs(d[:, 0]) > 1.0, 0])
    assert (np.diff(lean) != 0).sum() >= 1  # leans one way, then the other
    assert np.all(np.diff(J[:, 1])[:5] > 0)  # rising from the plate


def test_seated_block_is_the_root_and_rests_on_the_plate():
    V, F, J, B = demo_figure("seated")
    assert _roots(B) == {int(B[0, 0])}
    assert J[B[0, 0], 1] < 3.0 and J[B[0, 1], 1] > 12.0  # the block's bone runs up through it


def test_branch_cantilever():
    V, F, J, B = demo_figure("branch")
    assert 2 <= len(B) <= 3
    d = J[B[:, 1]] - J[B[:, 0]]
    assert np.any((np.abs(d[:, 1]) < 1e-9) & (np.abs(d[:, 0]) > 5))
    c = V[F].mean(axis=1)
    assert np.sum((_normals(V, F) @ UP3 < -0.7) & (c[:, 1] > 10)) > 5


# --- woody2d ------------------------------------------------------------------


def _signed_areas(V, F):
    e1 = V[F[:, 1]] - V[F[:, 0]]
    e2 = V[F[:, 2]] - V[F[:, 0]]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def _boundary_edges(F):
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return E[counts[inv.ravel()] == 1], counts


def test_woody2d_mesh():
    V, F, J, B = demo_figure("woody2d")
    a = _signed_areas(V, F)
    assert np.all(a > 1e-6)  # all CCW, no slivers of zero area
    bnd, counts = _boundary_edges(F)
    assert counts.max() <= 2  # manifold
    loops = igl.boundary_loop_all(F)
    assert len(loops) == 1  # one closed outline, no holes
    assert len(loops[0]) == len(bnd)
    # the oriented boundary edges form one CCW cycle
    nxt = dict(zip(bnd[:, 0].tolist(), bnd[:, 1].tolist()))
    assert len(nxt) == len(bnd)
    start = int(bnd[0, 0])
    k, steps = nxt[start], 1
    while k != start:
        k, steps = nxt[k], steps + 1
    assert steps == len(bnd)
    loop = V[loops[0]]
    area = 0.5 * np.sum(loop[:, 0] * np.roll(loop[:, 1], -1) - np.roll(loop[:, 0], -1) * loop[:, 1])
    assert abs(area) == pytest.approx(a.sum(), rel=1e-9)
    # Euler characteristic of a disk
    E = len(np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0))
    assert len(V) - E + len(F) == 1
    # arms held out horizontally
    d = J[B[:, 1]] - J[B[:, 0]]
    arm = (np.abs(d[:, 1]) < 1e-9) & (np.abs(d[:, 0]) > 5)
    assert arm.sum() >= 2


def test_woody2d_vertices_on_joints_and_bones():
    V, F, J, B = demo_figure("woody2d")
    # a vertex exactly at each joint, not on the boundary
    bverts = set(np.unique(_boundary_edges(F)[0]).tolist())
    for p in J:
        dist = np.linalg.norm(V - p, axis=1)
        k = int(np.argmin(dist))
        assert dist[k] == 0.0
        assert k not in bverts
    # at least 5 interior samples along every bone
    for a, b in B:
        pa, pb = J[a], J[b]
        t = (V - pa) @ (pb - pa) / ((pb - pa) @ (pb - pa))
        off = np.linalg.norm(V - (pa + t[:, None] * (pb - pa)), axis=1)
        on = (off < 1e-9) & (t > 1e-9) & (t < 1 - 1e-9)
        assert on.sum() >= 5
    # usable for bounded biharmonic weights (libigl's check runs in 3D)
    V3 = np.c_[V, np.zeros(len(V))]
    J3 = np.c_[J, np.zeros(len(J))]
    b, bc = igl.boundary_conditions(V3, F, J3, np.zeros(0, dtype=np.int64), B)
    assert bc.shape[1] == len(B)
    assert len(b) >= len(J) + 5 * len(B)


# --- the big character of the speed benchmark ------------------------------------------------------------------


def test_the_benchmark_character_is_a_big_clean_rig():
    """``supportless bench --targets``' character: a game-sized rig (60+ bones) on a surface dense enough for the proxy."""
    from supportless.rig.rig import PROXY_FACES
    from supportless.shapes.character import character

    V, F, J, B = character()
    assert len(B) == 68 and len(F) > PROXY_FACES
    assert _is_forest(len(J), B)
    assert set(np.unique(B).tolist()) == set(range(len(J)))
    _check_surface(V, F, J, B, clearance=0.05)  # fingertip joints sit 0.08 inside thin fingertips
    # fingers are chains of four bones from the palm, five per hand
    palms = [i for i in range(len(J)) if np.sum(B[:, 0] == i) == 5]
    assert len(palms) == 2
