"""Replay outputs: CSV rows, an MCAP results log, PNG charts and the summary (text or JSON).

No rclpy: the MCAP messages are encoded by :mod:`catenary_monitor.io.cdr` and written by
:mod:`catenary_monitor.io.mcap_column_writer`.
"""

from __future__ import annotations

import dataclasses

import datetime as _dt
import functools
import json
import math
from pathlib import Path
from typing import IO, Any, Callable, Optional, Sequence

import numpy as np

from catenary_monitor import __version__
from catenary_monitor.core.config.parameters import (
    FLOAT64,
    MonitorConfig,
    config_hash,
    config_to_params,
)
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules import holding, sensor_state
from catenary_monitor.core.alarms.latches import VIEW_TEXT
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.events import (
    EVENTS_TOPIC,
    NODE_NAME,
    Event,
    Start,
    Tick,
    event_record,
)
from catenary_monitor.core.twin.window import (
    MODEL_NAMES,
    LineResult,
    SnapshotColumns,
    StatusColumns,
    WORST_KEYS,
    worst,
)
from catenary_monitor.core.monitor.state import NO_DEPTH, OUTPUT_FIELDS, VALUE_FIELDS
from catenary_monitor.core.twin.engine import ReplayResult
from catenary_monitor.replay.driver import stamp_lines
from catenary_monitor.io.cdr import (
    diagnostic_array_bodies,
    diagnostic_array_parts,
    float64_payloads,
    key_values,
    multiarray_payloads,
    status_bodies,
    status_body,
    status_header,
    string_message,
)
from catenary_monitor.core.physics.result import Status
from catenary_monitor.io.ros_schemas import (
    QOS_DEFAULT,
    QOS_SENSOR_DATA,
    message_definition,
    type_description_hash,
)

__all__ = [
    'CSV_ALL',
    'CSV_COLUMNS',
    'NODE_NAME',
    'message_columns',
    'write_csv',
    'write_mcap',
    'write_plots',
    'summary_dict',
    'summary_text',
    'output_topic',
    'snapshot_payloads',
]

#: Every CSV column, in order, with its decimals (None: a label). Units: s, N, m, -.
#: ``time`` is exact (ns); forces have 3 decimals (1 mN), lengths 3 (1 mm), the safety factor 3,
#: ``time_to_uplift`` 3 (s; ``inf`` when no uplift is coming, ``nan`` while unknown); the bounds
#: and holding values (forces, lengths) 3 (``nan`` where the line has no solve or holding data);
#: ``time_to_uplift_view`` ``chain length held``, ``horizontal tension held`` or ``none``;
#: ``span`` the hook-anchor distance the line was solved at (m, 3 decimals) and
#: ``span_source`` where it came from (``installed``, ``dock_estimate``); ``sensor_state``
#: the line's sensor state word (``ok``, ``stuck``, ``spike``, ``over_mbl``, ``slack``,
#: ``suspected_parted``); ``drag_state`` the anchor's (``holding``, ``overloaded``,
#: ``dragging``, ``unknown``).
CSV_ALL: tuple[tuple[str, Optional[int]], ...] = (
    ('time', 9),
    ('line', None),
    ('top_tension', 3),
    ('depth', 3),
    ('horizontal_tension', 3),
    ('min_anchor_distance', 3),
    ('anchor_margin', 3),
    ('uplift_force', 3),
    ('tide_margin', 3),
    ('load_margin', 3),
    ('safety_factor', 3),
    ('time_to_uplift', 3),  # s
    # The bounds within sensor accuracy (core/rules/uncertainty.py) and holding
    # (core/rules/holding.py).
    ('uplift_force_upper', 3),
    ('anchor_margin_lower', 3),
    ('tide_margin_lower', 3),
    ('grounded_length', 3),
    ('holding_capacity', 3),
    ('drag_margin', 3),
    ('implied_anchor_distance', 3),
    ('tide_margin_at_length', 3),
    # The wave window and the dynamic uplift (core/rules/wave_window.py), and which view the
    # time to uplift counts down (a word: core.monitor.status.view_word).
    ('wave_tension', 3),
    ('peak_tension', 3),
    ('dynamic_uplift', 3),
    ('time_to_uplift_view', None),
    ('sensor_state', None),  # core.rules.sensor_state.LINE_STATES word
    ('status', None),
    ('level', None),
    ('model', None),
    ('drag_state', None),  # core.rules.holding.DRAG_STATES word, or unknown
    # Chain fatigue (core/rules/fatigue.py): Miner's damage, its rate (1/s), life left (s).
    ('fatigue_damage', 12),
    ('fatigue_damage_rate', 12),
    ('fatigue_life_left', 0),
    # A line of several channels (core/rules/channels.py): healthy count, states code.
    ('channels_healthy', 0),
    ('channel_states', 0),
    # The span solved at and its source (core/rules/dock_watch.py: a word).
    ('span', 3),
    ('span_source', None),
)
#: The default columns (the issue's contract), in this order.
CSV_COLUMNS = (
    'time',
    'line',
    'top_tension',
    'depth',
    'min_anchor_distance',
    'anchor_margin',
    'uplift_force',
    'level',
)
_LEVELS = [lv.name for lv in sorted(Level)]
_STATUS_LABELS = [str(s) for s in range(NO_DEPTH, max(Status) + 1)]  # every solver code

