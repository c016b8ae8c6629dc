"""The component statuses as alarms an operator acknowledges (ISA-18.2; no rclpy, no clock).

Every component status the journal records as an alarm (:data:`COMPONENTS`: the tide, the
intake, the logger, the fatigue store, the dock estimate, the ROS clock, the runtime-change
flag) is annunciated when it leaves OK or rises, so each is acknowledgeable, with the states of
a line's alarm (:mod:`.acknowledge`): ``unacknowledged`` when it leaves OK or its severity
rises, ``acknowledged`` once an operator acknowledged it (the console stops beeping), back to
``normal`` when an acknowledged one returns to OK, ``returned-unacknowledged`` when it returned
before anyone acknowledged it (listed until acknowledged). The tide's and the dock's STALE under
blind inputs is suppressed by design (:data:`CONSEQUENCES`: the ``sensors`` alarm announces the
cause): not active, ``alarm_state`` ``suppressed``. A component alarm is not shelvable (loss of
monitoring and impossible inputs are not for a shelf; the rest clears itself).

The state of each is an :class:`~.acknowledge.AckState` stepped at every level change
(:func:`follow`); :func:`values` are its ``/diagnostics`` keys, the same names a line's alarm
publishes. Times in s on the monitor's clock.
"""

from __future__ import annotations

import math
from typing import Sequence

from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.alarms.acknowledge import AckState
from catenary_monitor.core.alarms.journal import COMPONENTS, CONSEQUENCES
from catenary_monitor.core.rules.level import Level

__all__ = ['COMPONENTS', 'KEYS', 'initial', 'follow', 'view', 'values', 'acknowledgeable']

#: The ``/diagnostics`` keys of a component's alarm (a line's names; ``alarm_state`` where the
#: tide and the dock already had it).
KEYS = (
    'alarm_state',
    'acknowledged',
    'alarm_raised',
    'acknowledged_at',
    'acknowledged_by',
    'acknowledged_publisher',
)


def acknowledgeable(name: str) -> bool:
    """Whether ``name`` is a component status an operator acknowledges."""
    return name in COMPONENTS


def initial(levels: Sequence[Level], start: float) -> tuple[AckState, ...]:
    """The components' alarms (:data:`COMPONENTS` order) when the monitor starts at ``start``
    [s] with their ``levels``: one not OK then (and not a suppressed STALE) is raised."""
    return tuple(
        follow(AckState(), name, level, start) for name, level in zip(COMPONENTS, levels)
    )


def follow(ack: AckState, name: str, level: Level, now: float) -> AckState:
    """The component ``name``'s alarm after its status moved to ``level`` at ``now`` [s]
    (idempotent at an unchanged level)."""
    suppressed = name in CONSEQUENCES and level == Level.STALE  # a WARN or ERROR never is
    return alarm_ack.step(ack, level, now, suppressed=suppressed)


def view(ack: AckState, name: str, level: Level) -> AckState:
    """The alarm as shown with the status at ``level`` (the runtime-change flag's WARN expires
    between its events: its alarm then shows as returned)."""
    if level == ack.level or ack.state == alarm_ack.NORMAL:
        return ack
    return follow(ack, name, level, math.nan) if level == Level.OK else ack


def values(ack: AckState, name: str, level: Level) -> tuple[tuple[str, str], ...]:
    """The ``/diagnostics`` keys (:data:`KEYS`) of the component ``name``'s alarm at
    ``level``: ``alarm_state`` (a line's states; ``suppressed`` for a consequence's STALE),
    ``acknowledged`` (``false`` while it waits for one), ``alarm_raised`` [s, NaN when
    normal], ``acknowledged_at`` [s], ``acknowledged_by``, ``acknowledged_publisher``."""
    ack = view(ack, name, level)
    state = ack.state
    if state == alarm_ack.NORMAL and name in CONSEQUENCES and level == Level.STALE:
        state = alarm_ack.SUPPRESSED
    pending = state in (alarm_ack.UNACKNOWLEDGED, alarm_ack.RETURNED_UNACKNOWLEDGED)
    raised = math.nan if ack.state == alarm_ack.NORMAL else ack.raised
    return (
        ('alarm_state', state),
        ('acknowledged', 'false' if pending else 'true'),
        ('alarm_raised', repr(float(raised))),
        ('acknowledged_at', repr(float(ack.acknowledged_at))),
        ('acknowledged_by', ack.acknowledged_by),
        ('acknowledged_publisher', ack.acknowledged_publisher),
    )
