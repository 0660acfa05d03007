from sb3_aac.sarsa_aac.policies import DeepPolicy, MlpPolicy, RbfMlpPolicy, RbfPolicy, SarsaAACPolicy, TilePolicy
from sb3_aac.sarsa_aac.sarsa_aac import SarsaAAC

__all__ = ["DeepPolicy", "MlpPolicy", "RbfMlpPolicy", "RbfPolicy", "SarsaAAC", "SarsaAACPolicy", "TilePolicy"]
