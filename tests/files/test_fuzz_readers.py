"""The readers under random and mutated input (issue 18): a result that holds, or one line of InputError.

Every reader either returns arrays that keep their promises (finite, indices in range, a skeleton that
is a tree) or raises :class:`~supportless.base.errors.InputError` with a one-line message naming the file;
never another exception, and never a hang: a read still running after :data:`HANG_SECONDS` (thousands of
times what any example takes, so no load trips it) fails its example. Hypothesis's own per-example
deadline is off: a busy machine made it fail examples that were merely slow.
"""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import supportless as sl
from supportless.base.errors import InputError
from supportless.files.skeleton import check_skeleton

FUZZ = settings(max_examples=int(os.environ.get("SUPPORTLESS_FUZZ_EXAMPLES", "150")), deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], derandomize=True)

VALID_TGF = "1 0 0 0\n2 0 1 0\n3 0 2 0\n4 1 2 0\n#\n1 2\n2 3\n2 4\n#\n"
VALID_OBJ = ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
             "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n")


#: A read of one fuzzed file still running after this is a hang.
HANG_SECONDS = 120


def _hang(_signum, _frame):
    raise AssertionError(f"a reader still runs after {HANG_SECONDS} s: it hangs")


def _one_line_error(path: Path, read):
    """Call ``read(path)``; an error must be one line of InputError naming the file."""
    previous = signal.signal(signal.SIGALRM, _hang)
    signal.alarm(HANG_SECONDS)
    try:
        return read(path)
    except InputError as exc:
        message = str(exc)
        assert "\n" not in message and message.startswith(f"{path}: "), message
        return None
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _mutations(text: str):
    """Line-level mutations of a valid file: drop, repeat, swap lines, replace a token."""
    lines = text.splitlines()
    tokens = st.sampled_from(["", "-1", "0", "99", "1e309", "nan", "inf", "#", "x", "1.5", "\ufeff", "1 2 3 4 5",
                              "-0", "2147483648", "\t", "//", "f", "v"])
    op = st.tuples(st.sampled_from(["drop", "repeat", "swap", "token"]), st.integers(0, len(lines) - 1),
                   st.integers(0, len(lines) - 1), tokens, st.integers(0, 5))

    def apply(ops):
        out = list(lines)
        for kind, i, j, token, k in ops:
            if not out:
                break
            i, j = i % len(out), j % len(out)
            if kind == "drop":
                del out[i]
            elif kind == "repeat":
                out.insert(i, out[i])
            elif kind == "swap":
                out[i], out[j] = out[j], out[i]
            else:
                words = out[i].split() or [""]
                words[k % len(words)] = token
                out[i] = " ".join(words)
        return "\n".join(out) + "\n"

    return st.lists(op, min_size=1, max_size=6).map(apply)


random_text = st.lists(st.sampled_from(list("0123456789 .-e#\nnaf/v\t") + ["\ufeff", "nan", "inf", "\n#\n"]),
                       max_size=120).map("".join)


def _holds(points, indices, width):
    """``points`` (n, 3) finite and ``indices`` (k >= 1, width) into them."""
    assert points.ndim == 2 and points.shape[1] == 3 and np.isfinite(points).all()
    assert indices.ndim == 2 and indices.shape[1] == width and len(indices)
    assert indices.min() >= 0 and indices.max() < len(points)


def _read_text(folder, name, text, read):
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return _one_line_error(path, read)


@FUZZ
@given(text=st.one_of(_mutations(VALID_TGF), random_text))
def test_tgf_reader(tmp_path, text):
    out = _read_text(tmp_path, "s.tgf", text, sl.read_tgf)
    if out is not None:
        _holds(*out, 2)
        check_skeleton(*out)  # a tree with lengths: no error


@FUZZ
@given(text=st.one_of(_mutations(VALID_OBJ), random_text))
def test_obj_reader(tmp_path, text):
    out = _read_text(tmp_path, "m.obj", text, sl.read_mesh)
    if out is not None:
        _holds(*out, 3)


def _binary_stl() -> bytes:
    import trimesh

    return trimesh.creation.box((1, 2, 3)).export(file_type="stl")


@FUZZ
@given(cut=st.integers(0, 700), flips=st.lists(st.tuples(st.integers(0, 700), st.integers(0, 255)), max_size=8))
def test_binary_stl_reader(tmp_path, cut, flips):
    data = bytearray(_binary_stl())
    for i, byte in flips:
        if i < len(data):
            data[i] = byte
    path = tmp_path / "m.stl"
    path.write_bytes(bytes(data[: len(data) - cut]))
    out = _one_line_error(path, sl.read_mesh)
    if out is not None:
        _holds(*out, 3)


json_values = st.recursive(st.none() | st.booleans() | st.floats(allow_nan=True) | st.integers() | st.text(max_size=5),
                           lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner,
                                                                                       max_size=4), max_leaves=20)


@FUZZ
@given(data=st.one_of(json_values,
                      st.fixed_dictionaries({"angles": json_values, "bones": json_values}),
                      st.fixed_dictionaries({"angles": st.lists(st.lists(st.floats(allow_nan=True), min_size=3,
                                                                         max_size=3), min_size=3, max_size=3),
                                             "bones": st.sampled_from([[[0, 1], [1, 2], [1, 3]], [[0, 1]], "x"])})))
def test_pose_reader(tmp_path, data):
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data))
    bones = np.array([[0, 1], [1, 2], [1, 3]])
    out = _one_line_error(path, lambda p: sl.read_pose(p, bones))
    if out is not None:
        assert out.shape == (3, 3) and np.isfinite(out).all()


@pytest.fixture(scope="module")
def fox_bytes(shared_data):
    return (shared_data / "gltf" / "Fox.glb").read_bytes()


@FUZZ
@given(cut=st.integers(0, 4000), flips=st.lists(st.tuples(st.integers(0, 3000), st.integers(0, 255)), max_size=6))
def test_glb_reader(tmp_path, fox_bytes, cut, flips):
    """A real character's GLB, truncated and with bytes changed in its header and JSON."""
    from supportless.files.gltf import read_gltf_skin

    data = bytearray(fox_bytes)
    for i, byte in flips:
        data[i] = byte
    path = tmp_path / "c.glb"
    path.write_bytes(bytes(data[: len(data) - cut]))
    out = _one_line_error(path, read_gltf_skin)
    if out is not None:
        _holds(out.vertices, out.faces, 3)
