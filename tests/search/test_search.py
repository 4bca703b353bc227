"""Particle swarm and pose search."""

import numpy as np
import pytest

import supportless as sl
from supportless.rig.contact import ContactRules
from supportless.search.optimizer import POLISH_SAMPLES, particle_swarm
from supportless.search.settings import PSO_PRESETS, SearchSettings, resolve_fixed_bones


def sphere(X):
    return np.sum((X - 0.3) ** 2, axis=1)


def test_swarm_finds_minimum_of_a_quadratic():
    res = particle_swarm(sphere, -np.ones(4), np.ones(4), particles=40, iterations=80,
                         rng=np.random.default_rng(1))
    assert res.value < 1e-6
    np.testing.assert_allclose(res.x, 0.3, atol=1e-3)
    assert res.evaluations == 40 * 81


def test_swarm_one_batched_call_per_iteration():
    calls = []

    def f(X):
        calls.append(X.shape)
        return sphere(X)

    particle_swarm(f, -np.ones(3), np.ones(3), particles=17, iterations=5, rng=np.random.default_rng(0))
    assert calls == [(17, 3)] * 6


def test_swarm_respects_bounds_and_history_is_monotone():
    seen = []

    def f(X):
        seen.append(X.copy())
        return -X.sum(1)  # pushes to the upper bound

    lo, hi = np.array([-1.0, 0.0]), np.array([0.5, 2.0])
    res = particle_swarm(f, lo, hi, particles=10, iterations=20, rng=np.random.default_rng(0))
    allX = np.concatenate(seen)
    assert np.all(allX >= lo) and np.all(allX <= hi)
    assert np.all(np.diff(res.history) <= 0)
    np.testing.assert_allclose(res.x, hi, atol=1e-6)


def test_swarm_same_seed_same_result_and_different_seed_differs():
    kw = dict(particles=12, iterations=10)
    a = particle_swarm(sphere, -np.ones(3), np.ones(3), rng=np.random.default_rng(5), **kw)
    b = particle_swarm(sphere, -np.ones(3), np.ones(3), rng=np.random.default_rng(5), **kw)
    c = particle_swarm(sphere, -np.ones(3), np.ones(3), rng=np.random.default_rng(6), **kw)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.history, b.history)
    assert not np.array_equal(a.x, c.x)


def test_swarm_initial_particle_is_evaluated():
    # the minimum sits exactly at the given initial particle: found at iteration 0
    f = lambda X: np.sum(X ** 2, axis=1)  # noqa: E731
    res = particle_swarm(f, -np.ones(5), np.ones(5), particles=3, iterations=0, initial=np.zeros((1, 5)),
                         rng=np.random.default_rng(0))
    assert res.value == 0.0


def test_swarm_callback_stops_and_ctrl_c_keeps_best():
    res = particle_swarm(sphere, -np.ones(2), np.ones(2), particles=5, iterations=50,
                         callback=lambda it, x, v: it < 3)
    assert res.interrupted and len(res.history) == 4

    count = {"n": 0}

    def f(X):
        count["n"] += 1
        if count["n"] == 4:
            raise KeyboardInterrupt
        return sphere(X)

    res = particle_swarm(f, -np.ones(2), np.ones(2), particles=5, iterations=50)
    assert res.interrupted and np.isfinite(res.value) and len(res.history) == 3


def test_libigl_preset_converges_where_inertia_alone_does_not():
    kw = dict(particles=30, iterations=200, rng=np.random.default_rng(0))
    res = particle_swarm(sphere, -np.ones(4), np.ones(4), **kw, **PSO_PRESETS["libigl"])
    assert res.value < 1e-3
    drift = particle_swarm(sphere, -np.ones(4), np.ones(4), particles=30, iterations=200,
                           rng=np.random.default_rng(0), inertia=0.98, cognitive=0.0, social=0.0)
    assert drift.value > 1e-2  # the cognitive and social terms are what converge


