"""What a pose search is asked to do: one frozen settings object.

:class:`SearchSettings` holds the search's defaults (those the objective takes too, the weights and the
limits, are named in :mod:`supportless.search.objective`, whose
:class:`~supportless.search.objective.Objective` defaults to them), and
:data:`RANGES` the values each setting may take (the command line's and the
browser app's limits too); the rule that turns the printer's overhang
threshold into the one the search minimises is
:func:`supportless.files.printer.search_angle`. It builds the
:class:`~supportless.search.objective.Objective`, is stored in the report, and is
what the command line, the browser app and the benchmarks pass around.

The bone selection (which bones the search may rotate) lives here too: it turns
the ``fix``/``free`` settings and the rig into the search's variables.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..base.errors import InputError
from ..energies.raygrid import DEFAULT_RESOLUTION
from ..files.printframe import PRINT_HEIGHT_RANGE_MM, REFERENCE_HEIGHT_MM
from ..files.printer import DEFAULT_OVERHANG_ANGLE, OVERHANG_MARGIN, search_angle
from ..rig.rig import Rig
from ..rig.contact import ContactRules
from .anatomy import bone_part, joint_ranges
from .relaxed import arm_drops
from .objective import OVERHANG_MODELS, Objective, distortion
from .weights import (CHAIN_LIMIT, FOOTPRINT_MM2, HEAD_LIMIT, JOINT_LIMIT, W_ARAP, W_CHAIN, W_INTERSECT, W_OVERHANG,
                      W_PRIOR)

__all__ = ["AUTO", "DEFAULT_OVERHANG_ANGLE", "ORIENT_MODES", "ORIENT_SEEDS", "OVERHANG_MARGIN", "RANGES", "SearchSettings",
           "angle_layout", "bone_index", "resolve_fixed_bones"]


class _Auto:
    """The type of :data:`AUTO`."""

    def __repr__(self) -> str:
        return "AUTO"


#: ``SearchSettings.replace(name=AUTO)`` sets ``name`` to ``None``: the value the tool chooses.
AUTO = _Auto()

#: Least safety factor of an answer that is weaker than the rest pose as it stands (:attr:`SearchSettings.min_safety`):
#: the strength of its weakest section over the stress of its own weight and a 2 N grip at one chain end
#: (:func:`supportless.energies.strength.analyse_strength`). 1: it holds the grip. Chosen on the zoo and the shared
#: characters: see benchmarks/RESULTS.md, "Strength of a pose".
MIN_SAFETY = 1.0

#: Filaments the strength analysis knows (:data:`supportless.energies.strength.MATERIALS`).
MATERIAL_NAMES = ("PLA", "PETG", "ABS")

#: Print-orientation modes (:attr:`SearchSettings.orient`).
ORIENT_MODES = ("free", "keep")

#: Candidate printing directions the swarm starts particles at (the best by the
#: prism estimate at the rest pose). See benchmarks/RESULTS.md, "Pose and
#: orientation".
ORIENT_SEEDS = 4

#: The largest swarm and the most iterations a search takes (5000 particles measure the bunny in
#: about 300 MB; more is a mistake or an attack on the browser app, not a better search).
MAX_PARTICLES = 5000
MAX_ITERATIONS = 100_000

#: The allowed values of each numeric setting, ``(low, high)`` inclusive (``None``: no bound): the one source
#: of :class:`SearchSettings`' checks, the command line's option types and the browser app's fields.
RANGES = {
    "particles": (2, MAX_PARTICLES),  # one particle is no swarm: it only ever follows itself
    "iterations": (0, MAX_ITERATIONS),  # 0: the rest pose and the start positions only
    "polish": (0, MAX_ITERATIONS),
    "seed": (0, None),
    "joint_limit": (0.0, 180.0),
    "chain_limit": (0.0, 180.0),
    "head_limit": (0.0, 180.0),
    "footprint_mm2": (0.0, 10_000.0),
    "min_safety": (0.0, 100.0),
    "print_height_mm": PRINT_HEIGHT_RANGE_MM,
    "overhang_angle": (0.0, 90.0),
    "overhang_margin": (0.0, 45.0),
    "w_arap": (0.0, None),
    "w_overhang": (0.0, None),
    "w_intersect": (0.0, None),
    "w_prior": (0.0, None),
    "w_chain": (0.0, None),
}

#: Velocity-update coefficients of the swarm. ``standard`` is the
#: constriction-factor swarm (Clerc & Kennedy); ``libigl`` reproduces igl::pso's.
#: The searches (:data:`supportless.search.swarm.OPTIMIZERS`).
OPTIMIZER_NAMES = ("cma", "pso")

PSO_PRESETS = {
    "standard": {"inertia": 0.7298, "cognitive": 1.49618, "social": 1.49618},
    "libigl": {"inertia": 0.98, "cognitive": 0.01, "social": 0.01},
}


#: Bones that move less of the volume than this share follow their parent by
#: default (:attr:`SearchSettings.minor_share`).
MINOR_SHARE = 0.003


@dataclass(frozen=True)
class SearchSettings:
    """Every setting of a pose search, with the tool's defaults.

    Attributes
    ----------
    particles, iterations : int
        Swarm size and number of iterations (the paper: 200 x 120).
    seed : int
        Same seed, same result.
    overhang_angle : float
        The printer's overhang threshold, degrees from the build plate: what
        reports count as needing support (default: PrusaSlicer's automatic
        threshold at its default profile, :data:`DEFAULT_OVERHANG_ANGLE`; see
        :attr:`supportless.files.printer.PrinterProfile.overhang_angle`).
    overhang_margin : float
        The search counts faces up to ``overhang_angle + overhang_margin`` as
        needing support (see :data:`OVERHANG_MARGIN`).
    overhang_model : {"prism", "column", "slicer"}
        Support estimate the search minimises (:class:`supportless.search.objective.Objective`).
    w_arap, w_overhang, w_intersect : float
        Weights of the normalised terms.
    fix, free : tuple of str
        Bones to fix / free beyond the default (1-based numbers or ``"all"``),
        see :func:`resolve_fixed_bones`.
    preset : {"standard", "libigl"}
        Swarm coefficients, see :data:`PSO_PRESETS`.
    optimizer : {"pso", "cma"}
        ``pso``: the paper's particle swarm, ``particles`` for ``iterations``
        (the default: on the zoo it reaches the lower objective more often,
        ``benchmarks/optimizers.py``); ``cma``: CMA-ES with ``particles // 5``
        samples per generation for ``iterations`` generations
        (:func:`supportless.search.swarm.evolution_strategy`), faster.
    polish : int or None
        Generations of a local CMA-ES after the swarm, from its best pose with
        small steps (:data:`supportless.search.optimizer.POLISH_SIGMA`); after a dense
        model's proxy search it runs on the full surface. None (the default):
        :data:`supportless.search.answer.PROXY_POLISH_BUDGET` over the number of
        triangles after a proxy search (whose best is not quite the full
        surface's), none otherwise (on the bunny, at a353b18, 120 generations
        gained 0.4 % of the objective for 30 % more time).
    exact_intersections : bool
        Reject candidates for the swarm's best whose surface has intersecting
        triangles (CGAL's exact test, 3D).
    w_prior : float
        Weight of the natural-pose prior (:mod:`supportless.search.prior`).
    joint_limit : float
        Largest rotation of a joint, degrees, as one (geodesic) angle: the
        search turns each free bone by a rotation vector inside this ball.
        0 fixes every bone (with ``orient="free"``: turning only).
    limits : tuple of str
        Per-bone limits ``"BONE=DEGREES"`` (1-based bone numbers), e.g. ``("5=15",)``.
    chain_limit : float, optional
        Largest turn of a chain's end (a head, a hand, a tail tip) in the
        world from its rest direction, degrees: a hard rule over the whole
        chain, where ``joint_limit`` bounds each joint alone
        (:mod:`supportless.search.naturalness`); default :data:`CHAIN_LIMIT`.
        None (or 180): no such rule.
    head_limit : float, optional
        Largest turn of a head (the bone its name says is the head, or the top
        of an upright figure, :func:`supportless.search.naturalness.head_bones`)
        in the world from its rest direction, degrees: the same rule as
        ``chain_limit``, tighter; default :data:`HEAD_LIMIT`. None (or 180): no such rule.
    footprint_mm2 : float
        Least contact a turned print's first layer has with the plate, mm² at ``print_height_mm`` tall
        (:meth:`supportless.search.objective.Objective.footprint_shortfall`); a turn resting on less (a tip, an
        edge) is refused. Default :data:`FOOTPRINT_MM2`; 0: no such rule. The model as it stands is never judged.
    print_height_mm : float
        The printed height of the rest pose along up, mm (the print frame's), for ``footprint_mm2`` and strength.
    min_safety : float
        The choice among answers (:func:`supportless.search.choice.strong_enough`) never hands back one whose safety
        factor (:func:`supportless.energies.strength.analyse_strength`) is below both the rest pose's, as it stands
        (less :data:`supportless.search.choice.REST_STRENGTH_TOLERANCE`), and this. Default :data:`MIN_SAFETY`; 0:
        strength is not weighed.
    material : str
        The filament (one of :data:`MATERIAL_NAMES`) the strength is judged in; the CLI takes the printer
        profile's.
    w_chain : float
        Weight of the chain ends' squared world turn (radians) in the
        natural-pose prior (:meth:`supportless.search.objective.Objective.prior_cost`);
        default :data:`supportless.search.objective.W_CHAIN`; 0 leaves the prior to the
        joints' own turns.
    anatomy : bool
        Keep the joints the bone names identify (a glTF character's knees,
        elbows, spine, neck) within their range of motion
        (:mod:`supportless.search.anatomy`); bones without a known name keep
        the generic limits only.
    contact : bool
        Let a part press into a part it is jointed to, near their shared joint
        (an arm resting against the torso, thighs together): such crossings,
        within :mod:`supportless.rig.contact`'s bounds, pass the exact gate, and
        the written body is the posed surface's union with itself. False:
        any crossing refuses a pose.
    relaxed : bool
        Start some of the swarm's particles at relaxed poses, limbs let down
        toward gravity (:mod:`supportless.search.relaxed`; the rest pose is
        always one of them), and, with ``anatomy``, count a named upper arm's
        turn down toward the body as no departure from a natural pose (the
        prior and the chain limit judge what else it and its hand do).
    keep_standing : bool
        Reject poses that touch the plate with a new part or fall over
        (:mod:`supportless.search.standing`).
    symmetric : bool or None
        True: keep left/right pairs of bones mirror images
        (:mod:`supportless.search.layout`); False: pose each bone freely;
        None (the default): mirrored for a figure whose rest skeleton has a
        mirror plane, else free (:func:`supportless.search.answer.mirrored_answer`);
        a start pose that breaks the mirror is searched freely.
    orient : {"free", "keep"}
        ``free``: search the print orientation with the pose (support is
        counted with the posed model turned by a rotation R,
        :mod:`supportless.search.orientation`); ``keep``: print as the model stands.
    choose : bool
        With ``orient="free"`` (3D), return the answer with the least
        predicted slicer support among the search's best, the best pose
        printed as it stands and the best turned start pose
        (:func:`supportless.search.choice.choose`); False: the search's best.
    orient_seeds : int
        With ``orient="free"``, particles started (at the rest pose) at this
        many of the best-ranked candidate printing directions.
    support_floor : float
        Fixed cost of support however low it is: a height added to every
        prism of the estimate, as a fraction of the model's height.
    minor_share : float
        Bones that move less than this share of the volume when they turn
        (:attr:`Rig.moved_share`: fingers, toes, facial joints of a game
        character) follow their parent unless ``free``d: fewer dimensions to
        search, and they barely change the support.
    clusters : int or None
        Rotation clusters of the reduced ARAP energy.
    resolution : int
        Ray-grid resolution of the intersection (and column) estimate.
    backend : {"fast", "numpy"}
        Energy kernels: numba (parallel over poses) or the numpy reference.
    """

    particles: int = 200
    iterations: int = 120
    seed: int = 0
    overhang_angle: float = DEFAULT_OVERHANG_ANGLE
    overhang_margin: float = OVERHANG_MARGIN
    overhang_model: str = "prism"
    w_arap: float = W_ARAP
    w_overhang: float = W_OVERHANG
    w_intersect: float = W_INTERSECT
    fix: tuple = ()
    free: tuple = ()
    preset: str = "standard"
    optimizer: str = "pso"
    polish: int | None = None
    exact_intersections: bool = True
    w_prior: float = W_PRIOR
    joint_limit: float = JOINT_LIMIT
    limits: tuple = ()
    chain_limit: float | None = CHAIN_LIMIT
    head_limit: float | None = HEAD_LIMIT
    footprint_mm2: float = FOOTPRINT_MM2
    print_height_mm: float = REFERENCE_HEIGHT_MM
    min_safety: float = MIN_SAFETY
    material: str = "PLA"
    w_chain: float = W_CHAIN
    anatomy: bool = True
    contact: bool = True
    relaxed: bool = True
    keep_standing: bool = True
    symmetric: bool | None = None
    orient: str = "free"
    orient_seeds: int = ORIENT_SEEDS
    choose: bool = True
    support_floor: float = 0.0
    minor_share: float = MINOR_SHARE
    clusters: int | None = 100
    resolution: int = DEFAULT_RESOLUTION
    backend: str = "fast"

    def __post_init__(self):
        # bone lists arrive as lists, tuples or one comma-separated string
        for name in ("fix", "free", "limits"):
            value = getattr(self, name)
            if isinstance(value, str):
                value = [value]
            items = tuple(t for v in (value or ()) for t in str(v).replace(",", " ").split())
            object.__setattr__(self, name, items)
        if self.overhang_model not in OVERHANG_MODELS:
            raise InputError(None, f"overhang_model must be one of {OVERHANG_MODELS}, not {self.overhang_model!r}")
        if self.preset not in PSO_PRESETS:
            raise InputError(None, f"preset must be one of {tuple(PSO_PRESETS)}, not {self.preset!r}")
        if self.optimizer not in OPTIMIZER_NAMES:
            raise InputError(None, f"optimizer must be one of {OPTIMIZER_NAMES}, not {self.optimizer!r}")
        for name in ("particles", "iterations", "polish"):
            low, high = RANGES[name]
            value = getattr(self, name)
            if value is not None and not low <= value <= high:
                raise InputError(None, f"{name} must be within {low}..{high}, not {value}")
        if self.orient not in ORIENT_MODES:
            raise InputError(None, f"orient must be one of {ORIENT_MODES}, not {self.orient!r}")
        if self.orient_seeds < 0:
            raise InputError(None, f"orient_seeds must be at least 0, not {self.orient_seeds}")
        if not _within(self.joint_limit, RANGES["joint_limit"]):
            raise InputError(None, f"joint_limit must be within 0..180 degrees, not {self.joint_limit}")
        if self.chain_limit is not None and not _within(self.chain_limit, RANGES["chain_limit"]):
            raise InputError(None, f"chain_limit must be within 0..180 degrees, not {self.chain_limit}")
        if self.head_limit is not None and not _within(self.head_limit, RANGES["head_limit"]):
            raise InputError(None, f"head_limit must be within 0..180 degrees, not {self.head_limit}")
        for name, unit in (("footprint_mm2", "mm²"), ("print_height_mm", "mm"), ("min_safety", "")):
            if not _within(getattr(self, name), RANGES[name]):
                low, high = RANGES[name]
                raise InputError(None, f"{name} must be within {low:g}..{high:g} {unit}, not {getattr(self, name)}")
        if self.material not in MATERIAL_NAMES:
            raise InputError(None, f"material must be one of {', '.join(MATERIAL_NAMES)}, not {self.material!r}")
        for item in self.limits:
            _bone, _, value = item.partition("=")
            try:
                ok = 0.0 <= float(value) <= 180.0
            except ValueError:  # float() of a bad number
                ok = False
            if not ok:
                raise InputError(None, f"joint limit {item!r} is not BONE=DEGREES with 0..180 degrees, e.g. 5=15")
        for name in ("w_arap", "w_overhang", "w_intersect", "w_prior", "w_chain", "support_floor", "overhang_margin"):
            value = float(getattr(self, name))
            if not np.isfinite(value):
                raise InputError(None, f"{name} (--{name.replace('_', '-')}) must be a finite number, "
                                       f"not {value}")
            if name == "overhang_margin" and not _within(value, RANGES[name]):
                raise InputError(None, f"overhang_margin must be within 0..45 degrees, not {value}")
            if value < 0 and name != "overhang_margin":
                raise InputError(None, f"{name} (--{name.replace('_', '-')}) must be 0 or more, not {value}: "
                                       f"a negative weight would reward what the term measures (0 leaves it out)")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise InputError(None, f"seed must be a whole number 0 or more, not {self.seed!r}")
        if not _within(self.overhang_angle, RANGES["overhang_angle"]):
            raise InputError(None, f"overhang_angle must be within 0..90 degrees, not {self.overhang_angle}")

    @property
    def search_overhang_angle(self) -> float:
        """The threshold the search minimises: ``min(overhang_angle + overhang_margin, 89)`` degrees.

        The ``slicer`` overhang model takes the printer's threshold itself (it carries its own fitted offset).
        """
        if self.overhang_model == "slicer":
            return self.overhang_angle
        return search_angle(self.overhang_angle, self.overhang_margin)

    def replace(self, **changes) -> SearchSettings:
        """A copy with some settings changed: ``None`` leaves a setting as it is, :data:`AUTO` sets it to ``None``.

        ``None`` is what a command passes for an option the user did not give;
        ``settings.replace(polish=AUTO)`` brings back a setting whose ``None``
        means "chosen by the tool".
        """
        return dataclasses.replace(self, **{k: None if v is AUTO else v for k, v in changes.items() if v is not None})

    def distortion(self, terms: dict):
        """The distortion part of normalised ``terms`` at these weights (:func:`supportless.search.objective.distortion`)."""
        return distortion(terms, self.w_arap, self.w_prior)

    def objective(self, rig: Rig, arap_data=None, volume: float | None = None) -> Objective:
        """The objective the search minimises for ``rig``.

        Parameters
        ----------
        rig : Rig
        arap_data : supportless.energies.arap.ArapData, optional
            Precomputed ARAP operators of ``rig`` to share (they depend on the
            rig and ``clusters`` only).
        volume : float, optional
            The normalising volume (:class:`~supportless.search.objective.Objective`;
            default: the rig's).

        Returns
        -------
        objective : Objective
        """
        return Objective(rig, w_arap=self.w_arap, w_overhang=self.w_overhang, w_intersect=self.w_intersect,
                         overhang_angle=self.search_overhang_angle, overhang_model=self.overhang_model,
                         clusters=self.clusters, resolution=self.resolution, backend=self.backend,
                         arap_data=arap_data, w_prior=self.w_prior, joint_limits=self.joint_limits(rig),
                         keep_standing=self.keep_standing, support_floor=self.support_floor, volume=volume,
                         chain_limit=self.chain_limit, head_limit=self.head_limit, w_chain=self.w_chain,
                         footprint_mm2=self.footprint_mm2, print_height_mm=self.print_height_mm,
                         joint_ranges=joint_ranges(rig) if self.anatomy else None,
                         contact=ContactRules() if self.contact else None,
                         drops=arm_drops(rig) if self.relaxed and self.anatomy else None)

    def joint_limits(self, rig: Rig) -> np.ndarray:
        """Largest rotation of each joint, degrees: ``joint_limit`` with the per-bone ``limits``, (m,) float64.

        With ``anatomy``, a named upper arm of a humanoid may turn as far as its swing range
        (:data:`~supportless.search.anatomy.HUMANOID_TABLE`, 90 degrees) when that is more: a T-posed figure's
        arms come down to its sides.

        Raises
        ------
        ValueError
            For a bone that is not a bone number of ``rig``.
        """
        out = np.full(rig.bone_count, float(self.joint_limit))
        if self.anatomy and self.joint_limit > 0:  # a named upper arm swings as far as its range: arms let down
            ranges = joint_ranges(rig)
            if ranges is not None and ranges.table == "humanoid":
                arms = np.array([i for i, name in enumerate(ranges.names) if bone_part(name)[0] == "upper_arm"],
                                np.int64)
                if len(arms):
                    out[ranges.child[arms]] = np.maximum(out[ranges.child[arms]], np.degrees(ranges.swing[arms]))
        for name, unit in (("footprint_mm2", "mm²"), ("print_height_mm", "mm")):
            if not _within(getattr(self, name), RANGES[name]):
                low, high = RANGES[name]
                raise InputError(None, f"{name} must be within {low:g}..{high:g} {unit}, not {getattr(self, name)}")
        for item in self.limits:
            bone, _, value = item.partition("=")
            out[bone_index(bone, rig.bone_count, rig.labels)] = float(value)
        return out

    def check_bones(self, bone_count: int, labels: list | None = None) -> None:
        """Check the bones named in ``fix``, ``free`` and ``limits`` against a skeleton, before a rig exists.

        Raises
        ------
        InputError
            For a bone that is not a bone number 1..``bone_count`` (or a name in ``labels``) or ``"all"``.
        """
        for item in (*self.fix, *self.free, *(x.partition("=")[0] for x in self.limits)):
            if str(item).lower() != "all":
                bone_index(item, bone_count, labels)

    def fixed_bones(self, rig: Rig) -> np.ndarray:
        """Which bones keep their rotation, (m,) bool: :func:`resolve_fixed_bones`, and bones limited to 0 degrees."""
        return resolve_fixed_bones(rig, self.fix, self.free, self.minor_share) | (self.joint_limits(rig) == 0.0)

    def all_fixed(self, rig: Rig) -> str | None:
        """Why no bone of ``rig`` may move under these settings, or None when some may.

        With ``orient="keep"`` there is then nothing to search; with
        ``"free"`` the search only turns the model. Raises as
        :meth:`fixed_bones` for a bad ``fix``/``free``.
        """
        if not self.fixed_bones(rig).all():
            return None
        return (f"every bone of {rig.name} is fixed ({int(rig.anchored_bones.sum())} of {rig.bone_count} rest on the "
                "build plate or join bones that do)")

    def to_dict(self) -> dict:
        """The settings as JSON-ready values, plus the derived ``search_overhang_angle``."""
        out = dataclasses.asdict(self)
        out["fix"], out["free"] = list(self.fix), list(self.free)
        out["search_overhang_angle"] = self.search_overhang_angle
        return out

    @classmethod
    def from_dict(cls, data: dict) -> SearchSettings:
        """Settings from :meth:`to_dict` output (unknown and derived keys are ignored)."""
        names = {f.name for f in dataclasses.fields(cls)}
        return cls(**{k: v for k, v in data.items() if k in names})


# --------------------------------------------------------------------------- #
# which bones the search rotates
# --------------------------------------------------------------------------- #
def resolve_fixed_bones(rig: Rig, fix: list | None = None, free: list | None = None,
                        minor_share: float = 0.0) -> np.ndarray:
    """Which bones keep their rest rotation during the search.

    By default the bones resting on the build plate and the bones joining
    them (:attr:`Rig.anchored_bones`): the parts on the plate stay where they
    are and the rest of the body moves relative to them, about the contact
    (the rig's kinematic tree hangs from it). Also the bones no vertex is
    weighted to (:attr:`Rig.weightless_bones`) and, with ``minor_share``, the
    bones carrying less than that share of the volume.

    Parameters
    ----------
    rig : Rig
    fix, free : list of int or str, optional
        Bones to fix or free in addition to (or against) the default: 1-based
        bone numbers as in the TGF file (ints or digit strings), bone names
        (:attr:`Rig.labels`), or ``"all"``.
    minor_share : float
        Fix the bones that move less than this share of the volume
        (:attr:`Rig.moved_share`).

    Returns
    -------
    fixed : (m,) bool

    Raises
    ------
    ValueError
        For a name that is not a bone number or ``"all"``.
    """
    m = rig.bone_count
    fixed = rig.anchored_bones | rig.weightless_bones
    if minor_share > 0:
        fixed |= rig.moved_share < minor_share
    for names, value in ((fix, True), (free, False)):
        for name in names or []:
            if str(name).lower() == "all":
                fixed[:] = value
                continue
            fixed[bone_index(name, m, rig.labels)] = value
    return fixed


def bone_index(name, m: int, labels: list | None = None) -> int:
    """0-based index of a bone given as its 1-based number or (a glTF rig) its name; InputError otherwise."""
    if labels is not None and str(name) in labels:
        return labels.index(str(name))
    if labels is not None and not str(name).strip().isdigit():
        close = [x for x in labels if str(name).lower() in x.lower()][:5]
        raise InputError(None, f"bone {name!r} is not a bone name or number 1..{m}"
                         + (f"; did you mean {', '.join(close)}?" if close else ""))
    try:
        b = int(name) - 1
    except ValueError:
        raise InputError(None, f"bone {name!r} is not a bone number 1..{m} or 'all'") from None
    if not 0 <= b < m:
        raise InputError(None, f"bone {name} is out of range 1..{m}")
    return b


def angle_layout(rig: Rig, fixed: np.ndarray) -> np.ndarray:
    """Which Euler angles the search varies.

    Returns
    -------
    free : (m, 3) bool
        In 2D only the angle about the plane normal (index 2) of free bones.
    """
    free = np.zeros((rig.bone_count, 3), bool)
    if rig.dim == 2:
        free[~fixed, 2] = True
    else:
        free[~fixed] = True
    return free


def _within(value: float, bounds: tuple) -> bool:
    """``low <= value <= high`` for ``bounds = (low, high)``, ``None`` an open end."""
    low, high = bounds
    return (low is None or value >= low) and (high is None or value <= high)
