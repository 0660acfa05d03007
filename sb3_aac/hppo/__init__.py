from sb3_aac.hppo.hppo import HybridPPO
from sb3_aac.hppo.policies import HybridActorCriticPolicy, MlpPolicy

__all__ = ["HybridActorCriticPolicy", "HybridPPO", "MlpPolicy"]