def test_optimize_never_worse_than_rest_and_reproducible(branch_rig):
    rig = branch_rig
    a = sl.optimize(rig, particles=12, iterations=6, seed=3)
    b = sl.optimize(rig, SearchSettings(particles=12, iterations=6, seed=3))
    np.testing.assert_array_equal(a.angles, b.angles)
    assert a.settings == b.settings
    obj = SearchSettings().objective(rig)  # what the search minimises
    assert obj.overhang_angle == SearchSettings().search_overhang_angle
    rest = float(obj(rig.rest_angles()))
    assert a.value <= rest + 1e-12
    assert float(obj(a.angles, a.rotation)) == pytest.approx(a.value, rel=1e-12)
    # fixed bones keep zero angles; the output sits on the plate
    assert np.all(a.angles[a.fixed] == 0)
    assert np.isclose((a.vertices @ rig.up).min(), 0.0, atol=1e-12)
    # orient="free": the pose-only phase, then pose and turn (6 iterations each), the best value never rising
    assert len(a.history) == 13 and all(len(v) == 12 for v in a.term_history.values())
    assert np.all(np.diff(a.history) <= 0)
    # the best pose's terms are measured only when the best changed
    changed = 1 + np.count_nonzero(np.diff(a.history[1:7])) + 1 + np.count_nonzero(np.diff(a.history[7:]))
    assert 2 <= a.stats.progress.calls <= changed
    kept = sl.optimize(rig, particles=12, iterations=6, seed=3, orient="keep")
    assert len(kept.history) == 7 and 1 <= kept.stats.progress.calls <= 6
    assert a.value <= kept.value  # the turning phase starts from the pose-only phase's best


def test_optimize_reduces_support_of_the_cantilever(branch_rig):
    res = sl.optimize(branch_rig, particles=30, iterations=20, seed=0)
    assert res.terms["overhang"] < 0.8  # at least 20 % less support (search estimate) than at rest
    angle = res.settings.overhang_angle
    rest = sl.overhang_energy(branch_rig.vertices, branch_rig.faces, "y", angle)
    assert sl.overhang_energy(res.print_vertices, branch_rig.faces, branch_rig.up, angle) < 0.8 * rest
    posed = sl.optimize(branch_rig, particles=30, iterations=20, seed=0, orient="keep")
    assert posed.terms["overhang"] < 0.8 and np.array_equal(posed.print_vertices, posed.vertices)
    assert sl.overhang_energy(posed.vertices, branch_rig.faces, branch_rig.up, angle) < 0.8 * rest


def test_exact_intersection_gate_rejects_intersecting_poses(branch_rig):
    """With the ray-grid penalty off, the search would bend the arm into the body; the exact gate stops it."""
    from supportless.copyleft.cgal import intersecting_face_pairs

    rig = branch_rig
    settings = SearchSettings(particles=24, iterations=10, seed=0, w_intersect=0.0,
                              w_arap=0.0, w_prior=0.0, joint_limit=170.0, keep_standing=False, free=("all",),
                              orient="keep", contact=False)
    gated = sl.optimize(rig, settings)
    assert gated.stats.exact.calls > 0
    assert intersecting_face_pairs(rig.pose(gated.angles), rig.faces) == 0
    # with contact between jointed parts allowed, whatever crossing the answer has is such a contact
    touching = sl.optimize(rig, settings.replace(contact=True))
    A = touching.angles
    V = rig.pose(A)
    assert rig.crossings(V, rig.posed_joints(A), ContactRules(),
                         float(sl.self_intersection_volume(V, rig.faces, rig.up))).allowed
    open_gate = sl.optimize(rig, settings.replace(exact_intersections=False))
    assert open_gate.stats.exact is None
    # the ungated search does reach poses that intersect: the gate changed the result
    assert intersecting_face_pairs(rig.pose(open_gate.angles), rig.faces) > 0


def test_optimize_two_dimensional_only_rotates_in_plane(tmp_path):
    V, F, J, B = sl.demo_figure("woody2d")
    rig = sl.prepare_rig(V, F, J, B, up="y")
    res = sl.optimize(rig, particles=8, iterations=3, seed=0)
    assert np.all(res.angles[:, :2] == 0)
    assert res.vertices.shape[1] == 2


