"""Chains and trees of bones rooted on the plate: ``arm``, ``tree``, ``hand`` and ``tentacle``."""

from __future__ import annotations

import math

import numpy as np

from .sdf import Body, box, cap, direction, ell

__all__ = ["arm", "hand", "tentacle", "tree"]


def arm(seed=None):
    """An arm propped on the plate by its flat hand, the shoulder end raised over it.

    A chain of 4 bones: upper arm, forearm, palm and fingers. The hand (palm,
    fingers and thumb) lies flat on the plate, the forearm rises from it, and
    the upper arm reaches back over the hand, nearly horizontal, to a shoulder
    ball: both overhang the plate, and the centre of mass stays over the hand.

    Parameters
    ----------
    seed : int, optional
        Varies the lengths and the upper arm's slope.

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (5, 3), (4, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    wrist = np.array([24.0, 4.5, 0.0])
    elbow = wrist + p(15.0) * direction(180.0, 85.0)
    shoulder = body.joint("shoulder", elbow + p(13.6) * direction(0.0, p(12.0, 0.3)))
    body.joint("elbow", elbow)
    body.joint("wrist", wrist)
    body.joint("knuckles", (31.0, 2.2, 0.0))
    body.joint("tips", (36.5, 1.5, 0.0))
    body.add(ell(shoulder + (1.0, 0.0, 0.0), (5.5, 5.0, 5.0), 0.0))
    body.chain(["shoulder", "elbow", "wrist"], (4.3, 3.3, 2.4), (2.0, 1.2))
    body.bone("wrist", "knuckles")
    body.bone("knuckles", "tips")
    body.add(ell((28.0, 1.6, 0.0), (5.5, 2.3, 4.2), 1.5),  # palm
             ell((35.5, 1.3, 0.0), (3.5, 1.6, 3.6), 0.8),  # fingers
             cap((27.0, 1.8, 3.5), (31.0, 1.5, 6.0), 1.3, 1.1, 0.8))  # thumb
    return body.mesh(1.2)


def tree(seed=None):
    """A tree on a flared trunk: three branches that fork in two, and a leader that forks on top.

    Parameters
    ----------
    seed : int, optional
        Varies the branch lengths and angles.

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (14, 3), (13, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    body.joint("root", (0.0, 1.5, 0.0))
    fork = body.joint("fork", (0.0, p(14.0), 0.0))
    body.add(ell((0.0, 0.5, 0.0), (6.5, 3.0, 6.5), 0.0))
    body.chain(["root", "fork"], (3.4, 2.6), 2.5)
    for i in range(3):
        azimuth = 90.0 + 120.0 * i + p(10.0, 1.0)
        b = body.joint(f"branch{i}", fork + p(11.0) * direction(azimuth, p(30.0, 0.3)))
        body.chain(["fork", f"branch{i}"], (2.4, 1.8), 1.5)
        for j, (turn, rise) in enumerate(((30.0, 10.0), (-30.0, 55.0))):
            body.joint(f"twig{i}{j}", b + p(8.0) * direction(azimuth + turn, p(rise, 0.3)))
            body.chain([f"branch{i}", f"twig{i}{j}"], (1.7, 1.3), 1.0)
    top = body.joint("top", fork + (0.0, p(12.0), 0.0))
    body.chain(["fork", "top"], (2.4, 1.8), 1.5)
    for j, azimuth in enumerate((30.0, 210.0)):
        body.joint(f"crown{j}", top + p(7.0) * direction(azimuth, p(45.0, 0.3)))
        body.chain(["top", f"crown{j}"], (1.7, 1.3), 1.0)
    return body.mesh(1.3)


def hand(seed=None):
    """A hand standing on its wrist, fingers up and curled forward, the thumb out to the side.

    Parameters
    ----------
    seed : int, optional
        Varies the finger lengths, spread and curl.

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (17, 3), (16, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    body.joint("root", (0.0, 1.5, 0.0))
    body.joint("wrist", (0.0, 9.0, 0.0))
    body.add(cap((0.0, -1.0, 0.0), (0.0, 9.0, 0.0), 4.6, 4.0, 0.0),  # forearm stub
             box((0.0, 15.5, 0.0), (6.8, 6.5, 2.6), 2.0, 2.0))  # palm
    body.bone("root", "wrist")
    curl = p(55.0, 0.25)
    for i, (x, spread, length) in enumerate(zip((5.25, 1.75, -1.75, -5.25), (-20.0, -7.0, 7.0, 20.0), (6.0, 7.0, 6.5, 5.5))):
        names = [f"knuckle{i}", f"middle{i}", f"tip{i}"]
        a = math.radians(p(spread, 0.3))
        knuckle = body.joint(names[0], (x, 20.5, 0.0))
        middle = body.joint(names[1], knuckle + p(length) * _finger(a, math.radians(15.0)))
        body.joint(names[2], middle + p(4.5) * _finger(a, math.radians(curl)))
        body.bone("wrist", names[0])
        body.chain(names, (1.5, 1.35, 1.15), (1.0, 0.3))
    thumb = ["thumb0", "thumb1", "thumb2"]
    for name, q in zip(thumb, ((-5.5, 12.0, 1.5), (-10.0, 16.0, 3.0), (-13.0, 19.5, 4.5))):
        body.joint(name, q)
    body.bone("wrist", "thumb0")
    body.chain(thumb, (1.9, 1.6, 1.3), 0.8)
    body.add(cap(body["wrist"], body["thumb0"], 2.2, 1.9, 1.5))
    return body.mesh(1.0)


def _finger(spread, curl):
    """Unit direction of a finger segment: ``spread`` radians sideways from ``+Y`` towards ``-X``, ``curl`` towards ``+Z``."""
    return np.array([-math.sin(spread) * math.cos(curl), math.cos(spread) * math.cos(curl), math.sin(curl)])


def tentacle(seed=None):
    """A tapering tentacle rising from a round base in an S-curve, its tip curling over.

    Parameters
    ----------
    seed : int, optional
        Varies the segment lengths and the bends.

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (9, 3), (8, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    bends = (0.0, 20.0, 45.0, 60.0, 40.0, -10.0, -50.0, -80.0)
    names = [f"t{i}" for i in range(len(bends) + 1)]
    q = body.joint(names[0], (0.0, 1.5, 0.0))
    for i, bend in enumerate(bends):
        twist = math.radians(4.0 * i)
        tilt = math.radians(p(bend, 0.15))
        d = np.array([math.sin(tilt) * math.cos(twist), math.cos(tilt), math.sin(tilt) * math.sin(twist)])
        q = body.joint(names[i + 1], q + p(5.5, 0.08) * d)
    body.add(ell((0.0, 0.5, 0.0), (7.0, 3.0, 7.0), 0.0))
    body.chain(names, np.linspace(4.2, 1.3, len(names)), 1.5)
    return body.mesh(1.2)
