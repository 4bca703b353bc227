"""What the panel's numbers mean, in words and human units.

The search works in the model's own units; a user compares with a slicer,
which speaks millimetres and grams. :func:`filament_text` says a length of
filament and its grams (the figure the panel leads with,
:mod:`supportless.apps.ui.filament`); :func:`volume_text` turns a volume of the
model into the printed one (the print frame's scale cubed), with its grams as
solid filament; :func:`broken_rules` names the rule a pose breaks when the
objective jumps by :data:`~supportless.search.objective.INFEASIBLE`.
"""

from __future__ import annotations

import numpy as np

from ...files.printer import DEFAULT_DENSITY

__all__ = ["broken_rules", "filament_text", "grams", "volume_text"]


def grams(volume_mm3: float, density: float = DEFAULT_DENSITY) -> float:
    """Mass of a printed volume, g: ``volume_mm3`` mm³ of a filament of ``density`` g/cm³."""
    return float(volume_mm3) * 1e-3 * density


def volume_text(volume: float | None, scale: float, with_grams: bool = True) -> str:
    """A volume of the model as printed: ``"1,234 mm³ ≈ 1.5 g"``.

    Parameters
    ----------
    volume : float or None
        In the model's units cubed.
    scale : float
        Millimetres per model unit (the print frame's scale).
    with_grams : bool
        Also its grams as solid filament (off where a filament figure leads, so no second mass is read as it).

    Returns
    -------
    text : str
        ``n/a`` for None; millimetres cubed rounded to three significant
        figures, grams of PLA to 0.1 g (0.01 g below 1 g).
    """
    if volume is None or not np.isfinite(volume):
        return "n/a"
    mm3 = float(volume) * scale ** 3
    g = grams(mm3)
    rounded = float(f"{mm3:.3g}")
    mm3_text = f"{rounded:,.0f} mm³" if rounded >= 100 else f"{rounded:.3g} mm³"
    if not with_grams:
        return mm3_text
    return f"{mm3_text} ≈ {g:.2f} g" if g < 1 else f"{mm3_text} ≈ {g:.1f} g"


def filament_text(mm: float, g: float | None) -> str:
    """A length of support filament and its mass: ``"4,685 mm ≈ 14.0 g"``, as the command line's summary rounds.

    Parameters
    ----------
    mm : float
        Filament length, mm.
    g : float or None
        Its mass, g (None when unknown: the length alone).
    """
    return f"{mm:,.0f} mm" if g is None else f"{mm:,.0f} mm ≈ {g:.1f} g"


def broken_rules(objective, angles: np.ndarray, names: list[str] | None = None) -> list[str]:
    """The hard rules a pose breaks, each in words (empty when it keeps them all).

    A pose that breaks one gets ``INFEASIBLE + violation`` added to its
    objective (:meth:`supportless.search.objective.Objective.combine`); these
    are the words for that jump.

    Parameters
    ----------
    objective : supportless.search.objective.Objective
    angles : (m, 3) float64
        The pose, radians.
    names : list of str, optional
        Bone names (default: the rig's).

    Returns
    -------
    rules : list of str
        e.g. ``"bone 3 (forearm) turns 62° at its joint, past its 45° limit"``.
    """
    rig = objective.rig
    names = rig.bone_names() if names is None else names
    angles = np.asarray(angles, np.float64)
    rules = []
    turn = np.degrees(objective.prior.angles(angles))
    limit = np.degrees(objective.prior.limits)
    for b in np.flatnonzero(turn > limit + 1e-9):
        rules.append(f"bone {b + 1} ({names[b]}) turns {turn[b]:.0f}° at its joint, past its {limit[b]:.0f}° "
                     "joint limit")
    transforms = rig.transforms(angles)
    if objective.chain_limit is not None:
        d = rig.dim
        from ...search.naturalness import chain_ends, rotation_angle_deg

        ends = chain_ends(rig)
        world = rotation_angle_deg(transforms[ends, :d, :d])
        for k in np.flatnonzero(world > objective.chain_limit + 1e-9):
            b = int(ends[k])
            rules.append(f"bone {b + 1} ({names[b]}) ends a chain turned {world[k]:.0f}° from its rest, past the "
                         f"{objective.chain_limit:.0f}° a chain end may turn")
    if objective.joint_ranges is not None and float(objective.joint_ranges.excess(transforms)) > 0:
        u = objective.joint_ranges.usage(transforms)
        rules.append(f"the {u['joint']} is {u['outside_deg']:.0f}° outside its natural range ({u['measure']} "
                     f"{u['angle_deg']:.0f}° against {u['limit_deg']:.0f}°)")
    if objective.keep_standing:
        V = rig.pose(angles)
        if float(np.asarray(objective.standing.violation(transforms[None], V[None])).reshape(-1)[0]) > 0:
            rules.append("the pose no longer stands on what the rest pose stood on (it would tip or float)")
    return rules
