"""Each line's wave-frequency tension: the peak and half-range of its readings over a window.

A floating dock's hooks move with the waves (periods of seconds), and the chain's tension swings
with them. The quasi-static solve of one reading does not see the anchor's dynamic force: the
chain's inertia and drag make the force at the anchor lag and overshoot the hook's (the MoorDyn
study, docs/dynamics.md). The monitor therefore keeps, per line, the readings of the last
``wave_window`` seconds and derives at every reading:

``peak_tension`` (N)
    the largest reading in the window (the newest included);
``wave_tension`` (N)
    half the window's range, ``(max - min) / 2``: the wave-frequency tension amplitude.

The dynamic uplift and the bounds take ``peak_tension + wave_allowance x wave_tension``
(:mod:`catenary_monitor.core.rules.uncertainty`). Only finite readings above 0 and within the
plausible bound (:data:`~catenary_monitor.core.rules.plausible.MAX_TENSION_PER_MBL` x MBL)
enter the window: an impossible reading has its own alarm and must not inflate the swing.

Why a window of extremes, not a spectrum or a running mean: the maximum and the minimum are
exact in any order of evaluation, so the core (one reading at a time, :func:`step`) and its
vectorized twin (:func:`series`, a sparse table of range extremes) give the same bits; a
window a few wave periods long (30 s by default for 7-12 s waves) holds the peak of the last
waves, so the bound covers the phase lag between hook and anchor. NaN while the window holds no
valid reading.
"""

from __future__ import annotations

import math
from collections import deque
from typing import NamedTuple

import numpy as np

from catenary_monitor.core.rules.plausible import MAX_TENSION_PER_MBL

try:  # the column loop in C (_wave_loop.c beside this file; else a sparse table in numpy)
    from catenary_monitor.core.rules import _wave_loop  # type: ignore[attr-defined]
except ImportError:  # not built
    _wave_loop = None

__all__ = ['FIELDS', 'WaveState', 'valid', 'step', 'series']

#: The outputs derived from the window (appended to the per-line outputs), in order.
FIELDS = ('wave_tension', 'peak_tension')


class WaveState(NamedTuple):
    """The window as two monotone queues of ``(stamp [s], reading [N], number)``, oldest first:
    the readings no later one reaches (``high``, decreasing: its first is the window's maximum)
    and the readings no later one undercuts (``low``, increasing: its first is the minimum);
    ``number``: valid readings so far (a reading's number orders readings of one stamp). Each
    reading enters and leaves each queue once, so a step costs O(1) however fast the sensor."""

    high: deque[tuple[float, float, int]]
    low: deque[tuple[float, float, int]]
    number: list[int]

    @classmethod
    def empty(cls) -> WaveState:
        """No reading yet."""
        return cls(deque(), deque(), [0])


def valid(tension: np.ndarray, mbl: float) -> np.ndarray:
    """Which readings enter the window: finite, above 0, within the plausible bound."""
    with np.errstate(invalid='ignore'):
        return np.isfinite(tension) & (tension > 0.0) & (tension <= MAX_TENSION_PER_MBL * mbl)


def _push(state: WaveState, now: float, tension: float) -> None:
    high, low = state.high, state.low
    entry = (now, tension, state.number[0])
    state.number[0] += 1
    while high and high[-1][1] <= tension:
        high.pop()
    high.append(entry)
    while low and low[-1][1] >= tension:
        low.pop()
    low.append(entry)


def step(
    state: WaveState, now: float, tension: float, mbl: float, window: float
) -> tuple[float, float]:
    """One reading [N] at ``now`` [s] (``state`` updated in place): ``peak_tension`` and
    ``wave_tension`` [N] over the valid readings at or after ``now - window``."""
    if math.isfinite(tension) and 0.0 < tension <= MAX_TENSION_PER_MBL * mbl:  # valid()
        _push(state, now, tension)
    start = now - window
    for queue in (state.high, state.low):
        while queue and queue[0][0] < start:
            queue.popleft()
    if not state.high:
        return math.nan, math.nan
    peak, low = state.high[0][1], state.low[0][1]
    return peak, (peak - low) * 0.5


