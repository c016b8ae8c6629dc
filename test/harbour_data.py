"""A small fleet dataset written with the fleet's own writers (``fleet_dataset``), for the
harbour's KPIs: dock ``north``, two UTC days, lines l1 and l2 (see :data:`EXPECTED`)."""

from __future__ import annotations

import calendar
import time
from pathlib import Path

import numpy as np

DAY = '2026-12-01'
BEFORE = '2026-11-30'
D = float(calendar.timegm(time.strptime(DAY, '%Y-%m-%d')))

#: What the harbour must make of it, per day (oldest first).
EXPECTED = [
    # the ERROR episode that began the day before: one alarm, 100 s of it in that day
    {'day': BEFORE, 'covered_s': 3600.0, 'alarms': 1, 'alarms_per_10min': 1 / 6,
     'time_in_alarm_s': 100.0, 'fatigue': 1.0e-4, 'fatigue_line': 'l2'},
    # two overlapping WARN episodes (1000 s together), the ERROR's last 200 s, and one still
    # active at the end of the logs (D + 5000 to the last end, D + 5400); the flood status
    # is not an alarm
    {'day': DAY, 'covered_s': 86400.0, 'alarms': 3, 'alarms_per_10min': 3 / 144,
     'time_in_alarm_s': 1600.0, 'fatigue': 3.0e-4, 'fatigue_line': 'l2'},
]  # fmt: skip


def write_kpi_dataset(root: Path) -> Path:
    """The dataset under ``root`` (RESULTS): episodes and daily of dock ``north``."""
    from catenary_monitor.core.rules.level import Level
    from catenary_monitor.replay.fleet_dataset import (
        DailyExtremes,
        episodes_table,
        replace_dock_tables,
    )

    def episode(component, name, start, end, worst):
        duration = None if end is None else end - start
        return dict(component=component, name=name, start=start, end=end,
                    duration=duration, worst=worst, message=f'{name} {worst}')  # fmt: skip

    rows = [
        episode('line', 'l1', D - 100.0, D + 200.0, 'ERROR'),
        episode('line', 'l1', D + 1000.0, D + 1600.0, 'WARN'),
        episode('line', 'l2', D + 1300.0, D + 2000.0, 'WARN'),
        episode('alarms', 'alarms', D + 1000.0, D + 5400.0, 'WARN'),
        episode('sensors', 'sensors', D + 5000.0, None, 'WARN'),
    ]
    dates = np.asarray(
        [time.strftime('%Y-%m-%d', time.gmtime(r['start'])) for r in rows], dtype=object
    )
    day, before = int(D // 86_400), int(D // 86_400) - 1
    daily = DailyExtremes(['l1', 'l2'])
    daily.cells = {
        (0, before): {'messages': 10, 'fatigue_damage_max': 0.5e-4},
        (1, before): {'messages': 10, 'fatigue_damage_max': 1.0e-4},
        (0, day): {'messages': 10, 'fatigue_damage_max': 1.5e-4},
        (1, day): {'messages': 10, 'fatigue_damage_max': 3.0e-4},
    }
    seconds = {
        (0, before): {Level.OK: 3500.0, Level.ERROR: 100.0},
        (1, before): {Level.OK: 3600.0},
        (0, day): {Level.OK: 80000.0, Level.WARN: 6400.0},
        (1, day): {Level.OK: 86000.0},
    }
    tables = {'episodes': (episodes_table(rows), dates), 'daily': (daily.table(seconds), None)}
    replace_dock_tables(root, 'north', tables)
    return root
