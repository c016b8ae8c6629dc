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
* :func:`units_factor`, :func:`units_check`: a tension off by a unit factor (10, 9.80665, 100,
  1000, lbf...) against the line's own statics, scaled by the dock's common loading; now the
  core's (``core/rules/plausible.py``), called from here.
* :func:`chart_range`: default ``depth_min``/``depth_max`` from the lines; now the core's
  (``MonitorConfig.chart``).
"""

from __future__ import annotations

import math
from typing import Any, Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.config.parameters import chart_range as chart_from_lines
from catenary_monitor.core.config.tide_constituents import Constituent
from catenary_monitor.core.rules import plausible
from catenary_monitor.core.rules.tide_table import predicted

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
#: each with the mistake it names: the core's (:data:`catenary_monitor.core.rules.plausible.
#: UNIT_FACTORS`).
UNIT_FACTORS = dict(plausible.UNIT_FACTORS)


def units_factor(ratio: float, tolerance: float = 0.4, far: float = 3.0) -> Optional[float]:
    """The unit factor a tension is off by, from ``ratio`` = expected / reading (None: no
    claim): the core's :func:`catenary_monitor.core.rules.plausible.units_factor`."""
    k = plausible.units_factor(ratio, tolerance, far)
    return plausible.UNIT_FACTORS[k][0] if k >= 0 else None


def units_check(
    config: MonitorConfig, tensions: np.ndarray, depth: float
) -> list[Optional[float]]:
    """Per line, the unit factor its tension [N, as configured] is off by (None: fits), from
    one window's median readings, as the core judges a tick
    (:func:`catenary_monitor.core.rules.plausible.units_ratios`: each line against its own
    at-rest statics scaled by the dock's common loading; the calm gate left out)."""
    table = plausible.rest_table(config, config.chart)
    ratio, _ = plausible.units_ratios(
        table, np.array([depth]), np.asarray(tensions, np.float64)[None, :]
    )
    return [units_factor(float(r)) for r in ratio[0]]


def chart_range(config: MonitorConfig) -> tuple[float, float]:
    """Default ``(depth_min, depth_max)`` [m] from the lines: the core's
    :func:`catenary_monitor.core.config.parameters.chart_range`."""
    return chart_from_lines(config.lines)
