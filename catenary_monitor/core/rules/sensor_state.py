"""Sensor sanity, apart from load alarms: each line's ``sensor_state`` and the depth sensor's.

Pure (no rclpy, no clock). Two parts, each with a scalar path (the core) and an array path (its
batch twin) that share the arithmetic, so live and replay decide alike:

* **per sample** (:func:`sample`, :func:`samples`; the depth: :func:`sample_depth`): what a
  sensor's readings remember: the newest finite reading and its stamp, when it last *changed*:
  moved to another step of the resolution (``round(x / resolution)``: a gauge's readings lie
  on its grid, where ``floor``'s bin edges would be; ``tension_resolution`` N,
  ``depth_resolution`` m; a reading drifting at rate r changes at least every resolution / r)
  than the reading before; when it last *spiked*: a step ``|dx| > rate_max * (dt + jitter) +
  resolution`` between consecutive finite readings (a rate of change no chain and no tide can
  have; ``stamp_jitter`` for every input type: delivery bunches arrival stamps, a driver's
  double read its header stamps), for the depth plus ``spike_noise_k`` x sqrt(2) x the
  gauge's own noise. The depth memory keeps what the stuck rule needs of the sea too
  (:class:`DepthMemory`). Non-finite readings are not remembered.
* **per tick** (:func:`decide_lines`, :func:`decide_depth`): the states, decided at every tick
  (``diagnostic_rate``) from the newest readings, in this precedence (the first that holds):

  ======================  =====  ===================================================
  line state (code)       level  pattern
  ======================  =====  ===================================================
  ``over_mbl`` (3)        ERROR  newest tension > MBL
  ``suspected_parted``    ERROR  tension fell below ``(1 - parted_drop)`` x its value
  (5)                            ``parted_window`` ago to at or below w * h (what a
                                 chain parted below the hook reads; the other lines
                                 need not rise: a pretensioned dock's opposite lines
                                 slacken); held while the tension stays at or below
                                 w * h, and ``sensor_hold`` after last seen
  ``slack`` (4)           ERROR  tension <= w * h (the hanging chain's own weight at
                                 the depth at the hook)
  ``wrong_units_x10``     ERROR  the reading off by a unit factor against the line's
  ... (7-19)             input  statics, judged while the dock is calm
                                 (:func:`~catenary_monitor.core.rules.plausible.
                                 units_decide`); the ``input`` condition's, not a
                                 sensor condition's
  ``bad_stamp`` (6)       WARN   a sample refused for its header stamp (ahead of the
                                 monitor's clock by ``stamp_ahead_max``, or before
                                 the one before) within ``sensor_hold``
  ``spike`` (2)           WARN   a spiked sample within ``sensor_hold``
  ``stuck`` (1)           WARN   no change beyond the resolution for ``stuck_time``
                                 while the dock moves (another line or the depth
                                 changed since), the sensor still reporting
  ``ok`` (0)              OK
  ======================  =====  ===================================================

  The depth sensor: ``out_of_range`` (ERROR, depth outside ``[depth_min, depth_max]``, the
  chart range), ``bad_stamp`` (WARN, as a line's), ``spike`` (WARN, within ``sensor_hold``),
  ``stuck`` (WARN, still while the sea is known to have moved ``depth_stuck_steps``
  resolutions since its last step: :func:`decide_depth`, :func:`tide_motion`; never against
  the lines, which move with every wave), ``ok``.
"""

from __future__ import annotations

import math
from typing import Any, Callable, NamedTuple

import numpy as np

from catenary_monitor.core.rules.plausible import UNIT_FACTORS
from catenary_monitor.core.rules.tide_table import predicted


def _unit_word(factor: float) -> str:
    """``x10``, ``x9.81``, ``x4448``, ``div10``: a unit factor in a state word."""
    f, word = (factor, 'x') if factor >= 1.0 else (1.0 / factor, 'div')
    return f'{word}{f:.3g}' if f < 100.0 else f'{word}{f:.0f}'


__all__ = [
    'UNITS_BASE',
    'is_units',
    'LINE_STATES',
    'DEPTH_STATES',
    'NO_DATA',
    'OK',
    'STUCK',
    'SPIKE',
    'OVER_MBL',
    'SLACK',
    'PARTED',
    'OUT_OF_RANGE',
    'BAD_STAMP',
    'DEPTH_BAD_STAMP',
    'ERROR_STATES',
    'Memory',
    'DepthMemory',
    'SeaColumns',
    'sample_depth',
    'depth_samples',
    'sea_columns',
    'tide_motion',
    'LineLimits',
    'sample',
    'samples',
    'parted_pattern',
    'slack_mask',
    'parted_others',
    'firm_times',
    'decide_lines',
    'with_units',
    'decide_depth',
    'reference',
    'history_row',
    'line_word',
    'line_message',
    'depth_message',
]

