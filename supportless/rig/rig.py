"""The rig: rest surface, skeleton, volume mesh and skinning weights.

:func:`prepare_rig` builds a :class:`Rig` from arrays: it meshes the inside of the surface with the bones
sampled into it (TetGen, see :mod:`supportless.rig.tetmesh`) and computes bounded biharmonic weights
(``igl.boundary_conditions`` + ``igl.bbw``). :func:`load_rig` does the same from files and keeps the result
in an on-disk cache keyed by a hash of the inputs and settings, so loading the same model again takes a
fraction of a second. A planar figure (all z = 0, as the paper's 2D mode) becomes a 2D rig: arrays have
``d = 2`` columns and the "volume" mesh is the triangle mesh itself, refined so vertices lie on the bones.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..base import kinematics as kin
from ..base.errors import InputError
from ..base.geometry import parse_up, points_in_triangles, signed_volume
from ..base.progress import step
from ..copyleft.cgal import self_intersects
from ..files.joints import JOINT_INSIDE_MARGIN, JOINT_OUTSIDE_TOLERANCE, pull_joints_inside  # noqa: F401 (re-exported)
from ..files.meshes import check_closed_surface, check_not_flat
from ..files.repair import repair_degenerate_faces, repair_note
from ..files.skeleton import check_skeleton
from .balance import centre_of_mass_operator
from .cache import default_cache_dir, rig_cache_key
from .contact import BodyParts, ContactRules, ContactVerdict, contact_verdict
from .weights import BBW_ITERATIONS, check_weights, compute_weights

__all__ = ["Rig", "compute_weights", "default_cache_dir", "prepare_rig", "rig_cache_key"]

#: A surface with more triangles than this is simplified (quadric edge
#: collapse, no new self-intersections) to :data:`PROXY_TARGET` triangles for
#: the volume mesh, the weights and the search; outputs stay full resolution.
PROXY_FACES = 20000
PROXY_TARGET = 10000

#: How far along its bone a joint may move into a dense surface's simplified proxy (share of the bone's length,
#: :func:`~supportless.files.joints.pull_joints_inside`'s ``reach``): simplification thins fingertips, and the
#: 29k-triangle Mannequin's proxy lost the first 65 % of a fingertip bone, so its proxy was refused and it was
#: prepared and searched on the full surface (34 s and 41-45 s; with the proxy 9.4-9.8 s and 20-21 s). The
#: proxy's joints only place its weights; the rig keeps its own.
PROXY_JOINT_REACH = 0.9

#: Surface vertices within this fraction of the model's height of its lowest
#: point rest on the build plate (:attr:`Rig.contact_vertices`).
CONTACT_TOLERANCE = 0.01

#: Default settings of the weight computation (and :data:`~supportless.rig.weights.BBW_ITERATIONS`).
SAMPLES_PER_BONE = 10


@dataclass(eq=False)
class Rig:
    """A prepared model: everything needed to pose it and measure its energies.

    Attributes
    ----------
    vertices : (n, d) float64
        Full-resolution rest surface (d = 3), or the planar mesh (d = 2).
    faces : (f, 3) int64
        Surface triangles, outward oriented (counter-clockwise in 2D).
    joints : (j, d) float64
    bones : (m, 2) int64
        0-based ``[root, tip]`` joint indices, in TGF order.
    tet_vertices : (t, d) float64
        Volume mesh vertices; the first ``n`` rows are ``vertices``.
    tets : (k, d+1) int64
        Tetrahedra (triangles in 2D).
    tet_weights : (t, m) float64
        Bounded biharmonic weights on the volume mesh, rows sum to 1.
    up : (d,) float64
        Unit printing direction.
    name : str
        For reports and pictures.
    info : dict
        How the rig was made (timings, warnings, the source asset).
    labels : list of str, optional
        Bone names (a glTF rig's joint names); ``--fix``/``--free``/``--limit``
        accept them besides the 1-based numbers.
    coarse_faces : (c, 3) int64, optional
        For a dense surface, the triangles of the simplified surface the volume
        mesh was made from, indexing ``tet_vertices`` (its vertices follow the
        ``n`` surface vertices); the search runs on it (:meth:`coarse_rig`).
    """

    vertices: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    bones: np.ndarray
    tet_vertices: np.ndarray
    tets: np.ndarray
    tet_weights: np.ndarray
    up: np.ndarray
    name: str = "model"
    info: dict = field(default_factory=dict)
    labels: list | None = None
    coarse_faces: np.ndarray | None = None

    # ----------------------------------------------------------------- basics
    @property
    def dim(self) -> int:
        """2 for a planar figure, 3 otherwise."""
        return self.vertices.shape[1]

    @property
    def weights(self) -> np.ndarray:
        """(n, m) float64: skinning weights of the surface vertices."""
        return self.tet_weights[: len(self.vertices)]

    # ------------------------------------------------- contact and kinematic tree
    @cached_property
    def mass_moments(self) -> np.ndarray:
        """(m, d+1) float64: per-bone moments of the solid's volume (see
        :func:`~supportless.rig.balance.centre_of_mass_operator`); the last
        column is the share of the volume each bone's weights carry."""
        return centre_of_mass_operator(self.tet_vertices, self.tets, self.tet_weights)

    @cached_property
    def contact_vertices(self) -> np.ndarray:
        """(n,) bool: surface vertices resting on the build plate in the rest pose.

        Those within :data:`CONTACT_TOLERANCE` of the model's height of its
        lowest point along ``up``.
        """
        h = self.vertices @ self.up
        return h <= h.min() + CONTACT_TOLERANCE * (h.max() - h.min())

    @cached_property
    def contact_bones(self) -> np.ndarray:
        """(m,) bool: the bones that dominate (largest weight on) a contact vertex."""
        mask = np.zeros(self.bone_count, bool)
        mask[np.unique(np.argmax(self.weights[self.contact_vertices], axis=1))] = True
        return mask

    @cached_property
    def anchored_bones(self) -> np.ndarray:
        """(m,) bool: the contact bones and the bones joining them (:func:`~supportless.base.kinematics.connecting_bones`).

        The search keeps these where they are by default; the rest of the body
        moves relative to them.
        """
        return kin.connecting_bones(self.bones, self.contact_bones)

    @cached_property
    def anchor_order(self) -> np.ndarray:
        """(k,) int64: the anchored bones, nearest the skeleton's root (in the TGF's tree) first."""
        anchored = np.flatnonzero(self.anchored_bones)
        return anchored[np.argsort(kin.bone_depths(kin.bone_parents(self.bones))[anchored], kind="stable")]

    @property
    def root_bone(self) -> int:
        """The bone the kinematic tree hangs from: the anchored bone nearest the skeleton's root."""
        return int(self.anchor_order[0])

    @cached_property
    def tree(self) -> tuple[np.ndarray, np.ndarray]:
        """``(parents, pivots)``: :func:`~supportless.base.kinematics.kinematic_tree` from the anchored bones.

        The anchored bones never move; bones sharing a joint keep it together. Pose angles are relative to it.
        """
        return kin.kinematic_tree(self.bones, self.anchor_order)

    @property
    def parents(self) -> np.ndarray:
        """(m,) int64: parent bone of each bone in :attr:`tree`, -1 for roots."""
        return self.tree[0]

    @property
    def pivots(self) -> np.ndarray:
        """(m,) int64: the joint each bone turns about (shared with its parent)."""
        return self.tree[1]

    @cached_property
    def order(self) -> np.ndarray:
        """(m,) int64: bones with parents before children."""
        return kin.topological_order(self.parents)

    @cached_property
    def lbs(self):
        """(n, m*(d+1)) float64: skinning matrix of the surface, ``V' = M T``.

        A scipy.sparse CSR matrix when a vertex follows a few bones (a glTF
        skin), else an array (:func:`~supportless.base.kinematics.lbs_operator`).
        """
        return kin.lbs_operator(self.vertices, self.weights)

    @property
    def bone_count(self) -> int:
        return len(self.bones)

    def bone_names(self) -> list[str]:
        """Names for the bones: the rig's labels, else ``"bone 3 (4-5)"``, 1-based as in the TGF file."""
        if self.labels is not None:
            return list(self.labels)
        return [f"bone {i + 1} ({a + 1}-{b + 1})" for i, (a, b) in enumerate(self.bones)]

    @cached_property
    def moved_share(self) -> np.ndarray:
        """(m,) float64: the share of the volume that turning each bone moves (its weights and its descendants').

        Sums to more than 1 over the bones: a bone's share includes its
        children's. A finger moves a sliver of the body, an upper arm the arm
        and the hand.
        """
        share = self.mass_moments[:, -1] / max(float(self.mass_moments[:, -1].sum()), 1e-300)
        return np.array([share[kin.descendants(self.parents, b)].sum() for b in range(self.bone_count)])

    @cached_property
    def weightless_bones(self) -> np.ndarray:
        """(m,) bool: bones no vertex is weighted to (a glTF hip's second child).

        Turning one only turns the bones below it, which their own bones do
        already; the search keeps them fixed by default.
        """
        return self.tet_weights.max(axis=0) <= 1e-9

    # ----------------------------------------------------------------- posing
    def transforms(self, angles: np.ndarray) -> np.ndarray:
        """Bone transforms for a batch of poses.

        Parameters
        ----------
        angles : (P, m, 3) or (m, 3) float64
            Relative XYZ Euler angles per bone, radians.

        Returns
        -------
        transforms : (P, m, d, d+1) or (m, d, d+1) float64
        """
        return kin.forward_kinematics(self.joints, self.bones, angles, self.parents, self.order, self.pivots)

    def pose(self, angles: np.ndarray) -> np.ndarray:
        """Posed surface vertices for a batch of poses.

        Parameters
        ----------
        angles : (P, m, 3) or (m, 3) float64
            Relative XYZ Euler angles per bone, radians.

        Returns
        -------
        vertices : (P, n, d) or (n, d) float64
        """
        return kin.skin(self.lbs, self.transforms(angles))

    def self_intersects(self, angles: np.ndarray) -> bool:
        """Whether the surface posed by ``angles (m, 3) float64`` cuts itself (exactly, CGAL); False in 2D.

        A planar figure's outline is not checked: the search's 2D energies
        measure its overlaps, and CGAL's check is of triangle meshes in space.
        """
        return self.dim == 3 and self_intersects(self.pose(angles), self.faces)

    @cached_property
    def body_parts(self) -> BodyParts:
        """The surface split into bone regions, for :meth:`crossings` (:class:`~supportless.rig.contact.BodyParts`)."""
        return BodyParts(self.vertices, self.faces, self.weights, self.joints, self.bones, self.bone_names())

    @cached_property
    def rest_volume(self) -> float:
        """The rest surface's enclosed volume (area in 2D), model units."""
        return abs(float(signed_volume(self.vertices, self.faces)))

    def crossings(self, vertices: np.ndarray, posed_joints: np.ndarray, rules: ContactRules | None = None,
                  overlap_volume: float | None = None, pairs: np.ndarray | None = None) -> ContactVerdict:
        """Whether a posed surface's crossings are all contact between jointed parts (:mod:`~supportless.rig.contact`).

        Parameters
        ----------
        vertices : (n, 3) float64
            This rig's surface, posed (in any rigid placement).
        posed_joints : (j, 3) float64
            Its joints, placed alike.
        rules : ContactRules, optional
            None: no contact allowed (any crossing refuses the pose).
        overlap_volume : float, optional
            The volume it covers twice (the ray grid's), bounded by ``rules.volume`` of :attr:`rest_volume`.
        pairs : (k, 2) int64, optional
            Its intersecting triangle pairs when the caller has them (CGAL's, found here otherwise).

        Returns
        -------
        verdict : ContactVerdict
            Allowed (and every pair 2D) for a planar figure.
        """
        if self.dim != 3:
            return ContactVerdict(True, 0)
        rules = rules if rules is not None else ContactRules(hops=-1)
        from ..copyleft.cgal import intersecting_faces

        pairs = intersecting_faces(vertices, self.faces) if pairs is None else pairs
        return contact_verdict(self.body_parts, vertices, posed_joints, pairs, rules, overlap_volume,
                               self.rest_volume)

    def posed_joints(self, angles: np.ndarray) -> np.ndarray:
        """Joint positions of a batch of poses, (P, j, d) or (j, d) float64."""
        return kin.posed_joints(self.joints, self.bones, self.transforms(angles))

    def coarse_rig(self) -> Rig | None:
        """The rig of the simplified surface (a dense model's proxy for the search), or None.

        Same bones, joints, volume mesh and weights; its surface is the
        simplified one the volume mesh was made from (:attr:`coarse_faces`).
        """
        if self.coarse_faces is None:
            return None
        n = len(self.vertices)
        Fc = self.coarse_faces - n
        nc = int(Fc.max()) + 1
        return Rig(self.tet_vertices[n:n + nc], Fc, self.joints, self.bones, self.tet_vertices[n:], self.tets - n,
                   self.tet_weights[n:], self.up, name=self.name, info={"warnings": []}, labels=self.labels)

    def measure_rig(self) -> Rig | None:
        """A sculpt's rig on its surface quickly reduced, where the search measures it; None for other models.

        Past :data:`~supportless.files.simplify.FAST_FIRST_FACES` triangles (a sculpt searched through its
        proxy), what the search measures "on the full surface" (the best poses re-scored, the polish, the
        answers weighed and their exact checks) is measured on the surface reduced to
        :data:`~supportless.files.simplify.FAST_FIRST_TARGET` triangles
        (:func:`~supportless.files.simplify.quickly_reduced`: closed, uncrossed), weighted as the full
        surface is (from the model's skin, or from the proxy's bounded biharmonic weights); the same joints,
        volume mesh and proxy. What is written is the full surface
        posed, checked exactly there (:func:`supportless.search.answer.as_written`). Made once per rig.
        """
        from ..files.simplify import FAST_FIRST_FACES

        if self.coarse_faces is None or self.dim != 3 or len(self.faces) <= FAST_FIRST_FACES:
            return None
        if "_measure_rig" not in self.__dict__:
            self.__dict__["_measure_rig"] = self._reduced_rig()
        return self.__dict__["_measure_rig"]

    def _reduced_rig(self) -> Rig | None:
        """:meth:`measure_rig`, made (None when the quick reduction is not clean)."""
        from ..files.printbody import transfer_values
        from ..files.simplify import FAST_FIRST_TARGET, quickly_reduced

        with step(f"the surface reduced to {FAST_FIRST_TARGET} triangles for measuring"):
            reduced = quickly_reduced(self.vertices, self.faces, FAST_FIRST_TARGET)
            if reduced is None:
                return None
            U, G = reduced
            # the weights of the full surface where they come from: a skin's from the skin, bounded
            # biharmonic weights from the proxy's surface, as the full surface's came (seconds, not tens)
            source = self if self.info.get("weights") == "skin" else self.coarse_rig()
            W = transfer_values(U, source.vertices, source.faces, source.weights)
            W /= np.maximum(W.sum(1, keepdims=True), 1e-300)
        n, k = len(self.vertices), len(U)
        return Rig(U, G, self.joints, self.bones, np.vstack([U, self.tet_vertices[n:]]), self.tets - n + k,
                   np.vstack([W, self.tet_weights[n:]]), self.up, name=self.name, info={"warnings": []},
                   labels=self.labels, coarse_faces=self.coarse_faces - n + k)

    def rest_angles(self) -> np.ndarray:
        """(m, 3) float64 zeros: the rest pose."""
        return np.zeros((self.bone_count, 3))

    def __repr__(self) -> str:
        return (f"Rig({self.name!r}: {len(self.vertices)} vertices, {len(self.faces)} faces, "
                f"{len(self.tets)} {'tets' if self.dim == 3 else 'triangles'}, {self.bone_count} bones, "
                f"{self.dim}D)")


