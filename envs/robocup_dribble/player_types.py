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
from numba import njit

from .params import EPS, ServerProfile, kickable_radius, make_profile

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
        return kickable_radius(self.player_size, ball_size, self.kickable_margin)

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

    def unread(self, n: int) -> None:
        """Give back the last ``n`` values of the latest call (at most its size): the next call returns them again."""
        if not 0 <= n <= self._pos:
            raise ValueError(f"cannot give back {n} values, {self._pos} are buffered")
        self._pos -= n
        self.used -= n


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


class TypeRecipe(NamedTuple):
    """Spec §7.2 as arrays for the compiled generator (:func:`type_recipe`; numba takes arrays, not lists).

    Step ``i`` draws ``delta = step_lo[i] + step_span[i] * u`` (no draw when ``step_span[i] == 0``); term ``j`` of
    step ``term_step[j]`` computes ``term_a[j] + delta * term_b[j]``, rejects the trial unless it is ``> 0``
    (``term_rule[j] == 1``) or ``>= 0`` (``2``) and sets column ``term_column[j]`` (-1: none) of the type. With
    ``window[0]`` = 1 a type is kept only if its terminal speed lies in (``window[2]``, speed max + EPS) for
    ``max_power = window[1]`` (step 9).
    """

    default: np.ndarray  # (F,) type 0
    step_lo: np.ndarray
    step_span: np.ndarray
    term_step: np.ndarray
    term_column: np.ndarray
    term_a: np.ndarray
    term_b: np.ndarray
    term_rule: np.ndarray
    window: np.ndarray


_RULES = {"": 0, ">0": 1, ">=0": 2}


@functools.lru_cache(maxsize=16)
def type_recipe(profile: ServerProfile) -> TypeRecipe:
    """:func:`_steps` of ``profile`` as a :class:`TypeRecipe` (computed once per profile)."""
    steps = _steps(profile)
    lo = np.array([min(bounds) for bounds, _ in steps])  # the server swaps reversed bounds
    span = np.array([max(bounds) for bounds, _ in steps]) - lo
    terms = [(i, -1 if column is None else TYPE_FIELDS.index(column), a, b, _RULES[rule])
             for i, (_, step_terms) in enumerate(steps) for column, a, b, rule in step_terms]
    step_of, column, a, b, rule = (np.array(values) for values in zip(*terms))
    s = profile.server
    window = np.array([float(profile.hetero_acceptance == "speed_window"), s.max_power, s.player_speed_max_min - EPS])
    default = np.array(default_player_type(profile), dtype=np.float64)
    return TypeRecipe(default, lo, span, step_of.astype(np.int64), column.astype(np.int64), a.astype(np.float64),
                      b.astype(np.float64), rule.astype(np.int64), window)


@njit(cache=True, error_model="numpy", inline="always")
def next_uniform(buffer: np.ndarray, position: np.ndarray) -> float:
    """The value of ``buffer`` at ``position[0]``, which moves on by one; 0.5 once the buffer is used up (the position
    still moves on, so the caller sees from ``position[0] > buffer.shape[0]`` that it ran short and must redo)."""
    p = position[0]
    position[0] = p + 1
    return buffer[p] if p < buffer.shape[0] else 0.5


