"""
SarsaAAC, P-DQN and MP-DQN in rl-zoo3, the RL Baselines3 Zoo (``pip install rl_zoo3``): every rl-zoo3 flow, run
after :func:`sb3_aac.zoo.register` has made ``--algo sarsa_aac|pdqn|mpdqn`` known. This script registers the dribbling
envs (``import robocup_dribble``) and hands the command line to :func:`sb3_aac.zoo.main`: rl-zoo3's train (the default,
``--optimize`` included), or, as the first argument, ``--enjoy``, ``--record-video`` or ``--push-to-hub``::

    python examples/rl_zoo3_train.py --algo sarsa_aac --env RoboCupDribblePaper-v0 --conf-file hyperparams/sarsa_aac.yml
    python examples/rl_zoo3_train.py --enjoy --algo sarsa_aac --env RoboCupDribblePaper-v0 -f logs/ --no-render
    python examples/rl_zoo3_train.py --record-video --algo sarsa_aac --env RoboCupDribblePaper-v0 -f logs/ -n 200
    python examples/rl_zoo3_train.py --push-to-hub --algo sarsa_aac --env RoboCupDribblePaper-v0 -f logs/ -orga you
    python examples/rl_zoo3_train.py --algo mpdqn --env RoboCupDribblePaper-v0 --conf-file hyperparams/mpdqn.yml \
        --optimize --n-trials 20 --n-evaluations 5 --storage study.log --study-name zoo-dribble

Every option of the rl-zoo3 flow works (``-n``, ``--seed``, ``-f``, ``--hyperparams key:value``, ...); see
``docs/rl_zoo3.md``.
"""

import robocup_dribble  # noqa: F401  (registers RoboCupDribble-v0 and RoboCupDribblePaper-v0)
from sb3_aac.zoo import main

if __name__ == "__main__":
    main()
