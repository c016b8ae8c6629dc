"""Shelving an alarm (ISA-18.2 / IEC 62682): requests, the rules, what a shelf hides.

An operator shelves conditions of a line's alarm for a bounded time (``shelve_max``): the
shelved conditions are still computed, logged and shown, but not annunciated. A shelf is of
conditions, never of a whole line: ``LINE SECONDS`` shelves the conditions active at the request
(recorded in the shelf, ``shelved_condition`` ``anchor_margin,sensor_warn``), so a new, different
condition on a shelved line is annunciated; with none active it is refused. Conditions in
``unshelvable_conditions`` (default: ``uplift``, ``input``, ``sensor_error``, ``stale``,
``dragging`` and ``sensors``, the common-cause alarm: what endangers the dock or blinds the
monitor) are never hidden: a request naming one is refused, and a line shelf asked while one is
active is refused. The states themselves (the shelf
on the alarm, its expiry returning the alarm unacknowledged) are
:mod:`catenary_monitor.core.alarms.acknowledge`'s; the monitor core applies the requests
(:class:`~catenary_monitor.core.monitor.events.Shelve` events) and records them.

Requests: ``std_msgs/msg/String`` on :data:`SHELVE_TOPIC`, data ``LINE SECONDS [ORIGIN...]``
or ``LINE.CONDITION SECONDS [ORIGIN...]`` (``sensors`` for the sensors' common-cause alarm;
0 seconds unshelves). Conditions are the names of ``alarm_condition``
(:data:`catenary_monitor.core.config.parameters.ALARM_CONDITIONS`: ``uplift``, ``input``,
``stale``, ``anchor_margin``, ...). Times in s.
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple, Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import ALARM_CONDITIONS, AlarmConfig
from catenary_monitor.core.alarms.acknowledge import REQUEST_LIMIT, SENSORS, WHOLE, bounded_text
from catenary_monitor.core.alarms.latches import CONDITIONS, ERROR_CONDITIONS
from catenary_monitor.core.rules.level import Level

__all__ = [
    'SHELVE_TOPIC',
    'ShelveRequest',
    'parse_request',
    'hidden_conditions',
    'active_conditions',
    'masked_level',
    'masked_levels',
    'refusal',
    'label',
]

#: The node's shelving topic (std_msgs/msg/String: ``LINE[.CONDITION] SECONDS [ORIGIN...]``).
SHELVE_TOPIC = '/catenary_monitor/shelve'
_ERRORS = ERROR_CONDITIONS


class ShelveRequest(NamedTuple):
    """A shelving request: the alarm (a line name or ``sensors``), the condition
    (:data:`~catenary_monitor.core.alarms.acknowledge.WHOLE` for the whole alarm), the
    duration [s] (0: unshelve) and who asked."""

    alarm: str
    condition: str
    seconds: float
    origin: str


def parse_request(text: str) -> ShelveRequest:
    """The request of a shelving message's text (ValueError with one line when it is not
    ``LINE[.CONDITION] SECONDS [ORIGIN...]``), as an acknowledgement's is read: only its first
    :data:`~catenary_monitor.core.alarms.acknowledge.REQUEST_LIMIT` characters, the origin
    (default ``ros``) and the names bounded
    (:func:`~catenary_monitor.core.alarms.acknowledge.bounded_text`)."""
    parts = text[:REQUEST_LIMIT].strip().split(None, 2)
    usage = 'expected "LINE[.CONDITION] SECONDS [ORIGIN]" (0 seconds unshelves)'
    if len(parts) < 2:
        raise ValueError(f'incomplete shelving request {text[:80]!r}: {usage}')
    target, seconds_text = parts[0], parts[1]
    try:
        seconds = float(seconds_text)
    except ValueError:
        raise ValueError(f'not a duration: {seconds_text[:40]!r}: {usage}') from None
    if not math.isfinite(seconds) or seconds < 0.0:
        raise ValueError(f'the duration must be finite and >= 0 s, got {seconds_text[:40]!r}')
    alarm, _, condition = bounded_text(target, 120).partition('.')
    origin = bounded_text(parts[2]) if len(parts) > 2 else 'ros'
    return ShelveRequest(alarm, condition or WHOLE, seconds, origin or 'ros')


def hidden_conditions(condition: str, unshelvable: Sequence[str]) -> frozenset[str]:
    """The conditions a shelf of ``condition`` (one condition, several joined by ``,``, or
    :data:`WHOLE`: every one) hides: never an unshelvable one."""
    if condition == WHOLE:
        return frozenset(c for c in ALARM_CONDITIONS if c not in unshelvable)
    return frozenset(condition.split(',')) - frozenset(unshelvable)


def active_conditions(
    active: Sequence[bool], stale: bool, unshelvable: Sequence[str]
) -> tuple[str, ...]:
    """The shelvable conditions active on a line (``active``: its latch flags in
    :data:`~catenary_monitor.core.alarms.latches.CONDITIONS` order; ``stale``: an input stale):
    what a line shelf (``LINE SECONDS``) covers."""
    up = [c for c, on in zip(CONDITIONS, active) if on]
    up += ['stale'] if stale else []
    return tuple(c for c in up if c not in unshelvable)


def masked_level(active: Sequence[bool], stale: bool, hidden: frozenset[str]) -> Level:
    """The line's level without the ``hidden`` conditions (``active``: the latches' flags in
    :data:`~catenary_monitor.core.alarms.latches.CONDITIONS` order; ``stale``: an input stale),
    by the level rule ERROR > STALE > WARN > OK."""
    up = {cond for cond, on in zip(CONDITIONS, active) if on and cond not in hidden}
    if up & set(_ERRORS):
        return Level.ERROR
    if stale and 'stale' not in hidden:
        return Level.STALE
    return Level.WARN if up else Level.OK


def masked_levels(
    active: Mapping[str, np.ndarray], stale: np.ndarray, hidden: frozenset[str]
) -> np.ndarray:
    """:func:`masked_level` per step (int8): ``active`` condition -> bool per step."""
    n = len(stale)
    err = np.zeros(n, bool)
    warn = np.zeros(n, bool)
    for cond in CONDITIONS:
        if cond in hidden:
            continue
        if cond in _ERRORS:
            err |= active[cond]
        else:
            warn |= active[cond]
    levels = np.where(warn, np.int8(Level.WARN), np.int8(Level.OK))
    if 'stale' not in hidden:
        np.copyto(levels, np.int8(Level.STALE), where=stale)
    np.copyto(levels, np.int8(Level.ERROR), where=err)
    return levels


def label(condition: str) -> str:
    """A condition as an operator reads it: ``uplift ERROR``, ``stale STALE``,
    ``anchor_margin WARN``."""
    level = 'ERROR' if condition in _ERRORS else ('STALE' if condition == 'stale' else 'WARN')
    return f'{condition} {level}'


def refusal(
    request: ShelveRequest,
    lines: Sequence[str],
    config: AlarmConfig,
    active: Optional[Sequence[bool]] = None,
    stale: bool = False,
) -> Optional[str]:
    """Why ``request`` is refused (one line), or None: an unknown alarm or condition, every
    alarm at once, too long, shelving disabled, an unshelvable condition or alarm (the
    ``sensors`` one), a line shelf over an active unshelvable condition or with nothing active
    to shelve (``active``: the line's latch flags, ``stale``: an input stale)."""
    alarm, cond = request.alarm, request.condition
    if alarm == 'all':
        return 'shelve one alarm at a time (LINE or LINE.CONDITION), not all'
    if alarm not in lines and alarm != SENSORS:
        return f'unknown alarm {alarm!r} (alarms: {", ".join([*lines, SENSORS])})'
    if request.seconds == 0.0:
        return None  # unshelving is always allowed
    if config.shelve_max == 0.0:
        return 'shelving is disabled (shelve_max 0 s)'
    if request.seconds > config.shelve_max:
        return f'{request.seconds:g} s is longer than shelve_max ({config.shelve_max:g} s)'
    unshelvable = ', '.join(config.unshelvable_conditions) or 'none'
    if alarm == SENSORS:
        if cond != WHOLE:
            return 'the sensors alarm has no conditions: shelve "sensors"'
        if SENSORS in config.unshelvable_conditions:
            return (
                'the sensors common-cause alarm (loss of monitoring) cannot be shelved '
                f'(unshelvable_conditions: {unshelvable})'
            )
        return None
    if cond != WHOLE and cond not in ALARM_CONDITIONS:
        return f'unknown condition {cond!r} (conditions: {", ".join(ALARM_CONDITIONS)})'
    if cond in config.unshelvable_conditions:
        return (
            f'{alarm}: the {label(cond)} cannot be shelved '
            f'(unshelvable_conditions: {unshelvable})'
        )
    if cond == WHOLE and active is not None:
        for name, on in zip(CONDITIONS, active):
            if on and name in config.unshelvable_conditions:
                return (
                    f'{alarm}: its active {label(name)} cannot be shelved '
                    f'(unshelvable_conditions: {unshelvable}); shelve one other condition '
                    f'as {alarm}.CONDITION'
                )
        if not active_conditions(active, stale, config.unshelvable_conditions):
            return (
                f'{alarm}: nothing active to shelve (a shelf covers the conditions active at '
                f'the request); shelve one condition as {alarm}.CONDITION'
            )
    return None
