"""The node's log folder after a crash and under a vanishing directory (issue 10), with real
rclpy and DDS: the monitor runs as its own process (test/ros_harness.py). Every wait is bounded
and waits for an event; no sleep is an assertion.
"""

from __future__ import annotations

import shutil
import signal
import time
from pathlib import Path

import pytest
from mcap_readers import check_folder
from ros_harness import output_of, start_monitor, stop, write_params

from catenary_monitor.io.mcap_read import iter_messages
from catenary_monitor.io.mcap_recover import BACKUP_SUFFIX, is_finished

pytestmark = [pytest.mark.ros, pytest.mark.usefixtures('no_callback_errors')]

W, MBL, DEPTH = 1300.0, 4.827e6, 20.85
OK, ERROR = 0, 2
LOGGER = 'catenary_monitor: logger'


def wait_output(proc, text: str, timeout: float) -> str:
    deadline = time.monotonic() + timeout
    while text not in output_of(proc):
        assert proc.poll() is None, output_of(proc)
        assert time.monotonic() < deadline, f'no {text!r} in: {output_of(proc)[-2000:]}'
        time.sleep(0.05)
    return output_of(proc)


def feed_until_logged(client, topic: str, log_dir: Path, n: int) -> None:
    """Publish until the node has flushed at least ``n`` tension samples to its log."""
    deadline = time.monotonic() + 60.0
    i = 0
    while True:
        client.publish(topic, 400e3 + i)
        i += 1
        time.sleep(0.02)
        if i % 25 == 0:
            got = sum(1 for _ in iter_messages(sorted(log_dir.glob('*.mcap')), [topic]))
            if got >= n:
                return
        assert time.monotonic() < deadline, 'the monitor does not log'


def test_restart_after_sigkill_recovers_every_file_and_the_folder_is_a_bag(client, tmp_path):
    lines = {'crash': dict(weight=W, anchor_distance=120.0, mbl=MBL)}
    params = write_params(tmp_path / 'params.yaml', lines)
    log_dir = tmp_path / 'log'
    topic = '/mooring/crash/tension'
    proc = start_monitor(params, log_dir)
    try:
        client.wait_matched([topic], 30.0)
        client.feed('/tide/depth', DEPTH)
        feed_until_logged(client, topic, log_dir, 60)
        proc.send_signal(signal.SIGKILL)
        assert proc.wait(5) == -signal.SIGKILL
    finally:
        if proc.poll() is None:
            proc.kill()
    [killed] = sorted(log_dir.glob('*.mcap'))
    assert not is_finished(killed)
    readable = {(m.topic, m.log_time_ns, m.data) for m in iter_messages(killed)}
    assert len(readable) > 60
    users = log_dir / 'survey_2026.mcap'  # a user's unfinished file: never rewritten
    users.write_bytes(killed.read_bytes())

    proc = start_monitor(params, log_dir)
    try:
        out = wait_output(proc, f'recovered unfinished MCAP log {killed.name}', 60.0)
        assert 'original kept as' in out
        assert "survey_2026.mcap in the log folder is not the node's own: left as it is" in out
        status = client.wait_status(
            LOGGER, 30.0, OK, check=lambda s: s['values'].get('files_recovered') == '1'
        )
        assert int(status['values']['recovered_messages']) >= len(readable)
        client.wait_matched([topic], 30.0)
        feed_until_logged(client, topic, log_dir, len(readable) // 2 + 30)
    finally:
        client.feed('/tide/depth', None)
        assert stop(proc) == 0
    assert is_finished(killed) and (log_dir / (killed.name + BACKUP_SUFFIX)).exists()
    assert users.read_bytes() == (log_dir / (killed.name + BACKUP_SUFFIX)).read_bytes()
    assert not (log_dir / (users.name + BACKUP_SUFFIX)).exists()
    users.unlink()
    after = {(m.topic, m.log_time_ns, m.data) for m in iter_messages(killed)}
    assert readable <= after, f'{len(readable - after)} readable messages lost by recovery'
    files = sorted(log_dir.glob('*.mcap'))
    assert len(files) == 2 and all(is_finished(p) for p in files)
    assert check_folder(log_dir) > len(readable)  # mcap (CRC), rosbags, doctor; bag folder
    records = [
        m for m in iter_messages(killed.with_name(files[1].name), ['/catenary_monitor/events'])
        if b'log_recovered' in m.data
    ]
    assert len(records) == 1


def test_deleted_log_dir_is_an_error_within_seconds_then_a_new_file(client, tmp_path):
    lines = {'gone': dict(weight=W, anchor_distance=120.0, mbl=MBL)}
    params = write_params(tmp_path / 'params.yaml', lines)
    log_dir = tmp_path / 'log'
    topic = '/mooring/gone/tension'
    t0 = time.monotonic()  # the module's client also holds the earlier monitors' statuses
    proc = start_monitor(params, log_dir)
    try:
        client.wait_status(LOGGER, 30.0, OK, since=t0)
        client.wait_matched([topic], 30.0)
        client.feed(topic, 400e3)
        feed_until_logged(client, topic, log_dir, 5)
        [first] = sorted(log_dir.glob('*.mcap'))
        shutil.rmtree(log_dir)
        t_delete = time.monotonic()
        s = client.wait_status(
            LOGGER,
            10.0,
            ERROR,
            since=t_delete,
            check=lambda s: 'vanished' in s['values']['detail'],  # the full text
        )
        assert 'lost' in s['values']['detail'] and len(s['message']) <= 100
        s = client.wait_status(LOGGER, 15.0, OK, since=time.monotonic())
        new_path = Path(s['values']['file'])
        assert new_path.parent == log_dir and new_path.name != first.name
        assert new_path.exists()
        assert int(s['values']['files_vanished']) == 1
        assert 'vanished' in wait_output(proc, 'MCAP log not written', 5.0)
    finally:
        client.feed(topic, None)
        assert stop(proc) == 0
    assert check_folder(log_dir) > 0


def test_rotating_node_keeps_the_bag_openable_while_it_writes(client, tmp_path):
    """Files every second: metadata.yaml follows each rotation, the folder opens as a bag
    while the node runs, and after SIGTERM every file is finished and opens everywhere."""
    from mcap_readers import rosbags_count

    lines = {'rot': dict(weight=W, anchor_distance=120.0, mbl=MBL)}
    params = write_params(tmp_path / 'params.yaml', lines, log_rotate_duration=1.0)
    log_dir = tmp_path / 'log'
    topic = '/mooring/rot/tension'
    proc = start_monitor(params, log_dir)
    try:
        client.wait_matched([topic], 30.0)
        client.feed(topic, 400e3)

        def listed() -> list:
            path = log_dir / 'metadata.yaml'
            if not path.exists():
                return []
            import yaml

            info = yaml.safe_load(path.read_text())['rosbag2_bagfile_information']
            return info['relative_file_paths']

        client.wait_for(lambda: len(listed()) >= 3, 30.0, 'three rotated files in the bag')
        assert rosbags_count([log_dir]) > 0  # opens while the node writes its next file
    finally:
        client.feed(topic, None)
        assert stop(proc) == 0
    files = sorted(log_dir.glob('*.mcap'))
    assert all(is_finished(p) for p in files)
    assert listed() == [p.name for p in files]
    assert check_folder(log_dir) > 0
