"""The vectorized twin of :class:`~catenary_monitor.core.monitor.monitor_core.MonitorCore` over
log columns: :func:`advance`, :func:`run_log`, :func:`recompute`.

:func:`advance` takes a :class:`MonitorCore` and a :class:`~.window.Window` of events in time
order (tension samples per line, depth samples, ticks: columns of receive times in ns and values)
and leaves the core in exactly the state that stepping it event by event would leave (alarm
states, newest inputs and results, tide), returning what those steps did: every line's solved
updates (:data:`~catenary_monitor.core.monitor.state.OUTPUT_FIELDS`), every level transition
and, on request, every diagnostic snapshot. It exists only because it is measured faster (replay
of a day of log in seconds); ``test/test_batch.py`` feeds the same events to both and compares
every step. It writes the core's state only through its typed door
(:mod:`catenary_monitor.core.monitor.state`: ``state.take(part)``).

It follows the core's schedule (:mod:`catenary_monitor.core.monitor.monitor_core`): each line is
stepped at its tension samples, at every depth sample and at every tick; a line is solved at its
tension samples and, once it has a tension, at every depth sample; the tide is decided at depth
samples and ticks. Events with equal times are taken in the order depth, tensions (config order),
tick (the node's own logs have distinct stamps, so the rule only matters for other recordings).
The window-wide decisions are :mod:`.decisions`', the solves :mod:`.solve_columns`', the
snapshots :mod:`.snapshots`'.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Collection, Iterable, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.alarms import shelving
from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.alarms import flood as alarm_flood
from catenary_monitor.core.alarms.journal import AlarmEvent
from catenary_monitor.core.alarms.latches import CONDITIONS, LevelSeries, replay_levels
from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.monitor.events import Coalesced, Start
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.monitor.state import (
    NO_DEPTH,
    VALUE_FIELDS,
    LineAlarmPart,
    LineInputPart,
    LineRulesPart,
    LineSolvePart,
    LineState,
    StampPart,
)
from catenary_monitor.core.monitor.status import Change, Snapshot, line_dock_values
from catenary_monitor.core.monitor.status import depth_word as depth_state_word
from catenary_monitor.core.rules import channels, sensor_state, wave_window
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules import fatigue as fatigue_rule
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.rules.plausible import status_messages
from catenary_monitor.core.twin.decisions import (
    BlindColumns,
    DockColumns,
    SensorColumns,
    TideColumns,
    accept,
    chatter,
    decide_blind,
    decide_component_acks,
    decide_dock_window,
    decide_sensors_window,
    decide_units_window,
    decide_tide,
    fuse_channels,
    window_journal,
    write_refusals,
    write_tide,
)
from catenary_monitor.core.twin.schedule import LineSteps, line_steps, pick
from catenary_monitor.core.twin.snapshots import (
    DamageColumns,
    LineBefore,
    WindowMade,
    build_snapshot_columns,
    build_snapshots,
    line_word,
)
from catenary_monitor.core.twin.solve_columns import solve_line
from catenary_monitor.core.twin.window import (
    COLUMNS,
    EMPTY,
    MODEL_NAMES,
    Column,
    LineResult,
    SnapshotColumns,
    Window,
    WindowResult,
    concat_lines,
    slice_window,
    tick_grid,
)

__all__ = [
    'LineContext',
    'LineOutput',
    'LineRunner',
    'advance',
    'advance_lines',
    'run_log',
    'ReplayResult',
    'recompute',
]


_INCONSISTENT = CONDITIONS.index('inconsistent')


def _line_inputs(
    core: MonitorCore,
    line: LineState,
    steps: LineSteps,
    tide: TideColumns,
    values: dict[str, np.ndarray],
    status: np.ndarray,
    window: Window,
    tt: np.ndarray,
    dock: Optional[DockColumns] = None,
    k: int = 0,
    sensors: Optional[SensorColumns] = None,
    blind: Optional[BlindColumns] = None,
) -> dict[str, Any]:
    """The alarm inputs at every step of the line (newest solve, stamps, tide decision, the
    newest tick's dock estimate and sensor state, whether the sensors alarm stands)."""
    s = steps.s_idx
    before = dict(zip(VALUE_FIELDS, line.values))
    inputs: dict[str, Any] = {
        k: pick(s, values[k], before[k])
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
    inputs['status'] = np.maximum(pick(s, status.astype(np.float64), line.status), 0).astype(
        np.int64
    )
    inputs['uplift_view'] = inputs.pop('time_to_uplift_view')
    inputs['tide_rate'] = pick(steps.d_idx, tide.rates, core.state.trend.rate)
    inputs['tide_forecast'] = 1.0 if core.config.alarm.constituents else 0.0
    inputs['tension_stamp'] = pick(steps.t_idx, window.sample_s(k), line.tension_s)
    inputs['depth_stamp'] = pick(steps.d_idx, window.sample_s(None), core.state.depth_s)
    inputs['depth_stale'] = pick(
        steps.dk_idx, tide.stale.astype(np.float64), float(core.state.depth_stale)
    ).astype(bool)
    if sensors is not None:
        codes = sensors.codes[:, k].astype(np.float64)
        inputs['sensor_state'] = pick(steps.k_idx, codes, sensors.before[k])
        inputs['sensor_tension'] = pick(steps.t_idx, window.tensions[k][1], line.tension)
        inputs['mbl'] = line.config.mbl
        grouped = sensors.grouped[:, k].astype(np.float64)
        inputs['silent_group'] = pick(steps.k_idx, grouped, float(sensors.before_grouped[k]))
        inputs['parted_other'] = _parted_other(sensors, steps, k)
    if dock is not None:
        before_dock = dock.before[2][k]
        columns = dock.decision.line_inputs
        for j, key in enumerate(dock_live.LINE_INPUTS):
            col = columns[:, k, j] if columns is not None else np.zeros(0)
            inputs[key] = pick(steps.k_idx, col, before_dock[j])
        if blind is not None:  # the sensors alarm stands: the disagreement is its consequence
            stands = np.asarray(blind.levels != Level.OK, np.float64)
            was = float(blind.before[0][0] != Level.OK)
            masked = pick(steps.dk_idx, stands, was) == 1.0
            if masked.any():
                inputs['inconsistent'] = np.where(masked, np.nan, inputs['inconsistent'])
    return inputs


def _parted_other(sensors: SensorColumns, steps: LineSteps, k: int) -> Any:
    """Per step of line ``k``: the index of another line suspected parted at the newest tick
    (NaN none), as the core's ``parted_others`` of its lines' codes."""
    before = sensor_state.parted_others(np.asarray([sensors.before]))[0, k]
    codes = sensors.codes
    if before != before and not (codes == sensor_state.PARTED).any():
        return math.nan  # nobody parted before the window nor at its ticks
    column = sensor_state.parted_others(codes)[:, k] if len(codes) else np.zeros(0)
    return pick(steps.k_idx, column, float(before))


def _advance_line(
    core: MonitorCore,
    k: int,
    window: Window,
    tide: TideColumns,
    sensors: SensorColumns,
    dock: Optional[DockColumns] = None,
    blind: Optional[BlindColumns] = None,
) -> tuple[LineResult, LevelSeries, LineSteps, alarm_ack.AckSeries, np.ndarray]:
    """One line through the window; leaves the line's state in the core as after the steps
    (the core's depth and tide still as before the window). The last item: the line's fatigue
    damage after each of its tension samples."""
    line = core.state.lines[k]
    tt, tv = window.tensions[k]
    steps = line_steps(line, tt, window)
    times = window.sample_s(k)  # the reading times, as the core's tension_s
    peaks, waves, wave_state = wave_window.series(
        line.wave, times, tv, line.config.mbl, core.config.alarm.wave_window
    )
    values, status, used = solve_line(
        core, line, steps, tv, window, tide, sensors, k, (peaks, waves), dock
    )
    fatigue, fatigue_end = fatigue_rule.series(line.fatigue, times, tv, core.curves[k])
    at = steps.t_idx[steps.solved]
    for j, key in enumerate(fatigue_rule.FIELDS):
        values[key] = pick(at, fatigue[key], line.fatigue_values[j])
    fused = window.channel_values.get(k)
    for j, key in enumerate(channels.FIELDS):
        column = fused[j] if fused is not None else np.zeros(0)
        values[key] = pick(at, column, line.channel_values[j])
    inputs = _line_inputs(
        core, line, steps, tide, values, status, window, tt, dock, k, sensors, blind
    )
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
        chatter(core),
    )
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
    rules = line.read(LineRulesPart)._replace(wave=wave_state, fatigue=fatigue_end)
    if len(tt):
        rules = rules._replace(
            peak_tension=float(peaks[-1]),
            wave_tension=float(waves[-1]),
            fatigue_values=tuple(float(fatigue[key][-1]) for key in fatigue_rule.FIELDS),
        )
        if fused is not None:
            rules = rules._replace(channel_values=(float(fused[0][-1]), float(fused[1][-1])))
    line.take(rules)
    line.take(LineAlarmPart(series.final_state(), acks.final))
    _write_back(line, values, status, used, window.sample_ns(k), tv)
    return result, series, steps, acks, np.asarray(fatigue[fatigue_rule.FIELDS[0]], np.float64)


def _write_back(
    line: LineState,
    values: dict[str, np.ndarray],
    status: np.ndarray,
    used: Optional[np.ndarray],
    tt: np.ndarray,
    tv: np.ndarray,
) -> None:
    """The line's newest input and solve after its last step in the window (``tt``: its
    samples' reading times, ns)."""
    if len(tt):
        newest = line.read(LineInputPart)._replace(
            tension=float(tv[-1]), tension_s=float(tt[-1] * 1e-9), sample_ns=int(tt[-1])
        )
        line.take(newest)
    if len(status):
        last = int(status[-1])
        message = '' if last == NO_DEPTH else status_messages(line.config)[last]
        other = 3 if line.config.point_loads is not None else 2
        code = 0 if last == NO_DEPTH else (other if used is not None and used[-1] else 1)
        values_now = tuple(float(values[key][-1]) for key in VALUE_FIELDS)
        line.take(LineSolvePart(values_now, last, message, MODEL_NAMES[code]))


class LineContext(NamedTuple):
    """The window-wide decisions every line's steps read (made once, before the lines)."""

    tide: TideColumns
    sensors: SensorColumns
    dock: Optional[DockColumns]
    blind: BlindColumns


#: What one line's pass over a window gives: its results, level series, steps,
#: acknowledgement series and fatigue damage after each tension sample.
LineOutput = tuple[LineResult, LevelSeries, LineSteps, alarm_ack.AckSeries, np.ndarray]

#: Who runs the lines of a window (``advance(..., lines=)``): given the core after the
#: window-wide decisions, the window and the decisions, every line's :data:`LineOutput` in
#: order, each line's state left in the core as :func:`advance_lines` leaves it (only
#: asked without snapshots: the level series' inputs forgotten).
LineRunner = Callable[[MonitorCore, Window, LineContext], list[LineOutput]]


def advance_lines(
    core: MonitorCore,
    window: Window,
    context: LineContext,
    ks: Iterable[int],
    keep_inputs: bool = False,
    value_keys: Optional[Collection[str]] = None,
) -> list[LineOutput]:
    """Lines ``ks`` of the core through the window, in that order (each line's pass reads
    the core and writes only that line's state); without ``keep_inputs`` each level series
    lets its inputs go as soon as it is made (no snapshot asks for a message).
    ``value_keys``: only those values are kept of each line's results (None: every one)."""
    out = []
    for k in ks:
        r, s, st, a, d = _advance_line(
            core, k, window, context.tide, context.sensors, context.dock, context.blind
        )
        if not keep_inputs:
            s.forget_inputs()
        if value_keys is not None:
            r.values = {key: v for key, v in r.values.items() if key in value_keys}
        out.append((r, s, st, a, d))
    return out


def advance(
    core: MonitorCore,
    window: Window,
    snapshots: bool | str = False,
    lines: Optional[LineRunner] = None,
) -> WindowResult:
    """Step ``core`` through every event of ``window`` in vectorized code.

    Leaves ``core`` as ``core.step`` would, event by event (depth, tensions, tick at equal
    times), and returns what the steps did; ``snapshots=True`` also builds every diagnostic
    snapshot the core would have made (ticks and level changes); ``snapshots=COLUMNS``, the
    same as one :class:`SnapshotColumns` (or Snapshots where it falls back). ``lines``: who
    runs the lines without snapshots (:data:`LineRunner`; default :func:`advance_lines`
    here).
    """
    if len(window.tensions) != len(core.state.lines):
        raise ValueError(
            f'window has {len(window.tensions)} tension columns for '
            f'{len(core.state.lines)} lines'
        )
    given = window
    window, refusals = accept(core, window)
    window = fuse_channels(core, window)
    depth_before = (
        core.state.depth,
        core.state.depth_s,
        core.state.depth_stale,
        core.state.trend.rate,
    )
    tide_before = core.state.tide
    lines_before = [
        LineBefore(
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
            line_word(core, line, line.sensor_code, line.state.latches[_INCONSISTENT].active),
        )
        for line in core.state.lines
    ]
    depth_word = depth_state_word(core.state.depth_s, core.state.depth_code)
    sensors = decide_sensors_window(core, window, refusals)
    tide, tide_transitions = decide_tide(core, window, sensors)
    blind = decide_blind(core, window, tide, sensors)
    dock = decide_dock_window(core, window, tide)
    component_acks = decide_component_acks(core, window, tide, dock)
    decide_units_window(core, sensors, dock)
    befores = [line.fatigue_values[0] for line in core.state.lines]
    context = LineContext(tide, sensors, dock, blind)
    if lines is not None and not snapshots:
        outs = lines(core, window, context)
    else:
        outs = advance_lines(core, window, context, range(len(befores)), bool(snapshots))
    results, series, steps, acks, damage = [], [], [], [], []
    for k, (r, s, st, a, d) in enumerate(outs):
        results.append(r)
        series.append(s)
        steps.append(st)
        acks.append(a)
        damage.append(DamageColumns(window.tensions[k][0], d, befores[k]))
    journal, flood = window_journal(
        core, window, tide, blind, series, steps, acks, tide_transitions, dock
    )
    times = [c[0] for c in (*given.tensions, given.depth, (given.ticks, None)) if len(c[0])]
    start = int(min(t[0] for t in times)) if times else core.state.last_ns
    end = int(max(t[-1] for t in times)) if times else core.state.last_ns
    snaps: list[Snapshot | SnapshotColumns] = []
    if snapshots:
        build = build_snapshot_columns if snapshots == COLUMNS else build_snapshots
        made = build(
            WindowMade(
                core, window, tide, results, series, steps, depth_before, tide_before,
                lines_before, acks, dock, sensors, depth_word, blind, flood, damage,
                component_acks,
            )  # fmt: skip
        )
        snaps = [made] if isinstance(made, SnapshotColumns) else list(made)
    write_tide(core, window, tide, tide_transitions)
    write_refusals(core, refusals)
    core.state.take(StampPart(max(core.state.last_ns, end)))
    others = [Change('sensors', tr) for tr in blind.transitions]
    others += [] if dock is None else [Change('dock', tr) for tr in dock.transitions]
    others += [Change(alarm_flood.NAME, tr) for tr in flood.transitions]
    return WindowResult(results, tide_transitions, snaps, start, end, others, alarm_events=journal)


def run_log(
    core: MonitorCore,
    window: Window,
    events: Any = (),
    snapshots: bool | str = False,
    lines: Optional[LineRunner] = None,
) -> tuple[WindowResult, MonitorCore]:
    """Advance ``core`` over a whole log; return the results and the core at the end.

    ``window`` holds the input columns and the ticks; ``events`` the other records in time
    order: logger changes and reconfigurations, stepped by the core itself between vectorized
    stretches (inputs before an event's stamp go first), and :class:`Start` (the monitor
    restarted: a new core, blind again, from then on). ``snapshots=COLUMNS``: the snapshots
    are the pieces' in order, then the events' (not merged in time: see
    :class:`SnapshotColumns`). ``lines``: who runs the lines (:func:`advance`).
    """
    window, events, marks = _leave_out_coalesced(core, window, list(events))
    pieces: list[WindowResult] = []
    extra: list[Snapshot | SnapshotColumns] = []
    others: list[Change] = []
    journal: list[AlarmEvent] = []
    lo: Optional[int] = None
    for event in [*events, None]:
        hi = None if event is None else event.stamp_ns
        pieces.append(advance(core, slice_window(window, lo, hi), snapshots, lines))
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
    joined = [concat_lines([p.lines[k] for p in pieces]) for k in range(len(core.state.lines))]
    tide = [tr for p in pieces for tr in p.tide]
    others = sorted(
        others + [c for p in pieces for c in p.others], key=lambda c: c.transition.time
    )
    snaps = [s for p in pieces for s in p.snapshots] + extra
    if snapshots != COLUMNS:
        snaps.sort(key=lambda s: s.stamp_ns)  # type: ignore[union-attr]
    return (
        WindowResult(
            joined,
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
    core.state.take(StampPart(max(last, max(m.stamp_ns for m in kept))))


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
    columns = [tensions.get(line.name, EMPTY) for line in config.lines]
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