def test_swarm_feasibility_constraint_is_never_violated_by_the_result():
    # unconstrained minimum at x0 = 0.3; the constraint forbids x0 > 0
    checked = []

    def feasible(x):
        checked.append(x.copy())
        return x[0] <= 0.0

    res = particle_swarm(sphere, -np.ones(2), np.ones(2), particles=20, iterations=30,
                         rng=np.random.default_rng(0), feasible=feasible)
    assert res.x[0] <= 0.0
    assert abs(res.x[0]) < 0.05 and abs(res.x[1] - 0.3) < 0.05  # the constrained optimum (0, 0.3)
    assert 0 < len(checked) < 20 * 31  # asked only about would-be bests


def test_swarm_with_bound_matches_plain_swarm():
    """A bounded objective that skips work above the bound gives the same search."""
    def bounded(X, bound):
        cheap = np.sum((X - 0.3) ** 2, axis=1)
        return np.where(cheap < bound, cheap + 0.1 * np.abs(X[:, 0]), cheap)

    def full(X):
        cheap = np.sum((X - 0.3) ** 2, axis=1)
        return cheap + 0.1 * np.abs(X[:, 0])

    a = particle_swarm(bounded, -np.ones(3), np.ones(3), particles=15, iterations=20,
                       rng=np.random.default_rng(2), pass_bound=True)
    b = particle_swarm(full, -np.ones(3), np.ones(3), particles=15, iterations=20, rng=np.random.default_rng(2))
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.history, b.history)


def test_optimize_from_a_start_pose_is_never_worse_than_it(branch_rig):
    rig = branch_rig
    obj = sl.Objective(rig)
    fixed = resolve_fixed_bones(rig)
    start = np.zeros((rig.bone_count, 3))
    free_bone = int(np.flatnonzero(~fixed)[0])
    start[free_bone] = np.radians([20.0, -10.0, 25.0])
    res = sl.optimize(rig, particles=10, iterations=4, seed=1, start=start, objective=obj)
    assert res.value <= float(obj(start)) + 1e-12
    assert res.value <= float(obj(rig.rest_angles())) + 1e-12
    with pytest.raises(ValueError):
        sl.optimize(rig, particles=4, iterations=1, start=np.zeros((rig.bone_count + 1, 3)))


def test_search_margin_is_one_rule(branch_rig):
    """The search minimises the threshold plus the margin, capped at 89 degrees; the report keeps the printer's."""
    # PrusaSlicer's automatic threshold at its defaults, atan(0.3 / 0.225), plus the 2-degree margin
    assert SearchSettings().overhang_angle == pytest.approx(53.1301, abs=1e-4)
    assert SearchSettings().search_overhang_angle == pytest.approx(55.1301, abs=1e-4)
    assert SearchSettings(overhang_angle=88.0).search_overhang_angle == 89.0
    assert SearchSettings(overhang_margin=0.0, overhang_angle=45.0).search_overhang_angle == 45.0
    res = sl.optimize(branch_rig, particles=8, iterations=2, seed=0, overhang_angle=40.0, overhang_margin=5.0)
    assert res.objective.overhang_angle == 45.0
    assert res.settings.overhang_angle == 40.0


# --------------------------------------------------------------------------- #
# the print orientation, searched with the pose
# --------------------------------------------------------------------------- #
def _turned_copy(rig, Q):
    """The same rig turned by the rotation Q (mesh, skeleton, volume mesh; weights unchanged)."""
    return sl.Rig(vertices=rig.vertices @ Q.T, faces=rig.faces, joints=rig.joints @ Q.T, bones=rig.bones,
                  tet_vertices=rig.tet_vertices @ Q.T, tets=rig.tets, tet_weights=rig.tet_weights, up=rig.up,
                  name=rig.name + "-turned")


def _printed_support(result, rig):
    return sl.overhang_energy(result.print_vertices, rig.faces, rig.up, result.settings.overhang_angle)


