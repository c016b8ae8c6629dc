"""Nobody silences the monitor, and it loses nothing silently: against a monitor process.

* ``use_sim_time`` with no ``/clock`` (or a ``/clock`` that stops): the wall-clock watchdog
  keeps ``/diagnostics`` coming with the ``clock`` status ERROR.
* Samples lost before the node handles them are counted on the ``intake`` status
  (``messages_dropped``) and make it WARN or ERROR; a normal rate leaves it OK with 0.

Every wait is bounded and waits for the event it needs.
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from ros_harness import child_env, output_of, start_monitor, stop, write_params

pytestmark = pytest.mark.ros

W, DEPTH, MBL = 1300.0, 20.85, 4.827e6
CLOCK, INTAKE = 'catenary_monitor: clock', 'catenary_monitor: intake'
OK, ERROR = 0, 2
#: The flood's rate per line [Hz], and the load cells' configured one: 12 lines at 1 kHz are
#: more than the node steps on one core, or more than the flood's publisher sends on a loaded
#: one: a loss either way (at 400 Hz a lightly loaded node stepped 98.9 % of them, at the
#: edge of the warning's 1 %, and once took over 40 s to lose more).
FLOOD = 1000.0


def _lines(n):
    return {f'l{k:02d}': dict(weight=W, anchor_distance=121.06, mbl=MBL) for k in range(n)}


def test_use_sim_time_without_clock_still_publishes_a_clock_error(client, tmp_path):
    params = write_params(tmp_path / 'params.yaml', _lines(1))
    t0 = time.monotonic()
    proc = start_monitor(params, tmp_path / 'log', '-p', 'use_sim_time:=true')
    try:
        s = client.wait_status(CLOCK, 30.0, ERROR, since=t0)
        assert s['message'].startswith('ROS clock stopped: /clock not advancing for '), s
        t0 = time.monotonic()
        client.wait_for(lambda: len(client.levels(CLOCK, t0)) >= 2, 10.0, 'more /diagnostics')
        assert 'ROS clock stopped' in output_of(proc)
    finally:
        assert stop(proc) == 0


def test_a_clock_that_stops_is_reported(client, tmp_path):
    from rosgraph_msgs.msg import Clock

    pub = client.node.create_publisher(Clock, '/clock', 10)
    running = threading.Event()
    running.set()

    def tick():
        t = 1000.0
        while running.is_set():
            msg = Clock()
            msg.clock.sec, msg.clock.nanosec = int(t), int((t % 1) * 1e9)
            pub.publish(msg)
            t += 0.05
            time.sleep(0.05)

    params = write_params(tmp_path / 'params.yaml', _lines(1))
    t_start = time.monotonic()
    proc = start_monitor(params, tmp_path / 'log', '-p', 'use_sim_time:=true')
    thread = threading.Thread(target=tick, daemon=True)
    thread.start()
    try:
        s = client.wait_status(CLOCK, 30.0, OK, since=t_start)
        assert s['message'] == 'ROS clock advancing (use_sim_time)', s
        running.clear()
        thread.join(5.0)
        t0 = time.monotonic()
        s = client.wait_status(CLOCK, 30.0, ERROR, since=t0)
        assert 'ROS clock stopped: /clock not advancing for' in s['message'], s
    finally:
        running.clear()
        assert stop(proc) == 0
        client.node.destroy_publisher(pub)


def _flood(names, rate, duration):
    script = str(Path(__file__).with_name('flood_publisher.py'))
    return subprocess.Popen(
        [sys.executable, script, ','.join(names), str(rate), str(duration)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=child_env(),
    )


def _end(flood):
    """Stop the flood cleanly (SIGTERM), killed only if it does not end in 10 s."""
    flood.terminate()
    try:
        flood.wait(10)
    except subprocess.TimeoutExpired:
        flood.kill()
        flood.wait(10)


def _dropped(status):
    return int(status['values']['messages_dropped'])


def _to_act_on(status):
    """True when the intake's values show a loss an operator must act on, by the defaults:
    at least intake_warn_count samples and intake_warn_share of the window's not handled."""
    from catenary_monitor.core.config.parameters import AlarmConfig

    a = AlarmConfig()
    dropped, handled = _dropped(status), int(status['values']['messages_handled'])
    share = dropped / (dropped + handled) if dropped + handled else 0.0
    return dropped >= a.intake_warn_count and share >= a.intake_warn_share


