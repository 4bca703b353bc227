"""The search: what a pose costs, which poses are allowed, and the swarm that finds one.

* :mod:`.standing`: the pose stands as the rest stood (contact, balance);
* :mod:`.prior`: joint limits and the natural-pose prior; :mod:`.layout`: the search's
  variables (moving bones, left/right pairs, symmetric poses);
* :mod:`.orientation`: turning the whole model on the plate;
* :mod:`.objective`: the weighted, normalised sum of the energies and the hard rules;
* :mod:`.settings`: :class:`SearchSettings`, the one source of the search's defaults and ranges;
* :mod:`.swarm`: the optimisers (particle swarm, CMA-ES), batched over a generation;
* :mod:`.optimizer`: :func:`optimize`: the proxy, the phases, the exact gate, the polish;
* :mod:`.result`: :class:`PoseResult`, measured on the full surface and gated as written;
* :mod:`.naturalness`: how natural a pose looks, in numbers (chain-end turns, mirror error);
* :mod:`.candidates`: distinct good poses; :mod:`.choice`: the answer with the least
  predicted support among pose, turn, and both.
"""
