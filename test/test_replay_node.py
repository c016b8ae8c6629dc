"""Replay of a log written by the real live node gives, step for step, what the node did.

The monitor runs as its own process on a params file; this process publishes tension and depth
with rclpy: tension before the first depth (a late first depth), a storm that lifts line_02's
anchor, a tension dropout and a NaN on line_01, a depth dropout longer than ``depth_timeout``,
and line_03 an elastic chain (``ea`` set); an operator acknowledges line_02's alarm during the
storm, then every alarm, over the node's acknowledgement topic. The node is stopped with
SIGTERM and its MCAP log is replayed with the same params file. Compared with what the node
logged itself:

* every output message (``/catenary_monitor/NAME/outputs``): same times, solver status and
  level, values to 1e-12;
* every ``/diagnostics`` message: the same stamps, and for every line and the tide the same
  level, message and values (numbers to 1e-12);
* every alarm transition the node printed, with its message;
* the acknowledgement states (``acknowledged``, ``alarm_state``, ...): replay steps the
  acknowledgements the node recorded on its events channel.

The params files are written in the forms rcl accepts and PyYAML reads differently (``5.17e6``,
``1e6``, integers for doubles, the ``/**`` key, dotted and nested names): the node and replay
must read the same configuration from them (same configuration hash).
"""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from catenary_monitor.core.config.parameters import config_hash
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS, VALUE_FIELDS
from catenary_monitor.core.physics.result import Status
from catenary_monitor.io.mcap_read import iter_messages
from catenary_monitor.replay.driver import load_config, log_parameters, replay_log

ROOT = Path(__file__).resolve().parents[1]
pytestmark = [pytest.mark.ros, pytest.mark.slow]

#: Two params files for the same monitor, in the forms rcl reads its own way.
PARAMS = {
    'wildcard_key_and_rcl_scalars': '''\
/**:
  ros__parameters:
    lines: [line_01, line_02, line_03]
    log_dir: "{log_dir}"
    tension_timeout: 8e-1
    depth_timeout: 3
    clear_hold: 1
    warn_clear_hold: 1.
    margin_clear_hold: 1.
    diagnostic_rate: 4
    line_01: {{weight: 1300, anchor_distance: 120, mbl: 4.827e6}}
    line_02.weight: 13e2
    line_02.anchor_distance: 121.06
    line_02.mbl: 4827000
    line_02.allowed_uplift: 2e4
    line_02.tension_accuracy: 3e4
    line_02.chain_length: 25e1
    line_02.anchor_holding: 5e5
    line_02.chain_friction: 7e-1
    depth_accuracy: 2e-1
    drag_margin_warn: 1e5
    line_03:
      weight: 1.3e3
      anchor_distance: 121.06
      mbl: 4.827E6
      allowed_uplift: 20000
      ea: 6.6e8
      tension_accuracy: 2e4
      chain_length: 300
      anchor_holding: 3e5
      anchor_weight: 4e5
''',
    'node_key_and_plain_floats': '''\
catenary_monitor:
  ros__parameters:
    lines: ["line_01", "line_02", "line_03"]
    log_dir: {log_dir}
    tension_timeout: 0.8
    depth_timeout: 3.0
    clear_hold: 1.0
    warn_clear_hold: 1.0
    margin_clear_hold: 1.0
    diagnostic_rate: 4.0
    line_01:
      weight: 1300.0
      anchor_distance: 120.0
      mbl: 4827000.0
    line_02:
      weight: 1300.0
      anchor_distance: 121.06
      mbl: 4827000.0
      allowed_uplift: 20000.0
      tension_accuracy: 30000.0
      chain_length: 250.0
      anchor_holding: 500000.0
      chain_friction: 0.7
    depth_accuracy: 0.2
    drag_margin_warn: 100000.0
    line_03:
      weight: 1300.0
      anchor_distance: 121.06
      mbl: 4827000.0
      allowed_uplift: 20000.0
      ea: 660000000.0
      tension_accuracy: 20000.0
      chain_length: 300.0
      anchor_holding: 300000.0
      anchor_weight: 400000.0
''',
}


