"""Annunciations as the operator sees them: every status of ``/diagnostics`` that leaves OK.

The monitor publishes (and ``catenary-monitor replay --out`` records) a ``DiagnosticArray`` at
every tick: a status per line and the ``tide``, ``sensors``, ``alarms``, ``logger``, ``dock``,
``fatigue``, ``intake``, ``parameters`` and ``clock`` statuses. An operator hears a status
when what it shows active rises: OK to WARN, ERROR or STALE (raised), or WARN to ERROR
(escalated); a status whose ``alarm_state`` says ``suppressed`` or ``shelved`` shows nothing
active (a level it rises to then is shown as such and not annunciated: counted apart,
``hidden``), so leaving it for an active level is a raise (a line's suppressed start-up STALE
followed by an anchor-margin WARN is heard). An alarm with an acknowledgement state (a line's,
the ``sensors``': ``alarm_raised`` among its values) is heard as the console lists it: when its
``alarm_state`` becomes ``unacknowledged`` from another state, or with a new ``alarm_raised``
(raised again). A status that starts non-OK (the start-up wait) has not left OK.

:class:`Counter` takes the replay driver's snapshots (:class:`Snapshot`, or the columns of
``snapshots='columns'``: levels compared as arrays, the text read only where a level rises);
:func:`read_results` decodes the ``/diagnostics`` of a results log (``replay --out``) into the
same counter, so the two are checked equal (test/test_normal_days.py). :func:`cause` names an
annunciation's cause from its message (numbers masked), for tallies by class.
"""

from __future__ import annotations

import re
import struct
from collections import Counter as Tally
from pathlib import Path
from typing import Any, Callable, Iterable, NamedTuple, Optional, Sequence

import numpy as np

from catenary_monitor.core.monitor.status import Snapshot
from catenary_monitor.core.twin.engine import ReplayResult
from catenary_monitor.core.twin.window import SnapshotColumns, StatusColumns

__all__ = ['Annunciation', 'Counter', 'cause', 'family', 'read_results', 'HIDDEN']

#: ``alarm_state`` values under which a raised status is not annunciated.
HIDDEN = ('suppressed', 'shelved')
#: ``alarm_state`` of an alarm the console lists as raised and waiting for an acknowledgement.
UNACKNOWLEDGED = 'unacknowledged'
_PREFIX = 'catenary_monitor: '


class Annunciation(NamedTuple):
    """One rise of a status: when [s], which status (``line_03``, ``tide``...), the levels
    before and after (0 OK, 1 WARN, 2 ERROR, 3 STALE), its message, and ``hidden`` (the
    ``alarm_state`` that kept it silent, else empty)."""

    time: float
    status: str
    before: int
    after: int
    message: str
    hidden: str = ''


def _rank(level: np.ndarray) -> np.ndarray:
    """Levels ordered by urgency: OK < WARN < STALE < ERROR (STALE is 3 on the wire)."""
    return np.choose(np.clip(level, 0, 3), [0, 1, 3, 2])


def family(status: str) -> str:
    """``line`` for a line's status, else the status's own name."""
    return status if status in _GLOBAL else 'line'


_GLOBAL = ('tide', 'sensors', 'alarms', 'logger', 'dock', 'fatigue', 'intake', 'parameters',
           'clock')  # fmt: skip


def cause(message: str) -> str:
    """The cause an annunciation names: its message's first clause, numbers masked
    (``depth sensor stuck at # m while the lines move``)."""
    first = re.split(r';|: check|: a |\(', message, maxsplit=1)[0]
    first = re.sub(r'line_\w+|ml\d+', 'LINE', first)
    first = re.sub(r'-?\d+(\.\d+)?(e[-+]?\d+)?', '#', first)
    return re.sub(r'\s+', ' ', first).strip(' :,')


