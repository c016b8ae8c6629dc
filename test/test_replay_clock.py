"""``replay --publish`` publishes /clock with the log's time, and a monitor started with
``use_sim_time`` follows it: a playback at --rate 10 is judged in log time (real rclpy, DDS)."""

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from replay_data import T0_NS, dock_config, generate, params_yaml, write_log
from ros_harness import Client, start_monitor, stop

ROOT = Path(__file__).resolve().parents[1]
SECONDS = 20.0  # of log time, played in 2 s at --rate 10


@pytest.mark.timeout(120)
def test_a_sim_time_node_follows_the_playbacks_clock(tmp_path):
    from rosgraph_msgs.msg import Clock
    from std_msgs.msg import Float64

    # The log has three lines, the monitor watches two: the third's only subscriber is this
    # test's client, so --wait-subscribers waits for the client too (its /clock subscription
    # found with it), not only for the monitor (under load the client once matched 1.7 s late
    # and missed the first /clock ticks).
    alarm = dict(tension_timeout=2.0, depth_timeout=5.0)
    config = dock_config(3, **alarm)
    tensions, depth = generate(
        config, seconds=SECONDS, rate=10.0, depth_rate=2.0, seed=4, dropouts=False
    )
    log = write_log(tmp_path / 'play.mcap', config, tensions, depth)
    params = params_yaml(dock_config(2, **alarm), tmp_path / 'params.yaml')
    played_params = params_yaml(config, tmp_path / 'played.yaml')
    first = min(int(c[0][0]) for c in (*tensions.values(), depth))
    last = max(int(c[0][-1]) for c in (*tensions.values(), depth))
    monitor = start_monitor(params, tmp_path / 'live', '-p', 'use_sim_time:=true')
    client = Client('clock_test_client')
    clocks = []
    lock = threading.Lock()

    def on_clock(msg):
        with lock:
            clocks.append((time.monotonic(), msg.clock.sec * 10**9 + msg.clock.nanosec))

    client.node.create_subscription(Clock, '/clock', on_clock, 100)
    client.node.create_subscription(Float64, config.lines[2].tension_topic, lambda m: None, 100)
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(p for p in (str(ROOT), env.get('PYTHONPATH')) if p)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    try:
        client.wait_for(lambda: client.diagnostics, 30.0, 'the monitor up')
        cmd = [sys.executable, '-m', 'catenary_monitor.cli', 'replay', str(log), '--publish',
               '--params-file', str(played_params), '--rate', '10',
               '--wait-subscribers', '20']  # fmt: skip
        t0 = time.monotonic()
        played = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=60)
        wall = time.monotonic() - t0
        time.sleep(0.5)
    finally:
        code = stop(monitor)
        client.close()
    assert played.returncode == 0, played.stderr
    assert '/clock from the log' in played.stderr
    assert code == 0
    with lock:
        ticks = [c for _, c in clocks]
        clock_wall = [w for w, _ in clocks]
    # /clock follows the log's times: from its first to its last message, never backwards,
    # ten times faster than the wall clock.
    assert ticks[0] == first and ticks[-1] == last
    assert all(b >= a for a, b in zip(ticks, ticks[1:]))
    # (the rate from the fourth of the ticks on: the first ones may come late together, by
    # reliable repair, when the client's reader matched the playback's writer after it began)
    k0 = len(ticks) // 4
    span_wall = clock_wall[-1] - clock_wall[k0]
    assert (last - ticks[k0]) * 1e-9 / span_wall == pytest.approx(10.0, rel=0.2)
    assert wall < SECONDS / 2
    # The monitor judged it in log time: its /diagnostics are stamped in the log's time (a
    # year before the wall clock), one tick per second of log time, not of wall time.
    with client.lock:
        stamps = [s for s in client.diag_stamps if s >= T0_NS]
    assert stamps and all(first <= s <= last + 2 * 10**9 for s in stamps)
    assert len(stamps) >= 0.8 * SECONDS
    assert max(stamps) < time.time_ns() - 86400 * 10**9
