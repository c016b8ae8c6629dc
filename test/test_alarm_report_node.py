"""Alarm management on the running node, and the alarm report of its log (one scripted run).

The monitor runs as a process on six lines; a test node publishes a scripted dock: a steady
warning that is shelved over ROS and is still active when the shelf expires (it must come back
unacknowledged), an acknowledged warning, a lifted anchor whose uplift ERROR an operator tries
to shelve (refused with a message), a chattering load cell (its link drops out and comes back),
and a storm that raises enough alarms to flood. Then ``catenary-monitor alarms LOG_DIR --json``
replays the log, and its figures must equal an independent count from the ``/diagnostics``
arrays the node recorded, read with rosbags (not this package's reader).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest
from ros_harness import Client, child_env, output_of, start_monitor, stop, write_params

from catenary_monitor.core.alarms.shelving import SHELVE_TOPIC

LINES = [f'line_0{k}' for k in range(1, 7)]
OK_T, WARN_T, LIFT_T = 372e3, 450e3, 500e3  # N: anchor margin 15.5 m, 4.1 m (< 5), uplift
PERIOD = 600.0
RATE = 2.0  # Hz, diagnostic_rate


def _diag(name: str) -> str:
    return f'catenary_monitor: {name}'


def _tension(line: str) -> str:
    return f'/mooring/{line}/tension'


@pytest.fixture(scope='module')
def scripted_run(tmp_path_factory: Any) -> Any:
    """Run the script once; (the log folder, the client's arrays, the node's output, facts)."""
    import rclpy
    from rclpy.qos import QoSProfile
    from std_msgs.msg import String

    tmp = tmp_path_factory.mktemp('alarm_run')
    params = write_params(
        tmp / 'params.yaml',
        {name: dict(weight=1300.0, anchor_distance=120.0, mbl=4.827e6) for name in LINES},
        warn_clear_hold=0.5,
        margin_clear_hold=0.5,
        clear_hold=1.0,
        tension_timeout=3.0,
        # a lone line's STALE at its timeout: the chattering cell's 3.6 s dropouts stay STALE
        common_cause_window=0.0,
        depth_timeout=10.0,
        diagnostic_rate=RATE,
        chatter_count=3.0,
        chatter_window=20.0,
        flood_count=5.0,
        flood_window=60.0,
        shelve_max=60.0,
    )
    log_dir = tmp / 'log'
    proc = start_monitor(params, log_dir)
    client = Client('alarm_report_client')
    operator = rclpy.create_node('bridge_operator')
    shelve = operator.create_publisher(String, SHELVE_TOPIC, QoSProfile(depth=10))
    ack = operator.create_publisher(String, '/catenary_monitor/acknowledge', QoSProfile(depth=10))
    facts: dict[str, Any] = {}

    def state(line: str) -> Any:
        return client.latest_status(_diag(line)) or {'values': {}, 'level': -1}

    try:
        topics = [_tension(line) for line in LINES] + ['/tide/depth']
        client.wait_matched(topics, 60.0)
        client.wait_for(lambda: shelve.get_subscription_count() > 0, 30.0, 'the shelve topic')
        for line in LINES:
            client.feed(_tension(line), OK_T)
        client.feed('/tide/depth', 20.85)
        for line in LINES:
            client.wait_status(_diag(line), 30.0, level=0)
        # A steady warning, shelved for 6 s over ROS: still active when the shelf expires.
        client.feed(_tension('line_02'), WARN_T)
        warn = client.wait_status(_diag('line_02'), 10.0, level=1)
        facts['raised'] = float(warn['values']['alarm_raised'])
        shelve.publish(String(data='line_02 6 bridge watch'))
        shelved = client.wait_status(
            _diag('line_02'), 10.0, check=lambda s: s['values'].get('alarm_state') == 'shelved'
        )
        facts['until'] = float(shelved['values']['shelved_until'])
        assert shelved['values']['shelved_by'] == 'bridge watch'
        assert shelved['values']['shelved'] == 'true' and shelved['level'] == 1  # still shown
        assert '/bridge_operator gid' in shelved['values']['shelved_publisher']
        # An acknowledged warning (time to acknowledge about 1.5 s).
        client.feed(_tension('line_03'), WARN_T)
        client.wait_status(_diag('line_03'), 10.0, level=1)
        time.sleep(1.5)
        ack.publish(String(data='line_03 bridge watch'))
        # A lifted anchor: shelving its uplift ERROR is refused, as one condition or whole.
        client.feed(_tension('line_04'), LIFT_T)
        client.wait_status(_diag('line_04'), 10.0, level=2)
        shelve.publish(String(data='line_04.uplift 30 bridge watch'))
        answer = client.wait_status(
            _diag('alarms'), 10.0, check=lambda s: 'line_04.uplift' in s['values']['shelve_answer']
        )
        facts['refusal'] = answer['values']['shelve_answer']
        shelve.publish(String(data='line_04 30 bridge watch'))
        client.wait_for(lambda: 'SHELVE line_04: refused' in output_of(proc), 10.0, 'refusal')
        # A chattering load cell (its link drops out for 3.6 s, then reports for 1.4 s: STALE
        # and back, past tension_timeout) and a storm on two more lines: a flood.
        t0 = time.monotonic()
        k = 0
        while time.monotonic() - t0 < 12.0:
            out = k % 2 == 0
            client.feed(_tension('line_05'), None if out else OK_T)
            client.feed(_tension('line_06'), LIFT_T if out else OK_T)
            client.feed(_tension('line_01'), OK_T if out else WARN_T)
            k += 1
            time.sleep(3.6 if out else 1.4)
        for line in ('line_05', 'line_06', 'line_01', 'line_04', 'line_03'):
            client.feed(_tension(line), OK_T)
        # The shelf expired long ago with line_02 in WARN since before it, never acknowledged:
        # back unacknowledged as it was shelved (raised when it first was, not again).
        back = client.wait_status(
            _diag('line_02'),
            10.0,
            check=lambda s: s['values'].get('alarm_state') == 'unacknowledged',
        )
        facts['back'] = back
        client.wait_status(_diag('alarms'), 10.0, level=1)  # the flood is on now
        time.sleep(2.0)
        facts['arrays'] = list(client.diagnostics)
    finally:
        operator.destroy_node()
        client.close()
        code = stop(proc, sig=2)
    facts['output'] = output_of(proc)
    assert code == 0, facts['output']
    return log_dir, facts


@pytest.mark.ros
def test_live_shelving_refusal_and_expiry(scripted_run: Any) -> None:
    log_dir, facts = scripted_run
    # The uplift ERROR cannot be shelved: the monitor says why, in its answer and its log.
    assert facts['refusal'] == (
        'line_04.uplift: refused: line_04: the uplift ERROR cannot be shelved '
        '(unshelvable_conditions: uplift, input, sensor_error, stale, dragging, sensors)'
    )
    out = facts['output']
    assert 'SHELVE line_04: refused: line_04: its active uplift ERROR cannot be shelved' in out
    assert 'SHELVE line_02 shelved for 6 s by bridge watch: ' in out  # its active conditions
    assert '(a new condition still annunciates) (/bridge_operator gid' in out
    assert 'SHELVE line_02: shelf expired after 6 s; the alarm is shown again' in out
    assert 'CHATTERING line_05' in out and 'ALARM alarms: OK -> WARN: ALARM FLOOD' in out
    # Still active at the expiry, unacknowledged when shelved: unacknowledged again, raised
    # when it first was (a shelf raises nothing that was not raised before it).
    back = facts['back']['values']
    assert back['shelved'] == 'false' and back['acknowledged'] == 'false'
    assert float(back['alarm_raised']) == facts['raised']


def _recorded_arrays(log_dir: Path) -> list[tuple[float, dict[str, dict[str, str]]]]:
    """The /diagnostics the node recorded: (stamp s, {status name: values + level}), read
    with rosbags (its own CDR decoder)."""
    from rosbags.highlevel import AnyReader

    out = []
    with AnyReader(sorted(log_dir.glob('*.mcap'))) as reader:
        conns = [c for c in reader.connections if c.topic == '/diagnostics']
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            statuses = {}
            for st in msg.status:
                values = {kv.key: kv.value for kv in st.values}
                values['_level'] = str(int(st.level))
                statuses[st.name.split(': ', 1)[1]] = values
            out.append((stamp, statuses))
    out.sort(key=lambda a: a[0])
    return out


def _independent_counts(arrays: list[tuple[float, dict[str, dict[str, str]]]]) -> dict:
    """Per alarm, from the recorded arrays alone: raises (distinct alarm_raised of an alarm
    listed), chattering episodes (rising edges), acknowledgements (distinct acknowledged_at,
    with alarm_raised), time shelved (runs of shelved: true, between array stamps); overall:
    the 10-minute periods with arrays and those whose alarms status was in flood."""
    raises: dict[str, set[float]] = defaultdict(set)
    chatter: dict[str, int] = defaultdict(int)
    acks: dict[str, dict[float, float]] = defaultdict(dict)
    shelved_s: dict[str, float] = defaultdict(float)
    was_chattering: dict[str, bool] = defaultdict(bool)
    shelf_start: dict[str, float] = {}
    periods, flood = set(), set()
    for stamp, statuses in arrays:
        periods.add(math.floor(stamp / PERIOD))
        if statuses['alarms']['flood'] == 'true':
            flood.add(math.floor(stamp / PERIOD))
        for name in [*LINES, 'sensors']:
            v = statuses[name]
            if v['alarm_state'] in ('unacknowledged', 'returned-unacknowledged', 'acknowledged'):
                raises[name].add(float(v['alarm_raised']))
            on = v['chattering'] == 'true'
            chatter[name] += on and not was_chattering[name]
            was_chattering[name] = on
            at, raised = float(v['acknowledged_at']), float(v['alarm_raised'])
            if at == at and raised == raised:  # (raised is NaN once the alarm is normal)
                acks[name].setdefault(at, at - raised)
            if v['shelved'] == 'true' and name not in shelf_start:
                shelf_start[name] = stamp
            elif v['shelved'] == 'false' and name in shelf_start:
                shelved_s[name] += stamp - shelf_start.pop(name)
    return {
        'raises': raises,
        'chatter': chatter,
        'acks': acks,
        'shelved_s': shelved_s,
        'periods': periods,
        'flood': flood,
    }


@pytest.mark.ros
def test_the_report_equals_an_independent_count_of_the_recorded_diagnostics(
    scripted_run: Any, tmp_path: Path
) -> None:
    log_dir, facts = scripted_run
    done = subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'alarms', str(log_dir), '--json',
         '--progress', '--plot', str(tmp_path / 'chart.png'), '--html', str(tmp_path / 'r.html')],
        capture_output=True, text=True, env=child_env(), timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert 'alarms: done' in done.stderr  # the progress line
    report = json.loads(done.stdout)
    counts = _independent_counts(_recorded_arrays(log_dir))
    lines = report['lines']
    for name in LINES:
        got = lines[name]
        assert got['annunciated'] == len(counts['raises'][name]), name
        assert got['chattering'] == counts['chatter'][name], name
        assert got['acknowledged'] == len(counts['acks'][name]), name
        if counts['acks'][name]:
            mean = sum(counts['acks'][name].values()) / len(counts['acks'][name])
            assert got['mean_time_to_acknowledge'] == pytest.approx(mean, abs=1e-6), name
        else:
            assert got['mean_time_to_acknowledge'] is None
        # shelved: the arrays see a shelf end at the next array (one period at most later)
        assert got['shelved_s'] == pytest.approx(counts['shelved_s'][name], abs=1.0 / RATE)
        assert got['standing'] == 0
    assert report['sensors']['annunciated'] == len(counts['raises']['sensors'])
    total = sum(len(r) for r in counts['raises'].values())
    periods = len(counts['periods'])
    # the component statuses' raises (here the flood status's WARN) are counted too
    components = report['components']
    assert components['alarms']['annunciated'] == report['floods']
    total += sum(c['annunciated'] for c in components.values())
    assert report['annunciated'] == total and report['periods'] == periods
    assert report['per_10min_mean'] == pytest.approx(total / periods)
    bins: dict[int, int] = defaultdict(int)
    for raised in counts['raises'].values():
        for t in raised:
            bins[math.floor(t / PERIOD)] += 1
    assert max(bins.values()) <= report['per_10min_peak'] <= max(bins.values()) + report['floods']
    assert report['flood_share'] == pytest.approx(len(counts['flood']) / periods)
    # Not vacuous: the script made every kind.
    assert lines['line_05']['chattering'] >= 1 and report['floods'] >= 1
    assert lines['line_03']['acknowledged'] == 1 and lines['line_02']['shelved'] == 1
    assert lines['line_02']['shelved_s'] == pytest.approx(6.0, abs=1.0 / RATE)
    assert lines['line_04']['shelve_refused'] == 2
    assert (tmp_path / 'chart.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert 'Alarm report' in (tmp_path / 'r.html').read_text()
