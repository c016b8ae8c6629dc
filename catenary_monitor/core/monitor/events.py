"""The monitor's events: what :meth:`MonitorCore.step
<catenary_monitor.core.monitor.monitor_core.MonitorCore.step>` takes, and their records.

:class:`Tension` (a hook tension sample of one line), :class:`Depth` (a tide depth sample),
:class:`Tick` (the periodic step, at ``diagnostic_rate``), :class:`LoggerHealth` (the MCAP
logger's state changed), :class:`Reconfigure` (accepted parameter change), :class:`Acknowledge`
(an operator acknowledged a line's alarm, or all: :mod:`catenary_monitor.core.alarms.acknowledge`),
:class:`Shelve` (an operator shelved or unshelved an alarm:
:mod:`catenary_monitor.core.alarms.shelving`), :class:`Refusal` (a request refused before
the alarm rules), :class:`ClockHealth`, :class:`Intake`,
:class:`Coalesced` and :class:`FatigueStore`, each with its time ``stamp_ns`` (ns on the
monitor's clock; events come in time order). The node records the events that are not input
messages on :data:`EVENTS_TOPIC` (:func:`event_record`), so that replay redoes every step
(:func:`parse_event_record`).
"""

from __future__ import annotations

import json
import math
from typing import Any, NamedTuple, Optional, Union

from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.config.parameters import (
    MonitorConfig,
    config_from_params,
    config_to_params,
)
from catenary_monitor.core.rules.level import Level

__all__ = [
    'NODE_NAME',
    'EVENTS_TOPIC',
    'Tension',
    'Depth',
    'Tick',
    'LoggerHealth',
    'Reconfigure',
    'Start',
    'Acknowledge',
    'Shelve',
    'REQUESTS',
    'REASON_LIMIT',
    'Refusal',
    'ClockHealth',
    'Intake',
    'Coalesced',
    'FatigueStore',
    'FATIGUE_STORE_STATES',
    'Event',
    'event_record',
    'parse_event_record',
]

#: Characters kept of a refusal's reason.
REASON_LIMIT = 240
#: Node name: the ``/diagnostics`` status names start with it; params files use it as top key.
NODE_NAME = 'catenary_monitor'
#: MCAP-only channel where the node records the events that are not input messages (ticks,
#: logger changes, reconfigurations), so that replay redoes every step exactly.
EVENTS_TOPIC = f'/{NODE_NAME}/events'


class Tension(NamedTuple):
    """A hook tension sample [N] of line number ``line`` (config order), received at
    ``stamp_ns``; ``sample_ns`` the sensor's header stamp (None: a message without one, taken
    at its arrival)."""

    stamp_ns: int
    line: int
    value: float
    sample_ns: Optional[int] = None
    channel: int = 0  # a line of several channels (NAME.tension_topics): which one


class Depth(NamedTuple):
    """A tide depth sample [m] at the hooks, received at ``stamp_ns``; ``sample_ns`` as for
    :class:`Tension`."""

    stamp_ns: int
    value: float
    sample_ns: Optional[int] = None


class Tick(NamedTuple):
    """The periodic step at ``stamp_ns`` (staleness and hold-time clears are decided here)."""

    stamp_ns: int


class LoggerHealth(NamedTuple):
    """The MCAP logger's state at ``stamp_ns``: ``error`` (None while it writes), its file and
    a ``warning`` (low disk space; None: none)."""

    stamp_ns: int
    error: Optional[str]
    path: Optional[str]
    warning: Optional[str] = None


class Start(NamedTuple):
    """Not an event but a record: the monitor started (blind) at ``stamp_ns``."""

    stamp_ns: int


class Reconfigure(NamedTuple):
    """Accepted parameter change at ``stamp_ns``: the new configuration (same lines)."""

    stamp_ns: int
    config: MonitorConfig


class Acknowledge(NamedTuple):
    """An operator acknowledged line ``line``'s alarm (None: every line) from ``origin`` (as
    the message claims), published by ``publisher`` (the middleware's identity of the sender:
    node and GID; empty when unknown)."""

    stamp_ns: int
    line: Optional[str]
    origin: str
    publisher: str = ''


class Shelve(NamedTuple):
    """An operator shelved ``alarm`` (a line, or ``sensors``) or one ``condition`` of it
    (:data:`~catenary_monitor.core.alarms.acknowledge.WHOLE`: the whole alarm) for
    ``seconds`` (0: unshelve it), from ``origin`` (as claimed), published by ``publisher``
    (the middleware's identity of the sender; '' from the console's page)."""

    stamp_ns: int
    alarm: str
    condition: str
    seconds: float
    origin: str
    publisher: str = ''


