"""The ``supportless`` command line: thin commands over the Python API.

Every user error (bad file, bad option) prints one line on stderr and exits
with status 2; nothing half-written is left on disk.

This module is the command group and the executable (:func:`run`); each
command lives in a module of its own:

* :mod:`.cli_rig`: ``prepare`` and ``apply`` (a rig made ready, a saved pose put on it);
* :mod:`.cli_optimize`: ``optimize``, the search and its files (:mod:`.cli_summary`: what it prints);
* :mod:`.cli_slice`: ``slice-check``; :mod:`.cli_demo`: ``demo``; :mod:`.cli_view`: ``view``;
  :mod:`.cli_bench`: ``bench``; :mod:`.cli_batch`: ``batch``;
* :mod:`.cli_common`: the options, errors and loading they share.
"""

from __future__ import annotations

import sys

import click

from .cli_batch import batch
from .cli_bench import bench
from .cli_common import _Group
from .cli_demo import demo
from .cli_optimize import optimize
from .cli_rig import apply, prepare
from .cli_slice import slice_check_cmd
from .cli_summary import _standing_word  # noqa: F401  (imported from here by tests and scripts)
from .cli_view import view

__all__ = ["main", "run"]


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="supportless")
def main():
    """Re-pose a rigged model so it 3D-prints with less support material."""


for _command in (prepare, optimize, apply, slice_check_cmd, demo, view, bench, batch):
    main.add_command(_command)


def run() -> None:
    """The ``supportless`` executable: :func:`main` under :func:`supportless.base.crash.supervised` (a crash is one line)."""
    from ..base.crash import supervised

    sys.exit(supervised(main))


if __name__ == "__main__":  # pragma: no cover
    run()
