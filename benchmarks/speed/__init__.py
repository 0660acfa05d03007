"""Speed scripts: each prints figures measured against a peer in the same run (``python -m benchmarks.speed.<name>``).

* :mod:`benchmarks.speed.algo_speed`: SarsaAAC's training env steps/s next to SB3's PPO and DQN, its cost growth with
  the number of RBFs, and ``predict`` latency next to DQN's;
* :mod:`benchmarks.speed.pdqn_speed`: P-DQN's and MP-DQN's training env steps/s and ``predict`` latency next to TD3 and
  DQN;
* :mod:`benchmarks.speed.runtime_speed`: microseconds per decision of an exported policy next to ``SarsaAAC.predict``
  and ``DQN.predict``, and its growth with the number of RBFs;
* :mod:`benchmarks.speed.c_runtime_speed`: nanoseconds per decision of the C runtime (timed by ``c/aacp_speed.c``)
  next to ``RuntimePolicy.act``, and how closely its decisions follow;
* :mod:`benchmarks.speed.deep_speed`: SarsaAAC ``DeepPolicy``'s training env steps/s next to TD3;
* :mod:`benchmarks.speed.hppo_speed`: HybridPPO's training env steps/s next to PPO;
* :mod:`benchmarks.speed.timing`: the timing they share.

The env's own speed script is :mod:`robocup_dribble.speed`; ``sb3-aac bench`` prints a quick subset.
"""
