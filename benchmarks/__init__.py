"""Benchmarks of sb3-aac: speed scripts (``algo_speed.py``, ``runtime_speed.py``; the env's is
:mod:`robocup_dribble.speed`) and the learning benchmark.

The learning benchmark runs a grid of training runs (``python -m benchmarks.run --preset quick|full``), one JSON file
per finished run, and turns those files into a report with figures (``python -m benchmarks.report DIR``):

* :mod:`benchmarks.presets`: the grid (envs, algorithms, approximator configs, seeds, budgets, hyperparameters);
* :mod:`benchmarks.adapters`: baseline envs and adapters that let a Box/Discrete SB3 model act in the Tuple env;
* :mod:`benchmarks.cells`: the result files: where they live, atomic writing, the per-cell lock, the one loader;
* :mod:`benchmarks.evaluation`: the evaluation summary, the decision cost and the learning-curve callback;
* :mod:`benchmarks.platform_info`: versions, machine and load recorded in every cell;
* :mod:`benchmarks.execution`: one cell, and the resumable parallel grid of them;
* :mod:`benchmarks.engines`: running the cells on Ray (``--engine ray``);
* :mod:`benchmarks.reliability`: the reliability test of the best policies;
* :mod:`benchmarks.run`: the runner's command line;
* :mod:`benchmarks.groups`: the runs of a config as a group, and the IQM over seeds with its bootstrap interval;
* :mod:`benchmarks.significance`: the report's verdicts, from tests on the difference (Welch, bootstrap, probability
  of improvement) and one-sided tests against targets;
* :mod:`benchmarks.figures`: the report's figures;
* :mod:`benchmarks.report_text`: the report's tables and sections;
* :mod:`benchmarks.report`: ``report.md`` and its figures from a results directory (its command line);
* :mod:`benchmarks.provenance`: the clean-tree check, each cell's provenance, and the invocation log.
"""
