"""The alarm journal: every state change of the alarms as one record (ISA-18.2's audit trail).

The monitor core (and its vectorized twin, from the same alarm states) writes an
:class:`AlarmEvent` whenever an alarm is raised (annunciated), acknowledged, becomes active or
clears, is shelved or unshelved (by whom, or ``expired``), starts or stops chattering, when a
request (shelving or acknowledging) is refused, and when an alarm flood starts or ends; and
whenever a component status (:data:`COMPONENTS`: the tide, the intake, ...) leaves OK, rises
or returns (:func:`component_entries`). The node prints them, the alarm report
(``catenary-monitor alarms``) counts them: one alarm logic, its records read twice. Times in s
on the monitor's clock.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from catenary_monitor.core.alarms.acknowledge import UNACKNOWLEDGED, AckState, shelved
from catenary_monitor.core.alarms.latches import Transition
from catenary_monitor.core.rules.level import RANK, Level

__all__ = ['AlarmEvent', 'KINDS', 'COMPONENTS', 'CONSEQUENCES', 'entries', 'raised',
           'component_entries']

#: The component statuses whose changes the journal records as alarms (the lines, ``sensors``
#: and the flood's ``alarms`` have their own records).
COMPONENTS = ('tide', 'intake', 'logger', 'fatigue', 'dock', 'clock', 'parameters')
#: The components whose STALE is a consequence of blind inputs, shown ``suppressed`` (the
#: ``sensors`` alarm announces the cause): leaving it for another level is leaving OK.
CONSEQUENCES = ('tide', 'dock')

#: Every kind of record, in the order :func:`entries` writes those of one step.
KINDS = (
    'active',
    'shelved',
    'unshelved',
    'refused',
    'raised',
    'acknowledged',
    'cleared',
    'chattering',
    'chattering_end',
    'flood',
    'flood_end',
)


class AlarmEvent(NamedTuple):
    """One record: ``time`` [s], the ``alarm`` (a line, ``sensors``, ``alarms`` for a flood),
    its ``kind`` (:data:`KINDS`), the level (``raised``), the condition (``raised``: the
    line's; ``shelved``/``unshelved``: the shelf's; ``flood``: the first out's), ``by``
    (``acknowledged``, ``shelved``, ``unshelved``, ``refused``: who; ``flood``: the first out
    alarm) and ``value``: ``acknowledged`` when the alarm was raised [s], ``shelved`` until
    when [s], ``unshelved`` since when it was shelved [s], ``cleared`` how long it was active
    [s], ``flood`` when the first out was raised [s]; NaN otherwise. ``refused`` holds the
    reason in ``condition``, ``level`` ``acknowledge`` for a refused acknowledgement ('' a
    shelving request) and ``value`` how many requests it stands for (NaN: one, refused by the
    shelving rules)."""

    time: float
    alarm: str
    kind: str
    level: str = ''
    condition: str = ''
    by: str = ''
    value: float = math.nan


def _differ(a: float, b: float) -> bool:
    return a != b and not (a != a and b != b)


def raised(old: AckState, new: AckState) -> bool:
    """Whether the alarm was raised (annunciated) between ``old`` and ``new`` (not when a
    shelf ends on an alarm back as it was shelved, raised when it was)."""
    if new.state != UNACKNOWLEDGED:
        return False
    if shelved(old) and not shelved(new) and not _differ(new.raised, old.raised):
        return False
    return old.state != UNACKNOWLEDGED or _differ(new.raised, old.raised)


def entries(
    alarm: str, old: AckState, new: AckState, now: float, condition: str = '', by: str = ''
) -> list[AlarmEvent]:
    """The records of one change of ``alarm`` from ``old`` to ``new`` at ``now`` [s]:
    ``condition`` the line's condition then (for ``raised``), ``by`` who ended a shelf
    (``expired`` when nobody did)."""
    if old is new:
        return []
    out = []
    if new.active_since == new.active_since and old.active_since != old.active_since:
        out.append(AlarmEvent(new.active_since, alarm, 'active'))
    if shelved(new) and _differ(new.shelved_at, old.shelved_at):
        out.append(
            AlarmEvent(
                now, alarm, 'shelved', condition=new.shelved_condition, by=new.shelved_by,
                value=new.shelved_until,
            )  # fmt: skip
        )
    elif shelved(old) and not shelved(new):
        out.append(
            AlarmEvent(
                now, alarm, 'unshelved', condition=old.shelved_condition, by=by or 'expired',
                value=old.shelved_at,
            )  # fmt: skip
        )
    if raised(old, new):
        out.append(AlarmEvent(now, alarm, 'raised', new.level.name, condition))
    if _differ(new.acknowledged_at, old.acknowledged_at):
        out.append(
            AlarmEvent(
                new.acknowledged_at, alarm, 'acknowledged', by=new.acknowledged_by,
                value=new.raised,
            )  # fmt: skip
        )
    if old.active_since == old.active_since and new.active_since != new.active_since:
        out.append(AlarmEvent(now, alarm, 'cleared', value=now - old.active_since))
    if new.chattering != old.chattering:
        out.append(AlarmEvent(now, alarm, 'chattering' if new.chattering else 'chattering_end'))
    return out


def component_entries(name: str, change: Transition) -> list[AlarmEvent]:
    """The records of a level ``change`` of the component status ``name``: ``active`` when it
    leaves OK, ``raised`` (its new level, condition ``NAME.LEVEL``, e.g. ``tide.warn``) when
    its level rises (OK < WARN < STALE < ERROR), ``cleared`` when it returns to OK (``value``
    how long it was not OK [s]); a change not announced (``change.suppressed``: a consequence
    of blind inputs, which the ``sensors`` alarm announces) is neither active nor raised, and
    leaving such a STALE (:data:`CONSEQUENCES`) for WARN is leaving OK, as ``/diagnostics``
    shows it (``alarm_state`` ``suppressed``, then ``active``)."""
    old, new, now = change.old, change.new, change.time
    out = []
    quiet = old == Level.OK or (old == Level.STALE and name in CONSEQUENCES)
    if quiet and new != Level.OK and not change.suppressed:
        out.append(AlarmEvent(now, name, 'active'))
    if (RANK[new] > RANK[old] or quiet and new != Level.OK) and not change.suppressed:
        out.append(AlarmEvent(now, name, 'raised', new.name, f'{name}.{new.name.lower()}'))
    if new == Level.OK and old != Level.OK:
        duration = math.nan if change.duration is None else change.duration
        out.append(AlarmEvent(now, name, 'cleared', value=duration))
    return out
