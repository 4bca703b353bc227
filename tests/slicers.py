"""Stand-in slicer executables shared by the slicer and slice-ranking tests."""

import stat
import sys
import textwrap


def fake_exe(directory, name, body):
    """Write ``body`` (Python, dedented) as an executable script ``directory/name``; returns its path (str)."""
    p = directory / name
    p.write_text(f"#!{sys.executable}\n" + textwrap.dedent(body))
    p.chmod(p.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    return str(p)


def stand_in_slicer(support):
    """A stand-in PrusaSlicer script: reads the binary STL it is given and writes G-code comments.

    ``support`` is a Python expression of ``rec["v"]`` ((n, 3, 3) float32 triangle corners) and ``np``:
    the support filament (mm) it reports with ``--support-material`` (none without), on top of 1000 mm:
    in the summary line and as a ``;TYPE:Support material`` extrusion (after a retraction and its undoing).
    """
    return f"""\
import sys
import numpy as np
args = sys.argv[1:]
if "--help" in args:
    print("PrusaSlicer-0.0 stand-in"); sys.exit(0)
stl, out = args[-1], args[args.index("--output") + 1]
raw = open(stl, "rb").read()
n = int(np.frombuffer(raw[80:84], "<u4")[0])
rec = np.frombuffer(raw[84:84 + 50 * n], dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
support = ({support}) if "--support-material" in args else 0.0
body = "M82\\nG92 E0\\n;TYPE:Perimeter\\nG1 X1 Y1 E1000.0\\n"
if support:
    body += f";TYPE:Support material\\nG1 E999.2\\nG1 E1000.0\\nG1 X2 Y2 E{{1000.0 + support!r}}\\n"
open(out, "w").write(body + f"; filament used [mm] = {{1000.0 + support!r}}\\n; filament used [cm3] = 2.5\\n")
"""
