"""Prototypes of sensor rules that know the sea (a design study; not wired into the core).

Pure functions on plain arrays (SI: m, N, s), each the judgement one of the core's sensor rules
would make instead of today's (DESIGN_ALARMS.md says where each goes and with which
parameters). ``test/test_sea_rules.py`` runs them on generated normal days and faults
(:mod:`catenary_monitor_study.normal_days`).

* :func:`stuck_gauge`: a tide gauge is stuck only when the tide must have moved it: the motion
  the tide is known to make since the gauge's last step (the table's forecast, else the rate
  the trend had at that step, less the most the tide can bend) exceeds ``steps`` of the
  gauge's resolution. Never from the lines' wave motion; never at slack water.
* :func:`spike_threshold` and :func:`noise_estimate`: a jump is a spike only beyond what the
  rate limit allows over the stamps' interval (bunching counted for every message type), plus
  the resolution, plus ``k`` times the reading's own noise.
* :func:`intake_level`: a loss the operator must act on, by share and by count.
* :func:`common_silence`: inputs that fell silent together (their last samples within
  ``together`` s), one group per cause.
* :func:`first_out`: a flood's first-out among the alarms still active.
* :func:`units_factor`, :func:`at_rest_tension`, :func:`units_check`: a tension off by a unit
  factor (10, 9.80665, 100, 1000, lbf...) against the line's own statics, scaled by the dock's
  common loading (the median of every line's reading over its statics).
* :func:`chart_range`: default ``depth_min``/``depth_max`` from the lines: the depth at which
  each fixed-length chain lifts its anchor at its installed span.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.config.tide_constituents import Constituent
from catenary_monitor.core.rules.tide_table import predicted
from catenary_monitor.core.physics.fixed_length import lift_depth, statics_at_span

__all__ = [
    'stuck_gauge',
    'last_steps',
    'hidden_steps',
    'tide_motion',
    'accel_bound',
    'spike_threshold',
    'noise_estimate',
    'intake_level',
    'common_silence',
    'first_out',
    'UNIT_FACTORS',
    'units_factor',
    'at_rest_tension',
    'units_check',
    'chart_range',
]

#: Steps of the resolution the tide must have crossed before a still gauge is stuck.
STUCK_STEPS = 3.0
#: The most the weather's residual (a surge, not in the tide table) moves the sea [m/s]: 7 cm/h.
RESIDUAL_RATE = 2e-5
#: No tide rests this long [s] within a gauge's step (slack water within 1 cm lasts under an
#: hour at the ports of the normal days; a diurnal tide of 0.1 m, about two).
STILL_MAX = 3 * 3600.0
#: Semidiurnal angular speed [rad/s] (M2): the tide's acceleration is at most amplitude x this^2.
M2_OMEGA = 2 * math.pi / (12.4206012 * 3600.0)


def tide_motion(
    changed: np.ndarray,
    now: np.ndarray,
    table: Sequence[Constituent] = (),
    epoch: float = 0.0,
    rate: Any = math.nan,
    accel: float = 0.0,
    residual_rate: float = RESIDUAL_RATE,
    trend_window: float = 1200.0,
    grid: float = 60.0,
) -> np.ndarray:
    """The least the sea must have moved [m] between each ``changed`` and ``now`` [s].

    With a ``table``: the range of its forecast over the interval (every ``grid`` s) less what
    the weather's residual (not in the table: a surge, at most ``residual_rate`` m/s) may have
    undone. Without one: from ``rate`` [m/s], the trend at ``changed`` (residual included), and
    ``accel`` [m/s^2], the most the sea can bend: ``max(0, r tau - accel tau^2 / 2)`` with
    ``tau = now - changed`` and ``r = |rate| - accel trend_window / 2`` (the trend is the mean
    rate over its window, half a window late; 0 where the rate is unknown).
    """
    changed = np.asarray(changed, np.float64)
    now = np.asarray(now, np.float64)
    tau = np.maximum(now - changed, 0.0)
    if table:
        out = np.zeros(len(tau))
        for i in range(len(tau)):
            if tau[i] <= 0.0 or not math.isfinite(changed[i]):
                continue
            t = np.append(np.arange(changed[i], now[i], grid), now[i])
            p = predicted(tuple(table), t, epoch)
            out[i] = max(float(np.ptp(p)) - residual_rate * tau[i], 0.0)
        return out
    r = np.abs(np.asarray(rate, np.float64) * np.ones(len(tau))) - 0.5 * accel * trend_window
    with np.errstate(invalid='ignore'):
        motion = np.maximum(r * tau - 0.5 * accel * tau * tau, 0.0)
    return np.where(np.isfinite(motion), motion, 0.0)


def accel_bound(table: Sequence[Constituent] = (), amplitude: float = 3.0) -> float:
    """The most the tide can bend [m/s^2]: the table's ``sum A w^2``, else an M2 tide of
    ``amplitude`` m (3 m: a range of 6 m, few docks see more)."""
    if table:
        return float(sum(c.amplitude * math.radians(c.speed / 3600.0) ** 2 for c in table))
    return amplitude * M2_OMEGA**2


def stuck_gauge(
    changed: np.ndarray,
    now: np.ndarray,
    resolution: float,
    table: Sequence[Constituent] = (),
    epoch: float = 0.0,
    rate: Any = math.nan,
    accel: Optional[float] = None,
    steps: float = STUCK_STEPS,
    reporting: Any = True,
    seen_range: Any = 0.0,
    still_max: float = STILL_MAX,
) -> np.ndarray:
    """Whether the gauge is stuck at each ``now`` [s]: still reporting, its last step beyond
    the ``resolution`` [m] at ``changed`` [s], and the sea known to have moved more than
    ``steps`` resolutions since (:func:`tide_motion`; ``rate`` the trend at ``changed``); or,
    without that knowledge (no table, a still gauge since slack water), no step for
    ``still_max`` s on a gauge that has seen the tide move (``seen_range``, its readings' range
    over the last day, at least 10 resolutions): no tide rests that long. Without a table the
    sea bends at most as an M2 tide 1.5 times the range seen (``accel``: :func:`accel_bound`)."""
    seen = float(np.max(seen_range))
    if accel is None:
        # the table's, else an M2 tide spanning what the gauge has seen (x1.5)
        accel = accel_bound(table) if table or not seen else 0.75 * seen * M2_OMEGA**2
    res = max(resolution, 1e-6)
    motion = tide_motion(changed, now, table, epoch, rate, accel)
    still = (np.asarray(now) - np.asarray(changed) >= still_max) & (
        np.asarray(seen_range) >= 10.0 * res
    )
    return np.asarray(reporting, bool) & ((motion > steps * res) | still)


def last_steps(stamps: np.ndarray, values: np.ndarray, resolution: float) -> np.ndarray:
    """The time [s] of each reading's last step of ``resolution`` (``round(x / res)``
    changed), as the core's sensor memory keeps it. ``round``, not today's ``floor``: a
    gauge's readings lie on its resolution's grid, where floor's bin edges are, so a float's
    last bit (a Range's float32 taken from the gauge height) puts two neighbouring steps in
    one bin and hides the step (:func:`hidden_steps`)."""
    q = np.round(np.asarray(values) / resolution) if resolution > 0 else np.asarray(values)
    change = np.concatenate([[True], q[1:] != q[:-1]])
    at = np.where(change, stamps, -np.inf)
    return np.maximum.accumulate(at)


def hidden_steps(values: np.ndarray, resolution: float) -> tuple[int, int]:
    """How many changes between consecutive readings ``floor(x / res)`` and ``round(x / res)``
    miss (today's binning and the proposed one)."""
    v = np.asarray(values, np.float64)
    moved = np.diff(v) != 0
    floor = np.diff(np.floor(v / resolution)) == 0
    near = np.diff(np.round(v / resolution)) == 0
    return int(np.sum(moved & floor)), int(np.sum(moved & near))


def spike_threshold(
    dt: Any, rate_max: float, resolution: float, jitter: float, noise: Any, k: float = 5.0
) -> Any:
    """The largest jump [unit] between readings ``dt`` s apart that is no spike:
    ``rate_max (dt + jitter) + resolution + k sqrt(2) noise`` (``jitter`` for every message
    type: a driver's stamps bunch too; ``noise`` the reading's own, :func:`noise_estimate`)."""
    return rate_max * (np.asarray(dt) + jitter) + resolution + k * math.sqrt(2.0) * noise


def noise_estimate(values: np.ndarray) -> float:
    """The readings' white noise [unit, 1 sigma]: the median absolute successive difference
    x 1.4826 / sqrt(2) (a slow tide and a rare spike do not move it)."""
    d = np.diff(np.asarray(values, np.float64))
    if not len(d):
        return 0.0
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / math.sqrt(2.0))


def intake_level(
    dropped: int, total: int, share_warn: float = 0.01, count_warn: int = 10
) -> int:
    """0 OK, 1 WARN: samples lost in the intake window that an operator must act on: at least
    ``share_warn`` of them AND at least ``count_warn`` (a single lost datagram is counted in
    the status's values, never annunciated)."""
    share = dropped / total if total else 0.0
    return int(dropped >= count_warn and share >= share_warn)


def common_silence(
    last: np.ndarray, now: float, timeout: float, together: float = 1.0
) -> list[list[int]]:
    """The inputs silent at ``now`` (``now - last > timeout``), grouped by cause: inputs whose
    last samples [s] lie within ``together`` s of the group's first silent one fell silent
    together (a gateway, a network, a power supply). Groups of two or more are a common
    cause; a group of one keeps its own alarm."""
    last = np.asarray(last, np.float64)
    silent = np.flatnonzero(~(now - last <= timeout))
    order = silent[np.argsort(last[silent], kind='stable')]
    groups: list[list[int]] = []
    for i in order.tolist():
        if groups and abs(last[i] - last[groups[-1][0]]) <= together:
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def first_out(
    raises: Sequence[tuple[float, str]], active: Sequence[str]
) -> Optional[tuple[float, str]]:
    """A flood's first-out: the earliest raise (time, alarm) of its window whose alarm is still
    active when the flood begins (a returned one, e.g. the start-up wait, is no cause)."""
    live = set(active)
    for t, alarm in sorted(raises):
        if alarm in live:
            return t, alarm
    return None


#: Factors a tension reading can be off by (the true tension / the reading as configured),
#: each with the mistake it names.
UNIT_FACTORS = {
    10.0: 'daN read as N (x10)',
    9.80665: 'kgf read as N, or tonnes-force read as kN (x9.81)',
    100.0: 'x100 (hN, or a gain)',
    1000.0: 'kN read as N (x1000)',
    4.4482216: 'lbf read as N (x4.45)',
    4448.2216: 'kip read as N, or lbf read as mN (x4448)',
    0.1: 'N read as daN (/10)',
    0.101972: 'N read as kgf, or kN read as tonnes-force (/9.81)',
    0.001: 'N read as kN (/1000)',
}


def units_factor(ratio: float, tolerance: float = 0.4, far: float = 3.0) -> Optional[float]:
    """The unit factor a tension is off by, from ``ratio`` = expected / reading: None while the
    ratio is within ``far`` of 1 (a dock's lines differ, a storm loads some: no claim), else
    the factor of :data:`UNIT_FACTORS` within ``tolerance`` (relative, on the log scale) of it
    (the nearest; 10 and 9.81 are 2 % apart: the nearer is named, both are listed)."""
    if not (math.isfinite(ratio) and ratio > 0.0) or abs(math.log(ratio)) < math.log(far):
        return None
    best = min(UNIT_FACTORS, key=lambda k: abs(math.log(ratio / k)))
    return best if abs(math.log(ratio / best)) <= math.log1p(tolerance) else None


def at_rest_tension(config: MonitorConfig, depth: float) -> np.ndarray:
    """Each line's hook tension [N] at ``depth`` with the dock at rest: its fixed-length chain
    at the installed span (NaN for a line without ``chain_length``)."""
    w = np.array([line.weight for line in config.lines])
    h = depth + np.array([line.hook_height for line in config.lines])
    length = np.array([line.chain_length for line in config.lines], np.float64)
    span = np.array([line.anchor_distance for line in config.lines])
    ea = np.array([math.inf if not line.ea else line.ea for line in config.lines])
    return np.asarray(statics_at_span(w, h, length, span, ea).top_tension, np.float64)


def units_check(
    config: MonitorConfig, tensions: np.ndarray, depth: float
) -> list[Optional[float]]:
    """Per line, the unit factor its tension [N, as configured] is off by (None: fits), from
    one window's median readings: each line against its own at-rest statics scaled by the
    dock's common loading, the median over the lines of reading / statics (a calm dock: 1; a
    line in the wrong unit is one of many, so the median ignores it)."""
    rest = at_rest_tension(config, depth)
    t = np.asarray(tensions, np.float64)
    with np.errstate(invalid='ignore', divide='ignore'):
        load = np.nanmedian(t / rest) if np.any(np.isfinite(rest)) else math.nan
        ratio = rest * load / t
    return [units_factor(float(r)) for r in ratio]


def chart_range(
    config: MonitorConfig, low: float = 0.5, high: float = 1.25
) -> tuple[float, float]:
    """Default ``(depth_min, depth_max)`` [m] from the lines: ``low`` x the shallowest and
    ``high`` x the deepest depth at which a fixed-length chain lifts its anchor at its
    installed span (the depths the dock was laid for lie below those; a gauge reading half of
    them or a quarter more is a datum, scale or sensor fault). ``(0, 12000)`` without chain
    lengths."""
    lines = [line for line in config.lines if line.chain_length == line.chain_length]
    if not lines:
        return 0.0, 12000.0
    lift = lift_depth(
        np.array([line.weight for line in lines]),
        np.array([line.chain_length for line in lines]),
        np.array([line.anchor_distance for line in lines]),
    ) - np.array([line.hook_height for line in lines])
    return float(low * np.nanmin(lift)), float(high * np.nanmax(lift))
