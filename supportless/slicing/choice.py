"""Which slicer measures the support, and which support it lays down: PrusaSlicer's grid, Cura's normal or tree."""

from __future__ import annotations

from dataclasses import dataclass

from ..base.errors import InputError
from ..files.printer import slicer_label

__all__ = ["ENGINES", "SUPPORTS", "SlicerChoice", "choose_slicer"]

#: The slicers this tool drives.
ENGINES = ("prusa", "cura")
#: The support structures: ``grid`` (PrusaSlicer's supports, Cura's "normal") and ``tree`` (Cura only).
SUPPORTS = ("grid", "tree")


@dataclass(frozen=True)
class SlicerChoice:
    """A slicer and its support structure.

    Attributes
    ----------
    engine : str
        ``prusa`` or ``cura``.
    support : str
        ``grid`` or ``tree`` (``tree`` with Cura only: PrusaSlicer 2.5 has no tree supports).
    cura_definitions : str or None
        The folder of Cura's printer definitions (default: looked for, see :mod:`supportless.slicing.cura`).
    """

    engine: str = "prusa"
    support: str = "grid"
    cura_definitions: str | None = None

    def __post_init__(self):
        if self.engine not in ENGINES:
            raise InputError(None, f"unknown slicer {self.engine!r}; choose from {', '.join(ENGINES)}")
        if self.support not in SUPPORTS:
            raise InputError(None, f"unknown support {self.support!r}; choose from {', '.join(SUPPORTS)}")
        if self.engine == "prusa" and self.support == "tree":
            raise InputError(None, "PrusaSlicer 2.5 lays down grid supports only: --support tree needs --slicer cura")

    @property
    def label(self) -> str:
        """``PrusaSlicer``, ``Cura`` or ``Cura, tree supports``: for tables and messages."""
        return slicer_label(self.to_dict())

    def to_dict(self) -> dict:
        """``{"engine": ..., "support": ...}``, as a slicer report has them."""
        return {"engine": self.engine, "support": self.support}


def choose_slicer(engine: str | None = None, support: str = "grid", cura_definitions=None) -> SlicerChoice:
    """The slicer asked for, or the default one: PrusaSlicer if it is found, else Cura if it is found.

    Parameters
    ----------
    engine : str, optional
        ``prusa`` or ``cura``; None chooses (tree supports choose Cura).
    support : str
        ``grid`` or ``tree``.
    cura_definitions : str or os.PathLike, optional

    Returns
    -------
    choice : SlicerChoice
        With neither slicer installed, PrusaSlicer (whose run then says how to install it).
    """
    if engine is None:
        from .cura import find_cura_engine
        from .prusaslicer import find_prusa_slicer

        if support == "tree" or (find_prusa_slicer() is None and find_cura_engine() is not None):
            engine = "cura"
        else:
            engine = "prusa"
    return SlicerChoice(engine, support, None if cura_definitions is None else str(cura_definitions))
