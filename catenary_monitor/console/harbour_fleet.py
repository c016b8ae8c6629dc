"""The fleet's daily KPIs per dock for the harbour page, read from the fleet dataset.

``catenary-monitor fleet ... --out RESULTS`` writes ``RESULTS/episodes`` and ``RESULTS/daily``
per dock and UTC day (:mod:`catenary_monitor.replay.fleet_dataset`). For each harbour dock whose
name is a dock of the dataset (``dock=NAME``), per day, newest last:

``day``
    the UTC date (``YYYY-MM-DD``);
``covered_s``
    the seconds of that day the logs cover (the largest, over its lines, of the seconds at
    every level);
``alarms``, ``alarms_per_10min``
    the alarm episodes (WARN or ERROR at worst, of a line, the tide, the sensors or the dock;
    not the alarm system's own flood status) that began that day, and per 10 minutes covered;
``time_in_alarm_s``
    the seconds of that day within at least one such episode (their union, clipped to the day;
    one still active at the end of the logs counts until the latest time its episodes know);
``fatigue``
    the largest accumulated fatigue damage (Miner's sum) of its lines at the end of the day;
    ``fatigue_line`` that line.

The dataset is read again at most every :data:`REFRESH_S` seconds, so the page's frames cost
nothing. A dataset that cannot be read gives one line (``error``) instead of the KPIs.
"""

from __future__ import annotations

import calendar
import math
import threading
import time
from pathlib import Path
from typing import Any, Optional, Sequence

__all__ = ['FleetKpis', 'dock_kpis', 'REFRESH_S', 'DAYS']

#: Seconds between two readings of the dataset.
REFRESH_S = 300.0
#: Days per dock kept for the page (the newest).
DAYS = 7
_ALARM_LEVELS = ('WARN', 'ERROR')
_NOT_ALARMS = ('alarms',)


def _read(folder: Path) -> list[dict[str, Any]]:
    """Every row of a dock's dataset folder (``date=YYYY-MM-DD/*.parquet``), each with its
    ``date`` from the folder name."""
    import pyarrow.parquet as pq

    rows: list[dict[str, Any]] = []
    for part in sorted(folder.glob('date=*/*.parquet')):
        date = part.parent.name[len('date='):]
        for row in pq.read_table(part).to_pylist():
            rows.append({**row, 'date': date})
    return rows


def _day_bounds(date: str) -> tuple[float, float]:
    """The UTC day ``date`` as [start, end) s since the epoch."""
    start = float(calendar.timegm(time.strptime(date, '%Y-%m-%d')))
    return start, start + 86_400.0


def _union_in(intervals: list[tuple[float, float]], lo: float, hi: float) -> float:
    """Seconds of ``[lo, hi)`` within at least one of ``intervals``."""
    total, reach = 0.0, lo
    for a, b in sorted((max(a, lo), min(b, hi)) for a, b in intervals):
        if b <= a or b <= reach:
            continue
        total += b - max(a, reach)
        reach = b
    return total


def dock_kpis(root: Path, dock: str, days: int = DAYS) -> list[dict[str, Any]]:
    """The dock's daily KPIs (module doc), its ``days`` newest days, oldest first; [] when the
    dataset has no such dock."""
    daily = _read(root / 'daily' / f'dock={dock}')
    episodes = _read(root / 'episodes' / f'dock={dock}')
    alarms = [
        e for e in episodes if e['worst'] in _ALARM_LEVELS and e['component'] not in _NOT_ALARMS
    ]
    ends = [e['end'] for e in episodes if e['end'] is not None]
    log_end = max([*ends, *(e['start'] for e in episodes)], default=math.inf)
    intervals = [(e['start'], e['end'] if e['end'] is not None else log_end) for e in alarms]
    out = []
    for date in sorted({row['date'] for row in daily})[-days:]:
        rows = [r for r in daily if r['date'] == date]
        covered = max(
            sum(r.get(f'seconds_{lv}') or 0.0 for lv in ('ok', 'warn', 'error', 'stale'))
            for r in rows
        )
        lo, hi = _day_bounds(date)
        began = sum(1 for e in alarms if lo <= e['start'] < hi)
        damaged = [(r['fatigue_damage_max'], r['line']) for r in rows if r['fatigue_damage_max']]
        fatigue, line = max(damaged, default=(None, None))
        out.append(
            {
                'day': date,
                'covered_s': covered,
                'alarms': began,
                'alarms_per_10min': began / (covered / 600.0) if covered > 0 else None,
                'time_in_alarm_s': _union_in(intervals, lo, hi),
                'fatigue': fatigue,
                'fatigue_line': line,
            }
        )
    return out


class FleetKpis:
    """Every harbour dock's KPIs from the dataset ``root``, read at most every
    :data:`REFRESH_S` s (a callable for :class:`.harbour_source.HarbourSource`)."""

    def __init__(self, root: str, docks: Sequence[str]) -> None:
        self.root, self.docks = Path(root), list(docks)
        self._lock = threading.Lock()
        self._read_at = -math.inf
        self._kpis: dict[str, Any] = {}
        self.error: Optional[str] = None

    def __call__(self) -> dict[str, Any]:
        with self._lock:
            if time.monotonic() - self._read_at >= REFRESH_S:
                self._read_at = time.monotonic()
                self._refresh()
            return self._kpis

    def _refresh(self) -> None:
        kpis: dict[str, Any] = {}
        for dock in self.docks:
            try:
                kpis[dock] = dock_kpis(self.root, dock)
            except Exception as err:  # noqa: BLE001 - a damaged file is one line on its tile
                kpis[dock] = {'error': f'fleet dataset {self.root}: {type(err).__name__}: {err}'}
        self._kpis = kpis
