"""Range of motion from bone names: knees and elbows bend one way, spines and necks within their ranges.

A rig whose bones have names (a glTF character: Mixamo ``mixamorig:LeftLeg``,
VRM ``leftLowerLeg``, VRoid ``J_Bip_L_LowerLeg``, Unreal ``calf_l``, Blender
and Rigify ``shin.L`` / ``DEF-shin.L``, Quaternius ``LowerLeg.L`` and
``FrontLowerLeg.L``) says which bone is a thigh, a shin, a forearm, a neck, a
head (VRoid's centre bones ``J_Bip_C_Head``, Rigify's ``DEF-spine.004`` to
``.006``: neck and head, :func:`bone_parts`). Such a
bone's joint then gets the range of the joint it names
(:data:`HUMANOID_TABLE`, :data:`QUADRUPED_TABLE`), on top of the generic per-joint
limit every bone has:

* a **hinge** (knee, elbow) bends about one axis, one way, within a range of
  flexion; it may leave its plane and twist only a little;
* a **sagittal** joint (a four-legged animal's leg) bends either way, but in
  the plane of the body's length;
* a **ball** (hip, shoulder, spine, neck, head, wrist, ankle) swings within a
  cone and twists about the bone within a range.

Everything is measured on the joint's rotation *relative to its parent
bone* — ``Q = A_parent^T A_child`` of the two bones' skinning rotations, so it
does not matter which way the search's kinematic tree hangs — and on the rest
skeleton's geometry: the bone directions, and the body's left (from the
left/right names), up (hips to head) and front (``left x up`` for a figure
that stands on its legs; hips to head for one on all fours). A joint bent at
rest (a seated figure's knee) keeps its rest bend inside its range. Bones
without a name the tables know keep the generic limits only.

:func:`joint_ranges` builds the :class:`JointRanges` of a rig (None when no
bone is recognised); :meth:`JointRanges.excess` is the search's hard rule and
:meth:`JointRanges.usage` the report's figure.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..base.rotations import matrix_to_quaternion
from ..rig.rig import Rig

__all__ = ["HUMANOID_TABLE", "QUADRUPED_TABLE", "JointRange", "JointRanges", "bone_part", "bone_parts",
           "joint_ranges"]


@dataclass(frozen=True)
class JointRange:
    """The range of motion of one kind of joint, degrees.

    Attributes
    ----------
    kind : {"hinge", "sagittal", "ball"}
    bend : (float, float)
        Hinge and sagittal joints: the flexion range (low, high), positive
        the way the joint bends (a knee's shin backwards, an elbow's forearm
        forwards); the rest bend is always inside.
    side : float
        Hinge and sagittal joints: how far the child may leave the plane of bending.
    swing : float
        Ball joints: the cone the child's direction stays within.
    twist : float
        Largest turn about the child bone's own direction.
    """

    kind: str
    bend: tuple = (0.0, 0.0)
    side: float = 0.0
    swing: float = 0.0
    twist: float = 0.0


#: Joints of a figure on two legs, by the part a bone's name says it is (the joint at the bone's start).
#: Ranges after the usual clinical tables of active motion, narrowed towards a relaxed figure where a
#: figurine's pose should not go (e.g. a head's own tilt on its neck).
HUMANOID_TABLE = {
    "spine": JointRange("ball", swing=25.0, twist=20.0),
    "neck": JointRange("ball", swing=35.0, twist=40.0),
    "head": JointRange("ball", swing=30.0, twist=35.0),
    "shoulder": JointRange("ball", swing=20.0, twist=10.0),
    "upper_arm": JointRange("ball", swing=90.0, twist=60.0),
    "forearm": JointRange("hinge", bend=(-5.0, 145.0), side=10.0, twist=80.0),
    "hand": JointRange("ball", swing=60.0, twist=20.0),
    "thigh": JointRange("ball", swing=90.0, twist=35.0),
    "shin": JointRange("hinge", bend=(-5.0, 140.0), side=10.0, twist=15.0),
    "foot": JointRange("ball", swing=35.0, twist=20.0),
    "toe": JointRange("ball", swing=40.0, twist=10.0),
}

#: Joints of a figure on four legs: its legs bend in the plane of the body's length.
QUADRUPED_TABLE = {
    "spine": JointRange("ball", swing=25.0, twist=15.0),
    "neck": JointRange("ball", swing=45.0, twist=30.0),
    "head": JointRange("ball", swing=40.0, twist=30.0),
    "upper_leg": JointRange("sagittal", bend=(-np.inf, np.inf), side=20.0, twist=20.0),
    "lower_leg": JointRange("sagittal", bend=(-np.inf, np.inf), side=15.0, twist=15.0),
    "paw": JointRange("sagittal", bend=(-np.inf, np.inf), side=20.0, twist=20.0),
}

#: The part each kind of joint hangs from (the bone its range is measured against).
_PARENT_PARTS = {
    "spine": ("hips", "spine"), "neck": ("spine", "neck"), "head": ("neck", "spine"),
    "shoulder": ("spine",), "upper_arm": ("shoulder", "spine"), "forearm": ("upper_arm",), "hand": ("forearm",),
    "thigh": ("hips", "spine"), "shin": ("thigh",), "foot": ("shin",), "toe": ("foot",),
    "upper_leg": ("shoulder", "hips", "spine", "upper_leg"), "lower_leg": ("upper_leg",), "paw": ("lower_leg",),
}

#: Name stems (lower case, letters only) and the part they name.
_STEMS = {
    "hips": "hips", "pelvis": "hips", "root": None,
    "spine": "spine", "chest": "spine", "upperchest": "spine", "abdomen": "spine", "torso": "spine",
    "waist": "spine", "belly": "spine", "back": "spine", "shoulders": "spine",
    "neck": "neck", "necktwist": "neck", "necklower": "neck", "neckupper": "neck", "head": "head",
    "shoulder": "shoulder", "clavicle": "shoulder", "collar": "shoulder",
    "arm": "upper_arm", "upperarm": "upper_arm", "uparm": "upper_arm",
    "forearm": "forearm", "lowerarm": "forearm",
    "hand": "hand", "wrist": "hand", "fist": "hand",
    "upleg": "thigh", "upperleg": "thigh", "thigh": "thigh",
    "leg": "shin", "lowerleg": "shin", "lowleg": "shin", "calf": "shin", "shin": "shin",
    "foot": "foot", "ankle": "foot", "toebase": "toe", "toe": "toe", "toes": "toe", "ball": "toe",
    # DAZ's bend and twist bones, and its spine's halves
    "shldrbend": "upper_arm", "shldr": "upper_arm", "forearmbend": "forearm", "thighbend": "thigh",
    "abdomenlower": "spine", "abdomenupper": "spine", "chestlower": "spine", "chestupper": "spine",
}

#: Humanoid parts as a four-legged animal's: the front legs are its arms, the hind legs its legs.
_AS_QUADRUPED = {"upper_arm": ("front", "upper_leg"), "forearm": ("front", "lower_leg"), "hand": ("front", "paw"),
                 "thigh": ("back", "upper_leg"), "shin": ("back", "lower_leg"), "foot": ("back", "paw")}

_PREFIXES = ("mixamorig", "def-", "org-", "mch-", "j_bip_", "b_", "valvebiped.", "bip01", "bip001", "cc_base_")

#: A HumanIK/MotionBuilder character's prefix (``Character1_LeftArm``).
_HUMANIK = re.compile(r"(?i)^character\d*_")

#: DAZ's side letter, lower case before a capitalised part (``lShldrBend``, ``rThighTwist``).
_DAZ_SIDE = re.compile(r"^([lr])(?=[A-Z])")


def bone_part(name: str) -> tuple[str | None, str | None, str | None, str]:
    """What a bone's name says it is.

    Parameters
    ----------
    name : str
        A bone (joint) name as a rig file gives it.

    Returns
    -------
    part : str or None
        A key of :data:`HUMANOID_TABLE` (or ``"hips"``), ``"upper_leg"``,
        ``"lower_leg"`` or ``"paw"`` for a name that says front or back, or
        None for a name no table knows (a finger, an ear, a wing, a tail).
    side : {"left", "right"} or None
    group : {"front", "back"} or None
        Which pair of legs, for a name that says so.
    convention : str
        The naming convention recognised (``"Mixamo"``, ``"VRoid"``, ``"Unreal"``, ``"Blender"``, ``"VRM"``,
        ``"Left/Right"``, ``"plain"``),
        for the one line that says which table was applied.

    Examples
    --------
    >>> bone_part("mixamorig:LeftLeg")[:2]
    ('shin', 'left')
    >>> bone_part("FrontLowerLeg.R")[:3]
    ('lower_leg', 'right', 'front')
    """
    raw = str(name)
    if ">" in raw:  # a bone between two joints the file names ("A>B"): not the bone of either
        return None, None, None, ""
    convention = "Mixamo" if raw.lower().startswith("mixamorig") else "VRoid" if raw.startswith("J_Bip") else ""
    text = raw.split(":")[-1].split("|")[-1].strip()
    low = text.lower()
    for prefix in _PREFIXES:
        if low.startswith(prefix):
            text, low = text[len(prefix):], low[len(prefix):]
            convention = convention or ("3ds Max Biped" if prefix.startswith("bip") else "")
            text = text.lstrip(" _.:-")  # 3ds Max Biped's "Bip01 L UpperArm", Valve's "Bip01_L_UpperArm"
            low = text.lower()
    text = _HUMANIK.sub("", text)
    daz = _DAZ_SIDE.match(text)
    if daz and not convention:
        convention = "DAZ"
    text = re.sub(r"[._]\d+$", "", text)  # Blender's .001, an exporter's _06
    text = re.sub(r"(?i)^c[._ ](?=[a-z])", "", text)  # VRoid's centre bones: J_Bip_C_Head
    side = None
    if daz:
        side = "left" if daz.group(1) == "l" else "right"
        text = text[1:]
    match = None if daz else (re.search(r"(?i)[._ ]([lr])$", text) or re.search(r"(?i)^([lr])[._ ]", text))
    if match:
        side = "left" if match.group(1).lower() == "l" else "right"
        text = text[:match.start()] + text[match.end():]
        convention = convention or ("Unreal" if "_" in match.group(0) else "Blender")
    else:
        match = re.match(r"(?i)(left|right)", text)
        if match:
            side = match.group(1).lower()
            text = text[match.end():]
            convention = convention or ("VRM" if text[:1].islower() else "Left/Right")
    stem = re.sub(r"[^a-z]", "", text.lower())
    group = None
    for word, g in (("front", "front"), ("fore", "front"), ("back", "back"), ("hind", "back"), ("rear", "back")):
        if stem.startswith(word) and len(stem) > len(word) and not stem.startswith("forearm"):
            group, stem = g, stem[len(word):]
            break
    stem = stem.rstrip("s") if stem not in _STEMS and stem.rstrip("s") in _STEMS else stem
    part = _STEMS.get(stem)
    if stem == "hip" and side is None and group is None:
        part = "hips"
    if part is None and stem.startswith("spine"):
        part = "spine"
    if group is not None:
        part = {"upperleg": "upper_leg", "upleg": "upper_leg", "leg": "upper_leg", "lowerleg": "lower_leg",
                "lowleg": "lower_leg", "foot": "paw", "paw": "paw"}.get(stem)
        if part is None and stem == "shoulder":
            part = "shoulder"
    if part in ("shoulder", "upper_arm", "forearm", "hand", "thigh", "shin", "foot", "toe", "upper_leg",
                "lower_leg", "paw") and side is None:
        part = None  # a limb without a side is not one the tables can place
    return part, side, group, convention or "plain"


#: Rigify's deforming spine (``DEF-spine`` to ``DEF-spine.006`` of its human metarig): the last three are the
#: neck (``.004``, ``.005``) and the head (``.006``).
_RIGIFY_SPINE = re.compile(r"(?i)^(?:def-|org-)?spine\.(\d{3})$")


def bone_parts(labels: list) -> list[tuple]:
    """What each of a rig's bone names says it is.

    Parameters
    ----------
    labels : list of str
        The rig's bone names (:attr:`supportless.rig.rig.Rig.labels`).

    Returns
    -------
    parts : list of tuple
        :func:`bone_part` of each bone's own name (a bone ``"A>B"`` between two
        joints is ``A``'s when no other bone is), except Rigify's numbered spine:
        in a rig whose spine ends at ``spine.006`` and whose names say no neck
        or head, ``spine.004`` and ``spine.005`` are the neck and ``spine.006``
        the head.

    Examples
    --------
    >>> [p[0] for p in bone_parts(["DEF-spine", "DEF-spine.003", "DEF-spine.004", "DEF-spine.006"])]
    ['spine', 'spine', 'neck', 'head']
    """
    own = [_own_name(name, labels) for name in labels]
    parsed = [bone_part(name) for name in own]
    numbers = {}
    for b, name in enumerate(own):
        match = _RIGIFY_SPINE.match(name.split(":")[-1].split("|")[-1].strip())
        if match:
            numbers[b] = int(match.group(1))
    if numbers and max(numbers.values()) == 6 and not any(p[0] in ("neck", "head") for p in parsed):
        for b, n in numbers.items():
            if n >= 4:
                parsed[b] = ("neck" if n < 6 else "head", None, None, "Rigify")
    return parsed


def _unit(v: np.ndarray) -> np.ndarray:
    """``v`` scaled to length 1 along its last axis (a zero vector stays zero)."""
    v = np.asarray(v, np.float64)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


@dataclass(frozen=True)
class JointRanges:
    """The named joints of one rig and their ranges.

    Attributes
    ----------
    table : {"humanoid", "quadruped"}
    convention : str
        The naming convention recognised (:func:`bone_part`).
    child, parent : (k,) int64
        The bone each joint moves and the bone it is measured against.
    names : list of str
        The child bones' names (the joints').
    kinds : (k,) int64
        0 ball, 1 hinge or sagittal.
    direction : (k, 3) float64
        The child bone's rest direction (unit).
    reference : (k, 3) float64
        The parent bone's rest direction (unit): a hinge's zero bend.
    axis : (k, 3) float64
        A hinge's axis, orthogonal to ``reference`` (zero for a ball).
    bend_low, bend_high, side_rest, side, swing, twist : (k,) float64
        Radians: the flexion range (widened to hold the rest bend), the rest
        angle out of the bending plane and the allowance about it, the swing
        cone and the twist range.
    """

    table: str
    convention: str
    child: np.ndarray
    parent: np.ndarray
    names: list
    kinds: np.ndarray
    direction: np.ndarray
    reference: np.ndarray
    axis: np.ndarray
    bend_low: np.ndarray
    bend_high: np.ndarray
    side_rest: np.ndarray
    side: np.ndarray
    swing: np.ndarray
    twist: np.ndarray

    @property
    def count(self) -> int:
        """Number of named joints."""
        return len(self.child)

    def describe(self) -> str:
        """One line: which table, from which names, on how many joints."""
        return (f"joint ranges: the {self.table} table ({self.convention} bone names) on {self.count} joints: "
                + ", ".join(self.names[:6]) + (" ..." if self.count > 6 else ""))

    def measures(self, transforms: np.ndarray) -> dict[str, np.ndarray]:
        """Each joint's bend, side bend, swing and twist at a batch of poses.

        Parameters
        ----------
        transforms : (P, m, 3, 4) or (m, 3, 4) float64
            The bones' skinning transforms (:meth:`supportless.rig.rig.Rig.transforms`).

        Returns
        -------
        measures : dict of str -> (P, k) or (k,) float64
            ``bend`` (signed, about the hinge axis), ``side`` (signed, out of
            the bending plane), ``swing`` (from the rest direction) and
            ``twist`` (unsigned, about the child's direction), radians.
        """
        A = np.asarray(transforms, np.float64)[..., :3, :3]
        Q = np.swapaxes(A[..., self.parent, :, :], -1, -2) @ A[..., self.child, :, :]
        u = np.einsum("...kij,kj->...ki", Q, self.direction)
        f = np.cross(self.axis, self.reference)
        bend = np.arctan2(np.einsum("...ki,ki->...k", u, f), np.einsum("...ki,ki->...k", u, self.reference))
        side = np.arcsin(np.clip(np.einsum("...ki,ki->...k", u, self.axis), -1.0, 1.0))
        swing = np.arccos(np.clip(np.einsum("...ki,ki->...k", u, self.direction), -1.0, 1.0))
        q = matrix_to_quaternion(Q)
        along = np.einsum("...ki,ki->...k", q[..., :3], self.direction)
        twist = np.abs(2.0 * np.arctan2(np.abs(along), np.abs(q[..., 3])))
        return {"bend": bend, "side": side, "swing": swing, "twist": twist}

    def _overs(self, m: dict) -> dict[str, np.ndarray]:
        """How far each measure is past its range, radians, (P, k) each."""
        hinge = self.kinds == 1
        return {"bend": np.where(hinge, np.maximum(m["bend"] - self.bend_high, 0.0)
                                 + np.maximum(self.bend_low - m["bend"], 0.0), 0.0),
                "side": np.where(hinge, np.maximum(np.abs(m["side"] - self.side_rest) - self.side, 0.0), 0.0),
                "swing": np.where(hinge, 0.0, np.maximum(m["swing"] - self.swing, 0.0)),
                "twist": np.maximum(m["twist"] - self.twist, 0.0)}

    def excess(self, transforms: np.ndarray) -> np.ndarray:
        """How far the named joints are outside their ranges, summed, radians, (P,) or () float64; 0 within."""
        return sum(self._overs(self.measures(transforms)).values()).sum(axis=-1)

    def usage(self, transforms: np.ndarray) -> dict:
        """The joint nearest (or furthest past) its range at one pose, JSON-ready.

        Parameters
        ----------
        transforms : (m, 3, 4) float64

        Returns
        -------
        usage : dict
            ``joint`` (its name), ``measure`` (``bend``, ``side``, ``swing``
            or ``twist``), ``angle_deg`` and ``limit_deg`` (the end of the
            range it is nearest), ``share`` (angle over limit: above 1 is
            outside) and ``outside_deg`` (the largest excess of any joint, 0
            when every named joint is within its range).
        """
        m = self.measures(transforms)
        hinge = self.kinds == 1
        bend_limit = np.where(m["bend"] >= 0, self.bend_high, self.bend_low)
        side = m["side"] - self.side_rest
        values = {"bend": (m["bend"], bend_limit, hinge), "side": (side, self.side, hinge),
                  "swing": (m["swing"], self.swing, ~hinge), "twist": (m["twist"], self.twist, np.ones_like(hinge))}
        best = (-1.0, "", "", 0.0, 0.0)
        for what, (angle, limit, applies) in values.items():
            share = np.where(applies, np.abs(angle) / np.maximum(np.abs(limit), 1e-9), -1.0)
            k = int(np.argmax(share))
            if share[k] > best[0]:
                best = (float(share[k]), what, self.names[k], float(np.degrees(angle[k])), float(np.degrees(limit[k])))
        outside = max(float(np.degrees(v.max(initial=0.0))) for v in self._overs(m).values())
        share, what, joint, angle, limit = best
        return {"table": self.table, "joint": joint, "measure": what, "angle_deg": angle, "limit_deg": limit,
                "share": share, "outside_deg": outside}


def _own_name(label: str, labels: list) -> str:
    """The name of the joint a bone starts at: ``"A>B"`` (a bone no joint of the file carries) is ``A``'s
    when no other bone is called ``A``; otherwise the label as it is."""
    head = str(label).split(">")[0]
    return head if ">" in str(label) and head not in labels else str(label)


def _starts(start: np.ndarray, parsed: list, parts: tuple) -> np.ndarray | None:
    """The mean start joint of the bones named as one of ``parts``, (3,) float64, or None."""
    rows = [b for b, p in enumerate(parsed) if p[0] in parts]
    return start[rows].mean(axis=0) if rows else None


def joint_ranges(rig: Rig) -> JointRanges | None:
    """The range-of-motion table a rig's bone names call for, or None.

    Parameters
    ----------
    rig : Rig
        A 3D rig with :attr:`~supportless.rig.rig.Rig.labels`.

    Returns
    -------
    ranges : JointRanges or None
        None for a 2D rig, a rig without names, or one where no named bone
        joins a named parent (the generic limits alone apply).
    """
    if rig.dim != 3 or rig.labels is None:
        return None
    parsed = bone_parts(rig.labels)
    if not any(p[0] not in (None, "hips") for p in parsed):
        return None
    J, B = np.asarray(rig.joints, np.float64), np.asarray(rig.bones)
    start, end = J[B[:, 0]], J[B[:, 1]]
    mid = 0.5 * (start + end)

    def centre(part, side=None):
        rows = [b for b, p in enumerate(parsed) if p[0] == part and (side is None or p[1] == side)]
        return mid[rows].mean(axis=0) if rows else None

    left = [b for b, p in enumerate(parsed) if p[1] == "left"]
    right = [b for b, p in enumerate(parsed) if p[1] == "right"]
    if not left or not right:
        return None
    lateral = mid[left].mean(axis=0) - mid[right].mean(axis=0)
    hips = next((c for c in (centre("hips"), centre("spine"), _starts(start, parsed, ("thigh", "upper_leg")))
                 if c is not None), None)
    head = next((c for c in (centre("head"), centre("neck"), _starts(start, parsed, ("upper_arm", "shoulder")))
                 if c is not None), None)
    if hips is None or head is None:
        return None
    along = head - hips
    lateral = _unit(lateral - (lateral @ _unit(along)) * _unit(along))
    along = _unit(along)
    legs = [b for b, p in enumerate(parsed) if p[0] in ("thigh", "shin", "upper_leg", "lower_leg")]
    leg_dirs = _unit(end[legs] - start[legs]) if legs else np.zeros((0, 3))
    named_quadruped = any(p[2] is not None for p in parsed)
    standing_up = not named_quadruped and len(legs) > 0 and float((leg_dirs @ along).mean()) < -0.4
    table_name = "humanoid" if standing_up else "quadruped"
    table = HUMANOID_TABLE if standing_up else QUADRUPED_TABLE
    front = np.cross(lateral, along) if standing_up else along
    parts = []
    for part, side, group, _ in parsed:
        if not standing_up and part in _AS_QUADRUPED:
            group, part = _AS_QUADRUPED[part]
        parts.append((part, side, group))

    # bones that share a joint, and each bone's distance from the hips in that graph
    adjacency = [set() for _ in range(len(B))]
    by_joint: dict[int, list] = {}
    for b, (a, c) in enumerate(B):
        by_joint.setdefault(int(a), []).append(b)
        by_joint.setdefault(int(c), []).append(b)
    for bones in by_joint.values():
        for b in bones:
            adjacency[b].update(x for x in bones if x != b)
    roots = ([b for b, p in enumerate(parts) if p[0] == "hips"] or [b for b, p in enumerate(parts) if p[0] == "spine"]
             or [int(np.argmin(np.linalg.norm(mid - hips, axis=1)))])
    depth = np.full(len(B), np.inf)
    frontier = list(roots)
    depth[frontier] = 0
    while frontier:
        nxt = []
        for b in frontier:
            for x in adjacency[b]:
                if depth[x] == np.inf:
                    depth[x] = depth[b] + 1
                    nxt.append(x)
        frontier = nxt

    rows = []
    for b, (part, side, group) in enumerate(parts):
        if part not in table:
            continue
        candidates = [x for x in adjacency[b] if parts[x][0] in _PARENT_PARTS[part] and depth[x] < depth[b]
                      and (parts[x][1] in (None, side)) and (parts[x][2] in (None, group))]
        if not candidates:
            continue
        p = min(candidates, key=lambda x: depth[x])
        shared = set(B[p].tolist()) & set(B[b].tolist())
        if not shared:
            continue
        s = shared.pop()
        child_far = B[b][1] if B[b][0] == s else B[b][0]
        parent_far = B[p][1] if B[p][0] == s else B[p][0]
        d = J[child_far] - J[s]
        r = J[s] - J[parent_far]
        if np.linalg.norm(d) <= 0 or np.linalg.norm(r) <= 0:
            continue
        rows.append((b, p, part, _unit(d), _unit(r)))
    if not rows:
        return None

    k = len(rows)
    kinds = np.zeros(k, np.int64)
    axis = np.zeros((k, 3))
    low, high, side_rest, side_allow, swing, twist = (np.zeros(k) for _ in range(6))
    for i, (b, p, part, d, r) in enumerate(rows):
        spec = table[part]
        swing[i], twist[i] = np.radians(spec.swing), np.radians(spec.twist)
        if spec.kind == "ball":
            continue
        if part == "forearm":  # an elbow bends the forearm towards the front
            h = np.cross(r, front)
        else:  # a knee the shin towards the back, a leg in the body's length plane
            h = lateral - (lateral @ r) * r
        if np.linalg.norm(h) < 0.3:  # the hinge axis is not defined by the body's frame
            bent = np.cross(r, d)
            if np.linalg.norm(bent) < np.sin(np.radians(15.0)):
                kinds[i], swing[i] = 0, np.radians(max(spec.side, 15.0))  # keep it near its rest direction
                continue
            h = bent
        h = _unit(h)
        kinds[i], axis[i] = 1, h
        f = np.cross(h, r)
        rest_bend = np.arctan2(d @ f, d @ r)
        lo, hi = np.radians(spec.bend)
        low[i], high[i] = min(lo, rest_bend), max(hi, rest_bend)
        side_rest[i] = np.arcsin(np.clip(d @ h, -1.0, 1.0))
        side_allow[i] = np.radians(spec.side)
    convention = next((p[3] for p in parsed if p[0] is not None and p[1] is not None),
                      next(p[3] for p in parsed if p[0] is not None))
    return JointRanges(table_name, convention, np.array([r[0] for r in rows], np.int64),
                       np.array([r[1] for r in rows], np.int64), [rig.labels[r[0]] for r in rows], kinds,
                       np.array([r[3] for r in rows]), np.array([r[4] for r in rows]), axis, low, high,
                       side_rest, side_allow, swing, twist)
