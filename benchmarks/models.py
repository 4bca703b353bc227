"""The models the benchmarks run on: built-in figures by name, shared models from ../shared/data.

Imported by the benchmark scripts (run as ``python benchmarks/NAME.py``, so this
folder is on the import path).
"""

from __future__ import annotations

import re
from pathlib import Path

import supportless as sl

#: ``../shared/data`` beside the repository.
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"

#: The shared rigged models (OBJ + TGF, up +Y).
SHARED = ("bunny", "bb-bunny")


def available(name: str) -> bool:
    """A built-in figure, or a shared model whose files are present."""
    return name in sl.DEMO_FIGURES or ((DATA / f"{name}.obj").is_file() and (DATA / f"{name}.tgf").is_file())


def load(name: str) -> sl.Rig:
    """The rig of a built-in figure (``tpose``) or of a shared model (``bunny``, up ``y``)."""
    if name in sl.DEMO_FIGURES:
        return sl.load_rig(f"demo:{name}")
    return sl.load_rig(DATA / f"{name}.obj", DATA / f"{name}.tgf", up="y")


def write_section(path: Path, heading: str, text: str) -> None:
    """Put ``text`` as the ``heading`` section ("## ...") of the Markdown file ``path``: it replaces an existing
    one (up to the next "## " heading), else it is appended at the end."""
    path = Path(path)
    old = path.read_text() if path.is_file() else ""
    match = re.search(rf"^{re.escape(heading)}\s*$.*?(?=^## |\Z)", old, flags=re.M | re.S)
    if match:
        new = old[:match.start()] + text + ("\n" if old[match.end():] else "") + old[match.end():]
    else:
        new = old.rstrip("\n") + "\n\n" + text if old else text
    path.write_text(new)
