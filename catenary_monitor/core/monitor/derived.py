"""What the core adds to a solve: each line's derived values.

:func:`add_derived` completes freshly solved lines: their fatigue and channels' values, the
wave values and the dynamic uplift, the bounds within the sensors' accuracy
(:mod:`catenary_monitor.core.rules.uncertainty`), the holding values
(:mod:`catenary_monitor.core.rules.holding`) and the time to uplift
(:mod:`catenary_monitor.core.rules.tide_trend`, :mod:`catenary_monitor.core.rules.tide_table`).
:func:`derived_values`, :func:`bound_values` and :func:`holding_values` are the same on arrays,
the core's and its vectorized twin's; :func:`holding_one` one line in plain floats.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig
from catenary_monitor.core.monitor.state import (
    VALUE_INDEX,
    LineState,
    set_channels,
    with_fatigue,
)
from catenary_monitor.core.physics.point_loads import PointLoads
from catenary_monitor.core.rules import holding as holding_rule
from catenary_monitor.core.rules import tide_table, tide_trend, uncertainty, wave_window
from catenary_monitor.core.rules.tide_trend import TrendState

__all__ = [
    'HOLDING_FIELDS',
    'add_derived',
    'uplift_times',
    'derived_values',
    'bound_values',
    'holding_values',
    'holding_one',
    'derived_one',
]

_NAN = math.nan


def _column(cfgs: Sequence[LineConfig], key: str) -> np.ndarray:
    """One line constant per config as floats (None: NaN, ``ea`` None: inf)."""
    none = math.inf if key == 'ea' else math.nan
    return np.array([none if getattr(c, key) is None else getattr(c, key) for c in cfgs])


def _span(cfgs: Sequence[LineConfig], named: dict[str, np.ndarray]) -> np.ndarray:
    """Per element, the span [m] the values were solved at (``named['span']``), the line's
    installed ``anchor_distance`` where it is not given (NaN)."""
    installed = _column(cfgs, 'anchor_distance')
    if 'span' not in named:
        return installed
    span = np.asarray(named['span'], dtype=float)
    return np.where(np.isnan(span), installed, span)


def _given_span(lc: LineConfig, span: float) -> float:
    """:func:`_span` of one line in plain floats."""
    return lc.anchor_distance if span != span else span


def _wants_holding(c: LineConfig) -> bool:
    """Whether a line has holding values: a chain length or an anchor holding."""
    return c.chain_length is not None or c.anchor_holding is not None


#: The values :func:`holding_values` gives (core/rules/holding.py).
HOLDING_FIELDS = holding_rule.FIELDS + holding_rule.LENGTH_FIELDS + holding_rule.DRAG_FIELDS


def derived_values(
    cfgs: Sequence[LineConfig], alarm: Any, named: dict[str, np.ndarray], holding: bool = True
) -> dict[str, np.ndarray]:
    """What the core adds to a solve (the core and its batch twin both call this), per element
    of the nominal values ``named`` (VALUE_FIELDS -> arrays, with ``peak_tension`` and
    ``wave_tension`` from the wave window; ``span`` the span solved at, else the installed
    one), each element's line in ``cfgs`` (one config for all, or one per element): the wave
    values, ``dynamic_uplift``, the bounds (:mod:`catenary_monitor.core.rules.uncertainty`)
    and, with ``holding``, the holding values (:mod:`~catenary_monitor.core.rules.holding`;
    NaN for lines with neither ``chain_length`` nor ``anchor_holding``), all at that span."""
    n = len(named['top_tension'])
    out = {key: np.asarray(named[key], dtype=float) for key in wave_window.FIELDS}
    tension = uncertainty.dynamic_tension(
        named['peak_tension'], named['wave_tension'], alarm.wave_allowance
    )
    out.update(bound_values(cfgs, alarm.depth_accuracy, dict(named, top_tension=tension), True))
    if any(c.point_loads is not None for c in cfgs):  # with its clumps and buoys
        _loaded_bounds(cfgs, alarm.depth_accuracy, dict(named, top_tension=tension), out)
    if not holding:
        return out
    if len(cfgs) == 1 and _wants_holding(cfgs[0]):  # one line for every element (the twin)
        out.update(holding_values(cfgs, named, alarm.drag_tolerance))
    elif len(cfgs) == 1:  # none: one read-only NaN each, no memory per element
        out.update({key: np.broadcast_to(np.float64(np.nan), (n,)) for key in HOLDING_FIELDS})
    else:
        raise ValueError('derived_values: the holding of several lines is the core\'s')
    return out


def _loaded_bounds(
    cfgs: Sequence[LineConfig],
    depth_accuracy: float,
    named: dict[str, np.ndarray],
    out: dict[str, np.ndarray],
) -> None:
    """The bounds and dynamic uplift in ``out`` of the elements whose line has point loads
    (:func:`catenary_monitor.core.rules.uncertainty.loaded_bounds`, element by element)."""
    span = _span(cfgs, named)
    for k in range(len(named['top_tension'])):
        c = cfgs[k] if len(cfgs) > 1 else cfgs[0]
        if c.point_loads is None:
            continue
        one = uncertainty.loaded_bounds(
            c.weight,
            float(span[k]),
            c.mbl,
            c.point_loads,
            float(named['top_tension'][k]),
            float(named['depth'][k]),
            float(c.tension_accuracy_or_default),
            depth_accuracy,
            float(named['uplift_force'][k]),
        )
        for key, value in one.items():
            out[key] = np.array(out[key], dtype=float)
            out[key][k] = value


def bound_values(
    cfgs: Sequence[LineConfig],
    depth_accuracy: float,
    named: dict[str, np.ndarray],
    dynamic: bool = False,
) -> dict[str, np.ndarray]:
    """The bounds (:data:`catenary_monitor.core.rules.uncertainty.FIELDS`) per element of the
    nominal values ``named`` (VALUE_FIELDS -> arrays), each element's line in ``cfgs`` (one
    config, or one per element); the core and its batch twin both call this. ``dynamic``:
    also ``dynamic_uplift`` (``named['top_tension']`` the dynamic tension)."""
    return uncertainty.bounds(
        _column(cfgs, 'weight'),
        _span(cfgs, named),
        _column(cfgs, 'mbl'),
        _column(cfgs, 'ea'),
        named['top_tension'],
        named['depth'],
        np.array([c.tension_accuracy_or_default for c in cfgs]),
        depth_accuracy,
        named['uplift_force'],
        dynamic,
    )


def holding_values(
    cfgs: Sequence[LineConfig], named: dict[str, np.ndarray], tolerance: float = math.inf
) -> dict[str, np.ndarray]:
    """The holding values (:data:`HOLDING_FIELDS`), as :func:`bound_values`; ``tolerance``
    is ``drag_tolerance`` (m). Lines with point loads element by element (:func:`holding_one`,
    the core's own numbers)."""
    if any(c.point_loads is not None for c in cfgs):
        return _holding_by_element(cfgs, named, tolerance)
    line = holding_rule.HoldingInputs(
        _column(cfgs, 'weight'),
        _column(cfgs, 'ea'),
        _column(cfgs, 'chain_length'),
        _column(cfgs, 'anchor_holding'),
        _column(cfgs, 'anchor_weight'),
        _column(cfgs, 'chain_friction'),
        named['top_tension'],
        named['depth'],
        named['horizontal_tension'],
        named['suspended_length'],
        named['uplift_force'],
        _span(cfgs, named),
    )
    return holding_rule.holding(line, tolerance)


def _holding_by_element(
    cfgs: Sequence[LineConfig], named: dict[str, np.ndarray], tolerance: float
) -> dict[str, np.ndarray]:
    """:func:`holding_values` one element at a time through :func:`holding_one`."""
    n = len(named['top_tension'])
    out = {key: np.full(n, np.nan) for key in HOLDING_FIELDS}
    for k in range(n):
        values = [_NAN] * len(VALUE_INDEX)
        for key, i in VALUE_INDEX.items():
            if key in named:
                values[i] = float(named[key][k])
        one = holding_one(cfgs[k] if len(cfgs) > 1 else cfgs[0], values, tolerance)
        for key in HOLDING_FIELDS:
            out[key][k] = one[key]
    return out


def holding_one(
    lc: LineConfig, values: Sequence[float], tolerance: float = math.inf
) -> dict[str, float]:
    """:func:`holding_values` of one line's :data:`VALUE_FIELDS` values in plain floats
    (:func:`catenary_monitor.core.rules.holding.holding_scalar`: the same numbers to
    rounding, an order of magnitude faster than one-element arrays; a line with point loads:
    :func:`~catenary_monitor.core.rules.holding.holding_loaded`, the twin's too)."""

    def given(v: Optional[float]) -> float:
        return _NAN if v is None else v

    line = holding_rule.HoldingInputs(
        lc.weight,
        math.inf if lc.ea is None else lc.ea,
        given(lc.chain_length),
        given(lc.anchor_holding),
        given(lc.anchor_weight),
        given(lc.chain_friction),
        values[VALUE_INDEX['top_tension']],
        values[VALUE_INDEX['depth']],
        values[VALUE_INDEX['horizontal_tension']],
        values[VALUE_INDEX['suspended_length']],
        values[VALUE_INDEX['uplift_force']],
        _given_span(lc, values[VALUE_INDEX['span']]),
    )
    if lc.point_loads is not None:
        return holding_rule.holding_loaded(PointLoads.of(*lc.point_loads), line, tolerance)
    return holding_rule.holding_scalar(line, tolerance)


def add_derived(
    lines: Sequence[LineState], alarm: AlarmConfig, depth_s: float, trend: TrendState
) -> None:
    """The fatigue values, the wave values, the dynamic uplift, the bounds, the holding
    values and the time to uplift of freshly solved lines (from their values;
    :func:`derived_values`; one line, a tension event, in plain floats: :func:`derived_one`)."""
    for line in lines:
        line.values = with_fatigue(line.values, line.fatigue_values)
        set_channels(line)
    if len(lines) == 1:
        line = lines[0]
        line.values = derived_one(line, alarm, depth_s, trend)
        return
    named = {k: np.array([line.values[i] for line in lines]) for k, i in VALUE_INDEX.items()}
    named['peak_tension'] = np.array([line.peak_tension for line in lines])
    named['wave_tension'] = np.array([line.wave_tension for line in lines])
    cfgs = [line.config for line in lines]
    tolerance = alarm.drag_tolerance
    derived = derived_values(cfgs, alarm, named, holding=False)
    some = [k for k, line in enumerate(lines) if _wants_holding(line.config)]
    held: dict[str, Any] = {key: np.full(len(lines), np.nan) for key in HOLDING_FIELDS}
    if some:
        idx = np.array(some)
        part = holding_values(
            [cfgs[k] for k in some], {k: v[idx] for k, v in named.items()}, tolerance
        )
        for key in HOLDING_FIELDS:
            held[key][idx] = part[key]
    derived.update(held)
    margin, view = tide_trend.nearer_margin(
        named['tide_margin'], derived['tide_margin_at_length']
    )
    derived['time_to_uplift'] = np.array(
        uplift_times(alarm, depth_s, trend, margin, named['uplift_force'])
    )
    derived['time_to_uplift_view'] = view
    at = [(VALUE_INDEX[key], np.asarray(column).tolist()) for key, column in derived.items()]
    for j, line in enumerate(lines):
        v = list(line.values)
        for i, column in at:
            v[i] = column[j]
        line.values = tuple(v)


_AT = VALUE_INDEX
_BOUNDS_AT = tuple(VALUE_INDEX[key] for key in uncertainty.FIELDS)
_HOLDING_AT = tuple((VALUE_INDEX[key], key) for key in HOLDING_FIELDS)


def derived_one(
    line: LineState, alarm: AlarmConfig, depth_s: float, trend: TrendState
) -> tuple[float, ...]:
    """:func:`add_derived` of one line in plain floats: its values with the derived ones in
    their places (the same formulas as :func:`derived_values` on arrays, to rounding: the
    bounds by :func:`~catenary_monitor.core.rules.uncertainty.bounds_one`, the holding by
    :func:`holding_one`; test_derived_one)."""
    lc, v = line.config, list(line.values)
    h, f0 = v[_AT['depth']], v[_AT['uplift_force']]
    peak, wave = line.peak_tension, line.wave_tension
    tension = peak + alarm.wave_allowance * wave  # uncertainty.dynamic_tension
    x = _given_span(lc, v[_AT['span']])
    v[_AT['peak_tension']], v[_AT['wave_tension']] = peak, wave
    if lc.point_loads is None:
        ea = math.inf if lc.ea is None else lc.ea
        given = (lc.weight, x, lc.mbl, ea, tension, h)
        bounds = uncertainty.bounds_one(
            *given, lc.tension_accuracy_or_default, alarm.depth_accuracy, f0
        )
        for i, value in zip(_BOUNDS_AT, bounds):
            v[i] = value
        v[_AT['dynamic_uplift']] = uncertainty.dynamic_uplift_one(*given, f0)
    else:
        loaded = uncertainty.loaded_bounds(
            lc.weight,
            x,
            lc.mbl,
            lc.point_loads,
            tension,
            h,
            float(lc.tension_accuracy_or_default),
            alarm.depth_accuracy,
            f0,
        )
        for key, value in loaded.items():
            v[_AT[key]] = value
    if _wants_holding(lc):
        held = holding_one(lc, v, alarm.drag_tolerance)
        for i, key in _HOLDING_AT:
            v[i] = held[key]
    else:
        for i, _ in _HOLDING_AT:
            v[i] = _NAN
    tide, at_length = v[_AT['tide_margin']], v[_AT['tide_margin_at_length']]
    margin = at_length if at_length < tide else tide  # tide_trend.nearer_margin
    view = 1.0 if at_length < tide else (_NAN if tide != tide else 0.0)
    v[_AT['time_to_uplift']] = uplift_times(alarm, depth_s, trend, [margin], [f0])[0]
    v[_AT['time_to_uplift_view']] = view
    return tuple(v)


def uplift_times(
    alarm: AlarmConfig, depth_s: float, trend: TrendState, margins: Any, forces: Any
) -> list[float]:
    """Each line's time to uplift [s]: on the tide table's forecast from the newest depth
    sample where there is a table (core.rules.tide_table), else at the tide's trend."""
    a = alarm
    if a.constituents:
        times = tide_table.uplift_times(
            a.constituents,
            a.tide_table_epoch,
            a.tide_forecast_horizon,
            np.full(len(margins), depth_s),
            np.array(margins, np.float64),
            np.array(forces, np.float64),
        )
        return [float(v) for v in times]
    rate, excess = trend.rate, trend.excess
    return [tide_trend.time_to_uplift(m, f, rate, excess) for m, f in zip(margins, forces)]
