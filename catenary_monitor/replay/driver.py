"""The one replay driver: a log read once, the node's schedule rebuilt, the core advanced window
by window (bounded memory). ``catenary-monitor replay``, the console's log view and the tests
all call it: :func:`drive` for outputs written window by window, :func:`replay_log` for one
:class:`ReplayResult` of the whole log.

:func:`stream` walks the log (every file of a rotated set or directory, in time order, merged
across topics) in windows of log time (:func:`catenary_monitor.io.mcap_read.iter_windows`),
hands each window to :func:`catenary_monitor.core.twin.engine.run_log` with the core that the
previous window left (``advance`` leaves it exactly as stepping would), and gives each
window's results to the caller, which writes them (summary tally, CSV rows, MCAP, plot
envelopes). Every column of a window, ticks and events included, is cut at the same time
boundary (``t < hi`` in the window, ``t >= hi`` after it), so events at equal stamps stay
together in their window in the core's order (depth, tensions, tick) and a recorded event
still splits the inputs at its stamp. The results equal one window over the whole log (the
tests replay with tiny windows and compare).

Two facts are only known once the first window is read: when the monitor started (the first
Start record, else the first input message) and where the ticks come from (the node's
records or a grid). A log that contradicts them later (a Start after inputs without one
before, events after a first window without any, files overlapping in time) cannot be
streamed: :class:`Restart` asks the caller to replay it as one window (memory then grows with
the log; the summary says ``streamed: false``); :func:`drive` does that.

Errors a user can act on are :class:`ReplayError` (one line, with the command's exit status).
"""

from __future__ import annotations

import contextlib
import copy
import json
import os
from functools import partial
from dataclasses import dataclass, field
from pathlib import Path
from typing import (
    Any,
    Callable,
    Collection,
    Iterator,
    Mapping,
    NamedTuple,
    Optional,
    Protocol,
    Sequence,
)

import numpy as np

from catenary_monitor.core.config.parameters import (
    ConfigError,
    LineConfig,
    MonitorConfig,
    config_from_params,
    load_params_file,
    resolve_topic,
)
from catenary_monitor.core.rules import channels, readings
from catenary_monitor.core.monitor.events import (
    EVENTS_TOPIC,
    NODE_NAME,
    Reconfigure,
    Start,
    Tick,
    parse_event_record,
)
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.twin.engine import LineRunner, ReplayResult, run_log
from catenary_monitor.core.twin.window import (
    Window,
    concat_lines,
    grid_ticks,
    quiet_span,
    slice_window,
)
from catenary_monitor.core.physics import fused_kernel
from catenary_monitor.io import mcap_read, sensor_cdr
from catenary_monitor.io.cdr import string_message, string_text
from catenary_monitor.io.mcap_read import (
    EmptyLogError,
    LogWindow,
    TopicTypeError,
    UnorderedLogError,
    expand_paths,
    iter_windows,
    read_float64_topics,
)
from catenary_monitor.io.mcap_scan import McapReadError, ReadReport
from catenary_monitor.io.mcap_summary import read_metadata

__all__ = [
    'EXIT_EMPTY',
    'NoEventsChannel',
    'LogReplay',
    'ReplayError',
    'Restart',
    'Sink',
    'StreamState',
    'WINDOW_MESSAGES',
    'drive',
    'expand',
    'input_topics',
    'load_config',
    'log_parameters',
    'read_inputs',
    'replay_log',
    'stamp_figures',
    'stamp_lines',
    'stream',
]

#: Exit status for a log without any message on the requested topics.
EXIT_EMPTY = 3

#: Input messages per window by default (about 300 B each in flight for a summary, 750 B with
#: the diagnostics of ``--out``): the bound of replay's memory beyond the interpreter's.
WINDOW_MESSAGES = 1 << 17

#: With snapshots (``--out``), a window is recomputed in parts of at most this many ticks:
#: a part's snapshots (in columns) and their payloads, with the statuses' texts, take about
#: 0.24 MB per tick until written (the 3e6 log's ``--out``: 152 MiB peak; 126.5 at 128 ticks
#: for 9 % more CPU, 217 at 512). Each topic's messages do not depend on it (log times and
#: payloads), only how the topics interleave in the file.
TICKS_PER_PART = 256

#: A window on a grid of ticks is recomputed in parts of at most this many ticks (the window
#: holds a bounded number of messages, but each may be followed by a silence the grid ticks
#: through for :func:`quiet_span`).
GRID_TICKS_PER_PART = 1 << 14

_TICK_PAYLOAD = string_message('{"kind": "tick"}')


class ReplayError(Exception):
    """A failure a user can act on: ``str()`` is one line; ``code`` the command's exit status."""

    def __init__(self, message: str, code: int = 2) -> None:
        super().__init__(message)
        self.code = code


