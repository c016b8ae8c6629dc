"""The twin's window-wide decisions, each as the core takes it one event at a time: the sensor
states at the ticks, the tide, the sensors' common-cause alarm, the dock estimate, the samples
refused for their stamps, the channels of a line, the alarm flood and the alarm journal. Each
writes the core's state after the window through its typed door (``state.take(part)``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.alarms import shelving
from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.alarms import flood as alarm_flood
from catenary_monitor.core.alarms.journal import (
    COMPONENTS,
    CONSEQUENCES,
    AlarmEvent,
    component_entries,
    entries,
    raised,
)
from catenary_monitor.core.alarms.latches import CONDITIONS, LevelSeries, Transition, blind_quiet
from catenary_monitor.core.monitor.monitor_core import (
    MonitorCore,
    channel_limits,
    input_names,
    sensor_limits,
    silence_timeouts,
    units_rule,
)
from catenary_monitor.core.monitor.state import (
    BlindPart,
    ComponentAckPart,
    DockPart,
    FloodPart,
    LineInputPart,
    LineRulesPart,
    SensorPart,
    TidePart,
)
from catenary_monitor.core.monitor.status import tide_with_sensor
from catenary_monitor.core.rules import channels, readings, sensor_state, tide_trend
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules.health import (
    CommonCause,
    common_cause,
    common_cause_groups,
    runs,
    sensors_status,
    tide_status,
)
from catenary_monitor.core.rules.level import RANK, Level
from catenary_monitor.core.rules import plausible
from catenary_monitor.core.rules.plausible import MAX_DEPTH
from catenary_monitor.core.twin.schedule import LineSteps, level_changes, merge, newest, pick
from catenary_monitor.core.twin.window import KIND_DEPTH, KIND_TICK, Column, Window

__all__ = [
    'TideColumns',
    'tide_status_at',
    'SensorColumns',
    'decide_sensors_window',
    'decide_units_window',
    'decide_tide',
    'BlindColumns',
    'blind_status_at',
    'decide_blind',
    'chatter',
    'write_tide',
    'DockColumns',
    'decide_dock_window',
    'window_journal',
    'accept',
    'fuse_channels',
    'write_refusals',
    'FloodColumns',
]


@dataclass
class TideColumns:
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


def tide_status_at(core: MonitorCore, tide: TideColumns, i: int) -> tuple[Level, str]:
    """The tide's (level, message) at decision ``i`` (as the core's ``_decide_tide``)."""
    status = tide_status(
        float(tide.depth[i]),
        float(tide.depth_s[i]),
        float(tide.times[i] * 1e-9),
        core.config.alarm.depth_timeout,
    )
    code, depth = int(tide.sensor[i]), float(tide.depth[i])
    return tide_with_sensor(status, code, depth, core.config.alarm, core.config.chart)


@dataclass
class SensorColumns:
    """The sensor states at the window's ticks (core.rules.sensor_state): each line's code
    (ticks, lines) and the depth sensor's (ticks), and the codes before the window."""

    codes: np.ndarray
    depth_codes: np.ndarray
    before: list[int]
    before_depth: int
    # Silent under a common cause (core.rules.health.common_cause): (ticks, lines + depth), the
    # flags before the window, and the causes at each tick that has one (and before).
    grouped: np.ndarray
    before_grouped: tuple[bool, ...]
    cause_ids: np.ndarray  # per tick: its causes in ``causes`` (-1: none)
    causes: list[tuple[CommonCause, ...]]
    before_causes: tuple[CommonCause, ...]
    #: What the units check takes at the ticks (:func:`decide_units_window`): now [s], each
    #: line's newest tension [N] and stamp [s], the newest depth [m] and stamp [s].
    readings: tuple[np.ndarray, ...] = ()
    #: The tide trend over the window's depth samples (:func:`tide_trend.series`: rates,
    #: excess, state after), as the depth memory took it: the tide's decisions take it again.
    trend: tuple[Any, ...] = ()

    def causes_at(self, i: int) -> tuple[CommonCause, ...]:
        """The common causes after tick ``i`` (-1: before the window)."""
        if i < 0:
            return self.before_causes
        j = int(self.cause_ids[i])
        return self.causes[j] if j >= 0 else ()


