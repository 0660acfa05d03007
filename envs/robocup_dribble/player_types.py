"""Heterogeneous player types, drawn the way rcssserver draws them.

Reference: ``docs/physics.md`` §7 (read from rcssserver's ``src/heteroplayer.cpp``):
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
from typing import Any, NamedTuple

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
        """Speed reached by full dashes at effort_max, before the speed cap (docs/physics.md §2.3, §7.2 step 9)."""
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
    """Type 0: the ``server::`` values (docs/physics.md §7.1); the catchable-area stretch is 1."""
    s = make_profile(profile).server
    return PlayerType(s.player_speed_max, s.stamina_inc_max, s.player_decay, s.inertia_moment, s.dash_power_rate,
                      s.player_size, s.kickable_margin, s.kick_rand, s.extra_stamina, s.effort_init,  # effort_max
                      s.effort_min, s.kick_power_rate, s.foul_detect_probability, 1.0)  # fmt: skip


def stack_player_types(types: Sequence[PlayerType]) -> np.ndarray:
    """Stack types into a ``(n, len(TYPE_FIELDS))`` float64 array, columns in :data:`TYPE_FIELDS` order."""
    return np.array([tuple(t) for t in types], dtype=np.float64).reshape(len(types), len(TYPE_FIELDS))


class ServerRandom:
    """The random source of rcssserver 19's ``HeteroPlayer::delta`` (docs/physics.md §7.4), a ``uniform(lo, hi, n)`` callable.

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