class Restart(Exception):
    """The log cannot be streamed (see the module docstring): replay it as one window."""


class NoEventsChannel(LookupError):
    """``ticks='log'`` and the log has no events channel (it was not recorded by the node)."""


@dataclass
class StreamState:
    """What the stream knows after its first window, and the figures of the run; with the
    core and the next grid tick, all a later piece of the same log needs to go on
    (:func:`stream`'s ``resume``)."""

    start_ns: Optional[int] = None
    start_from_record: bool = False
    ticks_from_log: Optional[bool] = None
    windows: int = 0
    messages: int = 0
    bytes_done: int = 0
    bytes_total: int = 0
    core: Optional[MonitorCore] = None  # the core after the last window
    grid_k: int = 0  # the next grid tick's index
    # A log stepped on a grid (no recorded ticks): its samples, its bad stamps and silences.
    last_sample_ns: Optional[int] = None  # the newest input sample read, a bad stamp or not
    last_input_ns: Optional[int] = None  # the newest input sample stepped
    ticked_to: Optional[int] = None  # the newest grid tick given
    bad_stamps: int = 0  # samples far from every other (core.rules.readings.far_stamps)
    bad_stamp_first: list[tuple[str, int]] = field(default_factory=list)  # (input, ns), <= 3
    silences: int = 0  # silences longer than the grid ticks after an input (quiet_span)
    silent_ns: int = 0  # the time of those silences the grid did not tick through


def _events(window: LogWindow) -> tuple[bool, np.ndarray, list[Any]]:
    """(any record seen, tick stamps ns, the other records) of a window's events channel."""
    stamps, payloads = window.raw.get(EVENTS_TOPIC, (np.zeros(0, np.int64), []))
    if not len(payloads):
        return False, np.zeros(0, np.int64), []
    is_tick = np.fromiter((p == _TICK_PAYLOAD for p in payloads), bool, len(payloads))
    ticks = [stamps[is_tick]]
    others: list[Any] = []
    for i in np.flatnonzero(~is_tick).tolist():
        try:
            text = string_text(payloads[i])
        except ValueError:
            continue
        event = parse_event_record(int(stamps[i]), text)
        if isinstance(event, Tick):
            ticks.append(np.array([event.stamp_ns], np.int64))
        elif event is not None:
            others.append(event)
    return True, np.sort(np.concatenate(ticks)), others


def typed_inputs(config: MonitorConfig) -> dict[str, str]:
    """The input topics of a stamped type (resolved topic -> type name): read as raw
    messages and decoded (:mod:`catenary_monitor.io.sensor_cdr`), the others as Float64
    columns."""
    out = {
        resolve_topic(line.topics[0]): line.tension_type
        for line in config.lines
        if line.tension_type in readings.STAMPED
    }
    if config.depth_type in readings.STAMPED:
        out[resolve_topic(config.depth_topic)] = config.depth_type
    return out


class Inputs(NamedTuple):
    """A window's inputs in SI (:mod:`catenary_monitor.core.rules.readings`): tension columns
    (config order) and the depth column as (arrival ns, value), and the header stamps (ns)
    beside each column of a stamped type (None: taken at arrival; all None: no stamped
    input)."""

    tensions: list[Any]
    depth: Any
    tension_stamps: Optional[list[Optional[np.ndarray]]]
    depth_stamps: Optional[np.ndarray]
    channels: Optional[list[Optional[np.ndarray]]] = None  # a line's samples' channels


def _column(
    window: LogWindow, topic: str, type_name: str, convert: Callable[[dict[str, Any]], Any]
) -> tuple[Any, Optional[np.ndarray]]:
    """One input's column in SI, and its header stamps (None for Float64)."""
    if type_name not in readings.STAMPED:
        t, v = window.columns[topic]
        return (t, np.asarray(convert({'value': v}), np.float64)), None
    times, payloads = window.raw.get(topic, (np.zeros(0, np.int64), []))
    decoded = sensor_cdr.decode(type_name, payloads)
    value = np.asarray(convert(decoded.fields), np.float64).reshape(-1)
    return (times[decoded.ok], value), decoded.stamps


