"""Prototypes of sensor rules that know the sea still to come in the core (a design study;
not wired into the core).

The rules the core now takes are there, not here: the stuck depth gauge against the tide's
known motion, spikes beyond the stamps' bunching and the gauge's own noise, steps counted by
rounding (``catenary_monitor.core.rules.sensor_state``: ``sample_depth``, ``tide_motion``,
``decide_depth``) and the intake's warning by share and count
(``catenary_monitor.core.rules.health.intake_status``); ``test/test_sea_rules.py`` runs them
on generated normal days and faults. Pure functions on plain arrays (SI: m, N, s), each the
judgement one of the core's rules would make instead of today's (DESIGN_ALARMS.md says where
each goes and with which parameters):

* (moved into the core: inputs that fell silent together are
  ``catenary_monitor.core.rules.health.common_cause``, a flood's first out among the alarms
  still active ``catenary_monitor.core.alarms.flood.first_out``.)
* :func:`units_factor`, :func:`at_rest_tension`, :func:`units_check`: a tension off by a unit
  factor (10, 9.80665, 100, 1000, lbf...) against the line's own statics, scaled by the dock's
  common loading (the median of every line's reading over its statics).
* :func:`chart_range`: default ``depth_min``/``depth_max`` from the lines: the depth at which
  each fixed-length chain lifts its anchor at its installed span.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.physics.fixed_length import lift_depth, statics_at_span

__all__ = [
    'UNIT_FACTORS',
    'units_factor',
    'at_rest_tension',
    'units_check',
    'chart_range',
]


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
