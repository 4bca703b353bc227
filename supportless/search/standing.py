"""The found pose must stand where the rest pose stood: no new contacts, no falling over.

:class:`Standing` holds what a rig's rest pose says about its contact with the
build plate — which vertices rest on it, which stood clear of it, the support
polygon and how steadily the rest pose stands — and measures a batch of poses
against it (:mod:`supportless.rig.balance` does the geometry).

A pose is *standing* when

* no vertex that stood more than :data:`CLEARANCE` of the height above the
  plate comes within :data:`~supportless.rig.rig.CONTACT_TOLERANCE` of it, and
* its centre of mass projects inside the support polygon by at least
  ``min(rest margin, STAND_MARGIN x height)`` — or, when the rest pose does not
  stand, by no less than the rest pose does.

:meth:`Standing.violation` is 0 for a standing pose and grows with how far a
pose is from standing (a fraction of the height), so a search can both reject
and rank the poses that do not stand.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from ..base.geometry import plane_basis
from ..rig.balance import centre_of_mass, new_contact_depth, stability_margin, support_polygon
from ..rig.rig import CONTACT_TOLERANCE, Rig

__all__ = ["CLEARANCE", "STAND_MARGIN", "Standing"]

#: Vertices that stood more than this fraction of the height above the plate
#: at rest must not come down to it.
CLEARANCE = 0.02

#: The steadiness asked of a found pose whose rest pose stands: its centre of
#: mass inside the support polygon by this fraction of the height (or by the
#: rest pose's own margin, if that is smaller).
STAND_MARGIN = 0.02


class Standing:
    """Contact and balance of a rig's poses, measured against its rest pose.

    Parameters
    ----------
    rig : Rig

    Attributes
    ----------
    height : float
        Rest height along ``up``.
    plate : float
        Rest height of the lowest point (where the plate is).
    clear : (n,) bool
        Vertices that stood clear of the plate (above ``plate + CLEARANCE * height``).
    polygon : (q, d-1) float64
        Support polygon of the rest contact region.
    """

    def __init__(self, rig: Rig):
        self.rig = rig
        h = rig.vertices @ rig.up
        self.plate = float(h.min())
        self.height = float(h.max() - h.min())
        self.clear = h > self.plate + CLEARANCE * self.height
        self.touch_level = self.plate + CONTACT_TOLERANCE * self.height
        self.polygon = support_polygon(rig.vertices[rig.contact_vertices], rig.up)

    @cached_property
    def rest_margin(self) -> float:
        """Stability margin of the rest pose, in model units (negative: it does not stand)."""
        return float(self.margin(self.rig.transforms(self.rig.rest_angles())))

    @cached_property
    def required_margin(self) -> float:
        """The margin a pose needs to count as standing, in model units."""
        if self.rest_margin > 0:
            return min(self.rest_margin, STAND_MARGIN * self.height)
        return self.rest_margin

    def support_corners(self) -> np.ndarray:
        """(q, d) float64: the support polygon's corners in the rest frame, on the plate."""
        return self.polygon @ plane_basis(self.rig.up) + self.plate * self.rig.up

    def centre_of_mass(self, transforms: np.ndarray) -> np.ndarray:
        """Centres of mass of posed solids, (P, d) or (d,) float64, from bone transforms (P, m, d, d+1)."""
        return centre_of_mass(transforms, self.rig.mass_moments)

    def margin(self, transforms: np.ndarray) -> np.ndarray:
        """Stability margins (model units) of posed solids, (P,) float64 or float."""
        return stability_margin(self.centre_of_mass(transforms), self.polygon, self.rig.up)

    def new_contacts(self, vertices: np.ndarray) -> np.ndarray:
        """Number of clear vertices that come down to the plate, (P,) int64 or int.

        Parameters
        ----------
        vertices : (P, n, d) or (n, d) float64
            Posed surfaces in the rest frame.
        """
        h = np.asarray(vertices, np.float64)[..., self.clear, :] @ self.rig.up
        count = (h < self.touch_level).sum(axis=-1)
        return int(count) if np.ndim(count) == 0 else count

    def violation(self, transforms: np.ndarray, vertices: np.ndarray) -> np.ndarray:
        """How far poses are from standing, as a fraction of the height; 0 when they stand.

        Parameters
        ----------
        transforms : (P, m, d, d+1) float64
        vertices : (P, n, d) float64
            Posed surfaces in the rest frame.

        Returns
        -------
        violation : (P,) float64
            The depth by which clear parts reach the plate plus the shortfall
            of the stability margin, both over the height.
        """
        down = new_contact_depth(vertices, self.rig.up, self.clear, self.touch_level)
        short = np.maximum(0.0, self.required_margin - self.margin(transforms))
        return (down + short) / self.height

    def measures(self, transforms: np.ndarray, vertices: np.ndarray) -> dict:
        """What a report says about one pose's contact and balance.

        Parameters
        ----------
        transforms : (m, d, d+1) float64
        vertices : (n, d) float64

        Returns
        -------
        measures : dict
            ``new_contact_vertices`` (int), ``stability_margin`` (fraction of
            the height; negative: falls over), ``stands`` (bool: no new
            contact and the centre of mass inside the support polygon by the
            margin the rule above asks, never by a negative one),
            ``as_steady_as_rest`` (bool: the rule above, which a pose of a
            rest pose that does not stand can meet without standing) and
            ``centre_of_mass`` (list of d floats, rest frame).
        """
        margin = float(self.margin(transforms))
        new = int(self.new_contacts(vertices))
        steady = bool(new == 0 and margin >= self.required_margin - 1e-12 * self.height)
        return {"new_contact_vertices": new, "stability_margin": margin / self.height,
                "stands": steady and margin > 0, "as_steady_as_rest": steady,
                "centre_of_mass": [float(x) for x in self.centre_of_mass(transforms)]}
