"""The harbour's view of its docks, built from each dock's ``/diagnostics`` (no rclpy, no HTTP).

Each dock's monitor runs on its own PC in its own ROS domain; the harbour hears only its
``/diagnostics`` arrays (:mod:`.harbour_source`). This module keeps the newest array of each
dock (:class:`DockState`) and turns it into the dock's JSON view (:func:`dock_view`): its worst
level, its lines (level, uplift force, anchor margin, time to uplift), the lines in alarm, the
worst uplift and anchor margin, the nearest time to uplift, its active alarms with the dock's
first out, whether its monitor is alive and how old its newest status is; then the
harbour-wide alarm list (:func:`harbour_alarms`).

Everything is read by key name from the statuses ``catenary_monitor: NAME``: a key the
harbour does not know is ignored, a key it needs and does not find is ``null``. The monitor
decides every level and alarm state; the harbour adds one decision of its own: a dock whose
``/diagnostics`` stopped (older than its silence limit) is **STALE**, monitor not alive, each
of its lines STALE with its last known level beside it: a silent dock is never a stale green
tile.

Times are the harbour's wall clock (s since the epoch) at reception; forces N, lengths m.
"""

from __future__ import annotations

import math
import re
import statistics
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence
from urllib.parse import urlsplit

from catenary_monitor.console.frames import Status, alarm_rows, silence_limit
from catenary_monitor.console.frames import diagnostic_number as _num
from catenary_monitor.console.frames import forecast_state as _forecast_state
from catenary_monitor.core.config.parameters import COMPONENTS, MonitorConfig

__all__ = [
    'DockSpec',
    'DockState',
    'parse_dock',
    'parse_console_url',
    'parse_discovery_server',
    'line_names',
    'dock_view',
    'harbour_alarms',
    'mixed',
    'worst_level',
    'LEVEL_RANK',
    'MAX_DOMAIN_ID',
]

#: Severity of a level for the worst of several: ERROR > STALE > WARN > OK (the monitor's own
#: order: a sensor dropout must not hide a lifted anchor, a warning from old data is no news).
LEVEL_RANK = {'OK': 0, 'WARN': 1, 'STALE': 2, 'ERROR': 3}
#: The largest ROS domain id (rmw: 0-232; 0-101 and 215-232 leave every port free).
MAX_DOMAIN_ID = 232
_NAME = re.compile(r'^[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}$')
_NUMBER = r'[-+]?(?:\d+(?:\.\d*)?|\.\d+)'
_POSITION = re.compile(rf'@({_NUMBER}),({_NUMBER})$')
#: Alarm states whose condition is still there (``returned-unacknowledged`` is not).
_IN_ALARM = ('unacknowledged', 'acknowledged', 'active')
#: Inter-arrival gaps kept to learn the period of a monitor the harbour has no params for.
_GAPS = 9


@dataclass(frozen=True)
class DockSpec:
    """One dock of the harbour: its name, ROS domain, params file (its monitor's: lines and
    the ``/diagnostics`` rate), position (degrees, WGS84), its console's URL and the Fast DDS
    discovery server(s) its participant uses (a ``ROS_DISCOVERY_SERVER`` value; None: the
    process's discovery)."""

    name: str
    domain_id: int
    params_file: Optional[str] = None
    lat: Optional[float] = None
    lon: Optional[float] = None
    console_url: Optional[str] = None
    discovery_server: Optional[str] = None
    config: Optional[MonitorConfig] = None

    @property
    def line_names(self) -> list[str]:
        return [line.name for line in self.config.lines] if self.config else []

    @property
    def period(self) -> Optional[float]:
        """The monitor's ``/diagnostics`` period (s) when its params file says it."""
        return 1.0 / self.config.alarm.diagnostic_rate if self.config else None


