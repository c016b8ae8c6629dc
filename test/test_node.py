"""The live node with real rclpy and DDS: the monitor runs as its own process.

One monitor process serves the behaviour tests (each on its own line, so they do not interfere)
and is stopped with SIGTERM at the end to check its MCAP log; a second one is SIGKILLed.
Every wait is bounded; no sleep is an assertion.
"""

from __future__ import annotations

import math
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest
from ros_harness import child_env, output_of, start_monitor, stop, write_params
from scipy.optimize import brentq

from catenary_monitor import solve

pytestmark = [pytest.mark.ros, pytest.mark.usefixtures('no_callback_errors')]

W = 1300.0  # N/m, the paper's chain
DEPTH = 20.85  # m
MBL = 4.827e6  # N
CLEAR_HOLD = 1.0  # s, shortened for the tests
TENSION_TIMEOUT = 1.0  # s
RATE = 2.0  # Hz, diagnostics
LINES = {
    'val': dict(weight=W, anchor_distance=120.0, mbl=MBL, hook_height=1.5),
    'up': dict(weight=W, anchor_distance=121.06, mbl=MBL),
    'bad': dict(weight=W, anchor_distance=120.0, mbl=MBL),
    'stale': dict(weight=W, anchor_distance=120.0, mbl=MBL),
}
KEYS = (
    'top_tension',
    'depth',
    'horizontal_tension',
    'min_anchor_distance',
    'anchor_margin',
    'uplift_force',
    'tide_margin',
    'load_margin',
    'safety_factor',
)
OK, WARN, ERROR, STALE = 0, 1, 2, 3


def topic(line: str) -> str:
    return f'/mooring/{line}/tension'


def out_topic(line: str) -> str:
    return f'/catenary_monitor/{line}/outputs'


def name(line: str) -> str:
    return f'catenary_monitor: {line}'


@pytest.fixture(scope='module')
def monitor(tmp_path_factory, client):
    """The monitor on a ``/**`` params file, synchronised: every input topic delivers."""
    tmp = tmp_path_factory.mktemp('monitor')
    params = write_params(
        tmp / 'params.yaml',
        LINES,
        key='/**',
        clear_hold=CLEAR_HOLD,
        warn_clear_hold=CLEAR_HOLD,
        margin_clear_hold=CLEAR_HOLD,
        tension_timeout=TENSION_TIMEOUT,
        diagnostic_rate=RATE,
        depth_timeout=30.0,
        # These tests step the tension (400 kN -> 1.6 MN, 1e300 N -> 400 kN in one sample),
        # which the sensor check calls a spike (test/test_sensor.py): not held here.
        sensor_hold=0.0,
        # The wave window (default 30 s) would keep those steps' swing as wave tension, and the
        # dynamic uplift it implies, for 30 s after them (test/test_uncertainty.py): 1 s here,
        # so that each test's clear input clears within clear_hold.
        wave_window=1.0,
        # The uplift-time warning does not clear on an unknown forecast (docs/node.md); the
        # flat tide fed at 10 Hz gives a known trend (not rising) 2.5 s after the start.
        tide_trend_window=5.0,
    )
    proc = start_monitor(params, tmp / 'log')
    try:
        for line in LINES:
            client.subscribe_outputs(out_topic(line))
        client.wait_matched(['/tide/depth', *map(topic, LINES)], 30.0)
        client.feed('/tide/depth', DEPTH)
        client.wait_status(
            'catenary_monitor: tide', 10.0, OK, check=lambda s: s['values']['depth'] == repr(DEPTH)
        )
        for line in LINES:  # DDS delivers from now on: each line has produced an output
            client.feed(topic(line), 400e3)
            client.wait_for(lambda: client.outputs[out_topic(line)], 10.0, f'output of {line}')
            client.feed(topic(line), None)
        with client.lock:
            client.sent.clear()
            client.sent['/tide/depth'] = []
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)


def expected(tension: float, line: str = 'val', depth: float = DEPTH):
    c = LINES[line]
    return solve(
        W,
        depth + c.get('hook_height', 0.0),
        tension=tension,
        anchor_distance=c['anchor_distance'],
        mbl=MBL,
    )


