"""
Hyperparameter tuning with Optuna (``pip install sb3-aac[tune]``): the search spaces, the study (TPE sampler, median
pruner on periodic greedy evaluations, resumable storage), the multi-task study over a suite of tasks, the report of
the best settings, and rl-zoo3's sampler.
The command line is ``sb3-aac tune`` (:mod:`sb3_aac.cli.tune`).
"""

from sb3_aac.tune.evaluation import TrialEvaluation, greedy_score
from sb3_aac.tune.report import train_command, zoo_entry
from sb3_aac.tune.search_spaces import ALGORITHMS, SEARCH_SPACES, SearchSpace, search_space
from sb3_aac.tune.storage import open_storage
from sb3_aac.tune.study import StudyOutcome, TuneSettings, finished_trials, load_study, run_study, run_trials
from sb3_aac.tune.suite import SuiteSettings, SuiteTask, normalised_score, suite_objective

__all__ = [
    "ALGORITHMS",
    "SEARCH_SPACES",
    "SearchSpace",
    "StudyOutcome",
    "SuiteSettings",
    "SuiteTask",
    "TrialEvaluation",
    "TuneSettings",
    "finished_trials",
    "greedy_score",
    "load_study",
    "normalised_score",
    "open_storage",
    "run_study",
    "run_trials",
    "search_space",
    "suite_objective",
    "train_command",
    "zoo_entry",
]
