"""The combined, normalised objective."""

import numpy as np
import pytest

import supportless as sl


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    return sl.load_rig("demo:branch", cache_dir=tmp_path_factory.mktemp("cache"))


def random_angles(rig, P, scale=0.4, seed=0):
    return np.random.default_rng(seed).uniform(-scale, scale, (P, rig.bone_count, 3))


def test_terms_shapes_and_batch_equals_single(rig):
    obj = sl.Objective(rig)
    A = random_angles(rig, 5)
    terms = obj.terms(A)
    assert set(terms) == {"arap", "overhang", "intersection"}
    for v in terms.values():
        assert v.shape == (5,)
    values = obj(A)
    singles = np.array([float(obj(a)) for a in A])
    np.testing.assert_allclose(values, singles, rtol=1e-10, atol=1e-14)


def test_rest_pose_terms(rig):
    obj = sl.Objective(rig)
    t = obj.terms(rig.rest_angles())
    assert abs(float(t["arap"])) < 1e-10
    assert np.isclose(float(t["overhang"]), 1.0)  # normalised by the rest value
    assert float(t["intersection"]) == 0.0
    assert np.isclose(float(obj(rig.rest_angles())), obj.w_overhang)


def test_weighted_sum(rig):
    A = random_angles(rig, 3, seed=1)
    obj = sl.Objective(rig, w_arap=2.0, w_overhang=3.0, w_intersect=5.0)
    t = obj.terms(A)
    np.testing.assert_allclose(obj(A), 2 * t["arap"] + 3 * t["overhang"] + 5 * t["intersection"])


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
    if roots.sum() != 1:
        pytest.skip("figure has several root bones, whose joints differ: not a rigid motion")
    A[0, roots] = [0.3, -0.2, 0.5]
    assert float(obj.terms(A)["arap"][0]) < 1e-9


def test_column_model_option(rig):
    obj = sl.Objective(rig, overhang_model="column")
    assert np.isclose(float(obj.terms(rig.rest_angles())["overhang"]), 1.0)
    with pytest.raises(ValueError):
        sl.Objective(rig, overhang_model="cone")


def test_bounded_is_exact_below_the_bound_and_never_below_it_elsewhere(rig):
    obj = sl.Objective(rig)
    A = random_angles(rig, 40, scale=1.2, seed=7)
    exact = obj(A)
    bound = np.where(np.arange(40) % 2 == 0, np.inf, np.median(exact))
    got = obj.bounded(A, bound)
    below = exact < bound
    np.testing.assert_allclose(got[below], exact[below], rtol=1e-12)
    assert np.all(got[~below] >= bound[~below])
    assert np.all(got <= exact + 1e-12)  # a lower bound everywhere
