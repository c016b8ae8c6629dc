"""Offline recompute of a recorded log with the live node's update schedule (no rclpy, no I/O).

The live node (``catenary_monitor.node``) updates a line's alarm on three occasions:

* a tension sample of the line (receive time t): the line is solved at the newest depth
  (``depth + hook_height``) and its alarm stepped with the solved
  :class:`~catenary_monitor.alarms.AlarmInputs` (``tension_stamp = t``, ``depth_stamp`` = receive
  time of the newest depth); before the first depth sample the inputs are NaN, status 0;
* a depth sample: every line that already has a tension is re-solved at the new depth and stepped;
* a periodic tick (``1 / diagnostic_rate``): every line is stepped again with its previous inputs
  (this is where staleness and hold-time clears fire); a line that has had no update yet is
  stepped with ``AlarmInputs()``.

:func:`recompute` builds that schedule per line from whole columns (receive times in ns and
values), solves every update in vectorized code and runs
:func:`~catenary_monitor.alarms.replay_levels`, the exact vectorized equivalent of the scalar
alarm state machine. For the same inputs it gives the node's alarm transitions.

Events with equal receive times are taken in the order depth, tension, tick (the node's receive
times are distinct clock readings; the rule only matters for generated data).

Reuse: the critical hook tension of the load margin depends only on depth and line, so it is
solved once per depth sample, not once per update; the uplift iteration runs only on the updates
whose anchor is lifted. Every formula is the one :func:`catenary_monitor.solve` evaluates on
arrays, in the same order, so the values are bit-identical to ``solve()`` on arrays (and equal
to its scalar path, which the node uses for tension updates, to rounding).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Mapping, Optional

import numpy as np

from catenary_monitor.core import catenary as cat, elastic
from catenary_monitor.core.alarms import Level, LineAlarm, Transition, replay_levels
from catenary_monitor.core.config import LineConfig, MonitorConfig
from catenary_monitor.core.solve import STATUS_MESSAGES, Status

__all__ = ['OUTPUT_FIELDS', 'NO_DEPTH', 'LineResult', 'ReplayResult', 'solve_updates',
           'tick_grid', 'recompute', 'recompute_line']

#: Element order of the node's per-line ``Float64MultiArray`` outputs
#: (``/catenary_monitor/NAME/outputs``), same as ``catenary_monitor.node.OUTPUT_FIELDS``.
OUTPUT_FIELDS = ('top_tension', 'depth', 'horizontal_tension', 'min_anchor_distance',
                 'anchor_margin', 'uplift_force', 'tide_margin', 'load_margin', 'safety_factor',
                 'anchor_angle_deg', 'suspended_length', 'status', 'level')
#: The solved quantities among them (float64 columns of :class:`LineResult`).
VALUE_FIELDS = OUTPUT_FIELDS[:-2]
#: Solver status of an update made before any depth sample arrived (as the node publishes it).
NO_DEPTH = -1

#: Model names by :attr:`LineResult.model_codes` (as the node's ``/diagnostics`` key ``model``).
MODEL_NAMES = ('none', elastic.INEXTENSIBLE, elastic.ELASTIC)

#: Update kinds in :attr:`LineResult.kind`.
KIND_DEPTH, KIND_TENSION = 0, 1


@dataclass
class LineResult:
    """Every solved update of one line (tension and depth updates, time order) and its alarms.

    ``t_ns`` are receive times (ns); ``values`` maps each of :data:`VALUE_FIELDS` to a float64
    array (SI; ``depth`` is depth + hook height, the depth the chain was solved at);
    ``status`` the solver code per update (:data:`NO_DEPTH` before the first depth);
    ``level`` the alarm level after the update (int8 :class:`~catenary_monitor.alarms.Level`).
    ``tick_ns`` / ``tick_level``: the periodic steps and the level after each.
    ``transitions``: every level change, ticks included.
    ``elastic``: per update, True where the elastic model answered (None: an inextensible line,
    no ``ea``); see :func:`model_names`.
    """

    name: str
    t_ns: np.ndarray
    kind: np.ndarray
    values: dict[str, np.ndarray]
    status: np.ndarray
    level: np.ndarray
    tick_ns: np.ndarray
    tick_level: np.ndarray
    transitions: list[Transition] = field(default_factory=list)
    elastic: Optional[np.ndarray] = None

    @property
    def model_codes(self) -> np.ndarray:
        """Per update: index into :data:`MODEL_NAMES` (0, ``none``, before the first depth)."""
        code = np.ones(len(self.t_ns), np.int64)
        if self.elastic is not None:
            code[self.elastic] = 2
        code[self.status == NO_DEPTH] = 0
        return code

    @property
    def tension_rows(self) -> np.ndarray:
        """Indexes of the updates made by a tension sample (one per tension message)."""
        return np.flatnonzero(self.kind == KIND_TENSION)

    def episodes(self, end_ns: Optional[int] = None) -> list[dict[str, object]]:
        """Alarm episodes: maximal periods with level != OK.

        Each is a dict: ``start``, ``end`` (s; None if still open at the end of the log),
        ``duration`` (s; up to ``end_ns`` if still open), ``worst`` (level name, ERROR > STALE >
        WARN), ``message`` (first message at the worst level).
        """
        rank = {Level.OK: 0, Level.WARN: 1, Level.STALE: 2, Level.ERROR: 3}
        out: list[dict[str, object]] = []
        cur: Optional[dict[str, object]] = None
        for tr in self.transitions:
            if cur is None and tr.new != Level.OK:
                cur = {'start': tr.time, 'end': None, 'duration': None, 'worst': tr.new.name,
                       'message': tr.message}
            elif cur is not None:
                if tr.new == Level.OK:
                    cur['end'] = tr.time
                    cur['duration'] = tr.time - float(cur['start'])  # type: ignore[arg-type]
                    out.append(cur)
                    cur = None
                    continue
                if rank[tr.new] > rank[Level[str(cur['worst'])]]:
                    cur['worst'] = tr.new.name
                    cur['message'] = tr.message
        if cur is not None:
            if end_ns is not None:
                cur['duration'] = max(end_ns * 1e-9 - float(cur['start']), 0.0)  # type: ignore
            out.append(cur)
        return out


@dataclass
class ReplayResult:
    """Recompute of a whole log: one :class:`LineResult` per configured line, in config order."""

    lines: list[LineResult]
    tick_ns: np.ndarray
    ticks_from_log: bool
    start_ns: int
    end_ns: int

    @property
    def updates(self) -> int:
        """Solved updates over all lines."""
        return sum(len(r.t_ns) for r in self.lines)


def solve_updates(line: LineConfig, tension: np.ndarray, depth: np.ndarray,
                  a_crit: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Problems 3 and 4 for one line on arrays, with the critical parameter given per element.

    Parameters
    ----------
    line : the chain (weight N/m, anchor distance m, MBL N).
    tension : hook tension T (N) per update.
    depth : depth h (m) per update, hook height already added; NaN means no depth yet.
    a_crit : catenary parameter (m) of the critical no-uplift chain at that depth
        (:func:`catenary_monitor.catenary.critical_parameter`), per update.

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
    stiffness (``line.ea``) is solved by ``elastic.solve_with_correction`` as the node does (``a_crit`` unused).
    """
    if line.ea is not None:
        return _solve_updates_elastic(line, tension, depth)[:2]
    n = len(tension)
    w, x, mbl = line.weight, line.anchor_distance, line.mbl
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
        b = cat.two_prod_diff(t, w, h) / w
        x_min = b * cat.acosh1p(h / b)
        r = w * b
        length = np.sqrt(h * (h + 2.0 * b))
        uplift = np.zeros_like(b)
        angle = np.zeros_like(b)
        lift = np.flatnonzero(x < x_min)
        if lift.size:
            m = lift.size
            state, _, conv = cat.lifted_from_tension(np.full(m, w), b[lift], h[lift],
                                                     np.full(m, x))
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


