"""supportless: re-pose a rigged model so it 3D-prints with far less support.

The pipeline (see the README): a closed surface and its skeleton become a
:class:`Rig` (tetrahedral mesh + bounded biharmonic weights); Euler angles per
bone pose it by linear blend skinning; three energies of the posed surface
(ARAP distortion, overhang support, self-intersection volume) make the
:class:`Objective`; :func:`optimize` searches the rotations with a particle
swarm, as :class:`SearchSettings` say; :mod:`supportless.report.report` measures and
draws the result.
"""

from .base import numba_cache

numba_cache.configure()  # before numba is imported: a read-only install with no home still runs

from .base.errors import InputError, SlicerError, SupportlessError
from .base.kinematics import forward_kinematics, lbs_matrix, skin
from .energies.arap import arap_energy, arap_energy_direct, arap_precompute
from .energies.intersection import self_intersection_volume
from .energies.overhang import overhang_energy, risky_area, risky_faces
from .energies.support import support_volume
from .files.meshes import read_mesh, read_tgf, write_mesh, write_tgf
from .files.posefile import read_pose, write_pose
from .rig.load import load_rig
from .rig.rig import Rig, prepare_rig
from .search.objective import Objective
from .search.answer import optimize
from .search.optimizer import PoseResult, particle_swarm
from .search.settings import SearchSettings
from .shapes import DEMO_FIGURES, demo_figure

__version__ = "0.1.0"

#: Names of later stages, imported when first used (matplotlib and the slicer bridge stay out of ``import supportless``).
_LATER = {"build_report": "supportless.report.report", "write_pictures": "supportless.report.report",
          "slice_check": "supportless.slicing.prusaslicer"}


def __getattr__(name: str):
    if name in _LATER:
        import importlib

        return getattr(importlib.import_module(_LATER[name]), name)
    raise AttributeError(f"module 'supportless' has no attribute {name!r}")


__all__ = [
    "DEMO_FIGURES", "InputError", "Objective", "PoseResult", "Rig", "SearchSettings", "SlicerError", "SupportlessError",
    "arap_energy", "arap_energy_direct", "arap_precompute", "build_report", "demo_figure", "forward_kinematics",
    "lbs_matrix", "load_rig", "optimize", "overhang_energy", "particle_swarm", "prepare_rig", "read_mesh", "read_pose",
    "read_tgf", "risky_area", "risky_faces", "self_intersection_volume", "skin", "slice_check", "support_volume",
    "write_mesh", "write_pictures", "write_pose", "write_tgf",
]
