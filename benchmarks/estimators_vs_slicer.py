"""Does the slicer model predict PrusaSlicer? Collect sliced poses, fit the model, print the table.

Three steps, each optional:

``--collect``
    For each model: the rest pose, two random poses (every bone within ±30°,
    none self-intersecting), a random tilt of the rest pose (15-35°), the
    default search's result and up to three other distinct good poses of the
    same search (the candidates ``--slice-rank 4`` slices), and the search's
    result without the margin. All are sliced with PrusaSlicer (60 mm tall,
    the rest pose's scale; with ``--profile FILE`` that profile, else
    PrusaSlicer's defaults). Each sample (angles, print rotation, support
    filament) is appended to ``--samples`` (JSON lines).
``--fit``
    Grid search of the effective-threshold offset ``DELTA`` and interface
    height ``H``; for each, the coefficients that make the worst reduction
    error (rest -> found, every model and profile) smallest; prints the
    values to put in :mod:`supportless.energies.slicer_model` and each
    model's error when it is left out of the fit.
``--slicer-search``
    For each model: the default search with ``--overhang-model slicer`` (the
    slicer model as what the search minimises), sliced, against the default
    search's result in the samples (the prism estimate with the margin).
(always) the table
    For each model and profile: PrusaSlicer's reduction rest -> found
    (the search's result) and the predicted one, with the error in points;
    the slice-ranking gain (the least support among the distinct candidates
    against the search's result); the worst error.

    python benchmarks/estimators_vs_slicer.py --collect [--models ...] [--profile FILE] [--samples FILE]
    python benchmarks/estimators_vs_slicer.py --fit [--samples FILE]
    python benchmarks/estimators_vs_slicer.py --slicer-search [--models ...]
    python benchmarks/estimators_vs_slicer.py [--samples FILE]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

import models
import numpy as np
from scipy.optimize import minimize, nnls

import supportless as sl
from supportless.base.geometry import place_on_plate, print_pose
from supportless.copyleft.cgal import intersecting_face_pairs
from supportless.energies import slicer_model
from supportless.files.printer import default_profile, overhang_threshold, read_printer_profile
from supportless.files.printframe import REFERENCE_HEIGHT_MM
from supportless.slicing.prusaslicer import find_prusa_slicer, scale_for_height, slice_support
from supportless.slicing.ranking import distinct_poses

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SAMPLES = ROOT / "benchmarks" / "slicer_samples.jsonl"
ZOO = ("tpose", "branch", "apose", "quadruped", "lying", "seated", "arm", "tree", "hand", "bird", "tentacle",
       "dragon", "staff", "bunny", "bb-bunny")


def _rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    t = np.radians(degrees)
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K


def print_vertices(rig, angles, rotation):
    """The pose in its print frame (as the search's results are sliced)."""
    posed = place_on_plate(rig.pose(np.asarray(angles, float)), rig.up)
    return print_pose(posed, np.asarray(rotation, float), rig.up)


def collect(name, profile, profile_label, rng, out):
    """Slice one model's poses and append the samples."""
    rig = models.load(name)
    angle = overhang_threshold(profile)
    eye = np.eye(3)
    poses = [("rest", rig.rest_angles(), eye)]
    for _ in range(50):
        if len(poses) == 3:
            break
        A = rng.uniform(-1, 1, (rig.bone_count, 3)) * np.radians(30)
        if intersecting_face_pairs(rig.pose(A), rig.faces) == 0:
            poses.append((f"random{len(poses)}", A, eye))
    axis = np.cross(rig.up, rng.normal(size=3))
    poses.append(("tilt", rig.rest_angles(), _rotation(axis, rng.uniform(15, 35))))
    t0 = time.perf_counter()
    result = sl.optimize(rig, sl.SearchSettings(overhang_angle=angle))
    seconds = time.perf_counter() - t0
    for i, found in enumerate(distinct_poses(rig, result, 4)):
        poses.append((f"found{i + 1}" if i else "found", found.angles, found.rotation))
    bare = sl.optimize(rig, sl.SearchSettings(overhang_angle=angle, overhang_margin=0.0))
    poses.append(("found_no_margin", bare.angles, bare.rotation))
    scale = scale_for_height(rig.vertices, rig.up, REFERENCE_HEIGHT_MM)
    sliced = slice_support([(print_vertices(rig, A, R), rig.faces) for _, A, R in poses], rig.up, scale,
                           workers=2, profile=profile if profile.path else None)
    for (label, A, R), run in zip(poses, sliced.meshes):
        row = {"model": name, "profile": profile_label, "threshold": angle, "pose": label,
               "angles": np.asarray(A).round(10).tolist(), "rotation": np.asarray(R).round(12).tolist(),
               "slicer_mm": run["support_mm"], "search_s": seconds if label == "found" else None}
        out.write(json.dumps(row) + "\n")
        out.flush()
    print(f"{name}: {len(poses)} poses sliced", file=sys.stderr, flush=True)


def features(rig, rows, delta, interface_mm):
    """(len(rows), 3) features of the sampled poses at 60 mm."""
    scale = scale_for_height(rig.vertices, rig.up, REFERENCE_HEIGHT_MM)
    V = np.stack([print_vertices(rig, r["angles"], r["rotation"]) for r in rows])
    return slicer_model.support_features(V, rig.faces, rig.up, rows[0]["threshold"], scale, delta, interface_mm)


class Samples:
    """The samples by model, the rigs and a cache of features per (delta, H)."""

    def __init__(self, rows):
        self.rows = rows
        self.rigs = {m: models.load(m) for m in dict.fromkeys(r["model"] for r in rows)}
        self._cache = {}

    def X(self, rows, delta, interface_mm):
        out = []
        for r in rows:
            key = (r["model"], r["profile"], r["pose"], delta, interface_mm)
            if key not in self._cache:
                self._cache[key] = features(self.rigs[r["model"]], [r], delta, interface_mm)[0]
            out.append(self._cache[key])
        return np.array(out)


def reduction_errors(rows, predicted):
    """Per (model, profile): PrusaSlicer's and the predicted reduction rest -> found, and the ranking gain."""
    y = np.array([r["slicer_mm"] for r in rows])
    table = []
    for key in dict.fromkeys((r["model"], r["profile"]) for r in rows):
        idx = {r["pose"]: i for i, r in enumerate(rows) if (r["model"], r["profile"]) == key}
        if "rest" not in idx or "found" not in idx:
            continue
        b, f = idx["rest"], idx["found"]
        found = [i for p, i in idx.items() if p.startswith("found") and p != "found_no_margin"]
        best = min(found, key=lambda i: y[i])
        table.append({
            "model": key[0], "profile": key[1], "before": y[b], "after": y[f],
            "slicer": 100 * (1 - y[f] / y[b]) if y[b] > 0 else None,
            "predicted": 100 * (1 - predicted[f] / predicted[b]) if predicted[b] > 0 else None,
            "predicted_before": predicted[b], "predicted_after": predicted[f],
            "ranked": y[best], "ranked_of": len(found),
            "search_s": rows[f].get("search_s"),
        })
    for t in table:
        t["error"] = None if t["slicer"] is None or t["predicted"] is None else t["predicted"] - t["slicer"]
    return table


def _pairs(rows):
    """Row indices of (rest, found) per (model, profile), and PrusaSlicer's reductions there (points)."""
    table = reduction_errors(rows, np.ones(len(rows)))
    index = {(r["model"], r["profile"], r["pose"]): i for i, r in enumerate(rows)}
    kept = [t for t in table if t["slicer"] is not None]
    rest = np.array([index[(t["model"], t["profile"], "rest")] for t in kept], int)
    found = np.array([index[(t["model"], t["profile"], "found")] for t in kept], int)
    return rest, found, np.array([t["slicer"] for t in kept])


def _worst_error(coef, rest, found, slicer, X):
    """The worst |predicted - PrusaSlicer| reduction (points) with the coefficients ``|coef|``."""
    p = X @ np.abs(coef)
    with np.errstate(divide="ignore", invalid="ignore"):
        predicted = np.where(p[rest] > 0, 100 * (1 - p[found] / p[rest]), np.nan)
    err = np.abs(predicted - slicer)
    return float(np.nanmax(err)) if np.isfinite(err).any() else 0.0


def fit_coefficients(rows, X):
    """Coefficients that make the worst reduction error over ``rows`` smallest.

    A reduction does not change when every coefficient is scaled, so the
    direction ``(1, b, r)`` is chosen on a log grid of ``b`` and ``r`` and
    refined by Nelder-Mead on the worst error; the length then by least
    squares of the relative filament error.
    """
    y = np.array([r["slicer_mm"] for r in rows])
    weight = 1.0 / np.maximum(y, 50.0)  # relative errors: every model counts, not only the biggest supports
    pairs = _pairs(rows)
    grid = [(1.0, b, r) for b in np.geomspace(0.005, 1.0, 40) for r in np.r_[0.0, np.geomspace(0.01, 10.0, 50)]]
    scores = np.array([_worst_error(np.array(c), *pairs, X) for c in grid])
    best = None
    for k in np.argsort(scores)[:3]:
        m = minimize(_worst_error, np.array(grid[k]), args=(*pairs, X), method="Nelder-Mead",
                     options={"xatol": 1e-5, "fatol": 1e-4, "maxiter": 4000})
        if best is None or m.fun < best.fun:
            best = m
    coef = np.abs(best.x)
    p = X @ coef * weight
    return coef * (p @ (y * weight)) / (p @ p)


def fit(samples):
    """Grid over DELTA and H, minimax coefficients; the best by the worst reduction error over every profile.

    Also prints, for the chosen DELTA and H, the leave-one-model-out error:
    each model's error when the coefficients are fitted without it.
    """
    rows = samples.rows
    best = None
    for delta, H in itertools.product((1.0, 2.0, 3.0, 4.0, 5.0, 7.0, 9.0), (2.0, 3.0, 4.0, 5.0, 6.0, 8.0)):
        X = samples.X(rows, delta, H)
        coef = fit_coefficients(rows, X)
        errors = [abs(t["error"]) for t in reduction_errors(rows, X @ coef) if t["error"] is not None]
        score = (max(errors), float(np.mean(errors)))
        print(f"DELTA {delta:4.1f}  H {H:3.1f}  worst {score[0]:5.1f}  mean {score[1]:5.1f}  "
              f"coefficients {np.round(coef, 4).tolist()}", file=sys.stderr)
        if best is None or score < best[0]:
            best = (score, delta, H, coef)
    (worst, mean), delta, H, coef = best
    X = samples.X(rows, delta, H)
    held_out = []
    for name in dict.fromkeys(r["model"] for r in rows):
        keep = [i for i, r in enumerate(rows) if r["model"] != name]
        out = [i for i, r in enumerate(rows) if r["model"] == name]
        c = fit_coefficients([rows[i] for i in keep], X[keep])
        for t in reduction_errors([rows[i] for i in out], X[out] @ c):
            if t["error"] is not None:
                held_out.append((abs(t["error"]), f"{t['model']}/{t['profile']}"))
    print(f"best: DELTA = {delta:g}, INTERFACE_MM = {H:g}, COEFFICIENTS = {tuple(np.round(coef, 4).tolist())} "
          f"(worst reduction error {worst:.1f} points, mean {mean:.1f}, {len(rows)} sliced poses); "
          f"left out of the fit, each model's error: worst {max(held_out)[0]:.1f} points ({max(held_out)[1]}), "
          f"mean {np.mean([e for e, _ in held_out]):.1f}")
    return delta, H, coef


def slicer_search(samples, names):
    """The search minimising the slicer model against the default search, both sliced (default profile)."""
    angle = overhang_threshold(default_profile())
    ref = {(r["model"], r["pose"]): r for r in samples.rows if r["profile"] == "default"}
    print("| model | PrusaSlicer mm rest | default search (prism, margin) | search minimising the slicer model "
          "| search time (slicer model) |")
    print("|---|---|---|---|---|")
    worse = better = 0
    for name in names:
        if (name, "found") not in ref or not models.available(name):
            continue
        rig = models.load(name)
        t0 = time.perf_counter()
        result = sl.optimize(rig, sl.SearchSettings(overhang_angle=angle, overhang_model="slicer"))
        seconds = time.perf_counter() - t0
        scale = scale_for_height(rig.vertices, rig.up, REFERENCE_HEIGHT_MM)
        mm = slice_support([(print_vertices(rig, result.angles, result.rotation), rig.faces)], rig.up, scale,
                           workers=1).meshes[0]["support_mm"]
        rest, found = ref[(name, "rest")]["slicer_mm"], ref[(name, "found")]["slicer_mm"]
        worse += mm > found * 1.01
        better += mm < found * 0.99
        print(f"| {name} | {rest:.0f} | {found:.0f} ({_pct(100 * (1 - found / rest))}) "
              f"| {mm:.0f} ({_pct(100 * (1 - mm / rest))}) | {seconds:.0f} s |", flush=True)
    print(f"\nMinimising the slicer model needed more support than the default search on {worse} models "
          f"and less on {better} (1 % either way).")


def _pct(x):
    return "–" if x is None else f"{x:.1f} %"


def print_table(samples, model=None):
    """The table of predicted against PrusaSlicer reductions with ``model`` (delta, H, coefficients; default: the code's)."""
    rows = samples.rows
    delta, H, coef = model or (slicer_model.DELTA, slicer_model.INTERFACE_MM, slicer_model.COEFFICIENTS)
    predicted = samples.X(rows, delta, H) @ np.asarray(coef)
    table = reduction_errors(rows, predicted)
    print("| model | profile | PrusaSlicer support mm rest → found | reduction PrusaSlicer | predicted "
          "| error (points) | `--slice-rank 4`: support mm (of n poses) |")
    print("|---|---|---|---|---|---|---|")
    for t in table:
        gain = 100 * (1 - t["ranked"] / t["after"]) if t["after"] > 0 else 0.0
        error = "–" if t["error"] is None else f"{t['error']:+.1f}"
        print(f"| {t['model']} | {t['profile']} | {t['before']:.0f} → {t['after']:.0f} | {_pct(t['slicer'])} "
              f"| {_pct(t['predicted'])} | {error} "
              f"| {t['ranked']:.0f} ({t['ranked_of']}; {gain:.1f} % less) |")
    errors = [(abs(t["error"]), t["model"], t["profile"]) for t in table if t["error"] is not None]
    worst = max(errors)
    print(f"\nWorst |predicted − PrusaSlicer|: {worst[0]:.1f} points ({worst[1]}, {worst[2]}); "
          f"mean {np.mean([e[0] for e in errors]):.1f} points over {len(errors)} rows.")
    gains = [(t["after"] - t["ranked"], t["model"], t["profile"]) for t in table]
    better = [g for g in gains if g[0] > 0.5]
    print(f"Slice-ranking (4 poses) needed less support than the search's result on {len(better)} of {len(gains)} "
          f"rows" + (f", by up to {max(better)[0]:.0f} mm ({max(better)[1]})." if better else "."))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--collect", action="store_true", help="Slice poses of the models and append the samples.")
    p.add_argument("--fit", action="store_true", help="Refit the slicer model on the samples.")
    p.add_argument("--slicer-search", action="store_true",
                   help="Search with the slicer model as the overhang term and slice the results.")
    p.add_argument("--models", nargs="+", default=list(ZOO))
    p.add_argument("--profile", default=None, help="PrusaSlicer config (.ini) to collect with (default: its defaults).")
    p.add_argument("--samples", default=str(DEFAULT_SAMPLES))
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    if args.collect:
        if find_prusa_slicer() is None:
            sys.exit("PrusaSlicer not found: apt-get install prusa-slicer")
        profile = read_printer_profile(args.profile) if args.profile else default_profile()
        label = Path(args.profile).stem if args.profile else "default"
        rng = np.random.default_rng(args.seed)
        with open(args.samples, "a") as out:
            for name in args.models:
                if models.available(name):
                    collect(name, profile, label, rng, out)
    rows = [json.loads(line) for line in open(args.samples)]
    samples = Samples(rows)
    if args.slicer_search:
        slicer_search(samples, args.models)
        return
    print_table(samples, fit(samples) if args.fit else None)


if __name__ == "__main__":
    main()