def decide_sensors_window(
    core: MonitorCore, window: Window, refusals: _Refusals
) -> SensorColumns:
    """Every tick's sensor states (the arrays the core hands core.rules.sensor_state one tick
    at a time); leaves the core's sensor memories as after the window."""
    a, ticks = core.config.alarm, window.ticks
    lines = core.state.lines
    n, m = len(ticks), len(lines)
    before = [line.sensor_code for line in lines]
    before_depth = core.state.depth_code
    flags, causes = core.state.silent_grouped, core.state.common_causes
    now = ticks * 1e-9
    tension, tension_s = np.empty((n, m)), np.empty((n, m))
    changed, spiked = np.empty((n, m)), np.empty((n, m))
    refused = np.empty((n, m))
    memories = []
    for k, line in enumerate(lines):
        tt, tv = window.tensions[k]
        ts = window.sample_s(k)
        mem = line.sensor_memory
        rate = a.tension_rate_max * line.config.mbl
        ch, sp, memory = sensor_state.samples(
            mem, ts, tv, a.tension_resolution, rate, a.stamp_jitter
        )
        memories.append(memory)
        j = np.searchsorted(tt, ticks, 'right') - 1  # tensions go before a tick at one stamp
        tension[:, k] = pick(j, tv, line.tension)
        tension_s[:, k] = pick(j, ts, line.tension_s)
        changed[:, k] = pick(j, ch, mem.changed)
        spiked[:, k] = pick(j, sp, mem.spiked)
        r = refusals.lines[k]
        refused[:, k] = pick(np.searchsorted(r, ticks, 'right') - 1, r * 1e-9, line.stamp_refused)
    dd, dv = window.depth
    ds = window.sample_s(None)
    (d_ch, d_sp, d_sea), depth_memory, trend = _depth_memories(core, window)
    j = np.searchsorted(dd, ticks, 'right') - 1  # depth goes before a tick at one stamp
    depth, depth_s = pick(j, dv, core.state.depth), pick(j, ds, core.state.depth_s)
    at = j + 1  # row 0: the memory before the window
    d_changed, d_spiked = d_ch[at], d_sp[at]
    sea = sensor_state.SeaColumns(*(column[at] for column in d_sea))
    r = refusals.depth
    d_refused = pick(np.searchsorted(r, ticks, 'right') - 1, r * 1e-9, core.state.depth_refused)
    if n == 0:
        for line, memory in zip(lines, memories):
            line.take(line.read(LineRulesPart)._replace(sensor_memory=memory))
        core.state.take(core.state.read(SensorPart)._replace(depth_memory=depth_memory))
        return SensorColumns(
            np.zeros((0, m), np.int8), np.zeros(0, np.int8), before, before_depth,
            np.zeros((0, m + 1), bool), flags, np.zeros(0, np.int64), [], causes, (), trend,
        )  # fmt: skip
    times = np.concatenate([core.state.sensor_times, now])
    rows = np.vstack(
        [core.state.sensor_rows, sensor_state.history_row(now, tension, spiked, a.sensor_hold)]
    )
    ref, keep = sensor_state.reference(times, rows, now, a.parted_window)
    limits = sensor_limits(core.config)
    slack = sensor_state.slack_mask(limits, tension, depth)
    pattern = sensor_state.parted_pattern(tension, ref, a.parted_drop, slack)
    first = np.array([[line.parted_seen for line in lines]])
    seen = np.maximum.accumulate(
        np.vstack([first, np.where(pattern, now[:, None], -math.inf)]), axis=0
    )[1:]
    firm = sensor_state.firm_times(now, slack, np.array([line.firm_seen for line in lines]))
    codes = sensor_state.decide_lines(
        a,
        limits,
        now,
        tension,
        tension_s,
        changed,
        spiked,
        seen,
        depth,
        d_changed,
        refused,
        firm,
    )
    depth_codes = sensor_state.decide_depth(
        a, now, depth, depth_s, d_changed, d_spiked, sea, d_refused, core.config.chart
    )
    for k, line in enumerate(lines):
        line.take(
            line.read(LineRulesPart)._replace(
                sensor_memory=memories[k],
                sensor_code=int(codes[-1, k]),
                parted_seen=float(seen[-1, k]),
                firm_seen=float(firm[-1, k]),
            )
        )
    last = np.column_stack([tension_s, depth_s])
    window_s = a.common_cause_window
    grouped = common_cause(last, now, silence_timeouts(core.config), window_s, flags)
    ids, found = _causes(input_names(core.config), last, grouped, window_s)
    core.state.take(
        SensorPart(
            depth_memory, int(depth_codes[-1]), times[keep:], rows[keep:],
            tuple(grouped[-1].tolist()), found[ids[-1]] if ids[-1] >= 0 else (),
        )  # fmt: skip
    )
    return SensorColumns(
        codes, depth_codes, before, before_depth, grouped, flags, ids, found, causes,
        (now, tension, tension_s, depth, depth_s), trend,
    )  # fmt: skip


