"""The print frame: where a model goes in a file a slicer opens.

Every slicer (PrusaSlicer, Cura, Orca, Bambu Studio) and the 3MF core
specification take +Z as up and millimetres as the unit. The tool works in the
model's own frame (its up axis is ``--up``, its unit whatever the file used);
:class:`PrintFrame` maps that frame to the printer's: ``up`` turned to +Z by the
smallest rotation, one uniform scale to millimetres, the bounding box centred on
x = y = 0 and the lowest point at z = 0. glTF keeps its own convention (+Y up,
metres): :meth:`PrintFrame.to_gltf`.

The scale is chosen once per model, from its rest pose: by default the rest
pose is printed :data:`REFERENCE_HEIGHT_MM` tall, the height the tool's slicer
figures are for; ``--height-mm`` chooses another height and ``--keep-units``
keeps the file's own units (read as millimetres; glTF metres become
millimetres).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.errors import InputError

__all__ = ["BELIEVABLE_FILE_HEIGHT_MM", "PRINT_HEIGHT_RANGE_MM", "REFERENCE_HEIGHT_MM", "USUAL_HEIGHT_MM", "PrintFrame", "place_vertices", "print_frame", "rig_print_frame",
           "rotation_to_z"]

#: The printed height of a model's rest pose when the user gives none, mm: a figurine.
REFERENCE_HEIGHT_MM = 60.0
#: The printed heights a user may ask for, mm, ``(low, high)`` inclusive: the one bound of every command's
#: ``--height-mm`` and of :data:`supportless.search.settings.RANGES` ``["print_height_mm"]``.
PRINT_HEIGHT_RANGE_MM = (0.01, 100_000.0)
#: Printed heights outside this range (mm) are unusual for a figure: the tool says so.
USUAL_HEIGHT_MM = (10.0, 300.0)

#: Heights, in mm, a model whose file states its units (glTF: metres) is
#: believed to have: outside them the file's units are probably wrong (a
#: 79 m fox, a 3 mm person) and the user is told how to choose the size.
BELIEVABLE_FILE_HEIGHT_MM = (1.0, 10_000.0)


def rotation_to_z(up) -> np.ndarray:
    """The minimal proper rotation taking ``up`` to +Z.

    Parameters
    ----------
    up : (3,) float
        Any non-zero direction.

    Returns
    -------
    R : (3, 3) float64
        Rotation about ``up x z`` (``det R = 1``, never a mirror); for
        ``up = +Y`` it is +90 degrees about X: y -> z, z -> -y.

    Raises
    ------
    ValueError
        For a zero or non-finite ``up``.
    """
    u = np.asarray(up, dtype=np.float64).reshape(3)
    n = np.linalg.norm(u)
    if not np.isfinite(n) or n < 1e-12:
        raise ValueError(f"up direction must be a non-zero 3-vector, got {up!r}")
    u = u / n
    c = float(u[2])
    if c > 1.0 - 1e-12:
        return np.eye(3)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])  # 180 degrees about X
    axis = np.cross(u, [0.0, 0.0, 1.0])
    s = np.linalg.norm(axis)
    k = axis / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def place_vertices(vertices: np.ndarray, up, scale: float, center_xy=(0.0, 0.0)) -> np.ndarray:
    """Put a mesh on the bed: ``up`` to +Z, scaled, lowest point at z = 0, its x/y box centred at ``center_xy``.

    Parameters
    ----------
    vertices : (n, 3) float64
    up : (3,) float
    scale : float
        Model units to mm.
    center_xy : (2,) float
        Where the centre of the x/y bounding box goes.

    Returns
    -------
    placed : (n, 3) float64
    """
    v = (np.asarray(vertices, dtype=np.float64) @ rotation_to_z(up).T) * float(scale)
    lo, hi = v.min(axis=0), v.max(axis=0)
    mid = 0.5 * (lo + hi)
    return v + np.array([center_xy[0] - mid[0], center_xy[1] - mid[1], -lo[2]])


@dataclass(frozen=True)
class PrintFrame:
    """The map from a model's frame to a printer's: ``up`` to +Z, millimetres, centred, on the plate.

    Attributes
    ----------
    up : (d,) float64
        The model's printing direction (unit); d = 2 for a planar figure,
        which is only placed on its plate line, never turned or scaled.
    scale : float
        Model units to millimetres.
    height_mm : float
        The printed height of the rest pose along ``up``, mm.
    model_height : float
        The rest pose's height along ``up`` in the model's units.
    how : str
        ``"default"`` (:data:`REFERENCE_HEIGHT_MM`), ``"height"`` (the user's
        ``--height-mm``) or ``"units"`` (``--keep-units``).
    unit : str
        The model's unit as far as it is known: ``"mm"`` (a glTF asset, whose
        metres are read as millimetres) or ``"units"`` (a mesh file, which
        says nothing; read as millimetres).
    """

    up: np.ndarray
    scale: float
    height_mm: float
    model_height: float
    how: str = "default"
    unit: str = "units"

    def place(self, vertices: np.ndarray) -> np.ndarray:
        """Vertices in the print frame: turned so ``up`` is +Z, in mm, x/y centred on 0, lowest z = 0.

        Parameters
        ----------
        vertices : (n, 3) float64
            In the model's frame and units (any pose, any turn: the lowest
            point goes to the plate along +Z). A planar ``(n, 2)`` figure is
            only moved so its lowest point along ``up`` is at 0.

        Returns
        -------
        placed : (n, 3) or (n, 2) float64
        """
        V = np.asarray(vertices, np.float64)
        if V.shape[1] == 2:
            return V - (V @ self.up).min() * self.up
        return place_vertices(V, self.up, self.scale)

    def to_gltf(self, vertices: np.ndarray) -> np.ndarray:
        """Vertices as glTF wants them: the print frame with +Y up, in metres (x, z, -y) / 1000.

        Parameters
        ----------
        vertices : (n, 3) float64
            In the model's frame, as for :meth:`place`.

        Returns
        -------
        gltf : (n, 3) float64
        """
        P = self.place(vertices)
        return np.column_stack([P[:, 0], P[:, 2], -P[:, 1]]) / 1000.0

    def note(self) -> str:
        """One line for the user: how tall the model is printed, and how to change it."""
        own = (_length(self.model_height) if self.unit == "mm" else f"{self.model_height:.3g} {self.unit}")
        if self.how == "units":
            return f"printed {_length(self.height_mm)} tall, the file's own size (--height-mm H to scale it)"
        if self.how == "height":
            return f"printed {_length(self.height_mm)} tall (--height-mm; the file's own size is {own})"
        return (f"printed {_length(self.height_mm)} tall (the file's own size is {own}); --height-mm H to "
                "change it, --keep-units to keep the file's size")

    def unusual(self) -> str | None:
        """A warning when the printed height is far outside :data:`USUAL_HEIGHT_MM`, or the file's
        own height (in a file that states millimetres) outside :data:`BELIEVABLE_FILE_HEIGHT_MM`; else None."""
        if self.unit == "mm" and len(self.up) == 3 and not (
                BELIEVABLE_FILE_HEIGHT_MM[0] <= self.model_height <= BELIEVABLE_FILE_HEIGHT_MM[1]):
            return (f"the file says the model is {_length(self.model_height)} tall, outside "
                    f"{_length(BELIEVABLE_FILE_HEIGHT_MM[0])}-{_length(BELIEVABLE_FILE_HEIGHT_MM[1])}: its units may "
                    f"be wrong; it is printed {_length(self.height_mm)} tall (--height-mm H sets the printed height)")
        lo, hi = USUAL_HEIGHT_MM
        if lo <= self.height_mm <= hi or len(self.up) != 3:
            return None
        return (f"the model is printed {_length(self.height_mm)} tall, far outside the usual {lo:g}-{hi:g} mm of a "
                f"figure; --height-mm H sets the printed height")

    def to_dict(self) -> dict:
        """JSON: ``up``, ``scale``, ``height_mm``, ``model_height``, ``how`` and the frame's convention."""
        return {"up": np.asarray(self.up, np.float64).tolist(), "scale": float(self.scale),
                "height_mm": float(self.height_mm), "model_height": float(self.model_height), "how": self.how,
                "unit": self.unit,
                "convention": "+Z up, millimetres, x/y centred on 0, lowest point at z = 0"}


