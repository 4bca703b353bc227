"""The combined, normalised objective."""

import numpy as np
import pytest

import supportless as sl
from supportless.base.geometry import signed_volume
from supportless.search.objective import INFEASIBLE

#: The rules the objective's defaults (the tool's) add, left out: poses measured whatever their turns.
LOOSE = dict(joint_limits=180.0, chain_limit=None, head_limit=None, footprint_mm2=None, w_chain=0.0)


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    return sl.load_rig("demo:branch", cache_dir=tmp_path_factory.mktemp("cache"))


def random_angles(rig, P, scale=0.4, seed=0):
    return np.random.default_rng(seed).uniform(-scale, scale, (P, rig.bone_count, 3))


def test_terms_shapes_and_batch_equals_single(rig):
    obj = sl.Objective(rig)
    A = random_angles(rig, 5)
    terms = obj.terms(A)
    assert set(terms) == {"arap", "overhang", "intersection", "prior", "violation"}
    for v in terms.values():
        assert v.shape == (5,)
    values = obj(A)
    singles = np.array([float(obj(a)) for a in A])
    np.testing.assert_allclose(values, singles, rtol=1e-10, atol=1e-14)


def test_rest_pose_has_no_distortion_and_no_intersection(rig):
    obj = sl.Objective(rig)
    t = obj.terms(rig.rest_angles())
    assert abs(float(t["arap"])) < 1e-10
    assert float(t["intersection"]) == 0.0


def test_terms_of_a_known_pose_are_the_energies_over_their_scales(rig):
    """Each normalised term is its energy, computed on its own, over the rest volume or the rest support."""
    obj = sl.Objective(rig, overhang_angle=50.0)
    A = np.zeros((rig.bone_count, 3))
    A[-1] = [0.1, 0.2, -0.3]
    V, rest = rig.pose(A), rig.pose(rig.rest_angles())
    volume = signed_volume(rig.vertices, rig.faces)
    rest_support = sl.overhang_energy(rest, rig.faces, rig.up, 50.0)
    t = obj.terms(A)
    assert float(t["overhang"]) == pytest.approx(sl.overhang_energy(V, rig.faces, rig.up, 50.0) / rest_support,
                                                 rel=1e-12)
    assert float(t["intersection"]) == pytest.approx(
        sl.self_intersection_volume(V, rig.faces, rig.up, obj.resolution) / volume, rel=1e-12, abs=1e-15)
    assert float(t["arap"]) == pytest.approx(
        float(sl.arap_energy(obj.arap_data, rig.transforms(A))) / volume, rel=1e-12)


def test_support_scale_is_floored_for_a_model_that_needs_no_support(rig):
    """An overhang threshold of 0 degrees counts no face as risky: the scale falls back to 1e-3 of the volume."""
    obj = sl.Objective(rig, overhang_angle=0.0)
    assert obj.rest_overhang == 0.0
    assert obj.overhang_scale == pytest.approx(1e-3 * signed_volume(rig.vertices, rig.faces), rel=1e-12)


def test_prism_and_column_differ_where_the_body_is_below_an_overhang(rig):
    """The head folded over the arm: its prism reaches the plate, its column stops on the arm."""
    A = np.zeros((1, rig.bone_count, 3))
    A[0, 2] = [0.0, 0.0, -0.45 * np.pi]
    V = rig.pose(A)
    prism = sl.Objective(rig, overhang_model="prism")
    column = sl.Objective(rig, overhang_model="column")
    assert float(prism.overhang(V)[0]) == sl.overhang_energy(V[0], rig.faces, rig.up, prism.overhang_angle)
    assert float(column.overhang(V)[0]) == sl.support_volume(V[0], rig.faces, rig.up, column.overhang_angle,
                                                             column.resolution)
    grow_prism = float(prism.terms(A)["overhang"][0]) - 1.0
    grow_column = float(column.terms(A)["overhang"][0]) - 1.0
    assert grow_prism > 0.3  # the head's underside is far above the plate
    assert abs(grow_column) < 0.05  # ... but just above the arm
    np.testing.assert_array_equal(prism.terms(A)["arap"], column.terms(A)["arap"])


