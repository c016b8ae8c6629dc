"""Chain fatigue as it happens: rainflow counting (ASTM E1049-85) streamed sample by sample, and
Miner's rule with the seed's S-N curve (seed 001, the anchor-chain fatigue section).

S-N curve, as the seed writes it: ``N (delta_sigma / 1 MPa)^m = 10^log_a`` cycles to failure at
a stress range ``delta_sigma = stress_per_tension x delta_T`` (Pa per N times the tension range,
N). Seed 001: ``m = 3.36``, ``log_a = 13.6451`` and 0.0805 MPa/kN = 80.5 Pa/N from a
finite-element model of one link of a chain of 12 421 kN breaking load (the stress difference
between 3676 and 3776 kN). Damage by Miner's linear rule ``D = sum n_i / N_i`` (failure at 1).

Counting. The four-point rainflow method on a running residue: each sample either extends the
last (tentative) turning point or makes a new one; whenever the last four turning points
``A B C D`` have ``|C - B| <= |B - A|`` and ``|C - B| <= |D - C|``, the cycle ``B C`` is closed
(one full cycle of range ``|C - B|``) and B, C leave the residue. The damage at any time is the
closed cycles' plus the residue's ranges counted as half cycles: exactly ASTM E1049-85's count
(section 5.4.4, its half cycles from the starting point included) of the whole series so far, so
it equals a whole-history count by a library (``test/test_fatigue.py``: ``rainflow``, ``fatpack``)
and never depends on how the series was cut into windows or restarts (the residue is state).
The residue is bounded (:data:`RESIDUE_MAX` turning points: beyond, its oldest range is counted
as a half cycle for good).

The damage rate is taken over the last day: a mark ``(t, D)`` at most every :data:`MARK_EVERY`
seconds, marks older than :data:`RATE_WINDOW` dropped, the rate ``(D - D_mark) / (t - t_mark)``
against the oldest mark kept, known once that spans :data:`RATE_MIN_SPAN` (NaN before). Life left
is ``(1 - D) / rate`` (s; inf at a zero rate, 0 once ``D >= 1``, NaN while the rate is unknown).

Times s, tensions N. No clock, no files: the node stores the state (its store), replay carries it.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np

from catenary_monitor.core.config.parameters import LineConfig

try:  # the per-sample loop in C (_fatigue_loop.c beside this file; else step in a Python loop)
    from catenary_monitor.core.rules import _fatigue_loop  # type: ignore[attr-defined]
except ImportError:  # not built
    _fatigue_loop = None

__all__ = [
    'FIELDS',
    'SEED_M',
    'SEED_LOG_A',
    'SEED_STRESS_PER_TENSION',
    'SEED_MBL',
    'RESIDUE_MAX',
    'MARK_EVERY',
    'RATE_WINDOW',
    'RATE_MIN_SPAN',
    'Curve',
    'FatigueState',
    'initial',
    'cycle_damage',
    'step',
    'series',
    'rate',
    'life_left',
    'to_record',
    'from_record',
]

#: The per-line outputs (appended to OUTPUT_FIELDS), /diagnostics keys and CSV columns: the
#: cumulative damage (Miner), its rate over the last day (1/s) and the life left at it (s).
FIELDS = ('fatigue_damage', 'fatigue_damage_rate', 'fatigue_life_left')
#: Seed 001's S-N curve: slope m and log10 a (delta sigma in MPa).
SEED_M = 3.36
SEED_LOG_A = 13.6451
#: Seed 001's stress per tension, 0.0805 MPa/kN in Pa/N, for its chain of :data:`SEED_MBL`.
SEED_STRESS_PER_TENSION = 80.5
SEED_MBL = 12421.0e3
#: The most turning points the residue keeps (beyond: its oldest range a half cycle for good).
RESIDUE_MAX = 512
#: A rate mark at most this often (s), kept for :data:`RATE_WINDOW` (s), the rate known once
#: the marks span :data:`RATE_MIN_SPAN` (s).
MARK_EVERY = 900.0
RATE_WINDOW = 86400.0
RATE_MIN_SPAN = 3600.0


class Curve(NamedTuple):
    """One line's S-N curve: ``m``, ``log_a`` and the stress per tension (Pa/N); samples above
    ``limit`` (N) are not counted (no mooring produces them: a sensor or scaling fault)."""

    m: float = SEED_M
    log_a: float = SEED_LOG_A
    stress_per_tension: float = SEED_STRESS_PER_TENSION
    limit: float = math.inf

    @classmethod
    def of(cls, line: LineConfig) -> Curve:
        """A line's curve (``NAME.fatigue_*``); readings above 10 x MBL are skipped (the
        monitor's impossible-input bound, core/rules/plausible.py)."""
        return cls(line.fatigue_m, line.fatigue_log_a, line.stress_per_tension, 10.0 * line.mbl)

    @property
    def scale(self) -> float:
        """MPa of stress range per N of tension range."""
        return self.stress_per_tension * 1e-6

    @property
    def inv_a(self) -> float:
        """``10^-log_a``."""
        return 10.0 ** (-self.log_a)


