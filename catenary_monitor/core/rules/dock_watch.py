"""The dock estimate as the monitor makes it: at every tick, from each line's newest tension.

One decision, for the live core and its twin alike (:func:`decide_dock` takes arrays over
ticks, the core passes one, and decides them one after the other in plain floats): which
readings count (:func:`readings`), the estimate
(:func:`~catenary_monitor.core.body.estimate_tick.estimate_tick`), the ``dock`` status, and
what each line's alarm sees (:data:`LINE_INPUTS`).

A reading counts when its line has a tension no older than ``tension_timeout``, finite, above
``w h`` and plausible (:mod:`catenary_monitor.core.rules.plausible`; otherwise the line's own
status is an impossible input), and the depth is known, not stale, positive and plausible.

A line flagged at one tick is left out of the next tick's fit, until it agrees again.

One tick's normalized residual is noisy (a line within its accuracy exceeds 4 sigma once in
15 000 readings), so the decision uses each line's residual smoothed over the ticks: an
exponential average ``m <- m + lam (z - m)``, ``lam = 1 - exp(-dt / dock_residual_time)``,
divided by its own standard deviation under consistent readings (``v <- (1 - lam)^2 v +
lam^2``, exact from the first tick on, whatever the tick spacing): ``S = m / sqrt(v)`` is a
normal deviate while the line agrees with the others, and a drifting sensor's grows as
``sqrt(2 dock_residual_time / dt)`` times its per-tick deviation. A line is flagged while
``|S| > dock_residual_limit``. Ticks where the line is not tested leave its average as it was.

Each line's uplift is solved at the span the estimate gives it (:data:`SPAN_SOURCES`): the
hook's horizontal distance to its anchor with the dock at the fitted offset
(:attr:`~catenary_monitor.core.body.estimate.DockEstimate.span`), where the line was tested at
this tick and agrees with the others (its smoothed statistic within ``dock_residual_limit``);
else (no estimate, too few readings to test the line, its reading not used, the line
disagreeing) at its installed ``anchor_distance``. The estimate is made at a tick from the
lines' newest tensions; the spans it gives are taken by the lines' solves at the samples after
that tick (a tick solves nothing itself), so a solve at a tension or depth sample uses the
newest tick's estimate, in the core and in its twin alike.

When more lines disagree than :func:`most_flagged` allows (a third, at least one), the estimate
does not stand: no line is tested at that tick (none flagged, none agreeing; the spans the
installed ones), so a line is never called inconsistent by a fit that a bad line beside it
has biased (one reading off by x10 of a four-line dock flagged the three good lines; the
units check names that one).

The ``dock`` status is STALE while no estimate can be made (fewer than three readings, or no
usable depth) and OK otherwise; its message gives the offset and the load and names the lines
flagged. A line's ``inconsistent`` alarm condition (WARN) is latched in
:mod:`catenary_monitor.core.alarms.latches` (``on_delay``, ``warn_clear_hold``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.estimate import MIN_LINES, REMOVE_Z, DockEstimate, stack_ticks
from catenary_monitor.core.body.estimate_tick import TickEstimate, estimate_tick
from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.rules.plausible import MAX_DEPTH, most_flagged, reading_status

__all__ = [
    'LINE_INPUTS',
    'SPAN_SOURCES',
    'INSTALLED',
    'DOCK_ESTIMATE',
    'solve_spans',
    'span_word',
    'DOCK_KEYS',
    'TABLE_KEY',
    'DockDecision',
    'Smoothing',
    'smooth_step',
    'readings',
    'decide_dock',
    'dock_message',
    'dock_values',
    'sensor_state',
    'most_flagged',
]

#: What a line's alarm takes from the estimate (AlarmInputs fields): 1.0 flagged / 0.0 tested
#: and consistent / NaN not tested; residual and expected tension [N]; normalized residual.
LINE_INPUTS = ('inconsistent', 'dock_residual', 'dock_expected', 'dock_sigma')
#: Values of the ``catenary_monitor: dock`` status (SI; yaw in deg, REP 103).
DOCK_KEYS = ('offset_x', 'offset_y', 'yaw_deg', 'load_x', 'load_y', 'load_mz', 'readings')
#: Where a line's solve takes its span (``span_source``, the output's code is the index): the
#: installed ``anchor_distance``, or the hook's distance to its anchor in the dock estimate.
SPAN_SOURCES = ('installed', 'dock_estimate')
INSTALLED, DOCK_ESTIMATE = 0, 1
#: The dock status value, where a line has point loads, of its tables' largest span error [m]
#: (:mod:`catenary_monitor.core.physics.point_load_table`, measured when they were built).
TABLE_KEY = 'table_span_error'


class DockDecision(NamedTuple):
    """``n`` tick decisions: the estimate, per tick the level, per tick and line the inputs
    (the smoothed statistic S as ``dock_sigma``), the flags and the span each line's solves
    take after the tick (:func:`solve_spans`)."""

    estimate: DockEstimate
    level: np.ndarray  # (n,) int8 Level
    line_inputs: np.ndarray  # (n, m, 4): LINE_INPUTS
    flagged: np.ndarray  # (n, m) bool: |S| > dock_residual_limit
    span: np.ndarray  # (n, m) m, NaN: the installed anchor_distance
    #: The largest span error [m] of the point-load lines' tables (NaN: none has one).
    table_span_error: float = math.nan


class Smoothing(NamedTuple):
    """Each line's smoothed normalized residual: mean, its variance under consistency (NaN:
    no residual yet), whether it is flagged, and the time of the last tick [s] (NaN: none)."""

    mean: np.ndarray  # (m,)
    var: np.ndarray  # (m,)
    flagged: np.ndarray  # (m,) bool
    last_s: float

    @classmethod
    def initial(cls, m: int) -> 'Smoothing':
        """No residual seen yet."""
        return cls(np.zeros(m), np.full(m, math.nan), np.zeros(m, bool), math.nan)


def smooth_step(
    state: Smoothing, now: float, z: list[float], tau: float, limit: float
) -> tuple[list[float], Smoothing]:
    """One tick: the statistic S (m,) from the normalized residuals ``z`` (NaN: not tested,
    which leaves the line's average as it was) and the new state."""
    last = state.last_s
    lam = 1.0 if last != last else -math.expm1(-(now - last) / tau)
    means, variances, flagged, stat = [], [], [], []
    for zk, mean, var in zip(z, state.mean.tolist(), state.var.tolist()):
        seen = math.isfinite(zk)
        if seen and var != var:  # the first residual
            mean, var = zk, 1.0
        elif seen:
            mean, var = mean + lam * (zk - mean), (1.0 - lam) * (1.0 - lam) * var + lam * lam
        held = mean / math.sqrt(var) if var == var else math.nan
        means.append(mean)
        variances.append(var)
        flagged.append(False if var != var else abs(held) > limit)
        stat.append(held if seen else math.nan)
    new = Smoothing(np.array(means, float), np.array(variances, float), np.array(flagged), now)
    return stat, new


def readings(
    model: DockModel,
    timeout: float,
    now: float,
    depth: float,
    depth_ok: bool,
    tension: list[float],
    tension_s: list[float],
    chart: tuple[float, float] = (0.0, MAX_DEPTH),
) -> list[bool]:
    """Per line, whether its reading counts at one tick (see the module docstring): ``now`` s;
    ``depth`` m and ``depth_ok`` (known, not stale); the lines' newest ``tension`` N and its
    time ``tension_s`` s (NaN: none yet); ``chart`` the depth's chart range [m] (outside it no
    line counts)."""
    depth_good = (
        depth_ok
        and math.isfinite(depth)
        and 0.0 < depth <= MAX_DEPTH
        and chart[0] <= depth <= chart[1]
    )
    if not depth_good:
        return [False] * len(tension)
    use = []
    for t, t_s, w, hh, mbl in zip(
        tension, tension_s, model.weight.tolist(), model.hook_height.tolist(), model.mbl.tolist()
    ):
        h = depth + hh
        use.append(
            t_s == t_s
            and now - t_s <= timeout
            and math.isfinite(t)
            and t > w * h
            and reading_status(t, h, mbl) == 0
        )
    return use


class _Tick(NamedTuple):
    """One tick's decision in plain values."""

    estimate: TickEstimate
    flag: list[float]  # LINE_INPUTS' first: 1.0 flagged, 0.0 tested and consistent, NaN
    stat: list[float]  # the smoothed statistic S


def decide_dock(
    model: DockModel,
    config: MonitorConfig,
    now: np.ndarray,
    depth: np.ndarray,
    depth_ok: np.ndarray,
    tension: np.ndarray,
    tension_s: np.ndarray,
    state: Smoothing,
) -> tuple[DockDecision, Smoothing]:
    """The dock decisions at ``n`` ticks in time order, from the smoothing ``state`` before the
    first; and the state after the last. ``now`` (n,) s; ``depth`` (n,) m and ``depth_ok``
    (n,) bool (known, not stale); ``tension`` and ``tension_s`` (n, m) N and s (NaN: none yet).

    The lines flagged after one tick are left out of the next tick's fit (a bad line must not
    bias the others' residuals). So the ticks are decided one after the other, each in plain
    floats (:func:`~catenary_monitor.core.body.estimate_tick.estimate_tick`): the live core's
    one tick and replay's window of ticks go through the same code, the same bits.
    """
    n, m = tension.shape
    ticks: list[_Tick] = []
    for t_now, d, ok, t, t_s in zip(
        now.tolist(), depth.tolist(), depth_ok.tolist(), tension.tolist(), tension_s.tolist()
    ):
        tick, state = _decide_tick(model, config, t_now, d, bool(ok), t, t_s, state)
        ticks.append(tick)
    est = stack_ticks([tick.estimate for tick in ticks], n, m)
    flag = np.array([tick.flag for tick in ticks], float).reshape(n, m)
    stat = np.array([tick.stat for tick in ticks], float).reshape(n, m)
    inputs = np.stack([flag, est.residual, est.expected, stat], axis=-1)
    decision = DockDecision(
        est,
        np.array([Level.OK if v else Level.STALE for v in est.valid.tolist()], np.int8),
        inputs,
        flag == 1.0,
        solve_spans(est.span, flag),
        model.table_span_error,
    )
    return decision, state


def _decide_tick(
    model: DockModel,
    config: MonitorConfig,
    now: float,
    depth: float,
    depth_ok: bool,
    tension: list[float],
    tension_s: list[float],
    state: Smoothing,
) -> tuple[_Tick, Smoothing]:
    """One tick: the readings, the estimate (the lines flagged after the last tick left out),
    the smoothing and what each line takes from it."""
    use = readings(
        model, config.alarm.tension_timeout, now, depth, depth_ok, tension, tension_s, config.chart
    )
    limit, tau = config.dock.residual_limit, config.dock.residual_time
    h = depth if math.isfinite(depth) else 1.0
    est = estimate_tick(model, h, tension, use, state.flagged.tolist(), REMOVE_Z)
    stat, state = smooth_step(state, now, est.normalized, tau, limit)
    flag = [1.0 if abs(z) > limit else (0.0 if math.isfinite(z) else math.nan) for z in stat]
    if flag.count(1.0) > most_flagged(len(flag)):  # the estimate does not stand: none tested
        flag = [math.nan] * len(flag)
    return _Tick(est, flag, stat), state


def solve_spans(span: np.ndarray, flag: np.ndarray) -> np.ndarray:
    """The span [m] each line's solves take after a tick: the estimate's ``span`` where the
    line was tested and agrees (``flag`` 0.0, :data:`LINE_INPUTS`), else NaN (its installed
    ``anchor_distance``)."""
    return np.where((flag == 0.0) & np.isfinite(span), span, math.nan)


def span_word(source: float) -> str:
    """A ``span_source`` code's word (:data:`SPAN_SOURCES`; ``none`` for NaN)."""
    return SPAN_SOURCES[int(source)] if source in (0.0, 1.0) else 'none'


def _row(est: DockEstimate, i: int) -> DockEstimate:
    return DockEstimate(*(v[i] for v in est))


def load_from_deg(load: np.ndarray) -> float:
    """Direction the load comes from [deg, clockwise from the bow]."""
    return math.degrees(math.atan2(float(load[1]), -float(load[0]))) % 360.0


def dock_message(model: DockModel, decision: DockDecision, i: int) -> str:
    """The dock status message of tick ``i``."""
    est = _row(decision.estimate, i)
    if not est.valid:
        return (
            f'no dock estimate: {int(est.readings)} line(s) with a recent tension and a depth '
            f'(needs {MIN_LINES})'
        )
    x, y, psi = (float(v) for v in est.offset)
    text = f'offset x {x:+.2f} m, y {y:+.2f} m, yaw {math.degrees(psi):+.3f} deg'
    if np.all(np.isfinite(est.load[:2])):
        size = math.hypot(float(est.load[0]), float(est.load[1]))
        text += f'; load {size / 1e3:.0f} kN from {load_from_deg(est.load):.0f} deg'
    elif model.tables:
        text += (
            '; load not estimated (a line would be beyond its reach, or one with point loads '
            "is outside its table's depths)"
        )
    else:
        text += '; load not estimated (a line would be beyond its reach)'
    bad = [
        f'{model.names[k]} ({float(decision.line_inputs[i, k, 3]):+.1f} sigma)'
        for k in np.flatnonzero(decision.flagged[i]).tolist()
    ]
    if bad:
        text += '; disagreeing: ' + ', '.join(bad)
    return text


def dock_values(decision: DockDecision, i: int) -> tuple[tuple[str, str], ...]:
    """The dock status values of tick ``i`` (:data:`DOCK_KEYS`, strings ``float()`` reads)."""
    est = _row(decision.estimate, i)
    x, y, psi = (float(v) for v in est.offset)
    fx, fy, mz = (float(v) for v in est.load)
    numbers = (x, y, math.degrees(psi), fx, fy, mz)
    values = tuple(zip(DOCK_KEYS, [repr(v) for v in numbers] + [str(int(est.readings))]))
    error = decision.table_span_error
    return values + ((TABLE_KEY, repr(error)),) if error == error else values


def sensor_state(latched: bool, flag: float) -> str:
    """A line's ``sensor_state``: ``inconsistent`` while its alarm condition is up, ``suspect``
    when flagged but not yet for ``on_delay``, ``ok`` when tested and consistent, ``unchecked``
    when not tested (no accuracy, no reading or no estimate)."""
    if latched:
        return 'inconsistent'
    if flag == 1.0:
        return 'suspect'
    return 'ok' if flag == 0.0 else 'unchecked'
