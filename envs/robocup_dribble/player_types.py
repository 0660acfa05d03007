"""Heterogeneous player types, drawn the way rcssserver draws them.

Reference: ``../shared/ref/rcssserver-physics.md`` §7 (read from rcssserver's ``src/heteroplayer.cpp``):
§7.1 the default type 0 (:func:`default_player_type`); §7.2 the generation of types 1 .. player_types-1
(:func:`draw_type_table`, the one implementation, vectorised over independent type sets); §7.3 the ranges of
each era (``player::`` parameters in :mod:`robocup_dribble.params`); §7.4 the random source of rcssserver 19
(:class:`ServerRandom`), with which :func:`generate_player_types` reproduces the ``(player_type ...)`` messages
of a real rcssserver 19.0.0 for a given seed.

The v11 profile uses the same recipe with the v11 ranges: 7 types, no acceptance window and no catchable-area
draw (the stretch stays 1.0).  The 2007 server drew with ``boost::mt19937`` seeded from the clock, so the v11
types follow the v11 distribution, not a particular v11 server run.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from .params import EPS, ServerProfile, make_profile

MAX_TRIALS = 1000  # rcssserver HeteroPlayer::HeteroPlayer()

Uniform = Callable[[float, float, int], np.ndarray]  # uniform(lo, hi, n): n values in [lo, hi)


class PlayerType(NamedTuple):
    """One heterogeneous player type (a ``(player_type ...)`` message), fields in the column order of the tables."""

    player_speed_max: float
    stamina_inc_max: float
    player_decay: float
    inertia_moment: float
    dash_power_rate: float
    player_size: float
    kickable_margin: float
    kick_rand: float
    extra_stamina: float
    effort_max: float
    effort_min: float
    kick_power_rate: float
    foul_detect_probability: float
    catchable_area_l_stretch: float

    def kickable_area(self, ball_size: float) -> float:
        """Kickable radius: player_size + ball_size + kickable_margin (m)."""
        return self.player_size + ball_size + self.kickable_margin

    @property
    def terminal_speed(self) -> float:
        """Speed reached by full dashes at effort_max, before the speed cap (spec §2.3, §7.2 step 9)."""
        return 100.0 * self.dash_power_rate * self.effort_max / (1.0 - self.player_decay)

    @classmethod
    def from_array(cls, row: Sequence[float] | np.ndarray) -> PlayerType:
        """Build a type from one row of :func:`stack_player_types` / :func:`draw_type_table`."""
        if len(row) != len(TYPE_FIELDS):
            raise ValueError(f"expected {len(TYPE_FIELDS)} values ({', '.join(TYPE_FIELDS)}), got {len(row)}")
        return cls._make(float(v) for v in row)


TYPE_FIELDS: tuple[str, ...] = PlayerType._fields
_SPEED_MAX, _DECAY, _DASH_POWER_RATE, _EFFORT_MAX = (
    TYPE_FIELDS.index(f) for f in ("player_speed_max", "player_decay", "dash_power_rate", "effort_max")
)


def default_player_type(profile: str | ServerProfile = "v19") -> PlayerType:
    """Type 0: the ``server::`` values (spec §7.1); the catchable-area stretch is 1."""
    s = make_profile(profile).server
    return PlayerType(s.player_speed_max, s.stamina_inc_max, s.player_decay, s.inertia_moment, s.dash_power_rate,
                      s.player_size, s.kickable_margin, s.kick_rand, s.extra_stamina, s.effort_init,  # effort_max
                      s.effort_min, s.kick_power_rate, s.foul_detect_probability, 1.0)  # fmt: skip


def stack_player_types(types: Sequence[PlayerType]) -> np.ndarray:
    """Stack types into a ``(n, len(TYPE_FIELDS))`` float64 array, columns in :data:`TYPE_FIELDS` order."""
    return np.array([tuple(t) for t in types], dtype=np.float64).reshape(len(types), len(TYPE_FIELDS))


class ServerRandom:
    """The random source of rcssserver 19's ``HeteroPlayer::delta`` (spec §7.4), a ``uniform(lo, hi, n)`` callable.

    ``std::mt19937`` seeded with ``player::random_seed``; each uniform value takes two 32-bit outputs x1 then x2,
    ``u = (x1 + x2 * 2**32) / 2**64`` (clamped below 1, as libstdc++'s ``generate_canonical``) and returns
    ``lo + (hi - lo) * u``.  numpy's legacy ``RandomState`` has the same Mersenne Twister initialisation, so
    ``randint(0, 2**32, dtype=np.uint64)`` yields the raw stream; it is fetched and turned into ``u`` in blocks.
    """

    _TWO32 = 4294967296.0
    _BELOW_ONE = float(np.nextafter(1.0, 0.0))

    def __init__(self, seed: int, block: int = 512) -> None:
        seed = int(seed)
        if not 0 <= seed < 2**32:
            raise ValueError(f"seed must lie in [0, 2**32), got {seed} (the server draws a random seed for negative values)")
        self.seed = seed
        self._engine = np.random.RandomState(seed)
        self._block = max(int(block), 1)
        self._buf = np.empty(0)
        self._pos = 0
        self.used = 0  # uniform values drawn so far (each took two engine outputs)

    def _refill(self, n: int) -> None:
        x = self._engine.randint(0, 2**32, size=2 * max(n, self._block), dtype=np.uint64).astype(np.float64)
        u = (x[0::2] + x[1::2] * self._TWO32) / (self._TWO32 * self._TWO32)
        np.minimum(u, self._BELOW_ONE, out=u)
        self._buf = np.concatenate((self._buf[self._pos :], u))
        self._pos = 0

    def canonical(self, n: int) -> np.ndarray:
        """The next ``n`` values of ``std::generate_canonical<double, 53>`` in [0, 1)."""
        if self._pos + n > self._buf.size:
            self._refill(n)
        out = self._buf[self._pos : self._pos + n]
        self._pos += n
        self.used += n
        return out

    def uniform(self, lo: float, hi: float, n: int) -> np.ndarray:
        """``n`` draws of ``std::uniform_real_distribution<double>(lo, hi)``."""
        return lo + (hi - lo) * self.canonical(n)

    __call__ = uniform


def _steps(profile: ServerProfile) -> list:
    """Spec §7.2 steps 1-8 in the server's order: ``((delta min, delta max), [(column, a, b, rule), ...])``.

    Each step draws one delta d and computes the values ``a + d * b``; ``column`` is the TYPE_FIELDS column the
    value sets (None: the value is only checked, a later step sets that column) and ``rule`` rejects the trial
    unless the value is ``">0"`` or ``">=0"`` (``""``: no check).
    """
    s, p = profile.server, profile.player
    stretch = (p.catchable_area_l_stretch_min, p.catchable_area_l_stretch_max)
    return [
        ((p.player_speed_max_delta_min, p.player_speed_max_delta_max),
         [("player_speed_max", s.player_speed_max, 1.0, ">0"),
          (None, s.stamina_inc_max, p.stamina_inc_max_delta_factor, ">0")]),
        ((p.player_decay_delta_min, p.player_decay_delta_max),
         [("player_decay", s.player_decay, 1.0, ">0"),
          ("inertia_moment", s.inertia_moment, p.inertia_moment_delta_factor, ">=0")]),
        ((p.dash_power_rate_delta_min, p.dash_power_rate_delta_max),
         [(None, s.dash_power_rate, 1.0, ">0"),
          ("player_size", s.player_size, p.player_size_delta_factor, ">0")]),
        ((p.new_dash_power_rate_delta_min, p.new_dash_power_rate_delta_max),
         [("dash_power_rate", s.dash_power_rate, 1.0, ">0"),
          ("stamina_inc_max", s.stamina_inc_max, p.new_stamina_inc_max_delta_factor, ">0")]),
        ((p.kickable_margin_delta_min, p.kickable_margin_delta_max),
         [("kickable_margin", s.kickable_margin, 1.0, ">0"),
          ("kick_rand", s.kick_rand, p.kick_rand_delta_factor, ">=0")]),
        ((p.extra_stamina_delta_min, p.extra_stamina_delta_max),
         [("extra_stamina", s.extra_stamina, 1.0, ">=0"),
          ("effort_max", s.effort_init, p.effort_max_delta_factor, ">0"),
          ("effort_min", s.effort_min, p.effort_min_delta_factor, ">0")]),
        ((p.kick_power_rate_delta_min, p.kick_power_rate_delta_max),
         [("kick_power_rate", s.kick_power_rate, 1.0, ""),
          ("foul_detect_probability", s.foul_detect_probability, p.foul_detect_probability_delta_factor, "")]),
        (stretch if profile.catchable_area_stretch else (1.0, 1.0),  # before v14: no draw, the stretch stays 1
         [("catchable_area_l_stretch", 0.0, 1.0, "")]),
    ]  # fmt: skip


class _Recipe(NamedTuple):
    lo: np.ndarray  # (n_steps, 1) each step's lower delta bound (its delta when min == max)
    segments: list  # [(steps, lo, span, checks)]: draw the deltas of steps in one call, then the checks
    src: np.ndarray  # (F,) the step that sets each column: column = a + delta[src] * b
    a: np.ndarray  # (F, 1)
    b: np.ndarray  # (F, 1)
    window: tuple[float, float] | None  # (max_power, player_speed_max_min - EPS); None: accept every type


def _passes(value, strict: bool):
    """The rejection rule of spec §7.2: a value must be > 0 (strict) or >= 0; for floats and arrays."""
    return value > 0.0 if strict else value >= 0.0


@functools.lru_cache(maxsize=16)
def _recipe(profile: ServerProfile) -> _Recipe:
    """:func:`_steps` arranged for drawing many sets at once (computed once per profile)."""
    steps = _steps(profile)
    lo = np.array([min(bounds) for bounds, _ in steps])  # the server swaps reversed bounds
    span = np.array([max(bounds) for bounds, _ in steps]) - lo
    segments, drawn = [], []
    for i, (_, terms) in enumerate(steps):
        if span[i]:
            drawn.append(i)
        checks = []
        for _, a, b, rule in terms:
            # a + d * b is monotone in d, and a drawn d = lo + span * u lies in [lo, lo + span]: a check that passes
            # at both ends never rejects and is left out, so the draws up to the next check that can fail are one call.
            if rule and not all(_passes(a + d * b, rule == ">0") for d in (lo[i], lo[i] + span[i])):
                checks.append((i, a, b, rule == ">0"))
        if checks or i == len(steps) - 1:
            segments.append((np.array(drawn, dtype=np.intp), lo[drawn, None], span[drawn, None], checks))
            drawn = []
    columns = {column: (i, a, b) for i, (_, terms) in enumerate(steps) for column, a, b, _ in terms if column}
    src, a, b = zip(*(columns[name] for name in TYPE_FIELDS))
    s = profile.server
    window = (s.max_power, s.player_speed_max_min - EPS) if profile.hetero_acceptance == "speed_window" else None
    return _Recipe(lo[:, None], segments, np.array(src), np.array(a)[:, None], np.array(b)[:, None], window)


def _trial(r: _Recipe, sets: np.ndarray, uniform: Uniform) -> tuple[np.ndarray, np.ndarray]:
    """One trial (spec §7.2 steps 1-9) for each of ``sets``: the sets that accepted their type and the types ``(F, n)``.

    A set rejected by a check draws nothing more in this trial; the draws of one call are laid out step-major,
    so a single set takes the values from the stream in the server's order.
    """
    delta = np.empty((r.lo.size, sets.size))
    delta[:] = r.lo  # a step without a draw keeps its one value
    for steps, lo, span, checks in r.segments:
        if steps.size and sets.size:
            delta[steps] = lo + span * uniform(0.0, 1.0, steps.size * sets.size).reshape(steps.size, -1)
        for step, a, b, strict in checks:
            ok = _passes(a + delta[step] * b, strict)
            sets, delta = sets[ok], delta[:, ok]
    t = r.a + delta[r.src] * r.b  # with b == 1, a + d * 1 is a + d exactly, as the server computes it
    if r.window is None:
        return sets, t
    max_power, v_min = r.window  # step 9
    v = (max_power * t[_DASH_POWER_RATE] * t[_EFFORT_MAX]) / (1.0 - t[_DECAY])
    inside = (v_min < v) & (v < t[_SPEED_MAX] + EPS)
    return sets[inside], t[:, inside]


def draw_type_table(profile: str | ServerProfile, n_sets: int, uniform: Uniform) -> np.ndarray:
    """Draw ``n_sets`` independent type tables: ``(n_sets, player_types, len(TYPE_FIELDS))`` float64.

    Row 0 of each set is the default type; types 1.. are drawn one after the other, each trial for all the sets
    still without that type at once.  ``uniform(lo, hi, n)`` returns ``n`` uniform values in [lo, hi), e.g.
    ``lambda lo, hi, n: rng.uniform(lo, hi, n)`` for a numpy Generator ``rng``; it is called with (0, 1) and the
    values are scaled here as the server does, ``lo + (hi - lo) * u``.  With ``n_sets == 1`` and a
    :class:`ServerRandom` this is the server's stream, value for value; with more sets their values interleave
    in the stream (each set still follows the server's distribution).
    """
    prof = make_profile(profile)
    n_sets = int(n_sets)
    if n_sets < 0:
        raise ValueError(f"n_sets must be >= 0, got {n_sets}")
    recipe = _recipe(prof)
    table = np.empty((n_sets, prof.player.player_types, len(TYPE_FIELDS)))
    table[:] = default_player_type(prof)  # and so stays every type whose 1000 trials all failed
    for type_id in range(1, prof.player.player_types):
        pending = np.ones(n_sets, dtype=bool)
        for _ in range(MAX_TRIALS):
            sets = np.flatnonzero(pending)
            if not sets.size:
                break
            accepted, types = _trial(recipe, sets, uniform)
            table[accepted, type_id] = types.T
            pending[accepted] = False
    return table


def generate_player_types(profile: str | ServerProfile = "v19", seed: int = 1,
                          kick_rand_delta_factor: float | None = None) -> list[PlayerType]:
    """The types a server generates with ``player::random_seed = seed`` (list index = type id); exact for v19 (§7.4).

    ``kick_rand_delta_factor`` overrides ``profile.player.kick_rand_delta_factor`` (the golden recordings use 0 with
    server kick_rand 0, i.e. ``make_profile("v19", kick_rand=0)``); they were made with the default seed 1.
    """
    prof = make_profile(profile)
    if kick_rand_delta_factor is not None:
        player = dataclasses.replace(prof.player, kick_rand_delta_factor=kick_rand_delta_factor)
        prof = dataclasses.replace(prof, player=player)
    return [PlayerType._make(row) for row in draw_type_table(prof, 1, ServerRandom(seed))[0].tolist()]
