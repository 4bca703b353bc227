"""The quantities a pose is scored by, each batched over poses.

* :mod:`.overhang`: prism overhang energy and risky faces;
* :mod:`.support`: column support volume, and :mod:`.intersection`:
  self-intersection volume, both from the ray grid of :mod:`.raygrid`
  (implemented in ``_grid_reference``, ``_grid_fast``, ``_grid_numpy`` and
  ``_grid_common``);
* :mod:`.surface`: what they share: argument checks (:func:`.surface.prepare`,
  ``up`` as ``"-z"`` or a vector), orientation, 2D boundary edges, the frame of ``up``;
* :mod:`.arap`: as-rigid-as-possible deformation energy;
* :mod:`.slicer_model`: PrusaSlicer's support filament predicted from the column volume (fitted).
"""
