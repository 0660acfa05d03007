"""
Greedy decisions (SarsaAAC, HybridPPO, P-DQN, MP-DQN) from an exported policy file, with numpy alone.

:func:`sb3_aac.export_policy` writes a trained policy as plain arrays and a JSON description (format
``sb3-aac-policy`` versions 2 to 4, see ``docs/export-format.md``); :class:`RuntimePolicy` reads it back and acts::

    from sb3_aac.runtime import RuntimePolicy

    policy = RuntimePolicy.load("dribbler.aacp")
    action_type, params = policy.act(observation)  # params of that type, in the env's units

This package imports only the standard library and numpy (no torch, no Stable-Baselines3, nothing else of
``sb3_aac``: its modules import each other relatively), so its directory can be copied into an agent on its own
and imported there as ``runtime``. One module per job:

- :mod:`~sb3_aac.runtime.actions`: action layouts and parameter scaling (shared with training);
- :mod:`~sb3_aac.runtime.forward`: the approximators' forward pass, the very code training and ``model.predict``
  run, so the decisions are those of ``model.predict(obs, deterministic=True)``;
- :mod:`~sb3_aac.runtime.format`: the ``.aacp`` file format, its constants and the checking reader;
- :mod:`~sb3_aac.runtime.kernel`: the optional numba kernel for one decision (the same formulas compiled);
- :mod:`~sb3_aac.runtime.policy`: :class:`RuntimePolicy`.
"""

from .format import FORMAT_NAME, FORMAT_VERSION, read_policy_file
from .policy import RuntimePolicy

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "RuntimePolicy", "read_policy_file"]