def test_orient_keep_is_the_pose_only_search(branch_rig):
    """``orient="keep"`` adds nothing: the swarm over the pose variables alone, the same result bit for bit."""
    from supportless.search.layout import PoseLayout
    from supportless.search.optimizer import particle_swarm
    from supportless.search.settings import PSO_PRESETS

    rig, settings = branch_rig, SearchSettings(particles=16, iterations=8, seed=5, orient="keep",
                                               exact_intersections=False, symmetric=False, relaxed=False)
    kept = sl.optimize(rig, settings)
    objective = settings.objective(rig)
    layout = PoseLayout(rig, settings.fixed_bones(rig), np.zeros((rig.bone_count, 3)),
                        np.radians(settings.joint_limits(rig)))
    swarm = particle_swarm(lambda X, bound: objective.bounded(layout.to_angles(X), bound), layout.lower,
                           layout.upper, particles=16, iterations=8, rng=np.random.default_rng(5),
                           initial=np.zeros((1, layout.count)), pass_bound=True, **PSO_PRESETS["standard"])
    np.testing.assert_array_equal(kept.angles, layout.to_angles(swarm.x[None])[0])
    # the swarm poses with the search's pruned weights; the result is measured with the rig's own
    assert kept.value == float(objective(kept.angles)) == pytest.approx(swarm.value, rel=1e-4)
    np.testing.assert_array_equal(kept.rotation, np.eye(3))
    np.testing.assert_array_equal(kept.print_vertices, kept.vertices)


def test_free_orientation_is_never_worse_than_keeping_it(branch_rig):
    """The turning phase starts from the pose-only phase's best, so turning is never a loss (by the objective)."""
    settings = SearchSettings(particles=20, iterations=10, seed=0)
    free = sl.optimize(branch_rig, settings)
    kept = sl.optimize(branch_rig, settings.replace(orient="keep"))
    assert free.value <= kept.value
    R = free.rotation
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)
    # the objective's overhang term is the print frame's support
    printed = sl.overhang_energy(free.print_vertices, branch_rig.faces, branch_rig.up, free.objective.overhang_angle)
    assert free.terms["overhang"] == pytest.approx(printed / free.objective.overhang_scale, rel=1e-9)
    # contact and balance stay in the display frame: the standing mesh keeps its feet on the plate
    assert free.objective.standing.measures(branch_rig.transforms(free.angles), branch_rig.pose(free.angles))[
        "new_contact_vertices"] == 0


def test_a_rod_lying_flat_is_turned_to_print_upright(tmp_path):
    """A lying rod with every joint held (turning only) is stood on its end, where it needs no support."""
    import trimesh

    rod = trimesh.creation.cylinder(radius=1.0, height=10.0, sections=24)
    rod.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))  # along x, lying
    V = np.asarray(rod.vertices) + [0.0, 1.0, 0.0]
    joints = np.array([[-4.0, 1.0, 0.0], [0.0, 1.0, 0.0], [4.0, 1.0, 0.0]])
    rig = sl.prepare_rig(V, np.asarray(rod.faces), joints, np.array([[0, 1], [1, 2]]), up="y", name="rod")
    turned = sl.optimize(rig, particles=20, iterations=15, seed=0, joint_limit=0.0)
    direction = turned.rotation.T @ rig.up
    assert abs(direction[0]) > 0.99  # printed along its axis
    rest = sl.overhang_energy(rig.vertices, rig.faces, rig.up, SearchSettings().overhang_angle)
    assert _printed_support(turned, rig) < 1e-6 * rest
    np.testing.assert_array_equal(turned.angles, 0.0)  # every joint held
    kept = sl.optimize(rig, particles=20, iterations=15, seed=0, joint_limit=0.0, orient="keep")
    assert _printed_support(kept, rig) == pytest.approx(rest)


def test_a_turned_copy_finds_the_same_support(branch_rig):
    """The orientation search does not depend on how the input happened to be turned."""
    from scipy.spatial.transform import Rotation

    # the search's own; no footprint rule: it exempts each copy's own standing, which differs between them
    settings = SearchSettings(particles=30, iterations=25, seed=0, joint_limit=0.0, choose=False, footprint_mm2=0.0)
    base = sl.optimize(branch_rig, settings)
    for rotvec in ([np.pi / 2, 0, 0], [0.3, 1.0, -0.6]):
        copy = _turned_copy(branch_rig, Rotation.from_rotvec(rotvec).as_matrix())
        found = sl.optimize(copy, settings)
        assert _printed_support(found, copy) == pytest.approx(_printed_support(base, branch_rig), rel=0.05)