def parse_dock(text: str) -> DockSpec:
    """``NAME=DOMAIN_ID[:PARAMS_FILE][@LAT,LON]`` (the ``--dock`` option) as a spec (the
    params file not read yet). Raises ValueError with one line naming what is wrong."""
    usage = f'--dock {text[:80]!r}: expected NAME=DOMAIN_ID[:PARAMS_FILE][@LAT,LON]'
    name, sep, rest = text.partition('=')
    if not sep or not _NAME.match(name):
        raise ValueError(f'{usage} (NAME: letters, digits, _ . -; at most 64)')
    lat = lon = None
    where = _POSITION.search(rest)
    if where is not None:
        lat, lon = float(where.group(1)), float(where.group(2))
        rest = rest[: where.start()]
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise ValueError(f'{usage} (latitude -90..90, longitude -180..180 degrees)')
    domain, _, params = rest.partition(':')
    if not domain.isdigit() or int(domain) > MAX_DOMAIN_ID:
        raise ValueError(f'{usage} (DOMAIN_ID: 0 to {MAX_DOMAIN_ID})')
    return DockSpec(name, int(domain), params or None, lat, lon)


def parse_console_url(text: str) -> tuple[str, str]:
    """``NAME=URL`` (the ``--console-url`` option): the dock and its console's http(s) URL.
    Raises ValueError with one line."""
    name, sep, url = text.partition('=')
    parts = urlsplit(url)
    if not sep or not _NAME.match(name):
        raise ValueError(f'--console-url {text[:80]!r}: expected NAME=URL')
    if parts.scheme not in ('http', 'https') or not parts.netloc or not url.isprintable():
        raise ValueError(f'--console-url {text[:80]!r}: the URL must be http:// or https://')
    return name, url


#: A ``ROS_DISCOVERY_SERVER`` value: addresses (IPv4, [IPv6], names) with ports, ``;``-separated
#: by server id (an empty place for an id not used).
_SERVERS = re.compile(r'^[A-Za-z0-9_.:\[\];-]{1,1000}$')


def parse_discovery_server(text: str) -> tuple[str, str]:
    """``NAME=SERVERS`` (the ``--discovery-server`` option): the dock and the
    ``ROS_DISCOVERY_SERVER`` value its participant uses. Raises ValueError with one line."""
    name, sep, servers = text.partition('=')
    ports = [int(p) for p in re.findall(r':([0-9]+)(?:;|$)', servers)]
    if (
        not sep
        or not _NAME.match(name)
        or not _SERVERS.match(servers)
        or not servers.strip(';')
        or not all(1 <= p <= 65535 for p in ports)
    ):
        raise ValueError(
            f'--discovery-server {text[:80]!r}: expected NAME=ADDRESS:PORT (a '
            'ROS_DISCOVERY_SERVER value: ;-separated by server id)'
        )
    return name, servers


def worst_level(levels: Sequence[str]) -> str:
    """The worst of ``levels`` (:data:`LEVEL_RANK`; OK for none)."""
    return max(levels, key=lambda lv: LEVEL_RANK.get(lv, 2), default='OK')


@dataclass
class DockState:
    """What the harbour heard from one dock: the newest array's statuses and when it came
    (``rx``), when its worst level became what it is (``level_since``; a monitor heard again
    after a silence starts anew), when the first array came, and the traffic (arrays, bytes)
    since the harbour started at ``started`` (s). ``period``: the monitor's ``/diagnostics``
    period from its params file (s; None: learned from the arrays' gaps)."""

    started: float
    period: Optional[float] = None
    statuses: dict[str, Status] = field(default_factory=dict)
    rx: Optional[float] = None
    first_rx: Optional[float] = None
    level: Optional[str] = None
    level_since: Optional[float] = None
    arrays: int = 0
    bytes: int = 0
    gaps: list[float] = field(default_factory=list)

    def feed(self, rx: float, statuses: dict[str, Status], size: int) -> None:
        """One array of the dock's monitor received at ``rx`` (s), ``size`` bytes of CDR."""
        silent = self.rx is not None and rx - self.rx > self.silence_limit()
        if self.rx is not None:
            self.gaps.append(max(rx - self.rx, 0.0))
            del self.gaps[:-_GAPS]
        level = worst_level([st.level for st in statuses.values()])
        if level != self.level or silent or self.rx is None:
            self.level, self.level_since = level, rx
        self.statuses, self.rx = statuses, rx
        self.first_rx = rx if self.first_rx is None else self.first_rx
        self.arrays += 1
        self.bytes += size

    def silence_limit(self) -> float:
        """Seconds without an array after which the monitor counts as silent: the console's
        rule (twice the period plus 1 s) with the period from the params file, else the
        median gap between the last arrays (the default 1 Hz until three came)."""
        period = self.period
        if period is None:
            period = statistics.median(self.gaps) if len(self.gaps) >= 3 else 1.0
        return silence_limit(1.0 / max(period, 0.01))


