"""
sb3-aac's algorithms in rl-zoo3 (the RL Baselines3 Zoo, ``pip install rl_zoo3``): :func:`register` makes them known,
:func:`main` runs an rl-zoo3 flow (train, enjoy, record_video, push_to_hub) with them.

rl-zoo3 builds ``--algo``'s choices from ``rl_zoo3.ALGOS`` when it parses a command line and looks ``--optimize``'s
sampler up in ``rl_zoo3.hyperparams_opt.HYPERPARAMS_SAMPLER`` (and its converter in ``HYPERPARAMS_CONVERTER``), so an
external algorithm is registered before the flow runs. The algorithms are those of
:data:`sb3_aac.tune.search_spaces.ALGORITHMS`, each with the sampler of its search spaces (:mod:`sb3_aac.tune.zoo`):
an algorithm added there is in rl-zoo3 too. This module imports no env package: the caller imports those whose envs
it runs (``examples/rl_zoo3_train.py`` imports ``robocup_dribble``).
"""

from __future__ import annotations

import runpy
import sys
from collections.abc import Sequence
from functools import partial

from sb3_aac.common.envs import register_toy_env
from sb3_aac.tune.search_spaces import ALGORITHMS
from sb3_aac.tune.zoo import convert_params, sample_params

TRAIN = "rl_zoo3.train"
# The first argument of main that selects a flow other than train, and the rl-zoo3 module that runs it.
FLOWS = {"--enjoy": "rl_zoo3.enjoy", "--record-video": "rl_zoo3.record_video", "--push-to-hub": "rl_zoo3.push_to_hub"}


def register() -> None:
    """
    Add every algorithm of :data:`~sb3_aac.tune.search_spaces.ALGORITHMS` to rl-zoo3's tables under its name (the
    class, the ``--optimize`` sampler and converter) and register the toy env ``sb3_aac/ParameterizedTarget-v0``.
    An ``ImportError`` if rl-zoo3 is not installed.
    """
    from rl_zoo3 import ALGOS  # every flow module imports this one dict
    from rl_zoo3.hyperparams_opt import HYPERPARAMS_CONVERTER, HYPERPARAMS_SAMPLER

    register_toy_env()
    for name, algorithm in ALGORITHMS.items():
        ALGOS[name] = algorithm
        HYPERPARAMS_SAMPLER[name] = partial(sample_params, name)
        HYPERPARAMS_CONVERTER[name] = partial(convert_params, name)


def main(argv: Sequence[str] | None = None) -> None:
    """
    Run an rl-zoo3 flow on ``argv`` (default: the command line) after :func:`register`: the first argument
    ``--enjoy``, ``--record-video`` or ``--push-to-hub`` selects that flow, otherwise ``argv`` goes to rl-zoo3's
    train (``--optimize`` included). The flow reads ``sys.argv``, which is restored afterwards.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    module = FLOWS[args.pop(0)] if args and args[0] in FLOWS else TRAIN
    try:
        register()
    except ImportError as error:
        raise SystemExit(f"rl-zoo3 is not installed ({error}): pip install rl_zoo3") from None
    command_line = sys.argv
    sys.argv = [module, *args]
    try:
        runpy.run_module(module, run_name="__main__")
    finally:
        sys.argv = command_line
