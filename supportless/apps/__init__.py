"""The commands and the browser app, thin over the stages before.

* :mod:`.cli`: the ``supportless`` command (:mod:`.cli_common`: the options commands share;
  :mod:`.cli_batch`: the batch command);
* :mod:`.batch`: a folder of models on Dask; :mod:`.pareto`: the front of least support
  against least distortion;
* :mod:`.bench`, :mod:`.bench_targets`: timing of the stages and the speed targets;
* :mod:`.ui`: the browser app (:mod:`.ui.guard`: who may connect).
"""