def _range_extremes(
    x: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Max and min (NaN ignored) of ``x[lo[i] : hi[i] + 1]`` for every i (a sparse table:
    log2 of the longest range passes of ``np.fmax`` / ``np.fmin``)."""
    length = hi - lo + 1
    longest = int(length.max()) if len(length) else 1
    top, bottom = [x], [x]
    level = 1
    while 2 * level <= longest:
        prev_t, prev_b = top[-1], bottom[-1]
        top.append(np.fmax(prev_t[:-level], prev_t[level:]))
        bottom.append(np.fmin(prev_b[:-level], prev_b[level:]))
        level *= 2
    k = np.floor(np.log2(np.maximum(length, 1))).astype(np.int64)
    k = np.minimum(k, len(top) - 1)
    peak, low = np.empty(len(lo)), np.empty(len(lo))
    for j in np.unique(k).tolist():
        at = np.flatnonzero(k == j)
        right = hi[at] - (1 << j) + 1
        peak[at] = np.fmax(top[j][lo[at]], top[j][right])
        low[at] = np.fmin(bottom[j][lo[at]], bottom[j][right])
    return peak, low


def series(
    state: WaveState, t_s: np.ndarray, tension: np.ndarray, mbl: float, window: float
) -> tuple[np.ndarray, np.ndarray, WaveState]:
    """:func:`step` over sorted readings in vectorized code: ``peak_tension`` and
    ``wave_tension`` [N] after each, and the state after the last. The window's extremes by
    two monotone queues in C (``_wave_loop.c``: one pass), else by a sparse table in numpy
    (log2 of the window's readings passes): the same numbers."""
    n = len(t_s)
    if n == 0:
        return np.zeros(0), np.zeros(0), state
    ok = valid(tension, mbl)
    # The window before: the queues' readings stand for every older one in the window (a
    # reading a queue dropped is never an extreme again).
    carried = sorted(set(state.high) | set(state.low), key=lambda e: e[2])
    times = np.concatenate([np.array([e[0] for e in carried], np.float64), t_s])
    before = np.array([e[1] for e in carried], np.float64)
    values = np.concatenate([before, np.where(ok, tension, np.nan)])
    m = len(carried)
    lo = np.searchsorted(times, t_s[-1:] - window, 'left')  # the last reading's window
    if _wave_loop is not None:  # two monotone queues in C, one pass
        peak, low = np.empty(n), np.empty(n)
        _wave_loop.extremes(times, values, m, float(window), peak, low)
    else:  # a sparse table in numpy: the same maxima and minima
        peak, low = _range_extremes(
            values, np.searchsorted(times, t_s - window, 'left'), np.arange(m, m + n)
        )
    wave = (peak - low) * 0.5
    # The queues after the last reading: rebuilt from the window's readings (numbered as the
    # core numbered them), the same entries as pushing them one by one.
    numbers = np.concatenate(
        [np.array([e[2] for e in carried], np.int64), state.number[0] + np.cumsum(ok) - 1]
    )
    keep = np.flatnonzero(~np.isnan(values[lo[-1] :])) + lo[-1]
    v = values[keep]
    # a queue keeps a reading no later one reaches (high: strictly above every later one; low:
    # strictly below), which pushing them one by one leaves
    above = v > np.append(np.maximum.accumulate(v[::-1])[::-1][1:], -np.inf)
    below = v < np.append(np.minimum.accumulate(v[::-1])[::-1][1:], np.inf)
    entries = list(zip(times[keep].tolist(), v.tolist(), numbers[keep].tolist()))
    final = WaveState(
        deque(e for e, up in zip(entries, above.tolist()) if up),
        deque(e for e, down in zip(entries, below.tolist()) if down),
        [state.number[0] + int(ok.sum())],
    )
    return peak, wave, final
