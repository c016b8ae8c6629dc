"""``replay --publish``: a generated log played to a subscriber, with real rclpy and DDS.

The player runs as its own process (``catenary-monitor replay LOG --publish``); this process
subscribes to the input topics and checks that every message arrives, in order, with its
recorded value and the recorded timing divided by ``--rate``.
"""

import os
import signal
import subprocess
import sys
import threading
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from replay_data import dock_config, generate, params_yaml, write_log

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.ros
@pytest.mark.slow
def test_publish_plays_the_recorded_inputs(tmp_path):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile
    from std_msgs.msg import Float64

    config = dock_config(2)
    tensions, depth = generate(
        config, seconds=6.0, rate=10.0, depth_rate=2.0, seed=21, dropouts=False
    )
    log = write_log(tmp_path / 'play.mcap', config, tensions, depth)
    params = params_yaml(config, tmp_path / 'params.yaml')
    topics = {line.tension_topic: tensions[line.name] for line in config.lines}
    topics[config.depth_topic] = depth
    rate = 2.0

    if not rclpy.ok():
        rclpy.init()
    node = rclpy.create_node('replay_publish_test')
    got = defaultdict(list)
    lock = threading.Lock()

    def on(topic, msg):
        with lock:
            got[topic].append((time.monotonic(), msg.data))

    for topic in topics:
        node.create_subscription(
            Float64, topic, lambda m, t=topic: on(t, m), QoSProfile(depth=200)
        )
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spin = threading.Thread(target=executor.spin, daemon=True)
    spin.start()
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join(p for p in (str(ROOT), os.environ.get('PYTHONPATH')) if p),
    )
    proc = subprocess.Popen(
        [
            sys.executable,
            '-m',
            'catenary_monitor.cli',
            'replay',
            str(log),
            '--publish',
            '--params-file',
            str(params),
            '--rate',
            str(rate),
            '--wait-subscribers',
            '20',
        ],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    deadline = time.monotonic() + 5.0
    total = sum(len(t) for t, _ in topics.values())
    while time.monotonic() < deadline and sum(len(v) for v in got.values()) < total:
        time.sleep(0.05)
    first = {k: list(v) for k, v in got.items()}
    # --loop: the log plays again and again until SIGTERM (exit 0).
    with lock:
        got.clear()
    looping = subprocess.Popen(
        [
            sys.executable,
            '-m',
            'catenary_monitor.cli',
            'replay',
            str(log),
            '--publish',
            '--rate',
            '20',
            '--loop',
            '--wait-subscribers',
            '20',
            '--quiet',
        ],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 30.0
        depth_topic = config.depth_topic
        while time.monotonic() < deadline and len(got[depth_topic]) < 2.5 * len(depth[0]):
            time.sleep(0.05)
        looping.send_signal(signal.SIGTERM)
        loop_code = looping.wait(10)
    finally:
        if looping.poll() is None:
            looping.kill()
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()
    assert proc.returncode == 0, err
    assert f'{total} messages on 3 topic(s)' in err
    assert loop_code == 0
    played = [v for _, v in got[config.depth_topic]]
    n_depth = len(depth[0])
    assert len(played) >= 2 * n_depth
    assert played[n_depth : 2 * n_depth] == played[:n_depth] == depth[1].tolist()
    for topic, (t_ns, values) in topics.items():
        arrived = first[topic]
        assert [v for _, v in arrived] == values.tolist(), topic
        # Recorded timing scaled by 1/rate: compare the spans (scheduling jitter allowed) from
        # the fourth of the messages on: the playback starts once its writers have matched the
        # readers, and a reader that has not matched the writer yet gets the first samples by
        # reliable repair a moment later (on a fresh machine the first one came 0.29 s late).
        k0 = len(arrived) // 4
        span_recorded = (t_ns[-1] - t_ns[k0]) * 1e-9 / rate
        span_played = arrived[-1][0] - arrived[k0][0]
        assert span_played == pytest.approx(span_recorded, abs=0.25), topic
        gaps = np.diff([a for a, _ in arrived])
        want = np.diff(t_ns) * 1e-9 / rate
        assert np.median(np.abs(gaps - want)) < 0.02, topic
