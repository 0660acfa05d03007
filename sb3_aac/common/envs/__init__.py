"""Small parameterized-action envs of the package: the toy env with a known optimum, and a navigation task."""

from sb3_aac.common.envs.navigation_env import NavigationEnv
from sb3_aac.common.envs.parameterized_target_env import ParameterizedTargetEnv

TOY_ENV_ID = "sb3_aac/ParameterizedTarget-v0"
"""The Gymnasium id of :class:`ParameterizedTargetEnv`, once :func:`register_toy_env` has run."""


def register_toy_env() -> None:
    """Register :class:`ParameterizedTargetEnv` as :data:`TOY_ENV_ID` (once)."""
    import gymnasium as gym

    if TOY_ENV_ID not in gym.registry:
        gym.register(TOY_ENV_ID, entry_point="sb3_aac.common.envs:ParameterizedTargetEnv")


__all__ = ["TOY_ENV_ID", "NavigationEnv", "ParameterizedTargetEnv", "register_toy_env"]
