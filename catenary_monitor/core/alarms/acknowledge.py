"""Alarm acknowledgement: each line's alarm in ISA-18.2 / IEC 62682 states (no rclpy, no clock).

One alarm per line, and one for the sensors' common causes (:data:`SENSORS`: the depth sensor
silent, lines that never reported since the start;
:func:`catenary_monitor.core.rules.health.sensors_status`).
A line's alarm is *active* while its level is not OK (WARN, STALE or ERROR), except while it is
**suppressed by design**: the line is STALE only because of a common cause (no depth, or no
tension ever received: :attr:`~catenary_monitor.core.alarms.latches.AlarmState.suppressed`), which
the one ``sensors`` alarm reports, raised once the silence outlasts its timeout. So a blind start
or a silent depth sensor is one alarm, not one per line; a tension sensor that goes silent after
it reported is its own line's alarm at once. Likewise a margin WARN that another line's parted
chain brought about (raised within ``parted_consequence_window`` of the part, while it stands):
the parted line's ERROR reports the cause; an ERROR is never suppressed.

States (:data:`STATES`, the names the ``/diagnostics`` key ``alarm_state`` and the console use):

``normal``
    not active, nothing to acknowledge;
``unacknowledged``
    active and not yet acknowledged (an operator has not seen it);
``acknowledged``
    active and acknowledged: it stays until the condition clears;
``returned-unacknowledged``
    the condition cleared before anyone acknowledged it: it stays listed until acknowledged;
``suppressed`` (shown in ``alarm_state`` only; stored as ``normal`` with ``suppressed`` set)
    not active because suppressed by design, nothing waiting for an acknowledgement.

``shelved`` (shown in ``alarm_state`` only; stored as ``normal`` with a shelf)
    an operator shelved the alarm (or one condition of it) until ``shelved_until``: the
    shelved conditions are computed and shown but not annunciated (ISA-18.2 shelving).

Rules: an alarm is raised (``unacknowledged``, ``raised`` = now) when it becomes active from
``normal`` or ``returned-unacknowledged``, and raised again when its severity rises while active
(WARN < STALE < ERROR: an acknowledged warning that becomes a lifted anchor is news). When it
stops being active, ``unacknowledged`` becomes ``returned-unacknowledged`` and ``acknowledged``
becomes ``normal``. An acknowledgement turns ``unacknowledged`` into ``acknowledged`` and
``returned-unacknowledged`` into ``normal``; it never clears an active alarm: only the condition
does. :func:`step` is idempotent (same level, same activity: no change), which is what lets the
vectorized twin (:mod:`catenary_monitor.core.twin.engine`) apply it only where its inputs change.

**Shelving** (:func:`shelve`, :func:`unshelve`; requests and rules in
:mod:`catenary_monitor.core.alarms.shelving`): the alarm follows the level its shelf leaves
visible (``masked``: the level without the shelved conditions); shelving takes the alarm off
the list when that level is not active. When the shelf ends (it expires at the first step at or
after ``shelved_until``, or an operator unshelves) and it was hiding an active condition, the
alarm returns ``unacknowledged``, raised again at that time, unless it was active when shelved
and never cleared since (nor rose in severity): then it returns to the state it was shelved in,
raised no more than it was, however often a shelf is put on and taken off.

**Chattering**: the alarm keeps the times of its newest ``chatter_count`` level changes
(``flips``); it is ``chattering`` while the oldest of them is at most ``chatter_window`` old
(ISA-18.2: 3 in 60 s), decided at every step. ``active_since`` is when the alarm's condition
(shelved or not, not suppressed) last became active: the alarm report's standing alarms.

Times are seconds on the monitor's clock.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Optional, Sequence

import numpy as np

from catenary_monitor.core.alarms.latches import CONDITIONS, ERROR_CONDITIONS
from catenary_monitor.core.rules.level import RANK, Level

_NAN = math.nan

__all__ = [
    'NORMAL',
    'UNACKNOWLEDGED',
    'ACKNOWLEDGED',
    'RETURNED_UNACKNOWLEDGED',
    'STATES',
    'ALL_LINES',
    'ACKNOWLEDGE_TOPIC',
    'AckState',
    'initial',
    'SUPPRESSED',
    'SENSORS',
    'step',
    'acknowledge',
    'condition',
    'diagnostic_values',
    'parse_request',
    'bounded_text',
    'publisher_identity',
    'console_only_refusal',
    'CONSOLE_NODE_PREFIX',
    'ORIGIN_LIMIT',
    'REQUEST_LIMIT',
    'AckSeries',
    'replay_acks',
    'SHELVED',
    'WHOLE',
    'shelved',
    'shelve',
    'unshelve',
    'chatter_flags',
]

NORMAL = 'normal'
UNACKNOWLEDGED = 'unacknowledged'
ACKNOWLEDGED = 'acknowledged'
RETURNED_UNACKNOWLEDGED = 'returned-unacknowledged'
#: ``alarm_state`` of a line whose alarm is suppressed by design (a view of ``normal``).
SUPPRESSED = 'suppressed'
#: The name of the sensors' common-cause alarm (a status on /diagnostics, acknowledged as a line).
SENSORS = 'sensors'
#: ``alarm_state`` of an alarm whose shelf leaves nothing to annunciate (a view of ``normal``).
SHELVED = 'shelved'
#: ``shelved_condition`` of a shelf over the whole alarm (every shelvable condition).
WHOLE = 'all'
#: Every alarm state, in display order of urgency.
STATES = (UNACKNOWLEDGED, RETURNED_UNACKNOWLEDGED, ACKNOWLEDGED, NORMAL)
#: The line "name" of an acknowledgement of every line.
ALL_LINES = 'all'
#: The node's acknowledgement topic (std_msgs/msg/String: ``LINE|all [ORIGIN...]``).
ACKNOWLEDGE_TOPIC = '/catenary_monitor/acknowledge'
#: The node name of a console (``catenary_console_PID``): with ``acknowledge_from_ros`` false
#: the node takes acknowledgements only from such a node.
CONSOLE_NODE_PREFIX = 'catenary_console'
#: Characters kept of an acknowledgement's origin and of its publisher's identity.
ORIGIN_LIMIT = 160
#: Characters of an acknowledgement message read at most (the rest is never looked at).
REQUEST_LIMIT = 1024


@dataclass(frozen=True)
class AckState:
    """One line's alarm: its state, severity, when raised, the last acknowledgement (s, the
    origin it claimed, ``acknowledged_publisher``: who published it as the middleware saw it).

    ``level`` is the alarm's current severity while active, its last one after it returned;
    ``suppressed`` is True while the line's level is not OK only by a common cause (suppressed
    by design: not active).
    """

    state: str = NORMAL
    level: Level = Level.OK
    raised: float = math.nan
    acknowledged_at: float = math.nan
    acknowledged_by: str = ''
    suppressed: bool = False
    acknowledged_publisher: str = ''
    shelved_until: float = math.nan  # s; NaN: not shelved
    shelved_at: float = math.nan  # s, when the shelf was put on
    shelved_by: str = ''  # the origin the shelving request claimed
    shelved_publisher: str = ''  # who published it, as the middleware saw it
    shelved_condition: str = ''  # the conditions shelved (joined by ','), or WHOLE; '' not
    shelved_state: str = ''  # the alarm's state when shelved ('' not shelved)
    flips: tuple[float, ...] = ()  # s, the newest chatter_count level changes
    chattering: bool = False
    active_since: float = math.nan  # s, since when the condition is active; NaN: not active


def initial(start: float) -> AckState:
    """A line's alarm when the monitor starts at ``start`` (s): normal (the line is blind, its
    STALE suppressed by design: the ``sensors`` alarm says it once that is late)."""
    return AckState(suppressed=True)


#: The chattering rule by default: (chatter_count, chatter_window [s]).
CHATTER = (3, 60.0)


def shelved(ack: AckState) -> bool:
    """Whether the alarm is shelved."""
    return ack.shelved_until == ack.shelved_until


def step(
    ack: AckState,
    level: Level,
    now: float,
    suppressed: bool = False,
    masked: Optional[Level] = None,
    flip: bool = False,
    chatter: tuple[int, float] = CHATTER,
) -> AckState:
    """The alarm after the line was stepped to ``level`` at ``now`` (s).

    ``suppressed``: the level is a consequence of a common cause reported by another alarm
    (not active); ``masked``: the level the alarm's shelf leaves visible (None: ``level``);
    ``flip``: the level changed at this step (an announced change); ``chatter``:
    (chatter_count, chatter_window [s]).
    """
    ack = _watch(ack, level, now, suppressed, flip, chatter)
    if not shelved(ack):
        return _follow(ack, level, now, suppressed)
    shown = level if masked is None else masked
    if now >= ack.shelved_until:
        return unshelve(ack, now, level, shown, suppressed)
    return _follow(ack, shown, now, suppressed)


def _watch(
    ack: AckState,
    level: Level,
    now: float,
    suppressed: bool,
    flip: bool,
    chatter: tuple[int, float],
) -> AckState:
    """The alarm's chattering and activity after a step (whatever its shelf)."""
    count, window = chatter
    flips = (ack.flips + (now,))[-count:] if flip else ack.flips
    chattering = len(flips) >= count and now - flips[-count] <= window
    active = level != Level.OK and not _quiet(suppressed, level)
    since = (ack.active_since if ack.active_since == ack.active_since else now) if active else _NAN
    if flips is ack.flips and chattering == ack.chattering and _same(since, ack.active_since):
        return ack
    return replace(ack, flips=flips, chattering=chattering, active_since=since)