def decide_units_window(
    core: MonitorCore, sensors: SensorColumns, dock: Optional['DockColumns']
) -> None:
    """The units check at the window's ticks, after the dock estimate (one of its
    witnesses): the ``wrong_units`` claims put over the lines' sensor codes (``sensors`` is
    changed); leaves the core's units latches and codes as after the last tick (as the
    core's ``_decide_units``)."""
    if not sensors.readings:
        return
    lines = core.state.lines
    a = core.config.alarm
    now, tension, tension_s, depth, depth_s = sensors.readings
    inputs = None if dock is None else dock.decision.line_inputs
    units, units_after = plausible.units_decide(
        core.rest_table,
        units_rule(core.config),
        [line.units for line in lines],
        now,
        tension,
        tension_s,
        depth,
        depth_s,
        (a.tension_timeout, a.depth_timeout),
        core.config.chart,
        inputs,
    )
    sensors.codes = sensor_state.with_units(sensors.codes, units)
    for k, line in enumerate(lines):
        line.take(
            line.read(LineRulesPart)._replace(
                sensor_code=int(sensors.codes[-1, k]), units=units_after[k]
            )
        )


def _causes(
    names: list[str], last: np.ndarray, grouped: np.ndarray, window: float
) -> tuple[np.ndarray, list[tuple[CommonCause, ...]]]:
    """Per tick, the index of its common causes among the distinct ones (-1: none): the
    silent inputs' stamps do not change while they are silent, so a day of silence is one."""
    ids = np.full(len(grouped), -1, np.int64)
    some = np.flatnonzero(grouped.any(axis=1))
    if not len(some):
        return ids, []
    rows = np.where(grouped[some], last[some], -np.inf)
    first, run = runs(rows)
    found = [common_cause_groups(names, row, row > -np.inf, window) for row in rows[first]]
    ids[some] = run
    return ids, found


def _depth_memories(
    core: MonitorCore, window: Window
) -> tuple[
    tuple[np.ndarray, np.ndarray, sensor_state.SeaColumns],
    sensor_state.DepthMemory,
    tuple[Any, ...],
]:
    """The depth memory's ``changed``, ``spiked`` and sea columns before the window (row 0),
    then after each of its depth samples, and the memory after the last: the core's
    :func:`~catenary_monitor.core.rules.sensor_state.sample_depth` in one loop
    (:func:`~catenary_monitor.core.rules.sensor_state.depth_samples`), with the tide trend's
    rate after each sample as the core steps it; last, that trend (:func:`tide_trend.series`)."""
    a = core.config.alarm
    _, dv = window.depth
    ds = window.sample_s(None)
    trend = tide_trend.series(core.state.trend, window.sample_ns(None), dv, a.tide_trend_window)
    columns, memory = sensor_state.depth_samples(
        core.state.depth_memory, ds.tolist(), dv.tolist(), a, trend[0].tolist(), a.stamp_jitter
    )
    return columns, memory, trend


def decide_tide(
    core: MonitorCore, window: Window, sensors: SensorColumns
) -> tuple[TideColumns, list[Transition]]:
    """The tide's decisions in the window and its transitions (the core is not changed)."""
    dd, dv = window.depth
    times, kinds = merge(dd, np.zeros(0, np.int64), window.ticks)
    k_idx = newest(kinds == KIND_TICK)
    d_idx = newest(kinds == KIND_DEPTH)
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
    code = pick(k_idx, sensors.depth_codes, sensors.before_depth).astype(np.int64)
    level = _worse(
        level, np.where(code == sensor_state.OUT_OF_RANGE, Level.ERROR, Level.WARN), code
    )
    rates, excess, trend = sensors.trend or tide_trend.series(
        core.state.trend, window.sample_ns(None), dv, core.config.alarm.tide_trend_window
    )
    tide = TideColumns(times, depth, depth_s, level, stale, rates, excess, trend, code, kinds)
    transitions = []
    old, entered = core.state.tide[0], core.state.tide_entered
    for i in level_changes(level, old).tolist():
        new = tide_status_at(core, tide, i)
        t = float(now[i])
        quiet = blind_quiet(old, new[0])
        transitions.append(Transition(t, old, new[0], new[1], t - entered, quiet))
        old, entered = new[0], t
    return tide, transitions


