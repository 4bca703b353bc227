"""The app's long jobs: a model sent from the page prepared, a Slice, the front of least support.

:class:`BackgroundJobs` is the part of :class:`~supportless.apps.ui.app.App`
that starts them, each in a thread or process of its own
(:func:`~supportless.apps.ui.opener.prepare_model`,
:class:`~supportless.apps.ui.slicerun.SliceRun`,
:class:`~supportless.apps.ui.front.FrontBrowser`), and says in the page how they
went; the search is the state's (:class:`~supportless.apps.ui.searchrun.BackgroundSearch`).
"""

from __future__ import annotations

import logging
import threading

from ...base.errors import SupportlessError
from .filament import slice_meshes
from .opener import prepare_model
from .slicerun import slice_markdown

__all__ = ["BackgroundJobs"]

logger = logging.getLogger("supportless.apps.ui")


class BackgroundJobs:
    """Opening an uploaded model, slicing the rest pose and the pose, finding the front.

    A mixin of :class:`~supportless.apps.ui.app.App`, which sets what they
    use: ``state``, ``panel``, ``uploads``, ``open_options``, ``slicing`` (a
    :class:`~supportless.apps.ui.slicerun.SliceRun` reporting to
    :meth:`_slice_done`), ``front``, ``slice_report`` and ``_opening``, and
    ``open_rig``, ``_set_status``, ``_error`` and ``_request_render``.
    """

    def receive_upload(self, name: str, content: bytes) -> bool:
        """A file sent from the page: a skeleton is kept for its mesh; a model is prepared, then shown.

        Returns
        -------
        accepted : bool
            False (with one line in the page) for a bad file, or while another model is being prepared.
        """
        if self._opening is not None and self._opening.is_alive():
            self._error(f"{name}: another model is being prepared; send it again when it is open")
            return False
        try:
            model = self.uploads.receive(name, content)
        except SupportlessError as exc:
            self._error(str(exc))
            return False
        if model is None:
            self._set_status(f"skeleton {name} received; now send its mesh")
            return True
        skeleton = self.uploads.skeleton_for(model)
        self._opening = threading.Thread(target=self._prepare, args=(model, skeleton), name="supportless-ui-open",
                                         daemon=True)
        self._opening.start()
        return True

    def _prepare(self, model, skeleton) -> None:
        with_what = f" with {skeleton.name}" if skeleton is not None else ""
        self._set_status(f"opening {model.name}{with_what} ...")
        try:
            rig, frame = prepare_model(model, skeleton, self.open_options,
                                       progress=lambda step: self._set_status(f"opening {model.name}: {step} ..."))
            self.open_rig(rig, frame)
        except (SupportlessError, OSError, ValueError) as exc:  # said with the file's own name, not where it was kept
            self._error(f"cannot open {model.name}: {str(exc).replace(str(model) + ': ', '')}")
            return
        except Exception as exc:  # noqa: BLE001 - the app keeps serving whatever the file does
            logger.exception("opening %s failed", model.name)
            self._error(f"cannot open {model.name}: {type(exc).__name__}: {exc}")
            return
        notes = [w for w in rig.info.get("warnings", []) if "skeleton" in w and "built" in w]
        self._set_status(f"opened {rig.name}: {rig.bone_count} bones, {len(rig.faces)} triangles; "
                         f"{frame.note()}" + (f"; {notes[0]}" if notes else ""))

    def start_slice(self, slicer: tuple[str, str] = ("prusa", "grid")) -> bool:
        """Slice the rest pose and the current pose (as printed) with a real slicer, in the background.

        Parameters
        ----------
        slicer : tuple of str
            ``(engine, support)``: ``("prusa", "grid")``, ``("cura", "grid")`` or ``("cura", "tree")``.

        Returns
        -------
        started : bool
            False (and one line in the page) when the slicer is missing or a slice already runs.
        """
        from ...slicing.choice import SlicerChoice
        from ..cli_common import _slicer_missing

        try:
            choice = SlicerChoice(*slicer)
        except SupportlessError as exc:
            self._error(f"cannot slice: {exc}")
            return False
        missing = _slicer_missing(choice)
        if missing:
            self._error(f"cannot slice: {missing}")
            return False
        if not self.slicing.start(choice=choice, **slice_meshes(self.state)):
            self._set_status("a slice is already running")
            return False
        self.panel.show_slicing(True, f"slicing with {choice.label}: the rest pose and this pose, with and without "
                                      "support (four runs) ...")
        self._set_status(f"slicing with {choice.label} ...")
        return True

    def cancel_slice(self) -> None:
        """Stop the running slice (its slicer processes too)."""
        if self.slicing.cancel():
            self.panel.show_slicing(False, "slicing cancelled")
            self._set_status("slicing cancelled")

    def _slice_done(self, report: dict | None, error: str | None) -> None:
        if error is not None:
            self.panel.show_slicing(False, f"⚠ slicing failed: {error}")
            self._error(f"slicing failed: {error}")
            return
        self.slice_report = report
        self._request_render()  # the panel leads with the slicer's figure while the pose is the one sliced
        self.panel.show_slicing(False, slice_markdown(report))
        self._set_status("sliced: the slicer's figures are in the Slice folder")

    def start_front(self, count: int = 5) -> bool:
        """Find the front of least support against least distortion in the background (the Front folder)."""
        try:
            started = self.front.start(count)
        except (SupportlessError, ValueError) as exc:
            self._error(f"cannot find the front: {exc}")
            return False
        if started:
            self.panel.find_front.disabled = True
            self._set_status(f"finding a front of up to {count} poses (about three searches) ...")
        return started

    def show_front_pose(self, index: int) -> None:
        """Show pose ``index`` (0-based) of the front."""
        try:
            m = self.front.show(index)
        except ValueError as exc:
            self._error(str(exc))
            return
        self._set_status(f"front pose {index + 1}: support {m['support']:.4g}, distortion {m['distortion']:.3g}")