# --------------------------------------------------------------------------- #
# validation
# --------------------------------------------------------------------------- #
def _check_inputs(V, F, joints, bones, up, mesh_path=None, skel_path=None, joints_inside=True, pivots_only=False):
    """Validate and normalise arrays; returns (V, F, joints, dim, warnings)."""
    if len(bones) == 0:
        raise InputError(skel_path, "skeleton has no bones")
    if len(F) == 0 or len(V) == 0:
        raise InputError(mesh_path, "the mesh has no triangles")
    if bones.min() < 0 or bones.max() >= len(joints):
        raise InputError(skel_path, f"a bone refers to a joint out of range 0..{len(joints) - 1}")
    check_skeleton(joints, bones, skel_path)
    if F.min() < 0 or F.max() >= len(V):
        raise InputError(mesh_path, "a face refers to a vertex out of range")
    if joints.shape[1] != V.shape[1] and not (V.shape[1] == 2 and joints.shape[1] == 3):
        raise InputError(skel_path, f"skeleton is {joints.shape[1]}D but the mesh is {V.shape[1]}D")
    planar = V.shape[1] == 2 or (np.all(V[:, 2] == 0) and np.all(joints[:, 2] == 0))
    check_not_flat(V[:, :2] if planar else V, F, mesh_path)
    if planar:
        V2, J2 = V[:, :2], joints[:, :2]
        if signed_volume(V2, F) < 0:
            F = F[:, ::-1].copy()
        inside = points_in_triangles(V2, F, J2)
        if not inside.all():
            i = int(np.flatnonzero(~inside)[0])
            raise InputError(skel_path, f"joint {i + 1} at {J2[i].tolist()} lies outside the planar mesh "
                             f"{mesh_path or ''}".rstrip() + "; move it inside")
        return np.ascontiguousarray(V2), F, np.ascontiguousarray(J2), 2, []
    repaired = []
    if joints_inside:  # (a skinned model's vertices carry its weights: they stay as they are)
        V, F, count = repair_degenerate_faces(V, F)
        repaired = [repair_note(count)] if count else []
    check_closed_surface(F, mesh_path)
    if signed_volume(V, F) < 0:
        F = F[:, ::-1].copy()
    if not joints_inside:  # the weights come with the model: joints are only pivots
        return V, F, joints, 3, []
    if pivots_only:  # a glTF rig's joints, weights recomputed: every one goes inside, from however far
        joints, warnings = pull_joints_inside(V, F, joints, bones, up, skel_path, np.inf, JOINT_INSIDE_MARGIN)
    else:
        joints, warnings = pull_joints_inside(V, F, joints, bones, up, skel_path)
    return V, F, joints, 3, repaired + warnings


