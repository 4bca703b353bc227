"""The commands and the browser app, thin over the stages before.

* :mod:`.cli`: the ``supportless`` command group, each command in a module of its own
  (:mod:`.cli_rig`: prepare and apply; :mod:`.cli_optimize`: optimize, :mod:`.cli_summary`: what it
  prints; :mod:`.cli_slice`, :mod:`.cli_demo`, :mod:`.cli_view`, :mod:`.cli_bench`, :mod:`.cli_batch`);
  :mod:`.cli_common`: the options, errors and loading the commands share;
* :mod:`.batch`: a folder of models on Dask; :mod:`.pareto`: the front of least support
  against least distortion;
* :mod:`.bench`, :mod:`.bench_targets`: timing of the stages and the speed targets;
* :mod:`.ui`: the browser app (:mod:`.ui.guard`: who may connect).
"""
