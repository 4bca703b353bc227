"""The objective's default weights and the bounds of a natural pose, each with what it was chosen by.

:class:`~supportless.search.objective.Objective` and :class:`~supportless.search.settings.SearchSettings` both take
their defaults from here: one source.
"""

__all__ = ["CHAIN_LIMIT", "FOOTPRINT_MM2", "HEAD_LIMIT", "JOINT_LIMIT", "W_ARAP", "W_CHAIN", "W_CONTACT",
           "W_INTERSECT", "W_OVERHANG", "W_PRIOR"]

#: Default weights of the normalised terms (:mod:`supportless.search.objective`).
W_ARAP = 2.0
W_OVERHANG = 1.0
W_INTERSECT = 50.0
W_PRIOR = 0.3
#: Weight of the volume covered twice up to what a contact between jointed parts may cover
#: (:data:`~supportless.rig.contact.CONTACT_VOLUME`), in place of ``w_intersect``: an arm resting against the
#: body costs a little (0.2 % of the volume, the Xbot's arms lowered 60 degrees: 0.01, a hundredth of the rest
#: pose's support), a part through another costs ``w_intersect`` past it, and is refused by the exact gate
#: (:meth:`~supportless.search.objective.Objective.forbidden`) wherever it is not jointed.
W_CONTACT = 5.0
#: Weight of the chain ends' squared world turn in the prior
#: (:meth:`~supportless.search.objective.Objective.prior_cost`). Chosen on the zoo and the shared models with
#: PrusaSlicer (benchmarks/RESULTS.md, "The chain limit"): with the 60-degree chain limit, 0.03 gave
#: zoo 65.2 % (65.7 % at 0), bunny 54.3 % (41.4 %), bb-bunny 44.3 % (41.4 %), smaller turns.
W_CHAIN = 0.03

#: Default largest rotation of a joint, degrees (one angle). Chosen on the zoo and
#: the shared models with PrusaSlicer (benchmarks/RESULTS.md, "Zoo"): 45 degrees
#: with prior weight 0.3 gave bunny 51.9 %, bb-bunny 48.4 %, zoo mean 63.9 %;
#: 30 degrees with weight 1.0 gave 43.4 %, 35.3 % and lower zoo figures.
JOINT_LIMIT = 45.0

#: Default largest turn of a chain's end (a head, a hand, a tail or wing tip) in the world from its rest
#: direction, degrees. Chosen on the zoo and the shared models with PrusaSlicer (benchmarks/RESULTS.md,
#: "Zoo" and "The chain limit"): with the mirrored search, 60 degrees gave a zoo mean of 65.7 % (65.3 % with
#: neither) and keeps the dragon's wings spread, the staff across the body and no head bent into a chest.
CHAIN_LIMIT = 60.0

#: Default largest turn of a head (:func:`supportless.search.naturalness.head_bones`) in the world from its rest
#: direction, degrees: the chest, neck and head turns together. Tighter than :data:`CHAIN_LIMIT`, since a head
#: is what a person reads first: a witch searched standing hung her head the chain limit's full 60 degrees
#: (chest 23, neck and head 45) and her hat covered her face. 25 degrees is a chosen bound, not yet measured
#: on the zoo.
HEAD_LIMIT = 25.0

#: Least first-layer contact of a turned print, mm² at the printed size
#: (:attr:`~supportless.search.settings.SearchSettings.footprint_mm2`): the section half a first layer over its lowest point (:func:`supportless.energies.footprint.footprint_area`).
#: A turn that rests on less is refused. Chosen on the zoo and the shared characters: see benchmarks/RESULTS.md,
#: "Resting on an area".
FOOTPRINT_MM2 = 3.0