def _same(a: float, b: float) -> bool:
    return a == b or (a != a and b != b)


def _quiet(suppressed: bool, level: Level) -> bool:
    """Whether ``level`` is suppressed by design: ``suppressed`` applies to a STALE (blind
    inputs' common cause) or a WARN (a parted chain's consequence) only, never an ERROR."""
    return suppressed and level in (Level.STALE, Level.WARN)


def _follow(ack: AckState, level: Level, now: float, suppressed: bool) -> AckState:
    """The alarm's state machine on the level it annunciates (see the module docstring);
    ``suppressed`` applies to a STALE or WARN level only (:func:`_quiet`)."""
    suppressed = _quiet(suppressed, level)
    if suppressed != ack.suppressed:
        ack = replace(ack, suppressed=suppressed)
    active = level != Level.OK and not suppressed
    if active:
        if ack.state in (NORMAL, RETURNED_UNACKNOWLEDGED) or RANK[level] > RANK[ack.level]:
            return replace(ack, state=UNACKNOWLEDGED, level=level, raised=now)
        return ack if level == ack.level else replace(ack, level=level)
    if ack.state == UNACKNOWLEDGED:
        return replace(ack, state=RETURNED_UNACKNOWLEDGED)
    if ack.state == ACKNOWLEDGED:
        return replace(ack, state=NORMAL)
    return ack


