"""The alarm report: how the alarm system performed over any period of logs (ISA-18.2 / IEC
62682 and EEMUA 191 performance figures), counted from the alarm journal.

The logs are replayed by the one replay driver (:mod:`catenary_monitor.replay.driver`), so the
monitor core and its twin decide every alarm, shelf, chattering and flood again from the
recorded inputs and operator events, exactly as the node did live; :class:`AlarmReport` is a
sink that only counts their journal records
(:mod:`catenary_monitor.core.alarms.journal`), window by window: its memory is a few
counters per alarm and one per 10-minute period, whatever the length of the logs.

Figures, overall and per alarm (each line's and the sensors'): alarms raised (annunciated; a
shelved or suppressed condition is not) per 10-minute period, mean and peak; the share of
10-minute periods in which the monitor's flood status was raised; the most frequent alarms;
chattering episodes; standing alarms (active longer than 24 h); time to acknowledge; time
shelved. Each is set against the standards' targets (:data:`TARGETS`). Times are s (Unix);
periods are aligned on multiples of ``period`` s (UTC clock: 12:00, 12:10, ...).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Iterable, Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import MonitorConfig
from catenary_monitor.core.alarms.acknowledge import SENSORS
from catenary_monitor.core.alarms.journal import AlarmEvent
from catenary_monitor.core.monitor.events import Start
from catenary_monitor.core.twin.engine import ReplayResult
from catenary_monitor.core.twin.window import Window

__all__ = ['AlarmReport', 'TARGETS', 'STANDING_S', 'PERIOD_S', 'report_text']

#: The report's period [s] (ISA-18.2 and EEMUA 191 count alarms per 10 minutes).
PERIOD_S = 600.0
#: An alarm active longer than this is standing (ISA-18.2's stale alarm: 24 h).
STANDING_S = 86400.0
#: The targets each figure is set against: ISA-18.2 (IEC 62682) Table 5 and EEMUA 191.
TARGETS = {
    'per_10min_mean': 'about 1 per 10 min is very likely acceptable, about 2 the most manageable',
    'per_10min_peak': 'at most 10 in any 10 min (more is a flood)',
    'flood_share': 'below 1 % of the 10-minute periods in flood',
    'chattering': 'none',
    'standing': 'fewer than 5 at any time',
}


@dataclass
class _Tally:
    """What the report counts of one alarm."""

    raised: int = 0
    bins: Counter[int] = field(default_factory=Counter)
    acknowledged: int = 0
    ack_sum: float = 0.0
    ack_max: float = 0.0
    shelved: int = 0
    shelved_s: float = 0.0
    shelf_open: Optional[float] = None
    refused: int = 0
    chattering: int = 0
    chattering_s: float = 0.0
    chatter_open: Optional[float] = None
    standing: int = 0
    longest_active_s: float = 0.0
    active_open: Optional[float] = None

    def close(self, t: float, standing_s: float) -> None:
        """End what is open at ``t`` [s] (a restart of the monitor, the end of the logs)."""
        if self.shelf_open is not None:
            self.shelved_s += max(t - self.shelf_open, 0.0)
            self.shelf_open = None
        if self.chatter_open is not None:
            self.chattering_s += max(t - self.chatter_open, 0.0)
            self.chatter_open = None
        if self.active_open is not None:
            self.active(max(t - self.active_open, 0.0), standing_s)
            self.active_open = None

    def active(self, seconds: float, standing_s: float) -> None:
        """An activity of ``seconds`` ended."""
        self.longest_active_s = max(self.longest_active_s, seconds)
        if seconds > standing_s:
            self.standing += 1


class AlarmReport:
    """A replay sink (:func:`catenary_monitor.replay.driver.drive`) counting the alarm journal
    of every window; :meth:`figures` gives the report.

    ``since``/``until`` [s]: only what happened in that period is counted (default: all).
    """

    def __init__(
        self,
        config: MonitorConfig,
        period: float = PERIOD_S,
        standing: float = STANDING_S,
        top: int = 10,
        since: Optional[float] = None,
        until: Optional[float] = None,
    ) -> None:
        self.config, self.period, self.standing_s, self.top = config, period, standing, top
        self.since = -math.inf if since is None else since
        self.until = math.inf if until is None else until
        self.names = [line.name for line in config.lines] + [SENSORS]
        self.abandon()

    def abandon(self) -> None:
        """Forget what was counted (the driver replays the logs again)."""
        self.tallies = {name: _Tally() for name in self.names}
        self.bins: Counter[int] = Counter()
        self.monitored: set[int] = set()
        self.flood_bins: set[int] = set()
        self.flood_open: Optional[float] = None
        self.floods = 0
        self.flood_s = 0.0
        self.frequent: Counter[tuple[str, str, str]] = Counter()
        self.start: Optional[float] = None
        self.end: Optional[float] = None
        self.records = 0

    def __call__(self, result: ReplayResult, window: Window) -> None:
        """Take one window's results."""
        ticks = np.asarray(result.tick_ns, np.int64) * 1e-9
        ticks = ticks[(ticks >= self.since) & (ticks < self.until)]
        if len(ticks):
            self.monitored.update(np.unique(np.floor(ticks / self.period)).astype(int).tolist())
            first, last = float(ticks[0]), float(ticks[-1])
            self.start = first if self.start is None else min(self.start, first)
            self.end = last if self.end is None else max(self.end, last)
        restarts = [e.stamp_ns * 1e-9 for e in result.events if isinstance(e, Start)]
        self.take(result.alarm_events, restarts)

    def take(self, records: Iterable[AlarmEvent], restarts: Sequence[float] = ()) -> None:
        """Count journal ``records`` (time order); a monitor restart at each of ``restarts``
        [s] ends what was open (a restarted monitor starts with no shelf, no alarm)."""
        pending = sorted(restarts)
        for e in records:
            while pending and pending[0] <= e.time:
                self._restart(pending.pop(0))
            if self.since <= e.time < self.until:
                self._take(e)
        for t in pending:
            self._restart(t)

    def _restart(self, t: float) -> None:
        for tally in self.tallies.values():
            tally.close(t, self.standing_s)
        self._flood_end(t)

    def _take(self, e: AlarmEvent) -> None:
        self.records += 1
        if e.alarm == 'alarms':
            if e.kind == 'flood':
                self.floods += 1
                self.flood_open = e.time
            elif e.kind == 'flood_end':
                self._flood_end(e.time)
            return
        tally = self.tallies.get(e.alarm)
        if tally is None:
            return
        t = e.time
        if e.kind == 'raised':
            tally.raised += 1
            k = int(math.floor(t / self.period))
            tally.bins[k] += 1
            self.bins[k] += 1
            self.frequent[(e.alarm, e.condition, e.level)] += 1
        elif e.kind == 'acknowledged' and e.value == e.value:
            took = max(t - e.value, 0.0)
            tally.acknowledged += 1
            tally.ack_sum += took
            tally.ack_max = max(tally.ack_max, took)
        elif e.kind == 'shelved':
            tally.shelved += 1
            tally.shelf_open = t if tally.shelf_open is None else tally.shelf_open
        elif e.kind == 'unshelved' and tally.shelf_open is not None:
            tally.shelved_s += max(t - tally.shelf_open, 0.0)
            tally.shelf_open = None
        elif e.kind == 'refused' and not e.level:  # a shelving request's (NaN: one)
            tally.refused += int(e.value) if e.value == e.value else 1
        elif e.kind == 'chattering':
            tally.chattering += 1
            tally.chatter_open = t
        elif e.kind == 'chattering_end' and tally.chatter_open is not None:
            tally.chattering_s += max(t - tally.chatter_open, 0.0)
            tally.chatter_open = None
        elif e.kind == 'active':
            if tally.active_open is not None:  # a restart the records did not say
                tally.active(t - tally.active_open, self.standing_s)
            tally.active_open = t
        elif e.kind == 'cleared' and tally.active_open is not None:
            tally.active(e.value, self.standing_s)
            tally.active_open = None

    def _flood_end(self, t: float) -> None:
        if self.flood_open is None:
            return
        self.flood_s += max(t - self.flood_open, 0.0)
        lo, hi = int(math.floor(self.flood_open / self.period)), int(math.floor(t / self.period))
        self.flood_bins.update(range(lo, hi + 1))
        self.flood_open = None

    # ------------------------------------------------------------------ the figures
    def figures(self) -> dict[str, Any]:
        """The report (JSON-ready; None where a figure has no value): see the module docstring
        and docs/alarm_report.md."""
        end = self.end if self.end is not None else 0.0
        tallies = {name: _closed(t, end, self.standing_s) for name, t in self.tallies.items()}
        flood_bins = set(self.flood_bins)
        flood_s = self.flood_s
        if self.flood_open is not None:
            flood_s += max(end - self.flood_open, 0.0)
            lo = int(math.floor(self.flood_open / self.period))
            flood_bins.update(range(lo, int(math.floor(end / self.period)) + 1))
        periods = len(self.monitored)
        total = sum(t.raised for t in tallies.values())
        mean = total / periods if periods else None
        peak = max(self.bins.values(), default=0)
        share = len(flood_bins & self.monitored) / periods if periods else None
        alarms = {name: self._alarm(t, periods) for name, t in tallies.items()}
        chattering = sum(1 for t in tallies.values() if t.chattering)
        standing = sum(t.standing for t in tallies.values())
        return {
            'period_s': self.period,
            'start': self.start,
            'end': self.end,
            'periods': periods,
            'monitored_s': periods * self.period,
            'annunciated': total,
            'per_10min_mean': mean,
            'per_10min_peak': peak,
            'per_hour_mean': None if mean is None else mean * 3600.0 / self.period,
            'flood_share': share,
            'floods': self.floods,
            'flood_s': flood_s,
            'flood_rule': {
                'flood_count': self.config.alarm.flood_count,
                'flood_window': self.config.alarm.flood_window,
            },
            'chattering_alarms': chattering,
            'standing_alarms': standing,
            'most_frequent': [
                {'alarm': a, 'condition': c, 'level': lv, 'count': n}
                for (a, c, lv), n in sorted(self.frequent.items(), key=lambda kv: (-kv[1], kv[0]))[
                    : self.top
                ]
            ],
            'targets': self._targets(mean, peak, share, chattering, standing),
            'lines': {name: alarms[name] for name in self.names if name != SENSORS},
            'sensors': alarms[SENSORS],
            'per_10min': self.series(),
        }

    def series(self) -> dict[str, list[Any]]:
        """Raises per monitored 10-minute period: ``start`` [s] and ``count``; ``flood``
        whether the flood status was raised in it."""
        bins = sorted(self.monitored)
        end = self.end if self.end is not None else 0.0
        flood = set(self.flood_bins)
        if self.flood_open is not None:
            lo = int(math.floor(self.flood_open / self.period))
            flood.update(range(lo, int(math.floor(end / self.period)) + 1))
        return {
            'start': [k * self.period for k in bins],
            'count': [self.bins.get(k, 0) for k in bins],
            'flood': [k in flood for k in bins],
        }

    def _alarm(self, t: _Tally, periods: int) -> dict[str, Any]:
        return {
            'annunciated': t.raised,
            'per_10min_mean': t.raised / periods if periods else None,
            'per_10min_peak': max(t.bins.values(), default=0),
            'chattering': t.chattering,
            'chattering_s': t.chattering_s,
            'standing': t.standing,
            'longest_active_s': t.longest_active_s,
            'acknowledged': t.acknowledged,
            'mean_time_to_acknowledge': t.ack_sum / t.acknowledged if t.acknowledged else None,
            'max_time_to_acknowledge': t.ack_max if t.acknowledged else None,
            'shelved': t.shelved,
            'shelved_s': t.shelved_s,
            'shelve_refused': t.refused,
        }

    def _targets(
        self,
        mean: Optional[float],
        peak: int,
        share: Optional[float],
        chattering: int,
        standing: int,
    ) -> dict[str, dict[str, Any]]:
        def verdict_mean() -> Optional[str]:
            if mean is None:
                return None
            return (
                'acceptable'
                if mean <= 1.0
                else ('manageable' if mean <= 2.0 else 'over-demanding')
            )

        limit = int(self.config.alarm.flood_count)
        return {
            'per_10min_mean': {'value': mean, 'target': TARGETS['per_10min_mean'],
                               'verdict': verdict_mean()},  # fmt: skip
            'per_10min_peak': {'value': peak, 'target': TARGETS['per_10min_peak'],
                               'verdict': 'met' if peak <= limit else 'not met'},  # fmt: skip
            'flood_share': {'value': share, 'target': TARGETS['flood_share'],
                            'verdict': None if share is None else
                            ('met' if share < 0.01 else 'not met')},  # fmt: skip
            'chattering': {'value': chattering, 'target': TARGETS['chattering'],
                           'verdict': 'met' if chattering == 0 else 'not met'},  # fmt: skip
            'standing': {'value': standing, 'target': TARGETS['standing'],
                         'verdict': 'met' if standing < 5 else 'not met'},  # fmt: skip
        }