def _solve_updates_elastic(line: LineConfig, tension: np.ndarray, depth: np.ndarray
                           ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """:func:`solve_updates` for a line with ``ea``: ``elastic.solve_with_correction`` (the rule picks the model).

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
            line.weight, depth[has], tension[has], anchor_distance=line.anchor_distance,
            ea=line.ea, mbl=line.mbl)
        status[has] = res.status
        used[has] = np.asarray(res.model) == elastic.ELASTIC
        for k in VALUE_FIELDS:
            if k not in ('depth', 'top_tension'):
                out[k][has] = getattr(res, k)
    return out, status, used


def critical_parameters(line: LineConfig, depth: np.ndarray) -> np.ndarray:
    """Critical catenary parameter (m) per depth sample (depth already includes hook height)."""
    a = np.full(len(depth), np.nan)
    good = np.isfinite(depth) & (depth > 0)
    if good.any():
        h = depth[good]
        with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
            a[good], _ = cat.critical_parameter(h, np.full(h.size, line.anchor_distance))
    return a


def tick_grid(start_ns: int, end_ns: int, rate_hz: float) -> np.ndarray:
    """Synthetic periodic ticks: ``start + k / rate`` (ns) for k >= 0 up to ``end_ns``."""
    if end_ns < start_ns:
        return np.zeros(0, np.int64)
    period = 1e9 / rate_hz
    k = np.arange(int((end_ns - start_ns) // period) + 1, dtype=np.int64)
    ticks = start_ns + np.rint(k * period).astype(np.int64)
    return ticks[ticks <= end_ns]


def recompute_line(line: LineConfig, alarm: LineAlarm, tension: tuple[np.ndarray, np.ndarray],
                   depth: tuple[np.ndarray, np.ndarray], a_crit: np.ndarray,
                   tick_ns: np.ndarray) -> LineResult:
    """Schedule, solve and alarm one line (see the module docstring for the schedule).

    ``tension`` and ``depth`` are ``(receive time ns int64, value float64)``, sorted by time;
    ``depth`` values are the raw tide depth (hook height is added here); ``a_crit`` the
    critical parameter per depth sample (:func:`critical_parameters`); ``tick_ns`` sorted.
    """
    t_ns, tv = tension
    d_ns, dv = depth
    n_t = len(t_ns)
    if n_t:
        first = np.searchsorted(d_ns, t_ns[0], 'right')   # depths after the first tension
        dep_t = d_ns[first:]
        dep_i = np.searchsorted(t_ns, dep_t, 'left') - 1   # newest tension before the depth
        dep_j = np.arange(first, len(d_ns))
        ten_j = np.searchsorted(d_ns, t_ns, 'right') - 1   # newest depth at the tension
        ev_t = np.concatenate((dep_t, t_ns))
        ev_i = np.concatenate((dep_i, np.arange(n_t)))
        ev_j = np.concatenate((dep_j, ten_j))
        ev_kind = np.concatenate((np.full(len(dep_t), KIND_DEPTH, np.int8),
                                  np.full(n_t, KIND_TENSION, np.int8)))
        if len(dep_t):
            order = np.argsort(ev_t, kind='stable')        # depth first at equal times
            ev_t, ev_i, ev_j, ev_kind = ev_t[order], ev_i[order], ev_j[order], ev_kind[order]
    else:
        ev_t = np.zeros(0, np.int64)
        ev_i = ev_j = np.zeros(0, np.int64)
        ev_kind = np.zeros(0, np.int8)
    has_d = ev_j >= 0
    jj = np.where(has_d, ev_j, 0)
    if len(dv):
        h = np.where(has_d, dv[jj] + line.hook_height, np.nan)
        ac = np.where(has_d, a_crit[jj], np.nan)
    else:
        h = np.full(len(ev_t), np.nan)
        ac = h
    t_ev = tv[ev_i] if n_t else np.zeros(0)
    used: Optional[np.ndarray] = None
    if line.ea is not None:
        values, status, used = _solve_updates_elastic(line, t_ev, h)
    else:
        values, status = solve_updates(line, t_ev, h, ac)
    if len(dv) == 0:
        values['depth'] = h

    # Merge the ticks: updates first at equal times; a tick repeats the previous inputs.
    n_e = len(ev_t)
    all_t = np.concatenate((ev_t, tick_ns))
    order = np.argsort(all_t, kind='stable')
    is_ev = order < n_e
    src = np.maximum.accumulate(np.where(is_ev, order, -1)) if len(order) else order
    have = src >= 0
    s = np.where(have, src, 0)
    times = all_t[order] * 1e-9

    def col(a: np.ndarray, default: float = math.nan) -> np.ndarray:
        if n_e == 0:
            return np.full(len(order), default)
        return np.where(have, a[s], default)

    d_stamp = np.where(has_d, d_ns[jj] * 1e-9, np.nan) if len(d_ns) else np.full(n_e, np.nan)
    inputs = {k: col(values[k]) for k in ('uplift_force', 'anchor_margin', 'tide_margin',
                                          'load_margin', 'safety_factor')}
    inputs['status'] = np.maximum(col(status, 0), 0).astype(np.int64) if n_e else 0
    inputs['tension_stamp'] = col(t_ns[ev_i] * 1e-9 if n_t else ev_t * 1e-9)
    inputs['depth_stamp'] = col(d_stamp)
    result = replay_levels(times, inputs, alarm, STATUS_MESSAGES)
    pos = np.empty(len(order), np.int64)
    pos[order] = np.arange(len(order))
    return LineResult(line.name, ev_t, ev_kind, values, status,
                      result.levels[pos[:n_e]], tick_ns, result.levels[pos[n_e:]],
                      result.transitions, used)


def recompute(config: MonitorConfig, tensions: Mapping[str, tuple[np.ndarray, np.ndarray]],
              depth: tuple[np.ndarray, np.ndarray], tick_ns: Optional[np.ndarray] = None,
              progress: Optional[Callable[[int, int, str], None]] = None) -> ReplayResult:
    """Recompute every line of ``config`` from recorded columns.

    Parameters
    ----------
    config : the monitor configuration (lines, alarm settings).
    tensions : line name -> (receive time ns int64, tension N), sorted by time (missing = none).
    depth : (receive time ns int64, tide depth m), sorted by time.
    tick_ns : periodic tick times (ns); None gives a synthetic grid at ``diagnostic_rate``
        from the first to the last message (:func:`tick_grid`).
    progress : optional ``callback(done, total, line name)`` called after each line.
    """
    empty = (np.zeros(0, np.int64), np.zeros(0))
    starts = [c[0][0] for c in (*tensions.values(), depth) if len(c[0])]
    ends = [c[0][-1] for c in (*tensions.values(), depth) if len(c[0])]
    start = int(min(starts)) if starts else 0
    end = int(max(ends)) if ends else 0
    from_log = tick_ns is not None
    if tick_ns is None:
        tick_ns = tick_grid(start, end, config.alarm.diagnostic_rate) if starts else empty[0]
    else:
        tick_ns = np.sort(np.asarray(tick_ns, np.int64))
        if len(tick_ns):
            start, end = min(start, int(tick_ns[0])) if starts else int(tick_ns[0]), \
                max(end, int(tick_ns[-1]))
    results = []
    for k, line in enumerate(config.lines):
        alarm = LineAlarm.for_line(line, config.alarm)
        a_crit = critical_parameters(line, depth[1] + line.hook_height)
        results.append(recompute_line(line, alarm, tensions.get(line.name, empty), depth,
                                      a_crit, tick_ns))
        if progress is not None:
            progress(k + 1, len(config.lines), line.name)
    return ReplayResult(results, tick_ns, from_log, start, end)


def worst(result: LineResult) -> dict[str, Optional[dict[str, float]]]:
    """Worst value and its time (s) of each margin and force of a line over the log.

    Minimum of ``anchor_margin``, ``tide_margin``, ``load_margin``, ``safety_factor``; maximum of
    ``uplift_force`` and ``top_tension``. None when the quantity never had a value.
    """
    out: dict[str, Optional[dict[str, float]]] = {}
    for key, pick in (('anchor_margin', np.nanargmin), ('tide_margin', np.nanargmin),
                      ('load_margin', np.nanargmin), ('safety_factor', np.nanargmin),
                      ('uplift_force', np.nanargmax), ('top_tension', np.nanargmax)):
        v = result.values[key]
        if len(v) == 0 or np.all(np.isnan(v)):
            out[key] = None
            continue
        i = int(pick(v))
        out[key] = {'value': float(v[i]), 'time': float(result.t_ns[i] * 1e-9)}
    return out
