"""Replay of a log written by the real live node gives the node's own alarm levels.

The monitor runs as its own process (``python -m catenary_monitor.ros.node --ros-args --params-file
F``); this process publishes tension and depth with rclpy (a storm that lifts line_02's anchor,
a tension dropout and a NaN on line_01, tension before the first depth; line_03 is an elastic
chain, ``ea`` set), then stops the node with SIGTERM and replays its MCAP log. Compared with what
the node logged itself:

* every output message (``/catenary_monitor/NAME/outputs``): same update times, solver status,
  alarm level after the update, and values to rounding;
* every ``/diagnostics`` message: each line's level equals replay's level at that time.
"""
import csv
import io
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from replay_data import params_yaml

from catenary_monitor.cli.replay import run_replay
from catenary_monitor.cli.replay_output import write_csv
from catenary_monitor.core.alarms import Level
from catenary_monitor.core.batch import VALUE_FIELDS
from catenary_monitor.core.config import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.io.mcap_read import iter_messages

ROOT = Path(__file__).resolve().parents[1]
pytestmark = [pytest.mark.ros, pytest.mark.slow]


def test_replay_of_a_live_node_log_matches_the_node(tmp_path):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import QoSProfile
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64, Float64MultiArray

    log_dir = tmp_path / 'logs'
    config = MonitorConfig(
        lines=(LineConfig('line_01', 1300.0, 120.0, 4827000.0),
               LineConfig('line_02', 1300.0, 121.06, 4827000.0, allowed_uplift=20e3),
               LineConfig('line_03', 1300.0, 121.06, 4827000.0, allowed_uplift=20e3, ea=6.6e8)),
        log_dir=str(log_dir),
        alarm=AlarmConfig(tension_timeout=0.8, depth_timeout=3.0, clear_hold=1.0,
                          warn_clear_hold=1.0, diagnostic_rate=4.0))
    params = params_yaml(config, tmp_path / 'params.yaml')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (str(ROOT), os.environ.get('PYTHONPATH')) if p), PYTHONUNBUFFERED='1')
    out = open(tmp_path / 'node.out', 'w+')
    node_proc = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.ros.node', '--ros-args', '--params-file',
         str(params)], env=env, stdout=out, stderr=subprocess.STDOUT)
    try:
        if not rclpy.ok():
            rclpy.init()
        client = rclpy.create_node('replay_node_test')
        qos = QoSProfile(depth=10)
        pubs = {name: client.create_publisher(Float64, f'/mooring/{name}/tension', qos)
                for name in ('line_01', 'line_02', 'line_03')}
        depth_pub = client.create_publisher(Float64, '/tide/depth', qos)
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline and not (
                all(p.get_subscription_count() for p in pubs.values())
                and depth_pub.get_subscription_count()):
            time.sleep(0.05)
        assert node_proc.poll() is None, Path(out.name).read_text()
        assert depth_pub.get_subscription_count(), 'the node did not subscribe in 30 s'
        rng = np.random.default_rng(5)
        start = time.monotonic()
        k = 0
        while (now := time.monotonic() - start) < 8.0:
            # line_02: storm 2-5 s, lifts the anchor; line_01: silent 4-5.5 s, one NaN.
            storm = 1.3e6 * max(0.0, 1.0 - abs(now - 3.5) / 1.5)
            wave = 40e3 * np.sin(2 * np.pi * now / 1.3)
            if not 4.0 < now < 5.5:
                value = float('nan') if k == 30 else 372e3 + wave + rng.normal(0, 3e3)
                pubs['line_01'].publish(Float64(data=value))
            pubs['line_02'].publish(Float64(data=372e3 + storm - wave))
            pubs['line_03'].publish(Float64(data=372e3 + 0.9 * storm + wave))
            if now > 0.5 and k % 10 == 0:
                depth_pub.publish(Float64(data=20.85 + 0.3 * np.sin(now / 3)))
            k += 1
            time.sleep(0.05)
        time.sleep(1.0)
        client.destroy_node()
    finally:
        if node_proc.poll() is None:
            node_proc.send_signal(signal.SIGTERM)
        try:
            code = node_proc.wait(20)
        except subprocess.TimeoutExpired:
            node_proc.kill()
            node_proc.wait(5)
            raise AssertionError('the node did not stop within 20 s of SIGTERM')
    assert code == 0, Path(out.name).read_text()
    files = sorted(log_dir.glob('*.mcap'))
    assert files, Path(out.name).read_text()

    result, tensions, depth, report, _ = run_replay(files, config)
    assert report.complete and result.ticks_from_log
    assert sum(len(t) for t, _ in tensions.values()) > 150
    levels_seen = set()
    for r in result.lines:
        logged = [(m.log_time_ns, deserialize_message(m.data, Float64MultiArray))
                  for m in iter_messages(files, [f'/catenary_monitor/{r.name}/outputs'])]
        fields = logged[0][1].layout.dim[0].label.split(',')
        data = np.array([m.data for _, m in logged])
        assert [t for t, _ in logged] == r.t_ns.tolist(), r.name
        np.testing.assert_array_equal(data[:, fields.index('status')], r.status)
        np.testing.assert_array_equal(data[:, fields.index('level')], r.level, err_msg=r.name)
        for key in VALUE_FIELDS:
            np.testing.assert_allclose(data[:, fields.index(key)], r.values[key], rtol=1e-12,
                                       atol=1e-6, err_msg=f'{r.name} {key}')
        levels_seen |= set(r.level.tolist())
    # Every /diagnostics message: each line's level is replay's level at that time.
    steps = {}
    for r in result.lines:
        t = np.concatenate((r.t_ns, r.tick_ns))
        lv = np.concatenate((r.level, r.tick_level))
        order = np.argsort(t, kind='stable')
        steps[r.name] = (t[order], lv[order])
    n_diag = 0
    models = {name: set() for name in steps}
    for m in iter_messages(files, ['/diagnostics']):
        msg = deserialize_message(m.data, DiagnosticArray)
        for status in msg.status:
            name = status.name.split(': ')[-1]
            if name not in steps:
                continue
            models[name] |= {kv.value for kv in status.values if kv.key == 'model'}
            t, lv = steps[name]
            i = np.searchsorted(t, m.log_time_ns, 'right') - 1
            want = int(lv[i]) if i >= 0 else int(Level.OK)
            assert status.level[0] == want, (name, m.log_time_ns)
            n_diag += 1
    assert n_diag > 40
    # The elastic line says which model its results used; the others stay inextensible.
    assert models['line_03'] - {'none'} == {'elastic catenary'}  # none: before the first depth
    assert models['line_01'] - {'none'} == models['line_02'] - {'none'} == {'inextensible catenary'}
    # Replay's CSV says the same, row by row.
    buf = io.BytesIO()
    write_csv(buf, result, columns=('time', 'line', 'model'))
    rows = list(csv.reader(io.StringIO(buf.getvalue().decode())))[1:]
    csv_models = {name: {m for _, n, m in rows if n == name} for name in models}
    assert csv_models['line_03'] - {'none'} == {'elastic catenary'}
    assert csv_models['line_01'] - {'none'} == {'inextensible catenary'}
    assert {int(Level.ERROR), int(Level.STALE)} <= levels_seen
    # The node's own transition log lines: same sequence of levels per line, and the same
    # message for every transition made by an update (a periodic step's message may show an
    # age rounded differently: replay steps at the log time of the node's /diagnostics).
    text = Path(out.name).read_text()
    for r in result.lines:
        said = re.findall(rf'ALARM {r.name}: (\w+) -> (\w+): (.*?)(?: \(after [\d.]+ s\))?$',
                          text, re.M)
        assert [(old, new) for old, new, _ in said] == \
            [(tr.old.name, tr.new.name) for tr in r.transitions], r.name
        updates = set((r.t_ns * 1e-9).tolist())
        for (_, _, message), tr in zip(said, r.transitions):
            if tr.time in updates:
                assert message == tr.message, r.name


def test_output_layout_is_the_nodes():
    """Replay writes the node's per-line output layout (recompute.OUTPUT_FIELDS)."""
    from catenary_monitor.cli.replay_output import NODE_NAME, output_topic
    from catenary_monitor.core.batch import OUTPUT_FIELDS
    from catenary_monitor.ros import node
    assert node.OUTPUT_FIELDS == OUTPUT_FIELDS
    assert node.NODE_NAME == NODE_NAME and output_topic('l1') == f'/{node.NODE_NAME}/l1/outputs'
