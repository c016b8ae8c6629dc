"""The twin's data: a :class:`Window` of log columns (its events), what the twin made of it
(:class:`LineResult`, :class:`WindowResult`; the snapshots in columns: :class:`SnapshotColumns`),
and the helpers on them: :func:`tick_grid` (and :func:`grid_ticks` over a log's silences),
:func:`slice_window`, :func:`concat_lines`,
:func:`worst`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple, Optional

import numpy as np

from catenary_monitor.core.alarms.journal import AlarmEvent
from catenary_monitor.core.alarms.latches import Transition
from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.monitor.state import NO_DEPTH, NO_MODEL, VALUE_FIELDS
from catenary_monitor.core.monitor.status import Change, ComponentStatus, Snapshot
from catenary_monitor.core.physics import elastic, point_loads
from catenary_monitor.core.rules.level import Level

__all__ = [
    'MODEL_NAMES',
    'KIND_DEPTH',
    'KIND_TENSION',
    'KIND_TICK',
    'Column',
    'EMPTY',
    'Window',
    'LineResult',
    'WindowResult',
    'tick_grid',
    'quiet_span',
    'grid_ticks',
    'COLUMNS',
    'Field',
    'StatusColumns',
    'SnapshotColumns',
    'worst',
    'slice_window',
    'concat_lines',
]


#: Model names by :attr:`LineResult.model_codes` (as the ``/diagnostics`` key ``model``).
MODEL_NAMES = (NO_MODEL, elastic.INEXTENSIBLE, elastic.ELASTIC, point_loads.MODEL)


#: Step kinds in :attr:`LineResult.kind` and :attr:`LineResult.step_kind`.
KIND_DEPTH, KIND_TENSION, KIND_TICK = 0, 1, 2


Column = tuple[np.ndarray, np.ndarray]  # (receive times ns int64, values float64), sorted


EMPTY: Column = (np.zeros(0, np.int64), np.zeros(0))


@dataclass
class Window:
    """Events of a stretch of log, each column sorted by time (ns): ``tensions`` per line
    (config order), ``depth``, and the ``ticks``. ``tension_stamps`` (per line) and
    ``depth_stamps``: the header stamps (ns) of a stamped input's samples, beside its column
    (None: taken at arrival, the column's time)."""

    tensions: list[Column]
    depth: Column = EMPTY
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
    #: The alarm journal's records (core.alarms.journal), in time order (keyword only).
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


def quiet_span(config: MonitorConfig) -> float:
    """How long [s] a grid of ticks goes on after an input when no other follows.

    Without inputs, what a tick can still change runs on the clock: an input goes stale
    (``tension_timeout``, ``depth_timeout``), a raise waits ``on_delay``, a sensor state held
    since the last sample ends (``sensor_hold``, ``parted_window``, ``stuck_time``) and its
    latch clears after a clear hold; then what counts those changes over a window
    (``flood_window``, ``chatter_window``) or smooths the dock (``dock_residual_time``) forgets
    them. The longest such chain, and two periods more: a tick later in the same silence
    decides nothing new (its snapshot differs only in the ages it shows), so the grid does not
    tick through it, and a silence of days costs what one of this length does."""
    a = config.alarm
    held = max(a.sensor_hold, a.parted_window, a.stuck_time) + max(
        a.clear_hold, a.warn_clear_hold
    )
    first = max(a.tension_timeout, a.depth_timeout, a.on_delay, held)
    windows = max(a.flood_window, a.chatter_window, config.dock.residual_time)
    return first + windows + 2.0 / a.diagnostic_rate


def grid_ticks(
    start_ns: int,
    rate_hz: float,
    k0: int,
    inputs: np.ndarray,
    before_ns: Optional[int],
    quiet_ns: int,
    end_ns: int,
    cap: Optional[int] = None,
) -> tuple[np.ndarray, int]:
    """The grid ticks ``start + rint(k * 1e9 / rate)`` (ns) with ``k >= k0``, at or before
    ``end_ns``, that follow an input by at most ``quiet_ns`` (:func:`quiet_span`), at most
    ``cap`` of them (the first); and the k after the last one given (``k0`` if none).

    ``inputs``: the input stamps (ns, sorted) of a stretch of log; ``before_ns`` the newest
    input before them (None: none). The ticks are a set defined by the whole log (every grid
    point within ``quiet_ns`` after an input), so a log cut in windows gets the same ones.
    The work is in the inputs and the ticks given, never in the time they span."""
    period = 1e9 / rate_hz
    s = np.asarray(inputs, np.int64)
    if before_ns is not None:
        s = np.concatenate([np.array([before_ns], np.int64), s])
    if not len(s) or end_ns < s[0]:
        return np.zeros(0, np.int64), k0
    breaks = np.flatnonzero(np.diff(s) > quiet_ns)
    lo = s[np.concatenate([[0], breaks + 1])]
    hi = np.minimum(s[np.concatenate([breaks, [len(s) - 1]])] + quiet_ns, end_ns)
    keep = hi >= lo
    lo, hi = lo[keep], hi[keep]
    # Each stretch's candidate k: one period of slack either side for the rounding.
    ka = np.maximum(np.floor((lo - start_ns) / period).astype(np.int64) - 1, k0)
    kb = np.floor((hi - start_ns) / period).astype(np.int64) + 1
    every = np.maximum(kb - ka + 1, 0)
    budget = None if cap is None else int(cap) + 2
    while True:
        count = every
        if budget is not None:  # the candidates of the first ``budget`` (some fall out)
            count = np.minimum(every, np.maximum(budget - (np.cumsum(every) - every), 0))
        total = int(count.sum())
        first = np.cumsum(count) - count
        k = np.repeat(ka, count) + (np.arange(total, dtype=np.int64) - np.repeat(first, count))
        ticks = start_ns + np.rint(k * period).astype(np.int64)
        inside = (ticks >= np.repeat(lo, count)) & (ticks <= np.repeat(hi, count))
        k, ticks = k[inside], ticks[inside]
        if cap is None or len(k) >= cap or total == int(every.sum()):
            break
        budget = 2 * budget  # type: ignore[operator]
    if cap is not None:
        k, ticks = k[:cap], ticks[:cap]
    return ticks, (int(k[-1]) + 1 if len(k) else k0)


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


#: The values :func:`worst` reads.
WORST_KEYS = (
    'anchor_margin',
    'tide_margin',
    'load_margin',
    'safety_factor',
    'uplift_force',
    'top_tension',
)


def worst(result: LineResult) -> dict[str, Optional[dict[str, float]]]:
    """Worst value and its time (s) of each margin and force of a line over the log.

    Minimum of ``anchor_margin``, ``tide_margin``, ``load_margin``, ``safety_factor``; maximum of
    ``uplift_force`` and ``top_tension``. None when the quantity never had a value.
    """
    out: dict[str, Optional[dict[str, float]]] = {}
    for key in WORST_KEYS:
        best = np.fmax if key in ('uplift_force', 'top_tension') else np.fmin
        v = result.values[key]
        value = best.reduce(v) if len(v) else math.nan  # NaN only where every value is NaN
        if value != value:
            out[key] = None
            continue
        i = int(np.argmax(v == value))  # the first, as np.nanargmin (no NaN-free copy)
        out[key] = {'value': float(v[i]), 'time': float(result.t_ns[i] * 1e-9)}
    return out


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