@dataclass
class BlindColumns:
    """The sensors' common-cause alarm at the tide's decisions
    (core.rules.health.sensors_status)."""

    waiting: np.ndarray  # (decisions, lines) bool: the line has had no tension yet
    levels: np.ndarray  # int8 Level per decision
    transitions: list[Transition]
    acks: alarm_ack.AckSeries
    before: tuple[tuple[Level, str], int]  # the status and the lines waiting before the window
    tick_at: np.ndarray  # per decision: the newest tick of the window (-1: before it)
    sensors: SensorColumns  # the common causes at the ticks


def blind_status_at(
    core: MonitorCore, tide: TideColumns, blind: BlindColumns, i: int
) -> tuple[Level, str]:
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
        blind.sensors.causes_at(int(blind.tick_at[i])),
        [line.config.name for line in core.state.lines],
    )


def decide_blind(
    core: MonitorCore, window: Window, tide: TideColumns, sensors: SensorColumns
) -> BlindColumns:
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
    tick_at = newest(tide.kinds == KIND_TICK)
    has_cause = np.asarray(sensors.grouped.any(axis=1), np.float64)
    caused = pick(tick_at, has_cause, float(bool(sensors.before_causes))) == 1.0
    levels = np.where(late | silent | caused, Level.STALE, Level.OK).astype(np.int8)
    before = (core.state.sensors, core.state.sensors_waiting)
    acks = alarm_ack.AckSeries(core.state.sensors_ack, levels[:0], [])
    blind = BlindColumns(waiting, levels, [], acks, before, tick_at, sensors)
    old, entered = core.state.sensors[0], core.state.sensors_entered
    for i in level_changes(levels, old).tolist():
        new = blind_status_at(core, tide, blind, i)
        t = float(times[i] * 1e-9)
        blind.transitions.append(Transition(t, old, new[0], new[1], t - entered))
        old, entered = new[0], t
    shelf = alarm_ack.shelved(core.state.sensors_ack)
    blind.acks = alarm_ack.replay_acks(
        core.state.sensors_ack,
        times * 1e-9,
        levels,
        masked=np.zeros(len(levels), np.int8) if shelf else None,
        flip_at=level_changes(levels, core.state.sensors[0]),
        chatter=chatter(core),
    )
    status, waits = core.state.sensors, core.state.sensors_waiting
    if len(times):
        status = blind_status_at(core, tide, blind, len(times) - 1)
        waits = int(waiting[-1].sum())
    core.state.take(BlindPart(status, waits, entered, blind.acks.final))
    return blind


def chatter(core: MonitorCore) -> tuple[int, float]:
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


def write_tide(
    core: MonitorCore, window: Window, tide: TideColumns, transitions: list[Transition]
) -> None:
    """The core's depth and tide state after the window's last event."""
    part = core.state.read(TidePart)._replace(trend=tide.trend)
    if len(tide.times):
        i = len(tide.times) - 1
        part = part._replace(tide=tide_status_at(core, tide, i), depth_stale=bool(tide.stale[i]))
    if transitions:
        part = part._replace(tide_entered=transitions[-1].time)
    dd, dv = window.depth
    if len(dd):
        last = int(window.sample_ns(None)[-1])
        part = part._replace(
            depth=float(dv[-1]), depth_s=float(last * 1e-9), depth_sample_ns=last
        )
    core.state.take(part)


class ComponentAcks(NamedTuple):
    """The tide's and the dock's alarms over the window (core.alarms.components): at the
    tide's decisions and at the ticks (the dock's: None without the dock model)."""

    tide: alarm_ack.AckSeries
    dock: Optional[alarm_ack.AckSeries]


def _component_series(
    core: MonitorCore, name: str, times_ns: np.ndarray, levels: np.ndarray
) -> alarm_ack.AckSeries:
    """The component ``name``'s alarm stepped at each of its decisions (as the core steps it
    at its level changes: idempotent elsewhere)."""
    before = core.component_ack(name)
    quiet = (levels == int(Level.STALE)) & (name in CONSEQUENCES)
    return alarm_ack.replay_acks(before, times_ns * 1e-9, levels, quiet)


