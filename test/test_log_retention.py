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
    log.write('/a', payload, T0 + 5)  # the next file opens with its first message
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
    assert rosbags_count([folder]) == 3


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


# ---------------------------------------------------------------- the smallest bound; whose files
def _payload(k: int) -> bytes:
    """A status-like message: 4 B encapsulation and 196 B that compress only in part."""
    return b'\x00\x01\x00\x00' + bytes((k * 7 + i * i) % 251 for i in range(196))


def test_the_bound_holds_at_the_smallest_sizes_without_any_tick(tmp_path):
    """log_rotate_size 0.1 MiB and log_max_total_size 400000 at 800 messages a second, and
    the caller's timer never running (a flood keeps an executor's timers waiting): the
    retention runs at every rotation, so the folder never holds more than its bound. (It ran
    only from tick(): 140 files, 3.0 MB after 15 s, nothing deleted.)"""
    folder = tmp_path / 'log'
    mono, wall = Clock(100.0), Clock(1.795e9)
    bound = 400_000
    log = McapLogger(
        folder, fsync=False, max_bytes=int(0.1 * 2**20), clock=mono, wall_clock=wall,
        max_total_bytes=bound,
    )  # fmt: skip
    log.register('/a', 'diagnostic_msgs/msg/DiagnosticArray')
    log.add_metadata('catenary_monitor', {'parameters': 'x' * 3000})  # as the node does
    peak, files = 0, set()
    for k in range(12_000):  # 15 s at 800/s
        mono.now += 1 / 800
        wall.now += 1 / 800
        log.write('/a', _payload(k), T0 + k * 1_250_000)
        files.add(log.current_path)
        if k % 50 == 0:
            peak = max(peak, folder_bytes(folder))
    deleted = log.take_deleted()
    log.close()
    assert len(files) > 25 and len(deleted) >= len(files) - 8
    assert peak <= bound and folder_bytes(folder) <= bound, peak
    assert [p.name for p, _, _ in deleted] == sorted(p.name for p, _, _ in deleted)
    assert listed(folder) == sorted(p.name for p in folder.glob('*.mcap'))


def _run(folder: Path, wall0: float, n: int, **kw) -> list[Path]:
    """``n`` files of the logger (each rotated by hand) with its wall clock at ``wall0``."""
    mono, wall = Clock(100.0), Clock(wall0)
    log = McapLogger(folder, fsync=False, clock=mono, wall_clock=wall, **kw)
    log.register('/a', 'std_msgs/msg/Float64')
    payload = b'\x00\x01\x00\x00' + struct.pack('<d', 1.0) * 800
    made = []
    for k in range(n):
        for j in range(10):
            mono.now += 1.0
            wall.now += 1.0
            log.write('/a', payload, int(wall.now * 1e9))
        made.append(log.current_path)
        if k < n - 1:
            log.rotate()
    log.close()
    return made


def test_retention_deletes_only_its_own_files_the_future_dated_first(tmp_path):
    """A user's copy of a node file under another name, a file named as the node names them
    but written by another tool, and a file touched to 2100: the first two are neither counted
    nor deleted; the node's own files go by their recorded end, a file recorded in 2100 (a
    clock error later corrected) first of all, whatever the modification times say."""
    from mcap.writer import Writer

    folder = tmp_path / 'log'
    future = _run(folder, 4.1e9, 1)  # recorded in 2099
    old = _run(folder, 1.795e9 - 7200, 3)  # two hours ago
    keep = folder / 'storm_evidence_keep.mcap'
    keep.write_bytes(old[0].read_bytes())  # a user's copy: the node's header, another name
    alien = folder / 'catenary_monitor_20261201T000000Z_0000.mcap'  # the node's name, not its file
    with open(alien, 'wb') as f:
        w = Writer(f)
        w.start(profile='ros2', library='someone else')
        w.finish()
    for p in (alien, keep, future[0]):
        os.utime(p, (1.795e9 - 9000,) * 2)  # oldest by modification time
    os.utime(old[1], (4.2e9,) * 2)  # touched to 2103: its recorded end decides
    size = old[0].stat().st_size
    mono, wall = Clock(100.0), Clock(1.795e9)
    log = McapLogger(
        folder, fsync=False, clock=mono, wall_clock=wall, max_bytes=size,
        max_total_bytes=3 * size + size // 16 + 4096 + size // 2,
    )  # fmt: skip  # room for two finished files and the open one's reserve
    log.register('/a', 'std_msgs/msg/Float64')
    log.apply_retention()
    gone = log.take_deleted()
    log.close()
    assert [(p.name, why) for p, _, why in gone] == [
        (future[0].name, 'future'), (old[0].name, 'size')
    ], gone
    assert keep.exists() and alien.exists() and old[1].exists() and old[2].exists()


