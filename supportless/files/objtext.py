"""A plain OBJ file read in one pass over its bytes: the form a sculpting tool writes its millions of lines in.

:func:`read_plain_obj` classifies the lines and counts their words with numpy, then parses every number at once;
anything it does not know (polygons, relative indices, vertex colours, other statements) it leaves to trimesh's
reader by returning None.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["OBJ_SKIPPED", "read_plain_obj", "rows_of_three"]

#: Lines of an OBJ file :func:`read_plain_obj` passes over (comments, names, groups, materials, smoothing).
OBJ_SKIPPED = (b"#", b"o ", b"g ", b"s ", b"usemtl", b"mtllib", b"vn", b"vt", b"l ")


def read_plain_obj(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """A plain OBJ file's vertices and triangles, read in one pass (a sculpt's 2.7 million lines in seconds,
    where trimesh and the line check took 19 s); None for anything else, which trimesh reads.

    Plain: ``v x y z`` lines of three numbers, ``f`` lines of three positive vertex indices (``i``, ``i/t``,
    ``i/t/n`` or ``i//n``), and lines of :data:`OBJ_SKIPPED` kinds.
    """
    import re
    import warnings

    try:
        text = path.read_bytes().replace(b"\r", b"").replace(b"\t", b" ") + b"\n"
    except OSError:
        return None
    chars = np.frombuffer(text, np.uint8)
    ends = np.flatnonzero(chars == ord("\n"))  # each line's newline
    starts = np.r_[0, ends[:-1] + 1]
    first, second = np.r_[chars, 0][starts], np.r_[chars, 0, 0][starts + 1]
    vertex = (first == ord("v")) & (second == ord(" "))
    face = (first == ord("f")) & (second == ord(" "))
    for i in np.flatnonzero(~(vertex | face)):  # comments, names, groups, materials, blank lines
        line = text[starts[i]:ends[i]]
        if line.strip() and not line.lstrip().startswith(OBJ_SKIPPED):
            return None
    if not vertex.any() or not face.any():
        return None
    vertex_text = rows_of_three(chars, starts[vertex], ends[vertex])
    face_text = rows_of_three(chars, starts[face], ends[face])
    if vertex_text is None or face_text is None:
        return None
    if b"/" in face_text:
        face_text = re.sub(rb"/[^ \n]*", b"", face_text)
    with warnings.catch_warnings():  # a word that is no number: the old numpy warns and stops, the new raises
        warnings.simplefilter("ignore")
        try:
            V = np.fromstring(vertex_text, sep=" ")
            F = np.fromstring(face_text, dtype=np.int64, sep=" ")
        except ValueError:
            return None
    if V.size != 3 * vertex.sum() or F.size != 3 * face.sum():
        return None
    V, F = V.reshape(-1, 3), F.reshape(-1, 3) - 1
    if F.min() < 0 or F.max() >= len(V) or not np.isfinite(V).all():
        return None
    return V, F


def rows_of_three(chars: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> bytes | None:
    """The words of the lines ``chars[start + 2 : end]`` (each after its two-character kind), a line per row, or
    None when a line does not hold exactly three words (separated by spaces).

    Parameters
    ----------
    chars : (c,) uint8
        The file's characters; ``chars[end]`` is each line's newline.
    starts, ends : (r,) int64
    """
    inside = np.zeros(len(chars) + 1, np.int8)
    inside[starts + 2] += 1
    inside[ends + 1] -= 1  # each line's newline kept: it ends the row
    kept = chars[np.cumsum(inside[:-1], dtype=np.int8).astype(bool)]
    blank = (kept == ord(" ")) | (kept == ord("\n"))
    word = ~blank
    word[1:] &= blank[:-1]  # a word starts after a blank
    words, row_ends = np.flatnonzero(word), np.flatnonzero(kept == ord("\n"))
    if len(words) != 3 * len(row_ends):
        return None
    if np.any(words[0::3] < np.r_[0, row_ends[:-1]]) or np.any(words[2::3] > row_ends):
        return None  # row k holds words 3k to 3k + 2, so each row three
    return kept.tobytes()
