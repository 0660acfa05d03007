"""Server profiles: the rcssserver parameters one player and a ball need, as data.

Names follow the server's own ``server.conf`` / ``player.conf`` keys (``server::ball_decay`` becomes
``ServerParams.ball_decay``), so a value can be checked against a running server's ``(server_param ...)``
message. Values and version history: ``docs/physics.md`` §0 and §7.3, read from
rcssserver's ``src/serverparam.cpp`` and ``src/playerparam.cpp``.

Three profiles ship:

* ``"v19"``: rcssserver 19.0.0, the current server (default). Verified against recordings of a real server.
* ``"v15"``: rcssserver 15.2.2 as Half Field Offense builds it (the HFO fork of the server): v19's parameters but
  for the single-leg dash of v18 and earlier, dash power in [-100, 100], dash directions in steps of 45 degrees and
  back_dash_rate 0.6 (read from that fork's ``src/serverparam.cpp`` and ``src/player.cpp``; its player.conf defaults
  equal v19's).
* ``"v11"``: the 2007 server the paper (Uc-Cetina 2013) used: 7 player types, no dash direction,
  box-shaped noise, player speed max 1.2, ball speed max 2.7, stamina max 4000, kick_rand 0 for the
  default type and the effort-increase threshold bug.

A profile is a frozen dataclass; change a value with :func:`dataclasses.replace` or ``make_profile(name, **overrides)``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Literal

EPS = 1e-10  # rcssserver src/utility.h

PITCH_HALF_LENGTH = 52.5  # m: the goal lines stand at x = +-52.5 (hard-coded in the server, docs/physics.md §8)
PITCH_HALF_WIDTH = 34.0  # m: the touch lines at y = +-34
GOAL_POST_RADIUS = 0.06  # m (hard-coded in the server, docs/physics.md §6.3)


def kickable_radius(player_size: float, ball_size: float, kickable_margin: float) -> float:
    """Largest centre distance at which a player can kick the ball: player_size + ball_size + kickable_margin (m).

    The one definition; :func:`robocup_dribble.physics.kickable_radius` is this function compiled.
    """
    return player_size + ball_size + kickable_margin


@dataclass(frozen=True)
class ServerParams:
    """``server::`` parameters (one value for the whole server; per-type ones are the default type's)."""

    ball_size: float = 0.085  # m
    ball_decay: float = 0.94
    ball_rand: float = 0.05  # movement noise of the ball (fraction of its speed)
    ball_speed_max: float = 3.0  # m/cycle
    ball_accel_max: float = 2.7  # m/cycle^2
    player_size: float = 0.3  # m (type 0)
    player_decay: float = 0.4  # type 0
    player_rand: float = 0.1  # movement and turn noise of players
    player_speed_max: float = 1.05  # m/cycle (type 0)
    player_accel_max: float = 1.0  # m/cycle^2
    inertia_moment: float = 5.0  # type 0
    dash_power_rate: float = 0.006  # type 0
    kick_power_rate: float = 0.027  # type 0
    kickable_margin: float = 0.7  # m (type 0)
    kick_rand: float = 0.1  # type 0
    max_power: float = 100.0  # kick power range
    min_power: float = -100.0
    max_dash_power: float = 100.0
    min_dash_power: float = 0.0
    max_dash_angle: float = 180.0  # degrees
    min_dash_angle: float = -180.0
    dash_angle_step: float = 1.0  # degrees; dash directions are rounded to a multiple of it
    side_dash_rate: float = 0.4
    back_dash_rate: float = 0.7
    max_moment: float = 180.0  # turn range, degrees
    min_moment: float = -180.0
    stamina_max: float = 8000.0
    stamina_inc_max: float = 45.0  # type 0
    extra_stamina: float = 50.0  # type 0
    stamina_capacity: float = 130600.0  # a negative value disables the capacity rule
    recover_init: float = 1.0
    recover_dec_thr: float = 0.3
    recover_dec: float = 0.002
    recover_min: float = 0.5
    effort_init: float = 1.0
    effort_dec_thr: float = 0.3
    effort_dec: float = 0.005
    effort_min: float = 0.6  # type 0
    effort_inc_thr: float = 0.6
    effort_inc: float = 0.01
    player_speed_max_min: float = 0.75  # lower end of the heterogeneous acceptance window
    foul_detect_probability: float = 0.5  # type 0 (v14+); carried by player types, unused by the physics
    goal_width: float = 14.02  # m; the goal posts stand at y = +-(goal_width / 2 + GOAL_POST_RADIUS)
    tackle_dist: float = 2.0  # m: reach of a tackle in front of the player (v12+ values from here on)
    tackle_back_dist: float = 0.0  # m: reach behind (0: no tackle behind)
    tackle_width: float = 1.25  # m: reach to the side
    tackle_exponent: float = 6.0  # of the failure probability (|x| / dist)^e + (|y| / width)^e
    tackle_cycles: float = 10.0  # cycles a tackle freezes the player: its own and the next nine refuse every command
    tackle_power_rate: float = 0.027
    max_tackle_power: float = 100.0  # effective power of a tackle straight ahead
    max_back_tackle_power: float = 0.0  # ... and straight back
    tackle_rand_factor: float = 2.0  # tackle noise = the type's kick_rand times this factor


@dataclass(frozen=True)
class PlayerParams:
    """``player::`` parameters: how heterogeneous player types are drawn (docs/physics.md §7.2, §7.3)."""

    player_types: int = 18
    player_speed_max_delta_min: float = 0.0
    player_speed_max_delta_max: float = 0.0
    stamina_inc_max_delta_factor: float = 0.0
    player_decay_delta_min: float = -0.1
    player_decay_delta_max: float = 0.1
    inertia_moment_delta_factor: float = 25.0
    dash_power_rate_delta_min: float = 0.0
    dash_power_rate_delta_max: float = 0.0
    player_size_delta_factor: float = -100.0
    new_dash_power_rate_delta_min: float = -0.0012
    new_dash_power_rate_delta_max: float = 0.0008
    new_stamina_inc_max_delta_factor: float = -6000.0
    kickable_margin_delta_min: float = -0.1
    kickable_margin_delta_max: float = 0.1
    kick_rand_delta_factor: float = 1.0
    extra_stamina_delta_min: float = 0.0
    extra_stamina_delta_max: float = 50.0
    effort_max_delta_factor: float = -0.004
    effort_min_delta_factor: float = -0.004
    kick_power_rate_delta_min: float = 0.0
    kick_power_rate_delta_max: float = 0.0
    foul_detect_probability_delta_factor: float = 0.0
    catchable_area_l_stretch_min: float = 1.0
    catchable_area_l_stretch_max: float = 1.3


@dataclass(frozen=True)
class ServerProfile:
    """A server version's parameters plus the behaviours that changed between versions.

    :param name: short name (``"v19"``, ``"v11"``).
    :param server: the ``server::`` parameters.
    :param player: the ``player::`` parameters (heterogeneous types).
    :param dash_model: ``"bipedal"`` (v19: two legs, body rotation when stamina runs short, docs/physics.md §2.4)
        or ``"single"`` (v18 and earlier: one acceleration, docs/physics.md §2.3).
    :param dash_direction: whether ``(dash P D)`` takes a direction (v13+). Without it D is ignored.
    :param noise_shape: ``"polar"`` (v12+: radius uniform in [0, r], angle uniform) or ``"box"``
        (v11 and earlier: each axis uniform in [-r, r]); applies to movement and kick noise.
    :param effort_inc_uses_dec_thr: the v11 bug: effort rises whenever stamina >= effort_dec_thr * stamina_max.
    :param hetero_acceptance: ``"speed_window"`` (v12+: keep a type only if its terminal speed lies in
        [player_speed_max_min, player_speed_max]) or ``"none"`` (v11: every draw is kept).
    :param catchable_area_stretch: whether types draw catchable_area_l_stretch (v14+; consumes a random draw).
    """

    name: str
    server: ServerParams = field(default_factory=ServerParams)
    player: PlayerParams = field(default_factory=PlayerParams)
    dash_model: Literal["bipedal", "single"] = "bipedal"
    dash_direction: bool = True
    noise_shape: Literal["polar", "box"] = "polar"
    effort_inc_uses_dec_thr: bool = False
    hetero_acceptance: Literal["speed_window", "none"] = "speed_window"
    catchable_area_stretch: bool = True

    def __post_init__(self) -> None:
        _check_choice("dash_model", self.dash_model, ("bipedal", "single"))
        _check_choice("noise_shape", self.noise_shape, ("polar", "box"))
        _check_choice("hetero_acceptance", self.hetero_acceptance, ("speed_window", "none"))
        s = self.server
        for name in ("ball_size", "player_size", "ball_speed_max", "ball_accel_max", "player_speed_max", "player_accel_max"):
            if not getattr(s, name) > 0:
                raise ValueError(f"server.{name} must be > 0, got {getattr(s, name)!r}")
        for name in ("ball_decay", "player_decay"):
            if not 0 <= getattr(s, name) < 1:
                raise ValueError(f"server.{name} must lie in [0, 1), got {getattr(s, name)!r}")
        for name in ("ball_rand", "player_rand", "kick_rand"):
            if not getattr(s, name) >= 0:
                raise ValueError(f"server.{name} must be >= 0, got {getattr(s, name)!r}")
        if s.min_power > s.max_power or s.min_dash_power > s.max_dash_power:
            raise ValueError("server power ranges must satisfy min <= max")
        if not (s.tackle_cycles >= 0 and float(s.tackle_cycles).is_integer()):
            raise ValueError(f"server.tackle_cycles must be a whole number >= 0, got {s.tackle_cycles!r}")
        if not s.goal_width > 0:
            raise ValueError(f"server.goal_width must be > 0, got {s.goal_width!r}")
        if self.player.player_types < 1:
            raise ValueError(f"player.player_types must be >= 1, got {self.player.player_types}")

    @property
    def kickable_area(self) -> float:
        """The default type's kickable radius: player_size + ball_size + kickable_margin (m)."""
        return kickable_radius(self.server.player_size, self.server.ball_size, self.server.kickable_margin)


def _check_choice(name: str, value: str, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ValueError(f"{name}={value!r} is not supported; choose one of {list(allowed)}")


V19 = ServerProfile(name="v19")

V11 = ServerProfile(
    name="v11",
    server=ServerParams(
        ball_speed_max=2.7,
        player_speed_max=1.2,
        kick_rand=0.0,
        min_dash_power=-100.0,  # v11 clamped dash power to [min_power, max_power]; backwards costs 2x
        stamina_max=4000.0,
        extra_stamina=0.0,
        stamina_capacity=-1.0,  # no capacity rule before v13
        player_speed_max_min=0.0,
    ),
    player=PlayerParams(
        player_types=7,
        player_decay_delta_min=0.0,
        player_decay_delta_max=0.2,
        new_dash_power_rate_delta_min=0.0,
        new_dash_power_rate_delta_max=0.002,
        new_stamina_inc_max_delta_factor=-10000.0,
        kickable_margin_delta_min=0.0,
        kickable_margin_delta_max=0.2,
        kick_rand_delta_factor=0.5,
        extra_stamina_delta_min=0.0,
        extra_stamina_delta_max=100.0,
        effort_max_delta_factor=-0.002,
        effort_min_delta_factor=-0.002,
    ),
    dash_model="single",
    dash_direction=False,
    noise_shape="box",
    effort_inc_uses_dec_thr=True,
    hetero_acceptance="none",
    catchable_area_stretch=False,
)

V15 = ServerProfile(
    name="v15",
    server=ServerParams(min_dash_power=-100.0, dash_angle_step=45.0, back_dash_rate=0.6),
    dash_model="single",
)

PROFILES: dict[str, ServerProfile] = {"v19": V19, "v15": V15, "v11": V11}


def make_profile(profile: str | ServerProfile = "v19", **server_overrides: float) -> ServerProfile:
    """Return a profile by name (or as given), with ``server::`` parameters overridden.

    ``make_profile("v19", player_rand=0, ball_rand=0, kick_rand=0)`` is the noise-free v19 server.

    :raises ValueError: for an unknown profile name or an unknown server parameter.
    """
    if isinstance(profile, ServerProfile):
        base = profile
    elif profile in PROFILES:
        base = PROFILES[profile]
    else:
        raise ValueError(f"Unknown server profile {profile!r}; choose one of {sorted(PROFILES)} or pass a ServerProfile")
    if not server_overrides:
        return base
    known = {f.name for f in dataclasses.fields(ServerParams)}
    unknown = sorted(set(server_overrides) - known)
    if unknown:
        raise ValueError(f"Unknown server parameter(s) {unknown}; known: {sorted(known)}")
    return dataclasses.replace(base, server=dataclasses.replace(base.server, **server_overrides))


def without_noise(profile: ServerProfile) -> ServerProfile:
    """The profile with every noise source off: movement noise, kick noise, and no kick_rand for any player type."""
    return dataclasses.replace(
        profile,
        server=dataclasses.replace(profile.server, player_rand=0.0, ball_rand=0.0, kick_rand=0.0),
        player=dataclasses.replace(profile.player, kick_rand_delta_factor=0.0),
    )