def test_outputs_and_diagnostics_give_the_core_values(client, monitor):
    t0 = time.monotonic()
    client.feed(topic('val'), 412345.0)
    ref = expected(412345.0)
    _, data = client.wait_for(
        lambda: next(
            (
                o
                for o in reversed(client.outputs[out_topic('val')])
                if o[0] > t0 and o[1][0] == 412345.0
            ),
            None,
        ),
        5.0,
        'output of val',
    )
    got = dict(
        zip(
            (
                'top_tension',
                'depth',
                'horizontal_tension',
                'min_anchor_distance',
                'anchor_margin',
                'uplift_force',
                'tide_margin',
                'load_margin',
                'safety_factor',
                'anchor_angle_deg',
                'suspended_length',
                'status',
                'level',
            ),
            data,
        )
    )
    assert got['depth'] == pytest.approx(DEPTH + 1.5, rel=1e-15)
    for key in KEYS[2:]:
        assert got[key] == pytest.approx(getattr(ref, key), rel=1e-12, abs=1e-9), key
    assert got['status'] == 0
    status = client.wait_status(
        name('val'),
        5.0,
        OK,
        since=t0,
        check=lambda s: s['values']['top_tension'] == repr(412345.0),
    )
    values = {k: float(v) for k, v in status['values'].items() if k in KEYS}
    assert set(KEYS) <= set(status['values'])
    assert values['depth'] == pytest.approx(DEPTH + 1.5, rel=1e-15)
    for key in KEYS[2:]:
        assert values[key] == pytest.approx(getattr(ref, key), rel=1e-12, abs=1e-9), key
    assert status['hardware_id'] == topic('val')


def _tension_at_margin(margin: float) -> float:
    """Hook tension whose anchor margin at line 'up' is ``margin`` (m) at DEPTH."""
    return brentq(lambda t: expected(t, 'up').anchor_margin - margin, 3e5, 6e5, xtol=1e-6)


def test_uplift_raises_error_and_clears_with_hysteresis(client, monitor):
    client.feed(topic('up'), 400e3)
    client.wait_status(name('up'), 5.0, OK)
    # The table-3 typhoon: the first update showing uplift raises ERROR.
    t_up = time.monotonic()
    client.feed(topic('up'), 1623.5e3)
    s = client.wait_status(name('up'), 3.0, ERROR, since=t_up)
    assert 'uplift' in s['message'] and 'kN' in s['message']
    uplift = expected(1623.5e3, 'up').uplift_force
    assert float(s['values']['uplift_force']) == pytest.approx(uplift, rel=1e-9)
    # Hysteresis: no uplift any more, but the anchor margin (0.5 m) is below the 1 m clear level.
    t_hold = time.monotonic()
    t_near = _tension_at_margin(0.5)
    assert expected(t_near, 'up').uplift_force == 0.0
    client.feed(topic('up'), t_near)
    client.wait_for(
        lambda: len(client.levels(name('up'), t_hold)) >= 3 * CLEAR_HOLD * RATE,
        10.0,
        'diagnostics over three clear holds',
    )
    assert set(client.levels(name('up'), t_hold)) == {ERROR}
    # Wave-frequency swing across the threshold (half period < clear_hold): one alarm, no chatter.
    t_wave = time.monotonic()
    for i in range(11):  # ends on an uplift sample
        value = 1623.5e3 if i % 2 == 0 else 400e3
        client.feed(topic('up'), value)
        client.wait_for(
            lambda: any(
                o[1][0] == value and o[0] > t_wave for o in client.outputs[out_topic('up')][-5:]
            ),
            3.0,
            'the swing to reach the monitor',
        )
        time.sleep(0.3)  # paces the swing; assertions below wait on messages
    assert set(client.levels(name('up'), t_wave)) == {ERROR}
    # Clear: ERROR -> OK only after clear_hold of clear input, in one transition.
    client.feed(topic('up'), 400e3)
    t_clear = time.monotonic()
    client.wait_status(name('up'), CLEAR_HOLD + 4.0, OK, since=t_clear)
    with client.lock:
        first_ok = next(
            t
            for t, e in client.diagnostics
            if t > t_clear and name('up') in e and e[name('up')]['level'] == OK
        )
    assert first_ok - t_clear >= CLEAR_HOLD - 0.2
    levels = client.levels(name('up'), t_up)
    changes = [b for a, b in zip(levels, levels[1:]) if a != b]
    assert changes == [OK], levels


