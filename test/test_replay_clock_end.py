"""``replay --publish`` of a log recorded where ROS 2's /clock ends (builtin_interfaces/Time has
``int32 sec``: 2**31 s, 2038-01-19T03:14:08Z; a uint32 would have run to 2106): the clock never
goes backwards. Before, the seconds wrapped (2**31 s arrived as -2**31, 2**32 s as 0) and /clock
jumped back to 1901 or 1970 (and rclpy's TimeSource raises on negative seconds in every
``use_sim_time`` node). Messages /clock cannot carry are left out, counted, in one line; a log
entirely past the end is one line, exit 2."""

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from replay_data import T0_NS, dock_config, generate, params_yaml, write_log
from ros_harness import Client

ROOT = Path(__file__).resolve().parents[1]
CLOCK_END_NS = 2**31 * 10**9  # the first time /clock cannot carry


def _log(tmp_path: Path, start_ns: int, name: str) -> tuple[Path, Path, list[int]]:
    """20 s of a 2-line dock at 10 Hz, moved to start at ``start_ns``."""
    config = dock_config(2)
    tensions, depth = generate(config, seconds=20.0, rate=10.0, depth_rate=2.0, seed=5,
                               dropouts=False)  # fmt: skip
    move = start_ns - T0_NS
    tensions = {k: (t + move, v) for k, (t, v) in tensions.items()}
    depth = (depth[0] + move, depth[1])
    log = write_log(tmp_path / f'{name}.mcap', config, tensions, depth)
    stamps = sorted(int(s) for c in (*tensions.values(), depth) for s in c[0])
    return log, params_yaml(config, tmp_path / f'{name}.yaml'), stamps


def _play(log: Path, params: Path, wait: float = 0.0) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(p for p in (str(ROOT), env.get('PYTHONPATH')) if p)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    cmd = [sys.executable, '-m', 'catenary_monitor.cli', 'replay', str(log), '--publish',
           '--params-file', str(params), '--rate', '10', '--wait-subscribers', str(wait)]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=90)


@pytest.mark.timeout(150)
def test_clock_never_goes_backwards_where_ros_time_ends(tmp_path):
    from rosgraph_msgs.msg import Clock

    log, params, stamps = _log(tmp_path, CLOCK_END_NS - 8 * 10**9, 'end')
    kept = [s for s in stamps if s < CLOCK_END_NS]
    client = Client('clock_end_client')
    ticks: list[int] = []
    lock = threading.Lock()

    def on_clock(msg):
        with lock:
            ticks.append(msg.clock.sec * 10**9 + msg.clock.nanosec)

    client.node.create_subscription(Clock, '/clock', on_clock, 1000)
    try:
        played = _play(log, params, wait=20.0)
        time.sleep(0.5)
    finally:
        client.close()
    assert played.returncode == 0, played.stderr
    lines = [ln for ln in played.stderr.splitlines() if 'cannot carry' in ln]
    words = f'{len(stamps) - len(kept)} message(s) recorded from 2038-01-19T03:14:08Z'
    assert len(lines) == 1 and words in lines[0], played.stderr
    assert f'{len(kept)} messages published' in played.stderr
    with lock:
        seen = list(ticks)
    assert seen and all(b >= a for a, b in zip(seen, seen[1:]))  # never backwards
    assert all(0 <= t < CLOCK_END_NS for t in seen) and seen[-1] == kept[-1]


def test_a_log_past_2106_is_one_line(tmp_path):
    log, params, stamps = _log(tmp_path, (2**32 - 5) * 10**9, 'late')  # 2106-02-07
    played = _play(log, params)
    lines = played.stderr.strip().splitlines()
    assert played.returncode == 2 and len(lines) == 1, played.stderr
    assert 'every message is recorded from 2106-02-07T06:28' in lines[0], lines
    assert 'nothing to publish' in lines[0] and 'Traceback' not in played.stderr
