"""Particle swarm and pose search."""

import numpy as np
import pytest

import supportless as sl
from supportless.geometry import place_on_plate
from supportless.search import PSO_PRESETS, particle_swarm, plate_bones, resolve_fixed_bones


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


@pytest.fixture(scope="module")
def branch_rig(tmp_path_factory):
    return sl.load_rig("demo:branch", cache_dir=tmp_path_factory.mktemp("cache"))


def test_plate_bones_fixed_by_default(branch_rig):
    rig = branch_rig
    fixed = resolve_fixed_bones(rig)
    touching = plate_bones(rig)
    assert touching.any()
    # every fixed-by-default bone touches the plate or is an ancestor of one that does
    for b in np.flatnonzero(fixed):
        assert touching[b] or any(
            touching[c] for c in range(rig.bone_count) if b in _ancestors(rig.parents, c))
    assert not fixed.all()
    free_all = resolve_fixed_bones(rig, free=["all"])
    assert not free_all.any()
    fix_one = resolve_fixed_bones(rig, fix=[str(rig.bone_count)])
    assert fix_one[-1]
    with pytest.raises(ValueError):
        resolve_fixed_bones(rig, fix=["99"])


def _ancestors(parents, b):
    out, p = [], parents[b]
    while p >= 0:
        out.append(p)
        p = parents[p]
    return out


def test_optimize_never_worse_than_rest_and_reproducible(branch_rig):
    rig = branch_rig
    a = sl.optimize(rig, particles=12, iterations=6, seed=3)
    b = sl.optimize(rig, particles=12, iterations=6, seed=3)
    np.testing.assert_array_equal(a.angles, b.angles)
    from supportless.search import OVERHANG_MARGIN

    obj = sl.Objective(rig, overhang_angle=45.0 + OVERHANG_MARGIN)  # what the search minimises
    rest = float(obj(rig.rest_angles()))
    assert a.value <= rest + 1e-12
    assert np.isclose(float(obj(a.angles)), a.value)
    # fixed bones keep zero angles; the output sits on the plate
    assert np.all(a.angles[a.fixed] == 0)
    assert np.isclose((a.vertices @ rig.up).min(), 0.0, atol=1e-12)
    rep = a.report
    for key in ("before", "after", "reduction_percent", "max_vertex_displacement", "runtime_seconds",
                "settings", "history"):
        assert key in rep
    assert rep["after"]["intersecting_face_pairs"] == 0
    assert len(rep["history"]) == 7


def test_optimize_reduces_support_of_the_cantilever(branch_rig):
    res = sl.optimize(branch_rig, particles=30, iterations=20, seed=0)
    red = res.report["reduction_percent"]["overhang_prism"]
    assert red is not None and red > 20.0


def test_optimize_two_dimensional_only_rotates_in_plane(tmp_path):
    V, F, J, B = sl.demo_figure("woody2d")
    rig = sl.prepare_rig(V, F, J, B, up="y")
    res = sl.optimize(rig, particles=8, iterations=3, seed=0)
    assert np.all(res.angles[:, :2] == 0)
    assert res.vertices.shape[1] == 2


def test_place_on_plate():
    V = np.array([[0.0, 2.0, 0.0], [1.0, 5.0, 1.0]])
    out = place_on_plate(V, np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(out[:, 1], [0.0, 3.0])


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


def test_cli_bone_lists_accept_commas_and_repeats():
    from supportless.cli import _bone_list

    assert _bone_list(("3,4", "7")) == ["3", "4", "7"]
    assert _bone_list(("all",)) == ["all"]


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


def test_search_margin_reports_at_the_printers_threshold(branch_rig):
    rig = branch_rig
    res = sl.optimize(rig, particles=8, iterations=3, seed=0, overhang_angle=45.0, overhang_margin=10.0)
    rep = res.report
    assert rep["before"]["overhang_angle"] == 45.0
    assert np.isclose(rep["before"]["overhang_prism"], sl.overhang_energy(rig.vertices, rig.faces, rig.up, 45.0))
    assert rep["settings"]["overhang_angle"] == 55.0  # what the search used
    assert rep["settings"]["report_overhang_angle"] == 45.0
    none = sl.optimize(rig, particles=8, iterations=3, seed=0, overhang_margin=0.0)
    assert none.report["settings"]["overhang_angle"] == 45.0
