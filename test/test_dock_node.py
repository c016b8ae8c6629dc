"""The live node with the dock model: it publishes ``catenary_monitor: dock`` and flags the one
line whose sensor reads 30 % high; replay of its log gives every /diagnostics array again."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_replay_node import _assert_status_equal

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.equilibrium import solve_equilibrium
from catenary_monitor.io.mcap_read import iter_messages
from catenary_monitor.replay.driver import load_config, replay_log

ROOT = Path(__file__).resolve().parents[1]
DOCK_YAML = ROOT / 'config' / 'floating_dock.yaml'
pytestmark = [pytest.mark.ros, pytest.mark.slow]
NAMES = [f'line_{k:02d}' for k in range(1, 13)]


def _params(tmp_path: Path) -> Path:
    text = DOCK_YAML.read_text()
    extra = ''.join(f'    {n}.tension_accuracy: 20000.0\n' for n in NAMES)
    extra += f'    log_dir: {tmp_path / "logs"}\n    diagnostic_rate: 4.0\n'
    text = text.replace('    log_dir: ~/.ros/catenary_monitor\n', extra)
    path = tmp_path / 'dock.yaml'
    path.write_text(text)
    return path


def test_the_node_estimates_the_dock_and_flags_the_drifting_line(tmp_path):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import QoSProfile
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64

    params = _params(tmp_path)
    config = load_config(str(params))
    model = DockModel.from_config(config)
    eq = solve_equilibrium(model, 20.85, np.array([0.0, -1.2e6, 0.0]))
    truth = eq.lines.statics.top_tension
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join(p for p in (str(ROOT), os.environ.get('PYTHONPATH')) if p),
        PYTHONUNBUFFERED='1',
    )
    out_path = tmp_path / 'node.out'
    out = open(out_path, 'w+')
    cmd = [sys.executable, '-m', 'catenary_monitor.ros.node', '--ros-args', '--params-file']
    proc = subprocess.Popen([*cmd, str(params)], env=env, stdout=out, stderr=subprocess.STDOUT)
    try:
        if not rclpy.ok():
            rclpy.init()
        client = rclpy.create_node('dock_node_test')
        qos = QoSProfile(depth=10)
        pubs = [client.create_publisher(Float64, f'/mooring/{n}/tension', qos) for n in NAMES]
        depth_pub = client.create_publisher(Float64, '/tide/depth', qos)
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline and proc.poll() is None:
            if (
                all(p.get_subscription_count() for p in pubs)
                and depth_pub.get_subscription_count()
            ):
                break
            time.sleep(0.05)
        assert depth_pub.get_subscription_count(), out_path.read_text()
        rng = np.random.default_rng(2)
        start = time.monotonic()
        k = 0
        while (now := time.monotonic() - start) < 8.0:
            values = truth + rng.normal(0.0, 5e3, truth.size)
            if now > 3.0:
                values[8] *= 1.3  # line_09's sensor reads 30 % high
            for pub, v in zip(pubs, values):
                pub.publish(Float64(data=float(v)))
            if k % 5 == 0:
                depth_pub.publish(Float64(data=20.85))
            k += 1
            time.sleep(0.1)
        time.sleep(1.0)
        client.destroy_node()
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        code = proc.wait(30)
    text = out_path.read_text()
    assert code == 0, text
    files = sorted((tmp_path / 'logs').glob('*.mcap'))
    arrays = [
        (m.log_time_ns, deserialize_message(m.data, DiagnosticArray))
        for m in iter_messages(files, ['/diagnostics'])
    ]
    last = {st.name: st for st in arrays[-1][1].status}
    dock = last['catenary_monitor: dock']
    values = {kv.key: kv.value for kv in dock.values}
    assert {'offset_x', 'offset_y', 'yaw_deg', 'load_x', 'load_y'} <= set(values)
    assert dock.level[0] == 0 and 'disagreeing: line_09' in values['detail'], values['detail']
    assert abs(float(values['offset_y']) - eq.offset_y) < 0.05
    assert abs(float(values['load_y']) + 1.2e6) < 0.2e6
    states = {
        n: {kv.key: kv.value for kv in last[f'catenary_monitor: {n}'].values}['sensor_state']
        for n in NAMES
    }
    assert [n for n, s in states.items() if s == 'inconsistent'] == ['line_09'], states
    line_09 = {kv.key: kv.value for kv in last['catenary_monitor: line_09'].values}
    assert 'tension inconsistent with the other lines' in line_09['detail']
    # (its high reading also makes the line's own monitor see an uplift: the message says why)
    # Replay redoes every array the node published, dock status and line values included.
    result, _, _, report = replay_log(files, config, ticks='log', snapshots=True)
    assert report.complete
    assert [t for t, _ in arrays] == [s.stamp_ns for s in result.snapshots]
    for (stamp, array), snap in zip(arrays, result.snapshots):
        assert len(array.status) == len(snap.statuses)
        for got, want in zip(array.status, snap.statuses):
            _assert_status_equal(got, want, f'{stamp} {got.name}')
