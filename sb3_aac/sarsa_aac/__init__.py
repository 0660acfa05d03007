from sb3_aac.sarsa_aac.policies import MlpPolicy, RbfMlpPolicy, RbfPolicy, SarsaAACPolicy, TilePolicy
from sb3_aac.sarsa_aac.sarsa_aac import SarsaAAC

__all__ = ["MlpPolicy", "RbfMlpPolicy", "RbfPolicy", "SarsaAAC", "SarsaAACPolicy", "TilePolicy"]