def test_weighted_sum(rig):
    A = random_angles(rig, 3, seed=1)
    obj = sl.Objective(rig, w_arap=2.0, w_overhang=3.0, w_intersect=5.0, w_prior=7.0)
    t = obj.terms(A)
    base = 2 * t["arap"] + 3 * t["overhang"] + 5 * t["intersection"] + 7 * t["prior"]
    np.testing.assert_allclose(obj(A), base + np.where(t["violation"] > 0, INFEASIBLE + t["violation"], 0.0))
    free = sl.Objective(rig, w_arap=2.0, w_overhang=3.0, w_intersect=5.0, w_prior=7.0, keep_standing=False)
    np.testing.assert_allclose(free(A), base)  # no joint limit by default: no rule broken


def test_hard_rules_make_a_pose_worse_than_any_that_keeps_them(rig):
    """A joint past its limit, or a pose that falls over or touches the plate anew, costs INFEASIBLE more."""
    obj = sl.Objective(rig, joint_limits=20.0)
    A = np.zeros((3, rig.bone_count, 3))
    A[1, -1] = np.radians([0.0, 0.0, 15.0])  # within the limit
    A[2, -1] = np.radians([0.0, 0.0, 25.0])  # 5 degrees past it
    t = obj.terms(A)
    assert t["violation"][1] == 0.0
    assert t["violation"][2] >= np.radians(5.0) - 1e-12
    assert obj(A)[2] > INFEASIBLE > obj(A)[1]


def test_normalised_terms_are_scale_free(rig, tmp_path):
    """The same pose of the model scaled by 100 gives the same normalised terms."""
    s = 100.0
    big = sl.Rig(rig.vertices * s, rig.faces, rig.joints * s, rig.bones, rig.tet_vertices * s, rig.tets,
                 rig.tet_weights, rig.up)
    A = random_angles(rig, 4, seed=2)
    a = sl.Objective(rig).terms(A)
    b = sl.Objective(big).terms(A)
    for key in a:
        np.testing.assert_allclose(a[key], b[key], rtol=1e-9, atol=1e-12)


def test_rigid_motion_of_the_whole_model_costs_no_distortion(rig):
    """The same rotation on every root bone, with children at rest, is a rigid motion."""
    obj = sl.Objective(rig)
    A = np.zeros((1, rig.bone_count, 3))
    roots = rig.parents < 0
    assert roots.sum() == 1  # one root: rotating it about its joint moves the whole model rigidly
    A[0, roots] = [0.3, -0.2, 0.5]
    assert float(obj.terms(A)["arap"][0]) < 1e-9


def test_the_slicer_model_is_the_predicted_filament_at_60_mm_and_takes_the_printers_threshold(rig):
    from supportless.energies.slicer_model import predicted_support_mm

    A = random_angles(rig, 4, seed=3)
    settings = sl.SearchSettings(overhang_angle=53.13, overhang_model="slicer")
    assert settings.search_overhang_angle == 53.13  # no margin: the model carries its own fitted offset
    obj = settings.objective(rig)
    scale = 60.0 / np.ptp(rig.vertices @ rig.up)
    V = rig.pose(A)
    expected = predicted_support_mm(V, rig.faces, rig.up, 53.13, scale)
    np.testing.assert_allclose(obj.overhang(V), expected, rtol=1e-12)
    np.testing.assert_allclose([float(obj.overhang(v)) for v in V], expected, rtol=1e-12)  # batch = singles
    assert float(obj.terms(rig.rest_angles())["overhang"]) == pytest.approx(1.0)
    # the prism model keeps the margin
    assert sl.SearchSettings(overhang_angle=53.13).search_overhang_angle > 53.13


