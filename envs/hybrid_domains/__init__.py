"""The standard parameterized-action benchmark domains missing from Gymnasium 1.x, as Gymnasium environments.

Registered ids (``import hybrid_domains`` registers them, or ``gym.make("hybrid_domains:Goal-v0")``):

* ``Goal-v0``: Robot Soccer Goal (Masson, Ranchod & Konidaris 2016) with cycraig/gym-goal's dynamics;
* ``Moving-v0`` and ``Sliding-v0``: thomashirtz/gym-hybrid's point-agent tasks;
* ``CatchPoint-v0``: H-PPO's Catching Point (Fan et al. 2019) as the HyAR code implements it.

Platform (the fifth standard domain) is PyPI's ``hybrid-platform``. The action spaces keep each original's layout
(nested ``Tuple(Discrete(K), Tuple(Box...))``, or gym-hybrid's shared ``Tuple(Discrete(3), Box(2))``). This package
needs Gymnasium and numpy only.
"""

from gymnasium.envs.registration import register

from hybrid_domains.catch_point import CatchPointEnv
from hybrid_domains.goal import GoalEnv
from hybrid_domains.moving import MovingEnv, SlidingEnv

ENV_CLASSES: dict[str, type] = {
    "Goal-v0": GoalEnv,
    "Moving-v0": MovingEnv,
    "Sliding-v0": SlidingEnv,
    "CatchPoint-v0": CatchPointEnv,
}
"""The registered ids and their env classes (the one table; others should read it)."""

for _env_id, _cls in ENV_CLASSES.items():
    register(id=_env_id, entry_point=f"{_cls.__module__}:{_cls.__name__}")

__all__ = ["ENV_CLASSES", "CatchPointEnv", "GoalEnv", "MovingEnv", "SlidingEnv"]