def shelve(
    ack: AckState,
    now: float,
    until: float,
    condition: str,
    origin: str,
    masked: Level,
    suppressed: bool = False,
    publisher: str = '',
) -> AckState:
    """The alarm shelved at ``now`` until ``until`` (s) by ``origin`` (as claimed; published by
    ``publisher``, both bounded): ``condition`` is :data:`WHOLE` or conditions (joined by
    ``,``); ``masked`` the level the shelf leaves visible. An alarm whose visible level is not
    active leaves the list (``normal``, shown ``shelved``)."""
    before = ack.state
    if shelved(ack):  # shelved again: as it was before the first shelf, unless it cleared since
        still = ack.active_since == ack.active_since and ack.active_since <= ack.shelved_at
        before = ack.shelved_state if still else NORMAL
    ack = replace(
        ack,
        shelved_until=until,
        shelved_at=now,
        shelved_by=bounded_text(origin),
        shelved_publisher=bounded_text(publisher),
        shelved_condition=condition,
        shelved_state=before,
    )
    if masked == Level.OK or _quiet(suppressed, masked):
        ack = replace(ack, state=NORMAL)
    return _follow(ack, masked, now, suppressed)


def unshelve(
    ack: AckState, now: float, level: Level, masked: Level, suppressed: bool = False
) -> AckState:
    """The alarm's shelf ended at ``now`` (s; expired, or an operator unshelved it): ``level``
    the line's level, ``masked`` what the shelf left visible. An active condition the shelf hid
    returns the alarm ``unacknowledged``, raised at ``now``; but an alarm that was active when
    shelved and never cleared under the shelf, no more severe now, returns as it was then
    (``unacknowledged`` since it was raised, or ``acknowledged``): a shelf toggled on and off
    raises nothing that was not raised before."""
    before, since = ack.shelved_state, ack.shelved_at
    ack = replace(
        ack,
        shelved_until=_NAN,
        shelved_at=_NAN,
        shelved_by='',
        shelved_publisher='',
        shelved_condition='',
        shelved_state='',
    )
    quiet = _quiet(suppressed, level)
    if RANK[level] > RANK[masked] and level != Level.OK and not quiet:
        held = (
            before in (UNACKNOWLEDGED, ACKNOWLEDGED)
            and ack.active_since == ack.active_since
            and ack.active_since <= since
            and RANK[level] <= RANK[ack.level]
        )
        if held:
            state = before if ack.state == NORMAL else ack.state
            return replace(ack, state=state, level=level, suppressed=False)
        return replace(ack, state=UNACKNOWLEDGED, level=level, raised=now, suppressed=False)
    return _follow(ack, level, now, suppressed)