def _length(mm: float) -> str:
    """A length for people: ``60 mm``, ``0.15 mm``, ``4.5 m``."""
    mm = float(mm)
    return f"{mm / 1000:.3g} m" if mm >= 1000 else f"{mm:.3g} mm" if mm < 10 else f"{mm:.0f} mm"


def print_frame(vertices: np.ndarray, up, height_mm: float | None = None, keep_units: bool = False,
                unit: str = "units") -> PrintFrame:
    """The print frame of a model whose rest pose is ``vertices``.

    Parameters
    ----------
    vertices : (n, d) float64
        The rest pose, in the model's units.
    up : (d,) float64
        Unit printing direction.
    height_mm : float, optional
        Print the rest pose this tall (default :data:`REFERENCE_HEIGHT_MM`).
    keep_units : bool
        Keep the model's units as millimetres (scale 1); not with ``height_mm``.
    unit : str
        The model's unit, see :class:`PrintFrame`.

    Returns
    -------
    frame : PrintFrame

    Raises
    ------
    InputError
        A model with no height along ``up``, or ``height_mm`` with ``keep_units``.
    """
    V = np.asarray(vertices, np.float64)
    u = np.asarray(up, np.float64).ravel()
    u = u / np.linalg.norm(u)
    extent = float(np.ptp(V @ u)) if len(V) else 0.0
    if not (np.isfinite(extent) and extent > 0):
        raise InputError(None, "the model has no height along the printing direction: nothing to print")
    if keep_units and height_mm is not None:
        raise InputError(None, "--keep-units and --height-mm do not go together; choose one")
    if V.shape[1] == 2:
        return PrintFrame(u, 1.0, extent, extent, "units", unit)
    if keep_units:
        return PrintFrame(u, 1.0, extent, extent, "units", unit)
    height = REFERENCE_HEIGHT_MM if height_mm is None else float(height_mm)
    if not (np.isfinite(height) and height > 0):
        raise InputError(None, f"the printed height must be a positive number of mm, got {height_mm!r}")
    return PrintFrame(u, height / extent, height, extent, "default" if height_mm is None else "height", unit)


def rig_print_frame(rig, height_mm: float | None = None, keep_units: bool = False) -> PrintFrame:
    """:func:`print_frame` of a rig's rest pose (a glTF rig's unit is the millimetre).

    Parameters
    ----------
    rig : Rig
        Anything with ``vertices`` (n, d), ``up`` (d,) and ``info`` (dict).
    height_mm, keep_units
        As :func:`print_frame`.

    Returns
    -------
    frame : PrintFrame
    """
    unit = "mm" if rig.info.get("gltf") is not None else "units"
    return print_frame(rig.vertices, rig.up, height_mm, keep_units, unit)