def test_planar_search_turns_in_the_plane():
    rig = sl.prepare_rig(*sl.demo_figure("woody2d"), up="y")
    result = sl.optimize(rig, particles=16, iterations=6, seed=0)
    assert result.rotation.shape == (2, 2) and result.print_vertices.shape == rig.vertices.shape
    np.testing.assert_allclose(result.rotation @ result.rotation.T, np.eye(2), atol=1e-12)
    assert (result.print_vertices @ rig.up).min() == pytest.approx(0.0, abs=1e-9)


def test_a_repeated_search_is_never_worse_than_its_start_pose_and_turn(branch_rig):
    first = sl.optimize(branch_rig, particles=12, iterations=5, seed=0, choose=False)  # the objective's own best
    again = sl.optimize(branch_rig, particles=6, iterations=0, seed=9, start=first.angles,
                        start_rotation=first.rotation, choose=False)
    assert again.value <= first.value + 1e-12


# --------------------------------------------------------------------------- #
# CMA-ES (optimizer="cma")
# --------------------------------------------------------------------------- #
def test_evolution_strategy_finds_minimum_of_a_quadratic_with_batched_calls():
    from supportless.search.optimizer import CMA_SHARE, evolution_strategy

    calls = []

    def f(X):
        calls.append(X.shape)
        return sphere(X)

    res = evolution_strategy(f, -np.ones(4), np.ones(4), particles=60, iterations=80, rng=np.random.default_rng(1),
                             sigma=0.3)
    np.testing.assert_allclose(res.x, 0.3, atol=1e-3)
    lam = 60 // CMA_SHARE
    assert calls[0] == (1, 4) and all(c == (lam, 4) for c in calls[1:])  # the start, then one call per generation
    assert res.evaluations == 1 + lam * 80 and len(res.history) == 81
    assert np.all(np.diff(res.history) <= 0)


def test_evolution_strategy_respects_bounds_feasibility_and_is_reproducible():
    from supportless.search.optimizer import evolution_strategy

    seen = []

    def f(X):
        seen.append(X.copy())
        return np.sum((X - 2.0) ** 2, axis=1)  # minimum outside the box: the corner (1, 1, 1)

    def feasible(x):
        return x[0] <= 0.5  # forbid the corner's x0

    run = dict(particles=40, iterations=60, feasible=feasible, sigma=0.3)
    a = evolution_strategy(f, -np.ones(3), np.ones(3), rng=np.random.default_rng(2), **run)
    b = evolution_strategy(f, -np.ones(3), np.ones(3), rng=np.random.default_rng(2), **run)
    assert np.all(np.vstack(seen) >= -1) and np.all(np.vstack(seen) <= 1)
    assert a.x[0] <= 0.5 and a.x[0] > 0.4 and np.allclose(a.x[1:], 1.0, atol=1e-2)
    np.testing.assert_array_equal(a.x, b.x)
    c = evolution_strategy(f, -np.ones(3), np.ones(3), rng=np.random.default_rng(3), **run)
    assert not np.array_equal(a.x, c.x)


def test_evolution_strategy_never_worse_than_its_initial_positions_and_stops_on_callback():
    from supportless.search.optimizer import evolution_strategy

    start = np.array([[0.3, 0.3], [0.9, -0.9]])
    res = evolution_strategy(sphere, -np.ones(2), np.ones(2), particles=40, iterations=5, initial=start,
                             rng=np.random.default_rng(0))
    assert res.value <= 0.0 + 1e-15 and np.allclose(res.x, 0.3)
    stopped = evolution_strategy(sphere, -np.ones(2), np.ones(2), particles=40, iterations=50,
                                 rng=np.random.default_rng(0), callback=lambda it, x, v: it < 3)
    assert stopped.interrupted and len(stopped.history) == 4


def test_optimize_with_cma_is_never_worse_than_rest_and_has_no_intersection(branch_rig):
    from supportless.copyleft.cgal import intersecting_face_pairs

    rig = branch_rig
    res = sl.optimize(rig, particles=40, iterations=8, seed=0, optimizer="cma")
    obj = SearchSettings().objective(rig)
    assert res.value <= float(obj(rig.rest_angles())) + 1e-12
    assert float(obj(res.angles, res.rotation)) == pytest.approx(res.value, rel=1e-12)
    assert res.terms["overhang"] < 0.9
    assert intersecting_face_pairs(rig.pose(res.angles), rig.faces) == 0
    assert res.settings.optimizer == "cma" and len(res.history) == 17
    with pytest.raises(ValueError, match="optimizer"):
        SearchSettings(optimizer="sgd")