def acknowledge(ack: AckState, now: float, origin: str, publisher: str = '') -> AckState:
    """The alarm after an operator acknowledged it at ``now`` (s) from ``origin`` (as claimed),
    published by ``publisher`` (the middleware's identity of the sender); both kept bounded
    (:func:`bounded_text`)."""
    if ack.state not in (UNACKNOWLEDGED, RETURNED_UNACKNOWLEDGED):
        return ack
    state = ACKNOWLEDGED if ack.state == UNACKNOWLEDGED else NORMAL
    return replace(
        ack,
        state=state,
        acknowledged_at=now,
        acknowledged_by=bounded_text(origin),
        acknowledged_publisher=bounded_text(publisher),
    )


def condition(level: Level, latches: Sequence[bool]) -> str:
    """The condition that sets the line's level: an ERROR's name (``uplift``, ``input`` for an
    impossible input, ``sensor_error``, ``dragging``), ``stale``, a warning's name
    (``anchor_margin``, ...) or ``none`` when OK.

    ``latches`` are the active flags of :data:`~catenary_monitor.core.alarms.latches.CONDITIONS`.
    """
    if level == Level.ERROR:
        for name, up in zip(CONDITIONS, latches):
            if up and name in ERROR_CONDITIONS:
                return name
        return 'input'
    if level == Level.STALE:
        return 'stale'
    if level == Level.WARN:
        for name, up in zip(CONDITIONS, latches):
            if up and name not in ERROR_CONDITIONS:
                return name
    return 'none'


