"""The vectorized twin of :class:`~catenary_monitor.core.monitor.monitor_core.MonitorCore` over log
columns.

:func:`advance` takes a :class:`MonitorCore` and a :class:`Window` of events in time order
(tension samples per line, depth samples, ticks: columns of receive times in ns and values) and
leaves the core in exactly the state that stepping it event by event would leave (alarm
states, newest inputs and results, tide), returning what those steps did: every line's solved
updates (:data:`~catenary_monitor.core.monitor.state.OUTPUT_FIELDS`), every level transition
and, on request, every diagnostic snapshot. It exists only because it is measured faster (replay of
a day of log in seconds); ``test/test_batch.py`` feeds the same events to both and compares
every step.

It follows the core's schedule (:mod:`catenary_monitor.core.monitor.monitor_core`): each line is
stepped at its tension samples, at every depth sample and at every tick; a line is solved at its
tension samples and, once it has a tension, at every depth sample; the tide is decided at depth
samples and ticks. Events with equal times are taken in the order depth, tensions (config order),
tick (the node's own logs have distinct stamps, so the rule only matters for other recordings).

Reuse: the critical hook tension of the load margin depends only on depth and line, so it is
solved once per depth sample, not once per update; the uplift iteration runs only on the updates
whose anchor is lifted. The formulas are the ones :func:`catenary_monitor.solve` evaluates on
arrays, so values equal the core's scalar path to rounding (1e-12 relative) and levels and
messages are identical.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig
from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.rules import channels
from catenary_monitor.core.alarms import flood as alarm_flood, shelving
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules import fatigue as fatigue_rule
from catenary_monitor.core.rules import readings, sensor_state, tide_table, tide_trend, wave_window
from catenary_monitor.core.alarms.journal import AlarmEvent, entries, raised
from catenary_monitor.core.alarms.latches import (
    DIAGNOSTIC_KEYS,
    LevelSeries,
    Transition,
    quiet_change,
    replay_levels,
)
from catenary_monitor.core.rules.level import RANK, Level
from catenary_monitor.core.rules.health import sensors_status, tide_status
from catenary_monitor.core.alarms.latches import CONDITIONS
from catenary_monitor.core.monitor.state import (
    NO_DEPTH,
    NO_MODEL,
    OUTPUT_FIELDS,
    VALUE_FIELDS,
    LineState,
)
from catenary_monitor.core.monitor.events import NODE_NAME, Coalesced, Start
from catenary_monitor.core.monitor.status import Change, ComponentStatus, Snapshot
from catenary_monitor.core.monitor.monitor_core import MonitorCore, channel_limits
from catenary_monitor.core.monitor.status import depth_word as depth_state_word
from catenary_monitor.core.monitor.status import (
    dock_component,
    forecast_word,
    line_dock_values,
    line_status,
    sensors_component,
    tide_component,
    tide_with_sensor,
    view_word,
)
from catenary_monitor.core.monitor.derived import derived_values
from catenary_monitor.core.monitor.monitor_core import sensor_limits
from catenary_monitor.core.rules.plausible import MAX_DEPTH, reading_status_array, status_messages
from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics import elastic, fused_kernel, point_loads
from catenary_monitor.core.physics.solve import solve
from catenary_monitor.core.physics.solve import ALL_KEYS, Status

try:  # three of the loops below in C, next to this file (optional: else the numpy passes)
    from catenary_monitor.core.monitor import _twin_loops as _loops  # type: ignore[attr-defined]
except ImportError:  # not built
    _loops = None

__all__ = [
    'OUTPUT_FIELDS',
    'VALUE_FIELDS',
    'NO_DEPTH',
    'MODEL_NAMES',
    'KIND_DEPTH',
    'KIND_TENSION',
    'KIND_TICK',
    'Column',
    'Window',
    'slice_window',
    'LineResult',
    'WindowResult',
    'ReplayResult',
    'COLUMNS',
    'SnapshotColumns',
    'StatusColumns',
    'advance',
    'run_log',
    'recompute',
    'solve_updates',
    'critical_parameters',
    'tick_grid',
    'worst',
]

#: Model names by :attr:`LineResult.model_codes` (as the ``/diagnostics`` key ``model``).
MODEL_NAMES = (NO_MODEL, elastic.INEXTENSIBLE, elastic.ELASTIC, point_loads.MODEL)
_INCONSISTENT = CONDITIONS.index('inconsistent')
#: Step kinds in :attr:`LineResult.kind` and :attr:`LineResult.step_kind`.
KIND_DEPTH, KIND_TENSION, KIND_TICK = 0, 1, 2

Column = tuple[np.ndarray, np.ndarray]  # (receive times ns int64, values float64), sorted
_EMPTY: Column = (np.zeros(0, np.int64), np.zeros(0))


@dataclass
class Window:
    """Events of a stretch of log, each column sorted by time (ns): ``tensions`` per line
    (config order), ``depth``, and the ``ticks``. ``tension_stamps`` (per line) and
    ``depth_stamps``: the header stamps (ns) of a stamped input's samples, beside its column
    (None: taken at arrival, the column's time)."""

    tensions: list[Column]
    depth: Column = _EMPTY
    ticks: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    tension_stamps: Optional[list[Optional[np.ndarray]]] = None
    depth_stamps: Optional[np.ndarray] = None
    #: A line of several channels: per line, each sample's channel (int64; None: one channel);
    #: its column holds every channel's samples merged in time order.
    channels: Optional[list[Optional[np.ndarray]]] = None
    #: Filled by :func:`advance` once the channels are fused: line -> (healthy, states) columns.
    channel_values: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    @property
    def messages(self) -> int:
        """Input messages in the window."""
        return sum(len(t) for t, _ in self.tensions) + len(self.depth[0])

    def stamped(self, k: Optional[int]) -> bool:
        """Whether line ``k``'s samples (None: the depth's) carry header stamps."""
        if k is None:
            return self.depth_stamps is not None
        return self.tension_stamps is not None and self.tension_stamps[k] is not None

    def sample_ns(self, k: Optional[int]) -> np.ndarray:
        """The reading times (ns) of line ``k``'s samples (None: the depth's): the header
        stamps of a stamped input, else the arrival times."""
        if k is None:
            return self.depth[0] if self.depth_stamps is None else self.depth_stamps
        stamps = None if self.tension_stamps is None else self.tension_stamps[k]
        return self.tensions[k][0] if stamps is None else stamps

    def sample_s(self, k: Optional[int]) -> np.ndarray:
        """:meth:`sample_ns` in s."""
        return self.sample_ns(k) * 1e-9


@dataclass
class LineResult:
    """What one line's steps did in a window.

    Updates (the solved steps, one output message each): ``t_ns``, ``kind`` (tension or depth),
    ``values`` (:data:`VALUE_FIELDS` -> float64 arrays, SI; ``depth`` is depth + hook height),
    ``status`` (solver code, :data:`NO_DEPTH` before the first depth), ``level`` after the
    update, ``elastic`` (True where the elastic model answered; None for an inextensible line).
    Steps (every alarm step, ticks and unsolved depth steps too): ``step_ns``, ``step_kind``,
    ``step_level``. ``transitions``: every level change.
    """

    name: str
    t_ns: np.ndarray
    kind: np.ndarray
    values: dict[str, np.ndarray]
    status: np.ndarray
    level: np.ndarray
    step_ns: np.ndarray
    step_kind: np.ndarray
    step_level: np.ndarray
    transitions: list[Transition] = field(default_factory=list)
    elastic: Optional[np.ndarray] = None  # where the line's other model answered:
    other_model: int = 2  # its MODEL_NAMES index (the elastic chain, or 3: point loads)

    @property
    def model_codes(self) -> np.ndarray:
        """Per update: index into :data:`MODEL_NAMES` (0, ``none``, before the first depth)."""
        code = np.ones(len(self.t_ns), np.int64)
        if self.elastic is not None:
            code[self.elastic] = self.other_model
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
                cur = {
                    'start': tr.time,
                    'end': None,
                    'duration': None,
                    'worst': tr.new.name,
                    'message': tr.message,
                }
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
class WindowResult:
    """What :func:`advance` did: one :class:`LineResult` per line (config order), the tide's
    transitions, the snapshots (if asked for) and the window's time span (ns)."""

    lines: list[LineResult]
    tide: list[Transition]
    snapshots: list[Snapshot | SnapshotColumns]  # SnapshotColumns: snapshots=COLUMNS
    start_ns: int
    end_ns: int
    others: list[Change] = field(default_factory=list)  # e.g. the logger's
    #: The alarm journal's records (core.alarm_journal), in time order (keyword only).
    alarm_events: list[AlarmEvent] = field(default_factory=list, kw_only=True)

    @property
    def updates(self) -> int:
        """Solved updates over all lines."""
        return sum(len(r.t_ns) for r in self.lines)

    def changes(self) -> list[Change]:
        """Every transition of the window as the core reports them, in time order."""
        out = [Change('tide', tr) for tr in self.tide] + list(self.others)
        for r in self.lines:
            out += [Change(r.name, tr) for tr in r.transitions]
        return sorted(out, key=lambda c: c.transition.time)


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
_ROWS = {k: ALL_KEYS.index(k) for k in VALUE_FIELDS if k in ALL_KEYS}


def _solve_updates_kernel(
    line: LineConfig,
    tension: np.ndarray,
    depth: np.ndarray,
    keep: bool = False,
    span: Optional[np.ndarray] = None,
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """:func:`solve_updates` through the C kernel (core/fused_kernel.py): one pass, every value.

    ``keep``: the inputs are the caller's to give (kept as the ``top_tension`` and ``depth``
    columns, not copied), and the caller sets ``time_to_uplift`` and ``sensor_state``;
    ``span``: the anchor distance per update (m; None: the installed one)."""
    t = np.ascontiguousarray(tension, dtype=float)
    h = np.ascontiguousarray(depth, dtype=float)
    x: Any = (
        float(line.anchor_distance) if span is None else np.ascontiguousarray(span, dtype=float)
    )
    rows, status = fused_kernel.solve_arrays(float(line.weight), h, t, x, float(line.mbl), len(t))
    status[np.isnan(h)] = NO_DEPTH
    out = {k: rows[i] for k, i in _ROWS.items()}
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


def tick_grid(
    start_ns: int, end_ns: int, rate_hz: float, k0: int = 0, n: Optional[int] = None
) -> np.ndarray:
    """The periodic ticks of a log without recorded ones: ``start + rint(k * 1e9 / rate)`` (ns)
    for ``k0 <= k < n`` (default: every k up to ``end_ns``), at or before ``end_ns``."""
    period = 1e9 / rate_hz
    if n is None:
        if end_ns < start_ns:
            return np.zeros(0, np.int64)
        n = int((end_ns - start_ns) // period) + 1
    k = np.arange(k0, max(k0, n), dtype=np.int64)
    ticks = start_ns + np.rint(k * period).astype(np.int64)
    return ticks[ticks <= end_ns]


# --- the engine ----------------------------------------------------------------------------------


def _merge(dd: np.ndarray, tt: np.ndarray, kk: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge sorted depth, tension and tick times (ties: depth, tension, tick): (times, kinds)."""
    n = len(dd) + len(tt) + len(kk)
    if _loops is not None and dd.dtype == tt.dtype == kk.dtype == np.int64:
        times = np.empty(n, np.int64)
        kinds = np.empty(n, np.int8)
        sources = [np.ascontiguousarray(c) for c in (dd, tt, kk)]
        if _loops.merge3(*sources, times, kinds, KIND_DEPTH, KIND_TENSION, KIND_TICK):
            return times, kinds
    before = np.searchsorted
    pos_d = np.arange(len(dd)) + before(tt, dd, 'left') + before(kk, dd, 'left')
    pos_t = np.arange(len(tt)) + before(dd, tt, 'right') + before(kk, tt, 'left')
    pos_k = np.arange(len(kk)) + before(dd, kk, 'right') + before(tt, kk, 'right')
    times = np.empty(n, np.int64)
    kinds = np.empty(n, np.int8)
    for pos, src, kind in (
        (pos_d, dd, KIND_DEPTH),
        (pos_t, tt, KIND_TENSION),
        (pos_k, kk, KIND_TICK),
    ):
        times[pos] = src
        kinds[pos] = kind
    return times, kinds


def _newest(mask: np.ndarray) -> np.ndarray:
    """Per step: index (within the window) of the newest step where ``mask`` holds (-1: none)."""
    return np.cumsum(mask) - 1


@dataclass
class _Tide:
    """The tide's decisions in a window (at depth samples and ticks, in time order)."""

    times: np.ndarray  # ns
    depth: np.ndarray  # m, newest depth at each decision
    depth_s: np.ndarray  # s, its stamp (NaN: none)
    level: np.ndarray  # int8 Level
    stale: np.ndarray  # bool, the depth-stale decision the lines take
    rates: np.ndarray  # m/s, the tide's trend after each depth sample of the window
    excess: np.ndarray  # m, each depth sample's excess over the trend's level
    trend: tide_trend.TrendState  # the trend after the window's last depth sample
    sensor: np.ndarray  # the depth sensor's state code at each decision
    kinds: np.ndarray  # KIND_DEPTH or KIND_TICK: what made each decision


def _worse(level: np.ndarray, other: np.ndarray, code: np.ndarray) -> np.ndarray:
    """Per decision: the worse (by RANK) of the tide's level and its sensor's (where code)."""
    rank = np.array([RANK[Level(v)] for v in range(4)])
    pick = (code != sensor_state.OK) & (rank[other] > rank[level])
    return np.where(pick, other, level).astype(np.int8)


def _tide_at(core: MonitorCore, tide: _Tide, i: int) -> tuple[Level, str]:
    """The tide's (level, message) at decision ``i`` (as the core's ``_decide_tide``)."""
    status = tide_status(
        float(tide.depth[i]),
        float(tide.depth_s[i]),
        float(tide.times[i] * 1e-9),
        core.config.alarm.depth_timeout,
    )
    return tide_with_sensor(status, int(tide.sensor[i]), float(tide.depth[i]), core.config.alarm)


@dataclass
class _Sensors:
    """The sensor states at the window's ticks (core.rules.sensor_state): each line's code
    (ticks, lines) and the depth sensor's (ticks), and the codes before the window."""

    codes: np.ndarray
    depth_codes: np.ndarray
    before: list[int]
    before_depth: int


def _decide_sensors_window(core: MonitorCore, window: Window, refusals: '_Refusals') -> _Sensors:
    """Every tick's sensor states (the arrays the core hands core.rules.sensor_state one tick
    at a time); leaves the core's sensor memories as after the window."""
    a, ticks = core.config.alarm, window.ticks
    lines = core.state.lines
    n, m = len(ticks), len(lines)
    before = [line.sensor_code for line in lines]
    before_depth = core.state.depth_code
    now = ticks * 1e-9
    tension, tension_s = np.empty((n, m)), np.empty((n, m))
    changed, spiked = np.empty((n, m)), np.empty((n, m))
    refused = np.empty((n, m))
    for k, line in enumerate(lines):
        tt, tv = window.tensions[k]
        ts = window.sample_s(k)
        mem = line.sensor_memory
        rate = a.tension_rate_max * line.config.mbl
        jitter = 0.0 if window.stamped(k) else a.stamp_jitter
        ch, sp, line.sensor_memory = sensor_state.samples(
            mem, ts, tv, a.tension_resolution, rate, jitter
        )
        j = np.searchsorted(tt, ticks, 'right') - 1  # tensions go before a tick at one stamp
        tension[:, k] = _pick(j, tv, line.tension)
        tension_s[:, k] = _pick(j, ts, line.tension_s)
        changed[:, k] = _pick(j, ch, mem.changed)
        spiked[:, k] = _pick(j, sp, mem.spiked)
        r = refusals.lines[k]
        refused[:, k] = _pick(np.searchsorted(r, ticks, 'right') - 1, r * 1e-9, line.stamp_refused)
    dd, dv = window.depth
    ds = window.sample_s(None)
    dmem = core.state.depth_memory
    jitter = 0.0 if window.stamped(None) else a.stamp_jitter
    dch, dsp, core.state.depth_memory = sensor_state.samples(
        dmem, ds, dv, a.depth_resolution, a.depth_rate_max, jitter
    )
    j = np.searchsorted(dd, ticks, 'right') - 1  # depth goes before a tick at one stamp
    depth, depth_s = _pick(j, dv, core.state.depth), _pick(j, ds, core.state.depth_s)
    d_changed, d_spiked = _pick(j, dch, dmem.changed), _pick(j, dsp, dmem.spiked)
    r = refusals.depth
    d_refused = _pick(np.searchsorted(r, ticks, 'right') - 1, r * 1e-9, core.state.depth_refused)
    if n == 0:
        return _Sensors(np.zeros((0, m), np.int8), np.zeros(0, np.int8), before, before_depth)
    times = np.concatenate([core.state.sensor_times, now])
    rows = np.vstack(
        [core.state.sensor_rows, sensor_state.history_row(now, tension, spiked, a.sensor_hold)]
    )
    ref, keep = sensor_state.reference(times, rows, now, a.parted_window)
    pattern = sensor_state.parted_pattern(tension, ref, a.parted_drop)
    first = np.array([[line.parted_seen for line in lines]])
    seen = np.maximum.accumulate(
        np.vstack([first, np.where(pattern, now[:, None], -math.inf)]), axis=0
    )[1:]
    core.state.sensor_times, core.state.sensor_rows = times[keep:], rows[keep:]
    codes = sensor_state.decide_lines(
        a,
        sensor_limits(core.config),
        now,
        tension,
        tension_s,
        changed,
        spiked,
        seen,
        depth,
        d_changed,
        refused,
    )
    depth_codes = sensor_state.decide_depth(
        a, now, depth, depth_s, d_changed, d_spiked, changed, d_refused
    )
    for k, line in enumerate(lines):
        line.sensor_code, line.parted_seen = int(codes[-1, k]), float(seen[-1, k])
    core.state.depth_code = int(depth_codes[-1])
    return _Sensors(codes, depth_codes, before, before_depth)


def _decide_tide(
    core: MonitorCore, window: Window, sensors: _Sensors
) -> tuple[_Tide, list[Transition]]:
    """The tide's decisions in the window and its transitions (the core is not changed)."""
    dd, dv = window.depth
    times, kinds = _merge(dd, np.zeros(0, np.int64), window.ticks)
    k_idx = _newest(kinds == KIND_TICK)
    d_idx = _newest(kinds == KIND_DEPTH)
    have = d_idx >= 0
    j = np.maximum(d_idx, 0)
    depth = np.where(have, dv[j] if len(dv) else math.nan, core.state.depth)
    ds = window.sample_s(None)
    depth_s = np.where(have, ds[j] if len(dd) else math.nan, core.state.depth_s)
    now = times * 1e-9
    timeout = core.config.alarm.depth_timeout
    with np.errstate(invalid='ignore'):
        blind = np.isnan(depth_s)
        stale = ~blind & (now - depth_s > timeout)
        bad = ~(np.isfinite(depth) & (depth > 0) & (depth <= MAX_DEPTH))
    level = np.where(blind | stale, Level.STALE, np.where(bad, Level.ERROR, Level.OK))
    code = _pick(k_idx, sensors.depth_codes, sensors.before_depth).astype(np.int64)
    level = _worse(
        level, np.where(code == sensor_state.OUT_OF_RANGE, Level.ERROR, Level.WARN), code
    )
    window_s = core.config.alarm.tide_trend_window
    rates, excess, trend = tide_trend.series(
        core.state.trend, window.sample_ns(None), dv, window_s
    )
    tide = _Tide(times, depth, depth_s, level, stale, rates, excess, trend, code, kinds)
    transitions = []
    old, entered = core.state.tide[0], core.state.tide_entered
    for i in _changed(level, old).tolist():
        new = _tide_at(core, tide, i)
        t = float(now[i])
        quiet = quiet_change(old, True, new[0], True)
        transitions.append(Transition(t, old, new[0], new[1], t - entered, quiet))
        old, entered = new[0], t
    return tide, transitions


@dataclass
class _Blind:
    """The sensors' common-cause alarm at the tide's decisions
    (core.rules.health.sensors_status)."""

    waiting: np.ndarray  # (decisions, lines) bool: the line has had no tension yet
    levels: np.ndarray  # int8 Level per decision
    transitions: list[Transition]
    acks: alarm_ack.AckSeries
    before: tuple[tuple[Level, str], int]  # the status and the lines waiting before the window


def _blind_at(core: MonitorCore, tide: _Tide, blind: _Blind, i: int) -> tuple[Level, str]:
    """The sensors alarm's (level, message) at tide decision ``i`` (as the core's
    ``_decide_blind``)."""
    a = core.config.alarm
    names = [line.config.name for line, w in zip(core.state.lines, blind.waiting[i]) if w]
    return sensors_status(
        names,
        len(core.state.lines),
        float(tide.depth_s[i]),
        bool(tide.stale[i]),
        float(tide.times[i] * 1e-9),
        core.state.start_s,
        a.tension_timeout,
        a.depth_timeout,
    )


def _decide_blind(core: MonitorCore, window: Window, tide: _Tide) -> _Blind:
    """The sensors alarm at every tide decision of the window, its transitions and its
    acknowledgement states; leaves the core's as after the window."""
    a, times = core.config.alarm, tide.times
    waiting = np.zeros((len(times), len(core.state.lines)), bool)
    for k, line in enumerate(core.state.lines):
        tt = window.tensions[k][0]
        if line.tension_s == line.tension_s:
            continue
        if not len(tt):
            waiting[:, k] = True
            continue
        # A tick follows the tensions of its own stamp; a depth sample goes before them.
        waiting[:, k] = (times < tt[0]) | ((times == tt[0]) & (tide.kinds == KIND_DEPTH))
    since = times * 1e-9 - core.state.start_s
    late = waiting.any(axis=1) & (since > a.tension_timeout)
    silent = tide.stale | (np.isnan(tide.depth_s) & (since > a.depth_timeout))
    levels = np.where(late | silent, Level.STALE, Level.OK).astype(np.int8)
    before = (core.state.sensors, core.state.sensors_waiting)
    acks = alarm_ack.AckSeries(core.state.sensors_ack, levels[:0], [])
    blind = _Blind(waiting, levels, [], acks, before)
    old, entered = core.state.sensors[0], core.state.sensors_entered
    for i in _changed(levels, old).tolist():
        new = _blind_at(core, tide, blind, i)
        t = float(times[i] * 1e-9)
        blind.transitions.append(Transition(t, old, new[0], new[1], t - entered))
        old, entered = new[0], t
    shelf = alarm_ack.shelved(core.state.sensors_ack)
    blind.acks = alarm_ack.replay_acks(
        core.state.sensors_ack,
        times * 1e-9,
        levels,
        masked=np.zeros(len(levels), np.int8) if shelf else None,
        flip_at=_changed(levels, core.state.sensors[0]),
        chatter=_chatter(core),
    )
    if len(times):
        core.state.sensors = _blind_at(core, tide, blind, len(times) - 1)
        core.state.sensors_waiting = int(waiting[-1].sum())
    core.state.sensors_entered = entered
    core.state.sensors_ack = blind.acks.final
    return blind


def _chatter(core: MonitorCore) -> tuple[int, float]:
    """The chattering rule: (chatter_count, chatter_window [s])."""
    a = core.config.alarm
    return int(a.chatter_count), a.chatter_window


def _journal(
    name: str, acks: alarm_ack.AckSeries, times_ns: np.ndarray, condition: Any
) -> list[tuple[int, AlarmEvent]]:
    """The journal records of an alarm's states over the window, with their step stamps
    [ns]; ``condition(i, state)`` is the condition a raise at step ``i`` names."""
    out: list[tuple[int, AlarmEvent]] = []
    old = acks.before
    for new, i in zip(acks.states, acks.changes.tolist()):
        if new is not old:
            stamp = int(times_ns[i])
            cond = condition(i, new) if raised(old, new) else ''
            out += [(stamp, e) for e in entries(name, old, new, stamp * 1e-9, cond)]
        old = new
    return out


def _write_tide(
    core: MonitorCore, window: Window, tide: _Tide, transitions: list[Transition]
) -> None:
    """The core's depth and tide state after the window's last event."""
    if len(tide.times):
        i = len(tide.times) - 1
        core.state.tide = _tide_at(core, tide, i)
        core.state.depth_stale = bool(tide.stale[i])
    if transitions:
        core.state.tide_entered = transitions[-1].time
    core.state.trend = tide.trend
    dd, dv = window.depth
    if len(dd):
        last = int(window.sample_ns(None)[-1])
        core.state.depth, core.state.depth_s = float(dv[-1]), float(last * 1e-9)
        core.state.depth_sample_ns = last


@dataclass
class _Dock:
    """The dock decisions at the window's ticks (the dock model only)."""

    decision: dock_live.DockDecision
    levels: np.ndarray  # int8 per tick
    before: tuple[tuple[Level, str], tuple[tuple[str, str], ...], list[tuple[float, ...]]]
    transitions: list[Transition]
    span_before: list[float]  # each line's dock_span before the window (m, NaN: installed)


def _decide_dock_window(core: MonitorCore, window: Window, tide: _Tide) -> Optional[_Dock]:
    """Every tick's dock estimate from each line's newest tension and the tide's decision
    there (the same arrays the core hands :func:`dock_live.decide_dock` one tick at a time);
    leaves the core's dock state as after the last tick."""
    model = core.dock_model
    if model is None:
        return None
    before = (core.state.dock, core.state.dock_values, [line.dock for line in core.state.lines])
    span_before = [line.dock_span for line in core.state.lines]
    ticks = window.ticks
    n = len(ticks)
    if n == 0:
        none = dock_live.DockDecision(*([None] * 5))  # type: ignore
        return _Dock(none, np.zeros(0, np.int8), before, [], span_before)
    now = ticks * 1e-9
    at = np.searchsorted(tide.times, ticks, 'right') - 1  # the tick's own tide decision
    depth = tide.depth[at]
    depth_ok = ~np.isnan(tide.depth_s[at]) & ~tide.stale[at]
    tension = np.empty((n, len(core.state.lines)))
    tension_s = np.empty((n, len(core.state.lines)))
    for k, line in enumerate(core.state.lines):
        tt, tv = window.tensions[k]
        j = np.searchsorted(tt, ticks, 'right') - 1  # tensions go before a tick at one stamp
        tension[:, k] = _pick(j, tv, line.tension)
        tension_s[:, k] = _pick(j, window.sample_s(k), line.tension_s)
    decision, core.state.dock_smoothing = dock_live.decide_dock(
        model, core.config, now, depth, depth_ok, tension, tension_s, core.state.dock_smoothing
    )
    levels = decision.level
    transitions = []
    old, entered = core.state.dock[0], core.state.dock_entered
    for i in _changed(levels, old).tolist():
        new = Level(int(levels[i]))
        t = float(now[i])
        message = dock_live.dock_message(model, decision, i)
        quiet = quiet_change(old, True, new, True)
        transitions.append(Transition(t, old, new, message, t - entered, quiet))
        old, entered = new, t
    core.state.dock = (Level(int(levels[-1])), dock_live.dock_message(model, decision, n - 1))
    core.state.dock_entered = entered
    core.state.dock_values = dock_live.dock_values(decision, n - 1)
    for k, line in enumerate(core.state.lines):
        line.dock = tuple(decision.line_inputs[-1, k].tolist())
        line.dock_span = float(decision.span[-1, k])
    return _Dock(decision, levels, before, transitions, span_before)


@dataclass
class _Steps:
    """One line's steps in a window and what each step sees."""

    times: np.ndarray  # ns
    kinds: np.ndarray  # int8
    t_idx: np.ndarray  # newest tension sample in the window (-1: the core's)
    d_idx: np.ndarray  # newest depth sample in the window (-1: the core's)
    dk_idx: np.ndarray  # newest tide decision in the window (-1: the core's)
    solved: np.ndarray  # bool: the line is solved at this step
    s_idx: np.ndarray  # newest solve in the window (-1: the core's)
    k_idx: np.ndarray  # newest tick in the window (-1: the core's)


def _line_steps(line: LineState, tt: np.ndarray, window: Window) -> _Steps:
    times, kinds = _merge(window.depth[0], tt, window.ticks)
    if _loops is not None:  # one loop instead of five cumulative sums
        n = len(kinds)
        t_idx, d_idx, dk_idx, k_idx, s_idx = np.empty((5, n), np.int64)
        solved = np.empty(n, bool)
        had = line.tension_s == line.tension_s  # a tension before the window
        kind_codes = (KIND_DEPTH, KIND_TENSION, KIND_TICK)
        _loops.newest(kinds, *kind_codes, had, t_idx, d_idx, dk_idx, k_idx, solved, s_idx)
        return _Steps(times, kinds, t_idx, d_idx, dk_idx, solved, s_idx, k_idx)
    t_idx = _newest(kinds == KIND_TENSION)
    known = (t_idx >= 0) | (line.tension_s == line.tension_s)
    solved = (kinds == KIND_TENSION) | ((kinds == KIND_DEPTH) & known)
    return _Steps(
        times,
        kinds,
        t_idx,
        _newest(kinds == KIND_DEPTH),
        _newest(kinds != KIND_TENSION),
        solved,
        _newest(solved),
        _newest(kinds == KIND_TICK),
    )


def _pick(idx: np.ndarray, column: np.ndarray, before: float) -> np.ndarray:
    """``column[idx]`` where ``idx >= 0``, else ``before`` (the core's value before the window)."""
    if (
        _loops is not None
        and len(column)
        and column.dtype == np.float64
        and isinstance(before, (float, int))
        and idx.dtype == np.int64
    ):
        out = np.empty(len(idx))
        _loops.pick(np.ascontiguousarray(idx), np.ascontiguousarray(column), before, out)
        return out
    if not len(column):
        return np.full(len(idx), before)
    # ``before`` appended last: index -1 (``_newest``'s "none yet") picks it, one gather; the
    # dtype as ``np.where`` would give it (a Python scalar does not widen the column)
    picked = np.append(column, before)[idx]
    return picked.astype(np.result_type(column, before), copy=False)


def _solve_line(
    core: MonitorCore,
    line: LineState,
    steps: _Steps,
    tv: np.ndarray,
    window: Window,
    tide: _Tide,
    sensors: _Sensors,
    k: int,
    waves: tuple[np.ndarray, np.ndarray],
    dock: Optional[_Dock] = None,
) -> tuple[dict[str, np.ndarray], np.ndarray, Optional[np.ndarray]]:
    """Values, status and elastic flags at the line's solved steps, with the time to uplift
    at the tide's trend of the newest depth sample and the sensor state of the newest tick;
    ``waves`` the wave window's peak and wave tension after each tension sample; each solve at
    the span of the newest tick's dock estimate (``dock``; None: the installed span)."""
    span = _spans(line, steps, dock, k)
    values, status, used = _solve_at(core, line, steps, tv, window, span[0])
    values['span'], values['span_source'] = span
    values['sensor_state'] = _pick(
        steps.k_idx[steps.solved], sensors.codes[:, k].astype(np.float64), sensors.before[k]
    )
    d_idx = steps.d_idx[steps.solved]
    t_idx = steps.t_idx[steps.solved]
    values['peak_tension'] = _pick(t_idx, waves[0], line.peak_tension)
    values['wave_tension'] = _pick(t_idx, waves[1], line.wave_tension)
    values.update(derived_values([line.config], core.config.alarm, values))
    margin, values['time_to_uplift_view'] = tide_trend.nearer_margin(
        values['tide_margin'], values['tide_margin_at_length']
    )
    a = core.config.alarm
    if a.constituents:
        now = _pick(d_idx, window.sample_s(None), core.state.depth_s)
        values['time_to_uplift'] = tide_table.uplift_times(
            a.constituents,
            a.tide_table_epoch,
            a.tide_forecast_horizon,
            now,
            margin,
            values['uplift_force'],
        )
    else:
        rate = _pick(d_idx, tide.rates, core.state.trend.rate)
        excess = _pick(d_idx, tide.excess, core.state.trend.excess)
        values['time_to_uplift'] = tide_trend.uplift_times(
            margin, values['uplift_force'], rate, excess
        )
    return values, status, used


def _spans(
    line: LineState, steps: _Steps, dock: Optional[_Dock], k: int
) -> tuple[np.ndarray, np.ndarray]:
    """The span [m] and ``span_source`` code at the line's solved steps: the newest tick's
    dock estimate (:func:`dock_live.solve_spans`), the installed span where it gives none."""
    n = int(np.count_nonzero(steps.solved))
    installed = line.config.anchor_distance
    if dock is None:
        return np.full(n, installed), np.full(n, float(dock_live.INSTALLED))
    column = dock.decision.span[:, k] if dock.decision.span is not None else np.zeros(0)
    estimate = _pick(steps.k_idx[steps.solved], column, dock.span_before[k])
    known = ~np.isnan(estimate)
    source = np.where(known, float(dock_live.DOCK_ESTIMATE), float(dock_live.INSTALLED))
    return np.where(known, estimate, installed), source


def _solve_at(
    core: MonitorCore,
    line: LineState,
    steps: _Steps,
    tv: np.ndarray,
    window: Window,
    span: Optional[np.ndarray] = None,
) -> tuple[dict[str, np.ndarray], np.ndarray, Optional[np.ndarray]]:
    """Values, status and elastic flags at the line's solved steps (the solver's part), at
    ``span`` [m] per solved step (None: the installed span)."""
    lc = line.config
    where = np.flatnonzero(steps.solved)
    tension = _pick(steps.t_idx[where], tv, line.tension)
    d_idx = steps.d_idx[where]
    dv = window.depth[1]
    h = _pick(d_idx, dv + lc.hook_height, core.state.depth + lc.hook_height)  # NaN: no depth yet
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
        values, status = solve_updates(lc, tension, h, _pick(d_idx, a_depth, a_before))
    _mark_implausible(values, status, used, reading_status_array(tension, h, lc.mbl, lc.weight))
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


def _line_inputs(
    core: MonitorCore,
    line: LineState,
    steps: _Steps,
    tide: _Tide,
    values: dict[str, np.ndarray],
    status: np.ndarray,
    window: Window,
    tt: np.ndarray,
    dock: Optional[_Dock] = None,
    k: int = 0,
    sensors: Optional[_Sensors] = None,
) -> dict[str, Any]:
    """The alarm inputs at every step of the line (newest solve, stamps, tide decision, the
    newest tick's dock estimate and sensor state)."""
    s = steps.s_idx
    before = dict(zip(VALUE_FIELDS, line.values))
    inputs: dict[str, Any] = {
        k: _pick(s, values[k], before[k])
        for k in (
            'uplift_force',
            'anchor_margin',
            'tide_margin',
            'load_margin',
            'safety_factor',
            'time_to_uplift',
            'uplift_force_upper',
            'drag_margin',
            'holding_capacity',
            'drag_state',
            'implied_anchor_distance',
            'fatigue_damage',
            'fatigue_life_left',
            'dynamic_uplift',
            'time_to_uplift_view',
            'channels_healthy',
            'channel_states',
            'span',
        )
    }
    inputs['status'] = np.maximum(_pick(s, status.astype(np.float64), line.status), 0).astype(
        np.int64
    )
    inputs['uplift_view'] = inputs.pop('time_to_uplift_view')
    inputs['tide_rate'] = _pick(steps.d_idx, tide.rates, core.state.trend.rate)
    inputs['tide_forecast'] = 1.0 if core.config.alarm.constituents else 0.0
    inputs['tension_stamp'] = _pick(steps.t_idx, window.sample_s(k), line.tension_s)
    inputs['depth_stamp'] = _pick(steps.d_idx, window.sample_s(None), core.state.depth_s)
    inputs['depth_stale'] = _pick(
        steps.dk_idx, tide.stale.astype(np.float64), float(core.state.depth_stale)
    ).astype(bool)
    if sensors is not None:
        codes = sensors.codes[:, k].astype(np.float64)
        inputs['sensor_state'] = _pick(steps.k_idx, codes, sensors.before[k])
        inputs['sensor_tension'] = _pick(steps.t_idx, window.tensions[k][1], line.tension)
        inputs['mbl'] = line.config.mbl
    if dock is not None:
        before_dock = dock.before[2][k]
        columns = dock.decision.line_inputs
        for j, key in enumerate(dock_live.LINE_INPUTS):
            col = columns[:, k, j] if columns is not None else np.zeros(0)
            inputs[key] = _pick(steps.k_idx, col, before_dock[j])
    return inputs


def _advance_line(
    core: MonitorCore,
    k: int,
    window: Window,
    tide: _Tide,
    sensors: _Sensors,
    dock: Optional[_Dock] = None,
) -> tuple[LineResult, LevelSeries, _Steps, alarm_ack.AckSeries, np.ndarray]:
    """One line through the window; leaves the line's state in the core as after the steps
    (the core's depth and tide still as before the window). The last item: the line's fatigue
    damage after each of its tension samples."""
    line = core.state.lines[k]
    tt, tv = window.tensions[k]
    steps = _line_steps(line, tt, window)
    times = window.sample_s(k)  # the reading times, as the core's tension_s
    peaks, waves, wave_state = wave_window.series(
        line.wave, times, tv, line.config.mbl, core.config.alarm.wave_window
    )
    values, status, used = _solve_line(
        core, line, steps, tv, window, tide, sensors, k, (peaks, waves), dock
    )
    line.wave = wave_state
    if len(tt):
        line.peak_tension, line.wave_tension = float(peaks[-1]), float(waves[-1])
    fatigue, fatigue_end = fatigue_rule.series(line.fatigue, times, tv, core.curves[k])
    at = steps.t_idx[steps.solved]
    for j, key in enumerate(fatigue_rule.FIELDS):
        values[key] = _pick(at, fatigue[key], line.fatigue_values[j])
    fused = window.channel_values.get(k)
    for j, key in enumerate(channels.FIELDS):
        column = fused[j] if fused is not None else np.zeros(0)
        values[key] = _pick(at, column, line.channel_values[j])
    inputs = _line_inputs(core, line, steps, tide, values, status, window, tt, dock, k, sensors)
    series = replay_levels(
        steps.times * 1e-9, inputs, line.alarm, status_messages(line.config), initial=line.state
    )
    masked = None
    unshelvable = core.config.alarm.unshelvable_conditions
    if alarm_ack.shelved(line.ack):
        hidden = shelving.hidden_conditions(line.ack.shelved_condition, unshelvable)
        masked = shelving.masked_levels(
            {c: series.active(c) for c in CONDITIONS}, series.stale, hidden
        )
    quiet = np.array([tr.suppressed for tr in series.transitions], bool)
    acks = alarm_ack.replay_acks(
        line.ack,
        steps.times * 1e-9,
        series.levels,
        series.suppressed,
        masked,
        series.changed_at[~quiet] if len(quiet) else None,
        _chatter(core),
    )
    line.ack = acks.final
    where = np.flatnonzero(steps.solved)
    result = LineResult(
        line.config.name,
        steps.times[where],
        steps.kinds[where],
        values,
        status,
        series.levels[where],
        steps.times,
        steps.kinds,
        series.levels,
        series.transitions,
        used,
        3 if line.config.point_loads is not None else 2,
    )
    _write_back(line, series, values, status, used, window.sample_ns(k), tv)
    line.fatigue = fatigue_end
    if len(tt):
        line.fatigue_values = tuple(float(fatigue[key][-1]) for key in fatigue_rule.FIELDS)
        if fused is not None:
            line.channel_values = (float(fused[0][-1]), float(fused[1][-1]))
    return result, series, steps, acks, np.asarray(fatigue[fatigue_rule.FIELDS[0]], np.float64)


def _write_back(
    line: LineState,
    series: LevelSeries,
    values: dict[str, np.ndarray],
    status: np.ndarray,
    used: Optional[np.ndarray],
    tt: np.ndarray,
    tv: np.ndarray,
) -> None:
    """The line's state after its last step in the window (``tt``: its samples' reading
    times, ns)."""
    line.state = series.final_state()
    if len(tt):
        line.tension, line.tension_s = float(tv[-1]), float(tt[-1] * 1e-9)
        line.sample_ns = int(tt[-1])
    if len(status):
        line.values = tuple(float(values[key][-1]) for key in VALUE_FIELDS)
        line.status = int(status[-1])
        table = status_messages(line.config)
        line.status_message = '' if line.status == NO_DEPTH else table[line.status]
        other = 3 if line.config.point_loads is not None else 2
        code = 0 if line.status == NO_DEPTH else (other if used is not None and used[-1] else 1)
        line.model = MODEL_NAMES[code]


def advance(core: MonitorCore, window: Window, snapshots: bool | str = False) -> WindowResult:
    """Step ``core`` through every event of ``window`` in vectorized code.

    Leaves ``core`` as ``core.step`` would, event by event (depth, tensions, tick at equal
    times), and returns what the steps did; ``snapshots=True`` also builds every diagnostic
    snapshot the core would have made (ticks and level changes); ``snapshots=COLUMNS``, the
    same as one :class:`SnapshotColumns` (or Snapshots where it falls back).
    """
    if len(window.tensions) != len(core.state.lines):
        raise ValueError(
            f'window has {len(window.tensions)} tension columns for '
            f'{len(core.state.lines)} lines'
        )
    given = window
    window, refusals = _accept(core, window)
    window = _fuse_channels(core, window)
    depth_before = (
        core.state.depth,
        core.state.depth_s,
        core.state.depth_stale,
        core.state.trend.rate,
    )
    tide_before = core.state.tide
    lines_before = [
        _Before(
            line.state.level,
            line.state.message,
            line.values,
            line.status,
            line.model,
            line.tension_s,
            [latch.active for latch in line.state.latches],
            (
                line_dock_values(line.state.latches[_INCONSISTENT].active, line.dock)
                if core.dock_model is not None
                else ()
            ),
            _line_word(core, line, line.sensor_code, line.state.latches[_INCONSISTENT].active),
        )
        for line in core.state.lines
    ]
    depth_word = depth_state_word(core.state.depth_s, core.state.depth_code)
    sensors = _decide_sensors_window(core, window, refusals)
    tide, tide_transitions = _decide_tide(core, window, sensors)
    blind = _decide_blind(core, window, tide)
    dock = _decide_dock_window(core, window, tide)
    results, series, steps, acks, damage = [], [], [], [], []
    for k, line in enumerate(core.state.lines):
        before = line.fatigue_values[0]
        r, s, st, a, d = _advance_line(core, k, window, tide, sensors, dock)
        results.append(r)
        series.append(s)
        steps.append(st)
        acks.append(a)
        damage.append(_Damage(window.tensions[k][0], d, before))
    journal, flood = _window_journal(core, window, tide, blind, series, steps, acks)
    times = [c[0] for c in (*given.tensions, given.depth, (given.ticks, None)) if len(c[0])]
    start = int(min(t[0] for t in times)) if times else core.state.last_ns
    end = int(max(t[-1] for t in times)) if times else core.state.last_ns
    snaps: list[Snapshot | SnapshotColumns] = []
    if snapshots:
        build = _snapshot_columns if snapshots == COLUMNS else _snapshots
        made = build(
            _Made(
                core, window, tide, results, series, steps, depth_before, tide_before,
                lines_before, acks, dock, sensors, depth_word, blind, flood, damage,
            )  # fmt: skip
        )
        snaps = [made] if isinstance(made, SnapshotColumns) else list(made)
    _write_tide(core, window, tide, tide_transitions)
    _write_refusals(core, refusals)
    core.state.last_ns = max(core.state.last_ns, end)
    others = [Change('sensors', tr) for tr in blind.transitions]
    others += [] if dock is None else [Change('dock', tr) for tr in dock.transitions]
    others += [Change(alarm_flood.NAME, tr) for tr in flood.transitions]
    return WindowResult(results, tide_transitions, snaps, start, end, others, alarm_events=journal)


def _window_journal(
    core: MonitorCore,
    window: Window,
    tide: _Tide,
    blind: _Blind,
    series: list[LevelSeries],
    steps: list[_Steps],
    acks: list[alarm_ack.AckSeries],
) -> tuple[list[AlarmEvent], _Flood]:
    """The window's alarm journal (the sensors alarm, each line's, the flood's) in the core's
    order (time; within one event the sensors, the lines, the flood), and the flood decisions."""
    unshelvable = core.config.alarm.unshelvable_conditions
    ranked: list[tuple[int, int, AlarmEvent]] = []
    sensors = _journal(
        alarm_ack.SENSORS, blind.acks, tide.times, lambda i, a: alarm_ack.condition(a.level, ())
    )
    ranked += [(t, -1, e) for t, e in sensors]
    for k, line in enumerate(core.state.lines):
        condition = _raised_condition(series[k], unshelvable)
        ranked += [
            (t, k, e) for t, e in _journal(line.config.name, acks[k], steps[k].times, condition)
        ]
    raises = [(t, k, e.alarm) for t, k, e in ranked if e.kind == 'raised']
    flood, flood_log = _decide_flood(core, window, raises)
    ranked += [(t, len(core.state.lines), e) for t, e in flood_log]
    ranked.sort(key=lambda r: (r[0], r[1]))
    return [e for _, _, e in ranked], flood


@dataclass
class _Refusals:
    """The arrival times (ns) of the samples refused for their header stamps in a window
    (:func:`catenary_monitor.core.rules.readings.stamp_faults`): per line, and the depth's."""

    lines: list[np.ndarray]
    depth: np.ndarray


def _accept(core: MonitorCore, window: Window) -> tuple[Window, _Refusals]:
    """The window without the stamped samples the core refuses (a header stamp ahead of the
    clock, or going backwards: they are no reading, as :meth:`MonitorCore.step` takes them),
    and when those arrived."""
    ahead_max = core.config.alarm.stamp_ahead_max
    none = np.zeros(0, np.int64)

    def split(
        column: Column, stamps: Optional[np.ndarray], last: int
    ) -> tuple[Column, Optional[np.ndarray], np.ndarray]:
        if stamps is None or not len(stamps):
            return column, stamps, none
        bad = readings.stamp_faults(column[0], stamps, last, ahead_max) != 0
        if not bad.any():
            return column, stamps, none
        ok = ~bad
        return (column[0][ok], column[1][ok]), stamps[ok], column[0][bad]

    if window.tension_stamps is None and window.depth_stamps is None:
        return window, _Refusals([none] * len(window.tensions), none)
    tensions, stamps, refused = [], [], []
    for k, line in enumerate(core.state.lines):
        own = None if window.tension_stamps is None else window.tension_stamps[k]
        column, st, r = split(window.tensions[k], own, line.sample_ns)
        tensions.append(column)
        stamps.append(st)
        refused.append(r)
    depth, d_stamps, d_refused = split(
        window.depth, window.depth_stamps, core.state.depth_sample_ns
    )
    kept = Window(tensions, depth, window.ticks, stamps, d_stamps, window.channels)
    return kept, _Refusals(refused, d_refused)


def _fuse_channels(core: MonitorCore, window: Window) -> Window:
    """The window with each line of several channels as one tension column: the core's
    channel step (core.channels) over its merged samples, in order (such lines are rare: a
    Python loop); the healthy counts and states go to ``channel_values``."""
    if window.channels is None or not any(c is not None for c in window.channels):
        return window
    tensions = list(window.tensions)
    values: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for k, line in enumerate(core.state.lines):
        idx = window.channels[k]
        if idx is None or line.channels is None:
            continue
        tt, raw = window.tensions[k]
        limits = channel_limits(core, line)
        line.channels, fused, healthy, states = channels.run(
            line.channels, idx, window.sample_s(k), raw, limits
        )
        tensions[k] = (tt, fused)
        values[k] = (healthy, states)
    out = Window(
        tensions,
        window.depth,
        window.ticks,
        window.tension_stamps,
        window.depth_stamps,
        window.channels,
    )
    out.channel_values = values
    return out


def _write_refusals(core: MonitorCore, refusals: _Refusals) -> None:
    """When a sample was last refused for its stamp, per line and the depth, after the window."""
    for line, r in zip(core.state.lines, refusals.lines):
        if len(r):
            line.stamp_refused = float(r[-1] * 1e-9)
    if len(refusals.depth):
        core.state.depth_refused = float(refusals.depth[-1] * 1e-9)


# --- snapshots -----------------------------------------------------------------------------------


class _Before(NamedTuple):
    """A line as the core held it before the window (for snapshots before its first step)."""

    level: Level
    message: str
    values: tuple[float, ...]
    status: int
    model: str
    tension_s: float
    latches: list[bool]
    extra: tuple[tuple[str, str], ...] = ()  # the dock model's line values
    sensor_word: str = 'ok'  # the /diagnostics sensor_state


def _line_word(core: MonitorCore, line: LineState, code: int, latched: bool) -> str:
    """A line's ``sensor_state`` word (its own state, else the dock model's)."""
    if core.dock_model is None:
        return sensor_state.line_word(code)
    return sensor_state.line_word(code, dock_live.sensor_state(latched, line.dock[0]))


def _changed(levels: np.ndarray, before: Level) -> np.ndarray:
    """Indexes where the level differs from the one before (the first against ``before``)."""
    return np.flatnonzero(np.diff(levels, prepend=np.int8(before)))


def _snapshot_stamps(
    window: Window,
    tide: _Tide,
    results: list[LineResult],
    tide_before: tuple[Level, str],
    lines_before: list[_Before],
    blind: Optional[_Blind] = None,
    flood: Optional[_Flood] = None,
) -> np.ndarray:
    """The stamps of the window's snapshots: its ticks and every level change [ns]."""
    parts = [window.ticks, tide.times[_changed(tide.level, tide_before[0])]]
    if blind is not None:
        parts.append(tide.times[_changed(blind.levels, blind.before[0][0])])
    if flood is not None:
        parts.append(flood.stamps[flood.changes])
    parts += [r.step_ns[_changed(r.step_level, b.level)] for r, b in zip(results, lines_before)]
    return np.unique(np.concatenate(parts))


def _tide_statuses(
    core: MonitorCore,
    window: Window,
    tide: _Tide,
    stamps: np.ndarray,
    depth_before: tuple[float, float, bool, float],
    tide_before: tuple[Level, str],
    depth_word: str,
) -> list[ComponentStatus]:
    """The tide status at each of ``stamps`` [ns]."""
    dd, dv = window.depth
    ds = window.sample_s(None)
    tide_at = np.searchsorted(tide.times, stamps, 'right') - 1
    depth_at = np.searchsorted(dd, stamps, 'right') - 1
    out = []
    for n, stamp in enumerate(stamps.tolist()):
        i, j = int(tide_at[n]), int(depth_at[n])
        depth = float(dv[j]) if j >= 0 else depth_before[0]
        depth_s = float(ds[j]) if j >= 0 else depth_before[1]
        rate = float(tide.rates[j]) if j >= 0 else depth_before[3]
        state = tide_before if i < 0 else _tide_at(core, tide, i)
        word = depth_word if i < 0 else depth_state_word(depth_s, int(tide.sensor[i]))
        age = stamp * 1e-9 - depth_s
        forecast = forecast_word(core.config, rate)
        out.append(tide_component(state, core.depth_id, depth, age, rate, word, forecast))
    return out


def _raised_condition(series: LevelSeries, unshelvable: Any) -> Any:
    """The condition a raise of the line's alarm at step ``i`` names (the visible one under
    the alarm's shelf), as the core's ``_raised_condition``."""

    def condition(i: int, ack: alarm_ack.AckState) -> str:
        latches = series.active_at(i)
        if alarm_ack.shelved(ack):
            hidden = shelving.hidden_conditions(ack.shelved_condition, unshelvable)
            latches = [on and c not in hidden for c, on in zip(CONDITIONS, latches)]
        return alarm_ack.condition(ack.level, latches)

    return condition


class _Flood(NamedTuple):
    """The flood decisions of a window (core.alarm_flood): decision stamps [ns] (raises and
    ticks), per decision the window's oldest raise and count, the flood's start decision (-1:
    the flood before the window, or none), the raises counted (times [s], alarms), the flood
    before the window, and the status's transitions."""

    stamps: np.ndarray
    lo: np.ndarray
    counted: np.ndarray
    start: np.ndarray
    times: np.ndarray
    names: list[str]
    before: alarm_flood.Flood
    status_before: tuple[Level, str]
    transitions: list[Transition]
    changes: np.ndarray  # the decisions at which the status's level changed

    def at(self, j: int) -> alarm_flood.Flood:
        """The flood decision ``j`` (-1: as before the window)."""
        if j < 0:
            return self.before
        lo, hi = int(self.lo[j]), int(self.lo[j] + self.counted[j])
        recent = tuple(zip(self.times[lo:hi].tolist(), self.names[lo:hi]))
        start = int(self.start[j])
        if start == -2:  # no flood
            return alarm_flood.Flood(recent)
        if start < 0:
            return alarm_flood.Flood(recent, self.before.since, self.before.first_out)
        first = int(self.lo[start])
        since = float(self.stamps[start] * 1e-9)
        return alarm_flood.Flood(recent, since, (self.names[first], float(self.times[first])))


def _decide_flood(
    core: MonitorCore, window: Window, raises: list[tuple[int, int, str]]
) -> tuple[_Flood, list[tuple[int, AlarmEvent]]]:
    """The flood decisions at the window's raises (stamp ns, rank, alarm) and ticks, their
    journal records; leaves the core's flood state as after the window."""
    a = core.config.alarm
    raises = sorted(raises)
    before, status_before = core.state.flood, core.state.alarms
    stamps = np.unique(np.concatenate([np.array([r[0] for r in raises], np.int64), window.ticks]))
    times = np.concatenate(
        [np.array([t for t, _ in before.recent]), np.array([r[0] for r in raises]) * 1e-9]
    )
    names = [n for _, n in before.recent] + [r[2] for r in raises]
    # Raises up to each decision by their stamps (ns: two events 1 ns apart share a float s).
    hi = len(before.recent) + np.searchsorted(
        np.array([r[0] for r in raises], np.int64), stamps, 'right'
    )
    lo, count = alarm_flood.counts(times, hi, stamps * 1e-9, a.flood_window)
    flooded = count > a.flood_count
    was = np.concatenate([[before.since == before.since], flooded[:-1]])
    starts = flooded & ~was
    episode = np.cumsum(starts)
    first = np.flatnonzero(starts)
    start = np.where(episode > 0, first[np.maximum(episode - 1, 0)] if len(first) else -1, -1)
    start = np.where(flooded, start, -2)
    changes = np.flatnonzero(flooded != was)
    flood = _Flood(stamps, lo, count, start, times, names, before, status_before, [], changes)
    log: list[tuple[int, AlarmEvent]] = []
    old, entered = status_before, core.state.alarms_entered
    for j in changes.tolist():
        now = float(stamps[j] * 1e-9)
        state = flood.at(j)
        new = alarm_flood.status(state, a)
        flood.transitions.append(Transition(now, old[0], new[0], new[1], now - entered))
        if flooded[j]:
            name, at = state.first_out
            event = AlarmEvent(now, alarm_flood.NAME, 'flood', 'WARN', by=name, value=at)
        else:
            ended = now - flood.at(j - 1).since
            event = AlarmEvent(now, alarm_flood.NAME, 'flood_end', value=ended)
        log.append((int(stamps[j]), event))
        old, entered = new, now
    if len(stamps):
        core.state.flood = flood.at(len(stamps) - 1)
        core.state.alarms = alarm_flood.status(core.state.flood, a)
    core.state.alarms_entered = entered
    return flood, log


class _Damage(NamedTuple):
    """A line's fatigue damage through the window: after each tension sample (stamps ns)."""

    times: np.ndarray
    damage: np.ndarray
    before: float


class _Made(NamedTuple):
    """What a window's recompute made, from which its snapshots are built."""

    core: MonitorCore
    window: Window
    tide: _Tide
    results: list[LineResult]
    series: list[LevelSeries]
    steps: list[_Steps]
    depth_before: tuple[float, float, bool, float]
    tide_before: tuple[Level, str]
    lines_before: list[_Before]
    acks: list[alarm_ack.AckSeries]
    dock: Optional[_Dock] = None
    sensors: Optional[_Sensors] = None
    depth_word: str = 'ok'
    blind: Optional[_Blind] = None
    flood: Optional[_Flood] = None
    damage: Optional[list['_Damage']] = None

    def max_damage(self, stamps: np.ndarray) -> list[Optional[float]]:
        """The worst line's fatigue damage as the core held it at each of ``stamps`` [ns]
        (after the tension samples at or before the stamp), for the ``fatigue`` status."""
        if not self.damage:
            return [None] * len(stamps)
        worst = np.full(len(stamps), -np.inf)
        for d in self.damage:
            at = np.searchsorted(d.times, stamps, 'right') - 1
            value = np.where(
                at >= 0, d.damage[np.maximum(at, 0)] if len(d.damage) else 0, d.before
            )
            worst = np.fmax(worst, value)
        return [float(v) for v in worst]

    def stamps(self) -> np.ndarray:
        """The stamps of the window's snapshots (:func:`_snapshot_stamps`)."""
        return _snapshot_stamps(
            self.window, self.tide, self.results, self.tide_before, self.lines_before, self.blind,
            self.flood,
        )  # fmt: skip

    def alarms_statuses(self, stamps: np.ndarray) -> list[ComponentStatus]:
        """The ``alarms`` status (the flood decision) at each of ``stamps`` [ns]."""
        flood = self.flood
        assert flood is not None
        at = np.searchsorted(flood.stamps, stamps, 'right') - 1
        a = self.core.config.alarm
        out = []
        for j in at.tolist():
            state = flood.at(j)
            status = flood.status_before if j < 0 else alarm_flood.status(state, a)
            out.append(self.core.alarms_component(status, state))
        return out

    def blind_statuses(self, stamps: np.ndarray) -> list[ComponentStatus]:
        """The sensors alarm's status at each of ``stamps`` [ns]."""
        blind = self.blind
        assert blind is not None
        at = np.searchsorted(self.tide.times, stamps, 'right') - 1
        out = []
        for i in at.tolist():
            if i < 0:
                state, waiting = blind.before
            else:
                state = _blind_at(self.core, self.tide, blind, i)
                waiting = int(blind.waiting[i].sum())
            out.append(sensors_component(state, blind.acks.at(i), waiting))
        return out

    def line_parts(self, k: int) -> tuple[
        LineState, LineResult, LevelSeries, _Steps, np.ndarray, _Before,
        alarm_ack.AckSeries, Optional[_Dock], Optional[_Sensors],
    ]:  # fmt: skip
        """Line ``k``'s state, result, levels, steps, tension reading times, state before the
        window, acknowledgements, and the window's dock and sensor states."""
        return (
            self.core.state.lines[k], self.results[k], self.series[k], self.steps[k],
            self.window.sample_ns(k), self.lines_before[k], self.acks[k], self.dock,
            self.sensors,
        )  # fmt: skip


def _snapshots(m: _Made) -> list[Snapshot]:
    """Every snapshot the core made in the window (ticks and level changes), built from the
    vectorized results."""
    core, window, tide, dock = m.core, m.window, m.tide, m.dock
    stamps = m.stamps()
    tides = _tide_statuses(core, window, tide, stamps, m.depth_before, m.tide_before, m.depth_word)
    blinds = m.blind_statuses(stamps)
    alarms = m.alarms_statuses(stamps)
    columns = [_line_statuses(m, k, stamps) for k in range(len(m.results))]
    tick_at = np.searchsorted(window.ticks, stamps, 'right') - 1
    logger = ComponentStatus(
        'catenary_monitor: logger', core.state.logger[0], core.state.logger[1], core.logger_id, ()
    )
    worst = m.max_damage(stamps)
    out = []
    for n, stamp in enumerate(stamps.tolist()):
        statuses = [col[n] for col in columns]
        statuses.append(tides[n])
        statuses.append(blinds[n])
        statuses.append(alarms[n])
        statuses.append(logger)
        if dock is not None:
            statuses.append(_dock_status(core, dock, int(tick_at[n])))
        statuses += core.guard_components(stamp * 1e-9, worst[n])
        out.append(Snapshot(stamp, tuple(statuses)))
    return out


def _dock_status(core: MonitorCore, dock: _Dock, i: int) -> ComponentStatus:
    """The dock status as after tick ``i`` of the window (-1: as before the window)."""
    if i < 0:
        return dock_component(dock.before[0], dock.before[1])
    assert core.dock_model is not None
    level = Level(int(dock.levels[i]))
    message = dock_live.dock_message(core.dock_model, dock.decision, i)
    return dock_component((level, message), dock_live.dock_values(dock.decision, i))


def _line_statuses(m: _Made, k: int, stamps: np.ndarray) -> list[ComponentStatus]:
    """The line's status in each snapshot (as after its newest step at or before the stamp)."""
    line, r, series, steps, tt, before, acks, dock, sensors = m.line_parts(k)
    at = np.searchsorted(steps.times, stamps, 'right') - 1
    models = r.model_codes  # once per window, not once per snapshot
    inconsistent = series.active('inconsistent') if dock is not None else None
    out = []
    for n, i in enumerate(at.tolist()):
        level, message = before.level, before.message
        values, status, model, ts = before.values, before.status, before.model, before.tension_s
        latches = before.latches
        extra, word = before.extra, before.sensor_word
        code = sensor_state.OK
        if i >= 0 and sensors is not None:
            j = int(steps.k_idx[i])
            code = sensors.before[k] if j < 0 else int(sensors.codes[j, k])
            word = sensor_state.line_word(code)
        if i >= 0 and dock is not None:
            j = int(steps.k_idx[i])
            inputs = dock.before[2][k] if j < 0 else tuple(dock.decision.line_inputs[j, k])
            assert inconsistent is not None
            latched = bool(inconsistent[i])
            extra = line_dock_values(latched, inputs)
            word = sensor_state.line_word(code, dock_live.sensor_state(latched, inputs[0]))
        if i >= 0:
            level, message = Level(int(series.levels[i])), series.message_at(i)
            latches = series.active_at(i)
            s, t = int(steps.s_idx[i]), int(steps.t_idx[i])
            if s >= 0:
                values = tuple(float(r.values[key][s]) for key in VALUE_FIELDS)
                status, model = int(r.status[s]), MODEL_NAMES[int(models[s])]
            if t >= 0:
                ts = float(tt[t] * 1e-9)
        out.append(
            line_status(
                line.config,
                line.hardware_id,
                level,
                message,
                values,
                status,
                model,
                stamps[n] * 1e-9 - ts,
                word,
                tuple(alarm_ack.diagnostic_values(acks.at(i), level, latches)) + extra,
            )
        )
    return out


# --- snapshots in columns (replay's --out: encoded without a ComponentStatus per status) -------

#: ``advance(..., snapshots=COLUMNS)``: the snapshots as :class:`SnapshotColumns`.
COLUMNS = 'columns'

#: A column of a :class:`StatusColumns`: a str (the same in every status) or one per status.
Field = str | list[str]


class StatusColumns(NamedTuple):
    """``n`` DiagnosticStatus of one shape (the same keys), in columns: ``levels`` (n,) and
    ``name``, ``message``, ``hardware_id`` and each key's value as :data:`Field` s."""

    levels: np.ndarray
    name: Field
    message: Field
    hardware_id: Field
    keys: tuple[str, ...]
    values: tuple[Field, ...]


class SnapshotColumns(NamedTuple):
    """The snapshots of a window at ``stamps`` (ns), in columns: ``groups`` of (statuses,
    ``m``): a :class:`StatusColumns` or a list of ComponentStatus, ``m * len(stamps)`` of them,
    snapshot ``n``'s being numbers ``k * len(stamps) + n`` for ``k < m``, groups in order.
    They are the same snapshots as :class:`Snapshot` s (``test/test_batch.py`` compares)."""

    stamps: np.ndarray
    groups: tuple[tuple[StatusColumns | list[ComponentStatus], int], ...]

    def snapshots(self) -> list[Snapshot]:
        """The same as :class:`Snapshot` s."""
        n = len(self.stamps)
        rows: list[list[ComponentStatus]] = []
        for group, m in self.groups:
            if isinstance(group, StatusColumns):
                rows.append(_column_statuses(group, m * n))
            else:
                rows.append(group)
        out = []
        for i, stamp in enumerate(self.stamps.tolist()):
            statuses = [row[k * n + i] for row, (_, m) in zip(rows, self.groups) for k in range(m)]
            out.append(Snapshot(stamp, tuple(statuses)))
        return out


def _column_statuses(c: StatusColumns, n: int) -> list[ComponentStatus]:
    def get(f: Field, i: int) -> str:
        return f if isinstance(f, str) else f[i]

    return [
        ComponentStatus(
            get(c.name, i),
            Level(int(c.levels[i])),
            get(c.message, i),
            get(c.hardware_id, i),
            tuple((k, get(v, i)) for k, v in zip(c.keys, c.values)),
        )
        for i in range(n)
    ]


def _reprs(values: np.ndarray) -> Field:
    """``repr(float(x))`` of each element (each distinct value's once: the bits compared, so
    that -0.0 and 0.0 stay apart), or the one str where all are the same."""
    bits = np.ascontiguousarray(values, np.float64).view(np.int64)
    if not len(bits):
        return []
    unique, inverse = np.unique(bits, return_inverse=True)
    texts = list(map(repr, unique.view(np.float64).tolist()))
    if len(texts) == 1:
        return texts[0]
    return [texts[i] for i in inverse.tolist()]


def _same(texts: list[str]) -> Field:
    """The one str where every element is it, else ``texts``."""
    return texts[0] if texts and texts.count(texts[0]) == len(texts) else texts


def _take(column: np.ndarray, idx: np.ndarray, before: Any, dtype: Any = np.float64) -> np.ndarray:
    """``column[idx]`` where ``idx >= 0``, else ``before``."""
    out = np.full(len(idx), before, dtype)
    ok = idx >= 0
    if ok.any():
        out[ok] = column[idx[ok]]
    return out


def _at(index: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``index[at]`` where ``at >= 0``, else -1."""
    return _take(index, at, -1, np.int64)


def _level_columns(
    series: LevelSeries, before: _Before, at: np.ndarray
) -> tuple[np.ndarray, list[str], list[str]]:
    """Level, message and the alarm's condition per stamp (after step ``at``, else as before
    the window)."""
    levels = _take(series.levels, at, int(before.level), np.int64)
    messages, conditions = [], []
    for i, level in zip(at.tolist(), levels.tolist()):
        if i < 0:
            messages.append(before.message)
            conditions.append(alarm_ack.condition(before.level, before.latches))
        elif level == Level.OK:
            messages.append('OK')
            conditions.append('none')
        else:
            messages.append(series.message_at(i))
            conditions.append(alarm_ack.condition(Level(level), series.active_at(i)))
    return levels, messages, conditions


def _word_columns(
    m: _Made, k: int, at: np.ndarray, j_tick: np.ndarray
) -> tuple[list[str], tuple[str, ...], list[list[str]]]:
    """The sensor state word per stamp, and the dock model's keys and values per stamp."""
    _, _, series, _, _, before, _, dock, sensors = m.line_parts(k)
    n = len(at)
    words = [before.sensor_word] * n
    extra: list[list[str]] = [[v for _, v in before.extra] for _ in range(n)]
    extra_keys = tuple(key for key, _ in before.extra)
    codes = [sensor_state.OK] * n
    at_list, j_list = at.tolist(), j_tick.tolist()
    if sensors is not None:
        for n_, (i, j) in enumerate(zip(at_list, j_list)):
            if i >= 0:
                codes[n_] = sensors.before[k] if j < 0 else int(sensors.codes[j, k])
                words[n_] = sensor_state.line_word(codes[n_])
    if dock is not None:
        inconsistent = series.active('inconsistent')
        inputs = dock.decision.line_inputs
        for n_, (i, j) in enumerate(zip(at_list, j_list)):
            if i >= 0:
                dock_in = dock.before[2][k] if j < 0 else tuple(inputs[j, k])
                latched = bool(inconsistent[i])
                pairs = line_dock_values(latched, dock_in)
                extra_keys = tuple(key for key, _ in pairs)
                extra[n_] = [v for _, v in pairs]
                words[n_] = sensor_state.line_word(
                    codes[n_], dock_live.sensor_state(latched, dock_in[0])
                )
    return words, extra_keys, extra


def _ack_columns(
    acks: alarm_ack.AckSeries, before: _Before, at: np.ndarray, conditions: list[str]
) -> tuple[tuple[str, ...], list[Field]]:
    """The alarm's acknowledgement keys and columns (the same for every step between two
    changes)."""
    j_ack = np.searchsorted(acks.changes, at, 'right') - 1
    j_ack[at < 0] = -1
    ack_cache: dict[int, list[tuple[str, str]]] = {}
    ack_rows = []
    for j in j_ack.tolist():
        row = ack_cache.get(j)
        if row is None:
            state = acks.before if j < 0 else acks.states[j]
            row = ack_cache[j] = alarm_ack.diagnostic_values(state, Level.OK, before.latches)
        ack_rows.append(row)
    ack_keys = tuple(key for key, _ in ack_rows[0]) if len(at) else ()
    ack_columns: list[Field] = []
    for a, key in enumerate(ack_keys):
        if key == 'alarm_condition':
            ack_columns.append(conditions)
        else:
            ack_columns.append([row[a][1] for row in ack_rows])
    return ack_keys, ack_columns


def _line_columns(m: _Made, k: int, stamps: np.ndarray) -> StatusColumns:
    """:func:`_line_statuses` in columns (the same strings, built per key, not per status)."""
    line, r, series, steps, tt, before, acks, _, _ = m.line_parts(k)
    at = np.searchsorted(steps.times, stamps, 'right') - 1
    levels, messages, conditions = _level_columns(series, before, at)
    # The newest solve's values, status and model.
    s = _at(steps.s_idx, at)
    values = {
        key: _take(r.values[key], s, float(before.values[j])) for j, key in enumerate(VALUE_FIELDS)
    }
    status = _take(r.status, s, int(before.status), np.int64)
    names = [*MODEL_NAMES, before.model]  # -1: the model before the window
    models = [names[c] for c in _take(r.model_codes, s, -1, np.int64).tolist()]
    t = _at(steps.t_idx, at)
    ts = _take(m.window.sample_s(k), t, float(before.tension_s))
    age = stamps * 1e-9 - ts
    words, extra_keys, extra = _word_columns(m, k, at, _at(steps.k_idx, at))
    ack_keys, ack_columns = _ack_columns(acks, before, at, conditions)
    # The keys and values, in line_status's order.
    config = line.config
    reprs = {key: _reprs(values[key]) for key in DIAGNOSTIC_KEYS if key in values}
    columns: list[Field] = [reprs.get(key, 'nan') for key in DIAGNOSTIC_KEYS]
    columns += [
        reprs['top_tension'] if 'top_tension' in reprs else _reprs(values[VALUE_FIELDS[0]]),
        _reprs(age),
        repr(config.anchor_distance),
        repr(config.allowed_uplift),
        _reprs(values[VALUE_FIELDS[9]]),
        _same(list(map(str, status.tolist()))),
        _same(models),
        _same(words),
        _same([view_word(v) for v in values['time_to_uplift_view'].tolist()]),
        _reprs(values['span']),
        _same([dock_live.span_word(v) for v in values['span_source'].tolist()]),
    ]
    columns += [f if isinstance(f, str) else _same(f) for f in ack_columns]
    columns += [_same([row[e] for row in extra]) for e in range(len(extra_keys))]
    keys = (
        *DIAGNOSTIC_KEYS,
        'measured_tension',
        'tension_age',
        'anchor_distance',
        'allowed_uplift',
        'anchor_angle_deg',
        'solver_status',
        'model',
        'sensor_state',
        'time_to_uplift_view',
        'span',
        'span_source',
        *ack_keys,
        *extra_keys,
    )
    return StatusColumns(
        levels,
        f'{NODE_NAME}: {config.name}',
        _same(messages),
        line.hardware_id,
        keys,
        tuple(columns),
    )


def _stack(columns: list[StatusColumns], n: int) -> StatusColumns:
    """Statuses of one shape, one after the other (constants kept where all agree)."""

    def cat(fields: list[Field]) -> Field:
        if all(isinstance(f, str) for f in fields) and len(set(fields)) == 1:
            return fields[0]
        out: list[str] = []
        for f in fields:
            out += [f] * n if isinstance(f, str) else f
        return out

    return StatusColumns(
        np.concatenate([c.levels for c in columns]),
        cat([c.name for c in columns]),
        cat([c.message for c in columns]),
        cat([c.hardware_id for c in columns]),
        columns[0].keys,
        tuple(cat([c.values[j] for c in columns]) for j in range(len(columns[0].keys))),
    )


def _snapshot_columns(m: _Made) -> SnapshotColumns | list[Snapshot]:
    """The snapshots of :func:`_snapshots` in columns (its Snapshot s where the statuses
    after the dock do not have one shape)."""
    core, window, tide, dock = m.core, m.window, m.tide, m.dock
    stamps = m.stamps()
    n = len(stamps)
    worst = m.max_damage(stamps)
    guards = [core.guard_components(stamp * 1e-9, w) for stamp, w in zip(stamps.tolist(), worst)]
    shapes = {tuple((g.name, len(g.values)) for g in row) for row in guards}
    if len(shapes) > 1:
        return _snapshots(m)
    lines = [_line_columns(m, k, stamps) for k in range(len(m.results))]
    groups: list[tuple[StatusColumns | list[ComponentStatus], int]] = []
    if lines and len({c.keys for c in lines}) == 1:
        groups.append((_stack(lines, n), len(lines)))
    else:
        groups += [(c, 1) for c in lines]
    tick_at = np.searchsorted(window.ticks, stamps, 'right') - 1
    tides = _tide_statuses(core, window, tide, stamps, m.depth_before, m.tide_before, m.depth_word)
    groups.append((tides, 1))
    groups.append((m.blind_statuses(stamps), 1))
    groups.append((m.alarms_statuses(stamps), 1))
    logger = ComponentStatus(
        'catenary_monitor: logger', core.state.logger[0], core.state.logger[1], core.logger_id, ()
    )
    groups.append(([logger] * n, 1))
    if dock is not None:
        groups.append(([_dock_status(core, dock, int(i)) for i in tick_at.tolist()], 1))
    width = len(guards[0]) if guards else 0
    if width:
        groups.append(([row[g] for g in range(width) for row in guards], width))
    return SnapshotColumns(stamps, tuple(groups))


def worst(result: LineResult) -> dict[str, Optional[dict[str, float]]]:
    """Worst value and its time (s) of each margin and force of a line over the log.

    Minimum of ``anchor_margin``, ``tide_margin``, ``load_margin``, ``safety_factor``; maximum of
    ``uplift_force`` and ``top_tension``. None when the quantity never had a value.
    """
    out: dict[str, Optional[dict[str, float]]] = {}
    for key, best in (
        ('anchor_margin', np.fmin),
        ('tide_margin', np.fmin),
        ('load_margin', np.fmin),
        ('safety_factor', np.fmin),
        ('uplift_force', np.fmax),
        ('top_tension', np.fmax),
    ):
        v = result.values[key]
        value = best.reduce(v) if len(v) else math.nan  # NaN only where every value is NaN
        if value != value:
            out[key] = None
            continue
        i = int(np.argmax(v == value))  # the first, as np.nanargmin (no NaN-free copy)
        out[key] = {'value': float(v[i]), 'time': float(result.t_ns[i] * 1e-9)}
    return out


# --- a whole log ---------------------------------------------------------------------------------


def slice_window(window: Window, lo: Optional[int], hi: Optional[int]) -> Window:
    """The events of ``window`` with ``lo <= t < hi`` (None: unbounded)."""

    def cut(times: np.ndarray) -> slice:
        a = 0 if lo is None else int(np.searchsorted(times, lo, 'left'))
        b = len(times) if hi is None else int(np.searchsorted(times, hi, 'left'))
        return slice(a, b)

    tensions = [(t[cut(t)], v[cut(t)]) for t, v in window.tensions]
    dt, dv = window.depth
    stamps = None
    if window.tension_stamps is not None:
        pairs = zip(window.tension_stamps, window.tensions)
        stamps = [None if s is None else s[cut(t)] for s, (t, _) in pairs]
    d_stamps = None if window.depth_stamps is None else window.depth_stamps[cut(dt)]
    chans = None
    if window.channels is not None:
        pairs_c = zip(window.channels, window.tensions)
        chans = [None if c is None else c[cut(t)] for c, (t, _) in pairs_c]
    return Window(
        tensions,
        (dt[cut(dt)], dv[cut(dt)]),
        window.ticks[cut(window.ticks)],
        stamps,
        d_stamps,
        chans,
    )


def concat_lines(parts: list[LineResult]) -> LineResult:
    """One line's results of consecutive windows as one."""
    if len(parts) == 1:
        return parts[0]
    cat_ = np.concatenate
    flags = [p.elastic for p in parts]
    used = (
        None
        if all(f is None for f in flags)
        else cat_([np.zeros(len(p.t_ns), bool) if f is None else f for p, f in zip(parts, flags)])
    )
    return LineResult(
        parts[0].name,
        cat_([p.t_ns for p in parts]),
        cat_([p.kind for p in parts]),
        {k: cat_([p.values[k] for p in parts]) for k in VALUE_FIELDS},
        cat_([p.status for p in parts]),
        cat_([p.level for p in parts]),
        cat_([p.step_ns for p in parts]),
        cat_([p.step_kind for p in parts]),
        cat_([p.step_level for p in parts]),
        [tr for p in parts for tr in p.transitions],
        used,
        parts[0].other_model,
    )


def run_log(
    core: MonitorCore, window: Window, events: Any = (), snapshots: bool | str = False
) -> tuple[WindowResult, MonitorCore]:
    """Advance ``core`` over a whole log; return the results and the core at the end.

    ``window`` holds the input columns and the ticks; ``events`` the other records in time
    order: logger changes and reconfigurations, stepped by the core itself between vectorized
    stretches (inputs before an event's stamp go first), and :class:`Start` (the monitor
    restarted: a new core, blind again, from then on). ``snapshots=COLUMNS``: the snapshots
    are the pieces' in order, then the events' (not merged in time: see
    :class:`SnapshotColumns`).
    """
    window, events, marks = _leave_out_coalesced(core, window, list(events))
    pieces: list[WindowResult] = []
    extra: list[Snapshot | SnapshotColumns] = []
    others: list[Change] = []
    journal: list[AlarmEvent] = []
    lo: Optional[int] = None
    for event in [*events, None]:
        hi = None if event is None else event.stamp_ns
        pieces.append(advance(core, slice_window(window, lo, hi), snapshots))
        journal += pieces[-1].alarm_events
        if isinstance(event, Start):
            core = MonitorCore(
                core.config, event.stamp_ns, _ids(core), core.depth_id, core.logger_id
            )
        elif event is not None:
            step = core.step(event)
            others += list(step.transitions)
            journal += step.alarm_events
            if snapshots and step.snapshot is not None:
                extra.append(step.snapshot)
        lo = hi
    _keep_marks(core, marks, events)
    lines = [concat_lines([p.lines[k] for p in pieces]) for k in range(len(core.state.lines))]
    tide = [tr for p in pieces for tr in p.tide]
    others = sorted(
        others + [c for p in pieces for c in p.others], key=lambda c: c.transition.time
    )
    snaps = [s for p in pieces for s in p.snapshots] + extra
    if snapshots != COLUMNS:
        snaps.sort(key=lambda s: s.stamp_ns)  # type: ignore[union-attr]
    return (
        WindowResult(
            lines,
            tide,
            snaps,
            min(p.start_ns for p in pieces),
            max(p.end_ns for p in pieces),
            others,
            alarm_events=journal,
        ),
        core,
    )


def _leave_out_coalesced(
    core: MonitorCore, window: Window, events: list[Any]
) -> tuple[Window, list[Any], list[Coalesced]]:
    """The window without the samples the node coalesced (:class:`Coalesced` records: each
    leaves out its input's samples stamped after it and at most its ``last_ns``, and the core
    carries the newest bound into the next window), the other events, and the records."""
    marks = [e for e in events if isinstance(e, Coalesced)]
    if marks:
        events = [e for e in events if not isinstance(e, Coalesced)]
    carried = [line.coalesced_until for line in core.state.lines]
    if not marks and max(carried + [core.state.depth_coalesced_until]) < 0:
        return window, events, marks
    index = {line.config.name: k for k, line in enumerate(core.state.lines)}
    keep = [
        _kept(column[0], carried[k], [m for m in marks if index.get(m.line or '') == k])
        for k, column in enumerate(window.tensions)
    ]
    d_keep = _kept(
        window.depth[0], core.state.depth_coalesced_until, [m for m in marks if m.line is None]
    )

    def cut(array: Optional[np.ndarray], kept: Optional[np.ndarray]) -> Optional[np.ndarray]:
        return array if array is None or kept is None else array[kept]

    tension_stamps = window.tension_stamps
    if tension_stamps is not None:
        tension_stamps = [cut(s, kept) for s, kept in zip(tension_stamps, keep)]
    chans = window.channels
    if chans is not None:
        chans = [cut(c, kept) for c, kept in zip(chans, keep)]
    return (
        Window(
            [
                column if kept is None else (column[0][kept], column[1][kept])
                for column, kept in zip(window.tensions, keep)
            ],
            window.depth if d_keep is None else (window.depth[0][d_keep], window.depth[1][d_keep]),
            window.ticks,
            tension_stamps,
            cut(window.depth_stamps, d_keep),
            chans,
        ),
        events,
        marks,
    )


def _keep_marks(core: MonitorCore, marks: list[Coalesced], events: list[Any]) -> None:
    """What the core keeps of the window's coalescing records (those since its last start):
    each input's newest bound, and the newest stamp."""
    starts = [e.stamp_ns for e in events if isinstance(e, Start)]
    kept = [m for m in marks if not starts or m.stamp_ns > max(starts)]
    if not kept:
        return
    last = core.state.last_ns
    for mark in kept:
        core.step(mark)
    core.state.last_ns = max(last, max(m.stamp_ns for m in kept))


def _kept(t: np.ndarray, carried: int, marks: list[Coalesced]) -> Optional[np.ndarray]:
    """Which samples stamped ``t`` [ns] stay: not those at most ``carried`` nor inside a
    record's ``(stamp_ns, last_ns]`` (None: all of them)."""
    out = t <= carried
    if marks:
        starts = np.array([m.stamp_ns for m in marks], np.int64)
        ends = np.array([m.last_ns for m in marks], np.int64)
        order = np.argsort(starts, kind='stable')
        starts, ends = starts[order], ends[order]
        at = np.searchsorted(starts, t, 'left') - 1  # the newest record before each sample
        out |= (at >= 0) & (t <= ends[np.maximum(at, 0)])
    return ~out if out.any() else None


def _ids(core: MonitorCore) -> dict[str, str]:
    return {line.config.name: line.hardware_id for line in core.state.lines}


@dataclass
class ReplayResult(WindowResult):
    """:func:`recompute` of a log: the :class:`WindowResult` and the ticks it used (ns),
    taken from the log's events channel (``ticks_from_log``) or on a grid at
    ``diagnostic_rate``."""

    tick_ns: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    ticks_from_log: bool = False
    started_ns: int = 0  # when the monitor started (blind)
    events: list[Any] = field(default_factory=list)  # the other records it was given


def recompute(
    config: MonitorConfig,
    tensions: dict[str, Column],
    depth: Column,
    tick_ns: Optional[np.ndarray] = None,
    events: Any = (),
    start_ns: Optional[int] = None,
    snapshots: bool = False,
) -> ReplayResult:
    """Every step of a recorded log, as the monitor made them.

    Parameters
    ----------
    config : the monitor configuration (lines, topics, alarm settings).
    tensions : line name -> (receive time ns, tension N), sorted (a missing line: none).
    depth : (receive time ns, tide depth m), sorted.
    tick_ns : the ticks (ns), as the node recorded them; None: a grid at ``diagnostic_rate``
        from ``start_ns`` to the last message.
    events : the node's other records in time order (:class:`Start`, logger changes,
        reconfigurations).
    start_ns : when the monitor started (blind); default the first message.
    snapshots : also build every diagnostic snapshot.
    """
    columns = [tensions.get(line.name, _EMPTY) for line in config.lines]
    stamps = [c[0] for c in (*columns, depth) if len(c[0])]
    first = int(min(t[0] for t in stamps)) if stamps else 0
    last = int(max(t[-1] for t in stamps)) if stamps else 0
    start = first if start_ns is None else int(start_ns)
    from_log = tick_ns is not None
    if tick_ns is None:
        tick_ns = (
            tick_grid(start, last, config.alarm.diagnostic_rate)
            if stamps
            else np.zeros(0, np.int64)
        )
    ticks = np.sort(np.asarray(tick_ns, np.int64))
    core = MonitorCore(config, start)
    result, _ = run_log(core, Window(columns, depth, ticks), events, snapshots)
    return ReplayResult(
        result.lines,
        result.tide,
        result.snapshots,
        min(start, result.start_ns),
        result.end_ns,
        result.others,
        ticks,
        from_log,
        start,
        list(events),
        alarm_events=result.alarm_events,
    )
