"""What the console page shows, built from what the monitor published (no rclpy, no HTTP).

The console decides nothing: levels, messages, alarm states and acknowledgements come from the
monitor's ``/diagnostics`` (:mod:`catenary_monitor.core.alarms.acknowledge` made them) and the
values from its per-line outputs. This module turns those into one JSON-ready *frame* for the page
(:func:`build_frame`), the alarm list (:func:`alarm_rows`), the alarm history (by comparing
consecutive arrays, :class:`History`) and trend series bucketed for a chart (:class:`Trend`,
:func:`bucket`). Live and replay build frames with the same functions.

Times are seconds (epoch, the monitor's clock); forces N, lengths m: the page converts to kN.
"""

from __future__ import annotations

import math
from array import array
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import ALARM_CONDITIONS, MonitorConfig
from catenary_monitor.core.alarms.acknowledge import SENSORS
from catenary_monitor.core.alarms.journal import COMPONENTS
from catenary_monitor.core.monitor.events import NODE_NAME
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS

__all__ = [
    'AckError',
    'LEVEL_NAMES',
    'Status',
    'statuses_by_name',
    'console_config',
    'alarm_rows',
    'alarm_names',
    'consequence_lines',
    'component_rows',
    'COMPONENT_ALARMS',
    'shelved_rows',
    'flood_view',
    'History',
    'Trend',
    'bucket',
    'tide_trend',
    'build_frame',
    'silence_limit',
]

#: diagnostic_msgs levels by number.
LEVEL_NAMES = ('OK', 'WARN', 'ERROR', 'STALE')
_PREFIX = f'{NODE_NAME}: '
_INDEX = {name: i for i, name in enumerate(OUTPUT_FIELDS)}
#: History: at most this many entries are kept (the newest).
HISTORY_LIMIT = 2000


class AckError(Exception):
    """An acknowledgement that could not be sent: ``str()`` is one line; ``status`` HTTP."""

    def __init__(self, message: str, status: int = 400) -> None:
        super().__init__(message)
        self.status = status


@dataclass(frozen=True)
class Status:
    """One component of a ``/diagnostics`` array: level name, message, values (strings)."""

    level: str
    message: str
    values: Mapping[str, str]


def statuses_by_name(items: Iterable[tuple[str, int, str, Iterable[tuple[str, str]]]]) -> dict:
    """``{component: Status}`` from ``(name, level, message, (key, value)...)`` of one array;
    the component is the name without the ``catenary_monitor: `` prefix; others are left out."""
    out: dict[str, Status] = {}
    for name, level, message, values in items:
        if name.startswith(_PREFIX):
            lv = LEVEL_NAMES[level] if 0 <= level < len(LEVEL_NAMES) else 'STALE'
            out[name[len(_PREFIX) :]] = Status(lv, message, dict(values))
    return out


