"""Benchmarks of sb3-aac: one application, the learning benchmark's grid and its studies, with the tools on top of the
same pieces. Its entry points (run with ``PYTHONPATH=.:envs python -m benchmarks.NAME``):

* :mod:`benchmarks.run`: the grid (``--preset quick|full``) and the studies of one algorithm family (``--preset
  pdqn|hppo``), one JSON file per finished cell, resumable; ``--tune`` its tuning stage, ``--estimate`` its cost;
  ``--shard I/N`` one machine's share;
* :mod:`benchmarks.merge`: the results directories of several machines' shards as one, with one provenance log;
* :mod:`benchmarks.report`: ``report.md`` and its figures from a results directory;
* :mod:`benchmarks.learning`: the ad-hoc tool: SarsaAAC's learning targets per (task, policy) over seeds, and
  (``efficiency``) the sample-efficiency comparison with TD3 on the domains with interacting inputs;
* :mod:`benchmarks.suite`: SarsaAAC's default settings tuned and compared across a suite of tasks;
* :mod:`benchmarks.speed.training` and :mod:`benchmarks.speed.decisions`: training env steps/s and microseconds per
  decision, each next to a peer in the same run.

The pieces:

* :mod:`benchmarks.presets`: the grid and the studies (envs, algorithms, approximator configs, seeds, budgets);
* :mod:`benchmarks.domains`: the one table from an env id to its training env, evaluation episodes and metric;
* :mod:`benchmarks.models`: the one model builder (a cell's model; the P-DQN / MP-DQN / HybridPPO settings of
  ``hyperparams/*.yml``; the reference MP-DQN code's start on Goal-v0);
* :mod:`benchmarks.adapters`: baseline envs and adapters that let a Box/Discrete SB3 model act in the Tuple env;
* :mod:`benchmarks.zoo_hyperparams`: the ``hyperparams/*.yml`` entries and the training env of an entry;
* :mod:`benchmarks.evaluation`: the decision cost, the learning-curve callback and the equal wall-clock budget;
* :mod:`benchmarks.cells`: the result files: where they live, atomic writing, the per-cell lock, the one loader;
* :mod:`benchmarks.execution`: one cell, and the resumable grid of them;
* :mod:`benchmarks.workers`: the worker pool (processes that end with their driver, one BLAS thread each);
* :mod:`benchmarks.engines`: running the cells on Ray (``--engine ray``), each engine handed its cell runner;
* :mod:`benchmarks.process_reaper`: the watchdog that ends what a Ray instance leaves behind;
* :mod:`benchmarks.cost`: what a preset costs, per stage, in core-hours, and in wall time on N cores (``--estimate``;
  the pool's ordering, longest first);
* :mod:`benchmarks.shards`: a grid split between machines (``--shard I/N``), longest first as the pool;
* :mod:`benchmarks.tuning` and :mod:`benchmarks.tuned`: the tuning stage and the tuned settings;
* :mod:`benchmarks.reliability`: the reliability test of the best policies;
* :mod:`benchmarks.groups` and :mod:`benchmarks.significance`: runs as groups, the one IQM with its bootstrap interval,
  and the report's verdicts;
* :mod:`benchmarks.figures`, :mod:`benchmarks.report_text`, :mod:`benchmarks.report_budgets`: the report's figures,
  tables and sections;
* :mod:`benchmarks.provenance`: the clean-tree check, each cell's provenance (versions, machine, load), the invocation
  log (each invocation's host) and its merge records.

The hybrid domains' random and scripted figures are the envs' own (``python -m hybrid_domains.baselines``); the soak
test is a script beside the test suite (``python tests/soak.py``).
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
