"""The twin's diagnostic snapshots: every snapshot the core made in a window (its ticks and
level changes), built from the vectorized results, as :class:`Snapshot` s
(:func:`build_snapshots`) or in columns (:func:`build_snapshot_columns`, replay's ``--out``)."""

from __future__ import annotations

from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.alarms import flood as alarm_flood
from catenary_monitor.core.alarms.latches import DIAGNOSTIC_KEYS, LevelSeries
from catenary_monitor.core.alarms.texts import TEXT_KEYS, active_conditions, status_texts
from catenary_monitor.core.monitor.events import NODE_NAME
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.monitor.state import VALUE_FIELDS, LineState
from catenary_monitor.core.monitor.status import (
    ComponentStatus,
    Snapshot,
    dock_component,
    forecast_word,
    line_dock_values,
    line_status,
    sensors_component,
    tide_component,
    view_word,
)
from catenary_monitor.core.monitor.status import depth_word as depth_state_word
from catenary_monitor.core.rules import sensor_state
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.twin.decisions import (
    BlindColumns,
    ComponentAcks,
    DockColumns,
    FloodColumns,
    SensorColumns,
    TideColumns,
    blind_status_at,
    tide_status_at,
)
from catenary_monitor.core.twin.schedule import LineSteps, level_changes
from catenary_monitor.core.twin.window import (
    MODEL_NAMES,
    Field,
    LineResult,
    SnapshotColumns,
    StatusColumns,
    Window,
)

__all__ = [
    'LineBefore',
    'line_word',
    'DamageColumns',
    'WindowMade',
    'build_snapshots',
    'build_snapshot_columns',
]


class LineBefore(NamedTuple):
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


def line_word(core: MonitorCore, line: LineState, code: int, latched: bool) -> str:
    """A line's ``sensor_state`` word (its own state, else the dock model's)."""
    if core.dock_model is None:
        return sensor_state.line_word(code)
    return sensor_state.line_word(code, dock_live.sensor_state(latched, line.dock[0]))


def _snapshot_stamps(
    window: Window,
    tide: TideColumns,
    results: list[LineResult],
    tide_before: tuple[Level, str],
    lines_before: list[LineBefore],
    blind: Optional[BlindColumns] = None,
    flood: Optional[FloodColumns] = None,
) -> np.ndarray:
    """The stamps of the window's snapshots: its ticks and every level change [ns]."""
    parts = [window.ticks, tide.times[level_changes(tide.level, tide_before[0])]]
    if blind is not None:
        parts.append(tide.times[level_changes(blind.levels, blind.before[0][0])])
    if flood is not None:
        parts.append(flood.stamps[flood.changes])
    parts += [
        r.step_ns[level_changes(r.step_level, b.level)] for r, b in zip(results, lines_before)
    ]
    return np.unique(np.concatenate(parts))


def _tide_statuses(
    core: MonitorCore,
    window: Window,
    tide: TideColumns,
    stamps: np.ndarray,
    depth_before: tuple[float, float, bool, float],
    tide_before: tuple[Level, str],
    depth_word: str,
    acks: Optional[alarm_ack.AckSeries] = None,
) -> list[ComponentStatus]:
    """The tide status at each of ``stamps`` [ns] (``acks``: its alarm at the tide's
    decisions; None: as the core holds it)."""
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
        state = tide_before if i < 0 else tide_status_at(core, tide, i)
        word = depth_word if i < 0 else depth_state_word(depth_s, int(tide.sensor[i]))
        age = stamp * 1e-9 - depth_s
        forecast = forecast_word(core.config, rate)
        ack = core.component_ack('tide') if acks is None else acks.at(i)
        out.append(tide_component(state, core.depth_id, depth, age, rate, word, forecast, ack))
    return out


class DamageColumns(NamedTuple):
    """A line's fatigue damage through the window: after each tension sample (stamps ns)."""

    times: np.ndarray
    damage: np.ndarray
    before: float


