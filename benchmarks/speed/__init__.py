"""Speed scripts: each prints figures measured against a peer in the same run.

* :mod:`benchmarks.speed.training`: training env steps/s (``python -m benchmarks.speed.training sarsa|deep|hppo|pdqn``):
  SarsaAAC next to PPO and DQN (and its cost growth with the number of RBFs), ``DeepPolicy`` next to TD3, HybridPPO
  next to PPO, P-DQN and MP-DQN next to TD3 and DQN, with ``predict`` latency;
* :mod:`benchmarks.speed.decisions`: microseconds per decision of an exported policy (``python -m
  benchmarks.speed.decisions python|c``): :class:`sb3_aac.RuntimePolicy` next to ``predict`` and ``DQN.predict``, and the
  C runtime next to ``RuntimePolicy.act``;
* :mod:`benchmarks.speed.timing`: the timing they share.

The env's own speed script is :mod:`robocup_dribble.speed`; ``sb3-aac bench`` prints a quick subset.
"""
