"""Weak sections on the pictures: the faces a grip would snap, coloured, and the weakest section in one line.

:func:`~supportless.energies.strength.analyse_strength` gives each face the least safety factor of the sections
cutting it (``face_safety``). A face is drawn

* **cyan** where that factor is below :data:`BREAKS_BELOW` (1): the grip (2 N at a hand, the head, a tail)
  breaks the print there;
* **pale cyan** where it is below :data:`MARGINAL_BELOW` (2): it holds the grip, but less than twice over (a
  firmer grip, a knock or a weak print breaks it).

Red and the warm colours already say "needs support" (on the pictures and in the browser app), magenta "crosses
itself" (in the app) and green the support polygon, so the weakness colours are cyan ones, painted over the
support red: where the print snaps matters more than where it needs support. The browser app's strength overlay
(:mod:`supportless.apps.ui.strength`) uses the same thresholds and colours.
"""

from __future__ import annotations

import numpy as np

from .render import _BASE_COLOR, _face_base_colors

__all__ = ["BREAKS_BELOW", "LEGEND", "MARGINAL_BELOW", "WEAK_COLORS", "weak_face_colors", "weakest_caption",
           "weakness_levels"]

#: A section whose safety factor is below this breaks under the grip.
BREAKS_BELOW = 1.0
#: A section whose safety factor is below this (and not below :data:`BREAKS_BELOW`) is marginal.
MARGINAL_BELOW = 2.0
#: RGB in [0, 1] of each weakness level: 1 marginal (pale cyan), 2 breaks (cyan).
WEAK_COLORS = {1: (0.55, 0.88, 0.95), 2: (0.0, 0.78, 1.0)}
#: The pictures' legend of the weakness colours.
LEGEND = (f"cyan = breaks under a grip (safety < {BREAKS_BELOW:g}), "
          f"pale cyan = marginal (safety < {MARGINAL_BELOW:g})")


def weakness_levels(face_safety: np.ndarray) -> np.ndarray:
    """How weak each face is: 0 sound, 1 marginal, 2 breaks under the grip.

    Parameters
    ----------
    face_safety : (f,) float64
        The least safety factor of the sections cutting each face (inf: none cuts it), as
        :attr:`~supportless.energies.strength.Strength.face_safety`.

    Returns
    -------
    levels : (f,) int8
    """
    s = np.asarray(face_safety, np.float64)
    return (s < MARGINAL_BELOW).astype(np.int8) + (s < BREAKS_BELOW).astype(np.int8)


def weak_face_colors(face_safety: np.ndarray, risky: np.ndarray | None = None) -> np.ndarray:
    """The unshaded colour of each face of a picture: grey, red where it needs support, weakness over both.

    Parameters
    ----------
    face_safety : (f,) float64
        See :func:`weakness_levels`.
    risky : (f,) bool, optional
        Faces needing support (drawn red, as :func:`~supportless.report.render.render_mesh` draws them).

    Returns
    -------
    colors : (f, 3) float64
        RGB in [0, 1], for :func:`~supportless.report.render.render_before_after`'s ``face_colors``.
    """
    levels = weakness_levels(face_safety)
    colors = _face_base_colors(len(levels), None, risky, _BASE_COLOR)
    for level, color in WEAK_COLORS.items():
        colors[levels == level] = color
    return colors


def weakest_caption(entry: dict | None, label: str = "weakest") -> str | None:
    """A pose's weakest section in one line: ``weakest: LeftLeg 8 mm up, breaks at 0.9 N (safety 0.45)``.

    Parameters
    ----------
    entry : dict or None
        :func:`~supportless.report.report.weakest_section`'s JSON (``report["strength"]["rest"]`` or
        ``["answer"]``).
    label : str
        The line's first words (``weakest as printed`` for a pose drawn standing but printed turned).

    Returns
    -------
    caption : str or None
        None without an entry; ``weakest: none under load`` when nothing pulls on the body.
    """
    if not entry:
        return None
    w = entry.get("weakest")
    if not w:
        return f"{label}: none under load"
    bone = (w.get("bone") or "?").split(":")[-1]
    breaks = "never breaks under a grip" if w.get("breaks_at_n") is None else f"breaks at {w['breaks_at_n']:.1f} N"
    safety = float(entry["safety_factor"])
    safety_text = f"{safety:.2g}" if safety < 10 else f"{safety:.0f}"
    return f"{label}: {bone} {w['height_mm']:.0f} mm up, {breaks} (safety {safety_text})"