Progress = Optional[Callable[[str, float], None]]


def output_topic(line: str) -> str:
    """The node's per-line output topic (``~/NAME/outputs`` of node ``catenary_monitor``)."""
    return f'/{NODE_NAME}/{line}/outputs'


def _tension_rows(
    result: ReplayResult, keys: Sequence[str] = VALUE_FIELDS
) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray]:
    """All lines' tension updates merged in time order (stable: config order at equal times):
    times, the value columns ``keys``, line index, status and level."""
    parts = [(r, r.tension_rows) for r in result.lines]
    t = np.concatenate([r.t_ns[rows] for r, rows in parts])
    line = np.concatenate([np.full(len(rows), k, np.int64) for k, (_, rows) in enumerate(parts)])
    order = np.argsort(t, kind='stable')
    # Each column: the lines' whole arrays joined into one buffer (reused: a fresh array per
    # column cost its page faults), then one gather of the rows in time order (``np.take``):
    # 38 columns of 200 000 rows in 14 ms where a fresh join and ``[pick]`` took 41.
    offsets = np.cumsum([0] + [len(r.t_ns) for r, _ in parts[:-1]])
    pick = np.concatenate([rows + off for (_, rows), off in zip(parts, offsets.tolist())])
    pick = pick[order]
    buffers: dict[np.dtype, np.ndarray] = {}

    def joined(arrays: list[np.ndarray]) -> np.ndarray:
        kind = np.result_type(*arrays)
        if kind not in buffers:
            buffers[kind] = np.empty(sum(len(a) for a in arrays), kind)
        return np.take(np.concatenate(arrays, out=buffers[kind]), pick)

    values = {k: joined([r.values[k] for r in result.lines]) for k in VALUE_FIELDS if k in keys}
    status = (
        joined([r.status for r in result.lines]) if 'status' in keys else np.zeros(0, np.int64)
    )
    level = joined([r.level for r in result.lines])
    if 'model' in keys:
        values['model'] = joined([r.model_codes for r in result.lines])
    return t[order], values, line[order], status, level


