"""A search's answer as a typed record: :class:`PoseResult`, and what each stage adds to it.

* :class:`PoseResult`: what :func:`supportless.search.answer.optimize` returns;
* the stages' records (each a field of the result, None until its stage ran):
  :class:`SearchStats` (where one search's time went), :class:`FullSurface` (a proxy search's answer
  measured on the full surface), :class:`WrittenCheck` (the last gate's count of the mesh as written);
* :func:`measured_at`: a result moved to another pose and print rotation;
* :func:`at_full_resolution`: a result measured on a sculpt's reduced surface
  (:meth:`Rig.measure_rig`), posed on the full one;
* :func:`written_verdict`: whether the mesh as written may be written (the stages that check it are in
  :mod:`supportless.search.answer`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..base.geometry import place_on_plate, print_pose
from ..copyleft.cgal import intersecting_faces
from ..rig.contact import ContactRules, ContactVerdict, contact_verdict
from ..rig.rig import Rig
from .objective import Objective
from .settings import SearchSettings

__all__ = ["CallTime", "FullSurface", "PoseResult", "SearchStats", "WrittenCheck", "at_full_resolution", "faces_of",
           "measured_at", "written_verdict"]


@dataclass
class CallTime:
    """The calls of one measured step of a search and their wall time.

    Attributes
    ----------
    calls : int
        How many times the step ran.
    seconds : float
        Their wall time together, s.
    """

    calls: int = 0
    seconds: float = 0.0


@dataclass
class SearchStats:
    """Where one search's time went (:class:`supportless.search.optimizer._PoseSearch`), counted while it runs.

    Attributes
    ----------
    overlap_rejections : int
        Candidates for the swarm's best rejected without asking CGAL: the ray grid saw two layers
        (:data:`supportless.search.optimizer.OVERLAP_CERTAIN`).
    exact : CallTime or None
        CGAL checks of candidates for the swarm's best; None when the search had no gate.
    footprint : CallTime or None
        Checks of a turned candidate's contact with the plate; None when the search had no gate.
    footprint_rejections : int
        Candidates refused for resting on less plate than the footprint rule's bound.
    progress : CallTime or None
        Measures of the best pose's terms, once each time it changed; None when no phase ran.
    polish_evaluations : int
        Objective evaluations of the polish (CMA-ES with small steps), 0 without one.
    """

    overlap_rejections: int = 0
    exact: CallTime | None = None
    footprint: CallTime | None = None
    footprint_rejections: int = 0
    progress: CallTime | None = None
    polish_evaluations: int = 0

    def timing(self, name: str) -> CallTime:
        """The :class:`CallTime` named ``name`` (``"exact"``, ``"footprint"`` or ``"progress"``), made on first use."""
        if getattr(self, name) is None:
            setattr(self, name, CallTime())
        return getattr(self, name)

    def to_dict(self) -> dict:
        """The counts under the flat names benchmarks print (``exact_calls``, ``exact_seconds``, ...)."""
        out = {"overlap_rejections": self.overlap_rejections}
        for name in ("exact", "footprint", "progress"):
            timing = getattr(self, name)
            if timing is not None:
                out |= {f"{name}_calls": timing.calls, f"{name}_seconds": timing.seconds}
        if self.footprint_rejections:
            out["footprint_rejections"] = self.footprint_rejections
        return out | {"polish_evaluations": self.polish_evaluations}


@dataclass(frozen=True)
class FullSurface:
    """A proxy search's answer on the full surface (:func:`supportless.search.answer.on_full_surface`, then
    :func:`supportless.search.answer.polished`).

    Attributes
    ----------
    proxy_faces : int
        Triangles of the simplified proxy searched.
    proxy_value : float
        The proxy search's best objective value, measured on the proxy.
    full_rescored : int
        The proxy's best and other good poses (each copy once) measured on the full surface.
    full_exact_calls : int
        Exact self-intersection checks (CGAL) on the full surface: the measuring's, then the polish's gate's.
    full_polish_value : float or None
        The polish's best objective value on the full surface; None without a polish.
    full_polish_evaluations : int or None
        The polish's objective evaluations; None without a polish.
    """

    proxy_faces: int
    proxy_value: float
    full_rescored: int
    full_exact_calls: int
    full_polish_value: float | None = None
    full_polish_evaluations: int | None = None

    def to_dict(self) -> dict:
        """The fields under their names, the polish's only when it ran."""
        return {key: value for key, value in dataclasses.asdict(self).items() if value is not None}