def decide_component_acks(
    core: MonitorCore, window: Window, tide: TideColumns, dock: Optional[DockColumns]
) -> ComponentAcks:
    """The tide's and the dock's alarms over the window; leaves the core's as after it."""
    acks = list(core.state.component_acks)
    tide_acks = _component_series(core, 'tide', tide.times, tide.level)
    acks[COMPONENTS.index('tide')] = tide_acks.final
    dock_acks = None
    if dock is not None:
        dock_acks = _component_series(core, 'dock', window.ticks, dock.levels)
        acks[COMPONENTS.index('dock')] = dock_acks.final
    core.state.take(ComponentAckPart(tuple(acks)))
    return ComponentAcks(tide_acks, dock_acks)


@dataclass
class DockColumns:
    """The dock decisions at the window's ticks (the dock model only)."""

    decision: dock_live.DockDecision
    levels: np.ndarray  # int8 per tick
    before: tuple[tuple[Level, str], tuple[tuple[str, str], ...], list[tuple[float, ...]]]
    transitions: list[Transition]
    span_before: list[float]  # each line's dock_span before the window (m, NaN: installed)


def decide_dock_window(
    core: MonitorCore, window: Window, tide: TideColumns
) -> Optional[DockColumns]:
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
        return DockColumns(none, np.zeros(0, np.int8), before, [], span_before)
    now = ticks * 1e-9
    at = np.searchsorted(tide.times, ticks, 'right') - 1  # the tick's own tide decision
    depth = tide.depth[at]
    depth_ok = ~np.isnan(tide.depth_s[at]) & ~tide.stale[at]
    tension = np.empty((n, len(core.state.lines)))
    tension_s = np.empty((n, len(core.state.lines)))
    for k, line in enumerate(core.state.lines):
        tt, tv = window.tensions[k]
        j = np.searchsorted(tt, ticks, 'right') - 1  # tensions go before a tick at one stamp
        tension[:, k] = pick(j, tv, line.tension)
        tension_s[:, k] = pick(j, window.sample_s(k), line.tension_s)
    decision, smoothing = dock_live.decide_dock(
        model, core.config, now, depth, depth_ok, tension, tension_s, core.state.dock_smoothing
    )
    levels = decision.level
    transitions = []
    old, entered = core.state.dock[0], core.state.dock_entered
    for i in level_changes(levels, old).tolist():
        new = Level(int(levels[i]))
        t = float(now[i])
        message = dock_live.dock_message(model, decision, i)
        quiet = blind_quiet(old, new)
        transitions.append(Transition(t, old, new, message, t - entered, quiet))
        old, entered = new, t
    status = (Level(int(levels[-1])), dock_live.dock_message(model, decision, n - 1))
    values = dock_live.dock_values(decision, n - 1)
    core.state.take(DockPart(status, entered, values, smoothing))
    for k, line in enumerate(core.state.lines):
        line.take(
            line.read(LineRulesPart)._replace(
                dock=tuple(decision.line_inputs[-1, k].tolist()),
                dock_span=float(decision.span[-1, k]),
            )
        )
    return DockColumns(decision, levels, before, transitions, span_before)