def _closed(t: _Tally, end: float, standing_s: float) -> _Tally:
    """A copy of ``t`` with what is still open ended at ``end`` [s]."""
    c = _Tally(**{**t.__dict__, 'bins': t.bins})
    c.close(end, standing_s)
    return c


def _num(value: Optional[float], digits: int = 2, scale: float = 1.0) -> str:
    return '-' if value is None else f'{value / scale:.{digits}f}'


def report_text(figures: dict[str, Any]) -> str:
    """The report as a table (the figures of ``--json``, rounded, with the targets)."""
    from datetime import datetime, timezone

    def when(t: Optional[float]) -> str:
        if t is None:
            return '-'
        return datetime.fromtimestamp(t, timezone.utc).strftime('%Y-%m-%d %H:%M UTC')

    f = figures
    tg = f['targets']
    share = f['flood_share']
    lines = [
        f'alarm report {when(f["start"])} .. {when(f["end"])}: {f["periods"]} periods of '
        f'{f["period_s"] / 60:g} min monitored',
        f'  alarms raised (annunciated)   {f["annunciated"]}',
        f'  per 10 min, mean              {_num(f["per_10min_mean"])}   '
        f'[{tg["per_10min_mean"]["verdict"] or "-"}: {TARGETS["per_10min_mean"]}]',
        f'  per 10 min, peak              {f["per_10min_peak"]}   '
        f'[{tg["per_10min_peak"]["verdict"]}: {TARGETS["per_10min_peak"]}]',
        f'  periods in flood              '
        f'{"-" if share is None else f"{100 * share:.2f} %"} ({f["floods"]} floods, '
        f'{f["flood_s"] / 60:.1f} min)   [{tg["flood_share"]["verdict"] or "-"}: '
        f'{TARGETS["flood_share"]}]',
        f'  chattering alarms             {f["chattering_alarms"]}   '
        f'[{tg["chattering"]["verdict"]}: {TARGETS["chattering"]}]',
        f'  standing alarms (> 24 h)      {f["standing_alarms"]}   '
        f'[{tg["standing"]["verdict"]}: {TARGETS["standing"]}]',
        '',
        f'{"alarm":<12} {"raised":>7} {"/10min":>7} {"peak":>5} {"chatter":>8} {"standing":>9} '
        f'{"ack":>5} {"mean TTA s":>11} {"shelved":>8} {"shelved h":>10}',
    ]
    rows = dict(f['lines'])
    rows[SENSORS] = f['sensors']
    for name, a in rows.items():
        lines.append(
            f'{name:<12} {a["annunciated"]:>7} {_num(a["per_10min_mean"]):>7} '
            f'{a["per_10min_peak"]:>5} {a["chattering"]:>8} {a["standing"]:>9} '
            f'{a["acknowledged"]:>5} {_num(a["mean_time_to_acknowledge"], 1):>11} '
            f'{a["shelved"]:>8} {_num(a["shelved_s"], 2, 3600.0):>10}'
        )
    if f['most_frequent']:
        lines += ['', 'most frequent alarms:']
        for m in f['most_frequent']:
            lines.append(f'  {m["count"]:>6}  {m["alarm"]} {m["condition"]} ({m["level"]})')
    return '\n'.join(lines)