# --- distinct good poses (for slice-ranking) ----------------------------------


def test_pose_distance_is_the_largest_bone_or_print_rotation():
    from supportless.search.optimizer import pose_distance_deg

    a = np.zeros((3, 3))
    b = a.copy()
    b[1, 0] = np.radians(30.0)  # one bone turned 30 deg about x
    b[2, 2] = np.radians(-12.0)
    eye = np.eye(3)
    assert pose_distance_deg(a, eye, b, eye) == pytest.approx(30.0)
    assert pose_distance_deg(b, eye, a, eye) == pytest.approx(30.0)  # symmetric
    c = np.cos(np.radians(50.0))
    s = np.sin(np.radians(50.0))
    Q = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    assert pose_distance_deg(a, eye, b, Q) == pytest.approx(50.0)  # the turn dominates
    Q2 = np.array([[c, -s], [s, c]])
    assert pose_distance_deg(a, np.eye(2), a, Q2) == pytest.approx(50.0)  # planar turns too


def _candidates(angles_deg, values):
    A = np.radians(np.asarray(angles_deg, float))
    return {"angles": A, "rotations": np.repeat(np.eye(3)[None], len(A), 0), "values": np.asarray(values, float)}


def test_distinct_candidates_skip_near_copies_and_poor_poses():
    from supportless.search.optimizer import distinct_candidates, pose_distance_deg

    poses = np.zeros((6, 2, 3))
    poses[1, 0, 0] = 3.0    # a near-copy of the best
    poses[2, 0, 0] = 25.0   # another optimum
    poses[3, 1, 1] = 40.0   # a third
    poses[4, 1, 1] = -40.0  # a fourth, but 80 % worse than the best
    poses[5, 0, 2] = 60.0
    cand = _candidates(poses, [1.0, 1.01, 1.05, 1.2, 1.8, 1.9])
    kept = distinct_candidates(cand, 4, min_degrees=10.0, tolerance=0.25)
    assert kept == [0, 2, 3]
    for i in kept:
        for j in kept:
            if i < j:
                assert pose_distance_deg(cand["angles"][i], np.eye(3), cand["angles"][j], np.eye(3)) >= 10.0
    assert distinct_candidates(cand, 2, 10.0, 0.25) == [0, 2]
    assert distinct_candidates(cand, 4, 1.0, 0.25) == [0, 1, 2, 3]  # a small distance keeps the copy
    # a hard rule: the rejected pose is skipped, the first pose is never asked about
    asked = []

    def accept(A, Q):
        asked.append(np.degrees(A).round().tolist())
        return A[0, 0] == 0.0

    assert distinct_candidates(cand, 4, 10.0, 0.25, accept=accept) == [0, 3]
    assert len(asked) == 2


def test_search_result_carries_its_candidates_best_first(branch_rig):
    from supportless.search.optimizer import distinct_candidates

    res = sl.optimize(branch_rig, particles=24, iterations=10, seed=0, orient="keep", symmetric=False)
    c = res.candidates
    assert len(c["values"]) >= 2 and c["angles"].shape[1:] == (branch_rig.bone_count, 3)
    assert np.all(np.diff(c["values"]) >= 0)
    np.testing.assert_allclose(c["angles"][0], res.angles)
    assert c["values"][0] == pytest.approx(res.value)
    # each candidate's value is its objective, as the search measured it (with its pruned skinning weights)
    for i in range(min(3, len(c["values"]))):
        assert float(res.objective(c["angles"][i][None])[0]) == pytest.approx(c["values"][i], rel=1e-4)
    kept = distinct_candidates(c, 3, tolerance=10.0)
    assert kept[0] == 0 and len(set(kept)) == len(kept)


