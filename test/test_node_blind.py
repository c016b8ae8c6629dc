"""A blind start-up and a silent depth sensor are one alarm each, live (the node as a process).

Twelve lines, nothing published: the node prints one ``ALARM sensors`` line once the tensions
are late (not at t = 0 and not one per line), and when the data come no line announces its
return from that blindness. The depth sensor going silent later is one more ``sensors`` alarm,
the lines STALE but suppressed by design; a single load cell going silent after it reported is
its own line's alarm. Every wait is bounded; no sleep is an assertion.
"""

from __future__ import annotations

import re

import pytest
from ros_harness import Client, callback_errors, output_of, start_monitor, stop, write_params

pytestmark = pytest.mark.ros

LINES = {
    f'line_{k:02d}': dict(weight=1300.0, anchor_distance=120.0, mbl=4.827e6)
    for k in range(1, 13)
}
TENSION_TIMEOUT = 3.0  # s
DEPTH_TIMEOUT = 4.0  # s
STALE = 3
_ALARM = re.compile(r'ALARM (\S+): (\S+) -> (\S+): (.*)$')


def alarms(proc, skip: int = 0) -> list[tuple[str, str, str, str]]:
    """The ``ALARM NAME: OLD -> NEW: message`` lines the node printed (after the first
    ``skip``)."""
    found = [_ALARM.search(line) for line in output_of(proc).splitlines()]
    return [m.groups() for m in found if m][skip:]


def test_blind_start_then_silent_depth_then_one_silent_load_cell(tmp_path):
    params = write_params(
        tmp_path / 'params.yaml',
        LINES,
        key='/**',
        tension_timeout=TENSION_TIMEOUT,
        depth_timeout=DEPTH_TIMEOUT,
        diagnostic_rate=2.0,
    )
    callback_errors()  # (of earlier tests' monitors)
    client = Client('blind_test_client')
    proc = start_monitor(params, tmp_path / 'log')
    try:
        # 1. Blind start-up: one alarm, raised once the tensions are late, not one per line.
        client.wait_for(lambda: alarms(proc), 60.0, 'the first ALARM line')
        first = alarms(proc)
        assert len(first) == 1, first
        name, old, new, message = first[0]
        assert (name, old, new) == ('sensors', 'OK', 'STALE'), first
        assert message.startswith('waiting for sensors: no tension from all 12 lines'), message
        status = client.wait_status('catenary_monitor: line_03', 10.0, STALE)
        assert status['message'].startswith('blind: no tension received yet')
        assert 'suppressed by design' in status['message']
        assert status['values']['alarm_state'] == 'suppressed'
        sensors = client.wait_status('catenary_monitor: sensors', 10.0, STALE)
        assert sensors['values']['alarm_state'] == 'unacknowledged'
        tide = client.wait_status('catenary_monitor: tide', 10.0, STALE)
        assert tide['values']['sensor_state'] == 'no_data'
        # The data come: the return of the sensors alarm, no line announces its own.
        client.feed('/tide/depth', 20.85)
        for line in LINES:
            client.feed(f'/mooring/{line}/tension', 372e3)
        client.wait_status('catenary_monitor: sensors', 30.0, 0)
        for line in LINES:
            client.wait_status(f'catenary_monitor: {line}', 30.0, 0)
        client.wait_for(lambda: len(alarms(proc)) >= 2, 10.0, 'the sensors alarm returning')
        start_up = alarms(proc)
        assert [a[:3] for a in start_up] == [
            ('sensors', 'OK', 'STALE'),
            ('sensors', 'STALE', 'OK'),
        ], start_up
        # 2. The depth sensor goes silent: one alarm; the lines STALE, suppressed by design.
        client.feed('/tide/depth', None)
        client.wait_for(lambda: len(alarms(proc)) > 2, 30.0, 'the depth alarm')
        status = client.wait_status('catenary_monitor: line_07', 10.0, STALE)
        assert status['message'].startswith('blind: depth stale')
        assert status['values']['alarm_state'] == 'suppressed'
        depth_gone = alarms(proc, skip=2)
        assert [a[:3] for a in depth_gone] == [('sensors', 'OK', 'STALE')], depth_gone
        assert depth_gone[0][3].startswith('depth sensor silent: all 12 lines blind')
        client.feed('/tide/depth', 20.85)
        client.wait_status('catenary_monitor: line_07', 30.0, 0)
        client.wait_for(lambda: len(alarms(proc)) > 3, 10.0, 'the depth alarm returning')
        # 3. One load cell goes silent after it reported: its own line's alarm.
        client.feed('/mooring/line_05/tension', None)
        client.wait_for(
            lambda: any(a[0] == 'line_05' for a in alarms(proc)), 30.0, "line_05's own alarm"
        )
        own = [a for a in alarms(proc, skip=4) if a[2] != 'OK']
        assert [a[:3] for a in own] == [('line_05', 'OK', 'STALE')], own
        assert own[0][3].startswith('tension stale: last sample')
        status = client.wait_status('catenary_monitor: line_05', 10.0, STALE)
        assert status['values']['alarm_state'] == 'unacknowledged'
    finally:
        for topic in list(client.feeds):
            client.feed(topic, None)
        stop(proc)
        client.close()
    errors = callback_errors()  # a callback that failed fails the test, even if it went on
    assert not errors, errors[:3]