#: line_01's impossible samples by message index: NaN, 1e300 N, inf, 100 MN (> 10 x MBL).
#: After the first depth (index 30 at the latest): line_01 is OK for at least 9 samples first,
#: whatever the machine's load (the return from them is a spike, held for sensor_hold).
IMPOSSIBLE = {40: float('nan'), 42: 1e300, 44: float('inf'), 46: 1e8}


def _publish_scenario(pubs, depth_pub, ack_pub):
    """About 9 s of inputs: see the module docstring."""
    from std_msgs.msg import Float64, String

    # the last claims a 1 MB origin: stored bounded
    acks = {78: 'line_02 replay test', 50: 'nope', 150: 'all replay test ' + 'x' * 1_000_000}

    rng = np.random.default_rng(5)
    start = time.monotonic()
    k = 0
    while (now := time.monotonic() - start) < 9.0:
        storm = 1.3e6 * max(0.0, 1.0 - abs(now - 4.0) / 1.5)
        wave = 40e3 * np.sin(2 * np.pi * now / 1.3)
        if not 4.5 < now < 6.0:
            value = IMPOSSIBLE.get(k, 372e3 + wave + rng.normal(0, 3e3))
            pubs['line_01'].publish(Float64(data=value))
        pubs['line_02'].publish(Float64(data=372e3 + storm - wave))
        line_03 = 1e300 if k == 40 else 372e3 + 0.9 * storm + wave  # elastic line
        pubs['line_03'].publish(Float64(data=line_03))
        # First depth at 1.2 s; none from 5 to 8.6 s (longer than depth_timeout 3 s).
        if now > 1.2 and not 5.0 < now < 8.6 and k % 10 == 0:
            depth_pub.publish(Float64(data=1e6 if k == 60 else 20.85 + 0.3 * np.sin(now / 3)))
        if k in acks:
            ack_pub.publish(String(data=acks[k]))
        k += 1
        time.sleep(0.05)


def _run_node(params: Path, out_path: Path) -> tuple[int, str]:
    import rclpy
    from rclpy.qos import QoSProfile
    from std_msgs.msg import Float64, String

    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join(p for p in (str(ROOT), os.environ.get('PYTHONPATH')) if p),
        PYTHONUNBUFFERED='1',
    )
    out = open(out_path, 'w+')
    proc = subprocess.Popen(
        [
            sys.executable,
            '-m',
            'catenary_monitor.ros.node',
            '--ros-args',
            '--params-file',
            str(params),
        ],
        env=env,
        stdout=out,
        stderr=subprocess.STDOUT,
    )
    try:
        if not rclpy.ok():
            rclpy.init()
        client = rclpy.create_node('replay_node_test')
        qos = QoSProfile(depth=10)
        pubs = {
            name: client.create_publisher(Float64, f'/mooring/{name}/tension', qos)
            for name in ('line_01', 'line_02', 'line_03')
        }
        depth_pub = client.create_publisher(Float64, '/tide/depth', qos)
        ack_pub = client.create_publisher(String, '/catenary_monitor/acknowledge', qos)
        deadline = time.monotonic() + 60.0
        while (
            time.monotonic() < deadline
            and proc.poll() is None
            and not (
                all(p.get_subscription_count() for p in pubs.values())
                and depth_pub.get_subscription_count()
                and ack_pub.get_subscription_count()
            )
        ):
            time.sleep(0.05)
        assert proc.poll() is None, out_path.read_text()
        assert depth_pub.get_subscription_count(), 'the node did not subscribe in 60 s'
        _publish_scenario(pubs, depth_pub, ack_pub)
        time.sleep(1.0)
        (me,) = [
            e
            for e in client.get_publishers_info_by_topic('/catenary_monitor/acknowledge')
            if e.node_name == 'replay_node_test'
        ]
        gid = '.'.join(f'{b:02x}' for b in bytes(me.endpoint_gid)[:16])
        (out_path.parent / 'ack_publisher').write_text(f'/replay_node_test gid {gid}')
        client.destroy_node()
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            code = proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
            raise AssertionError('the node did not stop within 30 s of SIGTERM')
    return code, out_path.read_text()