@pytest.mark.parametrize(
    'value, words',
    [
        (math.nan, 'NaN'),
        (-5e3, 'hook tension must exceed'),
        # 400 kN to 20 kN < w h = 27.1 kN: what a chain parted below the hook reads, named as
        # such at the next tick (never an impossible input first)
        (20e3, 'suspected parted'),
        (1e300, 'above 10 x MBL'),  # an implausible reading, not a solver failure
    ],
)
def test_impossible_inputs_give_error_and_node_keeps_running(client, monitor, value, words):
    client.feed(topic('bad'), 400e3)
    client.wait_status(name('bad'), CLEAR_HOLD + 5.0, OK)
    t0 = time.monotonic()
    client.feed(topic('bad'), value)
    s = client.wait_status(name('bad'), 3.0, ERROR, since=t0)
    assert words in s['message'], s['message']
    assert ('impossible input' in s['message']) == (words != 'suspected parted'), s['message']
    assert monitor.poll() is None
    t1 = time.monotonic()
    client.feed(topic('bad'), 400e3)
    s = client.wait_status(name('bad'), CLEAR_HOLD + 5.0, OK, since=t1)
    assert float(s['values']['top_tension']) == 400e3
    assert client.latest_status(name('val'))['level'] == OK  # other lines unaffected


def test_stale_tension_gives_stale_then_recovers(client, monitor):
    client.feed(topic('stale'), 400e3)
    client.wait_status(name('stale'), 5.0, OK)
    client.feed(topic('stale'), None)
    t0 = time.monotonic()
    s = client.wait_status(name('stale'), TENSION_TIMEOUT + 2.0 / RATE + 2.0, STALE, since=t0)
    assert 'tension stale' in s['message'] and 'timeout' in s['message']
    assert client.latest_status(name('val'))['level'] == OK
    t1 = time.monotonic()
    client.feed(topic('stale'), 400e3)
    client.wait_status(name('stale'), 3.0, OK, since=t1)


def test_diagnostics_steady_rate_and_named_statuses(client, monitor):
    t0 = time.monotonic()
    client.wait_for(
        lambda: len([t for t, _ in client.diagnostics if t > t0]) >= 4,
        5.0,
        'four diagnostic arrays',
    )
    with client.lock:
        times = [t for t, _ in client.diagnostics if t > t0]
        names = set(client.diagnostics[-1][1])
    assert {name(n) for n in LINES} | {
        'catenary_monitor: tide',
        'catenary_monitor: logger',
    } <= names
    assert max(b - a for a, b in zip(times, times[1:])) < 1.5 / RATE + 0.3
    assert client.latest_status('catenary_monitor: logger')['level'] == OK


def test_parameter_change_is_validated_by_config(client, monitor):
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    params = AsyncParameterClient(client.node, 'catenary_monitor')
    assert params.wait_for_services(10.0)

    def set_(name, value):
        future = params.set_parameters([Parameter(name, value=value)])
        client.wait_for(future.done, 10.0, f'set {name}')
        return future.result().results[0]

    future = params.describe_parameters(['val.weight', 'lines', 'clear_hold'])
    client.wait_for(future.done, 10.0, 'describe_parameters')
    weight, lines, hold = future.result().descriptors
    assert weight.description and 'N/m' in weight.description
    assert (
        weight.floating_point_range[0].from_value,
        weight.floating_point_range[0].to_value,
    ) == (1.0, 1.0e5)
    assert lines.read_only and hold.floating_point_range and not hold.read_only

    bad = set_('val.mbl', -1.0)
    assert not bad.successful and 'val.mbl' in bad.reason
    assert not set_('lines', ['x']).successful  # structural: read-only
    same = set_('tension_timeout', TENSION_TIMEOUT)  # decides alarms: refused at runtime
    assert not same.successful and 'allow_runtime_changes' in same.reason
    assert not set_('allow_runtime_changes', True).successful  # read-only
    assert monitor.poll() is None