def test_a_node_file_recovered_after_a_crash_is_still_its_own(tmp_path):
    from catenary_monitor.io.mcap_recover import recover_file

    folder = tmp_path / 'log'
    made = _run(folder, 1.795e9 - 7200, 2)
    data = made[0].read_bytes()
    made[0].write_bytes(data[: len(data) * 2 // 3])  # cut: no summary, as after SIGKILL
    assert recover_file(made[0]).status == 'recovered'
    log = McapLogger(folder, fsync=False, max_total_bytes=1, max_bytes=1)
    log.register('/a', 'std_msgs/msg/Float64')
    log.apply_retention()
    assert {p.name for p, _, _ in log.take_deleted()} == {m.name for m in made}
    log.close()


@pytest.mark.timeout(150)
def test_the_node_holds_the_smallest_bound_under_a_flood(tmp_path):
    """The node with log_rotate_size 0.1 MiB and log_max_total_size 400000, one line and the
    depth at 400 samples/s each for 15 s: its files never exceed the bound (sampled every
    0.1 s) and deletions are reported during the flood; a user's file in the folder survives,
    and a file of the node recorded in 2099 is the first to go, named as such."""
    import subprocess
    import sys

    from ros_harness import child_env, output_of, start_monitor, stop, write_params

    params = write_params(
        tmp_path / 'p.yaml',
        {'a': {'weight': 1300.0, 'anchor_distance': 121.06, 'mbl': 5.17e6}},
        log_rotate_size=0.1,
        log_max_total_size=400000,
    )
    log = tmp_path / 'log'
    future = _run(log, 4.1e9, 1)[0]
    (log / 'metadata.yaml').unlink()
    keep = log / 'storm_evidence_keep.mcap'
    keep.write_bytes(future.read_bytes())
    proc = start_monitor(params, log)
    flood = None
    peak, during = 0, 0
    try:
        time.sleep(3.0)
        flood = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name('flood_publisher.py')), 'a', '400',
             '15', '400'],
            stdout=subprocess.PIPE, text=True, env=child_env(),
        )  # fmt: skip
        while flood.poll() is None:
            own = [p for p in log.glob('catenary_monitor_*.mcap')]
            peak = max(peak, sum(p.stat().st_size for p in own if p.exists()))
            time.sleep(0.1)
        during = output_of(proc).count('log retention: deleted')
        sent = int(flood.communicate()[0].split()[-1])
    finally:
        if flood is not None and flood.poll() is None:
            flood.terminate()
        code = stop(proc)
    text = output_of(proc)
    assert code == 0 and sent > 10_000, text[-2000:]
    assert peak <= 400_000, peak
    assert during >= 10, text[-2000:]
    first = next(ln for ln in text.splitlines() if 'log retention: deleted' in ln)
    assert future.name in first and 'dated ahead of the present' in first, first
    assert keep.exists()


def test_a_stop_right_after_a_rotation_leaves_no_empty_file(tmp_path):
    """A file rotated out by age, then the node stopped before its next message: no file
    without messages is left (the mcap writer drops an empty chunk and its channels but lists
    them in the summary; pymcap-cli doctor called that file broken). Every file passes all
    three readers."""
    folder = tmp_path / 'log'
    mono = Clock(100.0)
    log = McapLogger(folder, fsync=False, clock=mono, max_seconds=1.0)
    log.register('/a', 'std_msgs/msg/Float64')
    log.register('/b', 'std_msgs/msg/Float64')  # never written
    log.add_metadata('dock', {'name': 'test'})
    payload = b'\x00\x01\x00\x00' + struct.pack('<d', 1.0)
    log.write('/a', payload, T0)
    mono.now += 1.5
    log.tick()  # rotates by age
    log.close()
    assert len(list(folder.glob('*.mcap'))) == 1
    assert check_folder(folder) == 1
