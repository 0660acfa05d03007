from sb3_aac.common.envs.navigation_env import NavigationEnv
from sb3_aac.common.envs.parameterized_target_env import ParameterizedTargetEnv

__all__ = ["NavigationEnv", "ParameterizedTargetEnv"]
