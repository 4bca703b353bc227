"""What the pose search minimises: a weighted, normalised sum of energies, and hard rules.

``E = w_arap * E_arap / vol + w_overhang * E_overhang / S_rest + w_intersect * E_intersect / vol
+ w_prior * E_prior``, plus ``INFEASIBLE + violation`` for a pose that breaks a hard rule.

* ``vol`` is the rest volume of the model (area in 2D). ``E_arap`` and
  ``E_intersect`` scale like a volume (s³ in 3D, s² in 2D), so dividing by
  ``vol`` makes them dimensionless: the ARAP term becomes a mean squared strain,
  the intersection term the fraction of the body that overlaps itself.
* ``S_rest`` is the overhang (support) estimate of the rest pose, floored at
  ``1e-3 * vol`` so an already printable model does not divide by zero. The
  overhang term is then 1.0 at the rest pose and 0.6 for a pose needing 40 %
  less support.

* ``E_prior`` is the natural-pose prior (:mod:`supportless.search.prior`): squared
  joint angles weighted by the share of the body each joint turns.
* The hard rules: every joint within its limit (one angle), and the pose
  stands as the rest pose stood (:mod:`supportless.search.standing`). ``violation``
  measures how far a pose breaks them (0 when it keeps them).

All normalised terms are invariant to the model's scale and units, so the
same default weights work for a 6 cm and a 6 m model and for planar figures.
"""

from __future__ import annotations

import dataclasses
from functools import cached_property

import numpy as np

from ..base.geometry import signed_volume
from ..base.kinematics import lbs_operator, pruned_weights, skin
from ..copyleft.cgal import intersecting_faces
from ..energies import arap as arap_mod
from ..energies.footprint import footprint_area
from ..energies.intersection import DEFAULT_RESOLUTION, self_intersection_volume
from ..energies.overhang import overhang_energy
from ..energies.slicer_model import predicted_support_mm
from ..energies.support import support_volume
from ..files.printer import SEARCH_OVERHANG_ANGLE
from ..files.printframe import REFERENCE_HEIGHT_MM
from ..rig.contact import ContactRules, RefusedCrossings
from ..rig.rig import Rig
from .anatomy import JointRanges
from .naturalness import chain_ends, head_bones, rotation_angle_deg
from .prior import PosePrior
from .relaxed import ArmDrops, arms_above, without_drop
from .standing import Standing
from .weights import (CHAIN_LIMIT, FOOTPRINT_MM2, HEAD_LIMIT, JOINT_LIMIT, W_ARAP, W_CHAIN, W_CONTACT, W_INTERSECT,
                      W_OVERHANG, W_PRIOR)

__all__ = ["CHAIN_LIMIT", "FOOTPRINT_MM2", "HEAD_LIMIT", "INFEASIBLE", "INTERSECT_MOST", "JOINT_LIMIT", "OVERHANG_MODELS",
           "Objective", "POSE_CHUNK", "SEARCH_WEIGHT_FLOOR", "W_ARAP", "W_INTERSECT", "W_CHAIN", "W_OVERHANG", "W_PRIOR"]

#: The search measures the self-intersection of the poses that could become the swarm's best this many at a time,
#: the least costly by the other terms first (:meth:`Objective.bounded_overlap`): after each group, a pose whose
#: other terms cost more than the least total measured is not measured.
INTERSECT_CHUNK = 4

#: At most this many poses of a batch are measured so. Without a cap, a swarm gathered where a limb rests on the
#: body (the allowed contact costing a few percent) had every pose of that band measured: half the Xbot's search.
INTERSECT_MOST = 8

#: Added to the value of a pose that breaks a hard rule (joint limit, standing):
#: larger than any pose that keeps them can cost.
INFEASIBLE = 1e3

OVERHANG_MODELS = ("prism", "column", "slicer")

#: The search's skinning drops weights below this (:func:`supportless.base.kinematics.pruned_weights`,
#: :meth:`Objective.bounded` only): on the zoo, the bunny and a 68-bone character, random poses within 40° then
#: move no vertex by more than 0.012 % of the model's height; the search's skinning took 1.5x (bunny) to 4.6x
#: (68-bone character) less time.
SEARCH_WEIGHT_FLOOR = 1e-4

#: :meth:`Objective.bounded` measures larger batches in chunks of this many poses: the default swarm (200)
#: in one; a swarm of 5000 on the bunny peaks at 298 MB instead of 1059 MB (``benchmarks/memory.py``).
POSE_CHUNK = 256

