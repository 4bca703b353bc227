"""Filaments as printed: their density and their strength along the printed lines and across the layers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..files.printer import PrinterProfile

__all__ = ["DEFAULT_MATERIAL", "MATERIALS", "Material", "effective_strength", "material_of", "mostly_across"]


@dataclass(frozen=True)
class Material:
    """A filament's figures for the strength analysis.

    Attributes
    ----------
    name : str
    density : float
        g/cm³.
    along_mpa : float
        Tensile strength along the printed lines, MPa.
    interlayer : float
        The bond between layers as a share of ``along_mpa``.
    young_mpa : float
        Young's modulus, MPa (the finite element reference).
    poisson : float
    """

    name: str
    density: float
    along_mpa: float
    interlayer: float
    young_mpa: float
    poisson: float = 0.35

    @property
    def across_mpa(self) -> float:
        """Tensile strength across the layers, MPa."""
        return self.along_mpa * self.interlayer

    def to_dict(self) -> dict:
        return {"name": self.name, "density_g_cm3": self.density, "along_mpa": self.along_mpa,
                "across_mpa": round(self.across_mpa, 2), "interlayer": self.interlayer}


#: Common filaments as printed (typical published test figures of printed bars, not of the raw resin): tensile
#: strength along the lines and the share the layers' bond keeps (FDM interlayer strength is commonly 50–90 % of
#: in-plane; PLA at the lower end).
MATERIALS = {
    "PLA": Material("PLA", 1.24, 50.0, 0.5, 3500.0),
    "PETG": Material("PETG", 1.27, 45.0, 0.7, 2100.0),
    "ABS": Material("ABS", 1.04, 35.0, 0.6, 2200.0),
}
#: The filament when the printer profile names none of :data:`MATERIALS`.
DEFAULT_MATERIAL = "PLA"


def material_of(profile: PrinterProfile | None) -> Material:
    """The filament of a printer profile (PrusaSlicer's ``filament_type``, Cura's ``material_type``), its density
    from the profile when it gives one; :data:`DEFAULT_MATERIAL` otherwise."""
    base = MATERIALS[DEFAULT_MATERIAL]
    if profile is None:
        return base
    raw = getattr(profile, "raw", {}) or {}
    named = str(raw.get("filament_type") or raw.get("material_type") or "").strip().strip('"').upper()
    base = MATERIALS.get(named, base)
    density = float(getattr(profile, "filament_density", 0.0) or 0.0)
    if "filament_density" in raw and density > 0 and abs(density - base.density) > 1e-9:
        base = Material(base.name, density, base.along_mpa, base.interlayer, base.young_mpa, base.poisson)
    return base


def effective_strength(material: Material, normal_z: np.ndarray | float) -> np.ndarray:
    """The uniaxial strength along a direction whose vertical component is ``normal_z``, MPa.

    A stress along a unit direction ``n`` pulls the layers apart with its share ``n_z²`` and the lines with
    ``1 - n_z²``; the strength interpolates between the two quadratically (a Tsai–Hill form without shear):
    ``1 / S² = n_z² / S_across² + (1 - n_z²) / S_along²``, from ``S_across`` (vertical) to ``S_along``
    (horizontal), never outside them.

    Parameters
    ----------
    material : Material
    normal_z : float or (s,) float64

    Returns
    -------
    strength : float or (s,) float64
    """
    c2 = np.asarray(normal_z, np.float64) ** 2
    return 1.0 / np.sqrt(c2 / material.across_mpa ** 2 + (1.0 - c2) / material.along_mpa ** 2)


def mostly_across(material: Material, normal_z: float) -> bool:
    """Whether a stress along a direction whose vertical component is ``normal_z`` is held mostly by the bond
    between layers (its term of :func:`effective_strength` is the larger)."""
    c2 = float(normal_z) ** 2
    return c2 / material.across_mpa ** 2 >= (1.0 - c2) / material.along_mpa ** 2
