"""A full disk: the file it interrupts is finished as soon as space allows; recovery still works.

On a real small file system (a 4 MiB tmpfs mounted for the test, as root; skipped with the
reason where the machine cannot mount one):

* the logger, writing until the disk is full, cuts the file it was writing to its last whole
  chunk at once (the reader then reads it to its end, nothing cut), says so in its error, and
  finishes it where it lies (summary appended) at the first retry after space is freed: the
  mcap library (CRC-checked summary), rosbags and pymcap-cli doctor open it, with every message
  the cut file held; it is listed in ``metadata.yaml``;
* ``log recover`` on a disk too full for a copy finishes the file in place, and with ``--out
  DIR`` writes the finished copy to another file system and leaves the original as it was.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Iterator

import pytest
from mcap_readers import check_file, mcap_messages
from mcap_recover_helpers import TOPICS, cdr, cut_inside_last_chunk, write_log
from ros_harness import child_env

from catenary_monitor.io.mcap_log import McapLogger
from catenary_monitor.io.mcap_read import read_float64_topics
from catenary_monitor.io.mcap_recover import is_finished


@pytest.fixture
def small_fs(tmp_path: Path) -> Iterator[Path]:
    """A 4 MiB tmpfs, unmounted afterwards."""
    if not hasattr(os, 'geteuid') or os.geteuid() != 0:
        pytest.skip('mounting a small file system needs root')
    mnt = tmp_path / 'small'
    mnt.mkdir()
    r = subprocess.run(
        ['mount', '-t', 'tmpfs', '-o', 'size=4m', 'tmpfs', str(mnt)],
        capture_output=True,
        text=True,
    )
    if r.returncode != 0:
        pytest.skip(f'cannot mount a tmpfs here: {r.stderr.strip()}')
    try:
        yield mnt
    finally:
        subprocess.run(['umount', '-l', str(mnt)], capture_output=True)


def _fill(mnt: Path, leave: int) -> Path:
    """A file taking all but about ``leave`` bytes of the file system."""
    st = os.statvfs(mnt)
    free = st.f_bavail * st.f_frsize
    filler = mnt / 'filler'
    with open(filler, 'wb') as f:
        f.write(b'\0' * max(0, free - leave))
    return filler


def test_the_file_a_full_disk_interrupts_is_finished_as_soon_as_space_allows(
    small_fs: Path,
) -> None:
    clock = [0.0]
    log = McapLogger(
        small_fs / 'log',
        clock=lambda: clock[0],
        compression='none',
        chunk_size=2 << 10,  # many chunks: a summary larger than a page (tmpfs allocates pages)
        flush_period=0.5,
        retry_period=1.0,
    )
    for topic in TOPICS:
        log.register(topic, 'std_msgs/msg/Float64', 'sensor_data')
    filler = _fill(small_fs, 300_000)
    first = log.current_path
    assert first is not None
    i = 0
    while not log.unfinished and i < 100_000:  # ~43 B a message: full within 8 000
        log.write(TOPICS[i % 2], cdr(float(i)), 10**18 + 1000 * i)
        clock[0] += 0.001
        i += 1
    assert log.error and 'No space left' in log.error, log.error
    assert 'cut to its last whole chunk' in log.error
    [(path, (size, _))] = log.unfinished.items()
    assert path == first and path.stat().st_size == size and not is_finished(path)
    columns, report = read_float64_topics(path, list(TOPICS))
    assert report.skips == []  # cut between records: nothing of it is damaged
    held = sum(len(t) for t, _ in columns.values())
    assert held > 1000
    assert log.diagnostic_values()['files_unfinished'] == '1'

    # The cut gave back the room of the chunk it cut, enough for a summary: take it too.
    more = small_fs / 'more'
    with open(more, 'wb', buffering=0) as f:
        try:
            while True:
                f.write(b'\0' * 4096)
        except OSError:
            pass
    for _ in range(20):  # still full: retried, still unfinished, nothing raised
        log.write(TOPICS[0], cdr(0.0), 10**18 + 1000 * i)
        clock[0] += 0.5
        log.tick()
    assert not is_finished(path) and log.unfinished
    assert path.stat().st_size == size  # a failed summary is cut away again

    filler.unlink()
    more.unlink()
    clock[0] += 1.5
    log.tick()
    assert is_finished(path), path.stat().st_size
    assert log.take_finished_late() == [path] and not log.unfinished
    assert len(check_file(path)) == held  # mcap (CRC-checked), rosbags, pymcap-cli doctor
    assert log.current_path not in (None, path)  # logging goes on in a new file
    log.close()
    listed = (small_fs / 'log' / 'metadata.yaml').read_text()
    assert path.name in listed


def _recover(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', 'catenary_monitor', 'log', 'recover', *args, '--json'],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=120,
    )


def test_log_recover_on_a_full_disk_finishes_in_place_or_writes_elsewhere(
    small_fs: Path, tmp_path: Path
) -> None:
    folder = small_fs / 'log'
    a = write_log(folder, 'none', n=5000, chunk_size=16 << 10)
    b = folder / 'b.mcap'
    b.write_bytes(a.read_bytes())
    for path in (a, b):
        cut_inside_last_chunk(path)
    original = b.read_bytes()
    _fill(small_fs, 60_000)  # less than a copy of either (about 220 kB)

    r = _recover(str(a))
    assert r.returncode == 0, r.stderr
    [result] = json.loads(r.stdout)['files']
    assert result['status'] == 'finished_in_place', result
    assert 'no room for a copy' in result['damaged'][0]
    assert len(check_file(a)) == result['messages'] > 3000

    out = tmp_path / 'elsewhere'
    out.mkdir()
    r = _recover(str(b), '--out', str(out))
    assert r.returncode == 0, r.stderr
    [result] = json.loads(r.stdout)['files']
    assert result['status'] == 'recovered' and result['output'] == str(out / 'b.mcap')
    assert b.read_bytes() == original  # the original is left as it was
    assert len(mcap_messages(out / 'b.mcap')) == result['messages'] > 3000  # CRC-checked
    assert (out / 'metadata.yaml').exists()
