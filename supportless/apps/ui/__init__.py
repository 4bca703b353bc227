"""Interactive viewer and editor (a local web page served with viser).

* :mod:`supportless.apps.ui.state`: the editing state (pose, undo/redo, files,
  search settings, measures, background search), usable without a browser; its parts
  :mod:`supportless.apps.ui.editing` (the pose, undo/redo), :mod:`supportless.apps.ui.posefiles`
  (pose files, exported meshes) and :mod:`supportless.apps.ui.searchrun` (the search in the background);
* :mod:`supportless.apps.ui.scene`: the 3D view; :mod:`supportless.apps.ui.panel`: the
  side panel; :mod:`supportless.apps.ui.ports`: which port the server takes;
* :mod:`supportless.apps.ui.opener`: models sent from the page; :mod:`supportless.apps.ui.slicerun`: the
  Slice button's background run; :mod:`supportless.apps.ui.readout`: figures in words and human units;
  :mod:`supportless.apps.ui.filament`: the support filament the panel leads with (the summary's estimate, or the
  slicer's figure after a Slice);
* :mod:`supportless.apps.ui.app`: :class:`App` wires them, :func:`run_app` serves the page; its parts
  :mod:`supportless.apps.ui.actions` (what the page's controls do), :mod:`supportless.apps.ui.jobs` (opening
  a model sent from the page, a Slice, the front) and :mod:`supportless.apps.ui.rendering` (the render thread).
"""

from .app import App, run_app
from .ports import find_free_port

__all__ = ["App", "find_free_port", "run_app"]
