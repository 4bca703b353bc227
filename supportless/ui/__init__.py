"""Interactive viewer and editor (a local web page served with viser).

See :mod:`supportless.ui.app`: :func:`run_app`, :class:`App`, :func:`find_free_port`.
"""

from .app import App, find_free_port, run_app

__all__ = ["App", "find_free_port", "run_app"]