def write_csv(
    stream: IO[bytes],
    result: ReplayResult,
    progress: Progress = None,
    columns: Sequence[str] = CSV_COLUMNS,
    header: bool = True,
) -> int:
    """One row per tension message, in time order; returns the number of rows (``header``:
    the header line first; a streamed replay writes it with its first window only).

    ``columns`` are names from :data:`CSV_ALL` (written in that order): ``time`` is the
    receive time in s (exact ns), forces in N and lengths in m with 3 decimals, ``status`` the
    solver code (-1: no depth yet, 0: solved), ``level`` OK/WARN/ERROR/STALE after the update,
    ``model`` the model that answered (``inextensible catenary`` or ``elastic catenary``;
    ``none`` before the first depth).
    """
    unknown = set(columns) - {name for name, _ in CSV_ALL}
    if unknown:
        raise ValueError(
            f'unknown CSV column(s) {sorted(unknown)}; known: '
            + ', '.join(name for name, _ in CSV_ALL)
        )
    # the formatter's tables (built on import) only for a CSV: not a summary's start
    from catenary_monitor.io.csv_columns import FloatColumn, IntColumn, LabelColumn, write_rows

    decimals = dict(CSV_ALL)
    out_columns: list[Any] = []
    n = 0
    for name, column in message_columns(result, columns).items():
        if name == 'time':
            out_columns.append(IntColumn(name, column, 9))
            n = len(column)
        elif isinstance(column, tuple):
            out_columns.append(LabelColumn(name, column[0], column[1]))
            n = len(column[0])
        else:
            out_columns.append(FloatColumn(name, column, decimals[name] or 0))
            n = len(column)
    step = max(1 << 18, n // 10)
    for lo in range(0, max(n, 1 if header else 0), step):
        hi = min(n, lo + step)
        write_rows(stream, out_columns, hi, header=header and lo == 0, start=lo)
        if progress is not None:
            progress('writing CSV', hi / max(n, 1))
    return n


def message_columns(
    result: ReplayResult, columns: Sequence[str] = CSV_COLUMNS
) -> dict[str, Any]:
    """The CSV's rows as columns (one per tension message, in time order), in :data:`CSV_ALL`
    order: ``time`` int64 ns, a label column as (int codes, labels), the others float64 (SI,
    full precision): what :func:`write_csv` prints and the fleet's dataset stores."""
    wanted = [name for name, _ in CSV_ALL if name in set(columns)]
    t, values, line, status, level = _tension_rows(result, wanted)
    out: dict[str, Any] = {}
    for name in wanted:
        if name == 'time':
            out[name] = t
        elif name == 'line':
            out[name] = (line, [r.name for r in result.lines])
        elif name == 'status':
            out[name] = (status - NO_DEPTH, _STATUS_LABELS)
        elif name == 'level':
            out[name] = (level, _LEVELS)
        elif name == 'model':
            out[name] = (values['model'], list(MODEL_NAMES))
        elif name == 'sensor_state':
            out[name] = (values[name].astype(np.int64), list(sensor_state.LINE_STATES))
        elif name == 'drag_state':
            codes = np.where(np.isnan(values[name]), 3, values[name]).astype(np.int64)
            out[name] = (codes, [*holding.DRAG_STATES, 'unknown'])
        elif name == 'span_source':
            codes = np.where(np.isnan(values[name]), 2, values[name]).astype(np.int64)
            out[name] = (codes, [*dock_live.SPAN_SOURCES, 'none'])
        elif name == 'time_to_uplift_view':
            view = values[name]
            codes = np.where(np.isnan(view), 0, np.where(view == 1.0, 2, 1)).astype(np.int64)
            out[name] = (codes, ['none', VIEW_TEXT[0.0], VIEW_TEXT[1.0]])
        else:
            out[name] = values[name]
    return out


# ---------------------------------------------------------------------------- MCAP
def _event_payloads(result: ReplayResult, start: bool = True) -> tuple[list[int], list[bytes]]:
    """The events channel of the results log (start, ticks, the other records), so that a
    replay of the results redoes the same steps (``start``: with the Start record)."""
    records: list[tuple[int, Event | Start]] = (
        [(result.started_ns, Start(result.started_ns))] if start else []
    )
    records += [(int(t), Tick(int(t))) for t in result.tick_ns.tolist()]
    records += [(e.stamp_ns, e) for e in result.events]
    records.sort(key=lambda r: r[0])
    stamps, payloads = [], []
    for stamp, event in records:
        record = event_record(event)
        if record is not None:
            stamps.append(stamp)
            payloads.append(string_message(json.dumps(record)))
    return stamps, payloads


def snapshot_payloads(result: ReplayResult) -> tuple[list[int], list[bytes]]:
    """Every snapshot of the replay as a DiagnosticArray in CDR (stamps ns, payloads), in time
    order (a stable sort: as :func:`catenary_monitor.core.twin.engine.run_log` orders Snapshots).
    """
    headers: dict[tuple[int, str, str, str, int], Any] = {}
    stamps: list[int] = []
    payloads: list[bytes] = []
    for snap in result.snapshots:
        if isinstance(snap, SnapshotColumns):
            s, p = _columns_payloads(snap)
            stamps += s
            payloads += p
            continue
        parts = []
        for st in snap.statuses:
            key = (int(st.level), st.name, st.message, st.hardware_id, len(st.values))
            header = headers.get(key)
            if header is None:
                if len(headers) > 4096:
                    headers.clear()
                header = headers[key] = functools.lru_cache(maxsize=4)(
                    functools.partial(status_header, *key)
                )
            parts.append((header, key_values(st.values)))
        stamps.append(snap.stamp_ns)
        payloads.append(diagnostic_array_parts(snap.stamp_ns, parts))
    if any(b < a for a, b in zip(stamps, stamps[1:])):
        order = sorted(range(len(stamps)), key=stamps.__getitem__)
        stamps = [stamps[i] for i in order]
        payloads = [payloads[i] for i in order]
    return stamps, payloads


def _columns_payloads(table: SnapshotColumns) -> tuple[list[int], list[bytes]]:
    """The DiagnosticArrays of a :class:`SnapshotColumns` (every status of one shape encoded
    at once; the statuses given as objects encoded one by one, the repeated ones once)."""
    n = len(table.stamps)
    rows: list[tuple[list[int], list[bytes], int]] = []
    cache: dict[Any, bytes] = {}  # per window: nothing kept between windows
    for group, m in table.groups:
        if isinstance(group, StatusColumns):
            buf, starts, ends = status_bodies(
                m * n, group.name, group.message, group.hardware_id, group.keys, group.values
            )
            bodies = [buf[a:b] for a, b in zip(starts.tolist(), ends.tolist())]
            rows.append((group.levels.tolist(), bodies, m))
            continue
        levels, bodies = [], []
        for st in group:
            body = cache.get(st)
            if body is None:
                body = cache[st] = status_body(st.name, st.message, st.hardware_id, st.values)
            levels.append(int(st.level))
            bodies.append(body)
        rows.append((levels, bodies, m))
    stamps = table.stamps.tolist()
    payloads = []
    for i, stamp in enumerate(stamps):
        lv: list[int] = []
        bd: list[bytes] = []
        for levels, bodies, m in rows:
            lv += levels[i::n][:m] if m > 1 else [levels[i]]
            bd += bodies[i::n][:m] if m > 1 else [bodies[i]]
        payloads.append(diagnostic_array_bodies(stamp, lv, bd))
    return stamps, payloads


def write_mcap(
    stream: IO[bytes],
    result: ReplayResult,
    config: MonitorConfig,
    tensions: dict[str, tuple[np.ndarray, np.ndarray]],
    depth: tuple[np.ndarray, np.ndarray],
    topics: dict[str, str],
    depth_topic: str,
    sources: Sequence[str] = (),
    progress: Progress = None,
) -> int:
    """Results as a ROS 2 MCAP log shaped like the node's: inputs, outputs, /diagnostics.

    The recorded inputs are copied (``std_msgs/msg/Float64``); each line's updates go to
    :func:`output_topic` as ``std_msgs/msg/Float64MultiArray`` (:data:`OUTPUT_FIELDS`, label =
    the field names joined by commas); ``/diagnostics`` holds a ``DiagnosticArray`` at every
    snapshot the monitor made (``result`` recomputed with ``snapshots=True``). Returns the number
    of messages written. A streamed replay writes the same log window by window
    (:class:`McapSink`).
    """
    sink = McapSink(stream, config, [r.name for r in result.lines], topics, depth_topic, sources)
    sink.write(result, tensions, depth, progress)
    return sink.finish(progress)


def si_inputs(config: MonitorConfig) -> MonitorConfig:
    """``config`` reading SI values in ``std_msgs/Float64`` (what the results log holds as
    inputs): every input type Float64, ``tension_scale`` 1, ``depth_offset`` 0."""
    lines = tuple(
        dataclasses.replace(lc, tension_type=FLOAT64, tension_axis='norm', tension_scale=1.0)
        for lc in config.lines
    )
    return dataclasses.replace(config, lines=lines, depth_type=FLOAT64, depth_offset=0.0)


class McapSink:
    """The results log written as the replay goes: :meth:`write` each window's results (in
    time order), then :meth:`finish`."""

    def __init__(
        self,
        stream: IO[bytes],
        config: MonitorConfig,
        lines: Sequence[str],
        topics: dict[str, str],
        depth_topic: str,
        sources: Sequence[str] = (),
    ) -> None:
        # the MCAP writer (and the mcap library's writer) only for --out: not a summary's start
        from catenary_monitor.io.mcap_column_writer import ColumnWriter

        self.w = w = ColumnWriter(stream)
        self.topics = topics
        schemas = {}
        for type_name in (
            'std_msgs/msg/Float64',
            'std_msgs/msg/Float64MultiArray',
            'diagnostic_msgs/msg/DiagnosticArray',
            'std_msgs/msg/String',
        ):
            schemas[type_name] = w.register_schema(
                type_name, 'ros2msg', message_definition(type_name).encode()
            )

        def channel(topic: str, type_name: str, qos: str) -> int:
            meta = {'offered_qos_profiles': qos}
            type_hash = type_description_hash(type_name)
            if type_hash:
                meta['topic_type_hash'] = type_hash
            return w.register_channel(topic, 'cdr', schemas[type_name], meta)

        self.in_ids = {
            name: channel(topics[name], 'std_msgs/msg/Float64', QOS_SENSOR_DATA) for name in topics
        }
        self.depth_id = channel(depth_topic, 'std_msgs/msg/Float64', QOS_SENSOR_DATA)
        self.out_ids = [
            channel(output_topic(name), 'std_msgs/msg/Float64MultiArray', QOS_DEFAULT)
            for name in lines
        ]
        self.diag_id = channel('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', QOS_DEFAULT)
        self.event_id = channel(EVENTS_TOPIC, 'std_msgs/msg/String', QOS_DEFAULT)
        self.started = False
        # The inputs are written as their SI readings in std_msgs/Float64 at arrival: the
        # parameters recorded say so (types Float64, scale 1, offset 0), so the file reads back
        # as it is (a stamped input's header stamps are not kept: replay the original log).
        config = si_inputs(config)
        w.add_metadata(
            NODE_NAME,
            {
                'version': __version__,
                'config_hash': config_hash(config),
                'parameters': json.dumps(config_to_params(config), sort_keys=True),
                'output_fields': ','.join(OUTPUT_FIELDS),
                'units': 'SI (N, m, s)',
                'source': 'catenary-monitor replay',
                'replayed_files': ','.join(sources),
            },
        )

    def write(
        self,
        result: ReplayResult,
        tensions: dict[str, tuple[np.ndarray, np.ndarray]],
        depth: tuple[np.ndarray, np.ndarray],
        progress: Progress = None,
    ) -> None:
        """Write one window: its inputs, outputs, snapshots and events (the Start record with
        the first window)."""
        w, topics = self.w, self.topics
        t_in = [depth[0]] + [tensions[n][0] for n in topics if n in tensions]
        v_in = [depth[1]] + [tensions[n][1] for n in topics if n in tensions]
        c_in = [np.full(len(depth[0]), self.depth_id)] + [
            np.full(len(tensions[n][0]), self.in_ids[n]) for n in topics if n in tensions
        ]
        t_in_all = np.concatenate(t_in)
        order = np.argsort(t_in_all, kind='stable')
        t_in_all = t_in_all[order]
        c_in_all = np.concatenate(c_in)[order]
        v_in_all = np.concatenate(v_in)[order]
        t_out = np.concatenate([r.t_ns for r in result.lines])
        c_out = np.concatenate(
            [np.full(len(r.t_ns), cid) for r, cid in zip(result.lines, self.out_ids)]
        )
        order = np.argsort(t_out, kind='stable')
        label = ','.join(OUTPUT_FIELDS)
        named = {
            key: np.concatenate([r.values[key] for r in result.lines]) for key in VALUE_FIELDS
        }
        named['status'] = np.concatenate([r.status for r in result.lines]).astype(np.float64)
        named['level'] = np.concatenate([r.level for r in result.lines]).astype(np.float64)
        columns = [named[key] for key in OUTPUT_FIELDS]
        stamps, payloads = snapshot_payloads(result)
        diag_t = np.asarray(stamps, np.int64)
        ev_stamps, ev_payloads = _event_payloads(result, start=not self.started)
        self.started = True
        ev_t = np.asarray(ev_stamps, np.int64)
        # Written in stretches of time (inputs, outputs, diagnostics of each), so that the
        # chunks of the streams overlap only within a stretch.
        n_out = len(t_out)
        step = 1 << 14  # about two minutes of a 12-line dock at 10 Hz
        t_sorted = t_out[order]
        edges = [t_sorted[k] for k in range(step, n_out, step)]
        bounds = [None, *edges, None]
        for k in range(len(bounds) - 1):
            lo_t, hi_t = bounds[k], bounds[k + 1]

            def part(times: np.ndarray) -> slice:
                a = 0 if lo_t is None else int(np.searchsorted(times, lo_t, 'left'))
                b = len(times) if hi_t is None else int(np.searchsorted(times, hi_t, 'left'))
                return slice(a, b)

            s_in = part(t_in_all)
            w.write_columns(c_in_all[s_in], t_in_all[s_in], float64_payloads(v_in_all[s_in]))
            sel = order[part(t_sorted)]
            data = np.empty((len(sel), len(OUTPUT_FIELDS)))
            for j, col in enumerate(columns):
                data[:, j] = col[sel]
            w.write_columns(c_out[sel], t_out[sel], multiarray_payloads(label, data))
            s_d = part(diag_t)
            w.write_messages(self.diag_id, stamps[s_d], payloads[s_d])
            s_e = part(ev_t)
            w.write_messages(self.event_id, ev_stamps[s_e], ev_payloads[s_e])
            if progress is not None:
                progress('writing MCAP', (k + 1) / (len(bounds) - 1))

    def finish(self, progress: Progress = None) -> int:
        """Write the summary; return the number of messages written."""
        self.w.finish()
        if progress is not None:
            progress('writing MCAP', 1.0)
        return self.w.messages


# ---------------------------------------------------------------------------- charts
_SHADE = {
    Level.WARN: ('#f2c744', 'WARN'),
    Level.STALE: ('#9e9e9e', 'STALE'),
    Level.ERROR: ('#d62728', 'ERROR'),
}


class Envelope:
    """A series decimated into at most ``bins`` time bins (min and max of each: peaks kept),
    fed window by window in time order, so its memory does not grow with the series. Bins
    start 1 ms wide and double (neighbours merged) whenever the series outgrows them."""

    def __init__(self, bins: int = 1000) -> None:
        self.bins = bins
        self.origin: Optional[int] = None
        self.width = 1_000_000  # ns
        self.lo = np.full(bins, np.inf)
        self.hi = np.full(bins, -np.inf)
        self.seen = np.zeros(bins, bool)

    def add(self, t_ns: np.ndarray, v: np.ndarray) -> None:
        """Take samples (times ns, sorted; a NaN value marks its bin without a value)."""
        if len(t_ns) == 0:
            return
        if self.origin is None:
            self.origin = int(t_ns[0])
        while (int(t_ns[-1]) - self.origin) // self.width >= self.bins:
            self._coarsen()
        k = (np.asarray(t_ns, np.int64) - self.origin) // self.width
        starts = np.flatnonzero(np.diff(k, prepend=-1))
        idx = k[starts]
        lo = np.minimum.reduceat(np.where(np.isnan(v), np.inf, v), starts)
        hi = np.maximum.reduceat(np.where(np.isnan(v), -np.inf, v), starts)
        self.lo[idx] = np.minimum(self.lo[idx], lo)
        self.hi[idx] = np.maximum(self.hi[idx], hi)
        self.seen[idx] = True

    def _coarsen(self) -> None:
        """Double the bin width: bins 2i and 2i + 1 become bin i."""
        pad = self.bins % 2
        lo = np.append(self.lo, [np.inf] * pad).reshape(-1, 2).min(axis=1)
        hi = np.append(self.hi, [-np.inf] * pad).reshape(-1, 2).max(axis=1)
        seen = np.append(self.seen, [False] * pad).reshape(-1, 2).any(axis=1)
        n = len(lo)
        self.lo[:] = np.inf
        self.hi[:] = -np.inf
        self.seen[:] = False
        self.lo[:n], self.hi[:n], self.seen[:n] = lo, hi, seen
        self.width *= 2

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """(times s, values): each bin's min and max at its start (NaN where it had none)."""
        k = np.flatnonzero(self.seen)
        t = ((self.origin or 0) + k * self.width) * 1e-9
        lo = np.where(np.isinf(self.lo[k]), np.nan, self.lo[k])
        hi = np.where(np.isinf(self.hi[k]), np.nan, self.hi[k])
        return np.repeat(t, 2), np.column_stack((lo, hi)).ravel()


class PlotData:
    """What the charts show, gathered window by window in bounded memory: per line the
    envelopes of hook tension (kN), minimum anchor distance (m), uplift force (kN) and the
    level transitions; the tide's envelope (m)."""

    SERIES = (('top_tension', 1e3), ('min_anchor_distance', 1.0), ('uplift_force', 1e3))

    def __init__(self, lines: Sequence[str]) -> None:
        self.lines = list(lines)
        self.series = [{key: Envelope() for key, _ in self.SERIES} for _ in self.lines]
        self.transitions: list[list[Any]] = [[] for _ in self.lines]
        self.depth = Envelope()
        self.end_ns = 0

    def add(self, result: Any, depth: tuple[np.ndarray, np.ndarray]) -> None:
        """Take one window's results (a :class:`WindowResult`) and its depth column."""
        for k, r in enumerate(result.lines):
            for key, scale in self.SERIES:
                self.series[k][key].add(r.t_ns, r.values[key] / scale)
            self.transitions[k] += r.transitions
        self.depth.add(depth[0], depth[1])
        self.end_ns = max(self.end_ns, int(result.end_ns))


def _periods(transitions: Sequence[Any], end_ns: int) -> list[tuple[float, float, Level]]:
    """(start s, end s, level) of every non-OK period from the transitions."""
    out = []
    cur: Optional[tuple[float, Level]] = None
    for tr in transitions:
        if cur is not None:
            out.append((cur[0], tr.time, cur[1]))
        cur = (tr.time, tr.new) if tr.new != Level.OK else None
    if cur is not None:
        out.append((cur[0], end_ns * 1e-9, cur[1]))
    return out


def _dates(t_s: np.ndarray) -> np.ndarray:
    return (np.asarray(t_s) * 1e6).astype('int64').astype('datetime64[us]')


def _shade(ax: Any, periods: list[tuple[float, float, Level]]) -> None:
    for a, b, level in periods:
        color, _ = _SHADE[level]
        ax.axvspan(
            _dates(np.array([a]))[0], _dates(np.array([b]))[0], color=color, alpha=0.3, lw=0
        )


def write_plots(
    path: Path, result: ReplayResult, config: MonitorConfig, depth: tuple[np.ndarray, np.ndarray]
) -> list[Path]:
    """PNG charts of a whole result (:func:`draw_plots`)."""
    data = PlotData([r.name for r in result.lines])
    data.add(result, depth)
    data.end_ns = int(result.end_ns)
    return draw_plots(path, config, data)


def draw_plots(path: Path, config: MonitorConfig, data: PlotData) -> list[Path]:
    """PNG charts: ``path`` (overview: every line's tension, alarms shaded, and the tide) and
    ``<stem>_<line><suffix>`` per line (hook tension; minimum vs installed anchor distance;
    uplift force vs allowed; tide), alarm periods shaded (WARN yellow, STALE grey, ERROR red).
    Series are drawn as min/max envelopes over at most 1000 time bins (:class:`PlotData`).
    """
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    path = Path(path)
    written = []
    legend = [Patch(color=c, alpha=0.3, label=name) for c, name in _SHADE.values()]
    td, dv = data.depth.points()
    for k, name in enumerate(data.lines):
        lc = config.line(name)
        fig, axes = plt.subplots(4, 1, figsize=(11, 9), sharex=True)
        periods = _periods(data.transitions[k], data.end_ns)
        series = [
            ('hook tension [kN]', 'top_tension', None),
            (
                'minimum anchor distance [m]',
                'min_anchor_distance',
                (lc.anchor_distance, 'installed'),
            ),
            ('uplift force [kN]', 'uplift_force', (lc.allowed_uplift / 1e3, 'allowed')),
        ]
        for ax, (label, key, ref) in zip(axes, series):
            x, y = data.series[k][key].points()
            ax.plot(_dates(x), y, lw=0.7)
            if ref is not None:
                ax.axhline(ref[0], color='k', ls='--', lw=0.8, label=ref[1])
                ax.legend(loc='upper right', fontsize=8)
            ax.set_ylabel(label, fontsize=9)
            _shade(ax, periods)
            ax.grid(alpha=0.3)
        axes[3].plot(_dates(td), dv, lw=0.7, color='tab:blue')
        axes[3].set_ylabel('tide depth [m]', fontsize=9)
        axes[3].grid(alpha=0.3)
        _shade(axes[3], periods)
        axes[3].set_xlabel('time (UTC)')
        axes[0].legend(handles=legend, loc='upper left', fontsize=8, ncol=3)
        fig.suptitle(f'{name}: replay ({len(data.transitions[k])} alarm transitions)')
        fig.subplots_adjust(left=0.08, right=0.98, top=0.94, bottom=0.07, hspace=0.12)
        out = path.with_name(f'{path.stem}_{name}{path.suffix or ".png"}')
        fig.savefig(out, dpi=72)
        plt.close(fig)
        written.append(out)
    n = len(data.lines)
    fig, axes = plt.subplots(n + 1, 1, figsize=(11, 1.6 * (n + 1) + 1), sharex=True, squeeze=False)
    for k, (ax, name) in enumerate(zip(axes[:, 0], data.lines)):
        x, y = data.series[k]['top_tension'].points()
        ax.plot(_dates(x), y, lw=0.6)
        _shade(ax, _periods(data.transitions[k], data.end_ns))
        ax.set_ylabel(f'{name}\nT [kN]', fontsize=8)
        ax.grid(alpha=0.3)
    ax = axes[n, 0]
    ax.plot(_dates(td), dv, lw=0.7)
    ax.set_ylabel('tide [m]', fontsize=8)
    ax.set_xlabel('time (UTC)')
    axes[0, 0].legend(handles=legend, loc='upper left', fontsize=7, ncol=3)
    fig.suptitle('replay: hook tension per line, alarm periods shaded; tide')
    fig.subplots_adjust(
        left=0.09,
        right=0.98,
        top=1 - 0.75 / (1.6 * (n + 1) + 1),
        bottom=0.6 / (1.6 * (n + 1) + 1),
        hspace=0.15,
    )
    fig.savefig(path, dpi=72)
    plt.close(fig)
    return [path] + written


# ---------------------------------------------------------------------------- summary
def _utc(t: Optional[float]) -> str:
    if t is None or not math.isfinite(t):
        return '-'
    return _dt.datetime.fromtimestamp(t, _dt.timezone.utc).strftime('%Y-%m-%d %H:%M:%S.%f')[:-3]


def _better(new: Optional[dict[str, float]], cur: Optional[dict[str, float]], low: bool) -> bool:
    """True when ``new`` is strictly worse than ``cur`` (the earlier one wins a tie)."""
    if new is None:
        return False
    if cur is None:
        return True
    return new['value'] < cur['value'] if low else new['value'] > cur['value']


#: The line values a summary reads (:class:`LineTally`: the worst values, the fatigue).
SUMMARY_VALUES = frozenset(WORST_KEYS + ('fatigue_damage',))


class LineTally:
    """One line's part of the summary, gathered window by window (the same figures as over
    the whole log at once)."""

    LOW = ('anchor_margin', 'tide_margin', 'load_margin', 'safety_factor')

    def __init__(self, name: str) -> None:
        self.name = name
        self.tension_messages = 0
        self.updates = 0
        self.unsolved = 0
        self.worst: dict[str, Optional[dict[str, float]]] = {}
        self.transitions: list[Any] = []
        self.final: Optional[Level] = None
        self.fatigue = math.nan  # Miner's damage after the last update (docs/fatigue.md)

    def add(self, r: LineResult) -> None:
        """Take the line's results of the next window."""
        self.tension_messages += int(len(r.tension_rows))
        self.updates += int(len(r.t_ns))
        self.unsolved += int(np.count_nonzero(r.status != 0))
        for key, value in worst(r).items():
            if key not in self.worst or _better(value, self.worst[key], key in self.LOW):
                self.worst[key] = value
        self.transitions += r.transitions
        if len(r.step_level):
            self.final = Level(int(r.step_level[-1]))
        if len(r.t_ns):
            self.fatigue = float(r.values['fatigue_damage'][-1])

    def as_dict(self, end_ns: int) -> dict[str, Any]:
        """The summary's entry (final level: after the last step; STALE, blind, without)."""
        empty = np.zeros(0)
        episodes = LineResult(
            self.name, empty, empty, {}, empty, empty, empty, empty, empty, self.transitions
        ).episodes(end_ns)
        return {
            'tension_messages': self.tension_messages,
            'updates': self.updates,
            'unsolved_updates': self.unsolved,
            'worst': self.worst,
            'transitions': len(self.transitions),
            'final_level': (Level.STALE if self.final is None else self.final).name,
            'episodes': episodes,
            'fatigue_damage': None if self.fatigue != self.fatigue else self.fatigue,
        }


class Tally:
    """The summary of a replay gathered window by window: :meth:`add` each window's
    :class:`ReplayResult`, then :func:`summary_dict` of the tally."""

    def __init__(self, lines: Sequence[str]) -> None:
        self.lines = [LineTally(name) for name in lines]
        self.start_ns: Optional[int] = None
        self.end_ns: Optional[int] = None
        self.ticks = 0
        self.ticks_from_log = False
        #: The other components' transitions (the tide, the sensors alarm, the alarm flood
        #: status, the dock model).
        self.components: dict[str, list[Any]] = {'tide': [], 'sensors': [], 'alarms': []}

    def add(self, result: ReplayResult) -> None:
        """Take the next window's results."""
        for tally, r in zip(self.lines, result.lines):
            tally.add(r)
        self.components['tide'] += result.tide
        for change in result.others:
            self.components.setdefault(change.component, []).append(change.transition)
        start, end = int(result.start_ns), int(result.end_ns)
        self.start_ns = start if self.start_ns is None else min(self.start_ns, start)
        self.end_ns = end if self.end_ns is None else max(self.end_ns, end)
        self.ticks += int(len(result.tick_ns))
        self.ticks_from_log = bool(result.ticks_from_log)


def summary_dict(
    result: ReplayResult | Tally, report: Any, extra: Optional[dict[str, Any]] = None
) -> dict[str, Any]:
    """Machine-readable summary (``--json``): SI units, times in s since the Unix epoch."""
    if not isinstance(result, Tally):
        tally = Tally([r.name for r in result.lines])
        tally.add(result)
        result = tally
    start, end = result.start_ns or 0, result.end_ns or 0
    out: dict[str, Any] = {
        'files': [f.path for f in report.files],
        'complete': bool(report.complete),
        'messages': dict(report.messages),
        'missing_topics': list(report.missing_topics),
        'skipped': [
            {
                'path': s.path,
                'offset': s.offset,
                'kind': s.kind,
                'reason': s.reason,
                'messages_lost': s.messages_lost,
            }
            for s in report.skips
        ],
        'unfinished_files': [f.path for f in report.files if not f.finished],
        'start': start * 1e-9,
        'end': end * 1e-9,
        'duration': (end - start) * 1e-9,
        'ticks': {
            'count': result.ticks,
            'source': 'recorded by the node' if result.ticks_from_log else 'synthetic grid',
        },
        'components': {
            name: _component_dict(transitions, end)
            for name, transitions in result.components.items()
        },
        'lines': {t.name: t.as_dict(end) for t in result.lines},
    }
    if extra:
        out.update(extra)
    return out


def _component_dict(transitions: list[Any], end_ns: int) -> dict[str, Any]:
    """A component's entry: its transitions, final level (None: it never changed) and
    episodes, as a line's."""
    empty = np.zeros(0)
    episodes = LineResult(
        '', empty, empty, {}, empty, empty, empty, empty, empty, transitions
    ).episodes(end_ns)
    return {
        'transitions': len(transitions),
        'final_level': transitions[-1].new.name if transitions else None,
        'episodes': episodes,
    }


def _episode_text(episodes: list[dict[str, Any]]) -> list[str]:
    """One line per alarm episode (or that there was none), indented."""
    if not episodes:
        return ['  no alarm episode']
    out = []
    for e in episodes:
        end = (
            'still active at the end of the log'
            if e['end'] is None
            else f'until {_utc(e["end"])[11:]}'
        )
        dur = '' if e['duration'] is None else f'{e["duration"]:.1f} s, '
        out.append(f'  {e["worst"]:<5} from {_utc(e["start"])} ({dur}{end}): {e["message"]}')
    return out


def _fmt(value: Optional[dict[str, float]], scale: float, unit: str, fmt: str) -> str:
    if value is None:
        return 'n/a'
    return f'{format(value["value"] / scale, fmt)} {unit} at {_utc(value["time"])[11:]}'.replace(
        '  ', ' '
    )


def summary_text(summary: dict[str, Any]) -> str:
    """Human-readable summary: per line the worst margins and each alarm episode."""
    msgs = summary['messages']
    out = [
        f'replayed {len(summary["files"])} file(s): {sum(msgs.values())} messages, '
        f'{_utc(summary["start"])} to {_utc(summary["end"])} UTC '
        f'({summary["duration"]:.1f} s); {summary["ticks"]["count"]} periodic steps '
        f'({summary["ticks"]["source"]})'
    ]
    par = summary.get('parameters')
    if par:
        text = f'parameters: {par["source"]} (config hash {par["config_hash"][:12]})'
        if par['same_as_recorded'] is False:
            text += (
                f'; the log was recorded with other parameters (config hash '
                f'{par["recorded_config_hash"][:12]})'
            )
        elif par['same_as_recorded']:
            text += '; the same as recorded in the log'
        out.append(text)
    if summary['skipped'] or summary['unfinished_files']:
        out.append('DAMAGED INPUT: everything readable was used; skipped:')
        for f in summary['unfinished_files']:
            out.append(f'  {f}: not finished by its writer (no summary; killed?)')
        for s in summary['skipped']:
            lost = '' if s['messages_lost'] is None else f' ({s["messages_lost"]} messages lost)'
            out.append(f'  {s["path"]} @ byte {s["offset"]}: {s["kind"]}: {s["reason"]}{lost}')
    if summary['missing_topics']:
        out.append(f'no messages on: {", ".join(summary["missing_topics"])}')
    out += stamp_lines(summary)
    for name, c in summary.get('components', {}).items():
        final = c['final_level']
        final = 'level unchanged' if final is None else f'final level {final}'
        count = c['transitions']
        out += ['', f'{name}: {count} transition{"" if count == 1 else "s"}, {final}']
        out += _episode_text(c['episodes'])
    for name, ln in summary['lines'].items():
        w = ln['worst']
        out.append('')
        out.append(
            f'{name}: {ln["tension_messages"]} tension messages, {ln["updates"]} updates'
            f' ({ln["unsolved_updates"]} unsolved), final level {ln["final_level"]}'
        )
        out.append(
            f'  worst anchor margin {_fmt(w["anchor_margin"], 1, "m", "+.2f")}; '
            f'tide margin {_fmt(w["tide_margin"], 1, "m", "+.2f")}'
        )
        out.append(
            f'  worst load margin {_fmt(w["load_margin"], 1e3, "kN", "+.1f")}; '
            f'safety factor {_fmt(w["safety_factor"], 1, "", ".2f")}'
        )
        if ln.get('fatigue_damage') is not None:
            out.append(f'  fatigue damage at the end {ln["fatigue_damage"]:.4g} (Miner)')
        uplift = w['uplift_force']
        lifted = (
            'none (anchor never lifted)'
            if uplift is not None and uplift['value'] == 0
            else _fmt(uplift, 1e3, 'kN', '.1f')
        )
        out.append(
            f'  max uplift {lifted}; '
            f'max hook tension {_fmt(w["top_tension"], 1e3, "kN", ".1f")}'
        )
        out += _episode_text(ln['episodes'])
    for key in ('outputs', 'timing'):
        if summary.get(key):
            out.append('')
            out.append(f'{key}: ' + ', '.join(f'{k} {v}' for k, v in summary[key].items()))
    return '\n'.join(out)
