"""SearchSettings: one source of the search's defaults; which bones the search rotates."""

import dataclasses

import numpy as np
import pytest

import supportless as sl
from supportless.search.objective import INFEASIBLE, W_ARAP, W_INTERSECT, W_OVERHANG, W_PRIOR
from supportless.search.settings import SearchSettings, angle_layout, resolve_fixed_bones


def test_defaults_and_frozen():
    s = SearchSettings()
    assert (s.particles, s.iterations, s.seed, s.joint_limit) == (200, 120, 0, 45.0)
    assert (s.w_arap, s.w_overhang, s.w_intersect) == (W_ARAP, W_OVERHANG, W_INTERSECT)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.particles = 3


def test_bone_lists_accept_commas_repeats_and_strings():
    assert SearchSettings(fix=("3,4", "7")).fix == ("3", "4", "7")
    assert SearchSettings(free="all").free == ("all",)
    assert SearchSettings(fix=[2, 5]).fix == ("2", "5")


@pytest.mark.parametrize("bad", [dict(overhang_model="cone"), dict(preset="fast"), dict(particles=0),
                                 dict(overhang_angle=95.0)])
def test_bad_settings_are_refused(bad):
    with pytest.raises(ValueError):
        SearchSettings(**bad)


def test_replace_ignores_none_and_round_trips_through_dict():
    s = SearchSettings(particles=7, fix=("2",))
    assert s.replace(particles=None, seed=4) == SearchSettings(particles=7, fix=("2",), seed=4)
    d = s.to_dict()
    assert d["search_overhang_angle"] == pytest.approx(55.1301, abs=1e-4) and d["fix"] == ["2"]
    assert SearchSettings.from_dict(d) == s


def test_objective_is_built_from_the_settings_and_shares_operators(branch_rig):
    s = SearchSettings(w_arap=3.0, overhang_angle=40.0, overhang_margin=7.0, overhang_model="column")
    obj = s.objective(branch_rig)
    assert (obj.w_arap, obj.overhang_angle, obj.overhang_model) == (3.0, 47.0, "column")
    again = s.replace(w_overhang=2.0).objective(branch_rig, arap_data=obj.arap_data)
    assert again.arap_data is obj.arap_data
    A = np.random.default_rng(0).uniform(-0.4, 0.4, (3, branch_rig.bone_count, 3))
    t1, t2 = obj.terms(A), again.terms(A)
    np.testing.assert_array_equal(t1["arap"], t2["arap"])
    expected = (3.0 * t2["arap"] + 2.0 * t2["overhang"] + W_INTERSECT * t2["intersection"]
                + W_PRIOR * t2["prior"])
    np.testing.assert_array_equal(again(A), expected + np.where(t2["violation"] > 0, INFEASIBLE + t2["violation"], 0))


def test_the_bones_on_the_plate_are_fixed_by_default(branch_rig, tpose_rig):
    for rig in (branch_rig, tpose_rig):
        fixed = resolve_fixed_bones(rig)
        np.testing.assert_array_equal(fixed, rig.anchored_bones)
        assert rig.contact_bones.any() and not fixed.all()
        np.testing.assert_array_equal(SearchSettings().fixed_bones(rig), fixed)
    rig = branch_rig
    assert not resolve_fixed_bones(rig, free=["all"]).any()
    assert resolve_fixed_bones(rig, fix=[str(rig.bone_count)])[-1]
    with pytest.raises(ValueError, match="out of range"):
        resolve_fixed_bones(rig, fix=["99"])
    with pytest.raises(ValueError, match="not a bone number"):
        resolve_fixed_bones(rig, fix=["arm"])


def test_joint_limits_per_bone(branch_rig):
    s = SearchSettings(joint_limit=25.0, limits=("2=10", "3=40"))
    np.testing.assert_array_equal(s.joint_limits(branch_rig), [25.0, 10.0, 40.0])
    np.testing.assert_array_equal(s.objective(branch_rig).prior.limits, np.radians([25.0, 10.0, 40.0]))
    with pytest.raises(ValueError, match="out of range"):
        SearchSettings(limits=("9=10",)).joint_limits(branch_rig)
    for bad in ("2", "2=x", "2=200"):
        with pytest.raises(ValueError, match="BONE=DEGREES"):
            SearchSettings(limits=(bad,))


def test_angle_layout_three_angles_in_3d_one_in_2d(branch_rig):
    fixed = np.zeros(branch_rig.bone_count, bool)
    fixed[0] = True
    free = angle_layout(branch_rig, fixed)
    assert free.shape == (branch_rig.bone_count, 3)
    assert not free[0].any() and free[1:].all()
    V, F, J, B = sl.demo_figure("woody2d")
    rig2 = sl.prepare_rig(V, F, J, B, up="y")
    free2 = angle_layout(rig2, np.zeros(rig2.bone_count, bool))
    assert free2[:, 2].all() and not free2[:, :2].any()


def test_the_energies_default_angle_is_the_default_search_s(branch_rig):
    """``overhang_energy(V, F, up)`` measures what the default search minimises (one source: the threshold rule)."""
    from supportless.files.printer import SEARCH_OVERHANG_ANGLE, default_profile, search_angle

    settings = SearchSettings()
    assert settings.search_overhang_angle == SEARCH_OVERHANG_ANGLE == search_angle(default_profile().overhang_angle)
    assert 55.0 < SEARCH_OVERHANG_ANGLE < 55.2  # PrusaSlicer's automatic 53.1 degrees and the 2-degree margin
    V, F, up = branch_rig.vertices, branch_rig.faces, branch_rig.up
    assert sl.overhang_energy(V, F, up) == sl.overhang_energy(V, F, up, settings.search_overhang_angle)
    assert sl.overhang_energy(V, F, up) != sl.overhang_energy(V, F, up, 45.0)  # the angle matters on this figure
    assert settings.objective(branch_rig).overhang_angle == SEARCH_OVERHANG_ANGLE == sl.Objective(branch_rig).overhang_angle


def test_replace_keeps_a_setting_on_none_and_resets_it_on_auto():
    from supportless.search.settings import AUTO

    s = SearchSettings(polish=5)
    assert s.replace(polish=None).polish == 5 and s.replace(polish=AUTO).polish is None
    assert s.replace(particles=7).particles == 7
    with pytest.raises(sl.InputError, match="particles must be within 2..5000"):
        s.replace(particles=1)


def test_the_swarm_and_the_bench_default_to_the_settings_swarm():
    """One source of the default swarm: the optimisers' and the bench's defaults are SearchSettings'."""
    import inspect

    from supportless.apps.bench import bench_model, run_bench
    from supportless.search.swarm import evolution_strategy, particle_swarm

    d = sl.SearchSettings()
    for f in (particle_swarm, evolution_strategy, bench_model, run_bench):
        params = inspect.signature(f).parameters
        assert (params["particles"].default, params["iterations"].default) == (d.particles, d.iterations), f