def _merged(
    line: LineConfig, columns: Mapping[str, tuple[np.ndarray, np.ndarray]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A load cell's channel columns (Float64) merged in time order (stable): stamps (ns), each
    sample's channel and its reading in N."""
    parts = [columns[resolve_topic(t)] for t in line.channel_topics]
    times = np.concatenate([t for t, _ in parts])
    order = np.argsort(times, kind='stable')
    raw = np.concatenate([v for _, v in parts])[order]
    idx = np.concatenate([np.full(len(t), j, np.int64) for j, (t, _) in enumerate(parts)])
    value = np.asarray(readings.tension_si(line, {'value': raw}), np.float64)
    return times[order], idx[order], value


def fused_tensions(
    config: MonitorConfig, line: LineConfig, columns: Mapping[str, Any]
) -> tuple[np.ndarray, np.ndarray]:
    """A load cell's tension column from every channel, fused as the monitor fuses them
    (:func:`catenary_monitor.core.rules.channels.run` from the first sample): stamps (ns),
    tension (N; NaN while blind)."""
    times, idx, value = _merged(line, columns)
    a = config.alarm
    limits = channels.Limits(
        a.tension_timeout,
        a.stuck_time,
        a.tension_resolution,
        a.channel_tolerance,
        int(line.min_channels),
    )
    start = channels.initial(len(line.channel_topics))
    _, fused, _, _ = channels.run(start, idx, times * 1e-9, value, limits)
    return times, fused


def _inputs(config: MonitorConfig, window: LogWindow) -> Inputs:
    """The window's inputs (:class:`Inputs`), each read as its type says."""
    tensions: list[Any] = []
    stamps: list[Optional[np.ndarray]] = []
    chans: list[Optional[np.ndarray]] = []
    for line in config.lines:
        convert = partial(readings.tension_si, line)
        if line.channel_topics:  # every channel's samples merged in time order (stable)
            times, idx, value = _merged(line, window.columns)
            tensions.append((times, value))
            stamps.append(None)
            chans.append(idx)
            continue
        column, st = _column(window, resolve_topic(line.topics[0]), line.tension_type, convert)
        tensions.append(column)
        stamps.append(st)
        chans.append(None)
    depth, d_stamps = _column(
        window,
        resolve_topic(config.depth_topic),
        config.depth_type,
        lambda f: readings.depth_si(config, f),
    )
    stamped = any(s is not None for s in stamps) or d_stamps is not None
    channels = chans if any(c is not None for c in chans) else None
    return Inputs(tensions, depth, stamps if stamped else None, d_stamps, channels)


def stream(
    paths: Sequence[Path],
    config: MonitorConfig,
    sink: Callable[[ReplayResult, Window], None],
    *,
    ticks: str = 'auto',
    follow_log: bool = True,
    snapshots: bool | str = False,
    window_messages: Optional[int] = WINDOW_MESSAGES,
    jobs: int = 1,
    report: Optional[ReadReport] = None,
    progress: Optional[Callable[[StreamState], None]] = None,
    resume: Optional[StreamState] = None,
    goes_on: bool = False,
    next_ns: Optional[int] = None,
    line_processes: int = 1,
    value_keys: Optional[Collection[str]] = None,
) -> StreamState:
    """Replay ``paths`` window by window; ``sink(result, window)`` gets each window's
    :class:`ReplayResult` (its ticks, events, start) and its input :class:`Window`.

    A log replayed in pieces (consecutive files, every stamp of one before every stamp of the
    next): ``resume`` is the state the previous piece returned (its core goes on; it is not
    changed); ``goes_on``: more pieces follow (a piece without any input is then no error).
    Grid ticks of the gap between two pieces come with the next piece, before its inputs, as
    in one stream; ``next_ns``: the first stamp of the next piece (whether this piece's last
    sample is a bad stamp depends on it). The pieces' results are those of the whole log
    (:mod:`catenary_monitor.replay.fleet_tasks`).

    ``ticks``: ``auto`` takes the node's recorded ticks when the log has them, else a grid at
    ``diagnostic_rate``; ``log`` requires them; ``grid`` ignores them. On a grid, a sample far
    from every other (:func:`catenary_monitor.core.rules.readings.far_stamps`) is a bad stamp,
    left out and counted, and a silence of the inputs is ticked through only for
    :func:`~catenary_monitor.core.twin.window.quiet_span` (the state counts the silences).
    ``follow_log``: apply the parameter changes the node recorded (with the recorded
    parameters only);
    ``window_messages`` None replays the log as one window. Raises :class:`Restart` (see the
    module docstring), and what :func:`iter_windows` raises (EmptyLogError at the end).
    The solve kernel leaves the cores of the decoding to it: the read-ahead thread's, or the
    ``jobs`` worker processes' (on two cores, two kernel threads beside the read-ahead made the
    1e7 summary 10-25 % slower than one; docs/benchmarks.md).

    ``line_processes`` 2: each window's lines in two processes (:mod:`.line_split`: a worker
    forked before the log is read), where :func:`split_lines` allows it (else one); the
    results are the same. ``value_keys``: the line values ``sink`` reads (None: every one;
    the others need not come back from the worker).
    """
    busy = jobs if jobs > 1 else int(mcap_read.READ_AHEAD > 0)
    split = split_lines(config, line_processes, snapshots, jobs)
    with contextlib.ExitStack() as stack:
        lines = None
        if split:
            from catenary_monitor.replay.line_split import LineSplit, worker_lines

            n = len(config.lines)
            lines = stack.enter_context(LineSplit(n, worker_lines(n), value_keys))
        stack.enter_context(fused_kernel.cores_left_to(busy + int(split)))
        return _stream(
            paths,
            config,
            sink,
            ticks,
            follow_log,
            snapshots,
            window_messages,
            jobs,
            report,
            progress,
            resume,
            goes_on,
            next_ns,
            lines,
        )


def split_lines(
    config: MonitorConfig, line_processes: int, snapshots: bool | str = False, jobs: int = 1
) -> bool:
    """Whether :func:`stream` runs the lines in two processes: asked for (``line_processes``
    >= 2), two CPUs usable (``os.sched_getaffinity``), ``os.fork`` there, two lines or more,
    no snapshots (``--out``), no decoding processes (``jobs``)."""
    from catenary_monitor.replay.line_split import usable_cpus

    return (
        line_processes >= 2
        and not snapshots
        and jobs <= 1
        and len(config.lines) >= 2
        and hasattr(os, 'fork')
        and usable_cpus() >= 2
    )


def _stream(
    paths: Sequence[Path],
    config: MonitorConfig,
    sink: Callable[[ReplayResult, Window], None],
    ticks: str,
    follow_log: bool,
    snapshots: bool | str,
    window_messages: Optional[int],
    jobs: int,
    report: Optional[ReadReport],
    progress: Optional[Callable[[StreamState], None]],
    resume: Optional[StreamState] = None,
    goes_on: bool = False,
    next_ns: Optional[int] = None,
    lines: Optional[LineRunner] = None,
) -> StreamState:
    """:func:`stream` itself."""
    state = StreamState() if resume is None else copy.deepcopy(resume)
    state.bytes_done, state.bytes_total = 0, sum(p.stat().st_size for p in paths)
    lines_topics = [resolve_topic(t) for line in config.lines for t in line.topics]
    topics = [resolve_topic(config.depth_topic), *lines_topics]
    raw = [EVENTS_TOPIC] if ticks != 'grid' else []
    typed = typed_inputs(config)
    core = state.core
    try:
        for window in iter_windows(
            paths,
            topics,
            raw,
            window_messages,
            report,
            jobs,
            typed=typed,
            allow_empty=goes_on or resume is not None,
        ):
            seen, tick_ns, others = _events(window) if raw else (False, np.zeros(0, np.int64), [])
            if not follow_log:
                others = [e for e in others if not isinstance(e, Reconfigure)]
            inputs = _inputs(config, window)
            stamps: Optional[np.ndarray] = None  # the inputs' stamps, sorted (for the grid)
            if not (seen if core is None else state.ticks_from_log):  # stepped on a grid
                inputs, stamps = _without_bad_stamps(state, config, window, inputs, next_ns)
            tensions, depth = inputs.tensions, inputs.depth
            if core is None:
                firsts = [int(c[0][0]) for c in (*tensions, depth) if len(c[0])]
                starts = [e.stamp_ns for e in others if isinstance(e, Start)]
                if starts:
                    state.start_ns, state.start_from_record = starts[0], True
                    others = [
                        e for e in others if e.stamp_ns != starts[0] or not isinstance(e, Start)
                    ]
                elif firsts:
                    state.start_ns = min(firsts)
                elif not window.final or goes_on:
                    raise Restart('no input message and no start record in the first window')
                state.ticks_from_log = seen
                if ticks == 'log' and not seen:
                    if not window.final:
                        raise Restart('no events record in the first window')
                    raise NoEventsChannel(EVENTS_TOPIC)
                core = MonitorCore(config, state.start_ns or 0)
            elif any(isinstance(e, Start) for e in others) and not state.start_from_record:
                raise Restart('a start record after the first window, none before it')
            elif seen and not state.ticks_from_log:
                raise Restart('events records after a first window without any')
            whole = Window(
                tensions,
                depth,
                tick_ns,
                inputs.tension_stamps,
                inputs.depth_stamps,
                inputs.channels,
            )
            if state.ticks_from_log:
                parts = _parts(whole, others, TICKS_PER_PART if snapshots else 0)
            else:  # no recorded events: ``others`` is empty
                cap = TICKS_PER_PART if snapshots else GRID_TICKS_PER_PART
                parts = _grid_parts(state, config, window, whole, cap, goes_on, stamps)
            for part, part_events in parts:
                result, core = run_log(core, part, part_events, snapshots, lines)
                replay = ReplayResult(
                    result.lines,
                    result.tide,
                    result.snapshots,
                    min(state.start_ns or 0, result.start_ns),
                    result.end_ns,
                    result.others,
                    part.ticks,
                    bool(state.ticks_from_log),
                    state.start_ns or 0,
                    part_events,
                    alarm_events=result.alarm_events,
                )
                sink(replay, part)
                del result, replay, part, part_events  # not held while the next is recomputed
            state.windows += 1
            state.messages += window.messages
            state.bytes_done = window.bytes_done
            state.core = core
            # nothing of this window held while the next one is read and recomputed (its
            # results and inputs were a window's worth of memory on top of the next one's)
            del window, whole, inputs, tensions, depth, parts, others, stamps
            if progress is not None:
                progress(state)
    except UnorderedLogError as err:
        raise Restart(str(err)) from err
    return state


def _parts(window: Window, events: list[Any], ticks: int) -> Iterator[tuple[Window, list[Any]]]:
    """The window cut in time before every ``ticks``-th tick (all of it when ``ticks`` is 0
    or it has no more): each part is itself a legal window (every column cut at the same
    time), with the events of its stretch."""
    if not ticks or len(window.ticks) <= ticks:
        yield window, events
        return
    cuts = [int(t) for t in window.ticks[ticks::ticks]]
    lo: Optional[int] = None
    for hi in [*cuts, None]:
        part = slice_window(window, lo, hi)
        inside = [e for e in events if (lo is None or e.stamp_ns >= lo)]
        yield part, [e for e in inside if hi is None or e.stamp_ns < hi]
        lo = hi


def _grid_parts(
    state: StreamState,
    config: MonitorConfig,
    window: LogWindow,
    whole: Window,
    cap: int,
    goes_on: bool = False,
    stamps: Optional[np.ndarray] = None,
) -> Iterator[tuple[Window, list[Any]]]:
    """The window with its grid ticks (:func:`grid_ticks` from ``state.grid_k``), in parts of at
    most ``cap`` ticks, each cut in time before the next part's first tick (as :func:`_parts`).

    The ticks reach the window's end, except after its newest input when a silence longer
    than the grid ticks through (:func:`quiet_span`) reaches the window's end: those come with
    the next window (before its inputs), or never when no input follows; in a final window
    (one of a piece that ``goes_on`` too) they end at the newest input. ``state`` takes the
    next k, the newest input and tick, and the silences. ``stamps``: the window's input
    stamps sorted, when the caller has them (:func:`_without_bad_stamps`)."""
    rate = config.alarm.diagnostic_rate
    quiet = int(quiet_span(config) * 1e9)
    if stamps is None:
        stamps = _sorted_stamps(whole.tensions, whole.depth)
    before = state.last_input_ns
    last = int(stamps[-1]) if len(stamps) else before
    if last is None:  # no input yet (a piece without any): nothing to tick
        yield whole, []
        return
    end = window.hi - 1 if window.hi is not None else last
    if window.final or window.hi is None or window.hi - last > quiet:
        end = last
    if (
        window.final
        and not len(stamps)
        and not goes_on
        and state.ticked_to is not None
        and state.ticked_to > last
    ):
        raise Restart('the last window has no input message')
    seq = stamps if before is None else np.concatenate([[before], stamps])
    gaps = np.diff(seq)
    silent = gaps[gaps > quiet]
    state.silences += len(silent)
    state.silent_ns += int((silent - quiet).sum())
    state.last_input_ns = last
    start = state.start_ns or 0
    ticks, k = grid_ticks(start, rate, state.grid_k, stamps, before, quiet, end, cap)
    lo: Optional[int] = None
    while True:
        nxt, k_next = np.zeros(0, np.int64), k
        if len(ticks) == cap:
            nxt, k_next = grid_ticks(start, rate, k, stamps, before, quiet, end, cap)
        hi = int(nxt[0]) if len(nxt) else None
        part = slice_window(whole, lo, hi)
        part.ticks = ticks
        if len(ticks):
            state.ticked_to = int(ticks[-1])
        state.grid_k = k
        yield part, []
        if hi is None:
            return
        lo, ticks, k = hi, nxt, k_next


def _utc(t: float) -> str:
    try:
        text = str(np.datetime_as_string(np.datetime64(int(round(t * 1e3)), 'ms'), 'ms'))
        return text.replace('T', ' ') + ' UTC'
    except (OverflowError, ValueError):
        return f'{t!r} s'


def stamp_lines(figures: Mapping[str, Any]) -> list[str]:
    """One line on the bad stamps a grid replay left out and one on the silences it did not
    tick through, of :func:`stamp_figures` (none when there were none)."""
    out = []
    bad = figures.get('bad_stamps')
    if bad:
        days = readings.STAMP_FAR / 86_400.0
        first = ', '.join(f'{b["input"]} at {_utc(b["time"])}' for b in bad['first'])
        more = ', ...' if bad['count'] > len(bad['first']) else ''
        out.append(
            f'bad stamps: {bad["count"]} input sample(s) stamped more than {days:g} days from '
            f'every other, left out ({first}{more})'
        )
    quiet = figures.get('silences')
    if quiet:
        out.append(
            f'silences: {quiet["count"]} gap(s) in the inputs longer than the grid ticks '
            f'after an input, {quiet["not_ticked_s"] / 86_400.0:.2f} days not ticked through'
        )
    return out


def stamp_figures(state: StreamState) -> dict[str, Any]:
    """The bad stamps and the silences of a grid replay, for a summary (``bad_stamps``,
    ``silences``; empty when there are none)."""
    out: dict[str, Any] = {}
    if state.bad_stamps:
        out['bad_stamps'] = {
            'count': state.bad_stamps,
            'first': [{'input': n, 'time': ns * 1e-9} for n, ns in state.bad_stamp_first],
        }
    if state.silences:
        out['silences'] = {'count': state.silences, 'not_ticked_s': state.silent_ns * 1e-9}
    return out


def _without_bad_stamps(
    state: StreamState,
    config: MonitorConfig,
    window: LogWindow,
    inputs: Inputs,
    next_ns: Optional[int],
) -> tuple[Inputs, np.ndarray]:
    """The window's inputs without their bad stamps (samples far from every other:
    :func:`catenary_monitor.core.rules.readings.far_stamps`), counted in ``state``. The
    neighbours across windows: the newest sample before (``state``), and after the window the
    message its end was cut at (``next_ns`` after the final window of a piece that goes on).
    With the stamps of the inputs kept, sorted (:func:`_sorted_stamps`)."""
    stamps = _sorted_stamps(inputs.tensions, inputs.depth)
    if not len(stamps):
        return inputs, stamps
    after = window.hi if not window.final else next_ns
    far = readings.far_stamps(stamps, state.last_sample_ns, after)
    state.last_sample_ns = int(stamps[-1])
    if not far.any():
        return inputs, stamps
    bad = stamps[far]
    names = [line.name for line in config.lines] + ['depth']
    keep = [~np.isin(t, bad) for t, _ in (*inputs.tensions, inputs.depth)]
    for name, (t, _), kept in zip(names, (*inputs.tensions, inputs.depth), keep):
        for stamp in t[~kept].tolist():
            state.bad_stamps += 1
            if len(state.bad_stamp_first) < 3:
                state.bad_stamp_first.append((name, int(stamp)))

    def cut(col: Any, kept: np.ndarray) -> Any:
        return None if col is None else col[kept]

    n = len(config.lines)
    tensions = [(t[m], v[m]) for (t, v), m in zip(inputs.tensions, keep[:n])]
    depth = (inputs.depth[0][keep[n]], inputs.depth[1][keep[n]])
    t_stamps = (
        None
        if inputs.tension_stamps is None
        else [cut(c, m) for c, m in zip(inputs.tension_stamps, keep[:n])]
    )
    chans = None if inputs.channels is None else [cut(c, m) for c, m in zip(inputs.channels, keep)]
    out = Inputs(tensions, depth, t_stamps, cut(inputs.depth_stamps, keep[n]), chans)
    return out, stamps[~np.isin(stamps, bad)]  # the columns keep no sample at a bad stamp


def _sorted_stamps(tensions: Sequence[Any], depth: Any) -> np.ndarray:
    """The input columns' stamps [ns] in one sorted array, repeats kept (grid_ticks and the
    silences read only gaps > quiet): a stable sort merges the columns' sorted runs (numpy's
    hashed ``np.unique`` took 1.1 s of 3.8 s CPU on a 3e6-message replay)."""
    columns = [t for t, _ in (*tensions, depth) if len(t)]
    if not columns:
        return np.zeros(0, np.int64)
    return np.sort(np.concatenate(columns), kind='stable')


# --- the log, its parameters and the runs
# ---------------------------------------------------------


def input_topics(config: MonitorConfig) -> tuple[dict[str, str], str]:
    """(line name -> resolved tension topic, resolved depth topic)."""
    return (
        {line.name: resolve_topic(line.topics[0]) for line in config.lines},
        resolve_topic(config.depth_topic),
    )


def expand(paths: Sequence[str]) -> list[Path]:
    """The MCAP files of the given files and directories (ReplayError when there are none)."""
    try:
        out = expand_paths(paths)
    except FileNotFoundError as err:
        raise ReplayError(str(err)) from None
    if not out:
        raise ReplayError(f'no *.mcap file in {", ".join(paths)}')
    return out


def load_config(path: str) -> MonitorConfig:
    """The monitor configuration of a params file (ReplayError with the one-line reason)."""
    try:
        return config_from_params(load_params_file(path))
    except ConfigError as err:
        raise ReplayError(f'{path}: {err}') from err


def log_parameters(paths: Sequence[Path]) -> Optional[tuple[str, dict[str, Any]]]:
    """``(config hash, flat parameters)`` of the first ``catenary_monitor`` metadata record of
    the files: the parameters the node started with (it writes one at start and one on every
    parameter change, which replay follows from the events channel), or None.

    Read in bounded time and memory whatever the files hold
    (:func:`catenary_monitor.io.mcap_summary.read_metadata`: the summary's index of a finished
    file, else the heads of an unfinished file's top-level records; no chunk decompressed). A
    record whose parameters are not a JSON object is passed over.
    """
    for path in paths:
        for record in read_metadata(path, NODE_NAME):
            try:
                parameters = json.loads(record['parameters'])
            except (KeyError, ValueError, RecursionError):
                continue
            if isinstance(parameters, dict):
                return record.get('config_hash', ''), parameters
    return None


def read_inputs(
    paths: Sequence[Path], config: MonitorConfig
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], tuple[np.ndarray, np.ndarray], ReadReport]:
    """The whole input columns of a log in SI, not replayed (``whatif --log``): tension
    columns per line, the depth column (each as its type says: :func:`_inputs`) and the read
    report."""
    topics, depth_topic = input_topics(config)
    every = [resolve_topic(t) for line in config.lines for t in line.topics]  # each channel
    typed = typed_inputs(config)
    if typed:
        report = ReadReport()
        try:
            window = next(
                iter_windows(paths, [depth_topic, *every], [], None, report, typed=typed)
            )
        except TopicTypeError as err:
            raise ReplayError(f'unexpected message type: {err} (check the params file topics)')
        except EmptyLogError as err:
            raise ReplayError(f'empty log: {err}; nothing to replay', EXIT_EMPTY) from err
        except McapReadError as err:
            raise ReplayError(str(err)) from err
        inputs = _inputs(config, window)
        out = dict(zip(topics, inputs.tensions))
        for line in config.lines:
            if line.channel_topics:
                out[line.name] = fused_tensions(config, line, window.columns)
        return out, inputs.depth, report
    try:
        columns, report = read_float64_topics(paths, [depth_topic, *every])
    except TopicTypeError as err:
        raise ReplayError(f'unexpected message type: {err} (check the params file topics)')
    except EmptyLogError as err:
        raise ReplayError(f'empty log: {err}; nothing to replay', EXIT_EMPTY) from err
    except McapReadError as err:
        raise ReplayError(str(err)) from err
    tensions = {
        name: (t, np.asarray(readings.tension_si(config.line(name), {'value': v}), np.float64))
        for name, (t, v) in ((n, columns[topic]) for n, topic in topics.items())
    }
    for line in config.lines:
        if line.channel_topics:
            tensions[line.name] = fused_tensions(config, line, columns)
    dt, dv = columns[depth_topic]
    return tensions, (dt, np.asarray(readings.depth_si(config, {'value': dv}))), report


class Sink(Protocol):
    """What :func:`drive` hands each window's results to."""

    def __call__(self, result: ReplayResult, window: Window) -> None: ...

    def abandon(self) -> None:
        """Forget what was taken (the replay is redone as one window, or failed)."""


def drive(
    paths: Sequence[Path],
    config: MonitorConfig,
    make_sink: Callable[[Optional[int]], Sink],
    *,
    ticks: str = 'auto',
    follow_log: bool = True,
    snapshots: bool | str = False,
    window_messages: Optional[int] = WINDOW_MESSAGES,
    jobs: int = 1,
    progress: Optional[Callable[[StreamState], None]] = None,
    on_restart: Optional[Callable[[str], None]] = None,
    line_processes: int = 1,
    value_keys: Optional[Collection[str]] = None,
) -> tuple[Sink, StreamState, ReadReport]:
    """Replay ``paths`` into ``make_sink(window_messages)``: streamed, or, for a log that cannot
    be streamed (:class:`Restart`), again as one window into a new sink (``on_restart`` gets
    the reason). Returns the sink, the stream's figures and the read report; failures a user
    can act on are :class:`ReplayError`. ``line_processes``, ``value_keys``: :func:`stream`'s
    (a caller that runs replays in worker processes of its own keeps ``line_processes`` 1)."""
    window = window_messages
    while True:
        report = ReadReport()
        sink = make_sink(window)
        try:
            state = stream(
                paths,
                config,
                sink,
                ticks=ticks,
                follow_log=follow_log,
                snapshots=snapshots,
                window_messages=window,
                jobs=jobs,
                report=report,
                progress=progress,
                line_processes=line_processes,
                value_keys=value_keys,
            )
            return sink, state, report
        except Restart as err:
            sink.abandon()
            if window is None:
                raise ReplayError(f'cannot replay: {err}') from err
            if on_restart is not None:
                on_restart(str(err))
            window = None
        except NoEventsChannel as err:
            sink.abandon()
            raise ReplayError(
                '--ticks log: the log has no catenary_monitor events channel '
                f'({EVENTS_TOPIC}); it was not recorded by the node'
            ) from err
        except TopicTypeError as err:
            sink.abandon()
            raise ReplayError(f'unexpected message type: {err} (check the params file topics)')
        except EmptyLogError as err:
            sink.abandon()
            raise ReplayError(f'empty log: {err}; nothing to replay', EXIT_EMPTY) from err
        except McapReadError as err:
            sink.abandon()
            raise ReplayError(str(err)) from err


class _Collect:
    """A sink that keeps every window's results (for :func:`replay_log`): at most
    ``max_ticks`` ticks (None: no bound; more is a :class:`ReplayError`)."""

    def __init__(self, max_ticks: Optional[int] = None) -> None:
        self.results: list[ReplayResult] = []
        self.windows: list[Window] = []
        self.max_ticks = max_ticks
        self.ticks = 0

    def __call__(self, result: ReplayResult, window: Window) -> None:
        self.ticks += len(result.tick_ns)
        if self.max_ticks is not None and self.ticks > self.max_ticks:
            raise ReplayError(
                f'the log has more than {self.max_ticks} periodic steps (each a diagnostic '
                'snapshot held in memory): too long to hold at once; replay a shorter piece '
                'of it, or summarize it with catenary-monitor replay'
            )
        self.results.append(result)
        self.windows.append(window)

    def abandon(self) -> None:
        self.results, self.windows = [], []


class LogReplay(NamedTuple):
    """:func:`replay_log`'s answer: every step, the input columns it read, the read report."""

    result: ReplayResult
    tensions: dict[str, tuple[np.ndarray, np.ndarray]]  # line name -> (stamp ns, tension N)
    depth: tuple[np.ndarray, np.ndarray]  # (stamp ns, depth m)
    report: ReadReport


def replay_log(
    paths: Sequence[Path],
    config: MonitorConfig,
    *,
    ticks: str = 'auto',
    follow_log: bool = True,
    snapshots: bool = False,
    window_messages: Optional[int] = WINDOW_MESSAGES,
    max_ticks: Optional[int] = None,
    notes: Optional[list[str]] = None,
) -> LogReplay:
    """Every step of a log as one :class:`ReplayResult` (the windows' results joined), with the
    input columns and the read report: for the console's log view and the tests. Memory grows
    with the log; the command writes its outputs window by window (:func:`drive`).
    ``max_ticks``: a log of more ticks is refused (:class:`ReplayError`) before they are
    held; ``notes`` gets the lines on bad stamps and silences (:func:`stamp_lines`)."""
    sink, state, report = drive(
        paths,
        config,
        lambda _: _Collect(max_ticks),
        ticks=ticks,
        follow_log=follow_log,
        snapshots=snapshots,
        window_messages=window_messages,
    )
    assert isinstance(sink, _Collect)
    names = [line.name for line in config.lines]
    tensions = {
        name: _joined_column([w.tensions[k] for w in sink.windows]) for k, name in enumerate(names)
    }
    depth = _joined_column([w.depth for w in sink.windows])
    if notes is not None:
        notes += stamp_lines(stamp_figures(state))
    return LogReplay(_joined(sink.results, state), tensions, depth, report)


def _joined(parts: list[ReplayResult], state: StreamState) -> ReplayResult:
    """Consecutive windows' results as one (each list is in time order window after window)."""
    if not parts:
        start = state.start_ns or 0
        return ReplayResult([], [], [], start, start, [], started_ns=start)
    return ReplayResult(
        [concat_lines([p.lines[k] for p in parts]) for k in range(len(parts[0].lines))],
        [tr for p in parts for tr in p.tide],
        [s for p in parts for s in p.snapshots],
        min(p.start_ns for p in parts),
        max(p.end_ns for p in parts),
        [c for p in parts for c in p.others],
        np.concatenate([p.tick_ns for p in parts]),
        parts[0].ticks_from_log,
        parts[0].started_ns,
        [e for p in parts for e in p.events],
        alarm_events=[e for p in parts for e in p.alarm_events],
    )


def _joined_column(parts: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    if not parts:
        return np.zeros(0, np.int64), np.zeros(0)
    return np.concatenate([t for t, _ in parts]), np.concatenate([v for _, v in parts])
