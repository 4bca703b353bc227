"""The last gate (:func:`supportless.search.result.as_written`): what goes to the file never intersects itself more than rest."""

from __future__ import annotations

import dataclasses

import numpy as np

import supportless as sl
from supportless.base.geometry import place_on_plate, print_pose
from supportless.copyleft.cgal import intersecting_face_pairs, self_intersects
from supportless.search.result import as_written, measured_at


def intersecting_pose(rig, rng):
    """A pose of ``rig`` whose surface crosses itself (large random turns until one does)."""
    for _ in range(200):
        angles = rng.uniform(-2.5, 2.5, (rig.bone_count, 3))
        if self_intersects(rig.pose(angles), rig.faces):
            return angles
    raise AssertionError("no intersecting pose found")


def test_a_found_pose_that_intersects_as_written_gives_way_to_the_rest_pose(tpose_rig):
    rig = tpose_rig
    found = sl.optimize(rig, particles=6, iterations=2, seed=0)
    assert found.stats["written_pairs"] == 0 and "fell_back_to_rest" not in found.stats
    bad_angles = intersecting_pose(rig, np.random.default_rng(1))
    bad = measured_at(rig, found, bad_angles, found.rotation)
    gated = as_written(rig, bad)
    assert gated.stats["fell_back_to_rest"] == intersecting_face_pairs(bad.print_vertices, rig.faces) > 0
    np.testing.assert_array_equal(gated.angles, 0.0)
    assert gated.stats["written_pairs"] == intersecting_face_pairs(gated.print_vertices, rig.faces) == 0
    # the rest pose as written: turned only when turning lowers the objective
    upright = measured_at(rig, found, np.zeros_like(bad_angles), np.eye(3))
    turned = measured_at(rig, found, np.zeros_like(bad_angles), bad.rotation)
    assert gated.value == min(upright.value, turned.value)


def test_the_gate_judges_the_written_mesh_not_the_pose_it_came_from(tpose_rig):
    """A result whose pose is clean but whose mesh as written (here: a proxy's, moved) crosses itself is refused."""
    rig = tpose_rig
    found = sl.optimize(rig, particles=6, iterations=2, seed=0)
    crossing = place_on_plate(rig.pose(intersecting_pose(rig, np.random.default_rng(2))), rig.up)
    assert not self_intersects(rig.pose(found.angles), rig.faces)
    written = dataclasses.replace(found, print_vertices=print_pose(crossing, found.rotation, rig.up))
    gated = as_written(rig, written)
    assert gated.stats["fell_back_to_rest"] > 0 and np.all(gated.angles == 0.0)


def test_without_exact_checks_the_result_is_left_as_it_is(tpose_rig):
    found = sl.optimize(tpose_rig, particles=6, iterations=2, seed=0, exact_intersections=False)
    assert "written_pairs" not in found.stats
