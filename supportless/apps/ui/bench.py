"""Measure the viewer's input-to-update latency on a model.

    python -m supportless.apps.ui.bench MODEL [--skeleton S.tgf] [--up auto] [--edits 40] [--bone NAME ...]
        [--browser /usr/bin/chromium]

Server side: from an edit reaching the app (what a slider callback does) to
(1) the new bone frames being flushed to the browser (``mesh``), (2) the
energies, support estimates and overlays being recomputed and sent (``full``)
and (3) the exact crossings found and drawn after them (``exact``).
With ``--browser``, also end to end in headless Chromium: from a key press on
a slider to the redrawn energies appearing in the page.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

__all__ = ["browser_latency", "main", "server_latency"]


def server_latency(app, edits: int = 40, bone: int | None = None) -> dict:
    """Median and max latencies (ms) of ``edits`` single-angle edits, one at a time: ``mesh`` (the bones
    redrawn), ``full`` (the energies, the support preview and the overlays) and ``exact`` (the exact crossings
    found and drawn after them; nan in 2D)."""
    bone = app.rig.bone_count - 1 if bone is None else bone
    app.wait_idle(60)
    times = {"mesh": [], "full": [], "exact": []}
    for k in range(edits):
        app.state.set_bone_angles(bone, [0.0, 0.0, (k % 2) * 20.0 + k * 0.5], key=None)
        app.wait_idle(30)
        for key, seen in times.items():
            seen.append(app.latency_ms.get(key, np.nan))
    return {f"{key}_{stat}": float(fn(seen)) for key, seen in times.items()
            for stat, fn in (("median", np.median), ("max", np.max))}


def browser_latency(app, chromium: str, presses: int = 20) -> dict:
    """Key press on the Z slider -> redrawn energies in the page, ms (median, max)."""
    from playwright.sync_api import sync_playwright

    times = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=[
            "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
            "--disable-background-networking"])
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(app.url)
        page.get_by_text("Objective:").wait_for(timeout=60000)
        slider = page.get_by_role("slider").nth(2)
        slider.focus()
        # the energies list changes on every redraw (it shows the update time)
        get = "() => (document.body.innerText.match(/Objective:[^]*Update time:[^\\n]*/) || [])[0]"
        for _ in range(presses):
            before = page.evaluate(get)
            t0 = time.perf_counter()
            slider.press("ArrowRight")
            page.wait_for_function(f"b => ({get})() !== b", arg=before, timeout=20000, polling=10)
            times.append(1e3 * (time.perf_counter() - t0))
            page.wait_for_timeout(50)
        browser.close()
    return {"page_median": float(np.median(times)), "page_max": float(np.max(times))}


def _bone_named(names: list, end: str) -> int:
    """The index of the first bone whose name ends with ``end``; SystemExit with the names when none does."""
    for i, name in enumerate(names):
        if name and name.endswith(end):
            return i
    raise SystemExit(f"no bone's name ends with {end!r}; the bones: {', '.join(n for n in names if n)}")


def main(argv=None) -> None:
    from ...rig.load import load_rig
    from .app import App

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model")
    ap.add_argument("--skeleton")
    ap.add_argument("--up", default="auto")
    ap.add_argument("--edits", type=int, default=40)
    ap.add_argument("--bone", action="append", default=None,
                    help="a bone to edit, by the end of its name (repeat for several; default: the last bone)")
    ap.add_argument("--browser", help="path of a Chromium to also measure in the page")
    args = ap.parse_args(argv)
    rig = load_rig(args.model, skeleton=args.skeleton, up=args.up)
    app = App(rig, verbose=False)
    try:
        print(f"{rig!r}")
        names = rig.bone_names() or []
        bones = [None] if not args.bone else [_bone_named(names, b) for b in args.bone]
        for bone in bones:
            res = server_latency(app, args.edits, bone)
            label = "" if bone is None else f"{names[bone]}: "
            print(label + "server: mesh (bone frames sent) median {mesh_median:.1f} ms, max {mesh_max:.1f} ms; "
                  "with energies/overlays median {full_median:.1f} ms, max {full_max:.1f} ms; "
                  "exact crossings drawn median {exact_median:.1f} ms, max {exact_max:.1f} ms".format(**res))
        if args.browser:
            res = browser_latency(app, args.browser)
            print("page: key press -> energies redrawn median {page_median:.1f} ms, "
                  "max {page_max:.1f} ms".format(**res))
    finally:
        app.stop()


if __name__ == "__main__":
    main()
