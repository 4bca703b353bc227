"""Built-in rigged demo figures, generated procedurally (no files, no network).

Every figure is returned as ``(V, F, joints, bones)``:

* 3D figures are closed, outward-oriented, 2-manifold triangle meshes without
  self-intersections, built as the zero level set of a smooth signed distance
  field (smooth union of tapered capsules, ellipsoids and rounded boxes, see
  :mod:`supportless.shapes.sdf`) with :meth:`manifold3d.Manifold.level_set`,
  then cut flat at ``y = 0`` so they rest on the build plate.
* The 2D figure (``woody2d``) is a constrained quality triangulation of a
  stick-figure outline (:mod:`supportless.shapes.classic`).

Skeleton convention: ``joints`` is ``(j, d)`` float64; ``bones`` is ``(m, 2)``
int64, each row ``[root joint, tip joint]``; a bone rotates about its root
joint and its parent is the bone whose tip is its root.  The printing
direction is ``+Y``.

The figures live in :mod:`~supportless.shapes.classic` (``tpose``, ``branch``,
``woody2d``), :mod:`~supportless.shapes.humanoids` (``apose``, ``lying``,
``seated``, ``staff``), :mod:`~supportless.shapes.animals` (``quadruped``,
``bird``, ``dragon``) and :mod:`~supportless.shapes.chains` (``arm``, ``tree``,
``hand``, ``tentacle``).  The builders of the new figures take an optional
``seed`` that varies their proportions; :func:`demo_figure` uses the default.
:mod:`~supportless.shapes.character` builds the 68-bone, dense character of
``supportless bench --targets``; it is not one of the zoo's figures.
"""

from __future__ import annotations

import functools

import numpy as np

from . import animals, chains, classic, humanoids

__all__ = ["DEMO_FIGURES", "demo_figure"]

_BUILDERS = {
    "tpose": classic.tpose,
    "branch": classic.branch,
    "woody2d": classic.woody2d,
    "apose": humanoids.apose,
    "quadruped": animals.quadruped,
    "lying": humanoids.lying,
    "seated": humanoids.seated,
    "arm": chains.arm,
    "tree": chains.tree,
    "hand": chains.hand,
    "bird": animals.bird,
    "tentacle": chains.tentacle,
    "dragon": animals.dragon,
    "staff": humanoids.staff,
}

DEMO_FIGURES: tuple[str, ...] = tuple(_BUILDERS)


@functools.lru_cache(maxsize=None)
def _cached(name):
    """The built figure ``name``, built once per process, as read-only arrays."""
    V, F, joints, bones = _BUILDERS[name]()
    for a in (V, F, joints, bones):
        a.setflags(write=False)
    return V, F, joints, bones


def demo_figure(name):
    """Build one of the built-in rigged demo figures.

    Parameters
    ----------
    name : str
        One of :data:`DEMO_FIGURES`:

        ``"tpose"``
            A humanoid standing on flat feet with both arms held out
            horizontally; 16 joints, 15 bones (hips root, spine, neck/head,
            clavicle-shoulder-elbow-wrist, pelvis-hip-knee-ankle); about 3500
            faces.
        ``"branch"``
            An upright post with one horizontal cantilevered arm; 4 joints,
            3 bones; under 1500 faces.
        ``"woody2d"``
            A planar stick figure (body, head, horizontal arms, legs) as a 2D
            triangle mesh with counter-clockwise triangles and vertices exactly
            at every joint and at 5 interior samples along every bone; 12
            joints, 11 bones.
        ``"apose"``
            The humanoid with its arms 35 degrees below horizontal; 15 bones.
        ``"quadruped"``
            A dog-like animal on four paws with a raised neck, a head looking
            forward and a tail held out behind; 18 bones.
        ``"lying"``
            A humanoid lying on its back (the back flat on the plate) with its
            head, arms and legs raised; 15 bones.
        ``"seated"``
            A humanoid sitting on a block (part of the mesh; its bone is the
            skeleton's root), feet on the plate, arms held out forward; 16 bones.
        ``"arm"``
            An arm propped on the plate by its flat hand, the forearm rising
            from it and the upper arm reaching back over the hand to a raised
            shoulder (the centre of mass stays over the hand); a chain of 4
            bones (upper arm, forearm, palm, fingers).
        ``"tree"``
            A tree on a flared trunk with three levels of branches; 13 bones.
        ``"hand"``
            A hand standing on its wrist, fingers up and curled forward, the
            thumb out to the side; 16 bones.
        ``"bird"``
            A bird standing on two legs with its wings spread out sideways, a
            raised head and a tail; 18 bones.
        ``"tentacle"``
            A tapering tentacle rising from a round base in an S-curve whose
            tip curls over; 8 bones.
        ``"dragon"``
            A four-legged dragon with spread wings, a raised neck and a long
            tail; 24 bones.
        ``"staff"``
            A standing humanoid holding a long staff horizontally in front of
            it with both hands (the staff's two bones hang from the right
            hand); 18 bones.

    Returns
    -------
    V : numpy.ndarray, shape (n, d), dtype float64
        Vertex positions, ``d = 3`` (or ``d = 2`` for ``woody2d``); ``+Y`` is up
        and the lowest point is at ``y = 0``.
    F : numpy.ndarray, shape (f, 3), dtype int64
        Triangles: outward-oriented closed surface in 3D, counter-clockwise
        triangles in 2D.
    joints : numpy.ndarray, shape (j, d), dtype float64
        Joint positions, all strictly inside the shape.
    bones : numpy.ndarray, shape (m, 2), dtype int64
        ``[root joint, tip joint]`` per bone; the bones form a tree.

    Raises
    ------
    KeyError
        If ``name`` is not a known figure.

    Notes
    -----
    Generation is deterministic; results are cached and fresh writable copies
    are returned on every call.
    """
    if name not in _BUILDERS:
        raise KeyError(f"unknown demo figure {name!r}; choose from {DEMO_FIGURES}")
    return tuple(np.array(a, copy=True) for a in _cached(name))
