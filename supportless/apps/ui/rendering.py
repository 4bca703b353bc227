"""Drawing the page: the latest pose in the 3D view, its measures in the panel, in one render thread.

:class:`Rendering` is the part of :class:`~supportless.apps.ui.app.App` that
keeps the page responsive: an edit only asks for a redraw
(:meth:`Rendering._request_render`); one thread draws the latest pose (a burst
of slider events becomes one redraw) — the bone frames first, then the
measures with the full weights, the overlays (risky faces, the support preview,
the weak sections of :class:`~supportless.apps.ui.strength.StrengthOverlay`)
and the panel's figures, and records how long it took (``latency_ms``: ``mesh``,
``full``). Then, unless another edit is already waiting, the exact crossings
(CGAL), the one measure that can take longer than a frame on a large body
(an edit of the spine of a 40 000-triangle character: 130 ms): their faces and
count are drawn when found (``latency_ms["exact"]``), the last pose's shown
meanwhile, so a drag redraws at the energies' pace and the crossings follow
when it pauses.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from ...energies.support import support_columns
from .filament import support_lead
from .panel import measures_markdown
from .readout import broken_rules

__all__ = ["PREVIEW_RESOLUTION", "Rendering"]

logger = logging.getLogger("supportless.apps.ui")

#: Ray cells along the footprint's longer side of the support preview (coarser than the measure's, to draw fast).
PREVIEW_RESOLUTION = 64


class Rendering:
    """The render thread: requests counted, the latest pose drawn and measured, idle waited for.

    A mixin of :class:`~supportless.apps.ui.app.App`, which sets what it draws
    with: ``rig``, ``state``, ``scene``, ``panel``, ``view``, ``strength``,
    ``slice_report``, ``_swap`` (held while drawing), ``_cond``,
    ``_requested``, ``_rendered``, ``_input_time``, ``_stopping``,
    ``_dragging`` and ``_latencies``, and ``locked`` and ``_error``; it sets
    ``measures``, ``shown_vertices`` and ``latency_ms``.
    """

    def _request_render(self) -> None:
        with self._cond:
            if self._rendered >= self._requested:  # latency counts from the oldest input not yet drawn
                self._input_time = time.perf_counter()
            self._requested += 1
            self._cond.notify_all()

    def wait_idle(self, timeout: float = 10.0) -> bool:
        """Wait until the latest change is drawn and measured; True on success."""
        end = time.monotonic() + timeout
        with self._cond:
            target = self._requested
            while self._rendered < target:
                left = end - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def _render_loop(self) -> None:
        while True:
            with self._cond:
                while self._rendered >= self._requested and not self._stopping:
                    self._cond.wait(0.5)
                if self._stopping:
                    return
                version, t_in = self._requested, self._input_time
            try:
                self._render(t_in, version)
            except Exception as exc:  # noqa: BLE001 - keep serving
                if self._stopping:
                    return
                logger.exception("drawing the pose failed")
                self._error(f"drawing the pose failed: {exc}")
            with self._cond:
                self._rendered = max(self._rendered, version)
                self._cond.notify_all()

    def _render(self, t_in: float, version: int) -> None:
        with self._swap:
            if self.state is not None:
                self._draw(t_in, version)

    def _newer_waiting(self, version: int) -> bool:
        """Whether an edit came in after the one being drawn (``version``): its drawing replaces this one's."""
        with self._cond:
            return self._requested > version

    def _draw(self, t_in: float, version: int) -> None:
        state, view, rig = self.state, dict(self.view), self.rig
        (angles, R), selected, fixed, settings = state.get_pose(), state.selected, state.fixed, state.settings
        if view["before"]:  # the rest pose, standing, for a look back
            angles, R, view["frame"] = rig.rest_angles(), np.eye(rig.dim), "standing"
        printed = view["frame"] == "print"
        V = rig.pose(angles) if printed else None  # the plate placement needs the exact surface
        Q, shift = state.frame_transform(view["frame"], V, R)
        locked = self.locked()
        self.scene.draw_pose(angles, selected, fixed, move_gizmo=not self._dragging, placement=(Q, shift),
                             locked=locked)
        t_mesh = time.perf_counter()
        V = rig.pose(angles) if V is None else V
        m = state.measure(angles, rotation=R, exact=False, vertices=V)  # the crossings after the rest, below
        shown = V @ Q.T + shift
        weights = view["weights"]
        risky = m["risky"] if printed else m["risky_standing"]
        crossings = getattr(self, "_crossings", None)  # the last pose's, until this one's are found
        self.scene.draw_overlays(shown, risky if view["show_risky"] and not weights else None,
                                 None if weights else crossings, selected if weights else None)
        if rig.dim == 3:
            self.scene.draw_support(support_columns(shown, rig.faces, rig.up, settings.overhang_angle,
                                                    PREVIEW_RESOLUTION) if view["show_support"] else None)
        m["support_lead"] = lead = support_lead(state, angles, R, V, self.slice_report)
        t_done = time.perf_counter()
        self.measures, self.shown_vertices = m, shown
        mesh_ms, full_ms = 1e3 * (t_mesh - t_in), 1e3 * (t_done - t_in)
        self._latencies = (self._latencies + [mesh_ms])[-50:]
        self.latency_ms = {"mesh": mesh_ms, "full": full_ms, "median_mesh": float(np.median(self._latencies))}
        rules = broken_rules(state.objective, angles) if m["terms"]["violation"] > 0 else []
        head = "**Showing the rest pose (before)**\n\n" if view["before"] else ""
        strength = self.strength.show(self.scene, state, angles, R, shown, view["show_strength"] and not weights)

        def panel():
            text = measures_markdown(m, settings, self.latency_ms, rig.dim, state.print_frame.scale, rules, lead)
            self.panel.show_measures(head + text + strength)

        panel()
        if rig.dim == 3 and not self._newer_waiting(version):  # the exact crossings (CGAL) once the edits pause
            m |= state.exact_measures(V)
            self._crossings = m["intersecting_faces"]
            if not weights:
                self.scene.draw_crossings(shown, self._crossings)
            self.latency_ms["exact"] = 1e3 * (time.perf_counter() - t_in)
            panel()
        self.panel.show_bone(selected, fixed, locked)