class FatigueState(NamedTuple):
    """A line's fatigue between samples: the damage of the closed cycles (and of residue ranges
    counted for good), the residue (turning points, the last one tentative), each turning
    point's half cycle with the one before (``halves``, 0 for the first), the sum of those but
    the last (``fixed``, kept as it changes), and the rate marks ``((t s, D), ...)``."""

    closed: float = 0.0
    residue: tuple[float, ...] = ()
    halves: tuple[float, ...] = ()
    fixed: float = 0.0
    marks: tuple[tuple[float, float], ...] = ()

    def damage(self) -> float:
        """The cumulative damage now: closed cycles plus the residue's half cycles."""
        return self.closed + self.fixed + (self.halves[-1] if self.halves else 0.0)


def initial(damage: float = 0.0) -> FatigueState:
    """The state of a line with ``damage`` already done (``NAME.fatigue_damage_initial``)."""
    return FatigueState(closed=float(damage))


def cycle_damage(tension_range: float, curve: Curve) -> float:
    """Miner's damage of one full cycle of a tension range (N): ``delta_sigma^m / 10^log_a``."""
    return float((abs(tension_range) * curve.scale) ** curve.m * curve.inv_a)


def _push(s: list[float], r: list[float], h: list[float], value: float, curve: Curve) -> None:
    """One sample into the residue ``r`` and its halves ``h``; ``s`` is ``[closed, fixed]``
    (all changed in place). The same operations, in the same order, as the C loop."""
    n = len(r)
    if n and value == r[-1]:
        return
    if n < 2 or (value - r[-1]) * (r[-1] - r[-2]) <= 0.0:
        if n:
            s[1] += h[-1]  # the last range is fixed now
        r.append(value)
        h.append(0.5 * cycle_damage(value - r[-2], curve) if n else 0.0)
    else:
        r[-1] = value  # the tentative turning point moves on
        h[-1] = 0.5 * cycle_damage(value - r[-2], curve)
    while len(r) >= 4:
        a, b, c, d = r[-4], r[-3], r[-2], r[-1]
        inner = abs(c - b)
        if not (inner <= abs(b - a) and inner <= abs(d - c)):
            break
        s[0] += cycle_damage(inner, curve)
        s[1] -= h[-3] + h[-2]
        del r[-3:-1], h[-3:-1]
        h[-1] = 0.5 * cycle_damage(d - a, curve)
    if len(r) > RESIDUE_MAX:
        s[0] += h[1]
        s[1] -= h[1]
        del r[0], h[0]
        h[0] = 0.0


def _mark(
    marks: tuple[tuple[float, float], ...], t: float, damage: float
) -> tuple[tuple[float, float], ...]:
    """The rate marks after a sample at ``t`` (s) with ``damage``."""
    if not marks or t >= marks[-1][0] + MARK_EVERY:
        marks = marks + ((t, damage),)
    k = 0
    while k < len(marks) - 1 and marks[k][0] < t - RATE_WINDOW:
        k += 1
    return marks[k:] if k else marks


def rate(state: FatigueState, t: float, damage: float) -> float:
    """The damage rate (1/s) over the last day at ``t`` (s): NaN until the marks span
    :data:`RATE_MIN_SPAN`."""
    if not state.marks:
        return math.nan
    t0, d0 = state.marks[0]
    span = t - t0
    return (damage - d0) / span if span >= RATE_MIN_SPAN else math.nan


def life_left(damage: float, rate_per_s: float) -> float:
    """Seconds until ``D = 1`` at ``rate_per_s``: 0 at ``D >= 1``, inf at a zero rate, NaN
    unknown."""
    if damage >= 1.0:
        return 0.0
    if rate_per_s != rate_per_s:
        return math.nan
    return math.inf if rate_per_s <= 0.0 else (1.0 - damage) / rate_per_s