@njit(cache=True, error_model="numpy")
def draw_type_set(recipe: TypeRecipe, buffer: np.ndarray, position: np.ndarray, out: np.ndarray, row: int) -> None:
    """Draw one set of player types into ``out[row]`` (``(player_types, F)``), the server's way (spec §7.2).

    Type 0 is the default type; types 1.. are drawn one after the other, each by up to ``MAX_TRIALS`` trials (a type
    whose trials all fail stays the default type). The uniforms come from :func:`next_uniform` in the server's
    order, so with ``buffer`` holding :class:`ServerRandom`'s stream this is the server's set, value for value.
    """
    default, step_lo, step_span, term_step, term_column, term_a, term_b, term_rule, window = recipe  # unpacked once:
    # reading an array out of the tuple in the loops would update its reference count every time
    n_types, n_fields = out.shape[1], out.shape[2]
    n_steps, n_terms = step_lo.shape[0], term_step.shape[0]
    delta = np.empty(n_steps)
    for type_id in range(n_types):
        for f in range(n_fields):
            out[row, type_id, f] = default[f]
    for type_id in range(1, n_types):
        for _ in range(MAX_TRIALS):
            ok = True
            term = 0
            for step in range(n_steps):
                d = step_lo[step]
                if step_span[step] != 0.0:
                    d = step_lo[step] + step_span[step] * next_uniform(buffer, position)
                delta[step] = d
                while term < n_terms and term_step[term] == step:
                    value = term_a[term] + d * term_b[term]
                    rule = term_rule[term]
                    if (rule == 1 and not value > 0.0) or (rule == 2 and not value >= 0.0):
                        ok = False
                    term += 1
                if not ok:
                    break
            if not ok:
                continue
            if window[0] > 0.5:  # step 9: the terminal speed must lie in the acceptance window
                dash_power_rate = effort_max = decay = speed_max = 0.0
                for term in range(n_terms):
                    c = term_column[term]
                    value = term_a[term] + delta[term_step[term]] * term_b[term]
                    if c == _DASH_POWER_RATE:
                        dash_power_rate = value
                    elif c == _EFFORT_MAX:
                        effort_max = value
                    elif c == _DECAY:
                        decay = value
                    elif c == _SPEED_MAX:
                        speed_max = value
                v = (window[1] * dash_power_rate * effort_max) / (1.0 - decay)
                if not (window[2] < v < speed_max + EPS):
                    continue
            for term in range(n_terms):  # with b == 1, a + d * 1 is a + d exactly, as the server computes it
                c = term_column[term]
                if c >= 0:
                    out[row, type_id, c] = term_a[term] + delta[term_step[term]] * term_b[term]
            break


@njit(cache=True, error_model="numpy")
def _draw_sets(recipe: TypeRecipe, buffer: np.ndarray, out: np.ndarray, first: int) -> tuple[int, int]:
    """Draw sets ``first``.. of ``out`` from ``buffer`` until it runs short; returns (sets done, values they used)."""
    position = np.zeros(1, dtype=np.int64)
    used = 0
    for row in range(first, out.shape[0]):
        draw_type_set(recipe, buffer, position, out, row)
        if position[0] > buffer.shape[0]:
            return row, used
        used = position[0]
    return out.shape[0], used


_BLOCK = 4096  # uniforms fetched from a ``uniform`` callable per call


def draw_type_table(profile: str | ServerProfile, n_sets: int, uniform: Uniform) -> np.ndarray:
    """Draw ``n_sets`` independent type tables: ``(n_sets, player_types, len(TYPE_FIELDS))`` float64.

    Each set is drawn by :func:`draw_type_set`, one after the other, from the values of ``uniform(lo, hi, n)``
    (``n`` uniform values in [lo, hi), e.g. ``lambda lo, hi, n: rng.uniform(lo, hi, n)`` for a numpy Generator
    ``rng``), fetched in blocks with (0, 1). Values fetched beyond the last set's needs are given back if
    ``uniform`` has an ``unread(n)`` method (as :class:`ServerRandom` has), else dropped. With a
    :class:`ServerRandom` this is the server's stream, value for value.
    """
    prof = make_profile(profile)
    if isinstance(n_sets, bool) or not isinstance(n_sets, (int, np.integer)) or n_sets < 0:
        raise ValueError(f"n_sets must be an integer >= 0, got {n_sets!r}")
    recipe = type_recipe(prof)
    table = np.empty((int(n_sets), prof.player.player_types, len(TYPE_FIELDS)))
    buffer = np.empty(0)
    done = 0
    while done < len(table):
        fetched = np.asarray(uniform(0.0, 1.0, _BLOCK), dtype=np.float64)
        if fetched.shape != (_BLOCK,) or not ((fetched >= 0.0) & (fetched < 1.0)).all():
            raise ValueError(f"uniform(0, 1, {_BLOCK}) must return {_BLOCK} values in [0, 1)")
        buffer = np.concatenate((buffer, fetched))
        done, used = _draw_sets(recipe, buffer, table, done)
        buffer = buffer[used:]
    if len(buffer) and hasattr(uniform, "unread"):
        uniform.unread(len(buffer))
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
