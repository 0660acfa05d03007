"""Heterogeneous player types, drawn the way rcssserver draws them.

Reference: ``../shared/ref/rcssserver-physics.md`` §7 (read from rcssserver's ``src/heteroplayer.cpp``):

* §7.1 the default type (type 0) comes from the ``server::`` parameters: :func:`default_player_type`.
* §7.2 types 1 .. player_types-1 are drawn in order, each by up to 1000 trials of seven trade-offs plus the
  catchable-area stretch (v14+), with rejection rules after each draw and, since v12, an acceptance window
  on the terminal speed; after 1000 failed trials the type falls back to the default.
* §7.3 the ranges of each server era (``player::`` parameters in :mod:`robocup_dribble.params`).
* §7.4 the random source of rcssserver 19: a ``std::mt19937`` seeded with ``player::random_seed`` and
  libstdc++'s ``uniform_real_distribution``: :class:`ServerRandom`.

:func:`generate_player_types` is a literal, one-type-at-a-time implementation of §7.2; with the v19 profile it
reproduces the ``(player_type ...)`` messages of a real rcssserver 19.0.0 for a given seed.
:func:`draw_type_table` is the vectorised version the environment uses to draw many type tables at once.

The v11 profile uses the same recipe with the v11 ranges (§7.3): 7 types, no acceptance window
(``hetero_acceptance="none"``) and no catchable-area draw (``catchable_area_stretch=False``, the stretch
stays 1.0).  The 2007 server drew with ``boost::mt19937`` + ``boost::uniform_real`` seeded from the clock,
so its actual types cannot be reproduced bit-exactly from a seed; the v11 types here follow the v11
distribution, not a particular v11 server run.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .params import EPS, ServerProfile, make_profile

MAX_TRIALS = 1000  # rcssserver HeteroPlayer::HeteroPlayer()

Uniform = Callable[[float, float, int], np.ndarray]


@dataclass(frozen=True)
class PlayerType:
    """One heterogeneous player type (the numbers of a ``(player_type ...)`` message).

    The field order is the column order of :func:`stack_player_types` and :func:`draw_type_table`.
    """

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
        return cls(*(float(v) for v in row))


TYPE_FIELDS: tuple[str, ...] = tuple(f.name for f in dataclasses.fields(PlayerType))
_COL = {name: j for j, name in enumerate(TYPE_FIELDS)}


def _profile(profile: str | ServerProfile) -> ServerProfile:
    return make_profile(profile)


def default_player_type(profile: str | ServerProfile = "v19") -> PlayerType:
    """Type 0: the ``server::`` values (spec §7.1); the catchable-area stretch is 1."""
    s = _profile(profile).server
    return PlayerType(
        player_speed_max=s.player_speed_max,
        stamina_inc_max=s.stamina_inc_max,
        player_decay=s.player_decay,
        inertia_moment=s.inertia_moment,
        dash_power_rate=s.dash_power_rate,
        player_size=s.player_size,
        kickable_margin=s.kickable_margin,
        kick_rand=s.kick_rand,
        extra_stamina=s.extra_stamina,
        effort_max=s.effort_init,
        effort_min=s.effort_min,
        kick_power_rate=s.kick_power_rate,
        foul_detect_probability=s.foul_detect_probability,
        catchable_area_l_stretch=1.0,
    )


def stack_player_types(types: Sequence[PlayerType]) -> np.ndarray:
    """Stack types into a ``(n, len(TYPE_FIELDS))`` float64 array, columns in :data:`TYPE_FIELDS` order."""
    rows = [[getattr(t, f) for f in TYPE_FIELDS] for t in types]
    return np.array(rows, dtype=np.float64).reshape(len(types), len(TYPE_FIELDS))


class ServerRandom:
    """The random source of rcssserver 19's ``HeteroPlayer::delta`` (spec §7.4).

    ``std::mt19937`` seeded with ``player::random_seed``; each uniform value takes two 32-bit outputs
    x1 then x2, ``u = (x1 + x2 * 2**32) / 2**64`` (clamped below 1, as libstdc++'s ``generate_canonical``)
    and returns ``lo + (hi - lo) * u``.  numpy's legacy ``RandomState`` uses the same Mersenne Twister
    initialisation, so ``randint(0, 2**32, dtype=np.uint64)`` yields the raw stream; it is fetched and turned
    into ``u`` values in blocks.

    An instance is a ``uniform(lo, hi, n)`` callable for :func:`draw_type_table`.
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


# --------------------------------------------------------------------------------------------------
# Reference implementation: one type at a time, statement by statement as spec §7.2.


def _reference_type(profile: ServerProfile, uniform: Uniform) -> PlayerType:
    s, p = profile.server, profile.player

    def delta(lo: float, hi: float) -> float:
        if lo == hi:
            return lo  # no random number is consumed
        if lo > hi:
            lo, hi = hi, lo
        return float(uniform(lo, hi, 1)[0])

    for _ in range(MAX_TRIALS):
        d = delta(p.player_speed_max_delta_min, p.player_speed_max_delta_max)
        speed_max = s.player_speed_max + d
        if speed_max <= 0.0:
            continue
        stamina_inc = s.stamina_inc_max + d * p.stamina_inc_max_delta_factor
        if stamina_inc <= 0.0:
            continue

        d = delta(p.player_decay_delta_min, p.player_decay_delta_max)
        decay = s.player_decay + d
        if decay <= 0.0:
            continue
        inertia = s.inertia_moment + d * p.inertia_moment_delta_factor
        if inertia < 0.0:
            continue

        d = delta(p.dash_power_rate_delta_min, p.dash_power_rate_delta_max)
        if s.dash_power_rate + d <= 0.0:
            continue
        size = s.player_size + d * p.player_size_delta_factor
        if size <= 0.0:
            continue

        d = delta(p.new_dash_power_rate_delta_min, p.new_dash_power_rate_delta_max)
        dash_power_rate = s.dash_power_rate + d
        if dash_power_rate <= 0.0:
            continue
        stamina_inc = s.stamina_inc_max + d * p.new_stamina_inc_max_delta_factor
        if stamina_inc <= 0.0:
            continue

        d = delta(p.kickable_margin_delta_min, p.kickable_margin_delta_max)
        margin = s.kickable_margin + d
        if margin <= 0.0:
            continue
        kick_rand = s.kick_rand + d * p.kick_rand_delta_factor
        if kick_rand < 0.0:
            continue

        d = delta(p.extra_stamina_delta_min, p.extra_stamina_delta_max)
        extra = s.extra_stamina + d
        if extra < 0.0:
            continue
        effort_max = s.effort_init + d * p.effort_max_delta_factor
        effort_min = s.effort_min + d * p.effort_min_delta_factor
        if effort_max <= 0.0 or effort_min <= 0.0:
            continue

        d = delta(p.kick_power_rate_delta_min, p.kick_power_rate_delta_max)
        kick_power_rate = s.kick_power_rate + d
        foul = s.foul_detect_probability + d * p.foul_detect_probability_delta_factor

        stretch = 1.0
        if profile.catchable_area_stretch:
            stretch = delta(p.catchable_area_l_stretch_min, p.catchable_area_l_stretch_max)

        t = PlayerType(speed_max, stamina_inc, decay, inertia, dash_power_rate, size, margin, kick_rand,
                       extra, effort_max, effort_min, kick_power_rate, foul, stretch)
        if profile.hetero_acceptance == "none":
            return t
        v = (s.max_power * dash_power_rate * effort_max) / (1.0 - decay)
        if s.player_speed_max_min - EPS < v < speed_max + EPS:
            return t
    return default_player_type(profile)


def generate_player_types(
    profile: str | ServerProfile = "v19",
    seed: int = 1,
    kick_rand_delta_factor: float | None = None,
) -> list[PlayerType]:
    """The types a server generates with ``player::random_seed = seed`` (list index = type id).

    Exact for the v19 profile (spec §7.4).  ``kick_rand_delta_factor`` overrides
    ``profile.player.kick_rand_delta_factor`` (the golden recordings use 0 together with server kick_rand 0;
    pass such a profile as ``make_profile("v19", kick_rand=0)``).  The default seed 1 is the one the golden
    recordings were made with.
    """
    prof = _profile(profile)
    if kick_rand_delta_factor is not None:
        player = dataclasses.replace(prof.player, kick_rand_delta_factor=kick_rand_delta_factor)
        prof = dataclasses.replace(prof, player=player)
    rng = ServerRandom(seed)
    return [default_player_type(prof)] + [_reference_type(prof, rng) for _ in range(1, prof.player.player_types)]


# --------------------------------------------------------------------------------------------------
# Vectorised implementation.
#
# Of the eight deltas of a trial (spec §7.2 steps 1-8) only those with min != max are drawn; they are the rows of
# a (n_drawn, lanes) array.  Every final field and every rejection check is ``a + delta * b`` for one delta
# (with b = 1 the product is exact), the same floating-point operations as the reference, so the values are
# bit-identical to it.

_SCALAR_MAX_LANES = 1  # a trial with this few pending lanes runs on Python floats (far less overhead than numpy)


@dataclass(frozen=True)
class _Term:
    """``a + delta * b``; ``row`` is the delta's row among the drawn ones, None for a constant delta."""

    row: int | None
    a: float
    b: float
    const: float  # the value when row is None


@dataclass(frozen=True)
class _Check:
    term: _Term
    strict: bool  # reject if the value is <= 0 (strict) or < 0

    def passes(self, value: float) -> bool:
        return _passes(value, self.strict)


def _passes(value: float, strict: bool) -> bool:
    return value > 0.0 if strict else value >= 0.0


@dataclass(frozen=True)
class _Plan:
    lo: np.ndarray  # (n_drawn, 1) lower bounds of the drawn deltas
    span: np.ndarray  # (n_drawn, 1) hi - lo
    segments: tuple[tuple[int, int, tuple[_Check, ...]], ...]  # (first row, end row, checks after these draws)
    fields: tuple[_Term, ...]  # in TYPE_FIELDS order
    window: tuple[float, float, float] | None  # (max_power, player_speed_max_min - EPS, EPS), None: accept all
    default: np.ndarray  # (F,) the default type
    # for expanding: field j = a[j] + ext[src[j]] * b[j], ext = drawn deltas followed by the constant deltas
    const_rows: np.ndarray  # (n_const, 1)
    src: np.ndarray  # (F,)
    a: np.ndarray  # (F, 1)
    b: np.ndarray  # (F, 1)

    def term(self, name: str) -> _Term:
        return self.fields[_COL[name]]


@functools.lru_cache(maxsize=16)
def _make_plan(profile: ServerProfile) -> _Plan:
    s, p = profile.server, profile.player
    # step: (delta bounds, {field: (a, b)}, rejection checks (a, b, strict)) in the server's order
    stretch = (p.catchable_area_l_stretch_min, p.catchable_area_l_stretch_max)
    if not profile.catchable_area_stretch:
        stretch = (1.0, 1.0)  # no draw; the stretch stays 1
    steps = [
        ((p.player_speed_max_delta_min, p.player_speed_max_delta_max),
         {"player_speed_max": (s.player_speed_max, 1.0)},
         [(s.player_speed_max, 1.0, True), (s.stamina_inc_max, p.stamina_inc_max_delta_factor, True)]),
        ((p.player_decay_delta_min, p.player_decay_delta_max),
         {"player_decay": (s.player_decay, 1.0), "inertia_moment": (s.inertia_moment, p.inertia_moment_delta_factor)},
         [(s.player_decay, 1.0, True), (s.inertia_moment, p.inertia_moment_delta_factor, False)]),
        ((p.dash_power_rate_delta_min, p.dash_power_rate_delta_max),
         {"player_size": (s.player_size, p.player_size_delta_factor)},
         [(s.dash_power_rate, 1.0, True), (s.player_size, p.player_size_delta_factor, True)]),
        ((p.new_dash_power_rate_delta_min, p.new_dash_power_rate_delta_max),
         {"dash_power_rate": (s.dash_power_rate, 1.0),
          "stamina_inc_max": (s.stamina_inc_max, p.new_stamina_inc_max_delta_factor)},
         [(s.dash_power_rate, 1.0, True), (s.stamina_inc_max, p.new_stamina_inc_max_delta_factor, True)]),
        ((p.kickable_margin_delta_min, p.kickable_margin_delta_max),
         {"kickable_margin": (s.kickable_margin, 1.0), "kick_rand": (s.kick_rand, p.kick_rand_delta_factor)},
         [(s.kickable_margin, 1.0, True), (s.kick_rand, p.kick_rand_delta_factor, False)]),
        ((p.extra_stamina_delta_min, p.extra_stamina_delta_max),
         {"extra_stamina": (s.extra_stamina, 1.0), "effort_max": (s.effort_init, p.effort_max_delta_factor),
          "effort_min": (s.effort_min, p.effort_min_delta_factor)},
         [(s.extra_stamina, 1.0, False), (s.effort_init, p.effort_max_delta_factor, True),
          (s.effort_min, p.effort_min_delta_factor, True)]),
        ((p.kick_power_rate_delta_min, p.kick_power_rate_delta_max),
         {"kick_power_rate": (s.kick_power_rate, 1.0),
          "foul_detect_probability": (s.foul_detect_probability, p.foul_detect_probability_delta_factor)},
         []),
        (stretch, {"catchable_area_l_stretch": (0.0, 1.0)}, []),
    ]
    lo_rows: list[float] = []
    span_rows: list[float] = []
    fields: dict[str, _Term] = {}
    const_of_field: dict[str, float] = {}
    segments = []
    first = 0
    for bounds, step_fields, checks in steps:
        lo, hi = min(bounds), max(bounds)
        row = None
        ends = [lo]
        if lo != hi:
            row = len(lo_rows)
            lo_rows.append(lo)
            span_rows.append(hi - lo)
            ends.append(lo + (hi - lo))  # a drawn delta lo + (hi - lo) * u lies in [lo, this] (rounding is monotone)
        for name, (a, b) in step_fields.items():
            fields[name] = _Term(row, a, b, a + lo * b)
            const_of_field[name] = lo
        # Only checks that can fail somewhere in the delta's range need evaluating (a + d*b is monotone in d).
        live = tuple(
            _Check(_Term(row, a, b, a + lo * b), strict)
            for a, b, strict in checks
            if not all(_passes(a + d * b, strict) for d in ends)
        )
        if live:
            segments.append((first, len(lo_rows), live))
            first = len(lo_rows)
    if first < len(lo_rows) or not segments:
        segments.append((first, len(lo_rows), ()))
    window = None
    if profile.hetero_acceptance == "speed_window":
        window = (s.max_power, s.player_speed_max_min - EPS, EPS)
    terms = tuple(fields[n] for n in TYPE_FIELDS)
    const_names = [n for n in TYPE_FIELDS if fields[n].row is None]
    src = [t.row if t.row is not None else len(lo_rows) + const_names.index(n) for n, t in zip(TYPE_FIELDS, terms)]
    return _Plan(
        lo=np.array(lo_rows, dtype=np.float64).reshape(-1, 1),
        span=np.array(span_rows, dtype=np.float64).reshape(-1, 1),
        segments=tuple(segments),
        fields=terms,
        window=window,
        default=stack_player_types([default_player_type(profile)])[0],
        const_rows=np.array([const_of_field[n] for n in const_names], dtype=np.float64).reshape(-1, 1),
        src=np.array(src, dtype=np.intp),
        a=np.array([t.a for t in terms], dtype=np.float64).reshape(-1, 1),
        b=np.array([t.b for t in terms], dtype=np.float64).reshape(-1, 1),
    )


def _value(term: _Term, d: Any) -> Any:
    """The term for drawn deltas ``d`` (rows of an array, or a list of floats for one lane)."""
    if term.row is None:
        return term.const
    if term.b == 1.0:  # d * 1.0 == d exactly
        return term.a + d[term.row]
    return term.a + d[term.row] * term.b


def _accepts(plan: _Plan, d: Any) -> Any:
    """Spec §7.2 step 9 for the drawn deltas ``d`` (rows), or True without a window."""
    if plan.window is None:
        return True
    max_power, v_min, eps = plan.window
    v = (max_power * _value(plan.term("dash_power_rate"), d) * _value(plan.term("effort_max"), d)) / (
        1.0 - _value(plan.term("player_decay"), d)
    )
    return (v_min < v) & (v < _value(plan.term("player_speed_max"), d) + eps)


def _scalar_lane(plan: _Plan, uniform: Uniform, trials: int) -> list[float] | None:
    """One lane on Python floats: the drawn deltas of the first accepted trial, None after ``trials`` failures."""
    lo = plan.lo[:, 0].tolist()
    span = plan.span[:, 0].tolist()
    for _ in range(trials):
        d = [0.0] * len(lo)
        for r0, r1, checks in plan.segments:
            if r1 > r0:
                us = np.asarray(uniform(0.0, 1.0, r1 - r0), dtype=np.float64).tolist()
                for r, u in zip(range(r0, r1), us):
                    d[r] = lo[r] + span[r] * u
            if not all(c.passes(_value(c.term, d)) for c in checks):
                break
        else:
            if _accepts(plan, d):
                return d
    return None


def _draw_deltas(plan: _Plan, n_lanes: int, uniform: Uniform) -> tuple[np.ndarray, np.ndarray]:
    """Drawn deltas of ``n_lanes`` accepted types, ``(n_drawn, n_lanes)``, and the lanes that used up all trials.

    Each trial draws for the lanes still pending, segment by segment for the lanes still alive in the trial
    (one call per segment, one row of values per delta), so a single lane consumes the stream in the server's order.
    """
    nd = plan.lo.shape[0]
    deltas = np.empty((nd, n_lanes))
    if n_lanes == 1 and _SCALAR_MAX_LANES >= 1:  # the common n_sets == 1 case, without any set-up
        d = _scalar_lane(plan, uniform, MAX_TRIALS)
        if d is None:
            return deltas, np.zeros(1, dtype=np.intp)
        deltas[:, 0] = d
        return deltas, np.zeros(0, dtype=np.intp)
    pending = np.arange(n_lanes)
    for trial in range(MAX_TRIALS):
        k = pending.size
        if k == 0:
            break
        if k <= _SCALAR_MAX_LANES:
            failed = []
            for lane in pending.tolist():
                d = _scalar_lane(plan, uniform, MAX_TRIALS - trial)
                if d is None:
                    failed.append(lane)
                else:
                    deltas[:, lane] = d
            return deltas, np.array(failed, dtype=np.intp)
        d = deltas if k == n_lanes else np.empty((nd, k))  # the first trial writes in place
        alive = None  # positions (in pending) still in this trial; None = all
        for r0, r1, checks in plan.segments:
            n = k if alive is None else alive.size
            if n == 0:
                break
            if r1 > r0:
                u = np.asarray(uniform(0.0, 1.0, n * (r1 - r0)), dtype=np.float64).reshape(r1 - r0, n)
                if alive is None:
                    rows = d[r0:r1]
                    np.multiply(plan.span[r0:r1], u, out=rows)
                    rows += plan.lo[r0:r1]
                else:
                    d[r0:r1, alive] = plan.lo[r0:r1] + plan.span[r0:r1] * u
            for c in checks:
                v = _value(c.term, d if alive is None else d[:, alive])
                ok = np.broadcast_to(c.passes(v), (n,))
                alive = np.flatnonzero(ok) if alive is None else alive[ok]
        if d is not deltas:
            deltas[:, pending] = d  # lanes rejected in this trial are overwritten by a later one
        if alive is None:
            done = np.broadcast_to(_accepts(plan, d), (k,))
        else:
            done = np.zeros(k, dtype=bool)
            done[alive] = _accepts(plan, d[:, alive])
        pending = pending[~done]
    return deltas, pending


def _expand(plan: _Plan, deltas: np.ndarray, out: np.ndarray) -> None:
    """Write the types of ``deltas`` (``(n_drawn, a*b)``) into ``out`` (``(a, b, F)``)."""
    nd, n = deltas.shape
    ext = np.empty((nd + plan.const_rows.shape[0], n))
    ext[:nd] = deltas
    ext[nd:] = plan.const_rows
    block = ext[plan.src]  # field-major (F, n): contiguous rows, then one transposed copy
    block *= plan.b
    block += plan.a
    out[...] = block.T.reshape(out.shape)


def draw_type_table(profile: str | ServerProfile, n_sets: int, uniform: Uniform) -> np.ndarray:
    """Draw ``n_sets`` independent type tables: ``(n_sets, player_types, len(TYPE_FIELDS))`` float64.

    Row 0 of each set is the default type; rows 1.. follow spec §7.2 (draw order, no draw when min == max,
    swapped bounds, rejection rules, acceptance window or none, default after 1000 trials).
    ``uniform(lo, hi, n)`` returns ``n`` uniform values in [lo, hi); it is called as ``uniform(0.0, 1.0, n)`` and
    scaled here with the server's formula ``lo + (hi - lo) * u``.  With a numpy Generator ``rng``:
    ``draw_type_table("v19", 4096, lambda lo, hi, n: rng.uniform(lo, hi, n))``.

    Vectorised over sets: Python loops over trials (and types), never over sets.  With ``n_sets == 1`` the types
    are drawn one after the other and every trial takes its values from the stream in the server's order, so a
    :class:`ServerRandom` source reproduces :func:`generate_player_types` exactly.  With ``n_sets > 1`` all
    (set, type) pairs are drawn together as independent lanes (the same distribution, far fewer Python steps).
    """
    prof = _profile(profile)
    n_sets = int(n_sets)
    if n_sets < 0:
        raise ValueError(f"n_sets must be >= 0, got {n_sets}")
    n_types = prof.player.player_types
    plan = _make_plan(prof)
    default = plan.default
    table = np.empty((n_sets, n_types, default.size))
    table[:, 0] = default
    if n_types == 1 or n_sets == 0:
        return table
    if n_sets == 1:  # one type after the other, as the server
        deltas = np.empty((plan.lo.shape[0], n_types - 1))
        failed_list = []
        for t in range(n_types - 1):
            d, f = _draw_deltas(plan, 1, uniform)
            if f.size:
                failed_list.append(t)
            else:
                deltas[:, t] = d[:, 0]
        failed = np.array(failed_list, dtype=np.intp)
    else:
        deltas, failed = _draw_deltas(plan, n_sets * (n_types - 1), uniform)
    _expand(plan, deltas, table[:, 1:])
    table[failed // (n_types - 1), 1 + failed % (n_types - 1)] = default
    return table
