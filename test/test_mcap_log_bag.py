"""The logger's folder as a rosbag2 bag, and files or folders vanishing under it (issue 10).

Unit level, with an injected monotonic clock: no sleeps, no timing.
"""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import yaml
from mcap_readers import check_file, check_folder, mcap_messages, rosbags_count

from catenary_monitor.io.mcap_log import McapLogger

FLOAT64 = 'std_msgs/msg/Float64'
T0 = 1_795_000_000_000_000_000  # ns
TOPICS = ('/a', '/b')
ROSBAG2_KEYS = [
    'version',
    'storage_identifier',
    'duration',
    'starting_time',
    'message_count',
    'topics_with_message_count',
    'compression_format',
    'compression_mode',
    'relative_file_paths',
    'files',
    'custom_data',
    'ros_distro',
]


class FakeClock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def cdr(value: float) -> bytes:
    return b'\x00\x01\x00\x00' + struct.pack('<d', value)


def logger(folder: Path, clock: FakeClock, **kw) -> McapLogger:
    log = McapLogger(folder, fsync=False, chunk_size=2000, clock=clock, **kw)
    for t in TOPICS:
        log.register(t, FLOAT64, 'sensor_data')
    log.add_metadata('catenary_monitor', {'config_hash': 'abc'})
    return log


def metadata(folder: Path) -> dict:
    return yaml.safe_load((folder / 'metadata.yaml').read_text())['rosbag2_bagfile_information']


def test_metadata_yaml_is_rosbag2_v9_and_follows_rotation(tmp_path):
    clock = FakeClock()
    log = logger(tmp_path, clock, max_bytes=15_000)
    current = None
    for i in range(3000):
        log.write(TOPICS[i % 2], cdr(i), T0 + 1000 * i)
        clock.now += 0.001
        if log.current_path != current:
            current = log.current_path
            # Rewritten at each rotation: every finished file so far, so that bag readers
            # open the folder at any time.
            assert metadata(tmp_path)['relative_file_paths'] == [p.name for p in log.files]
            if log.files:
                assert rosbags_count([tmp_path]) == sum(
                    len(mcap_messages(p)) for p in log.files
                )
    log.close()
    assert len(log.files) >= 3
    info = metadata(tmp_path)
    assert list(info) == ROSBAG2_KEYS
    assert info['version'] == 9 and info['storage_identifier'] == 'mcap'
    assert info['relative_file_paths'] == [p.name for p in log.files]
    assert info['message_count'] == 3000 == sum(f['message_count'] for f in info['files'])
    assert info['starting_time'] == {'nanoseconds_since_epoch': T0}
    assert info['duration'] == {'nanoseconds': 1000 * 2999}
    assert info['compression_format'] == '' and info['custom_data'] is None
    topics = {t['topic_metadata']['name']: t for t in info['topics_with_message_count']}
    assert set(topics) == set(TOPICS)
    for t in topics.values():
        meta = t['topic_metadata']
        assert list(meta) == [
            'name',
            'type',
            'serialization_format',
            'offered_qos_profiles',
            'type_description_hash',
        ]
        assert meta['type'] == FLOAT64 and meta['serialization_format'] == 'cdr'
        assert meta['offered_qos_profiles'][0]['reliability'] == 'best_effort'
        assert meta['type_description_hash'].startswith('RIHS01_')
        assert t['message_count'] == 1500
    assert check_folder(tmp_path) == 3000
    # rosbags' own rosbag2 reader parses every field of the metadata (v9 QoS lists included).
    from rosbags.rosbag2 import Reader

    with Reader(tmp_path) as bag:
        assert bag.message_count == 3000 and bag.duration == 1000 * 2999 + 1
        assert not bag.compression_mode and bag.ros_distro == 'jazzy'
        for c in bag.connections:
            assert c.msgcount == 1500 and c.digest.startswith('RIHS01_')
            [qos] = c.ext.offered_qos_profiles
            assert qos.depth == 5 and qos.reliability.name == 'BEST_EFFORT'


