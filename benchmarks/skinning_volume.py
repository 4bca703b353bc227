"""Linear blend against dual quaternion skinning: volume and self-intersections of lowered arms.

For each rig, both upper arms are lowered by 20, 40 and 60 degrees (each
turned about the horizontal axis that takes it straight down, about its
shoulder joint; every other bone at rest) and the surface is posed twice from
the same bone transforms and weights: by linear blend skinning
(:meth:`supportless.Rig.pose`) and by dual quaternion skinning
(:func:`supportless.base.dualquat.dual_quaternion_skin`). Per pose: the
enclosed volume's change from the rest pose (signed-volume formula) and the
number of triangle pairs that intersect (CGAL's exact test,
:func:`supportless.copyleft.cgal.intersecting_faces`), beside the rest pose's
own. Prints a Markdown section; with ``--out`` it becomes that file's
"## Skinning: LBS against dual quaternions" section.

The upper arms are the bones named ``...LeftArm`` / ``...RightArm`` (a Mixamo glTF's
``mixamorig:LeftArm``), or else, on a rig without names, on each side the
long, roughly horizontal bone high on the body nearest its middle (the
clavicle is short, the forearm further out).

    python benchmarks/skinning_volume.py [--models gltf/reference/Xbot gltf/Xbot.glb] [--angles 20 40 60]
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import time

import numpy as np
from models import DATA, write_section

import supportless as sl
from supportless.base.dualquat import dual_quaternion_skin
from supportless.base.geometry import signed_volume
from supportless.base.kinematics import matrix_to_euler
from supportless.copyleft.cgal import intersecting_faces

HEADING = "## Skinning: LBS against dual quaternions"
MODELS = ("gltf/reference/Xbot", "gltf/reference/Mannequin", "gltf/Xbot.glb")
ARM_NAME = re.compile(r"(left|right)[ _.]?(upper)?[ _.]?arm$", re.I)


def load(name: str) -> sl.Rig:
    """``gltf/Xbot.glb`` (its skin), or ``gltf/reference/Xbot`` (OBJ + TGF) under ``../shared/data``."""
    if name.endswith((".glb", ".gltf")):
        return sl.load_rig(DATA / name)
    return sl.load_rig(DATA / f"{name}.obj", DATA / f"{name}.tgf")


def upper_arms(rig: sl.Rig) -> list[int]:
    """The two upper-arm bones: by name, else by shape (see the module docstring)."""
    if rig.labels is not None:
        named = [b for b, label in enumerate(rig.labels) if ARM_NAME.search(str(label))]
        if len(named) == 2:
            return named
    J, B, up = rig.joints, rig.bones, rig.up
    root, d = J[B[:, 0]], J[B[:, 1]] - J[B[:, 0]]
    length = np.linalg.norm(d, axis=1)
    height = J @ up
    span = float(np.ptp(rig.vertices @ up))
    candidates = np.flatnonzero((length > 0.1 * span) & (np.abs(d @ up) < 0.7 * length)
                                & (root @ up > height.min() + 0.6 * span))
    if len(candidates) < 2:
        raise ValueError(f"{rig.name}: no upper arms found")
    centre = J[B[rig.root_bone, 0]]
    across = d[candidates[np.argmax(length[candidates])]]  # an arm's direction: the body's left-right axis
    across = across - (across @ up) * up
    side = (root[candidates] - centre) @ across
    arms = []
    for s in (side < 0, side > 0):
        if s.any():
            arms.append(int(candidates[s][np.argmin(np.abs(side[s]))]))
    if len(arms) != 2:
        raise ValueError(f"{rig.name}: found upper arms on one side only")
    return arms


def lowering_angles(rig: sl.Rig, arms: list[int], degrees: float) -> np.ndarray:
    """(m, 3) float64 Euler angles turning each arm ``degrees`` towards straight down about its root joint."""
    from scipy.spatial.transform import Rotation

    angles = np.zeros((rig.bone_count, 3))
    for b in arms:
        d = rig.joints[rig.bones[b, 1]] - rig.joints[rig.bones[b, 0]]
        axis = np.cross(d, -rig.up)
        axis /= np.linalg.norm(axis)
        # the parent of an upper arm is at rest, so its relative rotation is the world one
        angles[b] = matrix_to_euler(Rotation.from_rotvec(np.radians(degrees) * axis).as_matrix())
    return angles


def measure(name: str, degrees: list[float]) -> list[dict]:
    """One row per angle: volume changes and intersecting pairs, LBS and DQS (and the rest pose's pairs)."""
    t0 = time.perf_counter()
    rig = load(name)
    prepare = time.perf_counter() - t0
    arms = upper_arms(rig)
    names = rig.bone_names()
    V, F, W = rig.vertices, rig.faces, rig.weights
    rest_volume = signed_volume(V, F)
    rest_pairs = len(intersecting_faces(V, F))
    angles = np.stack([lowering_angles(rig, arms, a) for a in degrees])
    T = rig.transforms(angles)
    rig.pose(angles[:1]), dual_quaternion_skin(V, W, T[:1])  # compiled and the skinning matrix built: not timed
    t = time.perf_counter()
    lbs = rig.pose(angles)
    t_lbs = time.perf_counter() - t
    t = time.perf_counter()
    dqs = dual_quaternion_skin(V, W, T)
    t_dqs = time.perf_counter() - t
    rows = []
    for p, a in enumerate(degrees):
        vl, vd = signed_volume(lbs[p], F), signed_volume(dqs[p], F)
        rows.append(dict(model=name, arms=", ".join(names[b] for b in arms), degrees=a, n=len(V), m=rig.bone_count,
                         rest_pairs=rest_pairs, dv_lbs=(vl - rest_volume) / rest_volume,
                         dv_dqs=(vd - rest_volume) / rest_volume, pairs_lbs=len(intersecting_faces(lbs[p], F)),
                         pairs_dqs=len(intersecting_faces(dqs[p], F)), t_lbs=t_lbs, t_dqs=t_dqs, prepare=prepare))
    return rows


def table(rows: list[dict]) -> str:
    out = ["| model | arms lowered | volume change LBS | volume change DQS | intersecting pairs LBS | "
           "intersecting pairs DQS |", "|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['model']} | {r['degrees']:g}° | {r['dv_lbs']:+.3%} | {r['dv_dqs']:+.3%} | "
                   f"{r['pairs_lbs']} | {r['pairs_dqs']} |")
    return "\n".join(out)


def notes(rows: list[dict]) -> str:
    seen, out = set(), []
    for r in rows:
        if r["model"] in seen:
            continue
        seen.add(r["model"])
        out.append(f"- {r['model']}: {r['n']} vertices, {r['m']} bones, arms {r['arms']}; {r['rest_pairs']} "
                   f"intersecting pairs at rest; posing {len([q for q in rows if q['model'] == r['model']])} poses "
                   f"LBS {r['t_lbs'] * 1e3:.0f} ms, DQS {r['t_dqs'] * 1e3:.0f} ms")
    return "\n".join(out)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", nargs="+", default=list(MODELS),
                        help="under ../shared/data: NAME for NAME.obj + NAME.tgf, or a .glb (default: %(default)s)")
    parser.add_argument("--angles", nargs="+", type=float, default=[20.0, 40.0, 60.0],
                        help="degrees to lower both upper arms by (default: %(default)s)")
    parser.add_argument("--out", help="write the section into this Markdown file (e.g. benchmarks/RESULTS.md)")
    args = parser.parse_args(argv)
    rows = []
    for name in args.models:
        rows += measure(name, args.angles)
        print(f"{name}: done", flush=True)
    command = "python benchmarks/skinning_volume.py" + ("" if args.models == list(MODELS) else
                                                        " --models " + " ".join(args.models))
    text = (f"{HEADING}\n\nCommand: `{command}` ({platform.machine()}, {os.cpu_count()} cores). Both upper arms "
            f"lowered (turned towards straight down about the shoulder), the same bone transforms and weights "
            f"posed by linear blend skinning and by dual quaternion skinning; volume change against the rest "
            f"surface's enclosed volume; intersecting triangle pairs by CGAL's exact test.\n\n{table(rows)}\n\n"
            f"{notes(rows)}\n")
    print(text)
    if args.out:
        write_section(args.out, HEADING, text)


if __name__ == "__main__":
    main()
