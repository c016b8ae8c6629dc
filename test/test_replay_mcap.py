"""Replay's writers: numpy CDR against rclpy's serializer, the column MCAP writer against the
mcap library's reader (CRCs, indexes, summary) and the project's own reader."""

import functools

import numpy as np
import pytest

from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.io.cdr import (
    diagnostic_array,
    diagnostic_array_bodies,
    diagnostic_array_parts,
    float64_payloads,
    key_values,
    multiarray_payloads,
    status_bodies,
    status_body,
    status_header,
)
from catenary_monitor.io.mcap_column_writer import ColumnWriter
from catenary_monitor.io.mcap_read import read_float64_topics
from catenary_monitor.io.ros_schemas import message_definition

VALUES = [0.0, -1.5, 372e3, float('nan'), float('inf'), 1e-300]


def test_cdr_equals_rclpy():
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from rclpy.serialization import deserialize_message, serialize_message
    from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension

    for v, row in zip(VALUES, float64_payloads(np.array(VALUES))):
        assert bytes(row) == serialize_message(Float64(data=v))
    label = ','.join(OUTPUT_FIELDS)
    data = np.arange(3 * len(OUTPUT_FIELDS), dtype=float).reshape(3, -1) * 1.25
    for row, payload in zip(data, multiarray_payloads(label, data)):
        msg = Float64MultiArray(data=row.tolist())
        msg.layout.dim = [MultiArrayDimension(label=label, size=len(row), stride=len(row))]
        assert deserialize_message(bytes(payload), Float64MultiArray) == msg
        assert len(payload) == len(serialize_message(msg))
    statuses = [
        (
            2,
            'catenary_monitor: line_01',
            'anchor uplift 193.3 kN > allowed 0.0 kN',
            '/mooring/line_01/tension',
            [('top_tension', '1623500.0'), ('depth', 'nan')],
        ),
        (0, 'catenary_monitor: l2', 'OK', 'hw', []),
        (3, 'x', 'tension stale: é', '', [('a', 'b'), ('abcdef', '1')]),
    ]
    raw = diagnostic_array(1_763_900_000_123_456_789, statuses)
    parts = diagnostic_array_parts(
        1_763_900_000_123_456_789,
        [
            (functools.partial(status_header, lv, n, m, h, len(kv)), key_values(kv))
            for lv, n, m, h, kv in statuses
        ],
    )
    assert raw == parts
    msg = deserialize_message(raw, DiagnosticArray)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1_763_900_000, 123_456_789)
    assert [
        (s.level[0], s.name, s.message, s.hardware_id, [(kv.key, kv.value) for kv in s.values])
        for s in msg.status
    ] == statuses
    ref = DiagnosticArray(
        status=[
            DiagnosticStatus(
                level=bytes([lv]),
                name=n,
                message=m,
                hardware_id=h,
                values=[KeyValue(key=k, value=v) for k, v in kv],
            )
            for lv, n, m, h, kv in statuses
        ]
    )
    ref.header.stamp.sec, ref.header.stamp.nanosec = 1_763_900_000, 123_456_789
    # rclpy leaves garbage in padding bytes: compare messages, and sizes.
    assert msg == ref and len(raw) == len(serialize_message(ref))


def test_status_bodies_encode_what_diagnostic_array_does():
    """Statuses of one shape encoded a column at a time (replay's --out) give the bytes of
    the field-by-field encoder: every length mod 4, empty and non-ASCII strings, constants
    and per-status columns, any number of statuses and keys."""
    import random

    rng = random.Random(11)

    def word():
        return ''.join(rng.choice('abé€x0.-') for _ in range(rng.randrange(0, 10)))

    for trial in range(400):
        n = rng.randrange(0, 7)
        keys = [word() for _ in range(rng.randrange(0, 6))]

        def field():
            return word() if rng.random() < 0.4 else [word() for _ in range(n)]

        name, message, hardware_id = field(), field(), field()
        values = [field() for _ in keys]
        buf, starts, ends = status_bodies(n, name, message, hardware_id, keys, values)

        def get(f, i):
            return f if isinstance(f, str) else f[i]

        statuses = []
        for i in range(n):
            pairs = [(k, get(v, i)) for k, v in zip(keys, values)]
            row = (get(name, i), get(message, i), get(hardware_id, i), pairs)
            assert buf[starts[i] : ends[i]] == status_body(*row), (trial, i)
            statuses.append((rng.randrange(4), *row))
        stamp = rng.randrange(0, 1 << 60)
        bodies = [buf[a:b] for a, b in zip(starts, ends)]
        got = diagnostic_array_bodies(stamp, [s[0] for s in statuses], bodies)
        assert got == diagnostic_array(stamp, statuses), trial


@pytest.mark.parametrize('compression', ['zstd', 'lz4', 'none'])
def test_column_writer_reads_back(compression, tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path = tmp_path / 'w.mcap'
    rng = np.random.default_rng(1)
    n = 20000
    t = np.sort(rng.integers(10**18, 10**18 + 10**12, n))
    v = rng.normal(size=n)
    which = rng.integers(0, 3, n)
    with open(path, 'wb') as f:
        w = ColumnWriter(f, compression=compression, chunk_bytes=64 * 1024)
        sid = w.register_schema(
            'std_msgs/msg/Float64', 'ros2msg', message_definition('std_msgs/msg/Float64').encode()
        )
        ids = [
            w.register_channel(f'/t{k}', 'cdr', sid, {'offered_qos_profiles': ''})
            for k in range(3)
        ]
        w.add_metadata('catenary_monitor', {'version': 'test'})
        w.write_columns(np.array(ids)[which], t, float64_payloads(v))
        w.finish()
    with open(path, 'rb') as f:
        reader = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert summary.statistics.message_count == n
        assert len(summary.chunk_indexes) > 5
        assert [m.name for m in reader.iter_metadata()] == ['catenary_monitor']
        got = [
            (c.topic, m.log_time, d.data)
            for _, c, m, d in reader.iter_decoded_messages(log_time_order=True)
        ]
    order = np.argsort(t, kind='stable')
    assert [g[1] for g in got] == t[order].tolist()
    assert sorted(g[2] for g in got) == sorted(v.tolist())
    cols, report = read_float64_topics(path, ['/t0', '/t1', '/t2'])
    assert report.complete and sum(report.messages.values()) == n
    for k in range(3):
        np.testing.assert_array_equal(cols[f'/t{k}'][1], v[which == k])