def test_rosbags_opens_the_folder_of_a_closed_logger_with_previous_runs(tmp_path):
    for run in range(2):
        clock = FakeClock()
        log = logger(tmp_path, clock)
        for i in range(100):
            log.write('/a', cdr(i), T0 + run * 10**9 + i)
        log.close()
    assert len(metadata(tmp_path)['relative_file_paths']) == 2
    assert rosbags_count([tmp_path]) == 200


def test_deleted_directory_is_an_error_then_a_new_file(tmp_path):
    clock = FakeClock()
    folder = tmp_path / 'log'
    log = logger(folder, clock, error_hold=2.0)
    for i in range(50):
        log.write('/a', cdr(i), T0 + i)
    log.flush()
    first = log.current_path
    shutil.rmtree(folder)
    clock.now += 0.25
    log.tick()  # the node's 0.25 s timer
    assert log.error is not None and 'vanished' in log.error, log.error
    assert '50 message(s) lost' in log.error
    assert log.dropped == 50 and log.messages_written['/a'] == 0
    assert log.current_path is not None and log.current_path != first  # a new file at once
    assert log.current_path.parent == folder and folder.is_dir()
    for i in range(50, 80):
        assert log.write('/a', cdr(i), T0 + i)
    clock.now += 1.0
    log.tick()
    assert log.error is not None  # held for error_hold
    clock.now += 1.5
    log.tick()
    assert log.error is None and log.ok
    assert log.diagnostic_values()['files_vanished'] == '1'
    assert 'vanished' in (log.last_error or '')
    log.close()
    got = [struct.unpack('<d', d[4:])[0] for _, _, d in mcap_messages(log.files[-1])]
    assert got == list(map(float, range(50, 80)))
    assert check_folder(folder) == 30


def test_moved_directory_keeps_its_file_finished_and_logging_goes_on(tmp_path):
    clock = FakeClock()
    folder = tmp_path / 'log'
    log = logger(folder, clock)
    for i in range(40):
        log.write('/a', cdr(i), T0 + i)
    first = log.current_path
    folder.rename(tmp_path / 'moved')
    clock.now += 0.25
    log.tick()
    assert 'vanished' in log.error and 'finished where it went' in log.error
    assert log.dropped == 0
    moved = tmp_path / 'moved' / first.name
    assert len(check_file(moved)) == 40  # finished with its summary where it went
    assert log.current_path.parent == folder
    log.write('/a', cdr(99.0), T0 + 99)
    log.close()
    assert len(mcap_messages(log.files[-1])) == 1


def test_replaced_file_is_detected(tmp_path):
    clock = FakeClock()
    log = logger(tmp_path, clock)
    log.write('/a', cdr(1.0), T0)
    log.flush()
    path = log.current_path
    path.unlink()
    path.write_bytes(b'someone else')
    clock.now += 0.25
    log.tick()
    assert 'was replaced' in log.error
    assert log.current_path != path
    log.close()


def test_without_create_dir_the_logger_waits_for_the_directory(tmp_path):
    clock = FakeClock()
    folder = tmp_path / 'mnt'
    log = logger(folder, clock, create_dir=False, retry_period=1.0)
    assert not log.ok and 'missing' in log.error  # not created
    folder.mkdir()
    clock.now += 1.0
    log.tick()
    assert log.ok and log.current_path.parent == folder
    log.write('/a', cdr(1.0), T0)
    shutil.rmtree(folder)
    clock.now += 0.25
    log.tick()
    assert not log.ok and not folder.exists()
    assert not log.write('/a', cdr(2.0), T0 + 1)
    folder.mkdir()
    clock.now += 1.0
    log.tick()
    assert log.current_path is not None and log.current_path.parent == folder
    clock.now += 1.0
    log.tick()
    assert log.ok  # the error was held error_hold (2 s), then cleared
    log.write('/a', cdr(3.0), T0 + 2)
    log.close()
    assert len(mcap_messages(log.files[-1])) == 1