#: ... and any batch in chunks of at most this many posed vertices (:meth:`Objective.raw_terms` too): a dense
#: surface's poses are measured a few at a time (the bunny subdivided four times, 891 648 vertices: 8 poses,
#: 190 MB of posed vertices), the 111 456-triangle bunny's 143 at a time, smaller rigs as before.
POSED_VERTICES = 8_000_000

#: Printed height (mm) at which the ``slicer`` overhang model measures a pose (as the report does).
SLICER_MODEL_HEIGHT_MM = REFERENCE_HEIGHT_MM


def distortion(terms: dict, w_arap: float, w_prior: float):
    """The distortion part of an objective: ``w_arap * arap + w_prior * prior``.

    Parameters
    ----------
    terms : dict
        Normalised terms (:meth:`Objective.terms`), ``"arap"`` and ``"prior"``
        each a float or ``(P,) float64``.
    w_arap, w_prior : float
        Their weights.

    Returns
    -------
    distortion : float or (P,) float64
    """
    return w_arap * terms["arap"] + w_prior * terms["prior"]


class Objective:
    """Weighted sum of the normalised ARAP, overhang and self-intersection energies.

    The defaults are the tool's (the named constants of this module, which
    :class:`~supportless.search.settings.SearchSettings` takes too): ``Objective(rig)`` is
    ``SearchSettings().objective(rig)`` but for the rules read from the rig's bone names, which the settings add
    with their ``anatomy``, ``contact`` and ``relaxed`` on and this leaves out unless given: ``joint_ranges``,
    ``contact``, ``drops``, and a named upper arm's wider ``joint_limits``
    (:meth:`~supportless.search.settings.SearchSettings.joint_limits`). For a rig without named bones (a TGF
    skeleton) that is no difference but ``contact``. Pass ``joint_limits=180.0, chain_limit=None,
    head_limit=None, footprint_mm2=None, w_chain=0.0`` for an objective without the naturalness rules.

    Parameters
    ----------
    rig : Rig
    w_arap, w_overhang, w_intersect : float
        Weights of the normalised terms.
    overhang_angle : float
        Threshold slope in degrees from the build plate (45 = the usual slicer
        default).
    overhang_model : {"prism", "column", "slicer"}
        ``prism``: the paper's per-face prism estimate. ``column``: support
        columns cast down to the plate or the body below
        (:func:`supportless.energies.support.support_volume`). ``slicer``:
        PrusaSlicer's support filament as the fitted slicer model predicts it
        at 60 mm tall (:mod:`supportless.energies.slicer_model`; 3D only).
    clusters : int or None
        Rotation clusters of the reduced ARAP energy (None = one per element).
    resolution : int
        Ray-grid resolution of the intersection (and column) estimate.
    backend : {"fast", "numpy"}
        ``fast``: numba kernels, parallel over poses; ``numpy``: the plain
        numpy implementations of the energies (slow; the reference).
    arap_data : supportless.energies.arap.ArapData, optional
        Precomputed reduced ARAP operators of this rig (with these
        ``clusters``), to share between objectives; computed on first use
        otherwise.
    w_prior : float
        Weight of the natural-pose prior (:meth:`supportless.search.prior.PosePrior.cost`).
    joint_limits : float or (m,) float64
        Largest rotation of each joint, degrees (one angle, see
        :mod:`supportless.search.prior`); a pose past a limit does not count.
        Default :data:`JOINT_LIMIT`.
    keep_standing : bool
        A pose that touches the plate with a new part or falls over does not
        count (:class:`supportless.search.standing.Standing`).
    support_floor : float
        Fixed cost of support however low it is, as a height added to every
        prism, in units of the model's rest height (the ``prism`` model).
    joint_ranges : supportless.search.anatomy.JointRanges, optional
        The ranges of motion of the named joints (:func:`supportless.search.anatomy.joint_ranges`): a
        pose with a joint outside its range (a knee bent backwards) does not count.
    chain_limit, head_limit : float, optional
        Largest world turn from rest of a chain end (:func:`supportless.search.naturalness.chain_ends`) and of
        a head (:func:`supportless.search.naturalness.head_bones`), degrees: a pose past one does not count
        (None: no such rule). Default :data:`CHAIN_LIMIT` and :data:`HEAD_LIMIT`.
    w_chain : float
        Weight of the chain ends' squared world turn in the prior (:meth:`prior_cost`); default :data:`W_CHAIN`.
    footprint_mm2 : float, optional
        Least first-layer contact of a turned print, mm² at ``print_height_mm`` tall (:meth:`footprint_shortfall`);
        default :data:`FOOTPRINT_MM2`, 0 or None: no such rule.
    print_height_mm : float
        The printed height of the rest pose, mm, for ``footprint_mm2``.
    volume : float, optional
        The volume the distortion and intersection terms are divided by
        (default: the rig's rest volume). A simplified proxy of a dense
        surface is given the full surface's, so its terms are those of the
        model it stands for (:meth:`supportless.rig.rig.Rig.coarse_rig`).

    Poses that break a hard rule (a joint limit, or standing) get the value
    ``INFEASIBLE + violation``: worse than any pose that keeps the rules, and
    ranked by how far they break them.
    """

    def __init__(self, rig: Rig, w_arap: float = W_ARAP, w_overhang: float = W_OVERHANG,
                 w_intersect: float = W_INTERSECT, overhang_angle: float = SEARCH_OVERHANG_ANGLE,
                 overhang_model: str = "prism", clusters: int | None = 100, resolution: int = DEFAULT_RESOLUTION,
                 backend: str = "fast", arap_data: arap_mod.ArapData | None = None, w_prior: float = W_PRIOR,
                 joint_limits=JOINT_LIMIT, keep_standing: bool = True, support_floor: float = 0.0,
                 volume: float | None = None, chain_limit: float | None = CHAIN_LIMIT, w_chain: float = W_CHAIN,
                 joint_ranges: JointRanges | None = None, contact: ContactRules | None = None, drops: ArmDrops | None = None,
                 head_limit: float | None = HEAD_LIMIT, footprint_mm2: float | None = FOOTPRINT_MM2,
                 print_height_mm: float = REFERENCE_HEIGHT_MM):
        if overhang_model not in OVERHANG_MODELS:
            raise ValueError(f"overhang_model must be one of {OVERHANG_MODELS}, not {overhang_model!r}")
        self.rig = rig
        self.w_arap = float(w_arap)
        self.w_overhang = float(w_overhang)
        self.w_intersect = float(w_intersect)
        self.overhang_angle = float(overhang_angle)
        self.overhang_model = overhang_model
        self.clusters = clusters
        self.resolution = int(resolution)
        if backend not in ("fast", "numpy"):
            raise ValueError(f"backend must be 'fast' or 'numpy', not {backend!r}")
        self.backend = backend
        if arap_data is not None:
            self.__dict__["arap_data"] = arap_data  # fills the cached property below
        self.w_prior = float(w_prior)
        self.keep_standing = bool(keep_standing)
        self.support_floor = float(support_floor)
        if volume is not None:
            self.__dict__["volume"] = float(volume)  # fills the cached property below
        self.prior = PosePrior(rig, np.broadcast_to(np.asarray(joint_limits, np.float64), (rig.bone_count,)), drops)
        self.drops = drops
        self.chain_limit = None if chain_limit is None else float(chain_limit)
        self.w_chain = float(w_chain)
        self._ends = chain_ends(rig)
        self._end_arms = arms_above(rig, self._ends, drops)  # (k,) the dropped arm above each chain end, or -1
        self.head_limit = None if head_limit is None else float(head_limit)
        self._heads = head_bones(rig) if head_limit is not None else np.zeros(0, np.int64)
        self.joint_ranges = joint_ranges
        self.contact, self._refused = contact, RefusedCrossings()  # the triangles of the last refused crossings
        self.footprint_mm2 = None if not footprint_mm2 else float(footprint_mm2)
        self.print_height_mm = float(print_height_mm)

    # ------------------------------------------------------------ precompute
    @cached_property
    def arap_data(self) -> arap_mod.ArapData:
        """Reduced ARAP operators of the rig (computed once)."""
        return arap_mod.arap_precompute(self.rig.tet_vertices, self.rig.tets, self.rig.tet_weights,
                                        clusters=self.clusters, rng=np.random.default_rng(0))

    @cached_property
    def standing(self) -> Standing:
        """Contact and balance against the rest pose."""
        return Standing(self.rig)

    @cached_property
    def volume(self) -> float:
        """Rest volume of the model (area in 2D)."""
        return abs(signed_volume(self.rig.vertices, self.rig.faces))

    @cached_property
    def rest_overhang(self) -> float:
        """Overhang estimate of the rest pose (the chosen model)."""
        return float(self.overhang(self.rig.vertices))

    @cached_property
    def overhang_scale(self) -> float:
        """Denominator of the overhang term: the rest value, floored at 1e-3 of the volume."""
        return max(self.rest_overhang, 1e-3 * self.volume)

    # --------------------------------------------------------------- energies
    def overhang(self, vertices: np.ndarray, rotations: np.ndarray | None = None) -> np.ndarray:
        """Raw overhang estimate of posed vertices, (P,) or float.

        ``rotations`` ((P, d, d) or (d, d) float64, optional) are the print
        rotations: support is counted on ``vertices @ R.T`` (the print frame,
        :mod:`supportless.search.orientation`); none = printed as the model stands.
        """
        up = self.rig.up
        if rotations is not None and self.overhang_model == "prism" and np.ndim(vertices) == 3:
            # V @ R.T measured along up is V measured along R.T @ up: no need to turn the poses
            along = np.einsum("...ij,i->...j", np.asarray(rotations, np.float64), np.asarray(up, np.float64))
            up = np.broadcast_to(along, (len(vertices), self.rig.dim))
        elif rotations is not None:
            vertices = np.matmul(vertices, np.swapaxes(rotations, -1, -2))
        if self.overhang_model == "slicer":
            return predicted_support_mm(vertices, self.rig.faces, self.rig.up, self.overhang_angle,
                                        SLICER_MODEL_HEIGHT_MM / self.height)
        if self.overhang_model == "column":
            return support_volume(vertices, self.rig.faces, self.rig.up, self.overhang_angle, self.resolution,
                                  backend=self.backend)
        # the rig's surface is outward oriented and skinning and turning keep it so: no need to measure it
        return overhang_energy(vertices, self.rig.faces, up, self.overhang_angle, backend=self.backend,
                               floor=self.support_floor * self.height, orient=1.0)

    @cached_property
    def height(self) -> float:
        """Rest height of the model along up."""
        return float(np.ptp(self.rig.vertices @ self.rig.up))

    @cached_property
    def search_lbs(self):
        """The skinning operator of :meth:`bounded`: the rig's, weights below :data:`SEARCH_WEIGHT_FLOOR` dropped."""
        return lbs_operator(self.rig.vertices, pruned_weights(self.rig.weights, SEARCH_WEIGHT_FLOOR))

    def _posed(self, angles: np.ndarray, search: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Bone transforms (P, m, d, d+1) and posed surface vertices (P, n, d) of a batch."""
        transforms = self.rig.transforms(angles)
        return transforms, skin(self.search_lbs if search else self.rig.lbs, transforms)

    def _intersection(self, vertices: np.ndarray) -> np.ndarray:
        return self_intersection_volume(vertices, self.rig.faces, self.rig.up, self.resolution, backend=self.backend)

    def raw_terms(self, angles: np.ndarray, rotations: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The three energies before normalisation.

        Parameters
        ----------
        angles : (P, m, 3) or (m, 3) float64
        rotations : (P, d, d) or (d, d) float64, optional
            Print rotations: the overhang is counted in the print frame
            (everything else is judged as the model stands).

        Returns
        -------
        terms : dict of str -> (P,) float64 (floats for a single pose)
            ``arap`` (volume units), ``overhang`` and ``intersection`` (volumes),
            ``prior`` (dimensionless) and ``violation`` (0 for a pose that
            keeps the hard rules).
        """
        chunk = self._chunk()
        if np.ndim(angles) == 3 and len(angles) > chunk:  # per pose, the same values: in chunks
            turns = rotations is not None and np.ndim(rotations) == 3
            parts = [self.raw_terms(angles[i:i + chunk], rotations[i:i + chunk] if turns else rotations)
                     for i in range(0, len(angles), chunk)]
            return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
        transforms, V = self._posed(angles)
        return self._cheap_terms(angles, transforms, V, rotations) | {"intersection": self._intersection(V)}

    def _chunk(self) -> int:
        """Poses measured at once: :data:`POSE_CHUNK`, fewer on a dense surface (:data:`POSED_VERTICES`)."""
        return max(1, min(POSE_CHUNK, POSED_VERTICES // max(len(self.rig.vertices), 1)))

    def chain_excess(self, transforms: np.ndarray, turns: np.ndarray | None = None) -> np.ndarray:
        """How far the chain ends turn past ``chain_limit`` and the heads past ``head_limit``: the sum over them,
        radians, (P,) float64 (0 when off). ``turns``: :meth:`end_turns_deg` of ``transforms``, if measured."""
        d = self.rig.dim
        excess = np.zeros(transforms.shape[:-3])
        for limit, turn in ((self.chain_limit, lambda: self.end_turns_deg(transforms) if turns is None else turns),
                            (self.head_limit, lambda: rotation_angle_deg(transforms[..., self._heads, :d, :d]))):
            if limit is not None and (len(self._ends) if limit is self.chain_limit else len(self._heads)):
                excess = excess + np.radians(np.maximum(turn() - limit, 0.0)).sum(axis=-1)
        return excess

    def end_turns_deg(self, transforms: np.ndarray) -> np.ndarray:
        """(..., k) float64 degrees: each chain end's turn in the world from its rest direction, less the turn
        down of a named upper arm above it (:func:`~supportless.search.relaxed.without_drop`): a hand follows
        its arm down at no cost."""
        d = self.rig.dim
        R = transforms[..., self._ends, :d, :d]
        below = np.flatnonzero(self._end_arms >= 0)
        if self.drops is None or not len(below):
            return rotation_angle_deg(R)
        k = self._end_arms[below]
        arm = transforms[..., self.drops.bones[k], :d, :d]
        rest = without_drop(arm, self.drops.axes[k], self.drops.reach[k])
        down = arm @ np.swapaxes(rest, -1, -2)  # D, the arm's turn down: arm = D rest
        R = R.copy()
        R[..., below, :, :] = np.swapaxes(down, -1, -2) @ R[..., below, :, :]
        return rotation_angle_deg(R)

    def posed_violation(self, transforms: np.ndarray, V: np.ndarray, turns: np.ndarray | None = None) -> np.ndarray:
        """How far posed bodies break the rules measured on the pose, not on the joints' own turns: the chain
        limit, the named joints' ranges and the standing rule; (P,) float64, 0 for a pose that keeps them.
        ``turns`` as in :meth:`chain_excess`."""
        violation = self.chain_excess(transforms, turns)
        if self.joint_ranges is not None:
            violation = violation + self.joint_ranges.excess(transforms)
        if self.keep_standing:
            violation = violation + self.standing.violation(transforms, V)
        return violation

    def footprint_shortfall(self, V: np.ndarray, rotations: np.ndarray | None) -> np.ndarray | float:
        """How far turned bodies fall short of resting on :attr:`footprint_mm2` of plate: ``1 - area / bound``
        where the first layer's contact (:func:`~supportless.energies.footprint.footprint_area`, at
        :attr:`print_height_mm` tall) is under the bound, else 0; (P,) float64.

        Only a turn is judged (``rotations`` given and not the identity): the model as it stands rests as its maker
        made it.
        """
        if self.footprint_mm2 is None or rotations is None or self.rig.dim != 3:
            return 0.0
        if np.ndim(V) == 2:  # one pose
            return float(self.footprint_shortfall(np.asarray(V)[None], np.asarray(rotations).reshape(1, *np.shape(rotations)[-2:]))[0])
        R = np.broadcast_to(np.asarray(rotations, np.float64), (len(V), self.rig.dim, self.rig.dim))
        shortfall = np.zeros(len(V))
        turned = ~np.all(np.isclose(R, np.eye(self.rig.dim)), axis=(-2, -1))  # upright is the model as it stands
        if np.any(turned):  # V @ R.T measured along up is V measured along R.T @ up
            along = np.einsum("pij,i->pj", R[turned], np.asarray(self.rig.up, np.float64))
            area = footprint_area(V if turned.all() else V[turned], self.rig.faces, along,
                                  self.print_height_mm / self.height)
            shortfall[turned] = np.maximum(0.0, 1.0 - area / self.footprint_mm2)
        return shortfall

    def rests(self, angles: np.ndarray, rotation: np.ndarray) -> bool:
        """Whether the pose ``angles (m, 3) float64`` turned by ``rotation (d, d) float64`` rests on at least
        :attr:`footprint_mm2` of plate, measured on this objective's whole surface (True with no such rule, and for
        the model as it stands). The search's gate of would-be bests: a proxy's coarser surface can rest on a
        blunt tip where the full one rests on a point."""
        if self.footprint_mm2 is None or self.rig.dim != 3:
            return True
        V = self.rig.pose(np.asarray(angles, np.float64))
        return bool(self.footprint_shortfall(V[None], np.asarray(rotation, np.float64)[None])[0] == 0)

    def prior_cost(self, angles: np.ndarray, transforms: np.ndarray, turns: np.ndarray | None = None) -> np.ndarray:
        """The natural-pose prior: the joints' own turns (:class:`PosePrior`), plus ``w_chain`` times the
        squared turn (radians) of each chain end in the world, summed: three joints turning one way cost
        more than three turning different ways. ``turns`` as in :meth:`chain_excess`."""
        if not self.w_chain:
            return self.prior.cost(angles)
        turn = np.radians(self.end_turns_deg(transforms) if turns is None else turns)
        return self.prior.cost(angles) + self.w_chain * (turn ** 2).sum(axis=-1)

    def _cheap_terms(self, angles, transforms, V, rotations=None) -> dict:
        """Every raw term but the (expensive) intersection."""
        turns = self.end_turns_deg(transforms)
        violation = (self.prior.excess(angles) + self.posed_violation(transforms, V, turns)
                     + self.footprint_shortfall(V, rotations))
        return {"arap": arap_mod.arap_energy(self.arap_data, transforms, backend=self.backend),
                "overhang": self.overhang(V, rotations), "prior": self.prior_cost(angles, transforms, turns),
                "violation": violation}

    def normalise(self, raw: dict) -> dict:
        """Raw terms -> normalised terms (see the module docstring)."""
        return {
            "arap": np.asarray(raw["arap"]) / self.volume,
            "overhang": np.asarray(raw["overhang"]) / self.overhang_scale,
            "intersection": np.asarray(raw["intersection"]) / self.volume,
            "prior": np.asarray(raw["prior"]),
            "violation": np.asarray(raw["violation"]),
        }

    def distortion(self, terms: dict):
        """The distortion part of this objective's ``terms`` (:func:`distortion` at its weights)."""
        return distortion(terms, self.w_arap, self.w_prior)

    @property
    def overlap_allowed(self) -> float:
        """The share of the volume a contact may cover twice (0 when no contact is allowed)."""
        return 0.0 if self.contact is None or not self.contact.allows_contact else float(self.contact.volume)

    def intersection_cost(self, share) -> np.ndarray:
        """Weighted cost of the volume covered twice, ``share`` of :attr:`volume` (P,) float64: :data:`W_CONTACT`
        up to :attr:`overlap_allowed`, ``w_intersect`` past it."""
        share = np.asarray(share, np.float64)
        within = np.minimum(share, self.overlap_allowed)
        return min(W_CONTACT, self.w_intersect) * within + self.w_intersect * (share - within)

    def forbidden(self, angles: np.ndarray) -> bool:
        """Whether the pose ``angles (m, 3) float64`` crosses itself other than by contact within the rules.

        CGAL's exact test (stopping at the first crossing when no contact is allowed); a crossing pose is then judged
        by :meth:`Rig.crossings` with :attr:`contact` from one CGAL call's pairs, last by its ray-grid overlap
        (measured only when the other rules allow it: the volume rule is the verdict's last). The last refused pose's
        crossing triangles are asked first (:class:`~supportless.rig.contact.RefusedCrossings`): the same verdict."""
        rig = self.rig
        if rig.dim != 3:
            return False
        if self.contact is None or not self.contact.allows_contact:
            return rig.self_intersects(angles)
        V, J = rig.pose(angles), rig.posed_joints(angles)
        if self._refused.refuse(rig.body_parts, V, J, self.contact):  # the last refused pose's crossings again
            return True
        pairs = intersecting_faces(V, rig.faces)
        if len(pairs) and not rig.crossings(V, J, self.contact, None, pairs).allowed:
            self._refused.remember(pairs)
            return True
        return bool(len(pairs)) and self.contact.covers_too_much(float(np.asarray(self._intersection(V[None]))[0]),
                                                                 rig.rest_volume)

    def combine(self, terms: dict) -> np.ndarray:
        """Weighted sum of normalised terms, plus ``INFEASIBLE + violation`` where a hard rule is broken."""
        value = (self.w_arap * terms["arap"] + self.w_overhang * terms["overhang"]
                 + self.intersection_cost(terms["intersection"]) + self.w_prior * terms["prior"])
        violation = terms["violation"]
        return value + np.where(violation > 0, INFEASIBLE + violation, 0.0)

    def terms(self, angles: np.ndarray, rotations: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Normalised terms of a batch of poses.

        Parameters
        ----------
        angles : (P, m, 3) or (m, 3) float64
        rotations : (P, d, d) or (d, d) float64, optional
            Print rotations (see :meth:`raw_terms`).

        Returns
        -------
        terms : dict with keys ``arap``, ``overhang``, ``intersection``, ``prior``, ``violation``
            (P,) float64 arrays (0-d arrays for a single pose).
        """
        return self.normalise(self.raw_terms(angles, rotations))

    def evaluate(self, angles: np.ndarray, rotations: np.ndarray | None = None) -> tuple[np.ndarray, dict, dict]:
        """Objective, normalised terms and raw terms in one pass."""
        raw = self.raw_terms(angles, rotations)
        terms = self.normalise(raw)
        return self.combine(terms), terms, raw

    def bounded(self, angles: np.ndarray, bound: np.ndarray, rotations: np.ndarray | None = None) -> np.ndarray:
        """Objective of a batch, exact only where it can beat ``bound``.

        What the search minimises: posed with :attr:`search_lbs` (the other methods pose with the rig's own
        weights). No term is ever negative, so a pose whose cheaper terms alone reach its bound cannot beat it:
        the terms are computed in order of cost (prior and overhang, then distortion, then the standing rule,
        then the expensive self-intersection), each only for the poses the ones before leave below their bound;
        a pose past a joint limit is not measured at all when its bound keeps the rules (below
        :data:`INFEASIBLE`). The swarm passes each particle's best value as its bound. A batch larger than
        :data:`POSE_CHUNK` is measured in chunks of that size (the same values; memory no longer grows with the
        swarm).

        Parameters
        ----------
        angles : (P, m, 3) float64
        bound : (P,) float64
        rotations : (P, d, d) float64, optional
            Print rotations (see :meth:`raw_terms`).

        Returns
        -------
        values : (P,) float64
            The objective where it is below ``bound``; elsewhere a lower bound
            of it that is at least ``bound``.
        """
        return self.bounded_overlap(angles, bound, rotations)[0]

    def bounded_overlap(self, angles: np.ndarray, bound: np.ndarray, rotations: np.ndarray | None = None,
                        intersection_bound: float | None = None, measured: dict | None = None
                        ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`bounded`, and the self-intersection volume it computed on the way.

        Parameters
        ----------
        angles, bound, rotations
            As :meth:`bounded`.
        intersection_bound : float, optional
            Measure the (expensive) self-intersection term only where the
            other terms are below this too: a pose whose other terms are
            below its ``bound`` but not below ``intersection_bound`` gets
            their sum, without the self-intersection term (a lower bound
            that may be below ``bound``). The search passes the swarm's best
            value: only a pose that could become the swarm's best is
            measured in full. Those are measured the least costly first, :data:`INTERSECT_CHUNK` at a time, at
            most :data:`INTERSECT_MOST`; a pose not measured gets the larger of its other terms' sum and
            ``intersection_bound``: it is not taken as the swarm's best.
        measured : dict, optional
            Filled with the normalised terms (as :meth:`terms`, posed with the search's weights) of the poses
            measured in full, the self-intersection too: ``"index"`` (r,) int64, their positions in the batch,
            and each term's (r,) float64 (the search's progress shows its best's).

        Returns
        -------
        values : (P,) float64
            As :meth:`bounded` (see ``intersection_bound``).
        overlap : (P,) float64
            The ray grid's self-intersection volume where it was computed, 0
            elsewhere. A closed surface that does not intersect itself is
            nowhere two layers deep, so a volume above rounding means the pose
            does intersect itself (the search's exact gate skips CGAL there).
        """
        values, overlap, terms = self._bounded_overlap(
            angles, np.broadcast_to(np.asarray(bound, np.float64), (len(angles),)), rotations,
            np.inf if intersection_bound is None else float(intersection_bound))
        if measured is not None:
            index = np.flatnonzero(np.isfinite(terms["intersection"]))
            measured.clear()
            measured.update({"index": index} | {key: v[index] for key, v in terms.items()})
        return values, overlap

    def _bounded_overlap(self, angles, bound, rotations, intersection_bound=np.inf):
        """:meth:`bounded_overlap` with ``bound`` (P,) float64: in chunks, without the poses that break a rule; the
        normalised terms of the poses measured in full as a third value (NaN elsewhere)."""
        chunk = self._chunk()
        if len(angles) > chunk:
            parts = [self._bounded_overlap(angles[i:i + chunk], bound[i:i + chunk],
                                           None if rotations is None else rotations[i:i + chunk],
                                           intersection_bound)
                     for i in range(0, len(angles), chunk)]
            return (np.concatenate([v for v, _, _ in parts]), np.concatenate([o for _, o, _ in parts]),
                    {key: np.concatenate([t[key] for _, _, t in parts]) for key in parts[0][2]})
        excess = np.asarray(self.prior.excess(angles), np.float64)
        # past a joint limit, against a bound that keeps the rules: INFEASIBLE + excess is a lower bound above it
        values, overlap = INFEASIBLE + excess, np.zeros(len(excess))
        terms = {key: np.full(len(excess), np.nan) for key in ("arap", "overhang", "intersection", "prior", "violation")}
        keep = np.flatnonzero((excess <= 0) | (bound >= INFEASIBLE))
        if len(keep) == 0:
            return values, overlap, terms
        if len(keep) < len(angles):
            angles, bound, excess = angles[keep], bound[keep], excess[keep]
            rotations = None if rotations is None else rotations[keep]
        transforms, V = self._posed(angles, search=True)
        # the terms in order of cost, each only for the poses the cheaper ones leave below their bound (every
        # term is >= 0, so a partial sum is a lower bound); the survivors' value is summed as combine() does
        prior = np.asarray(self.prior_cost(angles, transforms, turns := self.end_turns_deg(transforms)), np.float64)
        overhang = np.asarray(self.overhang(V, rotations), np.float64)
        kept = self.w_overhang * (overhang / self.overhang_scale) + self.w_prior * prior
        todo = np.flatnonzero(kept < bound)
        arap, violation = np.zeros(len(kept)), np.zeros(len(kept))
        if len(todo):
            arap[todo] = arap_mod.arap_energy(self.arap_data, transforms[todo], backend=self.backend)
            kept[todo] += self.w_arap * (arap[todo] / self.volume)
            todo = todo[kept[todo] < bound[todo]]
        if len(todo):
            Vt = V if len(todo) == len(V) else V[todo]  # (a copy of every pose's surface costs more than the rule)
            violation[todo] = (excess[todo] + self.posed_violation(transforms[todo], Vt, turns[todo])
                               + self.footprint_shortfall(Vt, None if rotations is None else rotations[todo]))
            partial = {"arap": arap[todo], "overhang": overhang[todo], "prior": prior[todo],
                       "intersection": 0.0, "violation": violation[todo]}
            kept[todo] = self.combine(self.normalise(partial))
            todo = todo[kept[todo] < np.minimum(bound[todo], intersection_bound)]
        if len(todo) and self.w_intersect != 0:
            if np.isfinite(intersection_bound):
                measured = self._intersect_best_first(V, todo, kept, overlap, keep)
                # the others cannot become the swarm's best: valued at or above it
                rest = np.setdiff1d(todo, measured, assume_unique=True)
                kept[rest] = np.maximum(kept[rest], intersection_bound)
            else:
                measured = todo
                inter = np.asarray(self._intersection(V[todo]), np.float64)
                overlap[keep[todo]] = inter
                kept[todo] += self.intersection_cost(inter / self.volume)
            at = keep[measured]
            for key, raw in (("arap", arap), ("overhang", overhang), ("prior", prior), ("violation", violation)):
                terms[key][at] = raw[measured]
            terms["intersection"][at] = overlap[at]
            terms = self.normalise(terms)
        values[keep] = kept
        return values, overlap, terms

    def _intersect_best_first(self, V, todo, kept, overlap, keep) -> np.ndarray:
        """Add the self-intersection cost to ``kept[todo]``, the least partial sums first, :data:`INTERSECT_CHUNK`
        poses at a time, stopping where the partial sums reach the least total measured (a pose whose other terms
        already cost that much cannot become the batch's best) or after :data:`INTERSECT_MOST` poses. Fills
        ``overlap[keep[...]]``; returns the measured indices into ``kept`` (int64)."""
        order = todo[np.argsort(kept[todo], kind="stable")][:INTERSECT_MOST]
        least, done = np.inf, 0
        while done < len(order) and kept[order[done]] < least:
            chunk = order[done:done + INTERSECT_CHUNK]
            chunk = chunk[kept[chunk] < least]
            inter = np.asarray(self._intersection(V[chunk]), np.float64)
            overlap[keep[chunk]] = inter
            kept[chunk] += self.intersection_cost(inter / self.volume)
            least = min(least, float(kept[chunk].min()))
            done += len(chunk)
        return order[:done]

    def __call__(self, angles: np.ndarray, rotations: np.ndarray | None = None) -> np.ndarray:
        """Objective value of a batch of poses: (P,) float64 (a 0-d array for one pose)."""
        return self.combine(self.terms(angles, rotations))

    def settings(self) -> dict:
        """The weights and options, for reports."""
        return {"w_arap": self.w_arap, "w_overhang": self.w_overhang, "w_intersect": self.w_intersect,
                "overhang_angle": self.overhang_angle, "overhang_model": self.overhang_model,
                "clusters": self.clusters, "resolution": self.resolution, "w_prior": self.w_prior,
                "chain_limit": self.chain_limit, "head_limit": self.head_limit, "w_chain": self.w_chain,
                "joint_ranges": None if self.joint_ranges is None else self.joint_ranges.describe(),
                "joint_limits": np.degrees(self.prior.limits).tolist(), "keep_standing": self.keep_standing,
                "support_floor": self.support_floor, "footprint_mm2": self.footprint_mm2,
                "contact": None if self.contact is None else dataclasses.asdict(self.contact)}