def line_names(spec: DockSpec, statuses: Mapping[str, Status]) -> list[str]:
    """The dock's lines: its params file's, else the statuses that are lines (not one of the
    monitor's components, and carrying a line's ``uplift_force``), in the array's order."""
    if spec.config is not None:
        return spec.line_names
    return [n for n, st in statuses.items() if n not in COMPONENTS and 'uplift_force' in st.values]


def _line(name: str, st: Optional[Status], alive: bool) -> dict[str, Any]:
    """One line of a dock: its level (STALE while the monitor is silent, the last known level
    beside it), message, alarm state and the three values of the tile."""
    v = st.values if st is not None else {}
    last = st.level if st is not None else None
    return {
        'name': name,
        'level': last if (alive and last is not None) else 'STALE',
        'last_level': last,
        'message': st.message if st is not None else 'not in the monitor\'s /diagnostics',
        'alarm_state': v.get('alarm_state', 'normal'),
        'uplift_force': _num(v.get('uplift_force')),
        'anchor_margin': _num(v.get('anchor_margin')),
        'time_to_uplift': _num(v.get('time_to_uplift')),
        'time_to_uplift_state': _forecast_state(v.get('time_to_uplift')),
    }


def _extreme(lines: list[dict[str, Any]], key: str, pick: Any) -> tuple[Any, Optional[str]]:
    """(value, line) of the largest (``pick`` max) or smallest (min) known ``key``."""
    known = [(ln[key], ln['name']) for ln in lines if ln[key] is not None]
    if not known:
        return None, None
    return pick(known, key=lambda x: x[0])


def _first_out(statuses: Mapping[str, Status], rows: list[dict[str, Any]]) -> tuple[str, str]:
    """The dock's first out and where it comes from: during a flood the monitor's own
    (``flood``: the alarm raised first when the flood began), else the alarm raised first
    among those still in alarm (``earliest``; one that returned to normal unacknowledged is
    listed but starts nothing); ('', '') with no alarm in alarm."""
    alarms = statuses.get('alarms')
    if alarms is not None and alarms.values.get('flood') == 'true':
        name = alarms.values.get('first_out', '')
        if name:
            return name, 'flood'
    raised = [
        (r.get('raised') or math.inf, r.get('line', ''))
        for r in rows
        if r.get('state') in _IN_ALARM
    ]
    if not raised:
        return '', ''
    return min(raised)[1], 'earliest'


def _alarms(spec: DockSpec, statuses: Mapping[str, Status], lines: list[str]) -> dict[str, Any]:
    """The dock's active alarms (the console's rows, its component statuses' too, each with
    ``dock`` and ``first_out``: this alarm is the dock's first out) and the first out."""
    rows = [dict(r, dock=spec.name) for r in alarm_rows(statuses, lines, components=True)]
    first, source = _first_out(statuses, rows)
    for row in rows:
        row['first_out'] = row.get('line') == first
    alarms = statuses.get('alarms')
    return {
        'rows': rows,
        'first_out': first or None,
        'first_out_source': source or None,
        'flood': alarms is not None and alarms.values.get('flood') == 'true',
        'flood_message': alarms.message if alarms is not None else '',
    }


