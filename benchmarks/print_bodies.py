"""The shared glTF characters' print bodies: the winding number counted along the grid's columns against libigl's.

For each of the 13 shared characters (``gltf/`` and ``gltf/quaternius/``), the print body is made twice from the
same skin: as the tool makes it (a closed surface's winding number counted along the grid's columns,
:func:`supportless.files.gridsurface.winding_by_columns`), and with libigl's fast winding number at every grid
point (the grid surface told the surface is not closed). Prints a Markdown table: the seconds each way, the
triangles, and whether the two bodies are the same arrays to the last bit.

    python benchmarks/print_bodies.py
"""

from __future__ import annotations

import time
from unittest import mock

import numpy as np
from models import DATA

from supportless.files import gridsurface
from supportless.files.gltf import read_gltf_skin
from supportless.files.printbody import print_body


def body(skin, columns: bool):
    """(seconds, print body), the winding number by columns or libigl's everywhere."""
    t0 = time.perf_counter()
    if columns:
        made = print_body(skin.vertices, skin.faces, skin.part, skin.weights, skin.part_names)
    else:
        with mock.patch.object(gridsurface, "_is_closed", lambda F: False):
            made = print_body(skin.vertices, skin.faces, skin.part, skin.weights, skin.part_names)
    return time.perf_counter() - t0, made


def main():
    folder = DATA / "gltf"
    paths = sorted([*folder.glob("*.glb"), *folder.glob("quaternius/*.glb")])
    print("| character | remade from its winding number | libigl's everywhere, s | counted along columns, s "
          "| triangles | the same body |")
    print("|---|---|---:|---:|---:|---|")
    for path in paths:
        skin = read_gltf_skin(path)
        slow, libigl = body(skin, columns=False)
        fast, counted = body(skin, columns=True)
        same = all(a.shape == b.shape and np.array_equal(a, b) for a, b in
                   ((libigl.vertices, counted.vertices), (libigl.faces, counted.faces)))
        remade = "yes" if any("winding number" in line for line in counted.log) else "no"
        print(f"| {path.relative_to(folder).with_suffix('')} | {remade} | {slow:.2f} | {fast:.2f} "
              f"| {len(counted.faces)} | {'yes' if same else 'NO'} |", flush=True)


if __name__ == "__main__":
    main()
