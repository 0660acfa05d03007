from sb3_aac.pdqn.pdqn import MPDQN, PDQN
from sb3_aac.pdqn.policies import MlpPolicy, PDQNPolicy

__all__ = ["MPDQN", "PDQN", "MlpPolicy", "PDQNPolicy"]