def _steps(profile: ServerProfile) -> list[Any]:
    """docs/physics.md §7.2 steps 1-8 in the server's order: ``((delta min, delta max), [(column, a, b, rule), ...])``.

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
    """docs/physics.md §7.2 as arrays for the compiled generator (:func:`type_recipe`; numba takes arrays, not lists).

    Step ``i`` draws ``delta[i] = step_lo[i] + step_span[i] * u`` (no draw when ``step_span[i] == 0``), then checks
    ``check_a[j] + delta[i] * check_b[j]`` for ``j`` in ``check_start[i] .. check_start[i + 1]``: the trial is rejected
    unless it is ``> 0`` (``check_strict[j]``) or ``>= 0``. Column ``f`` of an accepted type is
    ``column_a[f] + delta[column_step[f]] * column_b[f]``. With ``window[0]`` = 1 a type is kept only if its terminal
    speed lies in (``window[2]``, speed max + EPS) for ``max_power = window[1]`` (step 9).
    """

    default: np.ndarray  # (F,) type 0
    step_lo: np.ndarray  # (S,)
    step_span: np.ndarray
    check_start: np.ndarray  # (S + 1,) int64
    check_a: np.ndarray
    check_b: np.ndarray
    check_strict: np.ndarray  # bool
    column_step: np.ndarray  # (F,) int64
    column_a: np.ndarray
    column_b: np.ndarray
    window: np.ndarray  # (3,)


def _passes(value: float, strict: bool) -> bool:
    """The rejection rule of docs/physics.md §7.2: a value must be > 0 (strict) or >= 0."""
    return value > 0.0 if strict else value >= 0.0


@functools.lru_cache(maxsize=16)
def type_recipe(profile: ServerProfile) -> TypeRecipe:
    """:func:`_steps` of ``profile`` as a :class:`TypeRecipe` (computed once per profile)."""
    steps = _steps(profile)
    lo = np.array([min(bounds) for bounds, _ in steps])  # the server swaps reversed bounds
    span = np.array([max(bounds) for bounds, _ in steps]) - lo
    checks, check_start, columns = [], [0], {}
    for i, (_, terms) in enumerate(steps):
        for column, a, b, rule in terms:
            if column:
                columns[column] = (i, a, b)
            # a + d * b is monotone in d, and d lies in [lo, lo + span]: a check that passes at both ends never
            # rejects, and is left out
            if rule and not all(_passes(a + d * b, rule == ">0") for d in (lo[i], lo[i] + span[i])):
                checks.append((a, b, rule == ">0"))
        check_start.append(len(checks))
    check_a, check_b, strict = (np.array(values) for values in zip(*checks, strict=True)) if checks else (np.empty(0),) * 3
    by_field = (columns[name] for name in TYPE_FIELDS)
    column_step, column_a, column_b = (np.array(values) for values in zip(*by_field, strict=True))
    s = profile.server
    window = np.array([float(profile.hetero_acceptance == "speed_window"), s.max_power, s.player_speed_max_min - EPS])
    default = np.array(default_player_type(profile), dtype=np.float64)
    return TypeRecipe(
        default,
        lo,
        span,
        np.array(check_start, dtype=np.int64),
        check_a.astype(np.float64),
        check_b.astype(np.float64),
        strict.astype(np.bool_),
        column_step.astype(np.int64),
        column_a.astype(np.float64),
        column_b.astype(np.float64),
        window,
    )


@njit(cache=True, error_model="numpy", inline="always")
def next_uniform(buffer: np.ndarray, position: np.ndarray) -> float:
    """The value of ``buffer`` at ``position[0]``, which moves on by one; 0.5 once the buffer is used up (the position
    still moves on, so the caller sees from ``position[0] > buffer.shape[0]`` that it ran short and must redo)."""
    p = position[0]
    position[0] = p + 1
    return buffer[p] if p < buffer.shape[0] else 0.5


@njit(cache=True, error_model="numpy")
def draw_type_set(recipe: TypeRecipe, buffer: np.ndarray, position: np.ndarray, out: np.ndarray, row: int) -> None:
    """Draw one set of player types into ``out[row]`` (``(player_types, F)``), the server's way (docs/physics.md §7.2).

    Type 0 is the default type; types 1.. are drawn one after the other, each by up to ``MAX_TRIALS`` trials (a type
    whose trials all fail stays the default type). The uniforms come from :func:`next_uniform` in the server's
    order, so with ``buffer`` holding :class:`ServerRandom`'s stream this is the server's set, value for value.
    """
    # unpacked once: reading an array out of the tuple inside the loops would update its reference count every time
    default, lo, span, check_start, check_a, check_b, check_strict, column_step, column_a, column_b, window = recipe
    n_types, n_fields, n_steps = out.shape[1], out.shape[2], lo.shape[0]
    delta = np.empty(n_steps)
    for f in range(n_fields):
        out[row, 0, f] = default[f]
    for type_id in range(1, n_types):
        accepted = False
        for _ in range(MAX_TRIALS):
            ok = True
            for step in range(n_steps):
                d = lo[step]
                if span[step] != 0.0:
                    d = lo[step] + span[step] * next_uniform(buffer, position)
                delta[step] = d
                for j in range(check_start[step], check_start[step + 1]):
                    value = check_a[j] + d * check_b[j]
                    if not (value > 0.0 if check_strict[j] else value >= 0.0):
                        ok = False
                        break
                if not ok:
                    break
            if not ok:
                continue
            if window[0] > 0.5:  # step 9: the terminal speed must lie in the acceptance window
                dpr, eff, dec, spd = _DASH_POWER_RATE, _EFFORT_MAX, _DECAY, _SPEED_MAX
                dash_power_rate = column_a[dpr] + delta[column_step[dpr]] * column_b[dpr]
                effort_max = column_a[eff] + delta[column_step[eff]] * column_b[eff]
                decay = column_a[dec] + delta[column_step[dec]] * column_b[dec]
                speed_max = column_a[spd] + delta[column_step[spd]] * column_b[spd]
                v = (window[1] * dash_power_rate * effort_max) / (1.0 - decay)
                if not (window[2] < v < speed_max + EPS):
                    continue
            for f in range(n_fields):  # with b == 1, a + d * 1 is a + d exactly, as the server computes it
                out[row, type_id, f] = column_a[f] + delta[column_step[f]] * column_b[f]
            accepted = True
            break
        if not accepted:
            for f in range(n_fields):
                out[row, type_id, f] = default[f]


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
    if isinstance(n_sets, bool) or not isinstance(n_sets, (int, np.integer)) or n_sets < 0:  # type: ignore[redundant-expr]
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


def generate_player_types(
    profile: str | ServerProfile = "v19", seed: int = 1, kick_rand_delta_factor: float | None = None
) -> list[PlayerType]:
    """The types a server makes with ``player::random_seed = seed`` (index = type id), exact for v19 (docs/physics.md §7.4).

    ``kick_rand_delta_factor`` overrides ``profile.player.kick_rand_delta_factor`` (the golden recordings use 0 with
    server kick_rand 0, i.e. ``make_profile("v19", kick_rand=0)``); they were made with the default seed 1.
    """
    prof = make_profile(profile)
    if kick_rand_delta_factor is not None:
        player = dataclasses.replace(prof.player, kick_rand_delta_factor=kick_rand_delta_factor)
        prof = dataclasses.replace(prof, player=player)
    return [PlayerType._make(row) for row in draw_type_table(prof, 1, ServerRandom(seed))[0].tolist()]