def test_the_slicer_model_measures_poses_in_chunks_equal_to_one_batch(monkeypatch):
    from supportless.energies import slicer_model

    V = np.random.default_rng(0).normal(size=(5, 4, 3))
    F = np.array([[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]])
    whole = slicer_model.predicted_support_mm(V, F, "z", 53.13)
    monkeypatch.setattr(slicer_model, "_CHUNK_ELEMENTS", 8)  # two poses of four faces at a time
    np.testing.assert_allclose(slicer_model.predicted_support_mm(V, F, "z", 53.13), whole, rtol=1e-12)
    assert whole.shape == (5,) and np.all(whole >= 0)


def test_unknown_overhang_model_is_refused(rig):
    with pytest.raises(ValueError):
        sl.Objective(rig, overhang_model="cone")


def test_bounded_is_exact_below_the_bound_and_never_below_it_elsewhere(rig):
    obj = sl.Objective(rig)
    A = random_angles(rig, 40, scale=1.2, seed=7)
    exact = obj(A)
    bound = np.where(np.arange(40) % 2 == 0, np.inf, np.median(exact))
    searched = obj.bounded(A, bound)  # posed with the search's pruned weights: close to the rig's own
    obj.__dict__["search_lbs"] = rig.lbs  # the same weights as obj(A): the bound logic alone
    got = obj.bounded(A, bound)
    below = exact < bound
    np.testing.assert_allclose(got[below], exact[below], rtol=1e-12)
    assert np.all(got[~below] >= bound[~below])
    assert np.all(got <= exact + 1e-12)  # a lower bound everywhere
    np.testing.assert_allclose(searched[below], exact[below], rtol=1e-3)
    assert not np.array_equal(searched[below], exact[below])


def test_bounded_measures_each_term_only_where_the_cheaper_ones_leave_a_pose_below_its_bound(rig, monkeypatch):
    from supportless.search import objective as objective_mod

    obj = sl.Objective(rig, **LOOSE)
    obj.__dict__["search_lbs"] = rig.lbs  # the rig's own weights, as raw_terms pose
    A = random_angles(rig, 60, scale=1.2, seed=5)
    raw = obj.raw_terms(A)
    terms = obj.normalise(raw)
    exact = obj.combine(terms)
    # bounds between the partial sums, so that every stage leaves some poses out
    first = obj.w_overhang * terms["overhang"] + obj.w_prior * terms["prior"]
    second = first + obj.w_arap * terms["arap"]
    later = np.where(exact > second * (1 + 1e-6), 0.5 * (second + exact), exact * 1.001)  # standing or intersection
    bound = np.where(np.arange(60) % 3 == 0, first * 0.999, np.where(np.arange(60) % 3 == 1, exact * 1.001, later))
    calls = {"arap": [], "standing": [], "intersection": []}
    arap_energy, violation, intersection = objective_mod.arap_mod.arap_energy, obj.standing.violation, obj._intersection
    monkeypatch.setattr(objective_mod.arap_mod, "arap_energy",
                        lambda data, T, backend: calls["arap"].append(len(T)) or arap_energy(data, T, backend))
    monkeypatch.setattr(obj.standing, "violation", lambda T, V: calls["standing"].append(len(T)) or violation(T, V))
    monkeypatch.setattr(obj, "_intersection", lambda V: calls["intersection"].append(len(V)) or intersection(V))
    got = obj.bounded(A, bound)
    assert calls["arap"] == [int(np.sum(first < bound))] and 0 < calls["arap"][0] < 60
    assert calls["standing"] == [int(np.sum((first < bound) & (second < bound)))]
    cheap = obj.combine(terms | {"intersection": np.zeros(60)})
    assert calls["intersection"] == [int(np.sum(cheap < bound))] and 0 < calls["intersection"][0] < calls["standing"][0]
    below = exact < bound
    np.testing.assert_allclose(got[below], exact[below], rtol=1e-12)
    assert np.all(got[~below] >= bound[~below]) and np.all(got[~below] <= exact[~below] + 1e-12)


