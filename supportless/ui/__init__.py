"""Interactive viewer and editor (a local web page served with viser).

* :mod:`supportless.ui.state`: the editing state (pose, undo/redo, files,
  search settings, measures, background search), usable without a browser;
* :mod:`supportless.ui.scene`: the 3D view; :mod:`supportless.ui.panel`: the
  side panel; :mod:`supportless.ui.ports`: which port the server takes;
* :mod:`supportless.ui.app`: :class:`App` wires them, :func:`run_app` serves the page.
"""

from .app import App, run_app
from .ports import find_free_port

__all__ = ["App", "find_free_port", "run_app"]