def dock_view(spec: DockSpec, state: DockState, now: float) -> dict[str, Any]:
    """One dock as ``/api/docks`` shows it at ``now`` (s): see the module doc and
    docs/harbour.md for every key."""
    statuses = state.statuses
    age = None if state.rx is None else max(now - state.rx, 0.0)
    limit = state.silence_limit()
    alive = age is not None and age <= limit
    names = line_names(spec, statuses)
    lines = [_line(n, statuses.get(n), alive) for n in names]
    components = [
        {'name': n, 'level': st.level, 'message': st.message}
        for n, st in statuses.items()
        if n not in names
    ]
    last = worst_level([st.level for st in statuses.values()]) if statuses else None
    alarms = _alarms(spec, statuses, names)
    uplift, uplift_line = _extreme(lines, 'uplift_force', max)
    margin, margin_line = _extreme(lines, 'anchor_margin', min)
    ttu, ttu_line = _extreme(lines, 'time_to_uplift', min)
    in_alarm = [
        ln['name']
        for ln in lines
        if ln['last_level'] not in (None, 'OK') and ln['alarm_state'] != 'suppressed'
    ]
    return {
        'name': spec.name,
        'domain_id': spec.domain_id,
        'level': last if (alive and last is not None) else 'STALE',
        'last_level': last,
        'level_since': _level_since(state, alive, limit),
        'message': _message(spec, statuses, alive, age, limit, now - state.started),
        'monitor_alive': alive,
        'status_age_s': age,
        'silence_limit_s': limit,
        'lines': lines,
        'lines_in_alarm': in_alarm,
        'worst_uplift_force': uplift,
        'worst_uplift_line': uplift_line,
        'worst_anchor_margin': margin,
        'worst_anchor_margin_line': margin_line,
        'time_to_uplift': ttu,
        'time_to_uplift_line': ttu_line,
        'alarms': alarms['rows'],
        'first_out': alarms['first_out'],
        'first_out_source': alarms['first_out_source'],
        'flood': alarms['flood'],
        'components': components,
        'console_url': spec.console_url,
        'position': None if spec.lat is None else {'lat': spec.lat, 'lon': spec.lon},
        'received': {'arrays': state.arrays, 'bytes': state.bytes, 'first': state.first_rx},
    }


def _level_since(state: DockState, alive: bool, limit: float) -> float:
    """When the dock's level (as shown) began (s): its worst level's change while its monitor
    is alive, else the moment its silence passed the limit (from the harbour's start when
    nothing ever came)."""
    if alive and state.level_since is not None:
        return state.level_since
    return (state.rx if state.rx is not None else state.started) + limit


def _message(
    spec: DockSpec,
    statuses: Mapping[str, Status],
    alive: bool,
    age: Optional[float],
    limit: float,
    up: float,
) -> str:
    """The tile's one line: why the monitor counts as silent, else the message of its worst
    status (the first of the worst, in the array's order)."""
    if age is None:
        return (
            f'no /diagnostics from the monitor in domain {spec.domain_id} '
            f'({up:.0f} s since the harbour started)'
        )
    if not alive:
        return f'monitor silent: no /diagnostics for {age:.0f} s (limit {limit:.0f} s)'
    worst = worst_level([st.level for st in statuses.values()])
    for name, st in statuses.items():
        if st.level == worst and worst != 'OK':
            return f'{name}: {st.message}'
    return 'every status OK'


def mixed(view: dict[str, Any], monitors: Sequence[str]) -> None:
    """Mark a dock view whose domain holds several monitors (``monitors``: their node names):
    their arrays cannot be told apart, so the dock is STALE, whatever they say."""
    view['level'] = 'STALE'
    view['monitors'] = list(monitors)
    view['level_since'] = None
    view['message'] = (
        f'{len(monitors)} monitors publish /diagnostics in domain {view["domain_id"]} '
        f'({", ".join(monitors)}): the harbour cannot tell them apart; give each dock its own '
        'domain (a discovery server matches across domains: see the deploy guide)'
    )


def harbour_alarms(docks: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The harbour-wide alarm list: every dock's active alarms, each dock's first out first,
    then unacknowledged before acknowledged, ERROR before STALE before WARN, newest first; a
    silent dock is one row of its own (``monitor silent``), before every other, as is a dock
    whose domain holds several monitors (``monitors mixed``)."""
    rank_state = {
        'unacknowledged': 0,
        'active': 0,  # a component of a monitor that does not acknowledge it
        'returned-unacknowledged': 1,
        'acknowledged': 2,
    }
    rows: list[dict[str, Any]] = []
    for dock in docks:
        if not dock['monitor_alive'] or len(dock.get('monitors', ())) > 1:
            rows.append(
                {
                    'dock': dock['name'],
                    'line': '',
                    'state': 'monitor silent' if not dock['monitor_alive'] else 'monitors mixed',
                    'level': 'STALE',
                    'raised': None,
                    'message': dock['message'],
                    'first_out': False,
                }
            )
        rows.extend(dock['alarms'])
    rows.sort(
        key=lambda r: (
            r['state'] not in ('monitor silent', 'monitors mixed'),
            not r.get('first_out'),
            rank_state.get(r.get('state', ''), 3),
            -LEVEL_RANK.get(r.get('level', 'STALE'), 2),
            -(r.get('raised') or 0.0),
        )
    )
    return rows