class WindowMade(NamedTuple):
    """What a window's recompute made, from which its snapshots are built."""

    core: MonitorCore
    window: Window
    tide: TideColumns
    results: list[LineResult]
    series: list[LevelSeries]
    steps: list[LineSteps]
    depth_before: tuple[float, float, bool, float]
    tide_before: tuple[Level, str]
    lines_before: list[LineBefore]
    acks: list[alarm_ack.AckSeries]
    dock: Optional[DockColumns] = None
    sensors: Optional[SensorColumns] = None
    depth_word: str = 'ok'
    blind: Optional[BlindColumns] = None
    flood: Optional[FloodColumns] = None
    damage: Optional[list[DamageColumns]] = None
    component_acks: Optional[ComponentAcks] = None

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

    def tide_statuses(self, stamps: np.ndarray) -> list[ComponentStatus]:
        """The tide status at each of ``stamps`` [ns]."""
        acks = None if self.component_acks is None else self.component_acks.tide
        return _tide_statuses(
            self.core, self.window, self.tide, stamps, self.depth_before, self.tide_before,
            self.depth_word, acks,
        )  # fmt: skip

    def dock_acks(self) -> alarm_ack.AckSeries:
        """The dock's alarm at the window's ticks."""
        acks = None if self.component_acks is None else self.component_acks.dock
        if acks is None:
            return alarm_ack.AckSeries(self.core.component_ack('dock'), np.zeros(0, np.int64), [])
        return acks

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
                state = blind_status_at(self.core, self.tide, blind, i)
                waiting = int(blind.waiting[i].sum())
            out.append(sensors_component(state, blind.acks.at(i), waiting))
        return out

    def line_parts(self, k: int) -> tuple[
        LineState, LineResult, LevelSeries, LineSteps, np.ndarray, LineBefore,
        alarm_ack.AckSeries, Optional[DockColumns], Optional[SensorColumns],
    ]:  # fmt: skip
        """Line ``k``'s state, result, levels, steps, tension reading times, state before the
        window, acknowledgements, and the window's dock and sensor states."""
        return (
            self.core.state.lines[k], self.results[k], self.series[k], self.steps[k],
            self.window.sample_ns(k), self.lines_before[k], self.acks[k], self.dock,
            self.sensors,
        )  # fmt: skip


def build_snapshots(m: WindowMade) -> list[Snapshot]:
    """Every snapshot the core made in the window (ticks and level changes), built from the
    vectorized results."""
    core, window, dock = m.core, m.window, m.dock
    stamps = m.stamps()
    tides = m.tide_statuses(stamps)
    blinds = m.blind_statuses(stamps)
    alarms = m.alarms_statuses(stamps)
    columns = [_line_statuses(m, k, stamps) for k in range(len(m.results))]
    tick_at = np.searchsorted(window.ticks, stamps, 'right') - 1
    logger = core.logger_component()
    worst = m.max_damage(stamps)
    out = []
    for n, stamp in enumerate(stamps.tolist()):
        statuses = [tides[n], blinds[n], alarms[n], logger]
        if dock is not None:
            statuses.append(_dock_status(core, dock, int(tick_at[n]), m.dock_acks()))
        statuses += core.guard_components(stamp * 1e-9, worst[n])
        lines = tuple(col[n] for col in columns)
        out.append(Snapshot(stamp, lines + core.texts(statuses)))
    return out


def _dock_status(
    core: MonitorCore, dock: DockColumns, i: int, acks: alarm_ack.AckSeries
) -> ComponentStatus:
    """The dock status as after tick ``i`` of the window (-1: as before the window), its
    alarm from ``acks`` (at the ticks)."""
    if i < 0:
        return dock_component(dock.before[0], dock.before[1], acks.before)
    assert core.dock_model is not None
    level = Level(int(dock.levels[i]))
    message = dock_live.dock_message(core.dock_model, dock.decision, i)
    values = dock_live.dock_values(dock.decision, i)
    return dock_component((level, message), values, acks.at(i))


def _line_statuses(m: WindowMade, k: int, stamps: np.ndarray) -> list[ComponentStatus]:
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
                latches,
                m.core.config.response_texts,
            )
        )
    return out


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
    series: LevelSeries, before: LineBefore, at: np.ndarray
) -> tuple[np.ndarray, list[str], list[str], list[str]]:
    """Level, message, the alarm's condition and its active conditions (the ``conditions``
    value) per stamp (after step ``at``, else as before the window)."""
    levels = _take(series.levels, at, int(before.level), np.int64)
    messages, conditions, actives = [], [], []
    for i, level in zip(at.tolist(), levels.tolist()):
        if i < 0:
            messages.append(before.message)
            conditions.append(alarm_ack.condition(before.level, before.latches))
            actives.append(active_conditions(before.latches, level == Level.STALE))
        elif level == Level.OK:
            messages.append('OK')
            conditions.append('none')
            actives.append(active_conditions(series.active_at(i), False))
        else:
            latches = series.active_at(i)
            messages.append(series.message_at(i))
            conditions.append(alarm_ack.condition(Level(level), latches))
            actives.append(active_conditions(latches, level == Level.STALE))
    return levels, messages, conditions, actives