# --------------------------------------------------------------------------- #
# preparation
# --------------------------------------------------------------------------- #
def prepare_rig(vertices, faces, joints, bones, up="y", *, name="model", samples_per_bone=SAMPLES_PER_BONE,
                bbw_iterations=BBW_ITERATIONS, tet_mesh=None, tet_weights=None, mesh_path=None,
                skeleton_path=None, progress=None, surface_weights=None, labels=None, pivots_only=False) -> Rig:
    """Build a rig from arrays: volume mesh and bounded biharmonic weights.

    Parameters
    ----------
    vertices : (n, 3) or (n, 2) float64
        Closed surface, or a planar triangle mesh (z = 0 or two columns).
    faces : (f, 3) int64
    joints : (j, 3) or (j, 2) float64
    bones : (m, 2) int64
        0-based.
    up : str or (d,) float
        Printing direction, see :func:`supportless.base.geometry.parse_up`.
    name : str
    samples_per_bone : int
        Volume-mesh vertices inserted along each bone.
    bbw_iterations : int
        Active-set iterations of the weight solve.
    tet_mesh : ((t, 3) float64, (k, 4) int64), optional
        A precomputed volume mesh whose vertices include the surface's.
    tet_weights : (t, m) float64, optional
        Precomputed weights of ``tet_mesh``'s vertices (requires ``tet_mesh``).
    mesh_path, skeleton_path : str, optional
        Named in error messages.
    progress : callable(str), optional
        Told about each stage.
    surface_weights : (n, m) float64, optional
        Skinning weights that come with the model (a glTF skin), rows summing
        to 1. The volume mesh is then the surface's inside alone, the bones
        need not lie inside it, and every volume vertex takes the weights of
        its closest surface point (:func:`~supportless.files.printbody.transfer_values`).
    labels : list of str, optional
        Bone names (:attr:`Rig.labels`).
    pivots_only : bool
        The joints are pivots from a rigged asset (not drawn inside the body):
        for bounded biharmonic weights every joint is moved inside, from
        however far out.

    Returns
    -------
    rig : Rig
    """
    from .tetmesh import bone_samples, refine_triangulation_with_points, tetrahedralize_surface
    from .tetmesh import tetrahedralize_with_skeleton_or_remake as tetrahedralize_bones

    say = progress or (lambda msg: None)
    V, F, J, B = (np.asarray(a, t) for a, t in ((vertices, np.float64), (faces, np.int64), (joints, np.float64),
                                                  (bones, np.int64)))
    skinned = surface_weights is not None
    coarse = simplified = None
    V, J, tet_mesh, moved = _near_origin(V, J, tet_mesh, skinned)
    with step("checking the surface and the joints"):
        V, F, J, dim, warnings = _check_inputs(V, F, J, B, up, mesh_path, skeleton_path, joints_inside=not skinned,
                                               pivots_only=pivots_only)
    up_vec = parse_up(up, dim)
    t0 = time.perf_counter()
    if skinned:
        if dim != 3 or tet_mesh is not None or tet_weights is not None:
            raise InputError(mesh_path, "skin weights from the model go with a 3D surface and no --tets/--weights")
        Ws = np.asarray(surface_weights, np.float64)
        if Ws.shape != (len(V), len(B)):
            raise InputError(mesh_path, f"skin weights are {Ws.shape[0]}x{Ws.shape[1]} for {len(V)} vertices "
                             f"and {len(B)} bones")
        if len(F) > PROXY_FACES:
            say(f"simplifying the surface to {PROXY_TARGET} triangles for the volume mesh")
        simplified = _simplified(V, F, say) if len(F) > PROXY_FACES else None
        say("tetrahedralising")
        TV, TT, conforming = tetrahedralize_surface(*(simplified or (V, F)))
        if simplified is not None:  # the volume of the simplified surface, its rows after the full surface's
            Vc, Fc = simplified
            TV, TT = np.vstack([V, TV]), TT + len(V)
            warnings = list(warnings) + [f"{len(F)} triangles: the volume mesh and the search use the surface "
                                         f"simplified to {len(Fc)}; outputs and reports are full resolution"]
        if not conforming:
            warnings = list(warnings) + ["TetGen could not keep the surface as it is; the volume mesh splits it "
                                         "(distortion is measured on that mesh)"]
    elif tet_mesh is None and dim == 3 and len(F) > PROXY_FACES and (coarse := _coarse_volume(
            V, F, J, B, up, samples_per_bone, bbw_iterations, skeleton_path, say)) is not None:
        Vc, Fc, TVc, TTc, Wc = coarse
    elif tet_mesh is not None:
        TV, TT = (np.asarray(a) for a in tet_mesh)
        TV, TT, tet_order = _attach_surface(V, TV.astype(np.float64), TT.astype(np.int64), mesh_path)
    elif dim == 3:
        say("tetrahedralising")
        V, F, TV, TT, note = tetrahedralize_bones(V, F, J, B, samples_per_bone)
        warnings = list(warnings) + [note] * (note is not None)
    else:
        say("refining the planar mesh along the bones")
        TV, TT = refine_triangulation_with_points(V, F, bone_samples(J, B, samples_per_bone))
    t1 = time.perf_counter()
    if coarse is not None:
        from ..files.printbody import transfer_values

        with step("weights onto the full surface"):
            Ws = transfer_values(V, Vc, Fc, Wc[: len(Vc)])
            TV, TT, W = np.vstack([V, TVc]), TTc + len(V), np.vstack([Ws / Ws.sum(1, keepdims=True), Wc])
        warnings = list(warnings) + [f"{len(F)} triangles: the volume mesh and the search use the surface "
                                     f"simplified to {len(Fc)}; outputs and reports are full resolution"]
    elif skinned:
        from ..files.printbody import transfer_values

        W = np.vstack([Ws, transfer_values(TV[len(V):], V, F, Ws)]) if len(TV) > len(V) else Ws
        W /= np.maximum(W.sum(1, keepdims=True), 1e-300)
    elif tet_weights is not None:
        if tet_mesh is None:
            raise InputError(None, "precomputed weights need the tet mesh they were computed on (--tets)")
        W = np.asarray(tet_weights, np.float64)
        if W.shape != (len(TV), len(B)):
            raise InputError(None, f"weights are {W.shape[0]}x{W.shape[1]} but the tet mesh has {len(TV)} "
                             f"vertices and the skeleton {len(B)} bones")
        notes = []
        W = check_weights(W[tet_order], notes)
        warnings = list(warnings) + notes
    else:
        say("computing bounded biharmonic weights")
        notes = []
        W = compute_weights(TV, TT, J, B, bbw_iterations, notes=notes)
        warnings = list(warnings) + notes
    t2 = time.perf_counter()
    info = {"tet_seconds": t1 - t0, "weights_seconds": t2 - t1, "samples_per_bone": samples_per_bone,
            "bbw_iterations": bbw_iterations, "warnings": warnings, "weights": "skin" if skinned else "bbw"}
    if moved is not None:  # printed files are placed on the plate anyway; the report says where it was
        info |= {"moved_by": moved.tolist(), "warnings": warnings + [
            f"the model lies {np.linalg.norm(moved) / np.ptp(V, axis=0).max():.3g} times its size from the "
            "origin: it was moved to the origin first (its volumes would lose their digits)"]}
    proxy = coarse is not None or simplified is not None
    return Rig(V, F, J, B, TV, TT, W, up_vec, name=name, info=info, labels=list(labels) if labels is not None else None,
               coarse_faces=Fc + len(V) if proxy else None)


