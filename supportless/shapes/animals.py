"""Animal figures: ``quadruped``, ``bird`` and ``dragon``, all facing ``+Z``."""

from __future__ import annotations

import numpy as np

from .sdf import Body, box, cap, ell

__all__ = ["bird", "dragon", "quadruped"]


def _four_legs(body, p, size):
    """Four legs of three bones each (spine joint -> hip/shoulder -> knee/elbow -> paw), with paws on the plate.

    Parameters
    ----------
    body : Body
        Holds the joints ``hips`` and ``chest``.
    p : Proportions
    size : float
        Scale of the legs (1 for the dog).
    """
    for end, spine, knee_dz in (("f", "chest", 1.0), ("b", "hips", -2.0)):
        z = body[spine][2]
        length = p(1.0, 0.08)
        for s, x in (("l", 1.0), ("r", -1.0)):
            names = [f"{end}{s}_top", f"{end}{s}_knee", f"{end}{s}_paw"]
            body.joint(names[0], (3.8 * x * size, body[spine][1] - 1.5 * size, z))
            body.joint(names[1], (4.2 * x * size, 3.0 + 6.5 * size * length, z + knee_dz * size))
            paw = body.joint(names[2], (4.2 * x * size, 3.0, z + 0.5 * size))
            body.bone(spine, names[0])
            body.chain(names, (3.0 * size, 2.3 * size, 2.0 * size), (2.0, 1.0))
            body.add(cap(paw + (0.0, -1.8, -1.0), paw + (0.0, -1.8, 3.5 * size), 2.4, 2.2, 1.5))


