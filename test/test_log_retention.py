"""Log retention: the folder's MCAP files kept under log_max_total_size and log_max_age, the
oldest finished files first, never the open one, metadata.yaml true after every deletion,
rosbags still opening the folder; a WARN on low free space before anything is lost.

The logger at unit level (injected clocks, no sleeps), then the node (one log line and one
events record per deletion).
"""

from __future__ import annotations

import json
import os
import struct
import time
from pathlib import Path

import pytest
import yaml
from mcap_readers import check_folder, rosbags_count

from catenary_monitor.core.config.parameters import ConfigError, MonitorConfig, LineConfig
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.rules.health import logger_status
from catenary_monitor.io.mcap_log import McapLogger

T0 = 1_795_000_000_000_000_000  # ns


class Clock:
    def __init__(self, now: float) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def folder_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.glob('*.mcap'))


def listed(folder: Path) -> list[str]:
    meta = yaml.safe_load((folder / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    return sorted(meta['relative_file_paths'])


def test_the_folder_stays_under_its_bound_over_a_long_run(tmp_path):
    folder = tmp_path / 'log'
    mono, wall = Clock(100.0), Clock(1.795e9)
    bound = 72_000
    log = McapLogger(
        folder, fsync=False, chunk_size=4000, max_bytes=12_000, compression='none',
        clock=mono, wall_clock=wall, max_total_bytes=bound, retention_period=0.5,
    )  # fmt: skip
    log.register('/a', 'std_msgs/msg/Float64')
    log.add_metadata('catenary_monitor', {'units': 'SI'})  # as the node does
    payload = b'\x00\x01\x00\x00' + struct.pack('<d', 1.0)
    opened: set[Path] = set()
    deleted: list = []
    peak = 0
    for i in range(12_000):  # ~30 files' worth: a long run for this bound
        mono.now += 0.01
        wall.now += 0.01
        log.write('/a', payload, T0 + i * 10_000_000)
        log.tick()
        current = log.current_path
        assert current is not None and current.exists()  # the open file is never touched
        opened.add(current)
        deleted += log.take_deleted()
        if i % 10 == 0:
            peak = max(peak, folder_bytes(folder))
    assert not any(p == log.current_path for p, _, _ in deleted)
    log.close()
    assert peak <= bound
    assert folder_bytes(folder) <= bound
    assert len(opened) > 25 and len(deleted) >= len(opened) - 6
    # Oldest first, for size, each one gone; the metadata lists exactly what is left.
    names = [p.name for p, _, _ in deleted]
    assert names == sorted(names) and {why for _, _, why in deleted} == {'size'}
    assert not any(p.exists() for p, _, _ in deleted)
    assert listed(folder) == sorted(p.name for p in folder.glob('*.mcap'))
    assert log.deleted_files == len(deleted)
    assert log.diagnostic_values()['files_deleted'] == str(len(deleted))
    assert check_folder(folder) > 0  # rosbags, mcap and the node's reader all open it


def test_age_deletes_finished_files_only_and_the_metadata_follows(tmp_path):
    folder = tmp_path / 'log'
    mono, wall = Clock(100.0), Clock(1.795e9)
    log = McapLogger(folder, fsync=False, clock=mono, wall_clock=wall, max_age=3600.0)
    log.register('/a', 'std_msgs/msg/Float64')
    payload = b'\x00\x01\x00\x00' + struct.pack('<d', 1.0)
    for k in range(4):
        log.write('/a', payload, T0 + k)
        log.rotate()
    finished = sorted(p for p in folder.glob('*.mcap') if p != log.current_path)
    assert len(finished) == 4
    for k, p in enumerate(finished):  # ended 4, 3, 2, 1 hours ago
        os.utime(p, (wall.now - (4 - k) * 3600.0 + 60.0,) * 2)
    os.utime(log.current_path, (wall.now - 10 * 3600.0,) * 2)  # old, but open
    log.apply_retention()
    gone = log.take_deleted()
    assert [p for p, _, _ in gone] == finished[:3] and {w for _, _, w in gone} == {'age'}
    assert log.current_path.exists() and finished[3].exists()
    assert listed(folder) == [finished[3].name]
    log.write('/a', payload, T0 + 10)
    log.close()
    assert rosbags_count([folder]) == 2


def test_low_free_space_is_a_warning_before_anything_is_lost(tmp_path):
    log = McapLogger(tmp_path / 'log', fsync=False, min_free_bytes=10**18)
    log.tick()
    assert log.warning and 'low disk space' in log.warning and 'MiB free' in log.warning
    assert log.ok  # still writing
    level, message = logger_status(log.error, str(log.current_path), log.warning)
    assert level == Level.WARN and 'low disk space' in message
    assert logger_status('disk full', None, log.warning)[0] == Level.ERROR
    log.close()
    roomy = McapLogger(tmp_path / 'log2', fsync=False, min_free_bytes=1)
    roomy.tick()
    assert roomy.warning is None and int(roomy.diagnostic_values()['free_bytes_B']) > 1
    roomy.close()


def test_a_bound_below_two_files_is_refused():
    line = LineConfig('a', 1300.0, 120.0, 4.8e6)
    with pytest.raises(ConfigError, match='log_max_total_size') as err:
        MonitorConfig(lines=(line,), log_rotate_size=1.0, log_max_total_size=1.5 * 2**20)
    assert '2 x log_rotate_size' in str(err.value)
    MonitorConfig(lines=(line,), log_rotate_size=1.0, log_max_total_size=2.0 * 2**20)


@pytest.mark.timeout(90)
def test_the_node_reports_each_deletion(tmp_path):
    from ros_harness import Client, output_of, start_monitor, stop, write_params

    from catenary_monitor.io.mcap_read import iter_messages

    params = write_params(
        tmp_path / 'p.yaml',
        {'a': {'weight': 1300.0, 'anchor_distance': 121.06, 'mbl': 5.17e6}},
        log_rotate_duration=1.0,
        log_max_age=2.0,
    )
    log = tmp_path / 'log'
    proc = start_monitor(params, log)
    client = Client('retention_client')
    try:
        client.wait_matched(['/mooring/a/tension', '/tide/depth'], 30.0)
        client.feed('/mooring/a/tension', 370e3)
        client.feed('/tide/depth', 20.85)
        client.wait_for(lambda: 'log retention: deleted' in output_of(proc), 30.0, 'a deletion')
        time.sleep(1.5)
    finally:
        code = stop(proc)
        client.close()
    assert code == 0
    text = output_of(proc)
    lines = [ln for ln in text.splitlines() if 'log retention: deleted' in ln]
    assert lines and all('older than log_max_age 2 s' in ln for ln in lines)
    files = sorted(log.glob('*.mcap'))
    assert listed(log) == [p.name for p in files]
    records = [
        json.loads(m.data[8:-1].decode())
        for p in files
        for m in iter_messages(p, ['/catenary_monitor/events'])
    ]
    deletions = [r for r in records if r.get('kind') == 'log_deleted']
    named = {Path(r['path']).name for r in deletions}
    assert {ln.split('deleted ')[1].split(' ')[0] for ln in lines} >= named and deletions
    assert all(r['reason'] == 'age' and r['bytes'] > 0 for r in deletions)
    assert not any((log / n).exists() for n in named)
    assert check_folder(log) > 0