def test_unwritable_log_dir_is_an_error_diagnostic_not_a_stop(client, tmp_path):
    blocker = tmp_path / 'a_file'
    blocker.write_text('not a directory')
    lines = {'nolog': dict(weight=W, anchor_distance=120.0, mbl=MBL)}
    params = write_params(tmp_path / 'params.yaml', lines)
    proc = start_monitor(params, blocker / 'log', out_dir=tmp_path)
    try:
        s = client.wait_status(
            'catenary_monitor: logger',
            30.0,
            ERROR,
            check=lambda s: str(blocker) in s['values']['detail'],  # the path: in the detail
        )
        assert s['message'].startswith('MCAP log not written') and len(s['message']) <= 100
        client.wait_matched([topic('nolog')], 30.0)
        client.feed('/tide/depth', DEPTH)
        client.feed(topic('nolog'), 400e3)
        s = client.wait_status(
            name('nolog'), 10.0, OK, check=lambda s: s['values']['top_tension'] == repr(400e3)
        )
        assert proc.poll() is None
    finally:
        client.feed(topic('nolog'), None)
        client.feed('/tide/depth', None)
        assert stop(proc, signal.SIGTERM) == 0


def test_level_change_publishes_diagnostics_at_once(client, tmp_path):
    """With a 50 s diagnostics period, the uplift ERROR still arrives within seconds."""
    lines = {'now': dict(weight=W, anchor_distance=121.06, mbl=MBL)}
    params = write_params(tmp_path / 'params.yaml', lines, diagnostic_rate=0.02)
    proc = start_monitor(params, tmp_path / 'log')
    try:
        client.subscribe_outputs(out_topic('now'))
        client.wait_matched(['/tide/depth', topic('now')], 30.0)
        client.feed('/tide/depth', DEPTH)
        client.feed(topic('now'), 400e3)
        client.wait_for(lambda: client.outputs[out_topic('now')], 10.0, 'output of now')
        t_up = time.monotonic()
        client.feed(topic('now'), 1623.5e3)
        s = client.wait_status(name('now'), 5.0, ERROR, since=t_up)
        assert 'uplift' in s['message']
        assert time.monotonic() - t_up < 10.0  # far inside the 50 s period: published on change
    finally:
        client.feed(topic('now'), None)
        client.feed('/tide/depth', None)
        assert stop(proc, signal.SIGTERM) == 0


