"""TEMPORARY stand-in (replaced by the types branch)."""
from __future__ import annotations
from dataclasses import dataclass, fields, astuple
import numpy as np

@dataclass(frozen=True)
class PlayerType:
    player_speed_max: float = 1.05
    stamina_inc_max: float = 45.0
    player_decay: float = 0.4
    inertia_moment: float = 5.0
    dash_power_rate: float = 0.006
    player_size: float = 0.3
    kickable_margin: float = 0.7
    kick_rand: float = 0.1
    extra_stamina: float = 50.0
    effort_max: float = 1.0
    effort_min: float = 0.6
    kick_power_rate: float = 0.027
    foul_detect_probability: float = 0.5
    catchable_area_l_stretch: float = 1.0

TYPE_FIELDS = tuple(f.name for f in fields(PlayerType))

def default_player_type(profile) -> PlayerType:
    s = profile.server
    return PlayerType(s.player_speed_max, s.stamina_inc_max, s.player_decay, s.inertia_moment, s.dash_power_rate, s.player_size,
                      s.kickable_margin, s.kick_rand, s.extra_stamina, s.effort_init, s.effort_min, s.kick_power_rate, 0.5, 1.0)

def stack_player_types(types):
    return np.array([astuple(t) for t in types], dtype=np.float64)

def generate_player_types(profile, seed, kick_rand_delta_factor=None):
    raise NotImplementedError
