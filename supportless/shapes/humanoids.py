"""Humanoid figures: ``apose``, ``lying``, ``seated`` and ``staff``.

All share the skeleton of ``tpose`` (hips root, spine, neck/head,
clavicle-shoulder-elbow-wrist, pelvis-hip-knee-ankle) and the same skin of
capsules along it (:func:`humanoid_skin`); they differ in where the joints are.
"""

from __future__ import annotations

import numpy as np

from .sdf import Body, box, cap, direction, ell, unit

__all__ = ["apose", "humanoid_skin", "lying", "seated", "staff"]

#: The bones of every humanoid, by joint name.
HUMANOID_BONES = (
    ("hips", "chest"), ("chest", "neck"), ("neck", "head"),
    ("chest", "l_shoulder"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_wrist"),
    ("chest", "r_shoulder"), ("r_shoulder", "r_elbow"), ("r_elbow", "r_wrist"),
    ("hips", "l_hip"), ("l_hip", "l_knee"), ("l_knee", "l_ankle"),
    ("hips", "r_hip"), ("r_hip", "r_knee"), ("r_knee", "r_ankle"),
)


def _across(v, axis):
    """The part of ``facing`` ``v`` orthogonal to the unit ``axis``, normalised."""
    return unit(v - np.dot(v, axis) * axis)


def humanoid_skin(body, facing):
    """Add the humanoid bones and their skin to a body whose joints are placed.

    Parameters
    ----------
    body : Body
        Holds the joints named in :data:`HUMANOID_BONES`.
    facing : array_like, shape (3,)
        Where the face and the toes point.
    """
    J, facing = body.joints, unit(facing)
    for a, b in HUMANOID_BONES:
        body.bone(a, b)
    up_head = unit(J["head"] - J["neck"])
    face = _across(facing, up_head)
    body.add(
        cap(J["l_hip"], J["r_hip"], 4.2, 4.2, 0.0),  # pelvis
        cap(J["hips"], J["chest"], 5.0, 6.0, 2.5),  # belly and chest
        cap(J["l_shoulder"], J["r_shoulder"], 3.0, 3.0, 2.0),  # shoulders
        cap(0.5 * (J["l_shoulder"] + J["r_shoulder"]), J["neck"], 2.2, 2.0, 1.5),  # neck
        cap(J["head"] - 0.8 * up_head, J["head"] + 0.9 * up_head, 4.2, 4.0, 1.2),  # head
        ell(J["head"] - 0.3 * up_head + 3.9 * face, (1.1, 1.1, 1.1), 0.4),  # nose
    )
    for s in "lr":
        shoulder, elbow, wrist = J[s + "_shoulder"], J[s + "_elbow"], J[s + "_wrist"]
        hip, knee, ankle = J[s + "_hip"], J[s + "_knee"], J[s + "_ankle"]
        shin = unit(ankle - knee)
        toe = _across(facing, shin)
        body.add(
            cap(shoulder, elbow, 2.7, 2.1, 1.8),  # upper arm
            cap(elbow, wrist, 2.1, 1.7, 0.8),  # forearm
            cap(wrist, wrist + 2.6 * unit(wrist - elbow), 1.9, 1.6, 1.0),  # hand
            cap(hip, knee, 3.8, 2.9, 2.0),  # thigh
            cap(knee, ankle, 2.9, 2.1, 1.0),  # shin
            cap(ankle + 2.3 * shin - 1.0 * toe, ankle + 2.3 * shin + 5.0 * toe, 2.5, 2.2, 2.0),  # foot
        )


def _standing(seed):
    """A body with the legs, torso and head of a standing humanoid facing ``+Z`` (no arms yet)."""
    body = Body(seed)
    leg, torso = body.vary(1.0), body.vary(1.0)
    knee_y = 3.5 + 12.0 * leg
    hip_y = knee_y + 12.5 * leg
    hips = body.joint("hips", (0.0, hip_y + 2.0, 0.0))
    chest = body.joint("chest", hips + (0.0, 10.0 * torso, 0.0))
    body.joint("neck", chest + (0.0, 8.5 * torso, 0.0))
    body.joint("head", chest + (0.0, 8.5 * torso + 6.0, 0.5))
    for s, x in (("l", 1.0), ("r", -1.0)):
        body.joint(s + "_shoulder", chest + (7.5 * x, 6.0 * torso, 0.0))
    for s, x in (("l", 1.0), ("r", -1.0)):
        body.joint(s + "_hip", (4.0 * x, hip_y, 0.0))
        body.joint(s + "_knee", (4.5 * x, knee_y, 0.5))
        body.joint(s + "_ankle", (5.0 * x, 3.5, 0.0))
    return body


def apose(seed=None):
    """Humanoid standing upright with its arms held 35 degrees below horizontal.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions (leg, torso and arm lengths, arm angle).

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (16, 3), (15, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = _standing(seed)
    p = body.vary
    arm, angle = p(1.0), p(35.0, 0.15)
    for s, azimuth in (("l", 0.0), ("r", 180.0)):
        d = direction(azimuth, -angle)
        elbow = body.joint(s + "_elbow", body[s + "_shoulder"] + 9.0 * arm * d)
        body.joint(s + "_wrist", elbow + 8.5 * arm * d)
    humanoid_skin(body, (0.0, 0.0, 1.0))
    return body.mesh(2.0)


def staff(seed=None):
    """Humanoid standing upright holding a long staff horizontally in front of it.

    The staff passes through both fists; its two bones (to either end) hang
    from a grip joint in the right hand.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions (leg and torso lengths, staff length).

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (19, 3), (18, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = _standing(seed)
    p = body.vary
    half = p(30.0)
    for s, x in (("l", 1.0), ("r", -1.0)):
        shoulder = body[s + "_shoulder"]
        elbow = body.joint(s + "_elbow", shoulder + (4.0 * x, -8.0, 2.5))
        body.joint(s + "_wrist", elbow + (-4.5 * x, 1.0, 8.0))
    wrist, elbow = body["r_wrist"], body["r_elbow"]
    grip = body.joint("r_grip", wrist + 1.8 * unit(wrist - elbow))
    body.joint("staff_r", (-half, grip[1], grip[2]))
    body.joint("staff_l", (half, grip[1], grip[2]))
    humanoid_skin(body, (0.0, 0.0, 1.0))
    body.bone("r_wrist", "r_grip")
    body.bone("r_grip", "staff_r")
    body.bone("r_grip", "staff_l")
    body.add(cap(body["staff_r"] - (1.0, 0.0, 0.0), body["staff_l"] + (1.0, 0.0, 0.0), 1.5, 1.5, 0.6))
    return body.mesh(1.8)


def lying(seed=None):
    """Humanoid lying on its back along ``+X``, head, arms and legs raised.

    The back and the buttocks rest on the plate; the head is lifted off it,
    the arms reach up towards the feet and the straight legs are raised.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions and how far the head, arms and legs are raised.

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (16, 3), (15, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    torso, leg, arm = p(1.0), p(1.0), p(1.0)
    hips = body.joint("hips", (0.0, 4.8, 0.0))
    chest = body.joint("chest", hips + (-10.5 * torso, 0.4, 0.0))
    neck = body.joint("neck", chest + (-7.5 * torso, 1.2, 0.0))
    body.joint("head", neck + 6.0 * direction(180.0, p(35.0, 0.2)))
    arm_dir, leg_dir = p(40.0, 0.2), p(20.0, 0.2)
    for s, z in (("l", -1.0), ("r", 1.0)):
        shoulder = body.joint(s + "_shoulder", chest + (-5.0 * torso, 0.6, 7.5 * z))
        d = direction(-20.0 * z, arm_dir)
        elbow = body.joint(s + "_elbow", shoulder + 9.0 * arm * d)
        body.joint(s + "_wrist", elbow + 8.5 * arm * d)
        hip = body.joint(s + "_hip", hips + (1.5, 0.0, 4.6 * z))
        d = direction(-6.0 * z, leg_dir)
        knee = body.joint(s + "_knee", hip + 12.5 * leg * d)
        body.joint(s + "_ankle", knee + 12.0 * leg * d)
    humanoid_skin(body, (0.0, 1.0, 0.0))
    return body.mesh(1.8)


def seated(seed=None):
    """Humanoid sitting on a block, feet on the plate, arms held out forward.

    The block is part of the mesh, and its bone (from the block's base up to
    the hips) is the root of the skeleton.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions (block height, thigh, torso and arm lengths).

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (17, 3), (16, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    seat, thigh, torso, arm = p(13.0), p(12.0), p(1.0), p(1.0)
    base = body.joint("base", (0.0, 2.0, -2.0))
    hips = body.joint("hips", (0.0, seat + 3.5, -2.0))
    chest = body.joint("chest", hips + (0.0, 10.0 * torso, -0.5))
    body.joint("neck", chest + (0.0, 8.5 * torso, 0.0))
    body.joint("head", chest + (0.0, 8.5 * torso + 6.0, 0.5))
    for s, x in (("l", 1.0), ("r", -1.0)):
        shoulder = body.joint(s + "_shoulder", chest + (7.5 * x, 6.0 * torso, 0.0))
        elbow = body.joint(s + "_elbow", shoulder + (1.0 * x, -0.5, 9.0 * arm))
        body.joint(s + "_wrist", elbow + (-0.5 * x, 0.0, 8.5 * arm))
        hip = body.joint(s + "_hip", (4.0 * x, seat + 2.5, -1.0))
        knee = body.joint(s + "_knee", hip + (0.5 * x, 0.0, thigh))
        body.joint(s + "_ankle", (knee[0] + 0.5 * x, 3.5, knee[2] + 1.0))
    body.bone("base", "hips")
    body.add(box((base[0], 0.5 * (seat - 1.0), base[2]), (8.0, 0.5 * (seat + 1.0), 7.0), 1.5, 0.0))
    humanoid_skin(body, (0.0, 0.0, 1.0))
    return body.mesh(1.9)