#: The first ``wrong_units`` state's code: ``UNITS_BASE + i`` a reading off by
#: :data:`~catenary_monitor.core.rules.plausible.UNIT_FACTORS` ``[i]`` (an ``input`` ERROR);
#: the last two: far below / above the statics, the factor unsure (``wrong_units_low``,
#: ``wrong_units_high``: :data:`~catenary_monitor.core.rules.plausible.UNSURE_LOW`).
UNITS_BASE = 7
#: Line states by code (the ``sensor_state`` output field is the code, /diagnostics the word).
LINE_STATES = (
    'ok',
    'stuck',
    'spike',
    'over_mbl',
    'slack',
    'suspected_parted',
    'bad_stamp',
) + tuple(f'wrong_units_{_unit_word(f)}' for f, _ in UNIT_FACTORS) + (
    'wrong_units_low',
    'wrong_units_high',
)
OK, STUCK, SPIKE, OVER_MBL, SLACK, PARTED, BAD_STAMP = range(7)
#: Depth sensor states by code.
DEPTH_STATES = ('ok', 'stuck', 'spike', 'out_of_range', 'bad_stamp')
OUT_OF_RANGE = 3
DEPTH_BAD_STAMP = 4
#: The depth sensor's ``sensor_state`` word before its first sample (no state to decide yet).
NO_DATA = 'no_data'
#: Line states that are an ERROR (the others but ``ok`` are WARN).
ERROR_STATES = (OVER_MBL, SLACK, PARTED)
_NEVER = -math.inf
#: The message of ``bad_stamp`` (``what``: tension or depth).
BAD_STAMP_TEXT = (
    '{what} samples refused for their header stamps (ahead of the monitor\'s clock by more '
    'than stamp_ahead_max, or going backwards): check the sensor computer\'s clock '
    'synchronization (chrony, PTP) and its driver\'s stamping'
)


class Memory(NamedTuple):
    """One sensor's per-sample memory: newest finite reading and its stamp [s], when it last
    changed beyond the resolution [s] and when it last spiked [s] (-inf: never)."""

    value: float = math.nan
    stamp: float = math.nan
    changed: float = _NEVER
    spiked: float = _NEVER


class LineLimits(NamedTuple):
    """Per-line constants of the tick decision (arrays over lines): MBL [N], weight in water
    per metre [N/m], hook height [m]."""

    mbl: np.ndarray
    weight: np.ndarray
    hook_height: np.ndarray


def sample(
    mem: Memory, stamp: float, value: float, resolution: float, rate: float, jitter: float
) -> Memory:
    """The memory after one reading ``value`` at ``stamp`` [s]; ``rate`` the largest credible
    rate of change [unit/s], ``jitter`` how far off a stamp may be [s]."""
    if not math.isfinite(value):
        return mem
    d = abs(value - mem.value)
    changed = stamp if _step_one(mem.value, value, resolution) else mem.changed
    spiked = stamp if d > rate * (stamp - mem.stamp + jitter) + resolution else mem.spiked
    return Memory(value, stamp, changed, spiked)


def _step_one(before: float, after: float, resolution: float) -> bool:
    """Whether a reading is on another step of the resolution than the one before
    (``round(x / resolution)``: a gauge's readings lie on its grid, where ``floor``'s bin edges
    are, and a float's last bit would put neighbouring steps in one bin; a resolution of 0:
    another value; no reading before: yes), in plain floats (:func:`samples` takes the same
    test on columns)."""
    if not resolution > 0.0:
        return not after == before
    a, b = after / resolution, before / resolution
    if a != a or b != b:  # no reading before (NaN): round(NaN) equals nothing
        return True
    if math.isinf(a) or math.isinf(b):  # round(inf) is inf
        return not a == b
    return round(a) != round(b)