def diagnostic_values(
    ack: AckState, level: Level, latches: Sequence[bool]
) -> list[tuple[str, str]]:
    """The ``/diagnostics`` keys of a line's alarm: ``acknowledged`` (``true`` unless something
    waits for an acknowledgement), ``alarm_state``, ``alarm_raised`` [s, NaN when normal],
    ``alarm_condition``, ``acknowledged_at`` [s], ``acknowledged_by`` (the last one's origin, as
    it claimed) and ``acknowledged_publisher`` (who published it, as the middleware saw it),
    then ``shelved`` (``true``/``false``), ``shelved_until`` [s, NaN when not],
    ``shelved_condition`` (the conditions shelved, joined by ``,``; ``all`` for the sensors
    alarm), ``shelved_by``, ``shelved_publisher`` and
    ``chattering`` (``true``/``false``)."""
    pending = ack.state in (UNACKNOWLEDGED, RETURNED_UNACKNOWLEDGED)
    raised = math.nan if ack.state == NORMAL else ack.raised
    state = ack.state
    if ack.state == NORMAL:
        state = SHELVED if shelved(ack) else (SUPPRESSED if ack.suppressed else NORMAL)
    return [
        ('acknowledged', 'false' if pending else 'true'),
        ('alarm_state', state),
        ('alarm_raised', repr(float(raised))),
        ('alarm_condition', condition(level, latches)),
        ('acknowledged_at', repr(float(ack.acknowledged_at))),
        ('acknowledged_by', ack.acknowledged_by),
        ('acknowledged_publisher', ack.acknowledged_publisher),
        ('shelved', 'true' if shelved(ack) else 'false'),
        ('shelved_until', repr(float(ack.shelved_until))),
        ('shelved_condition', ack.shelved_condition),
        ('shelved_by', ack.shelved_by),
        ('shelved_publisher', ack.shelved_publisher),
        ('chattering', 'true' if ack.chattering else 'false'),
    ]


def bounded_text(text: str, limit: int = ORIGIN_LIMIT) -> str:
    """``text`` as one printable line of at most ``limit`` characters: runs of white space
    become one space, other unprintable characters ``?``; a longer text is cut, ending in
    ``...``. Idempotent."""
    head = text[: 4 * limit]
    clean = ''.join(c if c.isprintable() else '?' for c in ' '.join(head.split()))
    if len(clean) > limit or len(text) > 4 * limit:
        return clean[: limit - 3] + '...'
    return clean


def parse_request(text: str) -> tuple[Optional[str], str]:
    """(line name, or None for every line; origin) of an acknowledgement message's text:
    ``LINE [ORIGIN...]`` or ``all [ORIGIN...]``; the origin defaults to ``ros``. Only the first
    :data:`REQUEST_LIMIT` characters are read; the origin is bounded (:func:`bounded_text`).

    Raises ValueError for an empty text."""
    parts = text[:REQUEST_LIMIT].strip().split(None, 1)
    if not parts:
        raise ValueError('empty acknowledgement (expected "LINE [ORIGIN]" or "all [ORIGIN]")')
    origin = bounded_text(parts[1]) if len(parts) > 1 else 'ros'
    return (None if parts[0] == ALL_LINES else parts[0]), origin


def publisher_identity(endpoints: Sequence[tuple[str, bytes]]) -> str:
    """Who published an acknowledgement, from the publishers on the topic as the middleware
    lists them (``(node's full name, GID)`` each): ``/NODE gid 01.0f...``; with several,
    ``one of N: ...`` (rclpy in Jazzy gives no sender GID per message); ``unknown`` for none."""
    named = [f'{node} gid {".".join(f"{b:02x}" for b in gid[:16])}' for node, gid in endpoints]
    if not named:
        return 'unknown (no publisher on the topic)'
    if len(named) == 1:
        return named[0]
    return bounded_text(f'one of {len(named)}: ' + '; '.join(sorted(named)))


def console_only_refusal(endpoints: Sequence[tuple[str, bytes]]) -> Optional[str]:
    """Why an acknowledgement is refused where only a console may acknowledge
    (``acknowledge_from_ros`` false), or None: every publisher on the topic must be a console
    node (:data:`CONSOLE_NODE_PREFIX`), so a message cannot have come from another one."""
    others = sorted({node for node, _ in endpoints if not _is_console(node)})
    if not endpoints:
        return 'its publisher is not on the ROS graph'
    if others:
        return bounded_text(
            'acknowledge_from_ros is false and not only consoles publish on the topic: '
            + ', '.join(others),
            240,
        )
    return None