def _read_log(log_dir: Path):
    """Decode every message of the finished log with the mcap library (needs the summary)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = {}
    for path in sorted(log_dir.glob('*.mcap')):
        with open(path, 'rb') as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            assert reader.get_summary() is not None, f'{path} has no summary'
            assert reader.get_header().profile == 'ros2'
            for schema, channel, message, decoded in reader.iter_decoded_messages():
                assert channel.message_encoding == 'cdr' and schema.encoding == 'ros2msg'
                out.setdefault(channel.topic, []).append((message.log_time, decoded))
    return out


def test_sigterm_exits_zero_and_the_log_holds_every_message(client, monitor, tmp_path):
    for line in LINES:
        client.feed(topic(line), None)
    client.feed('/tide/depth', None)
    # Let the last inputs arrive (their outputs come back), then stop.
    mine = {topic(line) for line in LINES}  # other tests' monitors have their own lines
    with client.lock:
        last = {t: v[-1][1] for t, v in client.sent.items() if v and t in mine}
    for t, v in last.items():
        line = t.split('/')[2]
        client.wait_for(
            lambda: client.outputs[out_topic(line)]
            and client.outputs[out_topic(line)][-1][1][0] == v
            or math.isnan(v),
            3.0,
            f'last output of {line}',
        )
    assert stop(monitor, signal.SIGTERM) == 0
    log_dir = Path(monitor.args[monitor.args.index('-p') + 1].split(':=', 1)[1])
    logged = _read_log(log_dir)
    with client.lock:
        sent = {
            t: [v for _, v in vals]
            for t, vals in client.sent.items()
            if t in mine or t == '/tide/depth'
        }
        outputs = {
            t: [tuple(d) for _, d in vals]
            for t, vals in client.outputs.items()
            if t in {out_topic(line) for line in LINES}
        }
        stamps = [
            st for st, (_, e) in zip(client.diag_stamps, client.diagnostics) if name('val') in e
        ]  # this monitor's arrays
    # Every input sent is logged, but for the odd best-effort sample DDS may drop before the
    # node sees it (not the logger's loss); every output that came back is logged.
    for t, values in sent.items():
        got = Counter(repr(m.data) for _, m in logged.get(t, []))
        missing = sum((Counter(map(repr, values)) - got).values())
        assert missing <= max(2, len(values) // 50), f'{t}: {missing} of {len(values)} not logged'
    for t, arrays in outputs.items():
        got = Counter(repr(tuple(m.data)) for _, m in logged[t])
        missing = Counter(map(repr, arrays)) - got
        assert not missing, f'{t}: {sum(missing.values())} outputs not logged'
    logged_stamps = {
        m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in logged['/diagnostics']
    }
    assert set(stamps) <= logged_stamps
    assert 'stopped; MCAP log closed' in output_of(monitor)


def test_sigkill_loses_at_most_the_last_second(client, tmp_path):
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64

    from catenary_monitor.io.mcap_read import iter_messages

    lines = {'kill': dict(weight=W, anchor_distance=120.0, mbl=MBL)}
    params = write_params(tmp_path / 'params.yaml', lines)  # top key: catenary_monitor
    proc = start_monitor(params, tmp_path / 'log')
    try:
        client.subscribe_outputs(out_topic('kill'))
        client.wait_matched([topic('kill')], 30.0)
        client.feed('/tide/depth', DEPTH)
        client.feed(topic('kill'), 400e3)
        client.wait_for(
            lambda: any(o[1][0] == 400e3 for o in client.outputs[out_topic('kill')]),
            10.0,
            'a solved output',
        )
        client.feed(topic('kill'), None)
        t_start = time.monotonic()
        i = 0

        def received_before(t: float) -> int:
            with client.lock:
                return len([o for o in client.outputs[out_topic('kill')] if t_start < o[0] < t])

        # Publish until more than 20 outputs are older than 1.2 s (a loaded machine is slower).
        while received_before(time.monotonic() - 1.2) <= 20 or time.monotonic() - t_start < 3.0:
            client.publish(topic('kill'), 400e3 + i)
            i += 1
            time.sleep(0.02)  # paces the publisher at 50 Hz
            assert time.monotonic() - t_start < 40.0, 'the monitor does not answer'
        proc.send_signal(signal.SIGKILL)
        t_kill = time.monotonic()
        assert proc.wait(5) == -signal.SIGKILL
    finally:
        client.feed('/tide/depth', None)
        if proc.poll() is None:
            proc.kill()
    logged = {
        deserialize_message(m.data, Float64).data
        for m in iter_messages(sorted((tmp_path / 'log').glob('*.mcap')), [topic('kill')])
    }
    with client.lock:
        # Outputs the client got more than a second before the kill: the node had their input.
        old = [o[1][0] for o in client.outputs[out_topic('kill')] if t_start < o[0] < t_kill - 1.0]
    assert len(old) > 20
    missing = [v for v in old if v not in logged]
    assert not missing, f'{len(missing)} of {len(old)} inputs older than 1 s lost after SIGKILL'


BAD = {
    'missing': ({'l1': dict(weight=W, anchor_distance=120.0)}, "'l1.mbl'"),
    'range': ({'l1': dict(weight=-1300.0, anchor_distance=120.0, mbl=MBL)}, "'l1.weight'"),
    'unknown': ({'l1': dict(weight=W, anchor_distance=120.0, mbl=MBL, wieght=1.0)}, "'l1.wieght'"),
}


@pytest.mark.parametrize('case', sorted(BAD))
def test_bad_parameter_file_exits_nonzero_with_one_line(tmp_path, case):
    lines, needle = BAD[case]
    params = write_params(tmp_path / 'p.yaml', lines)
    r = subprocess.run(
        [
            sys.executable,
            '-m',
            'catenary_monitor.ros.node',
            '--ros-args',
            '--params-file',
            str(params),
        ],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=30,
    )
    assert r.returncode != 0
    err = r.stderr.strip().splitlines()
    assert len(err) == 1 and needle in err[0], r.stderr
    assert r.stdout == ''


def test_run_command_rejects_a_missing_file(tmp_path):
    r = subprocess.run(
        [
            sys.executable,
            '-m',
            'catenary_monitor.cli',
            'run',
            '--params-file',
            str(tmp_path / 'nope.yaml'),
        ],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=30,
    )
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and 'nope.yaml' in r.stderr