class Counter:
    """A replay sink (:func:`catenary_monitor.replay.driver.drive`) collecting every
    annunciation of the snapshots (replay with ``snapshots='columns'`` or True)."""

    def __init__(self) -> None:
        self.abandon()

    def abandon(self) -> None:
        self.level: dict[str, int] = {}
        #: Each status's last (level, alarm_state, alarm_raised or None).
        self.shown: dict[str, tuple[int, str, Optional[str]]] = {}
        self.events: list[Annunciation] = []
        #: Every level change of each status: name -> [(time s, level)], in time order.
        self.changes: dict[str, list[tuple[float, int]]] = {}
        self.snapshots = 0
        self.start: float | None = None
        self.end: float | None = None

    def __call__(self, result: ReplayResult, window: Any) -> None:
        self.take(result.snapshots)

    def take(self, snapshots: Iterable[Snapshot | SnapshotColumns]) -> None:
        """One window's snapshots (in any order: a window's event snapshots can come after
        its tick columns; each status is followed in time order)."""
        series: dict[str, list[tuple[Any, ...]]] = {}
        for snap in snapshots:
            if isinstance(snap, SnapshotColumns):
                self._columns(snap, series)
            else:
                stamp = np.array([snap.stamp_ns], np.int64)
                self.snapshots += 1
                self._mark(stamp)
                for st in snap.statuses:
                    values = dict(st.values)
                    text = (st.message, values.get('alarm_state', ''))
                    series.setdefault(_short(st.name), []).append(
                        (stamp, np.array([int(st.level)]), lambda i, t=text: t,
                         *_shown([values])))  # fmt: skip
        found: list[Annunciation] = []
        for name, pieces in series.items():
            found += self._rises(name, pieces)
        found.sort(key=lambda a: a.time)
        self.events += found

    def take_rows(self, stamp_ns: int, statuses: Sequence[tuple[str, int, str, dict]]) -> None:
        """One decoded DiagnosticArray (in time order): (name, level, message, values) per
        status."""
        self.snapshots += 1
        stamp = np.array([stamp_ns], np.int64)
        self._mark(stamp)
        for name, level, message, values in statuses:
            text = (message, values.get('alarm_state', ''))
            self.events += self._rises(_short(name), [(stamp, np.array([level]),
                                                       lambda i, t=text: t, *_shown([values]))])

    def _mark(self, stamps: np.ndarray) -> None:
        if len(stamps):
            first, last = float(stamps.min()) * 1e-9, float(stamps.max()) * 1e-9
            self.start = first if self.start is None else min(self.start, first)
            self.end = last if self.end is None else max(self.end, last)

    def _columns(self, snap: SnapshotColumns, series: dict[str, list]) -> None:
        stamps = np.asarray(snap.stamps, np.int64)
        n = len(stamps)
        if not n:
            return
        self.snapshots += n
        self._mark(stamps)
        for group, m in snap.groups:
            for k in range(m):
                if isinstance(group, StatusColumns):
                    levels = np.asarray(group.levels[k * n : (k + 1) * n], np.int64)
                    name = _get(group.name, k * n)
                    state = (group.values[group.keys.index('alarm_state')]
                             if 'alarm_state' in group.keys else '')  # fmt: skip
                    text = _column_text(group, k * n, state)
                    shown = _column_shown(group, k * n, n)
                else:
                    rows = group[k * n : (k + 1) * n]
                    levels = np.array([int(r.level) for r in rows])
                    name = rows[0].name
                    text = _row_text(rows)
                    shown = _shown([dict(r.values) for r in rows])
                series.setdefault(_short(name), []).append((stamps, levels, text, *shown))

    def _rises(self, name: str, pieces: list[tuple[Any, ...]]) -> list:
        """The rises of one status over ``pieces`` (stamps, levels, text(i), alarm states,
        ``alarm_raised`` or None) in time order."""
        stamps = np.concatenate([p[0] for p in pieces])
        levels = np.concatenate([p[1] for p in pieces])
        states = np.concatenate([p[3] for p in pieces])
        raised = None if pieces[0][4] is None else np.concatenate([p[4] for p in pieces])
        piece = np.concatenate([np.full(len(p[0]), j) for j, p in enumerate(pieces)])
        index = np.concatenate([np.arange(len(p[0])) for p in pieces])
        order = np.argsort(stamps, kind='stable')
        stamps, levels, piece, index = stamps[order], levels[order], piece[order], index[order]
        states = states[order]
        before = self.level.get(name)
        first = (levels[0], states[0], None if raised is None else raised[order][0])
        last = first if before is None else self.shown[name]
        prev = np.concatenate([[last[0]], levels[:-1]])
        prev_states = np.concatenate([[last[1]], states[:-1]])
        self.level[name] = int(levels[-1])
        moves = self.changes.setdefault(name, [])
        if before is None:
            moves.append((float(stamps[0]) * 1e-9, int(levels[0])))
        for i in np.flatnonzero(levels != prev).tolist():
            moves.append((float(stamps[i]) * 1e-9, int(levels[i])))
        hidden = np.isin(states, HIDDEN)
        rose = _rank(levels) > _rank(prev)
        if raised is None:  # a status: heard when what it shows active rises
            shown = np.where(np.isin(prev_states, HIDDEN), 0, prev)
            heard = ~hidden & (_rank(levels) > _rank(shown))
        else:  # an alarm: heard when the console lists it (raised again)
            raised = raised[order]
            prev_raised = np.concatenate([[last[2]], raised[:-1]])
            unack = states == UNACKNOWLEDGED
            heard = unack & ((prev_states != UNACKNOWLEDGED) | (raised != prev_raised))
        self.shown[name] = (int(levels[-1]), states[-1], None if raised is None else raised[-1])
        out = []
        for i in np.flatnonzero(heard | (hidden & rose)).tolist():
            message, state = pieces[int(piece[i])][2](int(index[i]))
            out.append(Annunciation(float(stamps[i]) * 1e-9, name, int(prev[i]), int(levels[i]),
                                    message, state if state in HIDDEN else ''))  # fmt: skip
        return out

    # ------------------------------------------------------------------ tallies
    def level_at(self, name: str, t: np.ndarray) -> np.ndarray:
        """The status's level at times ``t`` [s] (-1 before it was first seen)."""
        moves = self.changes.get(name, [])
        if not moves:
            return np.full(len(t), -1)
        times = np.array([m[0] for m in moves])
        levels = np.array([m[1] for m in moves])
        i = np.searchsorted(times, t, 'right') - 1
        return np.where(i >= 0, levels[np.maximum(i, 0)], -1)

    def heard(self, since: float = -np.inf, until: float = np.inf) -> list[Annunciation]:
        """The annunciations the operator heard in ``[since, until)`` [s]."""
        return [a for a in self.events if not a.hidden and since <= a.time < until]

    def by_cause(self, events: Iterable[Annunciation]) -> Tally[tuple[str, str, str]]:
        """(family, level word, cause) -> count."""
        words = {1: 'WARN', 2: 'ERROR', 3: 'STALE'}
        return Tally((family(a.status), words.get(a.after, str(a.after)), cause(a.message))
                     for a in events)  # fmt: skip


