"""``supportless bench``: the stages timed (:mod:`supportless.apps.bench`), or the speed targets of big rigs
(:mod:`supportless.apps.bench_targets`)."""

from __future__ import annotations

import sys

import click

from ..search.settings import RANGES, SearchSettings
from .cli_common import UP_HELP

__all__ = ["bench"]


@click.command()
@click.argument("model", required=False, type=click.Path(dir_okay=False))
@click.option("--skeleton", "-s", type=click.Path(dir_okay=False), default=None)
@click.option("--up", default="auto", show_default=True, help=UP_HELP)
@click.option("--particles", default=SearchSettings.particles, show_default=True,
              type=click.IntRange(*RANGES["particles"]))
@click.option("--iterations", default=SearchSettings.iterations, show_default=True,
              type=click.IntRange(1, RANGES["iterations"][1]))
@click.option("--backend", type=click.Choice(["fast", "numpy", "both"]), default="both", show_default=True)
@click.option("--targets", is_flag=True,
              help="Instead: the speed targets of big rigs (bunny, bb-bunny, a 68-bone character, the glTF robot, "
                   "a 111k-triangle bunny), each prepared and searched in its own process.")
@click.option("--reference", is_flag=True, help="With --targets: also search the full surface of the cases "
                                                "that have a simplified proxy (slow).")
def bench(model, skeleton, up, particles, iterations, backend, targets, reference):
    """Time preparation, one pose, one swarm iteration and a whole search."""
    if targets:
        from .bench_targets import run_targets

        rows = run_targets(reference=reference, echo=click.echo)
        sys.exit(1 if any("error" in r and not r.get("missing") for r in rows) else 0)
    from .bench import run_bench

    run_bench(model, skeleton, up, particles=particles, iterations=iterations, backend=backend,
              echo=click.echo)