def _usable(tension: float, limit: float) -> bool:
    """A sample the count takes: finite, not negative, not above ``limit`` (others are
    skipped)."""
    return math.isfinite(tension) and 0.0 <= tension <= limit


def step(
    state: FatigueState, t: float, tension: float, curve: Curve
) -> tuple[FatigueState, tuple[float, float, float]]:
    """One tension sample (N) at ``t`` (s): the new state and :data:`FIELDS` after it."""
    if _usable(tension, curve.limit):
        r, h = list(state.residue), list(state.halves)
        sums = [state.closed, state.fixed]
        _push(sums, r, h, float(tension), curve)
        state = FatigueState(sums[0], tuple(r), tuple(h), sums[1], state.marks)
    damage = state.damage()
    state = state._replace(marks=_mark(state.marks, t, damage))
    per_s = rate(state, t, damage)
    return state, (damage, per_s, life_left(damage, per_s))


def series(
    state: FatigueState, times: np.ndarray, tensions: np.ndarray, curve: Curve
) -> tuple[dict[str, np.ndarray], FatigueState]:
    """:func:`step` over every sample of a column (times s, tensions N): :data:`FIELDS` ->
    arrays, and the state after the last: the count's one column loop, in C where built
    (``_fatigue_loop.c``: 40 ms for the million-message replay's million samples), else
    :func:`step` in a Python loop (4.5 s there), the same bits."""
    n = len(times)
    out = {key: np.empty(n) for key in FIELDS}
    if _fatigue_loop is not None and n:
        return _series_c(state, times, tensions, curve, out)
    for i in range(n):
        state, values = step(state, float(times[i]), float(tensions[i]), curve)
        for key, v in zip(FIELDS, values):
            out[key][i] = v
    return out, state


def _series_c(
    state: FatigueState,
    times: np.ndarray,
    tensions: np.ndarray,
    curve: Curve,
    out: dict[str, np.ndarray],
) -> tuple[dict[str, np.ndarray], FatigueState]:
    """:func:`series` in C: the same operations in the same order (equal to the bit)."""
    cap = RESIDUE_MAX + 2
    residue, halves = np.zeros(cap), np.zeros(cap)
    if state.residue:
        residue[: len(state.residue)] = state.residue
        halves[: len(state.halves)] = state.halves
    marks = np.zeros((int(RATE_WINDOW // MARK_EVERY) + 3, 2))
    if state.marks:
        marks[: len(state.marks)] = state.marks
    closed, fixed, n_res, n_marks = _fatigue_loop.fatigue(
        np.ascontiguousarray(times, np.float64),
        np.ascontiguousarray(tensions, np.float64),
        curve.scale,
        curve.m,
        curve.inv_a,
        curve.limit,
        residue,
        halves,
        len(state.residue),
        marks,
        len(state.marks),
        state.closed,
        state.fixed,
        RESIDUE_MAX,
        MARK_EVERY,
        RATE_WINDOW,
        RATE_MIN_SPAN,
        out['fatigue_damage'],
        out['fatigue_damage_rate'],
        out['fatigue_life_left'],
    )
    new = FatigueState(
        float(closed),
        tuple(residue[:n_res].tolist()),
        tuple(halves[:n_res].tolist()),
        float(fixed),
        tuple((float(a), float(b)) for a, b in marks[:n_marks].tolist()),
    )
    return out, new


def to_record(state: FatigueState) -> dict[str, object]:
    """The state as JSON-able data (the store, the log's record)."""
    return {
        'damage': state.damage(),
        'closed': state.closed,
        'residue': list(state.residue),
        'marks': [list(m) for m in state.marks],
    }


def from_record(record: object, curve: Curve) -> Optional[FatigueState]:
    """The state of :func:`to_record`'s data (None when it is not one: damaged)."""
    try:
        assert isinstance(record, dict)
        closed = float(record['closed'])
        residue = tuple(float(v) for v in record['residue'])
        marks = tuple((float(a), float(b)) for a, b in record['marks'])
    except (AssertionError, KeyError, TypeError, ValueError):
        return None
    values = (closed, *residue, *(v for m in marks for v in m))
    if not all(math.isfinite(v) for v in values) or closed < 0.0 or len(residue) > RESIDUE_MAX:
        return None
    halves = tuple(
        0.5 * cycle_damage(residue[i] - residue[i - 1], curve) if i else 0.0
        for i in range(len(residue))
    )
    fixed = 0.0
    for half in halves[:-1]:
        fixed += half
    return FatigueState(closed, residue, halves, fixed, marks)
