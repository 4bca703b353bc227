"""Steps announced to listeners: the command line's progress lines and the benchmarks' stage times."""

import pytest

from supportless.base.progress import listening, step


def test_listeners_hear_each_step_start_and_end_nested_and_after_an_error():
    heard = []
    with listening(lambda event, name, seconds: heard.append((event, name, seconds is None))):
        with step("outer"):
            with step("inner"):
                pass
        with pytest.raises(ValueError), step("failing"):
            raise ValueError
    with step("unheard"):
        pass
    assert heard == [("start", "outer", True), ("start", "inner", True), ("done", "inner", False),
                     ("done", "outer", False), ("start", "failing", True), ("done", "failing", False)]


def test_a_search_of_a_dense_rig_announces_its_full_resolution_stages(tmp_path, monkeypatch, shared_file):
    """Each long full-resolution stage of optimize on a rig with a proxy is a step (the bunny, 6966 triangles,
    the proxy threshold lowered to it)."""
    import supportless as sl
    from supportless.files.meshes import read_mesh, read_tgf
    from supportless.rig import rig as rig_mod

    V, F = read_mesh(shared_file("bunny.obj"))  # skipped without the shared models, failed under CI
    J, B = read_tgf(shared_file("bunny.tgf"))
    monkeypatch.setattr(rig_mod, "PROXY_FACES", 5000)
    monkeypatch.setattr(rig_mod, "PROXY_TARGET", 2000)
    heard = []
    with listening(lambda event, name, seconds: heard.append(name) if event == "start" else None):
        rig = sl.prepare_rig(V, F, J, B, up="y")
        assert rig.coarse_faces is not None
        sl.optimize(rig, particles=6, iterations=2, seed=0, polish=2)
    for name in ("checking the surface and the joints", f"proxy: {len(F)} triangles simplified to 2000",
                 "proxy: volume mesh and weights", "weights onto the full surface", "searching on the proxy",
                 f"measuring the best poses on {len(F)} triangles", f"polishing on {len(F)} triangles",
                 "weighing the answers", "exact self-intersection check as written"):
        assert name in heard