def test_the_self_intersection_is_measured_only_where_a_pose_could_become_the_batchs_best(rig, monkeypatch):
    from supportless.search.objective import INTERSECT_CHUNK

    obj = sl.Objective(rig)
    obj.__dict__["search_lbs"] = rig.lbs  # the rig's own weights, as raw_terms pose
    A = random_angles(rig, 30, scale=1.5, seed=11)
    terms = obj.normalise(obj.raw_terms(A))
    exact = obj.combine(terms)
    others = obj.combine(terms | {"intersection": np.zeros(30)})
    cut = float(np.median(others))
    measured = []
    intersection = obj._intersection
    monkeypatch.setattr(obj, "_intersection", lambda V: measured.append(len(V)) or intersection(V))
    values, overlap = obj.bounded_overlap(A, np.full(30, np.inf), intersection_bound=cut)
    below = others < cut
    assert all(1 <= k <= INTERSECT_CHUNK for k in measured)
    count = sum(measured)
    assert 1 <= count < below.sum()  # some poses below the bound are not measured
    # the least costly by the other terms first, until they cost as much as the least total measured
    first = np.argsort(np.where(below, others, np.inf), kind="stable")[:count]
    was = np.zeros(30, bool)
    was[first] = True
    np.testing.assert_allclose(values[was], exact[was], rtol=1e-12)
    least = exact[was].min()
    assert np.all(others[below & ~was] >= least)
    # the batch's best is the one a measure of every pose below the bound finds
    assert least == pytest.approx(exact[below].min(), rel=1e-12)
    # the others cannot become the swarm's best: valued at or above the bound, never above their sum of terms
    np.testing.assert_allclose(values[below & ~was], np.maximum(others[below & ~was], cut), rtol=1e-12)
    np.testing.assert_allclose(values[~below], others[~below], rtol=1e-12)  # without the self-intersection
    assert np.all(overlap[~was] == 0)
    assert np.any(was & (terms["intersection"] > 0))  # a measured pose does overlap
    # without a bound every pose below its own bound is measured, at once
    measured.clear()
    np.testing.assert_allclose(obj.bounded(A, np.full(30, np.inf)), exact, rtol=1e-12)
    assert measured == [30]


def test_at_most_intersect_most_poses_of_a_batch_are_measured(rig, monkeypatch):
    from supportless.search import objective as objective_mod

    obj = sl.Objective(rig)
    obj.__dict__["search_lbs"] = rig.lbs
    A = random_angles(rig, 30, scale=1.5, seed=11)
    terms = obj.normalise(obj.raw_terms(A))
    others = obj.combine(terms | {"intersection": np.zeros(30)})
    cut = float(np.max(others)) + 1.0  # every pose could become the swarm's best: only the cap stops the measure
    measured = []
    intersection = obj._intersection
    monkeypatch.setattr(obj, "_intersection", lambda V: measured.append(len(V)) or intersection(V))
    values, _ = obj.bounded_overlap(A, np.full(30, np.inf), intersection_bound=cut)
    uncapped = sum(measured)
    assert uncapped <= objective_mod.INTERSECT_MOST
    monkeypatch.setattr(objective_mod, "INTERSECT_MOST", 2)
    measured.clear()
    values, _ = obj.bounded_overlap(A, np.full(30, np.inf), intersection_bound=cut)
    assert measured == [2]  # one chunk, cut to the cap
    was = np.zeros(30, bool)
    was[np.argsort(others, kind="stable")[:sum(measured)]] = True  # the least costly by the other terms
    np.testing.assert_allclose(values[was], obj.combine(terms)[was], rtol=1e-12)
    np.testing.assert_allclose(values[~was], np.maximum(others[~was], cut), rtol=1e-12)  # not the swarm's best