def quadruped(seed=None):
    """A dog-like animal on four paws with a raised neck, head with ears and a tail held out.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions (body, leg, neck and tail lengths).

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (19, 3), (18, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    half, neck, tail = p(9.5), p(1.0), p(1.0)
    hips = body.joint("hips", (0.0, 18.0, -half))
    chest = body.joint("chest", (0.0, 19.0, half))
    body.bone("hips", "chest")
    body.add(cap(hips, chest, 5.5, 6.2, 0.0))
    _four_legs(body, p, 1.0)
    n = body.joint("neck", chest + np.multiply((0.0, 7.0, 6.0), neck))
    head = body.joint("head", n + (0.0, 4.0, 4.0))
    body.joint("nose", head + (0.0, -1.2, 6.0))
    body.chain(["chest", "neck", "head"], (3.9, 2.9, 2.7), (2.0, 1.5))
    body.chain(["head", "nose"], (2.6, 1.7), 1.5)
    body.add(ell(head + (0.0, 0.5, -0.5), (3.6, 3.4, 4.0), 1.0))
    for x in (1.0, -1.0):  # ears
        body.add(ell(head + (2.2 * x, 3.6, -1.0), (1.3, 2.4, 1.2), 0.8))
    t1 = body.joint("tail1", hips + np.multiply((0.0, 2.5, -7.0), tail))
    body.joint("tail2", t1 + np.multiply((0.0, 2.5, -8.0), tail))
    body.chain(["hips", "tail1", "tail2"], (2.1, 1.7, 1.5), (1.5, 0.5))
    return body.mesh(1.6)


def _wing(body, side, names, points, radii, chords, thickness):
    """A wing spread along ``side`` (+1 left, -1 right): a bone chain with a flat membrane (rounded slab) trailing behind each bone.

    Parameters
    ----------
    body : Body
        Holds ``names[0]``, the joint the wing hangs from.
    side : float
        +1 for the left wing (``+X``), -1 for the right one.
    names : sequence of str
        The wing's joints, the first already in ``body``.
    points : sequence of array_like
        Positions of ``names[1:]`` for the left wing, shape (3,) each; mirrored for the right.
    radii : sequence of float
        Capsule radius at each joint of the wing, ``len(names) - 1`` values (from ``names[1]``).
    chords : sequence of float
        Membrane half-depth behind each of the wing's bones after the first, ``len(names) - 2`` values.
    thickness : float
        Half-thickness of the membrane, a rounded slab.
    """
    mirror = np.array([side, 1.0, 1.0])
    for name, q in zip(names[1:], points):
        body.joint(name, mirror * np.asarray(q, dtype=np.float64))
    body.bone(names[0], names[1])
    body.chain(names[1:], radii, 1.0)
    for i, (a, b, chord) in enumerate(zip(names[1:], names[2:], chords)):
        # a slab with rounded edges (no thin rim to pinch); the first starts
        # clear of the body (no loop through it, no near-touching sheets), the
        # others overlap the one before
        inner, outer = body[a][0] + side * (2.0 if i == 0 else -1.0), body[b][0] + side
        centre = 0.5 * (body[a] + body[b]) + (0.0, -0.2, -0.6 * chord)
        centre[0] = 0.5 * (inner + outer)
        body.add(box(centre, (0.5 * abs(outer - inner), thickness, chord), 0.95 * thickness, 1.0))


def bird(seed=None):
    """A bird standing on two legs with its wings spread out sideways, head raised, tail out.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions (wing span, neck and leg lengths).

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (19, 3), (18, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    span, neck, leg = p(1.0), p(1.0), p(1.0, 0.08)
    lift = 4.0 * (leg - 1.0)
    hips = body.joint("hips", (0.0, 12.5 + lift, -2.0))
    chest = body.joint("chest", (0.0, 15.5 + lift, 4.0))
    body.bone("hips", "chest")
    body.add(ell((0.0, 14.0 + lift, 0.5), (5.5, 5.0, 8.5), 0.0))
    n = body.joint("neck", chest + np.multiply((0.0, 4.5, 3.5), neck))
    head = body.joint("head", n + (0.0, 4.0, 1.5))
    body.chain(["chest", "neck", "head"], (3.2, 2.2, 2.0), (1.5, 1.0))
    body.add(ell(head, (2.8, 2.8, 3.2), 1.0), cap(head + (0.0, -0.3, 2.5), head + (0.0, -0.8, 6.5), 1.4, 0.8, 0.6))
    tail = body.joint("tail", hips + (0.0, 1.5, -11.0))
    body.bone("hips", "tail")
    body.add(cap(hips, tail, 2.2, 1.6, 1.5), ell(tail + (0.0, 0.2, -1.0), (4.0, 1.5, 4.0), 0.8))
    for s, x in (("l", 1.0), ("r", -1.0)):
        body.joint(s + "_hip", (2.5 * x, 10.5 + lift, -0.5))
        body.joint(s + "_knee", (3.0 * x, 2.0 + 4.0 * leg, 1.5))
        ankle = body.joint(s + "_ankle", (3.0 * x, 2.0, 0.5))
        body.bone("hips", s + "_hip")
        body.chain([s + "_hip", s + "_knee", s + "_ankle"], (2.2, 1.6, 1.5), (1.5, 0.5))
        body.add(cap(ankle + (0.0, -1.1, -2.0), ankle + (0.0, -1.1, 4.0), 1.6, 1.4, 1.0))
        _wing(body, x, ["chest", s + "_shoulder", s + "_elbow", s + "_wrist", s + "_tip"],
              [(4.0, 17.0 + lift, 3.0), (4.0 + 9.0 * span, 18.0 + lift, 2.0),
               (4.0 + 18.0 * span, 19.5 + lift, 0.0), (4.0 + 27.0 * span, 20.5 + lift, -3.0)],
              (1.8, 1.5, 1.3, 1.0), (4.5, 4.0, 3.0), 1.5)
    return body.mesh(1.4)


def dragon(seed=None):
    """A four-legged dragon with spread wings, a raised neck, horns and a long tail.

    Parameters
    ----------
    seed : int, optional
        Varies the proportions (wing span, neck and tail lengths).

    Returns
    -------
    V, F, joints, bones : numpy.ndarray
        Shapes (n, 3), (f, 3), (25, 3), (24, 2), as :func:`~supportless.shapes.demo_figure`.
    """
    body = Body(seed)
    p = body.vary
    span, neck, tail = p(1.0), p(1.0), p(1.0)
    hips = body.joint("hips", (0.0, 21.0, -12.0))
    chest = body.joint("chest", (0.0, 22.0, 10.0))
    body.bone("hips", "chest")
    body.add(cap(hips, chest, 6.5, 7.2, 0.0))
    _four_legs(body, p, 1.3)
    n = body.joint("neck", chest + np.multiply((0.0, 9.0, 7.0), neck))
    head = body.joint("head", n + (0.0, 6.0, 4.0))
    body.chain(["chest", "neck", "head"], (4.5, 3.2, 3.0), (2.0, 1.5))
    body.add(ell(head, (3.8, 3.4, 4.8), 1.0), cap(head, head + (0.0, -1.5, 8.0), 2.8, 1.8, 1.2))
    for x in (1.0, -1.0):  # horns
        body.add(cap(head + (2.0 * x, 2.5, -1.5), head + (3.0 * x, 5.0, -6.0), 1.3, 1.0, 0.8))
    t = np.multiply((0.0, 1.0, -10.0), tail)
    body.joint("tail1", hips + t)
    body.joint("tail2", hips + 2.0 * t + (0.0, 0.5, 0.0))
    body.joint("tail3", hips + 3.0 * t + (0.0, 2.0, 1.0))
    body.chain(["hips", "tail1", "tail2", "tail3"], (3.8, 2.9, 2.2, 1.7), (1.5, 1.0, 0.8))
    for s, x in (("l", 1.0), ("r", -1.0)):
        _wing(body, x, ["chest", s + "_wing", s + "_welbow", s + "_wtip"],
              [(5.0, 27.0, 7.0), (5.0 + 11.0 * span, 29.0, 4.0), (5.0 + 25.0 * span, 30.5, -4.0)],
              (2.2, 1.9, 1.5), (5.5, 5.0), 1.9)
    return body.mesh(2.2)