def _is_console(node: str) -> bool:
    return node.rsplit('/', 1)[-1].startswith(CONSOLE_NODE_PREFIX)


class AckSeries:
    """A line's alarm over a sequence of steps, as :func:`step` at every one of them gives.

    ``changes`` are the step indexes where :func:`step` was applied (where the level or the
    suppression changes; elsewhere it would change nothing) and ``states`` the alarm after each.
    """

    def __init__(self, before: AckState, changes: np.ndarray, states: list[AckState]) -> None:
        self.before, self.changes, self.states = before, changes, states

    def at(self, i: int) -> AckState:
        """The alarm after step ``i`` (``before`` for ``i < 0``)."""
        j = int(np.searchsorted(self.changes, i, 'right')) - 1 if i >= 0 else -1
        return self.before if j < 0 else self.states[j]

    @property
    def final(self) -> AckState:
        """The alarm after the last step."""
        return self.states[-1] if self.states else self.before


def chatter_flags(
    before: tuple[float, ...], times: np.ndarray, flip: np.ndarray, chatter: tuple[int, float]
) -> np.ndarray:
    """Per step at ``times`` (s): chattering after it, as :func:`step` decides, given the
    changes ``before`` (the alarm's ``flips``) and ``flip`` (bool per step)."""
    count, window = chatter
    n = len(times)
    if not len(before) and not flip.any():
        return np.zeros(n, bool)
    flips = np.concatenate([np.asarray(before, np.float64), times[flip]])
    k = len(before) + np.cumsum(flip) - count  # the count-th newest change so far
    ok = k >= 0
    oldest = flips[np.clip(k, 0, max(len(flips) - 1, 0))] if len(flips) else np.zeros(n)
    return ok & (times - oldest <= window)


def replay_acks(
    before: AckState,
    times: np.ndarray,
    levels: np.ndarray,
    suppressed: Optional[np.ndarray] = None,
    masked: Optional[np.ndarray] = None,
    flip_at: Optional[np.ndarray] = None,
    chatter: tuple[int, float] = CHATTER,
) -> AckSeries:
    """The alarm over steps at ``times`` (s) with the line's ``levels`` (int Level per step)
    and ``suppressed`` flags (bool per step; None: none), from ``before``, with no
    acknowledgement or shelving request among them: ``masked`` the levels ``before``'s shelf
    leaves visible (None: no shelf), ``flip_at`` the steps whose level change is announced.
    :func:`step` is applied where its inputs change (it is idempotent elsewhere: a level,
    suppression, visible level, chattering or activity change, a flip, the shelf's expiry),
    so the result equals stepping every one."""
    n = len(times)
    if n == 0:
        return AckSeries(before, np.zeros(0, np.int64), [])
    quiet = np.zeros(n, bool) if suppressed is None else np.asarray(suppressed, bool)
    flip = np.zeros(n, bool)
    if flip_at is not None:
        flip[flip_at] = True
    chat = chatter_flags(before.flips, times, flip, chatter)
    change = np.ones(n, dtype=bool)
    change[1:] = (quiet[1:] != quiet[:-1]) | (levels[1:] != levels[:-1]) | (chat[1:] != chat[:-1])
    change |= flip
    shelf = shelved(before)
    if shelf and masked is not None:
        change[1:] |= masked[1:] != masked[:-1]
        end = int(np.searchsorted(times, before.shelved_until, 'left'))
        if end < n:
            change[end] = True
    idx = np.flatnonzero(change)
    states, state = [], before
    for i in idx.tolist():
        shown = Level(int(masked[i])) if masked is not None and shelved(state) else None
        state = step(
            state,
            Level(int(levels[i])),
            float(times[i]),
            bool(quiet[i]),
            shown,
            bool(flip[i]),
            chatter,
        )
        states.append(state)
    return AckSeries(before, idx, states)
