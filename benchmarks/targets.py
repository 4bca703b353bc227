"""The speed targets: cold preparation, the default search and peak memory, one process per case.

Cases: the bunny, bb-bunny, the glTF RobotExpressive (53 joints) and the
bunny subdivided twice (111k triangles, made here with ``igl.upsample``).
Each case runs in its own Python process (a warm-up search first, so numba
is compiled), with an empty rig cache: preparation time, search time with
``--orient keep`` and with the default ``free``, the found support (prism
estimate, and the reduction), exact intersecting pairs and the process's peak
resident memory. Prints a Markdown table; ``--out FILE`` writes it as the
"## Speed targets" section of FILE.

    python benchmarks/targets.py [--cases bunny bb-bunny robot bunny111k] [--out benchmarks/RESULTS.md]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from models import DATA

HEADING = "## Speed targets"
CASES = ("bunny", "bb-bunny", "robot", "bunny111k")

CHILD = r"""
import json, resource, sys, tempfile, time
from pathlib import Path
import numpy as np
import supportless as sl
from supportless.report import build_report

case, path, skeleton, cache = sys.argv[1:5]
kwargs = {"height_mm": 60.0} if path.endswith(".glb") else {}
t = time.perf_counter()
rig = sl.load_rig(path, None if skeleton == "-" else skeleton, cache_dir=cache, **kwargs)
prepare = time.perf_counter() - t
sl.optimize(rig, particles=4, iterations=1)  # numba compiled, operators warm
out = {"case": case, "faces": len(rig.faces), "bones": rig.bone_count, "prepare_s": prepare,
       "proxy_faces": None if rig.coarse_faces is None else len(rig.coarse_faces)}
for orient in ("keep", "free"):
    t = time.perf_counter()
    result = sl.optimize(rig, orient=orient)
    out[f"search_{orient}_s"] = time.perf_counter() - t
    report = build_report(rig, result)
    out[f"reduction_{orient}"] = report["reduction_percent"]["support_prism"]
    out[f"pairs_{orient}"] = report["after"]["intersecting_face_pairs"]
out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


def case_files(case: str, tmp: Path) -> tuple[str, str]:
    """(mesh path, skeleton path or "-") of a case; the dense bunny is written into ``tmp``."""
    if case == "robot":
        return str(DATA / "gltf" / "RobotExpressive.glb"), "-"
    if case == "bunny111k":
        import igl
        import numpy as np

        from supportless.io import read_mesh, write_mesh

        V, F = read_mesh(DATA / "bunny.obj")
        V2, F2 = igl.upsample(V, F.astype(np.int64), 2)
        write_mesh(tmp / "bunny111k.obj", V2, F2)
        return str(tmp / "bunny111k.obj"), str(DATA / "bunny.tgf")
    return str(DATA / f"{case}.obj"), str(DATA / f"{case}.tgf")


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for case in args.cases:
            path, skeleton = case_files(case, tmp)
            cache = tmp / f"cache-{case}"
            run = subprocess.run([sys.executable, "-c", CHILD, case, path, skeleton, str(cache)],
                                 capture_output=True, text=True, env=dict(os.environ))
            if run.returncode:
                print(f"{case}: failed\n{run.stderr[-2000:]}", file=sys.stderr)
                continue
            rows.append(json.loads(run.stdout.strip().splitlines()[-1]))
            r = rows[-1]
            print(f"{case}: prepare {r['prepare_s']:.1f} s, search keep {r['search_keep_s']:.1f} s, "
                  f"free {r['search_free_s']:.1f} s, peak {r['peak_mb']:.0f} MB", file=sys.stderr, flush=True)
    lines = [HEADING, "",
             f"Machine: {platform.machine()}, {os.cpu_count()} cores, one process per case, numba warmed up, "
             "empty rig cache. Search: 200 × 120; reduction = the prism estimate's, rest → found.",
             "Command: `python benchmarks/targets.py " + " ".join(argv) + "`", "",
             "| case | triangles (proxy) | bones | prepare | search, `--orient keep` | search, default | "
             "reduction keep / default | exact pairs | peak memory |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        proxy = f" ({r['proxy_faces']})" if r["proxy_faces"] else ""
        lines.append(f"| {r['case']} | {r['faces']}{proxy} | {r['bones']} | {r['prepare_s']:.1f} s | "
                     f"{r['search_keep_s']:.1f} s | {r['search_free_s']:.1f} s | {r['reduction_keep']:.1f} % / "
                     f"{r['reduction_free']:.1f} % | {r['pairs_keep']} / {r['pairs_free']} | {r['peak_mb']:.0f} MB |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        path = Path(args.out)
        old = path.read_text() if path.is_file() else ""
        pattern = re.compile(rf"^{re.escape(HEADING)}\n.*?(?=^## |\Z)", re.S | re.M)
        path.write_text(pattern.sub(lambda _: text + "\n", old) if pattern.search(old)
                        else old.rstrip() + "\n\n" + text)


if __name__ == "__main__":
    main()
