"""Replay in bounded memory: the log read, recomputed and written window by window.

:func:`stream` walks the log (every file of a rotated set or directory, in time order, merged
across topics) in windows of log time (:func:`catenary_monitor.io.mcap_read.iter_windows`),
hands each window to :func:`catenary_monitor.core.batch.run_log` with the core that the
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
the log; the summary says ``streamed: false``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Optional, Sequence

import numpy as np

from catenary_monitor.core import kernels
from catenary_monitor.core.batch import ReplayResult, Window, run_log, slice_window
from catenary_monitor.core.config import MonitorConfig, resolve_topic
from catenary_monitor.core.monitor import (
    EVENTS_TOPIC,
    MonitorCore,
    Reconfigure,
    Start,
    Tick,
    parse_event_record,
)
from catenary_monitor.io import mcap_read
from catenary_monitor.io.cdr import string_message, string_text
from catenary_monitor.io.mcap_read import LogWindow, ReadReport, UnorderedLogError, iter_windows

__all__ = ['NoEventsChannel', 'Restart', 'StreamState', 'WINDOW_MESSAGES', 'stream']

#: Input messages per window by default (about 300 B each in flight for a summary, 750 B with
#: the diagnostics of ``--out``): the bound of replay's memory beyond the interpreter's.
WINDOW_MESSAGES = 1 << 17

#: With snapshots (``--out``), a window is recomputed in parts of at most this many ticks:
#: a part's snapshots (in columns) and their payloads take about 30 kB per tick until written.
TICKS_PER_PART = 512

_TICK_PAYLOAD = string_message('{"kind": "tick"}')


class Restart(Exception):
    """The log cannot be streamed (see the module docstring): replay it as one window."""


class NoEventsChannel(LookupError):
    """``ticks='log'`` and the log has no events channel (it was not recorded by the node)."""


@dataclass
class StreamState:
    """What the stream knows after its first window, and the figures of the run."""

    start_ns: Optional[int] = None
    start_from_record: bool = False
    ticks_from_log: Optional[bool] = None
    windows: int = 0
    messages: int = 0
    bytes_done: int = 0
    bytes_total: int = 0


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


def _inputs(config: MonitorConfig, window: LogWindow) -> tuple[list[Any], Any]:
    """The window's tension columns (config order) and depth column."""
    lines = [window.columns[resolve_topic(line.tension_topic)] for line in config.lines]
    return lines, window.columns[resolve_topic(config.depth_topic)]


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
) -> StreamState:
    """Replay ``paths`` window by window; ``sink(result, window)`` gets each window's
    :class:`ReplayResult` (its ticks, events, start) and its input :class:`Window`.

    ``ticks``/``follow_log`` as :func:`catenary_monitor.cli.replay.run_replay`;
    ``window_messages`` None replays the log as one window. Raises :class:`Restart` (see the
    module docstring), and what :func:`iter_windows` raises (EmptyLogError at the end).
    The solve kernel leaves the cores of the decoding to it: the read-ahead thread's, or the
    ``jobs`` worker processes' (on two cores, two kernel threads beside the read-ahead made the
    1e7 summary 10-25 % slower than one; docs/benchmarks.md).
    """
    busy = jobs if jobs > 1 else int(mcap_read.READ_AHEAD > 0)
    with kernels.cores_left_to(busy):
        return _stream(
            paths, config, sink, ticks, follow_log, snapshots, window_messages, jobs, report,
            progress,
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
) -> StreamState:
    """:func:`stream` itself."""
    state = StreamState()
    state.bytes_total = sum(p.stat().st_size for p in paths)
    lines_topics = [resolve_topic(line.tension_topic) for line in config.lines]
    topics = [resolve_topic(config.depth_topic), *lines_topics]
    raw = [EVENTS_TOPIC] if ticks != 'grid' else []
    core: Optional[MonitorCore] = None
    grid_k = 0  # next grid tick index
    period = 1e9 / config.alarm.diagnostic_rate
    try:
        for window in iter_windows(paths, topics, raw, window_messages, report, jobs):
            seen, tick_ns, others = _events(window) if raw else (False, np.zeros(0, np.int64), [])
            if not follow_log:
                others = [e for e in others if not isinstance(e, Reconfigure)]
            tensions, depth = _inputs(config, window)
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
                elif not window.final:
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
            if not state.ticks_from_log:
                tick_ns, grid_k = _grid(state, window, tensions, depth, grid_k, period)
            whole = Window(tensions, depth, tick_ns)
            for part, part_events in _parts(whole, others, TICKS_PER_PART if snapshots else 0):
                result, core = run_log(core, part, part_events, snapshots)
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
                )
                sink(replay, part)
            state.windows += 1
            state.messages += window.messages
            state.bytes_done = window.bytes_done
            if progress is not None:
                progress(state)
    except UnorderedLogError as err:
        raise Restart(str(err)) from err
    return state


def _parts(
    window: Window, events: list[Any], ticks: int
) -> Iterator[tuple[Window, list[Any]]]:
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


def _grid(
    state: StreamState,
    window: LogWindow,
    tensions: list[Any],
    depth: Any,
    k0: int,
    period: float,
) -> tuple[np.ndarray, int]:
    """The grid ticks of a window, ``start + k * period`` (as :func:`tick_grid`) below the
    window's end, or up to the last input message in the final window; and the next k."""
    start = state.start_ns or 0
    if window.final:
        lasts = [int(c[0][-1]) for c in (*tensions, depth) if len(c[0])]
        if not lasts:
            if state.windows:
                raise Restart('the last window has no input message')
            return np.zeros(0, np.int64), k0
        end = max(lasts)
        if end < start:
            return np.zeros(0, np.int64), k0
        n = int((end - start) // period) + 1
    else:
        assert window.hi is not None
        end = window.hi - 1
        n = max(0, int((window.hi - start) // period) + 1)
    k = np.arange(k0, max(k0, n), dtype=np.int64)
    ticks = start + np.rint(k * period).astype(np.int64)
    ticks = ticks[ticks <= end]
    return ticks, k0 + len(ticks)
