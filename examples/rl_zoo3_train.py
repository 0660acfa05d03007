"""
Train (or replay) SarsaAAC, P-DQN, MP-DQN or HybridPPO with rl-zoo3, the RL Baselines3 Zoo.

rl-zoo3 builds ``--algo``'s choices from ``rl_zoo3.ALGOS`` when it parses the command line, so an external algorithm
is added by a wrapper script that registers it first (the pattern of rl-zoo3's own docs for SBX). This script
registers ``sarsa_aac``, ``pdqn``, ``mpdqn``, ``hppo`` and the dribbling envs, then hands the command line to rl-zoo3's
``train`` (or, with ``--enjoy`` as the first argument, ``enjoy``)::

    pip install rl_zoo3
    python examples/rl_zoo3_train.py --algo sarsa_aac --env RoboCupDribblePaper-v0 --conf-file hyperparams/sarsa_aac.yml
    python examples/rl_zoo3_train.py --algo mpdqn --env Platform-v0 --gym-packages gym_platform \
        --conf-file hyperparams/mpdqn.yml
    python examples/rl_zoo3_train.py --algo hppo --env Platform-v0 --gym-packages gym_platform --conf-file hyperparams/hppo.yml
    python examples/rl_zoo3_train.py --enjoy --algo sarsa_aac --env RoboCupDribblePaper-v0 -f logs/ --no-render
    python examples/rl_zoo3_train.py --algo sarsa_aac --env RoboCupDribblePaper-v0 --conf-file hyperparams/sarsa_aac.yml \
        --optimize --n-trials 20 --n-evaluations 5 --storage study.log --study-name zoo-dribble

Every rl-zoo3 option works (``-n`` steps, ``--seed``, ``--tensorboard-log``, ``--eval-freq``, ``-f`` log folder,
``--hyperparams key:value``). rl-zoo3 wraps the env id in its own ``DummyVecEnv``; the batched
``robocup_dribble.DribbleVecEnv`` of ``sb3-aac train`` is faster.
"""

from __future__ import annotations

import sys

import robocup_dribble  # noqa: F401  (registers RoboCupDribble-v0 and RoboCupDribblePaper-v0)
from sb3_aac import MPDQN, PDQN, HybridPPO, SarsaAAC
from sb3_aac.cli import register_toy_env
from sb3_aac.tune.zoo import register_sampler

try:
    import rl_zoo3
    import rl_zoo3.enjoy
    import rl_zoo3.exp_manager
    import rl_zoo3.train
except ImportError as error:  # pragma: no cover - depends on the environment
    raise SystemExit(f"rl-zoo3 is not installed ({error}): pip install rl_zoo3") from None


def register() -> None:
    """
    Make ``--algo sarsa_aac|pdqn|mpdqn|hppo`` known to rl-zoo3 (train, enjoy and the experiment manager share one dict),
    and the ``--optimize`` samplers of SarsaAAC and HybridPPO (which sample the policy too, see :mod:`sb3_aac.tune.zoo`).
    """
    register_toy_env()  # sb3_aac/ParameterizedTarget-v0
    rl_zoo3.ALGOS["sarsa_aac"] = SarsaAAC
    rl_zoo3.ALGOS["pdqn"] = PDQN
    rl_zoo3.ALGOS["mpdqn"] = MPDQN
    rl_zoo3.ALGOS["hppo"] = HybridPPO
    rl_zoo3.train.ALGOS = rl_zoo3.ALGOS
    rl_zoo3.enjoy.ALGOS = rl_zoo3.ALGOS
    rl_zoo3.exp_manager.ALGOS = rl_zoo3.ALGOS
    register_sampler()  # --optimize: the search spaces of sb3-aac tune


def main() -> None:
    register()
    if len(sys.argv) > 1 and sys.argv[1] == "--enjoy":
        del sys.argv[1]
        rl_zoo3.enjoy.enjoy()
    else:
        rl_zoo3.train.train()


if __name__ == "__main__":
    main()
