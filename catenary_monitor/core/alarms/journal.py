"""The alarm journal: every state change of the alarms as one record (ISA-18.2's audit trail).

The monitor core (and its vectorized twin, from the same alarm states) writes an
:class:`AlarmEvent` whenever an alarm is raised (annunciated), acknowledged, becomes active or
clears, is shelved or unshelved (by whom, or ``expired``), starts or stops chattering, when a
request (shelving or acknowledging) is refused, and when an alarm flood starts or ends. The
node prints them, the alarm report (``catenary-monitor alarms``) counts them: one alarm logic,
its records read
twice. Times in s on the monitor's clock.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from catenary_monitor.core.alarms.acknowledge import UNACKNOWLEDGED, AckState, shelved

__all__ = ['AlarmEvent', 'KINDS', 'entries', 'raised']

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