def test_the_terms_of_the_poses_measured_in_full_are_handed_back_as_terms_gives_them(rig, monkeypatch):
    """``measured``: exactly the poses whose self-intersection was measured, each with the terms :meth:`terms`
    gives (the same weights), in chunks too; the search shows them as its best's progress."""
    from supportless.search import objective as objective_mod

    obj = sl.Objective(rig)
    obj.__dict__["search_lbs"] = rig.lbs  # the rig's own weights, as terms() pose
    A = random_angles(rig, 30, scale=1.5, seed=11)
    terms = obj.terms(A)
    others = obj.combine(terms | {"intersection": np.zeros(30)})
    cut = float(np.median(others))
    monkeypatch.setattr(objective_mod, "POSE_CHUNK", 7)  # the positions are the batch's across chunks
    for bound, intersection_bound in ((np.full(30, np.inf), cut), (np.full(30, np.inf), None),
                                      (np.where(np.arange(30) % 2 == 0, np.inf, -np.inf), None)):
        measured = {"stale": 1}
        values, overlap = obj.bounded_overlap(A, bound, intersection_bound=intersection_bound, measured=measured)
        index = measured.pop("index")
        assert set(measured) == set(terms) and 1 <= len(index) <= 30
        if intersection_bound is None:  # every pose below its own bound, and only those
            np.testing.assert_array_equal(index, np.flatnonzero(bound == np.inf))
        else:  # those whose overlap the search measured: the least costly first
            assert len(index) < np.sum(others < cut)
        for key, v in measured.items():
            np.testing.assert_allclose(v, terms[key][index], rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(values[index], obj.combine(terms)[index], rtol=1e-12)


def test_a_big_batch_is_measured_in_chunks_with_the_same_values(rig, monkeypatch):
    from supportless.search import objective as objective_mod

    obj = sl.Objective(rig, **LOOSE)
    A = random_angles(rig, 23, scale=0.8, seed=3)
    bound = np.where(np.arange(23) % 3 == 0, 0.0, np.inf)
    whole = obj.bounded(A, bound)
    sizes = []
    posed = obj._posed
    monkeypatch.setattr(objective_mod, "POSE_CHUNK", 5)
    monkeypatch.setattr(obj, "_posed", lambda angles, search=False: sizes.append(len(angles)) or posed(angles, search))
    np.testing.assert_array_equal(obj.bounded(A, bound), whole)
    assert sizes == [5, 5, 5, 5, 3]


def test_a_dense_surface_is_measured_a_few_poses_at_a_time_with_the_same_terms(rig, monkeypatch):
    """POSED_VERTICES bounds the posed vertices of one chunk (a sculpt's batch took gigabytes): terms,
    bounded values and rotations per pose are those of one batch."""
    from supportless.search import objective as objective_mod

    obj = sl.Objective(rig)
    A = random_angles(rig, 11, scale=0.6, seed=4)
    R = np.stack([np.eye(3)] * 11)
    whole, bounded = obj.terms(A, R), obj.bounded(A, np.full(11, np.inf))
    sizes = []
    posed = obj._posed
    monkeypatch.setattr(objective_mod, "POSED_VERTICES", 4 * len(rig.vertices))
    monkeypatch.setattr(obj, "_posed", lambda angles, search=False: sizes.append(len(angles)) or posed(angles, search))
    chunked = obj.terms(A, R)
    for key in whole:
        np.testing.assert_array_equal(chunked[key], whole[key])
    np.testing.assert_array_equal(obj.bounded(A, np.full(11, np.inf)), bounded)
    assert sizes == [4, 4, 3] * 2


def test_bounded_overlap_reports_the_intersection_volume_it_computed(rig):
    obj = sl.Objective(rig)
    obj.__dict__["search_lbs"] = rig.lbs  # the rig's own weights, as raw_terms pose
    A = random_angles(rig, 30, scale=1.5, seed=11)
    raw = obj.raw_terms(A)["intersection"]
    assert np.count_nonzero(raw) >= 3  # some of these poses overlap
    bound = np.where(np.arange(30) % 2 == 0, np.inf, -np.inf)  # every other pose cannot beat its bound
    values, overlap = obj.bounded_overlap(A, bound)
    np.testing.assert_array_equal(values, obj.bounded(A, bound))
    np.testing.assert_array_equal(overlap[::2], raw[::2])
    assert np.all(overlap[1::2] == 0)


def test_a_pose_past_a_joint_limit_is_not_measured_against_a_bound_that_keeps_the_rules(rig, monkeypatch):
    obj = sl.Objective(rig, joint_limits=45.0)
    A = random_angles(rig, 24, scale=0.8, seed=5)
    A[::3] *= 0.2  # some poses well within the limits
    past = obj.prior.excess(A) > 0
    assert 4 <= past.sum() <= 20
    exact = obj(A)
    bound = np.full(24, 0.5)  # a pose that keeps the rules reached 0.5
    posed = []
    real = obj._posed
    monkeypatch.setattr(obj, "_posed", lambda angles, search=False: posed.append(len(angles)) or real(angles, search))
    got = obj.bounded(A, bound)
    assert posed == [int((~past).sum())]  # only the others are posed
    assert np.all(got[past] >= bound[past]) and np.all(got[past] <= exact[past] + 1e-12)
    below = ~past & (exact < bound)
    np.testing.assert_allclose(got[below], exact[below], rtol=1e-3)  # the search's pruned weights
    # with no pose that keeps the rules yet (an infinite bound), every pose is measured
    posed.clear()
    np.testing.assert_allclose(obj.bounded(A, np.full(24, np.inf)), exact, rtol=1e-3)
    assert posed == [24]


def test_a_turn_resting_on_less_than_the_bound_breaks_a_rule_and_standing_as_made_never_does(tpose_rig):
    """The footprint rule, against the first-layer section measured on its own."""
    from supportless.energies.footprint import footprint_area
    from supportless.search.orientation import rotation_between

    rig = tpose_rig
    rest = rig.rest_angles()[None]
    V = rig.pose(rest[0])
    on_back = rotation_between(np.array([0.0, 0.0, 1.0]), np.asarray(rig.up, float))[None]  # lying, face up
    area = float(footprint_area(V @ on_back[0].T, rig.faces, rig.up, 60.0 / np.ptp(V @ rig.up)))
    assert area > 0
    strict = sl.Objective(rig, footprint_mm2=4 * area)
    assert float(strict.footprint_shortfall(V[None], on_back)[0]) == pytest.approx(0.75)
    assert strict.terms(rest, on_back)["violation"][0] >= 0.75
    assert strict(rest, on_back)[0] > INFEASIBLE
    lenient = sl.Objective(rig, footprint_mm2=area / 2)
    assert lenient.terms(rest, on_back)["violation"][0] == 0
    # as the model stands it is never judged, whatever the bound; nor with the rule off
    assert strict.terms(rest)["violation"][0] == 0
    assert sl.Objective(rig, footprint_mm2=0).terms(rest, on_back)["violation"][0] == 0
    # the bound is at the printed size: twice as tall, the section (half a first layer up) in mm² of that size
    taller = sl.Objective(rig, footprint_mm2=4 * area, print_height_mm=120.0)
    area_120 = float(footprint_area(V @ on_back[0].T, rig.faces, rig.up, 120.0 / np.ptp(V @ rig.up)))
    assert taller.terms(rest, on_back)["violation"][0] == pytest.approx(max(0.0, 1 - area_120 / (4 * area)))
    # the search's bounded evaluation breaks the rule the same way, and its gate of would-be bests too
    assert strict.bounded(rest, np.array([np.inf]), on_back)[0] > INFEASIBLE
    assert not strict.rests(rest[0], on_back[0]) and lenient.rests(rest[0], on_back[0])
    assert strict.rests(rest[0], np.eye(3))  # upright: the model as it stands
    assert strict.terms(rest, np.eye(3)[None])["violation"][0] == 0