def _assert_values_equal(got, want, what):
    np.testing.assert_allclose(
        np.asarray(got, float),
        np.asarray(want, float),
        rtol=1e-12,
        atol=1e-6,
        equal_nan=True,
        err_msg=what,
    )


def _assert_status_equal(node_status, replay_status, what):
    assert node_status.name == replay_status.name, what
    assert node_status.level[0] == int(replay_status.level), (
        what,
        node_status.message,
        replay_status.message,
    )
    assert node_status.message == replay_status.message, what
    if node_status.name.endswith(': logger'):
        return  # its counters are the node's own
    got = {kv.key: kv.value for kv in node_status.values}
    want = dict(replay_status.values)
    assert list(got) == list(want), what
    for key, value in want.items():
        if key in TEXT_KEYS or not _is_number(value):
            assert got[key] == value, (what, key)
        else:
            _assert_values_equal(float(got[key]), float(value), f'{what} {key}')


def _is_number(text: str) -> bool:
    """A value that float() reads (numbers to rounding; anything else, a word, exactly)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


#: The /diagnostics keys whose values are words, not numbers.
TEXT_KEYS = {
    'model',
    'acknowledged',
    'alarm_state',
    'alarm_condition',
    'acknowledged_by',
    'acknowledged_publisher',
    'sensor_state',
    'tide_forecast',
    'store_state',
    'time_to_uplift_view',
    'span_source',
    # Alarm management: shelving, chattering, the flood status.
    'shelved',
    'shelved_condition',
    'shelved_by',
    'shelved_publisher',
    'chattering',
    'flood',
    'first_out',
    'unshelvable_conditions',
    'shelve_answer',
}


@pytest.mark.parametrize('form', sorted(PARAMS))
def test_replay_of_a_live_node_log_redoes_every_step(tmp_path, form):
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64MultiArray

    log_dir = tmp_path / 'logs'
    params = tmp_path / 'params.yaml'
    params.write_text(PARAMS[form].format(log_dir=log_dir))
    config = load_config(str(params))  # replay's reading of the file
    assert config.line('line_03').ea == 6.6e8 and config.alarm.depth_timeout == 3.0
    code, text = _run_node(params, tmp_path / 'node.out')
    assert code == 0, text
    files = sorted(log_dir.glob('*.mcap'))
    assert files, text
    # The node read the same configuration from the file (its recorded hash).
    recorded = log_parameters(files)
    assert recorded is not None and recorded[0] == config_hash(config)

    result, tensions, _, report = replay_log(files, config, ticks='log', snapshots=True)
    assert report.complete and result.ticks_from_log
    assert sum(len(t) for t, _ in tensions.values()) > 300
    levels_seen = set()
    for r in result.lines:
        logged = [
            (m.log_time_ns, deserialize_message(m.data, Float64MultiArray))
            for m in iter_messages(files, [f'/catenary_monitor/{r.name}/outputs'])
        ]
        assert logged[0][1].layout.dim[0].label.split(',') == list(OUTPUT_FIELDS)
        data = np.array([m.data for _, m in logged])
        assert [t for t, _ in logged] == r.t_ns.tolist(), r.name
        assert data[:, 11].tolist() == r.status.tolist(), r.name
        assert data[:, 12].tolist() == r.level.tolist(), r.name
        for key in VALUE_FIELDS:
            j = OUTPUT_FIELDS.index(key)
            _assert_values_equal(data[:, j], r.values[key], f'{r.name} {key}')
        levels_seen |= set(r.step_level.tolist())
        if r.name == 'line_01':
            assert 0 in r.step_level.tolist(), 'line_01 never OK before its impossible samples'
    # Every /diagnostics array: the same stamps, the same statuses, one array per stamp.
    arrays = [
        (m.log_time_ns, deserialize_message(m.data, DiagnosticArray))
        for m in iter_messages(files, ['/diagnostics'])
    ]
    assert [t for t, _ in arrays] == [s.stamp_ns for s in result.snapshots]
    assert len({t for t, _ in arrays}) == len(arrays)
    for (stamp, array), snap in zip(arrays, result.snapshots):
        assert len(array.status) == len(snap.statuses)
        for got, want in zip(array.status, snap.statuses):
            _assert_status_equal(got, want, f'{stamp} {got.name}')
    # The acknowledgements: recorded (the unknown line refused), replayed, seen on /diagnostics.
    from catenary_monitor.core.monitor.events import Acknowledge

    from catenary_monitor.core.alarms.acknowledge import ORIGIN_LIMIT

    acks = [e for e in result.events if isinstance(e, Acknowledge)]
    bounded = 'replay test ' + 'x' * (ORIGIN_LIMIT - 15) + '...'
    assert [(e.line, e.origin) for e in acks] == [
        ('line_02', 'replay test'),
        (None, bounded),
    ], text
    # the publisher as the middleware names it (node and GID) in the event record
    publisher = (log_dir.parent / 'ack_publisher').read_text()
    assert [e.publisher for e in acks] == [publisher, publisher]
    values = {
        (st.name, kv.key): kv.value
        for _, array in arrays
        for st in array.status
        for kv in st.values
        if kv.key in ('acknowledged_by', 'acknowledged_publisher') and kv.value
    }
    assert values[('catenary_monitor: line_02', 'acknowledged_publisher')] == publisher
    assert max(len(v) for v in values.values()) <= ORIGIN_LIMIT
    assert max(len(line) for line in text.splitlines()) < 1000  # the node's log, too
    states = {
        (st.name, kv.value)
        for _, array in arrays
        for st in array.status
        for kv in st.values
        if kv.key == 'alarm_state'
    }
    assert ('catenary_monitor: line_02', 'acknowledged') in states
    assert "unknown line 'nope'" in text
    # The scenario reached what it was written for.
    assert {0, 2, 3} <= levels_seen  # OK, ERROR (uplift, NaN), STALE (dropouts, start)
    codes = {c for r in result.lines for c in r.status.tolist()}
    assert {Status.IMPLAUSIBLE_TENSION, Status.IMPLAUSIBLE_DEPTH} <= codes, codes
    assert Status.NO_CONVERGENCE not in codes
    assert any(tr.new.name == 'ERROR' and 'deeper than any' in tr.message for tr in result.tide)
    tide = [(tr.old.name, tr.new.name) for tr in result.tide]
    # (the depth's dropout comes while its spike, the implausible depth, is still held: WARN)
    assert tide[0] == ('STALE', 'OK') and any(new == 'STALE' for _, new in tide[1:])
    models = {r.name: set(r.model_codes.tolist()) for r in result.lines}
    assert 2 in models['line_03'] and 2 not in models['line_01']
    # The node's own transition lines: the same sequence, with the same messages (the
    # changes suppressed by design are printed by neither).
    said = re.findall(r'ALARM (\w+): (\w+) -> (\w+): (.*?)(?: \(after [\d.]+ s\))?$', text, re.M)
    want = [
        (c.component, c.transition.old.name, c.transition.new.name, c.transition.message)
        for c in result.changes()
        if not c.transition.suppressed
    ]
    assert any(c.transition.suppressed for c in result.changes())  # not vacuous
    assert sorted(said) == sorted(want)


def test_output_layout_is_the_nodes():
    """The node publishes the core's layout; replay writes it too."""
    from catenary_monitor.replay.outputs import output_topic
    from catenary_monitor.core.monitor.events import NODE_NAME
    from catenary_monitor.ros import node

    assert node.OUTPUT_FIELDS is OUTPUT_FIELDS
    assert output_topic('l1') == f'/{NODE_NAME}/l1/outputs'
