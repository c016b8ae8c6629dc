"""A line measured by several channels: a multi-wire load cell whose channels fail one by one.

Seed 001's anchor-cable dynamometer: several vibrating-wire gauges carry the load; channels fail
in service and the load is recovered from the rest by a linear regression on their history.
Here each channel ``i`` (``NAME.tension_topics``) publishes its own reading ``c_i`` of the line
tension (N), and the line's tension is the mean of ``k_i c_i`` over the healthy channels, where
``k_i`` is the regression through the origin of the line's tension on channel ``i`` over their
shared history while every channel was healthy (``k_i = sum(T c_i) / sum(c_i^2)``, both sums
forgetting with the time constant :data:`HISTORY`; 1 before any history). A gauge that reads
5 % high on an eccentric link keeps its weight after its neighbours fail: the recovered load
stays within the remaining channels' accuracy instead of taking their bias.

A channel's state at each channel sample (:data:`STATES`, codes 0-4):

``ok``
    healthy;
``silent``
    no sample for ``tension_timeout`` (or none ``tension_timeout`` after the line's first);
``stuck``
    no change beyond ``tension_resolution`` for ``stuck_time`` while another channel moved;
    it stays stuck until its reading changes (a steady load is no excuse once it was seen);
``out_of_line``
    its estimate ``k_i c_i`` differs from the median of the usable channels' by more than
    ``channel_tolerance`` x that median + ``tension_resolution`` (with two usable channels that
    disagree, both: which one is wrong cannot be told);
``none``
    no such channel (a code's unused places).

Fewer healthy channels than ``NAME.min_channels``: the line is blind (STALE, the message says
which channels failed and why). The states go out as one number, ``channel_states``: channel
``i``'s code times ``5^i`` (five codes: ``sum(code_i 5^i)``), beside ``channels_healthy``.

Plain floats, one sample at a time: the live core and its vectorized twin run the same
:func:`step` (lines with several channels are rare; the twin loops over their samples).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, Sequence

import numpy as np

__all__ = [
    'FIELDS',
    'STATES',
    'OK',
    'SILENT',
    'STUCK',
    'OUT_OF_LINE',
    'HISTORY',
    'MAX_CHANNELS',
    'Limits',
    'ChannelState',
    'initial',
    'step',
    'run',
    'decode',
    'describe',
]

#: The per-line outputs (appended to OUTPUT_FIELDS), /diagnostics values and CSV columns.
FIELDS = ('channels_healthy', 'channel_states')
STATES = ('ok', 'silent', 'stuck', 'out_of_line', 'none')
OK, SILENT, STUCK, OUT_OF_LINE = 0, 1, 2, 3
#: Time constant of the regression's memory (s).
HISTORY = 3600.0
#: The most channels a line may have (their codes in one float64).
MAX_CHANNELS = 16


class Limits(NamedTuple):
    """The rules: timeout, stuck time, resolution (N), tolerance (fraction), min channels."""

    timeout: float
    stuck_time: float
    resolution: float
    tolerance: float
    min_channels: int


class ChannelState(NamedTuple):
    """Per channel: newest reading (N) and its time (s; NaN none), when it last changed beyond
    the resolution (s), the regression's sums ``sum(T c)`` and ``sum(c^2)``; the time of the
    last learning step (s)."""

    values: tuple[float, ...]
    times: tuple[float, ...]
    changed: tuple[float, ...]
    sum_tc: tuple[float, ...]
    sum_cc: tuple[float, ...]
    learned: float = math.nan
    started: float = math.nan  # s, the line's first sample
    stuck: tuple[bool, ...] = ()  # per channel: flagged stuck, until its reading changes


def initial(n: int) -> ChannelState:
    """A line of ``n`` channels before any sample."""
    nan = (math.nan,) * n
    return ChannelState(nan, nan, nan, (0.0,) * n, (0.0,) * n, stuck=(False,) * n)


def _ratio(state: ChannelState, i: int) -> float:
    return state.sum_tc[i] / state.sum_cc[i] if state.sum_cc[i] > 0.0 else 1.0


def _median(values: list[float]) -> float:
    s = sorted(values)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def step(
    state: ChannelState, channel: int, t: float, value: float, limits: Limits
) -> tuple[ChannelState, float, int, float]:
    """One sample ``value`` (N) of ``channel`` at ``t`` (s): the new state, the line's tension
    (NaN while blind; the mean of the healthy channels' estimates), the healthy count and the
    ``channel_states`` code."""
    n = len(state.values)
    values, times, changed = list(state.values), list(state.times), list(state.changed)
    stuck = list(state.stuck)
    started = t if state.started != state.started else state.started
    if math.isfinite(value):
        old = values[channel]
        if not (abs(value - old) <= limits.resolution):  # (a first sample: NaN, a change)
            changed[channel], stuck[channel] = t, False
        values[channel], times[channel] = value, t
    codes = [OK] * n
    for i in range(n):
        late = times[i] != times[i] and t - started <= limits.timeout  # not yet, but soon
        if not (t - times[i] <= limits.timeout) and not late:
            codes[i] = SILENT
    moving = [i for i in range(n) if codes[i] == OK and t - changed[i] < limits.stuck_time]
    for i in range(n):
        if codes[i] == OK and moving and i not in moving and t - changed[i] >= limits.stuck_time:
            stuck[i] = True
        if codes[i] == OK and (stuck[i] or times[i] != times[i]):
            codes[i] = STUCK if stuck[i] else codes[i]
    ratios = [_ratio(state, i) for i in range(n)]
    usable = [i for i in range(n) if codes[i] == OK and times[i] == times[i]]
    if len(usable) >= 2:
        estimates = {i: ratios[i] * values[i] for i in usable}
        mid = _median(list(estimates.values()))
        for i in usable:
            if abs(estimates[i] - mid) > limits.tolerance * abs(mid) + limits.resolution:
                codes[i] = OUT_OF_LINE
    healthy = [i for i in range(n) if codes[i] == OK and times[i] == times[i]]
    fused = math.nan
    if healthy and len(healthy) >= limits.min_channels:
        fused = sum(ratios[i] * values[i] for i in healthy) / len(healthy)
    new = ChannelState(
        tuple(values),
        tuple(times),
        tuple(changed),
        state.sum_tc,
        state.sum_cc,
        state.learned,
        started,
        tuple(stuck),
    )
    if len(healthy) == n and n > 1:  # every channel healthy: the regression learns
        new = _learn(new, t, fused)
    code = float(sum(c * 5**i for i, c in enumerate(codes)))
    return new, fused, len(healthy), code


def run(
    state: ChannelState, idx: Any, times: Any, values: Any, limits: Limits
) -> tuple[ChannelState, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`step` over a line's channel samples merged in time order (channel ``idx``, time
    ``times`` s, reading ``values`` N): the state after them and, per sample, the tension, the
    healthy count and the ``channel_states`` code (the replay twin and ``whatif --log``)."""
    n = len(values)
    fused, healthy, codes = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        state, fused[i], count, codes[i] = step(
            state, int(idx[i]), float(times[i]), float(values[i]), limits
        )
        healthy[i] = count
    return state, fused, healthy, codes


def _learn(state: ChannelState, t: float, tension: float) -> ChannelState:
    """The regression's sums with this sample (forgetting with :data:`HISTORY`)."""
    keep = 1.0 if state.learned != state.learned else math.exp(-(t - state.learned) / HISTORY)
    keep = min(keep, 1.0)
    tc = tuple(keep * s + tension * c for s, c in zip(state.sum_tc, state.values))
    cc = tuple(keep * s + c * c for s, c in zip(state.sum_cc, state.values))
    return state._replace(sum_tc=tc, sum_cc=cc, learned=t)


def decode(code: float, n: int) -> list[int]:
    """The per-channel codes of a ``channel_states`` number (``n`` channels)."""
    c = int(code)
    out = []
    for _ in range(n):
        out.append(c % 5)
        c //= 5
    return out


def describe(code: float, names: Sequence[str]) -> str:
    """The failed channels in words: ``ch_b silent, ch_c out_of_line`` ('' when none)."""
    if code != code:
        return ''
    codes = decode(code, len(names))
    return ', '.join(f'{name} {STATES[c]}' for name, c in zip(names, codes) if c != OK)