#: A model whose centre lies farther from the origin than this many times its size is moved to the origin
#: before anything is computed: volumes, orientations and winding numbers of coordinates much larger than
#: the model lose their digits (the bunny moved 5e4 sizes away: joints "outside", faces flipped).
FAR_FROM_ORIGIN = 100.0


def _near_origin(V, J, tet_mesh, skinned):
    """``V``, ``J`` and ``tet_mesh`` moved to the origin when :data:`FAR_FROM_ORIGIN` says so, and by how much.

    A skinned (glTF) model keeps its frame: its skin is written back in it.
    """
    if skinned or not len(V) or not np.isfinite(V).all():
        return V, J, tet_mesh, None
    centre = (V.min(axis=0) + V.max(axis=0)) / 2
    size = float(np.ptp(V, axis=0).max())
    if not size > 0 or np.linalg.norm(centre) <= FAR_FROM_ORIGIN * size:
        return V, J, tet_mesh, None
    d = V.shape[1]
    J = J.copy()
    J[:, :d] -= centre
    if tet_mesh is not None:
        tet_mesh = (np.asarray(tet_mesh[0], np.float64) - centre, tet_mesh[1])
    return V - centre, J, tet_mesh, -centre


def _simplified(V, F, say, fast_first=True, target=None):
    """The surface simplified to ``target`` (default :data:`PROXY_TARGET`) triangles, or None."""
    from ..files.simplify import simplify_surface

    target = PROXY_TARGET if target is None else int(target)
    with step(f"proxy: {len(F)} triangles simplified to {target}"):
        return simplify_surface(V, F, target, fast_first)


