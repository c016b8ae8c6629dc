"""Behaviour tests of catenary_monitor.io.mcap_log (writer) against independent readers."""

from __future__ import annotations

import errno
import os
import re
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory

from catenary_monitor.io import ros_schemas
from catenary_monitor.io.mcap_log import McapLogger
from catenary_monitor.io.mcap_read import read_float64_topics

REPO = Path(__file__).resolve().parents[1]
FLOAT64 = 'std_msgs/msg/Float64'
T0 = 1_795_000_000_000_000_000  # ns, an arbitrary 2026 epoch time


def cdr_f64(value: float) -> bytes:
    """CDR (little endian) std_msgs/msg/Float64."""
    return b'\x00\x01\x00\x00' + struct.pack('<d', value)


class FakeClock:
    """Monotonic clock under test control (s)."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def all_records(path: Path) -> list:
    """Every record of a file via the mcap library, validating chunk and data CRCs."""
    with open(path, 'rb') as handle:
        return list(StreamReader(handle, validate_crcs=True).records)


def decoded(path: Path, topics: list[str] | None = None) -> list:
    with open(path, 'rb') as handle:
        reader = make_reader(handle, validate_crcs=True, decoder_factories=[DecoderFactory()])
        return list(reader.iter_decoded_messages(topics=topics))


# --------------------------------------------------------------------------- schema text
def test_schema_text_is_rosbag2_concatenation() -> None:
    share = Path(ros_schemas._share_dir('diagnostic_msgs')).parent
    texts = {
        name: (share / pkg / 'msg' / f'{typ}.msg').read_text()
        for name, pkg, typ in [
            ('root', 'diagnostic_msgs', 'DiagnosticArray'),
            ('diagnostic_msgs/DiagnosticStatus', 'diagnostic_msgs', 'DiagnosticStatus'),
            ('diagnostic_msgs/KeyValue', 'diagnostic_msgs', 'KeyValue'),
            ('std_msgs/Header', 'std_msgs', 'Header'),
            ('builtin_interfaces/Time', 'builtin_interfaces', 'Time'),
        ]
    }
    # rosbag2 visits dependencies depth first, sorted per file, each once.
    expected = texts['root']
    for dep in [
        'diagnostic_msgs/DiagnosticStatus',
        'diagnostic_msgs/KeyValue',
        'std_msgs/Header',
        'builtin_interfaces/Time',
    ]:
        expected += '\n' + '=' * 80 + f'\nMSG: {dep}\n' + texts[dep]
    assert ros_schemas.message_definition('diagnostic_msgs/msg/DiagnosticArray') == expected
    float64 = ros_schemas.message_definition(FLOAT64)
    assert float64 == (share / 'std_msgs' / 'msg' / 'Float64.msg').read_text()
    multi = ros_schemas.message_definition('std_msgs/msg/Float64MultiArray')
    assert re.findall(r'^MSG: (\S+)$', multi, re.M) == [
        'std_msgs/MultiArrayLayout',
        'std_msgs/MultiArrayDimension',
    ]


def test_unknown_type_and_misuse_raise(tmp_path: Path) -> None:
    log = McapLogger(tmp_path, fsync=False)
    with pytest.raises(ros_schemas.SchemaNotFoundError, match='no_such_msgs/msg/Foo'):
        log.register('/x', 'no_such_msgs/msg/Foo')
    with pytest.raises(ros_schemas.SchemaNotFoundError, match='expected'):
        log.register('/x', 'Float64')
    log.register('/x', FLOAT64)
    log.register('/x', FLOAT64)  # same type again: fine
    with pytest.raises(ValueError, match="'/x' is already registered as 'std_msgs/msg/Float64'"):
        log.register('/x', 'std_msgs/msg/String')
    with pytest.raises(ValueError, match='not registered'):
        log.write('/y', cdr_f64(1.0), T0)
    with pytest.raises(TypeError, match='bytes'):
        log.write('/x', 1.0, T0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match='log_time_ns'):
        log.write('/x', cdr_f64(1.0), -1)
    with pytest.raises(ValueError, match='compression'):
        McapLogger(tmp_path, compression='bz2')
    with pytest.raises(ValueError, match='flush_period'):
        McapLogger(tmp_path, flush_period=0)
    log.close()


# --------------------------------------------------------------------------- round trip
def test_round_trip_with_independent_readers(tmp_path: Path) -> None:
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from rclpy.serialization import deserialize_message, serialize_message
    from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension

    status = DiagnosticStatus(
        level=DiagnosticStatus.ERROR,
        name='catenary_monitor: chain_01',
        message='anchor uplift',
        hardware_id='lc-01',
        values=[KeyValue(key='hook_tension_N', value='123456.5')],
    )
    diag = DiagnosticArray(status=[status])
    diag.header.stamp.sec = 17
    margins = Float64MultiArray(data=[0.25, -1.5, 3.0])
    margins.layout.dim = [MultiArrayDimension(label='chain', size=3, stride=3)]
    values = np.linspace(-1e6, 1e6, 50)

    with McapLogger(tmp_path, fsync=False) as log:
        log.register('/chain_01/tension', FLOAT64, qos='sensor_data')
        log.register('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', qos='latched')
        log.add_metadata(
            'catenary_monitor', {'config_sha256': 'ab12', 'version': '0.1.0', 'units': 'N, m, s'}
        )
        for i, value in enumerate(values):
            log.write(
                '/chain_01/tension',
                serialize_message(Float64(data=float(value))),
                T0 + i * 10_000_000,
                publish_time_ns=T0 + i * 10_000_000 - 5,
            )
        log.write('/diagnostics', serialize_message(diag), T0 + 10**9)
        # A topic registered after writing started lands in the same file.
        log.register('/margins', 'std_msgs/msg/Float64MultiArray')
        log.write('/margins', serialize_message(margins), T0 + 2 * 10**9)
    assert log.error is None and log.dropped == 0
    assert log.messages_written == {'/chain_01/tension': 50, '/diagnostics': 1, '/margins': 1}
    [path] = log.files
    assert log.file_bytes == path.stat().st_size

    records = all_records(path)  # raises on any CRC mismatch
    header = records[0]
    assert header.profile == 'ros2'
    with open(path, 'rb') as handle:
        reader = make_reader(handle)
        summary = reader.get_summary()
        metadata = list(reader.iter_metadata())
    schemas = {s.name: s for s in summary.schemas.values()}
    assert set(schemas) == {
        FLOAT64,
        'diagnostic_msgs/msg/DiagnosticArray',
        'std_msgs/msg/Float64MultiArray',
    }
    for name, schema in schemas.items():
        assert schema.encoding == 'ros2msg'
        assert schema.data.decode() == ros_schemas.message_definition(name)
    channels = {c.topic: c for c in summary.channels.values()}
    assert all(c.message_encoding == 'cdr' for c in channels.values())
    assert channels['/diagnostics'].metadata['offered_qos_profiles'] == ros_schemas.QOS_LATCHED
    assert re.fullmatch(r'RIHS01_[0-9a-f]{64}', channels['/margins'].metadata['topic_type_hash'])
    assert summary.statistics.message_count == 52
    assert [(m.name, m.metadata) for m in metadata] == [
        ('catenary_monitor', {'config_sha256': 'ab12', 'version': '0.1.0', 'units': 'N, m, s'})
    ]

    msgs = decoded(path)
    tension = [m for m in msgs if m.channel.topic == '/chain_01/tension']
    assert [m.decoded_message.data for m in tension] == values.tolist()
    assert [m.message.log_time for m in tension] == [T0 + i * 10_000_000 for i in range(50)]
    assert [m.message.publish_time for m in tension] == [
        T0 + i * 10_000_000 - 5 for i in range(50)
    ]
    assert [m.message.sequence for m in tension] == list(range(50))
    [d] = [m for m in msgs if m.channel.topic == '/diagnostics']
    got = d.decoded_message.status[0]
    assert (got.level, got.name, got.message, got.hardware_id) == (
        2,
        'catenary_monitor: chain_01',
        'anchor uplift',
        'lc-01',
    )
    assert (got.values[0].key, got.values[0].value) == ('hook_tension_N', '123456.5')
    # The stored bytes are what rclpy serialized: rclpy reads them back unchanged.
    back = deserialize_message(d.message.data, DiagnosticArray)
    assert back.status[0].name == 'catenary_monitor: chain_01' and back.header.stamp.sec == 17
    [mm] = [m for m in msgs if m.channel.topic == '/margins']
    assert list(mm.decoded_message.data) == [0.25, -1.5, 3.0]
    assert mm.decoded_message.layout.dim[0].label == 'chain'

    columns, report = read_float64_topics(path, ['/chain_01/tension'])
    t, v = columns['/chain_01/tension']
    assert v.tolist() == values.tolist()
    assert t.tolist() == [T0 + i * 10_000_000 for i in range(50)]
    assert report.complete


def test_offered_qos_yaml_is_rosbag2_format() -> None:
    [profile] = yaml.safe_load(ros_schemas.QOS_LATCHED)
    infinite = {'sec': 9223372036, 'nsec': 854775807}
    assert profile == {
        'history': 'keep_last',
        'depth': 1,
        'reliability': 'reliable',
        'durability': 'transient_local',
        'deadline': infinite,
        'lifespan': infinite,
        'liveliness': 'automatic',
        'liveliness_lease_duration': infinite,
        'avoid_ros_namespace_conventions': False,
    }
    assert not ros_schemas.QOS_LATCHED.endswith('\n')  # YAML::Dump adds no final newline
    [sensor] = yaml.safe_load(ros_schemas.QOS_SENSOR_DATA)
    assert (sensor['reliability'], sensor['depth']) == ('best_effort', 5)


@pytest.mark.parametrize('compression', ['zstd', 'lz4', 'none'])
def test_compression_options(tmp_path: Path, compression: str) -> None:
    with McapLogger(tmp_path, compression=compression, fsync=False, chunk_size=2000) as log:
        log.register('/a', FLOAT64)
        for i in range(500):
            log.write('/a', cdr_f64(i), T0 + i)
    [path] = log.files
    assert len(all_records(path)) > 500
    with open(path, 'rb') as handle:
        chunks = list(StreamReader(handle, emit_chunks=True).records)
    chunks = [c for c in chunks if type(c).__name__ == 'Chunk']
    assert len(chunks) > 5  # chunk_size ends chunks
    assert {c.compression for c in chunks} == {'' if compression == 'none' else compression}
    assert [m.decoded_message.data for m in decoded(path)] == list(map(float, range(500)))


# --------------------------------------------------------------------------- rotation
def test_rotation_by_size_keeps_every_message_once(tmp_path: Path) -> None:
    clock = FakeClock()
    wall = [1_795_000_000.0]
    with McapLogger(
        tmp_path,
        prefix='dock',
        max_bytes=20_000,
        chunk_size=4_000,
        fsync=False,
        clock=clock,
        wall_clock=lambda: wall[0],
    ) as log:
        log.register('/a', FLOAT64)
        log.register('/b', FLOAT64)
        log.add_metadata('catenary_monitor', {'config_sha256': 'cafe'})
        for i in range(3000):
            log.write('/a' if i % 2 else '/b', cdr_f64(i), T0 + i * 1000)
            wall[0] += 0.01
    files = log.files
    assert len(files) >= 4
    assert sorted(tmp_path.glob('*.mcap')) == sorted(files)
    names = [p.name for p in files]
    assert all(re.fullmatch(r'dock_\d{8}T\d{6}Z_\d{4}\.mcap', n) for n in names)
    assert [int(n[-9:-5]) for n in names] == list(range(len(files)))
    assert names[0] == 'dock_20261118T110640Z_0000.mcap'  # UTC of wall time 1_795_000_000 s
    got = []
    for path in files:
        assert path.stat().st_size < 20_000 + 8_000  # rotated near max_bytes
        with open(path, 'rb') as handle:
            reader = make_reader(handle)
            assert [m.name for m in reader.iter_metadata()] == ['catenary_monitor']
            assert {c.topic for c in reader.get_summary().channels.values()} == {'/a', '/b'}
        got += [m.decoded_message.data for m in decoded(path)]
    assert got == list(map(float, range(3000)))
    columns, report = read_float64_topics(list(reversed(files)), ['/a', '/b'])
    assert columns['/a'][1].tolist() == list(map(float, range(1, 3000, 2)))
    assert report.complete and len(report.files) == len(files)


def test_rotation_by_time(tmp_path: Path) -> None:
    clock = FakeClock()
    with McapLogger(tmp_path, max_seconds=60.0, fsync=False, clock=clock) as log:
        log.register('/a', FLOAT64)
        for i in range(10):
            log.write('/a', cdr_f64(i), T0 + i)
            clock.now += 25.0  # 250 s in all: rotations at >= 60 s of file age
        assert len(log.files) == 3
        clock.now += 100.0
        log.tick()  # a timer tick rotates an idle file that is too old
        assert len(log.files) == 4
    # No file is opened after an idle rotation until a message comes: none stays empty.
    assert [len(decoded(p)) for p in log.files] == [3, 3, 3, 1]


# --------------------------------------------------------------------------- flushing
def test_flush_period_bounds_what_is_only_in_memory(tmp_path: Path) -> None:
    clock = FakeClock()
    log = McapLogger(tmp_path, flush_period=1.0, chunk_size=1 << 20, clock=clock)
    log.register('/a', FLOAT64)
    path = log.current_path

    def on_disk() -> int:
        try:
            columns, _ = read_float64_topics(path, ['/a'])
        except Exception as exc:  # EmptyLogError before the first flush
            assert type(exc).__name__ == 'EmptyLogError'
            return 0
        return len(columns['/a'][0])

    for i in range(5):
        log.write('/a', cdr_f64(i), T0 + i)
        clock.now += 0.1
    assert on_disk() == 0  # oldest message is 0.5 s old: still in the open chunk
    clock.now += 0.5
    assert log.tick() is True
    assert on_disk() == 5
    log.write('/a', cdr_f64(5), T0 + 5)
    clock.now += 0.99
    assert log.tick() is False and on_disk() == 5
    clock.now += 0.01
    log.write('/a', cdr_f64(6), T0 + 6)  # write() itself flushes once the oldest is 1 s old
    assert on_disk() == 7
    log.close()
    assert on_disk() == 7


# --------------------------------------------------------------------------- errors
def test_unwritable_directory_never_raises_and_recovers(tmp_path: Path) -> None:
    blocker = tmp_path / 'blocker'
    blocker.write_text('a regular file where the log directory should be')
    clock = FakeClock()
    log = McapLogger(blocker / 'logs', retry_period=5.0, clock=clock, fsync=False)
    assert not log.ok
    assert log.error is not None and 'blocker' in log.error
    log.register('/a', FLOAT64)
    log.add_metadata('catenary_monitor', {'version': '0.1.0'})
    assert log.write('/a', cdr_f64(1.0), T0) is False
    assert log.write('/a', cdr_f64(2.0), T0 + 1) is False
    assert log.tick() is False
    assert log.dropped == 2 and log.messages_written['/a'] == 0
    assert log.diagnostic_values()['messages_dropped'] == '2'
    first_errors = log.error_count

    blocker.unlink()  # the operator frees the path
    clock.now += 1.0
    log.tick()
    assert not log.ok and log.error_count == first_errors  # waits for retry_period
    clock.now += 5.0
    log.tick()
    assert log.ok and log.error is None and log.last_error is not None
    assert log.write('/a', cdr_f64(3.0), T0 + 2)
    log.close()
    columns, report = read_float64_topics(blocker / 'logs', ['/a'])
    assert columns['/a'][1].tolist() == [3.0]
    with open(log.files[0], 'rb') as handle:
        assert [m.name for m in make_reader(handle).iter_metadata()] == ['catenary_monitor']


def test_dev_null_path_and_closed_logger_never_raise() -> None:
    log = McapLogger('/dev/null/x')
    assert not log.ok and 'Not a directory' in (log.error or '')
    log.register('/a', FLOAT64)
    assert log.write('/a', cdr_f64(1.0), T0) is False
    log.close()
    log.close()
    assert log.write('/a', cdr_f64(1.0), T0) is False and log.dropped == 2


class _FullDisk:
    """A file object that raises ENOSPC once ``budget`` bytes were written."""

    def __init__(self, path: Path, budget: int) -> None:
        self._f = open(path, 'xb')
        self._budget = budget

    def write(self, data: bytes) -> int:
        if len(data) > self._budget:
            self._f.write(bytes(data[: self._budget]))
            self._f.flush()
            self._budget = 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self._budget -= len(data)
        return self._f.write(data)

    def __getattr__(self, name: str):
        return getattr(self._f, name)


def test_full_disk_mid_file_is_recorded_not_raised(tmp_path: Path, monkeypatch) -> None:
    clock = FakeClock()
    budgets = iter([6000, 0, 10**9])  # 1st file fills up, 1st retry fails, then space again

    def create_file(self):
        path = self.log_dir / f'f{len(list(self.log_dir.iterdir()))}.mcap'
        return path, _FullDisk(path, next(budgets))

    monkeypatch.setattr(McapLogger, '_create_file', create_file)
    log = McapLogger(tmp_path, chunk_size=1000, retry_period=2.0, clock=clock, fsync=False)
    log.register('/a', FLOAT64)
    accepted = []
    for i in range(600):  # 12 s: the disk fills at ~4 s, retries at ~6 s and ~8 s
        if log.write('/a', cdr_f64(i), T0 + i):
            accepted.append(i)
        clock.now += 0.02
    assert log.error_count >= 2
    assert 'No space left on device' in (log.last_error or '')
    assert log.ok  # the third file works
    log.close()
    assert log.dropped > 0
    assert log.dropped + log.messages_written['/a'] == 600
    # The retry that failed at open left no file behind; the first file, cut to its last
    # flush when the disk filled, was finished where it lies once space allowed (here at
    # close): its flushed messages, none of the chunk that failed (counted dropped).
    files = sorted(tmp_path.glob('*.mcap'))
    assert len(files) == 2
    assert log.take_finished_late() == [files[0]] and not log.unfinished
    columns, report = read_float64_topics(files, ['/a'])
    got = columns['/a'][1].astype(int).tolist()
    assert report.files[0].finished and report.files[1].finished and not report.skips
    assert log.messages_written['/a'] == len(got) <= len(accepted)
    assert got == sorted(set(got)) and set(got) <= set(accepted)
    after_recovery = [int(m.decoded_message.data) for m in decoded(files[1])]
    assert after_recovery == accepted[-len(after_recovery) :] == got[-len(after_recovery) :]
    assert len(after_recovery) > 100


def test_open_fails_on_dev_full(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(
        McapLogger, '_create_file', lambda self: (tmp_path / 'never', open('/dev/full', 'wb'))
    )
    log = McapLogger(tmp_path)
    assert not log.ok and 'No space left on device' in (log.error or '')
    log.register('/a', FLOAT64)
    assert log.write('/a', cdr_f64(0.0), T0) is False
    log.close()


# --------------------------------------------------------------------------- crash safety
_WRITER_SCRIPT = r'''
import struct, sys, time
from catenary_monitor.io.mcap_log import McapLogger
log = McapLogger(sys.argv[1], flush_period=1.0)
log.register('/counter', 'std_msgs/msg/Float64')
i = 0
next_t = time.monotonic()
while True:
    log.write('/counter', b'\x00\x01\x00\x00' + struct.pack('<d', i), time.time_ns())
    if i == 0:
        print('started', flush=True)
    i += 1
    next_t += 0.005
    time.sleep(max(0.0, next_t - time.monotonic()))
'''


def test_sigkill_loses_at_most_about_one_second(tmp_path: Path) -> None:
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen(
        [sys.executable, '-c', _WRITER_SCRIPT, str(tmp_path)],
        env=env,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == 'started'
        # Flushes happen about 1.0, 2.0, 3.0 s after the first message: killing at 2.95 s
        # is close to the worst case (about 0.95 s of data only in memory).
        time.sleep(2.95)
    finally:
        kill_ns = time.time_ns()
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
    [path] = list(tmp_path.glob('*.mcap'))
    columns, report = read_float64_topics(path, ['/counter'])
    t, v = columns['/counter']
    # Everything written up to about one second before the kill is there, without holes.
    assert v.tolist() == list(map(float, range(len(v))))
    assert len(v) > 200
    print(f"unflushed at kill: {(kill_ns - t[-1]) / 1e9:.3f} s")
    assert (kill_ns - t[-1]) / 1e9 < 1.3, report.summary()
    assert not report.files[0].finished