@dataclass(frozen=True)
class WrittenCheck:
    """The last gate's count of the mesh as written (:func:`supportless.search.answer.as_written`).

    Attributes
    ----------
    written_pairs : int
        Intersecting triangle pairs (CGAL) of the mesh written (full resolution, print frame).
    rest_pairs : int
        Intersecting triangle pairs of the rest pose.
    contacts : list of dict
        The contacts between jointed parts the written mesh keeps (:attr:`ContactVerdict.regions`:
        ``bones``, ``pairs``, ``depth``); empty when it crosses itself nowhere beyond the rest pose.
    fell_back_to_rest : int or None
        When the rest pose is written instead of the answer: the pairs the answer had; else None.
    refused_as_written : str or None
        Why the answer was refused, in words, when the rest pose is written instead.
    passed_over_as_written : int or None
        When another answer weighed is written instead: the 1-based number of the answer passed over.
    """

    written_pairs: int
    rest_pairs: int
    contacts: list = field(default_factory=list)
    fell_back_to_rest: int | None = None
    refused_as_written: str | None = None
    passed_over_as_written: int | None = None

    def to_dict(self) -> dict:
        """The fields under their names, those of a refusal only when set."""
        return {key: value for key, value in dataclasses.asdict(self).items()
                if value is not None or key == "refused_as_written" and self.fell_back_to_rest is not None}


@dataclass
class PoseResult:
    """Outcome of :func:`optimize`.

    Attributes
    ----------
    angles : (m, 3) float64
        Best pose, radians.
    vertices : (n, d) float64
        Posed full-resolution surface standing as the input stood (the
        display frame), placed on the build plate (lowest point at 0 along up).
    value : float
        Objective of the best pose.
    history : (iterations + 1,) float64
        Best objective per iteration.
    terms : dict of str -> float
        Normalised terms of the best pose.
    settings : SearchSettings
        What the search was asked to do.
    objective : Objective
        What it minimised (for measuring poses afterwards).
    interrupted : bool
        True when the search stopped early (Ctrl-C or the callback).
    fixed : (m,) bool
        The bones that kept their rotation.
    term_history : dict of str -> list of float
        Normalised terms of the best pose after each iteration.
    runtime_seconds : float
        Wall time of the search.
    stats : SearchStats
        Where the search's time went (of the search that found the pose: the proxy's, after one).
    rotation : (d, d) float64
        The print rotation R (the identity with ``orient="keep"``).
    print_vertices : (n, d) float64
        The posed surface in the print frame: ``vertices`` turned by R
        (:func:`supportless.base.geometry.print_pose`), on the plate. This is
        the mesh to slice.
    candidates : dict
        Other good poses the last phase of the search reached, best first:
        ``angles`` (q, m, 3) float64, ``rotations`` (q, d, d) float64 and
        ``values`` (q,) float64 (objective values as the search measured them, :meth:`Objective.bounded`;
        not checked for exact self-intersection). See :func:`distinct_candidates`.
    alternatives : dict of str -> dict
        With ``orient="free"``, the simpler answers the search met on its
        way, each in the form of ``candidates``: ``"pose"``, the pose phase's
        best and other good poses, printed as they stand, and ``"turn"``,
        the start pose upright and turned to each candidate printing direction
        (:func:`supportless.search.orientation.seed_params`). Empty otherwise.
    choice : supportless.search.choice.Choice or None
        How the result was chosen among the search's best and the simpler
        answers (:func:`supportless.search.choice.choose`), or None when it was not.
    symmetry : dict or None
        When the tool posed a figure with a mirror plane as mirror images
        (``settings.symmetric`` None, :func:`supportless.search.answer.mirrored_answer`):
        ``mode`` (``"auto"``), ``kept`` (``"mirrored"``) and ``mirrored_mm``
        (the answer's predicted support filament at the reference height).
        None otherwise.
    full_surface : FullSurface or None
        How a proxy search's answer was measured and polished on the full surface; None without a proxy.
    measured_faces : int or None
        The triangles the answer was measured on, when that is not the rig's surface (a sculpt's reduced
        surface, :func:`at_full_resolution`); else None.
    written : WrittenCheck or None
        The last gate's count of the mesh as written; None before it, or with exact checks off or in 2D.
    rest_instead : str or None
        Why the rest pose is written in place of the answer, when a command's guard found the answer needs more
        support than the rest pose (:func:`supportless.apps.rest_guard.rest_instead`); else None.

    The JSON report of a result is built by its caller
    (:func:`supportless.report.report.build_report`): it measures the rest pose and
    the found pose, which the search itself does not need.
    """

    angles: np.ndarray
    vertices: np.ndarray
    value: float
    history: np.ndarray
    terms: dict
    settings: SearchSettings
    objective: Objective
    interrupted: bool = False
    fixed: np.ndarray | None = None
    term_history: dict = field(default_factory=dict)
    runtime_seconds: float = 0.0
    stats: SearchStats = field(default_factory=SearchStats)
    rotation: np.ndarray | None = None
    print_vertices: np.ndarray | None = None
    candidates: dict = field(default_factory=dict)
    alternatives: dict = field(default_factory=dict)
    choice: object = None
    symmetry: dict | None = None
    full_surface: FullSurface | None = None
    measured_faces: int | None = None
    written: WrittenCheck | None = None
    rest_instead: str | None = None

    def __post_init__(self):
        if self.rotation is None:
            self.rotation = np.eye(self.vertices.shape[1])
        if self.print_vertices is None:
            self.print_vertices = self.vertices

    def flat_stats(self) -> dict:
        """The stages' counts in one dict under flat names (``exact_calls``, ``proxy_faces``, ``written_pairs``,
        ``chosen_kind``, ...), for benchmarks' tables; absent stages add nothing."""
        out = self.stats.to_dict()
        for record in (self.full_surface, self.written):
            out |= record.to_dict() if record is not None else {}
        if self.measured_faces is not None:
            out["measured_faces"] = self.measured_faces
        if self.choice is not None:
            out |= {"chosen_kind": self.choice.chosen_kind, "choice_seconds": self.choice.seconds}
        return out | ({"rest_instead": self.rest_instead} if self.rest_instead is not None else {})