def _text_columns(
    levels: np.ndarray,
    messages: list[str],
    conditions: list[str],
    actives: list[str],
    responses: tuple[tuple[str, str], ...],
) -> tuple[list[str], list[list[str]]]:
    """The headlines and the ``conditions``, ``detail`` and ``response`` values per stamp
    (:func:`~catenary_monitor.core.alarms.texts.status_texts`, each distinct row once)."""
    cache: dict[tuple[str, bool, str, str], tuple[str, list[str]]] = {}
    heads, rows = [], []
    for row in zip(messages, (lv == Level.OK for lv in levels.tolist()), conditions, actives):
        got = cache.get(row)
        if got is None:
            head, texts = status_texts(row[0], row[1], row[2], responses, row[3])
            got = cache[row] = head, [v for _, v in texts]
        heads.append(got[0])
        rows.append(got[1])
    return heads, rows


def _word_columns(
    m: WindowMade, k: int, at: np.ndarray, j_tick: np.ndarray
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
    acks: alarm_ack.AckSeries, before: LineBefore, at: np.ndarray, conditions: list[str]
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


def _line_columns(m: WindowMade, k: int, stamps: np.ndarray) -> StatusColumns:
    """:func:`_line_statuses` in columns (the same strings, built per key, not per status)."""
    line, r, series, steps, tt, before, acks, _, _ = m.line_parts(k)
    at = np.searchsorted(steps.times, stamps, 'right') - 1
    levels, messages, conditions, actives = _level_columns(series, before, at)
    heads, texts = _text_columns(
        levels, messages, conditions, actives, m.core.config.response_texts
    )
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
    columns += [_same([row[e] for row in texts]) for e in range(len(TEXT_KEYS))]
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
        *TEXT_KEYS,
    )
    return StatusColumns(
        levels,
        f'{NODE_NAME}: {config.name}',
        _same(heads),
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


def build_snapshot_columns(m: WindowMade) -> SnapshotColumns | list[Snapshot]:
    """The snapshots of :func:`_snapshots` in columns (its Snapshot s where the statuses
    after the dock do not have one shape)."""
    core, window, dock = m.core, m.window, m.dock
    stamps = m.stamps()
    n = len(stamps)
    worst = m.max_damage(stamps)
    guards = [core.guard_components(stamp * 1e-9, w) for stamp, w in zip(stamps.tolist(), worst)]
    shapes = {tuple((g.name, len(g.values)) for g in row) for row in guards}
    if len(shapes) > 1:
        return build_snapshots(m)
    lines = [_line_columns(m, k, stamps) for k in range(len(m.results))]
    groups: list[tuple[StatusColumns | list[ComponentStatus], int]] = []
    if lines and len({c.keys for c in lines}) == 1:
        groups.append((_stack(lines, n), len(lines)))
    else:
        groups += [(c, 1) for c in lines]
    tick_at = np.searchsorted(window.ticks, stamps, 'right') - 1
    tides = m.tide_statuses(stamps)
    groups.append((list(core.texts(tides)), 1))
    groups.append((list(core.texts(m.blind_statuses(stamps))), 1))
    groups.append((list(core.texts(m.alarms_statuses(stamps))), 1))
    logger = core.logger_component()
    groups.append((list(core.texts([logger])) * n, 1))
    if dock is not None:
        docks = [_dock_status(core, dock, int(i), m.dock_acks()) for i in tick_at.tolist()]
        groups.append((list(core.texts(docks)), 1))
    width = len(guards[0]) if guards else 0
    if width:
        groups.append((list(core.texts([row[g] for g in range(width) for row in guards])), width))
    return SnapshotColumns(stamps, tuple(groups))
