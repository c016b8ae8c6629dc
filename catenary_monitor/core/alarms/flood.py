"""Alarm floods (EEMUA 191, ISA-18.2): more than ``flood_count`` alarms raised within
``flood_window``, the monitor's ``catenary_monitor: alarms`` status.

Every alarm raised (annunciated: a line's, the sensors'; not a shelved or suppressed one) is
counted with its time. The monitor decides at every event that raised one and at every tick:
the count is of the raises in the last ``flood_window`` s (``now - window < t <= now``); more
than ``flood_count`` is a flood (WARN), which names its *first out*, the oldest raise of the
window whose alarm is still active when the flood began (the alarm most likely to be its
cause: never one that returned, such as the start-up wait; :func:`first_out`). The count is a
function of the raise times, so the vectorized twin makes it on columns (:func:`counts`) and
gets the same transitions. Times in s.
"""

from __future__ import annotations

import math
from typing import Collection, NamedTuple, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import AlarmConfig
from catenary_monitor.core.rules.level import Level

__all__ = ['NAME', 'Flood', 'initial', 'decide', 'first_out', 'status', 'values', 'counts']

#: The status's name (``catenary_monitor: alarms``).
NAME = 'alarms'
_NAN = math.nan


class Flood(NamedTuple):
    """What the flood decision carries: the raises of the window as of the last decision
    (time [s], alarm), in order; when the flood began [s] (NaN: no flood); its first out
    (alarm, raised at [s]; ``('', nan)`` outside a flood)."""

    recent: tuple[tuple[float, str], ...] = ()
    since: float = _NAN
    first_out: tuple[str, float] = ('', _NAN)


def initial() -> Flood:
    """No raise yet, no flood."""
    return Flood()


def first_out(
    recent: Sequence[tuple[float, str]], active: Collection[str]
) -> tuple[str, float]:
    """A flood's first out: the oldest raise (alarm, time [s]) of ``recent`` (time, alarm),
    in order, whose alarm is ``active`` when the flood begins; ``('', nan)`` when every one
    returned."""
    for t, alarm in recent:
        if alarm in active:
            return alarm, t
    return '', _NAN


def decide(
    flood: Flood,
    raised: Sequence[tuple[float, str]],
    now: float,
    config: AlarmConfig,
    active: Collection[str] = (),
) -> Flood:
    """The decision at ``now`` [s] after the ``raised`` (time, alarm) of this event; ``active``
    the alarms active now (the first out is one of them)."""
    cut = now - config.flood_window
    recent = tuple(r for r in (*flood.recent, *raised) if r[0] > cut)
    if len(recent) <= config.flood_count:
        return Flood(recent)
    if flood.since == flood.since:
        return Flood(recent, flood.since, flood.first_out)
    return Flood(recent, now, first_out(recent, active))


def status(flood: Flood, config: AlarmConfig) -> tuple[Level, str]:
    """The status's level and message: OK with the count, WARN in a flood naming the first out."""
    n, window, limit = len(flood.recent), config.flood_window, int(config.flood_count)
    word = 'alarm' if n == 1 else 'alarms'
    if flood.since != flood.since:
        return (
            Level.OK,
            f'{n} {word} raised in the last {window:g} s (a flood is more than {limit})',
        )
    return (
        Level.WARN,
        f'ALARM FLOOD: {n} {word} raised in the last {window:g} s (more than {limit}); '
        f'first out: {flood.first_out[0] or "none still active"}',
    )


def values(
    flood: Flood, config: AlarmConfig, answer: str, requests: int
) -> tuple[tuple[str, str], ...]:
    """The status's ``/diagnostics`` values: ``flood`` (true/false), ``alarms_in_window``,
    ``flood_since`` [s], ``first_out``, ``first_out_at`` [s] (NaN, '' outside a flood), then
    the shelving rules any client may read (``shelve_max`` [s], ``unshelvable_conditions``,
    comma-separated) and the monitor's answer to the newest shelving request
    (``shelve_answer``, ``shelve_requests``: how many it answered)."""
    in_flood = flood.since == flood.since
    return (
        ('flood', 'true' if in_flood else 'false'),
        ('alarms_in_window', str(len(flood.recent))),
        ('flood_since', repr(float(flood.since))),
        ('first_out', flood.first_out[0]),
        ('first_out_at', repr(float(flood.first_out[1]))),
        ('shelve_max', repr(float(config.shelve_max))),
        ('unshelvable_conditions', ','.join(config.unshelvable_conditions)),
        ('shelve_answer', answer),
        ('shelve_requests', str(requests)),
    )


def counts(
    raised: np.ndarray, hi: np.ndarray, at: np.ndarray, window: float
) -> tuple[np.ndarray, np.ndarray]:
    """Per decision at ``at`` [s], given ``hi`` (the raises made up to it): (index of the
    oldest raise in its window, number of raises in it), ``raised`` the raise times [s] in
    order."""
    lo = np.minimum(np.searchsorted(raised, at - window, 'right'), hi)
    return lo, hi - lo