def samples(
    mem: Memory,
    stamps: np.ndarray,
    values: np.ndarray,
    resolution: float,
    rate: float,
    jitter: float,
) -> tuple[np.ndarray, np.ndarray, Memory]:
    """:func:`sample` over sorted readings: ``changed`` and ``spiked`` [s] after each, and the
    memory after the last.

    The sensor memory's one column loop (:func:`sample` is its reference), numpy and no C: on
    the million-message replay (a million readings; 1.3 s in all) these passes take 28 ms, a C
    loop took 4.6 ms, and without a compiler its fallback, :func:`sample` in a Python loop,
    would take 8 s."""
    n = len(values)
    if n == 0:
        return np.zeros(0), np.zeros(0), mem
    values = np.ascontiguousarray(values, np.float64)
    stamps = np.ascontiguousarray(stamps, np.float64)
    good = np.isfinite(values)
    every = bool(good.all())
    idx = None if every else np.flatnonzero(good)
    # the memory's reading first, then the finite readings (one pass per quantity)
    vv = _after(mem.value, values if idx is None else values[idx])
    tt = _after(mem.stamp, stamps if idx is None else stamps[idx])
    with np.errstate(invalid='ignore', divide='ignore'):
        d = np.abs(np.diff(vv))
        if resolution > 0.0:
            q = np.round(vv / resolution)
            change = ~(q[1:] == q[:-1])
        else:
            change = ~(vv[1:] == vv[:-1])
        spike = d > rate * (np.diff(tt) + jitter) + resolution
    ch = _after(mem.changed, np.where(change, tt[1:], _NEVER))
    sp = _after(mem.spiked, np.where(spike, tt[1:], _NEVER))
    np.maximum.accumulate(ch, out=ch)
    np.maximum.accumulate(sp, out=sp)
    final = mem
    if len(vv) > 1:
        final = Memory(float(vv[-1]), float(tt[-1]), float(ch[-1]), float(sp[-1]))
    if every:
        return ch[1:], sp[1:], final
    at = np.cumsum(good)  # position in ch / sp after each reading (0: the memory's)
    return ch[at], sp[at], final


def _after(first: float, rest: np.ndarray) -> np.ndarray:
    """``[first, *rest]`` as a new float64 array."""
    out = np.empty(len(rest) + 1)
    out[0] = first
    out[1:] = rest
    return out


def _moved_since(changed: np.ndarray, depth_changed: np.ndarray) -> np.ndarray:
    """Per (tick, line): another line's or the depth's last change is newer than the line's.

    The other lines' newest change is the row's newest, or for the line holding it (the first
    of equal ones) the newest of the rest: two reductions per row, not one per line."""
    n, lines = changed.shape
    if lines > 1:
        top = changed.argmax(axis=1)  # the first NaN where there is one: np.max gives NaN
        rows = np.arange(n)
        rest = changed.copy()
        rest[rows, top] = _NEVER
        newest = np.repeat(changed[rows, top][:, None], lines, axis=1)
        newest[rows, top] = rest.max(axis=1)
    else:
        newest = np.full((n, lines), _NEVER)
    with np.errstate(invalid='ignore'):
        return np.maximum(newest, depth_changed[:, None]) > changed


def parted_pattern(
    tension: np.ndarray, ref: np.ndarray, drop: float, slack: np.ndarray
) -> np.ndarray:
    """Per (tick, line): the tension fell below ``(1 - drop)`` x its reference to at or below
    the hanging chain's own weight (``slack``, :func:`slack_mask`; NaN references: no), and not
    below 0 (the rest of a parted chain still hangs from the hook: a negative force is the
    cell's or its zero's, an impossible input)."""
    with np.errstate(invalid='ignore'):
        return (tension < (1.0 - drop) * ref) & slack & (tension >= 0.0)


