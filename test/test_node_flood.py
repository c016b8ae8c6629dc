"""A node that keeps its head above water: a short flood against a monitor process.

``catenary-monitor bench-flood`` (the paper's dock, 12 lines) for 4 s in bursts of 50 samples
of a line at once (200 Hz on average), the node told to step only the newest of the samples it
finds waiting (``intake_step_budget: 0``), so it coalesces whatever the machine. Then:
``/diagnostics`` never paused more than two periods, the intake status turned not-OK within two
periods of the first sample not stepped and never said "none dropped", the node's counts
(stepped, coalesced) are what its log shows (lost: at most those it could see, the samples a
gap in the sequence numbers or DDS revealed), and
``catenary-monitor replay`` of the log redoes exactly the steps the node made (its CSV rows are
the node's outputs at its tension events). The 60 s floods are the command's, not the suite's
(docs/benchmarks.md).
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
import pytest
from ros_harness import child_env

pytestmark = pytest.mark.ros


def _run(*args: str, timeout: float = 240.0) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli.main', *args],
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def _ns(text: str) -> int:
    """A CSV time (s with 9 decimals) as exact ns."""
    whole, _, frac = text.partition('.')
    return int(whole) * 10**9 + int(frac.ljust(9, '0'))


def _node_tension_outputs(log_dir, config):
    """Per line: the outputs the node published at its tension events (log time ns, array)."""
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64MultiArray

    from catenary_monitor.io.mcap_read import iter_messages, read_float64_topics

    files = sorted(log_dir.glob('*.mcap'))
    topics = [line.tension_topic for line in config.lines]
    columns, _ = read_float64_topics(files, topics)
    out = {}
    for line, topic in zip(config.lines, topics):
        stamps = set(columns[topic][0].tolist())
        rows = [
            (m.log_time_ns, deserialize_message(m.data, Float64MultiArray).data)
            for m in iter_messages(files, [f'/catenary_monitor/{line.name}/outputs'])
            if m.log_time_ns in stamps
        ]
        out[line.name] = rows
    return out, {line.name: len(columns[t][0]) for line, t in zip(config.lines, topics)}


def test_a_flooded_node_stays_on_time_counts_what_it_coalesced_and_replays_the_same(tmp_path):
    from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
    from catenary_monitor_study.bench_flood import flood_params

    log_dir = tmp_path / 'log'
    done = _run(
        'bench-flood', '--rate', '200', '--duration', '4', '--burst', '50', '--json',
        '--set', 'intake_step_budget=0', '--log-dir', str(log_dir),
    )  # fmt: skip
    assert done.stdout.strip(), done.stderr
    r = json.loads(done.stdout.splitlines()[-1])
    print({k: v for k, v in r.items() if k != 'last_intake_message'})
    assert r['not_stepped'] > 0 and r['coalescing_records'] > 0, r  # it did coalesce
    assert r['sent'] == 12 * 800 and r['logged'] >= 0.99 * r['sent'], r  # logged (or counted)
    lost = r['sent'] - r['logged']
    assert r['node_counted']['dropped'] <= lost, r  # none counted that was not lost
    checks = {k: v for k, v in r['checks'].items() if k != 'node counted what it lost'}
    assert checks == {name: True for name in checks}, r
    assert 'coalesced' in r['last_intake_message'] and r['last_intake_level'] == 2, r
    # The status's 60 s window holds the whole run, the priming samples included.
    every = r['logged_with_priming'] + lost
    want = (every - r['stepped_with_priming']) / every
    assert abs(r['last_intake_share'] - want) < 0.02, r

    # catenary-monitor replay on the node's log (the parameters it recorded): one CSV row per
    # tension the node stepped, none for those it coalesced, the node's numbers.
    out_csv = tmp_path / 'replay.csv'
    done = _run('replay', str(log_dir), '--csv', str(out_csv), '--csv-columns', 'all', '--quiet')
    assert done.returncode == 0, done.stderr
    config = flood_params(tmp_path / 'params.yaml')  # the bench's lines and topics
    node, logged = _node_tension_outputs(log_dir, config)
    with open(out_csv) as f:
        rows = list(csv.DictReader(f))
    for line in config.lines:
        mine = [row for row in rows if row['line'] == line.name]
        want = node[line.name]
        assert len(want) < logged[line.name]  # some of this line's samples were coalesced
        assert [_ns(row['time']) for row in mine] == [t for t, _ in want]
        for key in ('top_tension', 'uplift_force', 'anchor_margin', 'tide_margin_at_length'):
            got = np.array([float(row[key]) for row in mine])
            exp = np.array([v[OUTPUT_FIELDS.index(key)] for _, v in want])
            np.testing.assert_allclose(got, exp, atol=6e-4, rtol=0, err_msg=key)
        levels = [int(v[OUTPUT_FIELDS.index('level')]) for _, v in want]
        names = ['OK', 'WARN', 'ERROR', 'STALE']
        assert [row['level'] for row in mine] == [names[k] for k in levels]


def test_the_outputs_encoded_in_place_decode_as_rclpy_serializes_them():
    """The node packs each output's values after its layout, serialized once: rclpy decodes it
    to the message rclpy itself serializes (values exact: NaN, inf, -0.0, subnormals), and a
    Float64 sample read in place is the deserialized value."""
    import math
    import struct

    from rclpy.serialization import deserialize_message, serialize_message
    from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension

    from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
    from catenary_monitor.ros.node import OutputEncoder, float64_value

    n = len(OUTPUT_FIELDS)
    msg = Float64MultiArray()
    msg.layout.dim = [MultiArrayDimension(label=','.join(OUTPUT_FIELDS), size=n, stride=n)]
    encode = OutputEncoder(msg)
    assert encode.prefix is not None  # the fast path is what is tested
    rng = np.random.default_rng(1)
    special = [math.nan, math.inf, -math.inf, -0.0, 5e-324, 1.7976931348623157e308]
    for values in [tuple(rng.normal(0, 1e6, n)), tuple((special * n)[:n])]:
        got = deserialize_message(encode(values), Float64MultiArray)
        want = Float64MultiArray(layout=msg.layout, data=list(values))
        back = deserialize_message(serialize_message(want), Float64MultiArray)
        assert got.layout == back.layout
        assert struct.pack(f'<{n}d', *got.data) == struct.pack(f'<{n}d', *back.data)
    for value in [372e3, -0.0, math.inf, 5e-324]:
        assert struct.pack('<d', float64_value(serialize_message(Float64(data=value)))) == (
            struct.pack('<d', value)
        )
    assert math.isnan(float64_value(serialize_message(Float64(data=math.nan))))
