"""A game-style character rig for speed benchmarks: 68 bones, a dense surface.

Real characters (a Mixamo or VRoid export) carry far more bones than the zoo's
figures: four per finger, toes, a spine in several parts, face joints. Most
of them move little of the body. :func:`character` builds such a rig
procedurally (no files, no network) so the speed of preparing and searching a
big rig is measured on something anyone can rebuild. It is not one of the
zoo's :data:`~supportless.shapes.DEMO_FIGURES`: those stay small so the test
suite and the zoo tables stay quick.
"""

from __future__ import annotations

import numpy as np

from .sdf import Body, cap, direction, ell, unit

__all__ = ["character"]

#: Finger lengths (metacarpal, proximal, middle, distal), thumb first.
_FINGERS = ((1.6, 1.5, 1.1, 0.9), (2.4, 1.6, 1.1, 0.9), (2.4, 1.8, 1.2, 0.9), (2.3, 1.7, 1.1, 0.9),
            (2.1, 1.3, 0.9, 0.8))


def _hand(body, side, wrist, along, forward):
    """A palm and five four-bone fingers from ``wrist`` along ``along``, the thumb towards ``forward``."""
    palm = body.joint(side + "_palm", wrist + 0.9 * along)
    body.bone(side + "_wrist", side + "_palm")
    body.add(cap(wrist, palm + 1.6 * along, 1.25, 1.15, 0.6))
    for k, lengths in enumerate(_FINGERS):
        if k == 0:  # the thumb leaves the palm forwards and out
            d = unit(0.55 * along + 0.85 * forward)
            base = palm + 0.6 * forward
        else:
            d = unit(along + 0.12 * (k - 2.5) * forward)
            base = palm + (0.75 - 0.5 * (k - 1)) * forward
        names = [side + "_palm"] + [f"{side}_f{k}_{i}" for i in range(1, 5)]
        ra, rb = (0.6, 0.55) if k == 0 else (0.5, 0.45)
        body.add(cap(base, base + lengths[0] * d, ra, rb, 0.25))
        body.joint(names[1], base + lengths[0] * d)  # the metacarpal bone runs from the palm joint
        for i, length in enumerate(lengths[1:], start=1):
            body.joint(names[i + 1], body[names[i]] + length * d)
        body.chain(names, (0.6, 0.55, 0.5, 0.45, 0.4) if k == 0 else (0.5, 0.45, 0.42, 0.38, 0.33), 0.25)


def character(seed=None, edge_length=0.7):
    """A standing character in an A-pose with hands, feet and face joints: 68 bones.

    Skeleton: hips, a two-part spine, neck, head (with a top, a jaw and two
    eyes), and on each side a clavicle, upper arm, forearm, palm, five fingers
    of four bones each, a pelvis bone, thigh, shin, foot and toes.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions (leg, torso and arm lengths, arm angle).
    edge_length : float
        Target edge length of the surface: 0.7 gives about 30 000 triangles
        on a figure about 55 units tall.

    Returns
    -------
    V : (n, 3) float64
    F : (f, 3) int64
    joints : (j, 3) float64
    bones : (68, 2) int64
        As :func:`~supportless.shapes.demo_figure` (up is ``+Y``).
    """
    body = Body(seed)
    p = body.vary
    leg, torso, arm, angle = p(1.0), p(1.0), p(1.0), p(35.0, 0.15)
    knee_y = 3.5 + 12.0 * leg
    hip_y = knee_y + 12.5 * leg
    hips = body.joint("hips", (0.0, hip_y + 2.0, 0.0))
    spine = body.joint("spine", hips + (0.0, 5.0 * torso, 0.0))
    chest = body.joint("chest", spine + (0.0, 5.0 * torso, 0.0))
    neck = body.joint("neck", chest + (0.0, 8.5 * torso, 0.0))
    head = body.joint("head", neck + (0.0, 6.0, 0.5))
    body.joint("head_top", head + (0.0, 3.5, 0.0))
    body.joint("jaw", head + (0.0, -1.8, 2.4))
    for s, x in (("l", 1.0), ("r", -1.0)):
        body.joint(s + "_eye", head + (1.4 * x, 0.6, 3.0))
    for a, b in (("hips", "spine"), ("spine", "chest"), ("chest", "neck"), ("neck", "head"), ("head", "head_top"),
                 ("head", "jaw"), ("head", "l_eye"), ("head", "r_eye")):
        body.bone(a, b)
    body.add(cap(hips, spine, 5.0, 5.2, 2.0),  # belly
             cap(spine, chest + (0.0, 3.0, 0.0), 5.2, 6.0, 2.5),  # chest
             cap(chest + (0.0, 5.5, 0.0), neck, 2.2, 2.0, 1.5),  # neck
             cap(head - (0.0, 0.8, 0.0), head + (0.0, 0.9, 0.0), 4.2, 4.0, 1.2),  # head
             ell(head + (0.0, -0.3, 3.9), (1.1, 1.1, 1.1), 0.4),  # nose
             cap(body["jaw"] - (0.0, 0.0, 1.5), body["jaw"], 2.6, 1.8, 1.2))  # chin
    forward = np.array([0.0, 0.0, 1.0])
    for s, x, azimuth in (("l", 1.0, 0.0), ("r", -1.0, 180.0)):
        clavicle = body.joint(s + "_clavicle", chest + (1.5 * x, 6.0 * torso, 0.5))
        shoulder = body.joint(s + "_shoulder", chest + (7.5 * x, 6.0 * torso, 0.0))
        d = direction(azimuth, -angle)
        elbow = body.joint(s + "_elbow", shoulder + 9.0 * arm * d)
        wrist = body.joint(s + "_wrist", elbow + 8.5 * arm * d)
        for a, b in (("chest", "_clavicle"), ("_clavicle", "_shoulder"), ("_shoulder", "_elbow"),
                     ("_elbow", "_wrist")):
            body.bone(a if a == "chest" else s + a, s + b)
        body.add(cap(clavicle, shoulder, 2.6, 3.0, 2.0),  # shoulder
                 cap(shoulder, elbow, 2.7, 2.1, 1.8),  # upper arm
                 cap(elbow, wrist, 2.1, 1.5, 0.8))  # forearm
        _hand(body, s, wrist, d, forward)
        hip = body.joint(s + "_hip", (4.0 * x, hip_y, 0.0))
        knee = body.joint(s + "_knee", (4.5 * x, knee_y, 0.5))
        ankle = body.joint(s + "_ankle", (5.0 * x, 3.5, 0.0))
        ball = body.joint(s + "_ball", (5.0 * x, 1.6, 4.0))
        body.joint(s + "_toe", (5.0 * x, 1.4, 6.5))
        for a, b in (("hips", "_hip"), ("_hip", "_knee"), ("_knee", "_ankle"), ("_ankle", "_ball"),
                     ("_ball", "_toe")):
            body.bone(a if a == "hips" else s + a, s + b)
        body.add(cap(hips, hip, 4.2, 4.2, 1.0),  # pelvis
                 cap(hip, knee, 3.8, 2.9, 2.0),  # thigh
                 cap(knee, ankle, 2.9, 2.1, 1.0),  # shin
                 cap(ankle + (0.0, -1.2, -1.0), ball, 2.3, 2.0, 1.5),  # foot
                 cap(ball, body[s + "_toe"], 2.0, 1.6, 0.8))  # toes
    return body.mesh(edge_length)
