"""Benchmarks of sb3-aac: speed scripts (``algo_speed.py``, ``env_speed.py``) and the learning benchmark of issue 5.

The learning benchmark runs a grid of training runs (``python -m benchmarks.run --preset quick|full``), one JSON file
per finished run, and turns those files into a report with figures (``python -m benchmarks.report DIR``):

* :mod:`benchmarks.presets`: the grid (envs, algorithms, approximator configs, seeds, budgets, hyperparameters);
* :mod:`benchmarks.adapters`: baseline envs and adapters that let a Box/Discrete SB3 model act in the Tuple env;
* :mod:`benchmarks.run`: the resumable, parallel runner, and the reliability test of the best policies;
* :mod:`benchmarks.report`: statistics over seeds, figures and ``report.md``;
* :mod:`benchmarks.significance`: the report's verdicts, from tests on the difference (Welch, bootstrap, probability
  of improvement) and one-sided tests against targets;
* :mod:`benchmarks.engines`: running the cells on Ray (``--engine ray``);
* :mod:`benchmarks.provenance`: the clean-tree check, each cell's provenance, and the invocation log.
"""
