"""The optional tide table's forecast (harmonic constituents) and the time to uplift on it.

Pure (no rclpy, no clock). The constituents are parsed by
:mod:`catenary_monitor.core.config.tide_constituents`. The params file's ``tide_table`` is a string
of constituents separated by ``;``, each ``NAME AMPLITUDE PHASE SPEED`` (m, deg, deg/h), e.g.
``"M2 1.0 112.3 28.9841042; S2 0.33 141.0 30.0"``; the predicted tide is

    P(t) = sum_i A_i cos(speed_i (t - tide_table_epoch) / 3600 s - phase_i)   [m]

about the mean level (t and the epoch in s on the monitor's clock, Unix time). With a table, a
line's ``time_to_uplift`` follows the prediction instead of the trend: the first time ``tau`` in
``(0, tide_forecast_horizon]`` at which the predicted *rise from now*, ``P(now + tau) - P(now)``,
reaches the line's ``tide_margin`` (the horizontal tension held, as for the trend), ``now`` the
newest depth sample's stamp; ``inf`` when it does not within the horizon. Only the rise enters,
so the table needs no datum: its mean level cancels, and the measured depth stays the start.

The crossing is found on a 10 min grid (the first grid point at or past the margin; a tide
constituent's period is hours, so a crossing between two grid points and back is missed only by
less than 0.4 % of its amplitude) and refined by 40 bisections (to below a microsecond). One
array function serves the core (arrays of one) and its batch twin, so both compute alike.
"""

from __future__ import annotations

import math

import numpy as np

from catenary_monitor.core.config.tide_constituents import Constituent

__all__ = ['GRID_S', 'predicted', 'uplift_times']

#: Grid step of the crossing search [s].
GRID_S = 600.0
_BISECTIONS = 40
_CHUNK = 4096  # rows of the grid search at a time (memory)


def predicted(table: tuple[Constituent, ...], t: np.ndarray, epoch: float) -> np.ndarray:
    """The predicted tide about its mean level [m] at times ``t`` [s]."""
    hours = (np.asarray(t, np.float64) - epoch) / 3600.0
    out = np.zeros(hours.shape)
    for c in table:
        out = out + c.amplitude * np.cos(np.radians(c.speed * hours - c.phase))
    return out


def uplift_times(
    table: tuple[Constituent, ...],
    epoch: float,
    horizon: float,
    now: np.ndarray,
    tide_margin: np.ndarray,
    uplift_force: np.ndarray,
) -> np.ndarray:
    """Time to uplift [s] on the table's forecast from ``now`` [s] for each margin [m]: 0 while
    lifted (margin <= 0 or uplift > 0 N), inf when the predicted rise does not reach the margin
    within ``horizon`` [s], NaN when the line is unsolved."""
    now = np.asarray(now, np.float64)
    m = np.asarray(tide_margin, np.float64)
    f = np.asarray(uplift_force, np.float64)
    with np.errstate(invalid='ignore'):
        lifted = (m <= 0.0) | (f > 0.0)
        ask = np.isfinite(m) & ~lifted & np.isfinite(now)
    out = np.where(lifted, 0.0, math.inf)
    out[np.isnan(m)] = math.nan
    idx = np.flatnonzero(ask)
    if not len(idx) or not table:
        return out
    grid = np.minimum(np.arange(1, int(math.ceil(horizon / GRID_S)) + 1) * GRID_S, horizon)
    for lo in range(0, len(idx), _CHUNK):
        rows = idx[lo : lo + _CHUNK]
        out[rows] = _crossing(table, epoch, grid, now[rows], m[rows])
    return out


def _crossing(
    table: tuple[Constituent, ...], epoch: float, grid: np.ndarray, now: np.ndarray, m: np.ndarray
) -> np.ndarray:
    """The first predicted crossing [s] (inf: none on the grid) for each (now, margin)."""
    p0 = predicted(table, now, epoch)
    rise = predicted(table, now[:, None] + grid[None, :], epoch) - p0[:, None]
    hit = rise >= m[:, None]
    found = hit.any(axis=1)
    j = np.argmax(hit, axis=1)
    hi = grid[j]
    lo = np.where(j > 0, grid[np.maximum(j - 1, 0)], 0.0)
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        up = predicted(table, now + mid, epoch) - p0 >= m
        hi = np.where(up, mid, hi)
        lo = np.where(up, lo, mid)
    return np.where(found, hi, math.inf)