def test_poses_the_ray_grid_sees_overlapping_skip_cgal_with_the_same_result(monkeypatch):
    """An embedded closed surface is nowhere two layers deep: such candidates are rejected without CGAL."""
    from supportless.search import optimizer as search_mod

    rig = sl.load_rig("demo:tree")
    asked = []

    def counted(angles):  # the exact check, counted
        answer = rig.self_intersects(angles)
        asked.append(answer)
        return answer

    fast = sl.optimize(rig, particles=30, iterations=10, orient="keep", intersects=counted, contact=False)
    fast_asked = list(asked)
    asked.clear()
    monkeypatch.setattr(search_mod, "OVERLAP_CERTAIN", np.inf)  # CGAL asked about every candidate
    slow = sl.optimize(rig, particles=30, iterations=10, orient="keep", intersects=counted, contact=False)
    assert fast.stats.overlap_rejections >= 3 and slow.stats.overlap_rejections == 0
    assert len(asked) == len(fast_asked) + fast.stats.overlap_rejections
    assert sum(asked) == sum(fast_asked) + fast.stats.overlap_rejections  # CGAL agreed: each one intersects
    np.testing.assert_array_equal(fast.angles, slow.angles)
    assert fast.value == slow.value


def test_the_searchs_shortcuts_decide_as_the_whole_objective_would(monkeypatch):
    """Skipping the intersection term of poses that cannot beat their bound, and every term of poses past a joint
    limit, leaves the swarm's decisions as they are with every pose measured in full."""
    from supportless.search.objective import Objective

    rig = sl.load_rig("demo:tree")
    settings = SearchSettings(particles=30, iterations=12, joint_limit=30.0)
    posed = []
    real_posed = Objective._posed
    monkeypatch.setattr(Objective, "_posed",
                        lambda self, angles, search=False: posed.append(len(angles)) or real_posed(self, angles, search))
    short = sl.optimize(rig, settings)
    short_posed = sum(posed)
    posed.clear()
    bounded = Objective.bounded_overlap
    monkeypatch.setattr(Objective, "bounded_overlap",  # no bound: every pose gets every term (the
                        # self-intersection, as in the search, where the others are below the swarm's best)
                        lambda self, angles, bound, rotations=None, intersection_bound=None, measured=None: bounded(
                            self, angles, np.full(len(angles), np.inf), rotations, intersection_bound, measured))
    full = sl.optimize(rig, settings)
    assert short_posed < 0.9 * sum(posed)  # the shortcuts did skip poses
    np.testing.assert_array_equal(short.angles, full.angles)
    np.testing.assert_array_equal(short.rotation, full.rotation)
    assert short.value == full.value and short.history.tolist() == full.history.tolist()


def test_the_polish_starts_from_the_swarms_best_and_is_never_worse(branch_rig):
    plain = sl.optimize(branch_rig, particles=12, iterations=6, seed=3, choose=False, symmetric=False)
    assert plain.stats.polish_evaluations == 0  # none by default on a model searched at full resolution
    polished = sl.optimize(branch_rig, particles=12, iterations=6, seed=3, polish=5, choose=False, symmetric=False)
    assert polished.stats.polish_evaluations == 1 + 5 * POLISH_SAMPLES
    assert polished.value < plain.value  # a short swarm leaves room that small steps find
    np.testing.assert_array_equal(polished.history[:len(plain.history)], plain.history)  # the same swarm first
    assert len(polished.history) == len(plain.history) + 5 and np.all(np.diff(polished.history) <= 0)
    assert not sl.copyleft.cgal.self_intersects(branch_rig.pose(polished.angles), branch_rig.faces)
    with pytest.raises(sl.InputError):
        SearchSettings(polish=-1)


def test_only_poses_that_could_become_the_swarms_best_are_measured_for_self_intersection(branch_rig, monkeypatch):
    from supportless.search.objective import Objective

    measured = []
    real = Objective._intersection
    monkeypatch.setattr(Objective, "_intersection",  # poses measured (one for an unbatched pose)
                        lambda self, V: measured.append(len(V) if V.ndim == 3 else 1) or real(self, V))
    result = sl.optimize(branch_rig, particles=30, iterations=10, seed=2, symmetric=False)
    progress = result.stats.progress.calls  # each change of the best measures it once, in full
    evaluations = 30 * 11 + 15 * 11  # the pose phase, then half the swarm turning
    assert 0 < sum(measured) - progress < 0.2 * evaluations
    assert float(result.objective(result.angles, result.rotation)) == pytest.approx(result.value, rel=1e-12)
    assert not sl.copyleft.cgal.self_intersects(branch_rig.pose(result.angles), branch_rig.faces)