def _column_text(group: Any, at: int, state: Any) -> Callable[[int], tuple[str, str]]:
    """(message, alarm_state) of the ``i``-th snapshot of a status in columns."""
    return lambda i: (_get(group.message, at + i), _get(state, at + i) if state else '')


def _shown(values: Sequence[dict]) -> tuple[np.ndarray, Optional[np.ndarray]]:
    """The ``alarm_state`` of each of a status's values (empty when it has none) and its
    ``alarm_raised`` (None for a status without one)."""
    states = np.array([v.get('alarm_state', '') for v in values], object)
    if not values or 'alarm_raised' not in values[0]:
        return states, None
    return states, np.array([v['alarm_raised'] for v in values], object)


def _column_shown(group: Any, at: int, n: int) -> tuple[np.ndarray, Optional[np.ndarray]]:
    """:func:`_shown` of the ``n`` snapshots of a status in columns from ``at``."""

    def column(key: str) -> np.ndarray:
        field = group.values[group.keys.index(key)]
        if isinstance(field, str):
            return np.full(n, field, object)
        return np.array(field[at : at + n], object)

    states = column('alarm_state') if 'alarm_state' in group.keys else np.full(n, '', object)
    return states, column('alarm_raised') if 'alarm_raised' in group.keys else None


def _row_text(rows: Any) -> Callable[[int], tuple[str, str]]:
    """(message, alarm_state) of the ``i``-th of a status's rows."""
    return lambda i: (rows[i].message, dict(rows[i].values).get('alarm_state', ''))


def _short(name: str) -> str:
    return name[len(_PREFIX) :] if name.startswith(_PREFIX) else name


def _get(field: Any, i: int) -> str:
    return field if isinstance(field, str) else field[i]


# --- a results log's /diagnostics -----------------------------------------------------------


def _string(data: bytes, pos: int) -> tuple[str, int]:
    pos += -pos % 4
    (n,) = struct.unpack_from('<I', data, pos)
    pos += 4
    return data[pos : pos + n - 1].decode('utf-8', 'replace'), pos + n


def decode_diagnostic_array(data: bytes) -> tuple[int, list[tuple[str, int, str, dict]]]:
    """(header stamp ns, statuses) of a ``diagnostic_msgs/msg/DiagnosticArray`` in CDR (little
    endian, as the monitor writes it); each status (name, level, message, values)."""
    body = memoryview(data)[4:].tobytes()  # offsets count from the end of the encapsulation
    sec, nsec = struct.unpack_from('<iI', body, 0)
    _, pos = _string(body, 8)  # frame_id
    pos += -pos % 4
    (count,) = struct.unpack_from('<I', body, pos)
    pos += 4
    out = []
    for _ in range(count):
        level = body[pos]
        pos += 1
        name, pos = _string(body, pos)
        message, pos = _string(body, pos)
        _, pos = _string(body, pos)  # hardware_id
        pos += -pos % 4
        (nv,) = struct.unpack_from('<I', body, pos)
        pos += 4
        values = {}
        for _ in range(nv):
            key, pos = _string(body, pos)
            value, pos = _string(body, pos)
            values[key] = value
        out.append((name, int(level), message, values))
    return sec * 1_000_000_000 + nsec, out


def read_results(path: Path) -> Counter:
    """The annunciations of a results log's ``/diagnostics`` (``replay --out``)."""
    from mcap.reader import make_reader

    counter = Counter()
    with open(path, 'rb') as f:
        reader = make_reader(f)
        for _, _, message in reader.iter_messages(topics=['/diagnostics'], log_time_order=True):
            stamp, statuses = decode_diagnostic_array(message.data)
            counter.take_rows(stamp, statuses)
    return counter