def _num(text: Optional[str]) -> Optional[float]:
    """A /diagnostics number as a float (None for a missing value or NaN: JSON has no NaN)."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _forecast_state(text: Optional[str]) -> str:
    """What a time to uplift says: ``unknown`` (NaN: the trend not known yet, or no solve),
    ``not coming`` (inf: the tide not rising), ``lifted`` (0) or ``forecast``."""
    value = _num(text)
    if value is None:
        return 'not coming' if text is not None and text.strip() == 'inf' else 'unknown'
    return 'lifted' if value <= 0.0 else 'forecast'


def _finite(value: float) -> Optional[float]:
    return value if math.isfinite(value) else None


def silence_limit(diagnostic_rate: float) -> float:
    """Seconds without ``/diagnostics`` after which the monitor counts as silent: twice its
    period plus one second (jitter of a loaded machine is not a lost monitor)."""
    return 2.0 / diagnostic_rate + 1.0


def console_config(
    config: Optional[MonitorConfig], names: Sequence[str], mode: str, **extra: Any
) -> dict[str, Any]:
    """The page's static facts: lines (heading, hook on the dock, MBL, anchor distance, allowed
    uplift), the dock's size, the warning thresholds, the monitor's period and the silence
    limit. Without a configuration
    (a console started without ``--params-file``) the lines are those seen on /diagnostics."""
    rate = config.alarm.diagnostic_rate if config else 1.0
    lines = []
    if config is not None:
        for line, heading in zip(config.lines, config.headings()):
            lines.append(
                {
                    'name': line.name,
                    'heading': heading,
                    'mbl': line.mbl,
                    'anchor_distance': line.anchor_distance,
                    'allowed_uplift': line.allowed_uplift,
                    'hook_x': line.hook_x,
                    'hook_y': line.hook_y,
                    'channels': list(line.tension_topics),  # a load cell's channels, or []
                }
            )
    else:
        n = len(names)
        for k, name in enumerate(names):
            lines.append(
                {
                    'name': name,
                    'heading': (k + 0.5) * 360.0 / max(n, 1),
                    'mbl': None,
                    'anchor_distance': None,
                    'allowed_uplift': None,
                    'hook_x': None,
                    'hook_y': None,
                }
            )
    alarm = config.alarm if config else None
    dock = config.dock if config else None
    return {
        'mode': mode,
        'lines': lines,
        'dock_length': dock.length if dock else None,
        'dock_beam': dock.beam if dock else None,
        'safety_factor_warn': alarm.safety_factor_warn if alarm else 2.0,
        'anchor_margin_warn': alarm.anchor_margin_warn if alarm else 5.0,
        'tide_margin_warn': alarm.tide_margin_warn if alarm else 1.0,
        'uplift_time_warn': alarm.uplift_time_warn if alarm else 1800.0,
        'drag_margin_warn': alarm.drag_margin_warn if alarm else 0.0,
        'fatigue_damage_warn': alarm.fatigue_damage_warn if alarm else 0.5,
        'tension_timeout': alarm.tension_timeout if alarm else 5.0,
        'alarm_conditions': list(ALARM_CONDITIONS),  # what an operator may name to shelve
        'period_s': 1.0 / rate,
        'silence_limit_s': silence_limit(rate),
        **extra,
    }


#: The monitor's own statuses shown under the tide: the sensors' common-cause alarm, the logger
#: and the guards (the node publishes the last three only when they have something to say:
#: allowed runtime changes, a sim clock, intake counts).
MONITOR_STATUSES = (SENSORS, 'logger', 'parameters', 'clock', 'intake')


def monitor_rows(statuses: Mapping[str, Status]) -> list[dict[str, str]]:
    """The monitor's own statuses present in the array (sensors, logger, parameters, clock,
    intake): name, level and message, in that order."""
    return [
        {'name': name, 'level': statuses[name].level, 'message': statuses[name].message}
        for name in MONITOR_STATUSES
        if name in statuses
    ]


def alarm_names(lines: Sequence[str]) -> list[str]:
    """The alarms on the page: each line's, then the sensors' common-cause alarm."""
    return [*lines, SENSORS]


#: The component statuses listed as alarms while not OK (the ones the alarm journal records and
#: ``catenary-monitor alarms`` counts: tide, intake, logger, fatigue store, dock, clock,
#: parameters), each acknowledged as a line's alarm (``alarm_state``); a monitor that publishes
#: no state for them lists them ``active`` until they clear.
COMPONENT_ALARMS = COMPONENTS
#: The ``alarm_state`` of a component row that waits for nothing (an older monitor's).
_ACTIVE = 'active'
#: Row order: the state's rank (an active component ranks with the unacknowledged alarms, after
#: them at the same level), then the level's (ERROR before STALE before WARN).
_RANK_STATE = {'unacknowledged': 0, 'active': 0, 'returned-unacknowledged': 1, 'acknowledged': 2}
_RANK_LEVEL = {'ERROR': 0, 'STALE': 1, 'WARN': 2, 'OK': 3}
_RANK_KIND = {'line': 0, 'sensors': 0, 'component': 1}
#: A component's level by severity (the journal's order: OK < WARN < STALE < ERROR).
_SEVERITY = {'OK': 0, 'WARN': 1, 'STALE': 2, 'ERROR': 3}


def alarm_rows(
    statuses: Mapping[str, Status],
    lines: Sequence[str],
    components: bool = False,
    history: Sequence[dict] = (),
) -> list[dict[str, Any]]:
    """The alarm list: one row per alarm (each line's, the sensors') that is neither
    ``normal`` nor ``suppressed`` (by design: the sensors alarm stands for it) nor ``shelved``
    (listed apart: :func:`shelved_rows`), most urgent first (unacknowledged, then
    returned-unacknowledged, then acknowledged; ERROR before STALE before WARN; newest first).
    Each row says its ``kind`` (``line``, ``sensors``), whether the alarm chatters, whether one
    of its conditions is shelved, whether it is the first out of the flood the monitor
    reports (:func:`flood_view`) and the lines whose warnings are its suppressed consequences
    (:func:`consequence_lines`: a parted chain's). With ``components`` (the console's list) the
    component statuses not OK are listed too (:func:`component_rows`, their time raised from
    ``history``), each after the unacknowledged alarms of its level."""
    flood = flood_view(statuses)
    first = flood['first_out'] if flood['flood'] else None
    rows: list[dict[str, Any]] = []
    for name in alarm_names(lines):
        st = statuses.get(name)
        if st is None:
            continue
        state = st.values.get('alarm_state', 'normal')
        if state in ('normal', 'suppressed', 'shelved'):
            continue
        rows.append(
            {
                'line': name,
                'kind': 'sensors' if name == SENSORS else 'line',
                'state': state,
                'level': st.level,
                'raised': _num(st.values.get('alarm_raised')),
                'condition': st.values.get('alarm_condition', ''),
                'message': st.message,
                # the full text of every condition, and what to do (cause, consequence, action)
                'detail': st.values.get('detail', st.message),
                'response': st.values.get('response', ''),
                'acknowledged_by': st.values.get('acknowledged_by', ''),
                'acknowledged_at': _num(st.values.get('acknowledged_at')),
                'chattering': st.values.get('chattering') == 'true',
                'shelved_condition': (
                    st.values.get('shelved_condition', '')
                    if st.values.get('shelved') == 'true'
                    else ''
                ),
                'first_out': name == first,
                'consequences': consequence_lines(statuses, lines, name),
            }
        )
    if components:
        rows += component_rows(statuses, lines, history)
    rows.sort(
        key=lambda r: (
            _RANK_STATE.get(r['state'], 3),
            _RANK_LEVEL.get(r['level'], 3),
            _RANK_KIND.get(r['kind'], 1),
            -(r['raised'] or 0.0),
        )
    )
    return rows


def consequence_lines(
    statuses: Mapping[str, Status], lines: Sequence[str], name: str
) -> list[str]:
    """The lines whose warning is suppressed by design as a consequence of ``name``'s parted
    chain (their message begins with it: :func:`~catenary_monitor.core.alarms.latches.
    consequence_text`), listed under that alarm."""
    head = f"consequence of {name}'s parted chain"
    return [
        line
        for line in lines
        if (st := statuses.get(line)) is not None
        and st.values.get('alarm_state') == 'suppressed'
        and st.message.startswith(head)
    ]


def _component_listed(name: str, st: Optional[Status], lines: Sequence[str]) -> bool:
    """Whether a component status is an alarm row: not OK (or OK and
    ``returned-unacknowledged``: listed until acknowledged), not a STALE the ``sensors`` alarm
    announces (``alarm_state`` ``suppressed``), not named as a line (the line's)."""
    if st is None or name in lines:
        return False
    state = st.values.get('alarm_state', _ACTIVE)
    if st.level == 'OK':
        return state == 'returned-unacknowledged'
    return state not in ('normal', 'suppressed', 'shelved')


def component_rows(
    statuses: Mapping[str, Status], lines: Sequence[str], history: Sequence[dict] = ()
) -> list[dict[str, Any]]:
    """The component statuses (:data:`COMPONENT_ALARMS`) listed as alarms
    (:func:`_component_listed`), as rows of ``kind`` ``component`` in their alarm's state
    (``unacknowledged``, ``acknowledged``, ``returned-unacknowledged``: acknowledged as a
    line's; ``active`` from a monitor that publishes no state for them: the row clears when
    its condition does), a STALE the ``sensors`` alarm announces (``alarm_state``
    ``suppressed``) left out; ``raised``: ``alarm_raised``, else when the console's
    ``history`` saw it leave OK (:class:`History`; None when it has not). The flood's first
    out is marked as on a line's."""
    flood = flood_view(statuses)
    first = flood['first_out'] if flood['flood'] else None
    rows: list[dict[str, Any]] = []
    for name in COMPONENT_ALARMS:
        st = statuses.get(name)
        if st is None or not _component_listed(name, st, lines):
            continue
        raised = _num(st.values.get('alarm_raised'))
        rows.append(
            {
                'line': name,
                'kind': 'component',
                'state': st.values.get('alarm_state', _ACTIVE),
                'level': st.level,
                'raised': _component_raised(history, name) if raised is None else raised,
                'condition': st.values.get('conditions', '') or name,
                'message': st.message,
                'detail': st.values.get('detail', st.message),
                'response': st.values.get('response', ''),
                'acknowledged_by': st.values.get('acknowledged_by', ''),
                'acknowledged_at': _num(st.values.get('acknowledged_at')),
                'chattering': False,
                'shelved_condition': '',
                'first_out': name == first,
                'consequences': [],
            }
        )
    return rows


def _component_raised(history: Sequence[dict], name: str) -> Optional[float]:
    """When the component ``name`` last left OK in ``history`` [s] (None: not seen)."""
    for entry in reversed(history):
        if entry.get('line') == name:
            if entry.get('event') == 'raised':
                return entry.get('time')
            if entry.get('event') == 'cleared':
                return None
    return None


def shelved_rows(statuses: Mapping[str, Status], lines: Sequence[str]) -> list[dict[str, Any]]:
    """The shelved alarms (each line's, the sensors'), the soonest to return first: what is
    shelved (``all`` or one condition), until when, by whom, and the alarm's level, condition,
    state and message now (a shelved alarm is computed and shown, not annunciated)."""
    rows = []
    for name in alarm_names(lines):
        st = statuses.get(name)
        if st is None or st.values.get('shelved') != 'true':
            continue
        v = st.values
        rows.append(
            {
                'line': name,
                'condition': v.get('shelved_condition', ''),
                'until': _num(v.get('shelved_until')),
                'by': v.get('shelved_by', ''),
                'level': st.level,
                'alarm_condition': v.get('alarm_condition', ''),
                'state': v.get('alarm_state', ''),
                'message': st.message,
                'chattering': v.get('chattering') == 'true',
            }
        )
    rows.sort(key=lambda r: (r['until'] or 0.0, r['line']))
    return rows


def flood_view(statuses: Mapping[str, Status]) -> dict[str, Any]:
    """The monitor's alarm-system status (``catenary_monitor: alarms``): the flood (on or off,
    since, its first out), the alarms raised in its window, the message, the shelving rules
    (``shelve_max`` s, ``unshelvable`` conditions) and the answer to the newest shelving
    request; a monitor that publishes none gives no flood and no rules."""
    st = statuses.get('alarms')
    v = st.values if st is not None else {}
    unshelvable = v.get('unshelvable_conditions', '')
    return {
        'flood': v.get('flood') == 'true',
        'level': st.level if st is not None else 'OK',
        'message': st.message if st is not None else '',
        'count': int(v.get('alarms_in_window', '0') or 0),
        'since': _num(v.get('flood_since')),
        'first_out': v.get('first_out', ''),
        'first_out_at': _num(v.get('first_out_at')),
        'shelve_max': _num(v.get('shelve_max')),
        'unshelvable': [c for c in unshelvable.split(',') if c],
        'shelve_answer': v.get('shelve_answer', ''),
        'shelve_requests': int(v.get('shelve_requests', '0') or 0),
    }


@dataclass
class History:
    """The alarm history (audit trail) seen in consecutive ``/diagnostics`` arrays: raised,
    raised again (severity rose), acknowledged (by whom), returned to normal, cleared, shelved
    (by whom, until when) and unshelved; a component status listed as an alarm
    (:func:`component_rows`): raised, raised again, acknowledged (by whom), cleared."""

    entries: list[dict[str, Any]] = field(default_factory=list)
    _last: dict[str, tuple[str, str, float]] = field(default_factory=dict)
    _component: dict[str, str] = field(default_factory=dict)  # component -> level listed
    _component_ack: dict[str, str] = field(default_factory=dict)  # component -> acknowledged_at
    _shelf: dict[str, float] = field(default_factory=dict)  # alarm -> shelved until [s]

    def feed(self, stamp: float, statuses: Mapping[str, Status], lines: Sequence[str]) -> None:
        """Compare one array (stamp s) with the previous and add what changed (the lines'
        alarms and the sensors')."""
        for name in alarm_names(lines):
            st = statuses.get(name)
            if st is None:
                continue
            self._feed_shelf(stamp, name, st)
            state = st.values.get('alarm_state', 'normal')
            raised = _num(st.values.get('alarm_raised')) or 0.0
            old = self._last.get(name, ('normal', 'OK', 0.0))
            self._last[name] = (state, st.level, raised)
            event = _history_event(old, (state, st.level, raised))
            if event is None:
                continue
            when = raised if event.startswith('raised') else stamp
            if event == 'acknowledged':
                when = _num(st.values.get('acknowledged_at')) or stamp
            by = st.values.get('acknowledged_by', '') if event == 'acknowledged' else ''
            condition = st.values.get('alarm_condition', '')
            self.entries.append(_entry(when, name, event, st, condition, by))
        self._feed_components(stamp, statuses, lines)
        if len(self.entries) > HISTORY_LIMIT:
            del self.entries[: len(self.entries) - HISTORY_LIMIT]

    def _feed_components(
        self, stamp: float, statuses: Mapping[str, Status], lines: Sequence[str]
    ) -> None:
        """The component statuses listed as alarms (:func:`component_rows`): ``raised`` when
        one is listed, ``raised again`` when its level rises, ``cleared`` when it is no longer
        listed (OK again, or a STALE the sensors alarm announces), at ``stamp`` s."""
        for name in COMPONENT_ALARMS:
            st = statuses.get(name)
            if st is None:
                continue
            self._feed_component_ack(stamp, name, st)
            new = st.level if _component_listed(name, st, lines) else 'OK'
            old = self._component.get(name, 'OK')
            self._component[name] = new
            if new == old or (new != 'OK' and _SEVERITY.get(new, 3) < _SEVERITY.get(old, 0)):
                continue
            event = 'cleared' if new == 'OK' else ('raised' if old == 'OK' else 'raised again')
            self.entries.append(
                _entry(stamp, name, event, st, st.values.get('conditions', '') or name, '')
            )

    def _feed_component_ack(self, stamp: float, name: str, st: Status) -> None:
        """A component's alarm acknowledged since the previous array (by whom)."""
        at = st.values.get('acknowledged_at', 'nan')
        old = self._component_ack.get(name)
        self._component_ack[name] = at
        when = _num(at)
        if old is None or at == old or when is None:
            return
        by = st.values.get('acknowledged_by', '')
        condition = st.values.get('conditions', '') or name
        self.entries.append(_entry(when, name, 'acknowledged', st, condition, by))

    def _feed_shelf(self, stamp: float, name: str, st: Status) -> None:
        """A shelf put on (or renewed) or taken off since the previous array."""
        v = st.values
        until = _num(v.get('shelved_until')) if v.get('shelved') == 'true' else None
        old = self._shelf.get(name)
        if until == old:
            return
        if until is None:
            self._shelf.pop(name, None)
            event, by, condition = 'unshelved', '', ''
        else:
            self._shelf[name] = until
            event, by = 'shelved', v.get('shelved_by', '')
            condition = v.get('shelved_condition', '')
        self.entries.append(_entry(stamp, name, event, st, condition, by))


def _entry(
    stamp: float, name: str, event: str, st: Status, condition: str, by: str
) -> dict[str, Any]:
    """One history entry: ``event`` of alarm ``name`` at ``stamp`` s, its status now."""
    return {
        'time': stamp,
        'line': name,
        'event': event,
        'level': st.level,
        'condition': condition,
        'message': st.message,
        'by': by,
    }


def _history_event(old: tuple[str, str, float], new: tuple[str, str, float]) -> Optional[str]:
    """What happened between two alarm states of a line (None: nothing to record; suppressed
    by design counts as normal)."""
    (s0, _, r0), (s1, _, r1) = old, new
    s0, s1 = ('normal' if s in ('suppressed', 'shelved') else s for s in (s0, s1))
    if s1 == 'unacknowledged' and (s0 != 'unacknowledged' or r1 != r0):
        return 'raised' if s0 in ('normal', 'returned-unacknowledged') else 'raised again'
    if s0 == s1:
        return None
    if s1 == 'acknowledged' or (s0 == 'returned-unacknowledged' and s1 == 'normal'):
        return 'acknowledged'
    if s1 == 'returned-unacknowledged':
        return 'returned to normal (unacknowledged)'
    if s0 == 'acknowledged' and s1 == 'normal':
        return 'cleared'
    return None


def bucket(
    t: np.ndarray, columns: Mapping[str, np.ndarray], lo: float, hi: float, n: int = 600
) -> dict[str, list[Optional[float]]]:
    """Chart series over ``[lo, hi]`` s in at most ``n`` time buckets: per bucket its last time,
    the maximum of ``*_max`` columns and the minimum of ``*_min`` columns (an envelope keeps
    every peak a person must see); empty buckets are left out."""
    keep = (t >= lo) & (t <= hi)
    t = t[keep]
    out: dict[str, list[Optional[float]]] = {'t': []}
    for key in columns:
        out[key] = []
    if not len(t):
        return out
    lo = max(lo, float(t[0]))  # a record shorter than the span: buckets over what there is
    width = max((hi - lo) / n, 1e-9)
    b = np.minimum(((t - lo) / width).astype(np.int64), n - 1)
    starts = np.flatnonzero(np.diff(b, prepend=-1))
    ends = np.append(starts[1:], len(b))
    out['t'] = t[ends - 1].tolist()
    with np.errstate(invalid='ignore'):
        for key, col in columns.items():
            v = np.asarray(col)[keep]
            if key.endswith('_min'):
                agg = np.fmin.reduceat(v, starts)
            else:
                agg = np.fmax.reduceat(v, starts)
            out[key] = [_finite(float(x)) for x in agg]
    return out


class Trend:
    """Newest hours of a few series of one source, stored in ``resolution`` s buckets (maximum
    of ``*_max`` keys, minimum of ``*_min`` keys) as arrays of doubles (two hours of three
    series at 0.25 s: 0.7 MB), for the live console's charts."""

    def __init__(
        self, keys: Sequence[str], keep_s: float = 7200.0, resolution: float = 0.25
    ) -> None:
        self.keys, self.keep_s, self.resolution = tuple(keys), keep_s, resolution
        self.t = array('d')
        self.cols = {k: array('d') for k in keys}

    def add(self, t: float, values: Mapping[str, float]) -> None:
        """One sample at ``t`` (s)."""
        r = self.resolution
        if self.t and math.floor(self.t[-1] / r) == math.floor(t / r):
            self.t[-1] = t
            for k in self.keys:
                old, new = self.cols[k][-1], values[k]
                pick = min if k.endswith('_min') else max
                self.cols[k][-1] = new if old != old else (old if new != new else pick(old, new))
            return
        self.t.append(t)
        for k in self.keys:
            self.cols[k].append(values[k])
        if t - self.t[0] > self.keep_s + 60.0:
            cut = int(np.searchsorted(np.frombuffer(self.t), t - self.keep_s))
            del self.t[:cut]
            for k in self.keys:
                del self.cols[k][:cut]

    def series(self, lo: float, hi: float, n: int = 600) -> dict[str, list[Optional[float]]]:
        """:func:`bucket` of the stored samples over ``[lo, hi]``."""
        return bucket(np.array(self.t), {k: np.array(v) for k, v in self.cols.items()}, lo, hi, n)


def tide_trend(statuses: Mapping[str, Status]) -> dict:
    """The tide's trend as the monitor decided it (the ``rate`` value [m/s] of the tide's
    ``/diagnostics`` status, :mod:`catenary_monitor.core.rules.tide_trend`): rate in m/h and
    whether it is rising, falling or steady (|rate| < 0.05 m/h); unknown while the monitor says
    nan."""
    tide = statuses.get('tide')
    rate = _num(tide.values.get('rate')) if tide is not None else None
    if rate is None:
        return {'rate_m_per_h': None, 'trend': 'unknown'}
    slope = rate * 3600.0
    word = 'steady' if abs(slope) < 0.05 else ('rising' if slope > 0 else 'falling')
    return {'rate_m_per_h': slope, 'trend': word}


def _line_view(
    name: str,
    status: Optional[Status],
    output: Optional[tuple[float, Sequence[float]]],
    sample_t: Optional[float],
    now: float,
) -> dict[str, Any]:
    """One tile: level and message (the newest of /diagnostics and the outputs), values, the
    alarm's state, and the age of the newest tension sample (s)."""
    view: dict[str, Any] = {'name': name, 'level': 'STALE', 'message': 'no data from the monitor'}
    if status is not None:
        v = status.values
        view.update(
            level=status.level,
            message=status.message,
            model=v.get('model', ''),
            alarm_state=v.get('alarm_state', 'normal'),
            acknowledged=v.get('acknowledged', 'true') == 'true',
            alarm_condition=v.get('alarm_condition', ''),
            sensor_state=v.get('sensor_state', 'ok'),  # the core's word: ok, stuck, spike, ...
            shelved=v.get('shelved') == 'true',
            shelved_condition=v.get('shelved_condition', ''),
            shelved_until=_num(v.get('shelved_until')),
            shelved_by=v.get('shelved_by', ''),
            chattering=v.get('chattering') == 'true',
            detail=v.get('detail', status.message),
            response=v.get('response', ''),
        )
        for key in (
            'top_tension',
            'anchor_margin',
            'uplift_force',
            'safety_factor',
            'tide_margin',
            'min_anchor_distance',
            'time_to_uplift',  # s; None when not coming (inf) or unknown
            'uplift_force_upper',  # N, within sensor accuracy; None when not configured
            'drag_margin',  # N, holding minus horizontal load; None without anchor_holding
            'implied_anchor_distance',  # m, from the chain length; None without it
            'tide_margin_at_length',  # m, the chain length held; None without it
            'drag_state',  # 0 holding, 1 overloaded, 2 dragging; None unknown
            'fatigue_damage',  # Miner's damage so far
            'fatigue_life_left',  # s at the last day's rate; None unknown or unlimited
            'wave_tension',  # N, the wave-frequency tension (half-range over wave_window)
            'dynamic_uplift',  # N, the uplift at the waves' peak tension (what ERROR takes)
            'span',  # m, the hook-anchor distance the line was solved at
            'channels_healthy',  # a load cell's healthy channels; None for one channel
            'channel_states',  # their states, sum code_i 5^i (core.rules.channels)
        ):
            view[key] = _num(v.get(key))
        view['span_source'] = v.get('span_source', 'none')  # installed, dock_estimate, none
        # time_to_uplift is None both when unknown (NaN) and when not coming (inf): say which
        view['time_to_uplift_state'] = _forecast_state(v.get('time_to_uplift'))
        view['time_to_uplift_view'] = v.get('time_to_uplift_view', 'none')
    if output is not None:
        rx, values = output
        for key in ('top_tension', 'anchor_margin', 'uplift_force', 'safety_factor'):
            view[key] = _finite(float(values[_INDEX[key]]))
    view.update(_uplift_shown(view))
    view['age_s'] = None if sample_t is None else max(now - sample_t, 0.0)
    return view


def _uplift_shown(view: Mapping[str, Any]) -> dict[str, Any]:
    """The uplift the tile shows: the one the alarm is raised on (``uplift_shown``, N), the
    dynamic uplift at the waves' peak tension where it exceeds the quasi-static one
    (``uplift_dynamic`` true), else the quasi-static ``uplift_force``."""
    static, dynamic = view.get('uplift_force'), view.get('dynamic_uplift')
    if dynamic is not None and (static is None or dynamic > static):
        return {'uplift_shown': dynamic, 'uplift_dynamic': True}
    return {'uplift_shown': static, 'uplift_dynamic': False}


def build_frame(
    now: float,
    config_lines: Sequence[str],
    snapshot_t: Optional[float],
    statuses: Mapping[str, Status],
    outputs: Mapping[str, tuple[float, Sequence[float]]],
    sample_t: Mapping[str, float],
    depth: Optional[dict[str, Any]],
    history: Sequence[dict[str, Any]],
    silence_limit_s: float,
    started: Optional[float] = None,
    **extra: Any,
) -> dict[str, Any]:
    """One frame of the page at ``now`` (s).

    ``snapshot_t``: when the newest ``/diagnostics`` array arrived (or its stamp in replay);
    ``statuses`` its components; ``outputs`` line -> (time, OUTPUT_FIELDS values) of the newest
    output; ``sample_t`` line -> time of the newest tension sample; ``depth``: the tide view.
    Levels, messages and alarm states are the array's (the monitor publishes one at once on
    every level change and acknowledgement); the values are the newest outputs'.
    """
    since = snapshot_t if snapshot_t is not None else started
    silent = None if since is None else max(now - since, 0.0)
    lines = []
    for name in config_lines:
        lines.append(
            _line_view(name, statuses.get(name), outputs.get(name), sample_t.get(name), now)
        )
    tide = statuses.get('tide')
    logger = statuses.get('logger')
    return {
        'now': now,
        'snapshot_t': snapshot_t,
        'silent_s': silent,
        'connection': (
            'lost'
            if silent is not None and silent > silence_limit_s
            else ('waiting' if snapshot_t is None else 'ok')
        ),
        'lines': lines,
        'tide': {
            'level': tide.level if tide else 'STALE',
            'message': tide.message if tide else 'no data from the monitor',
            'depth': _num(tide.values.get('depth')) if tide else None,
            **(depth or {}),
        },
        'logger': {
            'level': logger.level if logger else 'STALE',
            'message': logger.message if logger else '',
        },
        'monitor': monitor_rows(statuses),
        'alarms': alarm_rows(statuses, config_lines, True, history),
        'shelved': shelved_rows(statuses, config_lines),
        'flood': flood_view(statuses),
        'history': list(history[-200:]),
        **extra,
    }


#: A /diagnostics number and what a time to uplift says, for the other views (the harbour's).
diagnostic_number = _num
forecast_state = _forecast_state
