"""The twin's solves: problems 3 and 4 of one line on arrays (:func:`solve_updates`, through the
C kernel where built), with the derived values and the time to uplift at each solved step
(:func:`solve_line`).

Reuse: the critical hook tension of the load margin depends only on depth and line, so it is
solved once per depth sample, not once per update; the uplift iteration runs only on the updates
whose anchor is lifted. The formulas are the ones :func:`catenary_monitor.solve` evaluates on
arrays, so values equal the core's scalar path to rounding (1e-12 relative) and levels and
messages are identical."""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from catenary_monitor.core.config.parameters import LineConfig
from catenary_monitor.core.monitor.derived import derived_values
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.monitor.state import NO_DEPTH, VALUE_FIELDS, LineState
from catenary_monitor.core.physics import elastic, fused_kernel
from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics.solve import ALL_KEYS, Status, solve
from catenary_monitor.core.rules import tide_table, tide_trend
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules.plausible import reading_status_array
from catenary_monitor.core.twin.decisions import DockColumns, SensorColumns, TideColumns
from catenary_monitor.core.twin.schedule import LineSteps, pick
from catenary_monitor.core.twin.window import Window

__all__ = [
    'solve_updates',
    'critical_parameters',
    'solve_line',
]


def solve_updates(
    line: LineConfig,
    tension: np.ndarray,
    depth: np.ndarray,
    a_crit: np.ndarray,
    span: Optional[np.ndarray] = None,
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Problems 3 and 4 for one line on arrays, with the critical parameter given per element.

    Parameters
    ----------
    line : the chain (weight N/m, anchor distance m, MBL N).
    tension : hook tension T (N) per update.
    depth : depth h (m) per update, hook height already added; NaN means no depth yet.
    a_crit : catenary parameter (m) of the critical no-uplift chain at that depth
        (:func:`catenary_monitor.core.physics.catenary.critical_parameter`), per update.
    span : the anchor distance (m) per update (None: the line's installed one).

    Returns
    -------
    values : dict of :data:`VALUE_FIELDS` -> float64 arrays (NaN where status != 0, except
        ``top_tension`` and ``depth``, the measured inputs, as the node publishes them)
    status : int64 array, :class:`~catenary_monitor.solve.Status` codes, :data:`NO_DEPTH` where
        ``depth`` is NaN.

    Notes
    -----
    Same checks (first failed rule wins) and the same floating-point operations as
    ``solve(w, h, tension=T, anchor_distance=x, mbl=mbl)`` on arrays.  A line with an axial
    stiffness (``line.ea``) is solved by ``elastic.solve_with_correction`` as the core
    does (``a_crit`` unused).
    """
    if line.ea is not None:
        return _solve_updates_elastic(line, tension, depth, span)[:2]
    if fused_kernel.AVAILABLE:  # the C kernel, as the core's scalar solve() (a_crit unused)
        return _solve_updates_kernel(line, tension, depth, span=span)
    n = len(tension)
    w, mbl = line.weight, line.mbl
    x_all: Any = line.anchor_distance if span is None else np.asarray(span, dtype=float)
    out = {k: np.full(n, np.nan) for k in VALUE_FIELDS}
    status = np.zeros(n, dtype=np.int64)
    with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
        finite = np.isfinite(tension) & np.isfinite(depth)
        status[~finite] = Status.NON_FINITE
        status[(status == 0) & ~(depth > 0)] = Status.DEPTH
        status[(status == 0) & ~(tension > w * depth)] = Status.TENSION
        status[np.isnan(depth)] = NO_DEPTH
        out['depth'] = depth.copy()
        ok = status == 0
        out['top_tension'] = tension.copy()
        all_ok = bool(ok.all())
        t = tension if all_ok else tension[ok]
        h = depth if all_ok else depth[ok]
        ac = a_crit if all_ok else a_crit[ok]
        x = x_all if span is None or all_ok else x_all[ok]
        b = cat.two_prod_diff(t, w, h) / w
        x_min = b * cat.acosh1p(h / b)
        r = w * b
        length = np.sqrt(h) * np.sqrt(h + 2.0 * b)  # cat.grounded's form: no underflow
        uplift = np.zeros_like(b)
        angle = np.zeros_like(b)
        lift = np.flatnonzero(x < x_min)
        if lift.size:
            m = lift.size
            state, _, conv = cat.lifted_from_tension(
                np.full(m, w), b[lift], h[lift], np.broadcast_to(x, b.shape)[lift]
            )
            r[lift] = state.horizontal_tension
            length[lift] = state.suspended_length
            uplift[lift] = state.uplift_force
            angle[lift] = np.degrees(state.anchor_angle)
        cols = {
            'horizontal_tension': r,
            'min_anchor_distance': x_min,
            'anchor_margin': x - x_min,
            'uplift_force': uplift,
            'tide_margin': cat.depth_reached(r / w, x) - h,
            'load_margin': w * (ac + h) - t,
            'safety_factor': mbl / t,
            'anchor_angle_deg': angle,
            'suspended_length': length,
        }
        if lift.size and not conv.all():
            bad = lift[~conv]
            for v in cols.values():
                v[bad] = np.nan
            where = np.flatnonzero(ok)[bad] if not all_ok else bad
            status[where] = Status.NO_CONVERGENCE
        for k, v in cols.items():
            if all_ok:
                out[k] = v
            else:
                out[k][ok] = v
    return out, status


#: Values the caller sets (inputs, the tide's forecast, the bounds and the holding values).
_NOT_SOLVED = frozenset(('depth', 'top_tension', 'time_to_uplift')) | frozenset(
    k for k in VALUE_FIELDS if k not in ALL_KEYS
)


#: The kernel's rows the values take (the measured tension and depth are the inputs', the
#: grounded length the holding rule's): only those are written.
_KERNEL_ROWS = tuple(
    k for k in ALL_KEYS if k in VALUE_FIELDS and k not in ('top_tension', 'grounded_length')
)


def _solve_updates_kernel(
    line: LineConfig,
    tension: np.ndarray,
    depth: np.ndarray,
    keep: bool = False,
    span: Optional[np.ndarray] = None,
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """:func:`solve_updates` through the C kernel (core/physics/fused_kernel.py): one pass,
    every value.

    ``keep``: the inputs are the caller's to give (kept as the ``top_tension`` and ``depth``
    columns, not copied), and the caller sets ``time_to_uplift`` and ``sensor_state``;
    ``span``: the anchor distance per update (m; None: the installed one)."""
    t = np.ascontiguousarray(tension, dtype=float)
    h = np.ascontiguousarray(depth, dtype=float)
    x: Any = (
        float(line.anchor_distance) if span is None else np.ascontiguousarray(span, dtype=float)
    )
    rows, status = fused_kernel.solve_arrays(
        float(line.weight), h, t, x, float(line.mbl), len(t), rows=_KERNEL_ROWS
    )
    status[np.isnan(h)] = NO_DEPTH
    out = dict(zip(_KERNEL_ROWS, rows))
    if keep:
        out['depth'], out['top_tension'] = h, t
        return out, status
    out['depth'], out['top_tension'] = h.copy(), t.copy()
    for key in VALUE_FIELDS:  # the caller's: the tide's forecast, the ticks, the derived values
        out.setdefault(key, np.full(len(t), np.nan))
    return out, status


def _solve_updates_elastic(
    line: LineConfig, tension: np.ndarray, depth: np.ndarray, span: Optional[np.ndarray] = None
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """:func:`solve_updates` for a line with ``ea``: ``elastic.solve_with_correction`` (the
    rule picks the model), at ``span`` (m per update; None: the installed anchor distance).

    Also returns, per update, whether the elastic model answered.
    """
    n = len(tension)
    out = {k: np.full(n, np.nan) for k in VALUE_FIELDS}
    out['depth'], out['top_tension'] = depth.copy(), tension.copy()
    status = np.full(n, NO_DEPTH, dtype=np.int64)
    used = np.zeros(n, dtype=bool)
    has = ~np.isnan(depth)
    if has.any():
        res, _ = elastic.solve_with_correction(
            line.weight,
            depth[has],
            tension[has],
            anchor_distance=line.anchor_distance if span is None else span[has],
            ea=line.ea,
            mbl=line.mbl,
        )
        status[has] = res.status
        used[has] = np.asarray(res.model) == elastic.ELASTIC
        for k in VALUE_FIELDS:
            if k not in _NOT_SOLVED:
                out[k][has] = getattr(res, k)
    return out, status, used


def _solve_updates_loads(
    line: LineConfig, tension: np.ndarray, depth: np.ndarray, span: Optional[np.ndarray] = None
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """:func:`solve_updates` for a line with point loads: the core's scalar solve() per
    element (core/physics/point_loads.py), at ``span`` (m per update; None: the installed
    anchor distance); also where that model answered."""
    n = len(tension)
    out = {k: np.full(n, np.nan) for k in VALUE_FIELDS}
    out['depth'], out['top_tension'] = depth.copy(), tension.copy()
    status = np.full(n, NO_DEPTH, dtype=np.int64)
    has = ~np.isnan(depth)
    for i in np.flatnonzero(has).tolist():
        res = solve(
            line.weight,
            float(depth[i]),
            tension=float(tension[i]),
            anchor_distance=line.anchor_distance if span is None else float(span[i]),
            mbl=line.mbl,
            point_loads=line.point_loads,
        )
        status[i] = res.status
        for k in VALUE_FIELDS:
            if k not in _NOT_SOLVED:
                out[k][i] = getattr(res, k)
    return out, status, has.copy()


def critical_parameters(
    line: LineConfig, depth: np.ndarray, span: Optional[np.ndarray] = None
) -> np.ndarray:
    """Critical catenary parameter (m) per depth sample (depth already includes hook height),
    at ``span`` (m per sample; None: the installed anchor distance)."""
    a = np.full(len(depth), np.nan)
    good = np.isfinite(depth) & (depth > 0)
    if good.any():
        h = depth[good]
        x = np.full(h.size, line.anchor_distance) if span is None else span[good]
        with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
            a[good], _ = cat.critical_parameter(h, x)
    return a


def solve_line(
    core: MonitorCore,
    line: LineState,
    steps: LineSteps,
    tv: np.ndarray,
    window: Window,
    tide: TideColumns,
    sensors: SensorColumns,
    k: int,
    waves: tuple[np.ndarray, np.ndarray],
    dock: Optional[DockColumns] = None,
) -> tuple[dict[str, np.ndarray], np.ndarray, Optional[np.ndarray]]:
    """Values, status and elastic flags at the line's solved steps, with the time to uplift
    at the tide's trend of the newest depth sample and the sensor state of the newest tick;
    ``waves`` the wave window's peak and wave tension after each tension sample; each solve at
    the span of the newest tick's dock estimate (``dock``; None: the installed span)."""
    span = _spans(line, steps, dock, k)
    values, status, used = _solve_at(core, line, steps, tv, window, span[0])
    values['span'], values['span_source'] = span
    values['sensor_state'] = pick(
        steps.k_idx[steps.solved], sensors.codes[:, k].astype(np.float64), sensors.before[k]
    )
    d_idx = steps.d_idx[steps.solved]
    t_idx = steps.t_idx[steps.solved]
    values['peak_tension'] = pick(t_idx, waves[0], line.peak_tension)
    values['wave_tension'] = pick(t_idx, waves[1], line.wave_tension)
    values.update(derived_values([line.config], core.config.alarm, values))
    margin, values['time_to_uplift_view'] = tide_trend.nearer_margin(
        values['tide_margin'], values['tide_margin_at_length']
    )
    a = core.config.alarm
    if a.constituents:
        now = pick(d_idx, window.sample_s(None), core.state.depth_s)
        values['time_to_uplift'] = tide_table.uplift_times(
            a.constituents,
            a.tide_table_epoch,
            a.tide_forecast_horizon,
            now,
            margin,
            values['uplift_force'],
        )
    else:
        rate = pick(d_idx, tide.rates, core.state.trend.rate)
        excess = pick(d_idx, tide.excess, core.state.trend.excess)
        values['time_to_uplift'] = tide_trend.uplift_times(
            margin, values['uplift_force'], rate, excess
        )
    return values, status, used


def _spans(
    line: LineState, steps: LineSteps, dock: Optional[DockColumns], k: int
) -> tuple[np.ndarray, np.ndarray]:
    """The span [m] and ``span_source`` code at the line's solved steps: the newest tick's
    dock estimate (:func:`dock_live.solve_spans`), the installed span where it gives none."""
    n = int(np.count_nonzero(steps.solved))
    installed = line.config.anchor_distance
    if dock is None:  # constants: read-only, no memory per step
        return (
            np.broadcast_to(np.float64(installed), (n,)),
            np.broadcast_to(np.float64(dock_live.INSTALLED), (n,)),
        )
    column = dock.decision.span[:, k] if dock.decision.span is not None else np.zeros(0)
    estimate = pick(steps.k_idx[steps.solved], column, dock.span_before[k])
    known = ~np.isnan(estimate)
    source = np.where(known, float(dock_live.DOCK_ESTIMATE), float(dock_live.INSTALLED))
    return np.where(known, estimate, installed), source


def _solve_at(
    core: MonitorCore,
    line: LineState,
    steps: LineSteps,
    tv: np.ndarray,
    window: Window,
    span: Optional[np.ndarray] = None,
) -> tuple[dict[str, np.ndarray], np.ndarray, Optional[np.ndarray]]:
    """Values, status and elastic flags at the line's solved steps (the solver's part), at
    ``span`` [m] per solved step (None: the installed span)."""
    lc = line.config
    where = np.flatnonzero(steps.solved)
    tension = pick(steps.t_idx[where], tv, line.tension)
    d_idx = steps.d_idx[where]
    dv = window.depth[1]
    h = pick(d_idx, dv + lc.hook_height, core.state.depth + lc.hook_height)  # NaN: no depth yet
    if span is not None and np.all(span == lc.anchor_distance):
        span = None  # the installed span throughout: the constant's faster paths
    used: Optional[np.ndarray] = None
    if lc.ea is not None:
        values, status, used = _solve_updates_elastic(lc, tension, h, span)
    elif lc.point_loads is not None:  # rare: solve() element by element
        values, status, used = _solve_updates_loads(lc, tension, h, span)
    elif fused_kernel.AVAILABLE:  # solve_updates' kernel path, which needs no critical parameter
        values, status = _solve_updates_kernel(lc, tension, h, keep=True, span=span)
    elif span is not None:  # spans that change: the critical parameter per solve
        values, status = solve_updates(lc, tension, h, critical_parameters(lc, h, span), span)
    else:
        a_depth = critical_parameters(lc, dv + lc.hook_height)
        a_before = critical_parameters(lc, np.array([core.state.depth + lc.hook_height]))[0]
        values, status = solve_updates(lc, tension, h, pick(d_idx, a_depth, a_before))
    lo, hi = core.config.chart
    code = reading_status_array(
        tension, h, lc.mbl, lc.weight, lo + lc.hook_height, hi + lc.hook_height
    )
    _mark_implausible(values, status, used, code)
    return values, status, used


def _mark_implausible(
    values: dict[str, np.ndarray], status: np.ndarray, used: Optional[np.ndarray], code: np.ndarray
) -> None:
    """Implausible readings (core.rules.plausible), as the core marks them: their status, no
    solved values (the measured tension and depth kept), the inextensible model named."""
    hit = code != 0
    if not hit.any():
        return
    status[hit] = code[hit]
    for key, column in values.items():
        if key not in ('depth', 'top_tension', 'sensor_state'):
            column[hit] = np.nan
    if used is not None:
        used[hit] = False
