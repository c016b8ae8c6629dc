"""The alarm report's counting (replay/alarm_report.py) on journal records written by hand:
10-minute periods on the clock, the flood share, standing alarms (one still open at the end
included), time shelved across a renewed shelf, a monitor restart ending what was open, the
``--since``/``--until`` period, and the command's one-line errors."""

from __future__ import annotations

import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from replay_data import dock_config
from ros_harness import child_env

from catenary_monitor.core.alarms.journal import AlarmEvent
from catenary_monitor.core.monitor.events import Start
from catenary_monitor.replay.alarm_report import AlarmReport

T0 = 1_764_000_000.0  # a multiple of 600 s: periods start at T0, T0 + 600, ...
DAY = 86400.0


def _window(records, ticks, starts=()):
    """A replay window's result as the report reads it."""
    return SimpleNamespace(
        tick_ns=(np.asarray(ticks) * 1e9).astype(np.int64),
        events=[Start(int(t * 1e9)) for t in starts],
        alarm_events=records,
    )


def test_periods_floods_standing_shelves_and_restarts():
    report = AlarmReport(dock_config(2))
    ticks = np.arange(T0, T0 + 2 * DAY + 1200.0, 60.0)  # two days and two periods
    raised = [T0 + 10, T0 + 20, T0 + 30, T0 + 610, T0 + 1300]
    records = [AlarmEvent(t, 'line_01', 'raised', 'WARN', 'anchor_margin') for t in raised]
    records += [
        AlarmEvent(T0 + 5, 'line_02', 'active'),
        AlarmEvent(T0 + 25, 'alarms', 'flood', 'WARN', by='line_01', value=T0 + 10),
        AlarmEvent(T0 + 700, 'alarms', 'flood_end', value=675.0),
        AlarmEvent(T0 + 100, 'line_01', 'shelved', condition='all', by='a', value=T0 + 400),
        AlarmEvent(T0 + 300, 'line_01', 'shelved', condition='all', by='b', value=T0 + 900),
        AlarmEvent(T0 + 900, 'line_01', 'unshelved', condition='all', by='expired', value=T0),
        AlarmEvent(T0 + 40, 'line_01', 'acknowledged', by='op', value=T0 + 30),
        AlarmEvent(T0 + 1000, 'line_01', 'chattering'),
    ]
    records.sort(key=lambda e: e.time)
    report(_window(records, ticks), None)
    # A restart a day and a half later: line_02's activity and line_01's chattering end there.
    report(_window([], [], starts=[T0 + 1.5 * DAY]), None)
    f = report.figures()
    assert f['periods'] == len(np.unique(np.floor(ticks / 600.0)))
    # the five raises and the flood status's WARN (heard on /diagnostics as a raise)
    assert f['annunciated'] == 6 and f['per_10min_peak'] == 4
    assert f['per_10min_mean'] == pytest.approx(6 / f['periods'])
    assert f['components']['alarms']['annunciated'] == 1
    assert f['flood_share'] == pytest.approx(2 / f['periods'])  # the flood spans two periods
    assert f['floods'] == 1 and f['flood_s'] == pytest.approx(675.0)
    one, two = f['lines']['line_01'], f['lines']['line_02']
    assert one['shelved'] == 2 and one['shelved_s'] == pytest.approx(800.0)  # renewed shelf
    assert one['acknowledged'] == 1 and one['mean_time_to_acknowledge'] == pytest.approx(10.0)
    assert one['chattering'] == 1
    assert one['chattering_s'] == pytest.approx(1.5 * DAY - 1000.0)
    assert two['standing'] == 1 and two['longest_active_s'] == pytest.approx(1.5 * DAY - 5.0)
    assert f['standing_alarms'] == 1
    assert f['most_frequent'][0] == {
        'alarm': 'line_01', 'condition': 'anchor_margin', 'level': 'WARN', 'count': 5,
    }  # fmt: skip
    # The period asked for: the second day only.
    day2 = AlarmReport(dock_config(2), since=T0 + DAY, until=T0 + 2 * DAY)
    day2(_window(records, ticks), None)
    g = day2.figures()
    assert g['annunciated'] == 0 and g['periods'] == 144 and g['flood_share'] == 0.0


def test_an_activity_still_open_at_the_end_counts_when_standing():
    report = AlarmReport(dock_config(1))
    ticks = np.arange(T0, T0 + 1.2 * DAY, 600.0)
    report(_window([AlarmEvent(T0 + 1, 'line_01', 'active')], ticks), None)
    f = report.figures()
    assert f['lines']['line_01']['standing'] == 1 and f['standing_alarms'] == 1
    assert f['targets']['standing']['verdict'] == 'met'  # fewer than 5


def test_the_command_fails_with_one_line(tmp_path):
    def run(*args):
        return subprocess.run(
            [sys.executable, '-m', 'catenary_monitor.cli.main', 'alarms', *args],
            capture_output=True, text=True, env=child_env(), timeout=60,
        )  # fmt: skip

    done = run(str(tmp_path / 'nothing'))
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert done.stderr.startswith('catenary-monitor alarms: ')
    (tmp_path / 'empty.mcap').write_bytes(b'')
    done = run(str(tmp_path / 'empty.mcap'))
    assert done.returncode in (2, 3) and len(done.stderr.strip().splitlines()) == 1, done.stderr
    done = run(str(tmp_path), '--since', 'yesterday')
    assert done.returncode == 2 and 'not a time' in done.stderr