@pytest.mark.parametrize('executor', ['single', 'events'])
def test_an_overflowing_intake_is_counted_and_reported(client, tmp_path, monkeypatch, executor):
    """12 lines at 1 kHz into the node (12,010 samples a second), the load cells' rate
    configured: a loss to act on (lost against the publisher's sequence numbers, coalesced,
    or never sent at the rate: missing), and the intake leaves OK with a headline naming it,
    under either executor. No message of the intake, warned or not, leaves out a loss
    counted in its values (a smaller one is said with its figures, beside the busy
    callbacks too)."""
    monkeypatch.setenv('CATENARY_MONITOR_EXECUTOR', executor)
    lines = _lines(12)
    params = write_params(tmp_path / 'params.yaml', lines, tension_sample_rate=FLOOD)
    t0 = time.monotonic()  # the client keeps what earlier tests' monitors published
    proc = start_monitor(params, tmp_path / 'log')
    flood = _flood(list(lines), FLOOD, 60.0)
    try:
        s = client.wait_status(INTAKE, 60.0, since=t0, check=_to_act_on)
        print(f'\nintake after {time.monotonic() - t0:.0f} s:', s['level'], s['message'])
        assert s['level'] != OK, s
        # the headline the operator reads names the loss (lost or coalesced, or missing)
        assert 'dropped' in s['message'] or 'missing' in s['message'], s
        with client.lock:
            seen = [e[INTAKE] for t, e in client.diagnostics if t >= t0 and INTAKE in e]
        for st in seen:  # never silent: the figure of the values in the full message
            if _dropped(st):
                assert f"{_dropped(st)} of " in st['values']['detail'], st
    finally:
        _end(flood)
        assert stop(proc) == 0


@pytest.mark.parametrize('executor', ['single', 'events'])
def test_samples_missing_against_the_sample_rate_are_counted(
    client, tmp_path, monkeypatch, executor
):
    """Load cells configured at 40 Hz that deliver 20 Hz: half the samples never reach the
    node (whatever the executor can see), counted per line and reported ERROR."""
    monkeypatch.setenv('CATENARY_MONITOR_EXECUTOR', executor)
    params = write_params(tmp_path / 'params.yaml', _lines(2), tension_sample_rate=40.0)
    t0 = time.monotonic()
    proc = start_monitor(params, tmp_path / 'log')
    flood = _flood(['l00', 'l01'], 20.0, 90.0)
    try:
        s = client.wait_status(INTAKE, 80.0, since=t0, check=lambda s: s['level'] == ERROR)
        assert 'missing' in s['message'], s
        assert int(s['values']['l00.messages_missing']) > 0, s
        assert int(s['values']['messages_dropped']) >= int(s['values']['messages_missing']), s
    finally:
        _end(flood)
        assert stop(proc) == 0


def test_a_normal_rate_drops_nothing(client, tmp_path, monkeypatch):
    """2 lines at 20 Hz: the intake stays OK with 0 dropped, and the counts the node recorded
    (its last Intake event at close included) add up to every sample it logged."""
    import json

    from rclpy.serialization import deserialize_message
    from std_msgs.msg import String

    from catenary_monitor.core.monitor.events import EVENTS_TOPIC
    from catenary_monitor.io.mcap_read import iter_messages

    monkeypatch.setenv('CATENARY_MONITOR_EXECUTOR', 'single')
    params = write_params(tmp_path / 'params.yaml', _lines(2))
    proc = start_monitor(params, tmp_path / 'log')
    flood = _flood(['l00', 'l01'], 20.0, 5.0)
    try:
        assert 'sent' in flood.communicate(timeout=60)[0]
        t0 = time.monotonic()  # statuses published after every sample was sent
        client.wait_for(lambda: len(client.levels(INTAKE, t0)) >= 2, 20.0, 'intake status')
        s = client.latest_status(INTAKE, t0)
        assert s['level'] == OK and _dropped(s) == 0, s
        assert s['values']['l00.messages_dropped'] == '0', s
    finally:
        if flood.poll() is None:
            _end(flood)
        assert stop(proc) == 0
    files = sorted((tmp_path / 'log').glob('*.mcap'))
    records = [
        json.loads(deserialize_message(m.data, String).data)
        for m in iter_messages(files, [EVENTS_TOPIC])
    ]
    intake = [r for r in records if r.get('kind') == 'intake']
    topics = ['/mooring/l00/tension', '/mooring/l01/tension', '/tide/depth']
    logged = sum(1 for _ in iter_messages(files, topics))
    received = sum(sum(r['received']) + sum(r.get('coalesced', [])) for r in intake)
    assert received == logged and logged >= 150, (received, logged)
    assert sum(sum(r['dropped']) for r in intake) == 0