#: :attr:`Refusal.request` of each request topic's requests.
REQUESTS = ('acknowledge', 'shelve')


class Refusal(NamedTuple):
    """A request refused before the alarm rules could take it: unreadable (a duration that is
    not a finite number >= 0, an empty acknowledgement), from a publisher that may not send
    it (``acknowledge_from_ros`` false), or over its publisher's rate limit
    (:mod:`catenary_monitor.core.alarms.requests`). ``request`` (:data:`REQUESTS`), the
    ``alarm`` it named ('' none), the one-line ``reason``, ``origin`` and ``publisher`` as for
    :class:`Shelve`, and ``requests``: how many requests the record stands for (those over a rate
    limit are summed, one record per publisher and period)."""

    stamp_ns: int
    request: str
    alarm: str
    reason: str
    origin: str = ''
    publisher: str = ''
    requests: int = 1


class ClockHealth(NamedTuple):
    """The ROS clock (``use_sim_time``) at ``stamp_ns``: ``stopped_for`` [s] of wall time
    without advancing (None: it advances)."""

    stamp_ns: int
    stopped_for: Optional[float]


class Intake(NamedTuple):
    """Samples since the previous Intake event: per line, then the depth, ``received``
    (handled: stepped), ``dropped`` (lost before the node took them) and ``coalesced`` (taken
    and logged, not stepped: a newer sample of the same input was handled instead; empty:
    none, as in logs from before coalescing); ``busy`` [s] of wall time spent in callbacks
    over ``period`` [s] of wall time."""

    stamp_ns: int
    received: tuple[int, ...]
    dropped: tuple[int, ...]
    busy: float
    period: float
    coalesced: tuple[int, ...] = ()


class Coalesced(NamedTuple):
    """The node took ``samples`` samples of line ``line`` (a name; None: the depth) faster than
    it could handle them: they are logged, stamped after ``stamp_ns`` and at most ``last_ns``,
    and not stepped (the newer sample that follows them is). Recorded before them, so replay
    leaves out exactly the samples the node left out."""

    stamp_ns: int
    line: Optional[str]
    last_ns: int
    samples: int


class FatigueStore(NamedTuple):
    """The fatigue store at ``stamp_ns`` (core/rules/fatigue.py; the node keeps it beside
    its log): its ``state`` (:data:`FATIGUE_STORE_STATES`), one-line ``message``, and, when it
    was read at start, each line's stored state (``(name, record or None)``: None, from
    ``NAME.fatigue_damage_initial``); ``lines`` None only changes the status (a write that
    failed or worked again)."""

    stamp_ns: int
    state: str
    message: str
    lines: Optional[tuple[tuple[str, Any], ...]] = None


#: The fatigue store's states and their levels: read at start (``loaded``), none yet in a new
#: log folder (``new``), none where logs are (``missing``), unreadable (``damaged``), a save that
#: failed (``write_failed``).
FATIGUE_STORE_STATES = {
    'loaded': Level.OK,
    'new': Level.OK,
    'saved': Level.OK,
    'missing': Level.WARN,
    'damaged': Level.WARN,
    'write_failed': Level.WARN,
}


Event = Union[
    Tension,
    Depth,
    Tick,
    LoggerHealth,
    Reconfigure,
    Acknowledge,
    Shelve,
    Refusal,
    ClockHealth,
    Intake,
    FatigueStore,
    Coalesced,
]