def slack_mask(limits: LineLimits, tension: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Per (tick, line): the tension [N] at or below the hanging chain's own weight ``w h`` at
    the depth [m] (per tick) at the hook (an unknown depth: no)."""
    h = depth[:, None] + limits.hook_height[None, :]
    with np.errstate(invalid='ignore'):
        return np.isfinite(h) & (h > 0) & (tension <= limits.weight * h)


def parted_others(codes: np.ndarray) -> np.ndarray:
    """Per (tick, line) of line state codes (:func:`decide_lines`): the index of another line
    suspected parted at that tick (the lowest), NaN none (float)."""
    codes = np.atleast_2d(codes)
    ticks, n = codes.shape
    parted = codes == PARTED
    out = np.full((ticks, n), math.nan)
    if not parted.any():
        return out
    rows = np.arange(ticks)
    first = np.argmax(parted, axis=1)
    rest = parted.copy()
    rest[rows, first] = False
    second = np.where(rest.any(axis=1), np.argmax(rest, axis=1), -1)
    one = parted.any(axis=1)
    lines = np.arange(n)[None, :]
    pick = np.where(lines != first[:, None], first[:, None], second[:, None])
    return np.where(one[:, None] & (pick >= 0), pick.astype(np.float64), math.nan)


def firm_times(now: np.ndarray, slack: np.ndarray, before: np.ndarray) -> np.ndarray:
    """Per (tick, line): when the line was last above ``w h`` at a tick [s] (``before``: as
    before the first tick, per line)."""
    at = np.where(slack, -math.inf, now[:, None])
    return np.maximum.accumulate(np.vstack([before[None, :], at]), axis=0)[1:]


def decide_lines(
    cfg: object,
    limits: LineLimits,
    now: np.ndarray,
    tension: np.ndarray,
    tension_s: np.ndarray,
    changed: np.ndarray,
    spiked: np.ndarray,
    parted_seen: np.ndarray,
    depth: np.ndarray,
    depth_changed: np.ndarray,
    refused: np.ndarray | None = None,
    firm: np.ndarray | None = None,
    units: np.ndarray | None = None,
) -> np.ndarray:
    """Line state codes (int8, shape (ticks, lines)) at ticks ``now`` [s] from each line's
    newest tension [N] and its stamp [s], its memory's ``changed`` and ``spiked`` [s], when
    the parted pattern was last seen [s], the newest depth [m] and the depth's ``changed``,
    when a sample's stamp was last refused [s] (None: never) and when the line was last above
    ``w h`` at a tick (:func:`firm_times`; None: the parted state only ``sensor_hold`` long)
    and the unit factor each line is claimed off by
    (:func:`~catenary_monitor.core.rules.plausible.units_latch`; -1 or None: none).
    ``cfg`` is the :class:`~catenary_monitor.core.config.parameters.AlarmConfig`."""
    t_now = now[:, None]
    hold = getattr(cfg, 'sensor_hold')
    slack = slack_mask(limits, tension, depth)
    with np.errstate(invalid='ignore'):
        reporting = np.isfinite(tension) & (t_now - tension_s <= getattr(cfg, 'tension_timeout'))
        over = tension > limits.mbl
        spike = t_now - spiked <= hold
        parted = t_now - parted_seen <= hold
        if firm is not None:
            parted |= slack & (parted_seen > firm)  # slack ever since it parted
        quiet = t_now - changed >= getattr(cfg, 'stuck_time')
    stuck = reporting & quiet & _moved_since(changed, depth_changed)
    code = np.full(tension.shape, OK, np.int8)
    for mask, c in ((stuck, STUCK), (spike, SPIKE), (slack, SLACK), (parted, PARTED)):
        code[mask] = c
    if refused is not None:
        with np.errstate(invalid='ignore'):
            code[(t_now - refused <= hold) & ~(over | slack | parted)] = BAD_STAMP
    code[over] = OVER_MBL
    return code if units is None else with_units(code, units)


def with_units(code: np.ndarray, units: np.ndarray) -> np.ndarray:
    """Line state codes (:func:`decide_lines`) with the ``wrong_units`` claims (the index of
    the unit factor per (tick, line), -1: none): a claim outranks every state but the ERROR
    ones (over MBL, suspected parted, slack). Decided after the dock estimate, whose expected
    tensions are one of its witnesses (:func:`~catenary_monitor.core.rules.plausible.
    units_decide`)."""
    wrong = (units >= 0) & ~np.isin(code, ERROR_STATES)
    return np.where(wrong, UNITS_BASE + units, code).astype(np.int8)


#: Semidiurnal (M2) angular speed [rad/s]: a tide of amplitude A bends at most A x this^2.
M2_OMEGA = 2.0 * math.pi / (12.4206012 * 3600.0)
#: Without a table, before a day of readings: the most a tide bends [m/s^2], an M2 tide of 3 m
#: amplitude (a range of 6 m; few docks see more).
DEFAULT_BEND = 3.0 * M2_OMEGA**2
#: Hours of readings whose range (x 1.5, as an M2 tide) bounds the tide's bend without a table.
SEEN_HOURS = 25
#: Grid [s] on which the table's forecast range since the gauge's last step is taken.
FORECAST_GRID = 60.0
#: The noise estimate (mean absolute successive difference) x this is 1 sigma x sqrt(2):
#: ``sqrt(pi) / 2 x sqrt(2)`` (white noise: E|x1 - x2| = 2 sigma / sqrt(pi)).
NOISE_DIFF_SIGMA2 = math.sqrt(math.pi / 2.0)


class DepthMemory(NamedTuple):
    """The depth sensor's per-sample memory: :class:`Memory`'s four fields, then what the sea
    rules need: the smallest nonzero step between consecutive readings (the gauge's own
    quantum) [m], the readings' noise (an exponentially weighted mean absolute successive
    difference) [m], the tide trend's rate at the last step [m/s] (NaN: unknown), and the
    readings' extremes per hour, ``(hour, lo, hi)`` over the last :data:`SEEN_HOURS` hours
    (spiked readings enter none of these)."""

    value: float = math.nan
    stamp: float = math.nan
    changed: float = _NEVER
    spiked: float = _NEVER
    quantum: float = math.inf
    noise: float = 0.0
    rate: float = math.nan
    hours: tuple[tuple[float, float, float], ...] = ()


class SeaColumns(NamedTuple):
    """What the stuck rule knows of the sea at each tick (arrays over ticks), from the depth
    memory: the gauge's own quantum [m] (inf: no step yet), the trend's rate at its last step
    [m/s], the range its readings spanned over the last day [m] and whether they span a whole
    day (``seen_day``: then the range bounds the tide's bend)."""

    quantum: np.ndarray
    rate: np.ndarray
    seen: np.ndarray
    seen_day: np.ndarray


def sample_depth(
    mem: DepthMemory,
    stamp: float,
    value: float,
    cfg: object,
    trend_rate: float,
    jitter: float,
) -> DepthMemory:
    """The depth memory after one reading ``value`` [m] at ``stamp`` [s]; ``trend_rate`` the
    tide trend's rate after it [m/s] and ``jitter`` how far off a stamp may be [s].

    A spike is a jump beyond ``depth_rate_max`` x (dt + jitter) + ``depth_resolution`` +
    ``spike_noise_k`` x sqrt(2) x the readings' own noise (1 sigma, from the memory's
    estimate: its time constant ``spike_noise_time``): a noisy gauge's double read a few ms
    apart is no spike, a glitch of metres still is."""
    if not math.isfinite(value):
        return mem
    c: Any = cfg
    resolution = c.depth_resolution
    dt = stamp - mem.stamp
    d = abs(value - mem.value)
    noise = c.spike_noise_k * NOISE_DIFF_SIGMA2 * mem.noise
    spike = d > c.depth_rate_max * (dt + jitter) + resolution + noise
    step = _step_one(mem.value, value, resolution)
    quantum, level, hours = mem.quantum, mem.noise, mem.hours
    if not spike:
        if 0.0 < d < quantum:
            quantum = d
        if dt > 0.0 and d == d:
            level += -math.expm1(-dt / c.spike_noise_time) * (d - level)
        hours = _hours(hours, stamp, value)
    return DepthMemory(
        value,
        stamp,
        stamp if step else mem.changed,
        stamp if spike else mem.spiked,
        quantum,
        level,
        trend_rate if step else mem.rate,
        hours,
    )


def _getter(cfg: object) -> Callable[[str], Any]:
    """``cfg``'s parameters by name (``cfg``: the
    :class:`~catenary_monitor.core.config.parameters.AlarmConfig`)."""
    return lambda name: getattr(cfg, name)


def _hours(
    hours: tuple[tuple[float, float, float], ...], stamp: float, value: float
) -> tuple[tuple[float, float, float], ...]:
    """The per-hour extremes after a reading (the last :data:`SEEN_HOURS` hours kept)."""
    hour = float(math.floor(stamp / 3600.0))
    if hours and hours[-1][0] == hour:
        _, lo, hi = hours[-1]
        if lo <= value <= hi:
            return hours
        return hours[:-1] + ((hour, min(lo, value), max(hi, value)),)
    keep = tuple(h for h in hours if h[0] > hour - SEEN_HOURS)
    return keep + ((hour, value, value),)


def sea_columns(mems: list[DepthMemory]) -> tuple[np.ndarray, np.ndarray, SeaColumns]:
    """The depth memories' ``changed`` and ``spiked`` [s] and :class:`SeaColumns`, one per
    memory (the core: its one memory; the twin: the memory at each tick)."""
    n = len(mems)
    changed, spiked = np.empty(n), np.empty(n)
    quantum, rate, seen = np.empty(n), np.empty(n), np.empty(n)
    day = np.zeros(n, bool)
    last: Any = None
    span, whole = 0.0, False
    for i, m in enumerate(mems):
        changed[i], spiked[i], quantum[i], rate[i] = m.changed, m.spiked, m.quantum, m.rate
        if m.hours is not last:  # memories in a row mostly share their hours
            last = m.hours
            span, whole = _hours_seen(last)
        seen[i], day[i] = span, whole
    return changed, spiked, SeaColumns(quantum, rate, seen, day)


def _hours_seen(hours: tuple[tuple[float, float, float], ...]) -> tuple[float, bool]:
    """The range [m] the per-hour extremes span, and whether they span :data:`SEEN_HOURS`."""
    if not hours:
        return 0.0, False
    top, bottom, whole = _hours_top(hours)
    return top - bottom, whole


def _hours_top(hours: tuple[tuple[float, float, float], ...]) -> tuple[float, float, bool]:
    """The highest and lowest of (non-empty) per-hour extremes [m], and whether they span
    :data:`SEEN_HOURS`."""
    top, bottom = max(h[2] for h in hours), min(h[1] for h in hours)
    return top, bottom, hours[0][0] <= hours[-1][0] - (SEEN_HOURS - 1)


def depth_samples(
    mem: DepthMemory,
    stamps: list[float],
    values: list[float],
    cfg: object,
    rates: list[float],
    jitter: float,
) -> tuple[tuple[np.ndarray, np.ndarray, SeaColumns], DepthMemory]:
    """:func:`sample_depth` over a window's readings (``stamps`` [s], ``values`` [m], the
    trend's ``rates`` [m/s] after each) and :func:`sea_columns` of the memories: before the
    readings (row 0), then after each; and the memory after the last.

    The same arithmetic as :func:`sample_depth`, in one loop of local floats (the twin's
    depth: :func:`sample_depth` and a memory per reading took 0.3 s of CPU on a 3e6-message
    replay's 24804 depth readings)."""
    c: Any = cfg
    resolution, rate_max, tau = c.depth_resolution, c.depth_rate_max, c.spike_noise_time
    noise_k = c.spike_noise_k * NOISE_DIFF_SIGMA2
    value, stamp, changed, spiked, quantum, level, rate, hours = mem
    span, whole = _hours_seen(hours)
    top, bottom, _ = _hours_top(hours) if hours else (0.0, 0.0, False)
    rows = [(changed, spiked, quantum, rate, span)]
    days = [whole]
    took = False
    for t, v, r in zip(stamps, values, rates):
        if math.isfinite(v):
            took = True
            dt = t - stamp
            d = abs(v - value)
            spike = d > rate_max * (dt + jitter) + resolution + noise_k * level
            if _step_one(value, v, resolution):
                changed, rate = t, r
            if spike:
                spiked = t
            else:
                if 0.0 < d < quantum:
                    quantum = d
                if dt > 0.0 and d == d:
                    level += -math.expm1(-dt / tau) * (d - level)
                hour = float(math.floor(t / 3600.0))
                if hours and hours[-1][0] == hour:  # the hour's extremes, and all hours'
                    _, lo, hi = hours[-1]
                    if not lo <= v <= hi:
                        hours = hours[:-1] + ((hour, min(lo, v), max(hi, v)),)
                        top, bottom = max(top, v), min(bottom, v)
                        span = top - bottom
                else:
                    hours = _hours(hours, t, v)
                    top, bottom, whole = _hours_top(hours)
                    span = top - bottom
            value, stamp = v, t
        rows.append((changed, spiked, quantum, rate, span))
        days.append(whole)
    if took:
        mem = DepthMemory(value, stamp, changed, spiked, quantum, level, rate, hours)
    out = np.array(rows, np.float64).T
    day = np.array(days, bool)
    return (out[0], out[1], SeaColumns(out[2], out[3], out[4], day)), mem


def tide_motion(
    cfg: object,
    changed: np.ndarray,
    now: np.ndarray,
    sea: SeaColumns,
    ask: np.ndarray,
    floor: np.ndarray,
) -> np.ndarray:
    """The least the sea must have moved [m] between each ``changed`` and ``now`` [s] (0
    where not ``ask``; with a table, 0 too where even its fastest rise would not exceed
    ``floor`` [m]: no forecast taken).

    With a tide table: the range of its forecast over the interval (every
    :data:`FORECAST_GRID` s, and at ``now``) less what a surge the table does not hold may
    have undone (``depth_residual_rate`` x the time). Without one: from the trend's rate at
    the last step r and the most the tide can bend a (an M2 tide 1.5 x the range the gauge saw
    over a day; :data:`DEFAULT_BEND` before a day), ``max(0, r' tau - a tau^2 / 2)``,
    ``r' = |r| - a W / 2`` (the trend is the mean rate over its window W, half a window
    late), ``tau`` at most ``r' / a`` (where the bent sea would turn); 0 where the rate is
    unknown. Either never falls as ``now`` goes on: once the sea must have moved, a gauge
    that has not stepped since stays stuck until it steps."""
    g = _getter(cfg)
    tau = now - changed
    out = np.zeros(len(now))
    table = g('constituents')
    if table:
        speed = sum(abs(c.amplitude) * math.radians(abs(c.speed)) / 3600.0 for c in table)
        with np.errstate(invalid='ignore'):
            ask = ask & np.isfinite(changed) & (tau > 0.0) & (tau * speed > floor)
        epoch, residual = g('tide_table_epoch'), g('depth_residual_rate')
        for c in np.unique(changed[ask]).tolist():
            idx = np.flatnonzero(ask & (changed == c))
            nows = now[idx]
            grid = np.arange(c, float(nows.max()), FORECAST_GRID)
            pg = predicted(table, grid, epoch)
            pn = predicted(table, nows, epoch)
            hi, lo = np.maximum.accumulate(pg), np.minimum.accumulate(pg)
            # at each grid point: the forecast's range so far less the surge's allowance; the
            # most of it since the step (once the sea must have moved, the gauge should have)
            sofar = np.maximum.accumulate((hi - lo) - residual * (grid - c))
            k = np.searchsorted(grid, nows, 'left') - 1  # the grid's points before now
            top, bottom = np.maximum(hi[k], pn), np.minimum(lo[k], pn)
            out[idx] = np.maximum(sofar[k], (top - bottom) - residual * (nows - c))
        return np.maximum(out, 0.0)
    bend = np.where(sea.seen_day, 0.75 * sea.seen * M2_OMEGA**2, DEFAULT_BEND)
    r = np.maximum(np.abs(sea.rate) - 0.5 * bend * g('tide_trend_window'), 0.0)
    with np.errstate(invalid='ignore'):
        tau = np.minimum(tau, r / bend)  # the most since the step: the sea turns at r / a
        motion = np.maximum(r * tau - 0.5 * bend * tau * tau, 0.0)
    return np.where(ask & np.isfinite(motion), motion, 0.0)


def decide_depth(
    cfg: object,
    now: np.ndarray,
    depth: np.ndarray,
    depth_s: np.ndarray,
    mem_changed: np.ndarray,
    mem_spiked: np.ndarray,
    sea: SeaColumns,
    refused: np.ndarray | None = None,
    chart: tuple[float, float] | None = None,
) -> np.ndarray:
    """Depth sensor state codes (int8 per tick) from the newest depth [m] and its stamp [s],
    the depth memory's ``changed`` and ``spiked`` [s], what it knows of the sea
    (:class:`SeaColumns`), when a depth sample's stamp was last refused [s] (None: never) and
    the chart range [m] (None: ``cfg``'s ``depth_min``, ``depth_max``; the monitor passes
    :attr:`~catenary_monitor.core.config.parameters.MonitorConfig.chart`).

    Stuck: still reporting, no step for ``stuck_time``, and the sea known to have moved more
    than ``depth_stuck_steps`` x the resolution (``depth_resolution`` or the gauge's own
    quantum, the larger) since its last step (:func:`tide_motion`); or no step for
    ``depth_still_max`` on a gauge that has seen 10 resolutions of tide over the last day
    (no tide rests that long). The lines' motion never enters: they move with every wave."""
    g = _getter(cfg)
    lo, hi = _chart(cfg, chart)
    res_cfg = g('depth_resolution')
    with np.errstate(invalid='ignore'):
        reporting = np.isfinite(depth) & (now - depth_s <= g('depth_timeout'))
        out = reporting & ((depth < lo) | (depth > hi))
        spike = now - mem_spiked <= g('sensor_hold')
        tau = now - mem_changed
        quiet = reporting & (tau >= g('stuck_time'))
        res = np.where(sea.quantum < math.inf, np.maximum(sea.quantum, res_cfg), res_cfg)
        need = g('depth_stuck_steps') * res
        moved = tide_motion(cfg, mem_changed, now, sea, quiet, need) > need
        still = (tau >= g('depth_still_max')) & (sea.seen >= 10.0 * res)
    stuck = quiet & (moved | still)
    code = np.full(len(now), OK, np.int8)
    code[stuck] = STUCK
    code[spike] = SPIKE
    if refused is not None:
        with np.errstate(invalid='ignore'):
            code[now - refused <= g('sensor_hold')] = DEPTH_BAD_STAMP
    code[out] = OUT_OF_RANGE
    return code


def line_message(code: int, tension: float, mbl: float) -> str:
    """What a line's sensor state tells the operator to check (empty for ``ok``)."""
    kn = f'{tension / 1e3:.1f} kN'
    return {
        STUCK: f'tension sensor stuck at {kn} while the dock moves: check the load cell, its '
        'cable and the amplifier',
        SPIKE: 'tension sensor spike (a change no chain can make): check the load cell cable '
        'and connector, electrical noise, the amplifier',
        OVER_MBL: f'tension {kn} above the MBL {mbl / 1e3:.0f} kN: check the chain at once '
        '(about to part?) and the sensor calibration',
        SLACK: f'tension {kn} at or below the hanging chain\'s own weight: slack or parted line '
        'or failed sensor: check the chain, the stopper and the load cell',
        PARTED: f'suspected parted chain: tension collapsed to {kn}, at or below the hanging '
        'chain\'s own weight: check the chain and the anchor at once',
        BAD_STAMP: BAD_STAMP_TEXT.format(what='tension'),
    }.get(int(code), '')


def _chart(cfg: object, chart: tuple[float, float] | None) -> tuple[float, float]:
    """``chart``, else ``cfg``'s ``(depth_min, depth_max)``."""
    return chart if chart is not None else (getattr(cfg, 'depth_min'), getattr(cfg, 'depth_max'))


def depth_message(
    code: int, depth: float, cfg: object, chart: tuple[float, float] | None = None
) -> str:
    """What the depth sensor's state tells the operator to check (empty for ``ok``; ``chart``
    as :func:`decide_depth`'s)."""
    lo, hi = _chart(cfg, chart)
    return {
        STUCK: f'depth sensor stuck at {depth:.2f} m while the tide moves: check the tide '
        'gauge and its cable',
        SPIKE: 'depth sensor spike (a change no tide makes): check the tide gauge, its cable '
        'and electrical noise',
        OUT_OF_RANGE: f'impossible depth {depth:.2f} m (chart {lo:.4g}-{hi:.4g} m): the gauge\'s '
        'datum, scale or the sensor; no line is solved on it',
        DEPTH_BAD_STAMP: BAD_STAMP_TEXT.format(what='depth'),
    }.get(int(code), '')


def reference(
    times: np.ndarray, rows: np.ndarray, now: np.ndarray, window: float
) -> tuple[np.ndarray, int]:
    """Each tick's reference tensions (rows of the newest tick at or before ``now - window``;
    NaN where none) from the tick history ``times`` [s] / ``rows`` (ticks, lines), and the first
    history row still needed after the last tick."""
    idx = np.searchsorted(times, now - window, 'right') - 1
    lines = rows.shape[1]
    ref = np.full((len(now), lines), math.nan)
    have = idx >= 0
    if len(rows):
        ref[have] = rows[idx[have]]
    keep = int(idx[-1]) if len(idx) and idx[-1] >= 0 else 0
    return ref, keep


def history_row(
    now: np.ndarray, tension: np.ndarray, spiked: np.ndarray, hold: float
) -> np.ndarray:
    """The tick's tensions as a later reference of the parted test: NaN where the line's
    reading spiked within ``hold`` (a spike is no reference)."""
    with np.errstate(invalid='ignore'):
        return np.where(now[:, None] - spiked <= hold, math.nan, tension)


def is_units(code: float) -> bool:
    """Whether a line state code is a ``wrong_units`` one (an ``input`` ERROR)."""
    return code >= UNITS_BASE


def line_word(code: int, dock: str = '') -> str:
    """A line's ``sensor_state`` word in /diagnostics: its own state unless ``ok``, then the
    dock model's (``inconsistent``, ``suspect``, ``ok`` or ``unchecked``) where there is one."""
    if code != OK or not dock:
        return LINE_STATES[int(code)]
    return dock