def window_journal(
    core: MonitorCore,
    window: Window,
    tide: TideColumns,
    blind: BlindColumns,
    series: list[LevelSeries],
    steps: list[LineSteps],
    acks: list[alarm_ack.AckSeries],
    tide_transitions: list[Transition],
    dock: Optional[DockColumns],
) -> tuple[list[AlarmEvent], FloodColumns]:
    """The window's alarm journal (the tide's and the dock's, the sensors alarm, each line's,
    the flood's) in the core's order (time; within one event the components, the sensors, the
    lines, the flood), and the flood decisions."""
    unshelvable = core.config.alarm.unshelvable_conditions
    ranked: list[tuple[int, int, AlarmEvent]] = []
    at = level_changes(tide.level, core.state.tide[0])
    for i, tr in zip(at.tolist(), tide_transitions):
        ranked += [(int(tide.times[i]), -2, e) for e in component_entries('tide', tr)]
    if dock is not None and len(dock.levels):
        at = level_changes(dock.levels, dock.before[0][0])
        for i, tr in zip(at.tolist(), dock.transitions):
            ranked += [(int(window.ticks[i]), -2, e) for e in component_entries('dock', tr)]
    sensors = _journal(
        alarm_ack.SENSORS, blind.acks, tide.times, lambda i, a: alarm_ack.condition(a.level, ())
    )
    ranked += [(t, -1, e) for t, e in sensors]
    for k, line in enumerate(core.state.lines):
        condition = _raised_condition(series[k], unshelvable)
        ranked += [
            (t, k, e) for t, e in _journal(line.config.name, acks[k], steps[k].times, condition)
        ]
    raises = [(t, k, e.alarm) for t, k, e in ranked if e.kind == 'raised' and k > -2]

    def active(stamp: int) -> set[str]:
        """The alarms active after the event at ``stamp`` [ns]."""
        out = set()
        for k, line in enumerate(core.state.lines):
            i = int(np.searchsorted(steps[k].times, stamp, 'right')) - 1
            if _active(acks[k].at(i)):
                out.add(line.config.name)
        i = int(np.searchsorted(tide.times, stamp, 'right')) - 1
        if _active(blind.acks.at(i)):
            out.add(alarm_ack.SENSORS)
        return out

    flood, flood_log = _decide_flood(core, window, raises, active)
    ranked += [(t, len(core.state.lines), e) for t, e in flood_log]
    ranked.sort(key=lambda r: (r[0], r[1]))
    return [e for _, _, e in ranked], flood


@dataclass
class _Refusals:
    """The arrival times (ns) of the samples refused for their header stamps in a window
    (:func:`catenary_monitor.core.rules.readings.stamp_faults`): per line, and the depth's."""

    lines: list[np.ndarray]
    depth: np.ndarray


def accept(core: MonitorCore, window: Window) -> tuple[Window, _Refusals]:
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


def fuse_channels(core: MonitorCore, window: Window) -> Window:
    """The window with each line of several channels as one tension column: the core's
    channel step (core.rules.channels) over its merged samples, in order (such lines are rare: a
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
        state, fused, healthy, states = channels.run(
            line.channels, idx, window.sample_s(k), raw, limits
        )
        line.take(line.read(LineRulesPart)._replace(channels=state))
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


def write_refusals(core: MonitorCore, refusals: _Refusals) -> None:
    """When a sample was last refused for its stamp, per line and the depth, after the window."""
    for line, r in zip(core.state.lines, refusals.lines):
        if len(r):
            line.take(line.read(LineInputPart)._replace(stamp_refused=float(r[-1] * 1e-9)))
    if len(refusals.depth):
        refused = float(refusals.depth[-1] * 1e-9)
        core.state.take(core.state.read(TidePart)._replace(depth_refused=refused))


def _active(ack: alarm_ack.AckState) -> bool:
    return ack.active_since == ack.active_since


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


class FloodColumns(NamedTuple):
    """The flood decisions of a window (core.alarms.flood): decision stamps [ns] (raises and
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
    first: dict[int, tuple[str, float]]  # each start decision's first out

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
        since = float(self.stamps[start] * 1e-9)
        return alarm_flood.Flood(recent, since, self.first[start])


def _decide_flood(
    core: MonitorCore,
    window: Window,
    raises: list[tuple[int, int, str]],
    active: Callable[[int], set[str]],
) -> tuple[FloodColumns, list[tuple[int, AlarmEvent]]]:
    """The flood decisions at the window's raises (stamp ns, rank, alarm) and ticks, their
    journal records; leaves the core's flood state as after the window. ``active(stamp)``:
    the alarms active after the event at ``stamp`` [ns] (a flood's first out is one)."""
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
    outs = {}
    for j in first.tolist():
        lo_j = int(lo[j])
        recent = list(zip(times[lo_j : lo_j + int(count[j])].tolist(), names[lo_j:]))
        outs[j] = alarm_flood.first_out(recent, active(int(stamps[j])))
    flood = FloodColumns(
        stamps, lo, count, start, times, names, before, status_before, [], changes, outs
    )
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
    part = FloodPart(core.state.flood, core.state.alarms, entered)
    if len(stamps):
        last = flood.at(len(stamps) - 1)
        part = FloodPart(last, alarm_flood.status(last, a), entered)
    core.state.take(part)
    return flood, log