def event_record(event: Union[Event, Start]) -> Optional[dict[str, Any]]:
    """What the node records on :data:`EVENTS_TOPIC` for an event that is not an input message
    (None for tension and depth: their input messages are the record)."""
    if isinstance(event, Start):
        return {'kind': 'start'}
    if isinstance(event, Tick):
        return {'kind': 'tick'}
    if isinstance(event, LoggerHealth):
        record = {'kind': 'logger', 'error': event.error, 'path': event.path}
        if event.warning is not None:
            record['warning'] = event.warning
        return record
    if isinstance(event, Reconfigure):
        return {'kind': 'configure', 'parameters': config_to_params(event.config)}
    if isinstance(event, Acknowledge):
        line = alarm_ack.ALL_LINES if event.line is None else event.line
        return {
            'kind': 'acknowledge',
            'line': line,
            'origin': alarm_ack.bounded_text(event.origin),
            'publisher': alarm_ack.bounded_text(event.publisher),
        }
    if isinstance(event, Shelve):
        return {
            'kind': 'shelve',
            'alarm': event.alarm,
            'condition': event.condition,
            'seconds': event.seconds,
            'origin': alarm_ack.bounded_text(event.origin),
            'publisher': alarm_ack.bounded_text(event.publisher),
        }
    if isinstance(event, Refusal):
        return {
            'kind': 'refused',
            'request': event.request,
            'alarm': alarm_ack.bounded_text(event.alarm),
            'reason': alarm_ack.bounded_text(event.reason, REASON_LIMIT),
            'origin': alarm_ack.bounded_text(event.origin),
            'publisher': alarm_ack.bounded_text(event.publisher),
            'requests': int(event.requests),
        }
    if isinstance(event, ClockHealth):
        return {'kind': 'clock', 'stopped_for': event.stopped_for}
    if isinstance(event, FatigueStore):
        lines = None if event.lines is None else dict(event.lines)
        return {'kind': 'fatigue', 'state': event.state, 'message': event.message, 'lines': lines}
    if isinstance(event, Intake):
        return {
            'kind': 'intake',
            'received': list(event.received),
            'dropped': list(event.dropped),
            'coalesced': list(event.coalesced),
            'busy': event.busy,
            'period': event.period,
        }
    if isinstance(event, Coalesced):
        where = {'input': 'depth'} if event.line is None else {'line': event.line}
        return {'kind': 'coalesced', **where, 'last_ns': event.last_ns, 'samples': event.samples}
    return None


def parse_event_record(stamp_ns: int, text: str) -> Optional[Union[Event, Start]]:
    """The event (or :class:`Start`) of one :data:`EVENTS_TOPIC` record (None for an unknown
    or damaged one)."""
    try:
        record = json.loads(text)
        kind = record['kind']
        if kind == 'start':
            return Start(stamp_ns)
        if kind == 'tick':
            return Tick(stamp_ns)
        if kind == 'logger':
            return LoggerHealth(
                stamp_ns, record.get('error'), record.get('path'), record.get('warning')
            )
        if kind == 'configure':
            return Reconfigure(stamp_ns, config_from_params(record['parameters']))
        if kind == 'clock':
            stopped = record.get('stopped_for')
            return ClockHealth(stamp_ns, None if stopped is None else float(stopped))
        if kind == 'intake':
            return Intake(
                stamp_ns,
                tuple(int(x) for x in record['received']),
                tuple(int(x) for x in record['dropped']),
                float(record['busy']),
                float(record['period']),
                tuple(int(x) for x in record.get('coalesced', ())),
            )
        if kind == 'coalesced':
            line = None if record.get('input') == 'depth' else str(record['line'])
            return Coalesced(stamp_ns, line, int(record['last_ns']), int(record['samples']))
        if kind == 'shelve':
            seconds = float(record['seconds'])
            if not math.isfinite(seconds) or seconds < 0.0:
                return None
            return Shelve(
                stamp_ns,
                alarm_ack.bounded_text(str(record['alarm'])),
                alarm_ack.bounded_text(str(record.get('condition') or alarm_ack.WHOLE)),
                seconds,
                alarm_ack.bounded_text(str(record.get('origin', ''))),
                alarm_ack.bounded_text(str(record.get('publisher', ''))),
            )
        if kind == 'refused':
            request, count = str(record['request']), int(record.get('requests', 1))
            if request not in REQUESTS or count < 1:
                return None
            return Refusal(
                stamp_ns,
                request,
                alarm_ack.bounded_text(str(record.get('alarm', ''))),
                alarm_ack.bounded_text(str(record['reason']), REASON_LIMIT),
                alarm_ack.bounded_text(str(record.get('origin', ''))),
                alarm_ack.bounded_text(str(record.get('publisher', ''))),
                count,
            )
        if kind == 'fatigue':
            lines = record.get('lines')
            return FatigueStore(
                stamp_ns,
                str(record['state']),
                str(record['message']),
                None if lines is None else tuple((str(k), v) for k, v in dict(lines).items()),
            )
        if kind == 'acknowledge':
            line = str(record['line'])
            return Acknowledge(
                stamp_ns,
                None if line == alarm_ack.ALL_LINES else alarm_ack.bounded_text(line),
                alarm_ack.bounded_text(str(record.get('origin', ''))),
                alarm_ack.bounded_text(str(record.get('publisher', ''))),
            )
    except (ValueError, KeyError, TypeError, RecursionError):  # a damaged or crafted record
        return None
    return None