#: A sculpt's proxy made the fast way that TetGen refuses with the skeleton inside is made again at these
#: shares of :data:`PROXY_TARGET` (from the same quick reduction: 5-15 s each) before the slow way (minutes):
#: on the 5.35M-triangle bunny TetGen (libigl's ``mesh_with_skeleton``) refused the proxies of 10 000 and
#: 8 000 triangles and took those of 9 000 and 11 000, every one closed and uncrossed, the skeleton inside.
PROXY_RETRIES = (0.9, 1.1, 0.8, 1.2)


def _coarse_volume(V, F, J, B, up, samples_per_bone, bbw_iterations, skeleton_path, say):
    """Volume mesh and weights of the surface simplified to :data:`PROXY_TARGET` triangles.

    Returns ``(Vc, Fc, TVc, TTc, Wc)``, or None when the simplified surface
    cannot be meshed or weighted (then the full surface is). A sculpt's proxy
    is made the fast way first (:func:`supportless.files.simplify.simplify_surface`),
    at :data:`PROXY_RETRIES` sizes when it cannot be meshed, then the slow way.
    """
    from ..files.simplify import FAST_FIRST_FACES
    from .tetmesh import tetrahedralize_with_skeleton

    say(f"simplifying the surface to {PROXY_TARGET} triangles for the volume mesh")
    tries = [(True, PROXY_TARGET)]
    if len(F) > FAST_FIRST_FACES:
        tries += [(True, round(share * PROXY_TARGET)) for share in PROXY_RETRIES] + [(False, PROXY_TARGET)]
    for fast_first, target in tries:
        simplified = _simplified(V, F, say, fast_first, target)
        if simplified is None:
            continue
        Vc, Fc = simplified
        try:
            Jc, _ = pull_joints_inside(Vc, Fc, J, B, up, skeleton_path, reach=PROXY_JOINT_REACH)
            with step("proxy: volume mesh and weights"):
                TVc, TTc = tetrahedralize_with_skeleton(Vc, Fc, Jc, B, samples_per_bone)
                Wc = compute_weights(TVc, TTc, Jc, B, bbw_iterations)
        except (InputError, RuntimeError):
            continue
        return Vc, Fc, TVc, TTc, Wc
    say("the simplified surface could not be meshed; meshing the full surface")
    return None


def _attach_surface(V, TV, TT, path):
    """Reorder a given volume mesh so its first rows are the surface vertices.

    Returns the reordered vertices (t, 3), the re-indexed tets (k, 4) and the
    order (t,) int64 (new row i is old row ``order[i]``).
    """
    from scipy.spatial import cKDTree

    dist, idx = cKDTree(TV).query(V)
    scale = float(np.ptp(V, axis=0).max())
    if np.max(dist) > 1e-7 * scale:
        raise InputError(path, "the tet mesh does not contain the surface's vertices; "
                         "give the tet mesh made from this surface")
    rest = np.setdiff1d(np.arange(len(TV)), idx)
    order = np.concatenate([idx, rest])
    inverse = np.empty_like(order)
    inverse[order] = np.arange(len(order))
    TV = TV[order]
    TV[: len(V)] = V  # exactly the surface, not just within tolerance
    return TV, inverse[TT], order
