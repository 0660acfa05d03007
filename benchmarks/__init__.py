"""Benchmarks of sb3-aac: the learning benchmark's grid, the per-task learning targets and the speed scripts.

The grid runs training runs (``python -m benchmarks.run --preset quick|full``), one JSON file per finished run, and
turns those files into a report with figures (``python -m benchmarks.report DIR``):

* :mod:`benchmarks.presets`: the grid (envs, algorithms, approximator configs, seeds, budgets, hyperparameters);
* :mod:`benchmarks.domains`: the grid's envs beyond dribbling and how each one is scored;
* :mod:`benchmarks.adapters`: baseline envs and adapters that let a Box/Discrete SB3 model act in the Tuple env;
* :mod:`benchmarks.zoo_hyperparams`: the P-DQN / MP-DQN / HybridPPO settings from ``hyperparams/*.yml`` and the
  training env of an entry;
* :mod:`benchmarks.cells`: the result files: where they live, atomic writing, the per-cell lock, the one loader;
* :mod:`benchmarks.evaluation`: the evaluation summary, the decision cost and the learning-curve callback;
* :mod:`benchmarks.platform_info`: versions, machine and load recorded in every cell;
* :mod:`benchmarks.execution`: one cell, and the resumable parallel grid of them;
* :mod:`benchmarks.cost`: what a preset costs, per stage, in core-hours (``--estimate``; the pool's ordering);
* :mod:`benchmarks.engines`: running the cells on Ray (``--engine ray``);
* :mod:`benchmarks.wall_clock`: the equal wall-clock budget (training stopped after a cell's seconds);
* :mod:`benchmarks.tuning`: the tuning stage (``--tune``): one equal-size Optuna study per headline learner and env;
* :mod:`benchmarks.tuned`: the learners' search spaces and their tuned settings (``hyperparams/tuned``);
* :mod:`benchmarks.reliability`: the reliability test of the best policies;
* :mod:`benchmarks.run`: the runner's command line;
* :mod:`benchmarks.groups`: the runs of a config as a group, and the IQM over seeds with its bootstrap interval;
* :mod:`benchmarks.significance`: the report's verdicts, from tests on the difference (Welch, bootstrap, probability
  of improvement) and one-sided tests against targets;
* :mod:`benchmarks.figures`: the report's figures;
* :mod:`benchmarks.report_text`: the report's tables and sections;
* :mod:`benchmarks.report_budgets`: the report's tuned-against-default, per-budget and wall-clock sections;
* :mod:`benchmarks.report`: ``report.md`` and its figures from a results directory (its command line);
* :mod:`benchmarks.provenance`: the clean-tree check, each cell's provenance, and the invocation log.

Outside the grid:

* :mod:`benchmarks.learning`: SarsaAAC's learning targets per (task, policy) over seeds
  (``python -m benchmarks.learning``);
* :mod:`benchmarks.pdqn_dribble`: P-DQN / MP-DQN dribbling figures at env-step budgets
  (``python -m benchmarks.pdqn_dribble``);
* :mod:`benchmarks.pdqn_platform`: P-DQN / MP-DQN greedy score on Platform-v0 or Goal-v0 against env steps
  (``python -m benchmarks.pdqn_platform``);
* :mod:`benchmarks.reference_init`: the reference MP-DQN code's initial parameter policy on Goal-v0
  (``pdqn_platform --reference-init``, and the grid's MP-DQN on Goal-v0);
* :mod:`benchmarks.domain_baselines`: a random and a scripted policy's figures on every ``hybrid_domains`` env
  (``python -m benchmarks.domain_baselines``);
* :mod:`benchmarks.hppo`: HybridPPO against PPO through the flatten wrapper, per domain over seeds
  (``python -m benchmarks.hppo``);
* :mod:`benchmarks.speed`: the speed scripts (``python -m benchmarks.speed.<name>``; the env's is
  :mod:`robocup_dribble.speed`).

The soak test is a script beside the test suite (``python tests/soak.py``).
"""

import os

# One BLAS/OpenMP thread per process, set when this package is first imported, so before any of its modules imports
# numpy or torch (``python -m benchmarks.X`` imports the package first); spawned workers inherit it, Ray tasks get it
# through :func:`benchmarks.workers.worker_env`. On a busy two-core machine OpenBLAS's own threads made SarsaAAC's
# small matrix products up to 70x slower (256 lanes, RbfPolicy: 15 ms instead of 0.2 ms per forward pass), and with
# two workers on two cores some configs (RbfMlpPolicy with 20 hidden units) up to 7x slower.
SINGLE_THREAD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
for _name, _value in SINGLE_THREAD_ENV.items():
    os.environ.setdefault(_name, _value)