def measured_at(rig: Rig, result: PoseResult, angles: np.ndarray, rotation: np.ndarray,
                objective: Objective | None = None) -> PoseResult:
    """``result`` with another pose and print rotation, measured with an objective.

    Parameters
    ----------
    rig : Rig
        The rig the pose is for (full resolution).
    result : PoseResult
        The result to take the rest from (history, settings, stats, candidates).
    angles : (m, 3) float64
        Relative Euler angles, radians.
    rotation : (d, d) float64
        Print rotation.
    objective : Objective, optional
        What measures the pose (default: ``result.objective``).

    Returns
    -------
    result : PoseResult
        With ``angles``, ``rotation``, ``vertices``, ``print_vertices``,
        ``value``, ``terms`` and ``objective`` of the new measurement.
    """
    objective = result.objective if objective is None else objective
    angles = np.asarray(angles, np.float64)
    rotation = np.asarray(rotation, np.float64)
    turned = not np.allclose(rotation, np.eye(rig.dim))
    posed = place_on_plate(rig.pose(angles), rig.up)
    value, terms, _ = objective.evaluate(angles, rotation if turned else None)
    return dataclasses.replace(result, angles=angles, rotation=rotation, vertices=posed, value=float(value),
                               terms={k: float(v) for k, v in terms.items()}, objective=objective,
                               print_vertices=print_pose(posed, rotation, rig.up) if turned else posed)


def at_full_resolution(rig: Rig, result: PoseResult) -> PoseResult:
    """``result`` posed on ``rig``'s surface, when it was measured on another (:meth:`Rig.measure_rig`).

    The pose, the print rotation, the value and the terms stay those measured; the surfaces
    (``vertices``, ``print_vertices``) become ``rig``'s, and ``measured_faces`` says how many triangles it
    was measured on. A result of ``rig``'s own surface is returned as it is.

    Parameters
    ----------
    rig : Rig
        Full resolution.
    result : PoseResult

    Returns
    -------
    result : PoseResult
    """
    if result.vertices.shape == rig.vertices.shape:
        return result
    posed = place_on_plate(rig.pose(result.angles), rig.up)
    turned = not np.allclose(result.rotation, np.eye(rig.dim))
    measured = len(result.objective.rig.faces) if result.objective is not None else None
    return dataclasses.replace(result, vertices=posed, measured_faces=measured,
                               print_vertices=print_pose(posed, result.rotation, rig.up) if turned else posed)


def written_verdict(rig: Rig, result: PoseResult, rest_pairs: int) -> ContactVerdict:
    """Whether ``result``'s mesh as written (``print_vertices`` with ``rig``'s faces) may be written.

    Allowed when it has no more intersecting triangle pairs (CGAL) than the rest pose's ``rest_pairs``, or when
    every crossing is contact between jointed parts within the search's rules (``settings.contact``,
    :meth:`Rig.crossings`, the ray grid's overlap in the print frame). Its ``regions`` name the contacts.
    """
    from ..energies.intersection import self_intersection_volume

    P = result.print_vertices
    pairs = intersecting_faces(P, rig.faces)
    if len(pairs) <= rest_pairs:
        return ContactVerdict(True, len(pairs))
    rules = ContactRules() if getattr(result.settings, "contact", False) else None
    if rules is None:
        return ContactVerdict(False, len(pairs), f"{len(pairs)} pairs of triangles cross")
    X = rig.pose(result.angles)  # the same surface before its rigid placement in the print frame
    R = np.asarray(result.rotation, np.float64)
    offset = P[0] - X[0] @ R.T
    joints = rig.posed_joints(result.angles) @ R.T + offset
    overlap = float(self_intersection_volume(P, rig.faces, rig.up))
    return contact_verdict(rig.body_parts, P, joints, pairs, rules, overlap, rig.rest_volume)


def faces_of(rig: Rig, result: PoseResult) -> np.ndarray:
    """(f, 3) int64: the triangles of ``result``'s surfaces: ``rig``'s, or those of the surface it was
    measured on when that is not ``rig``'s (an answer a sculpt's choice weighed, :meth:`Rig.measure_rig`)."""
    if result.print_vertices.shape == rig.vertices.shape or result.objective is None:
        return rig.faces
    return result.objective.rig.faces
