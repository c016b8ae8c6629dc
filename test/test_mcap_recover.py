"""``catenary-monitor log recover`` and io/mcap_recover.py: unfinished logs made finished.

A log left by SIGKILL is made from a real McapLogger file: flushed chunks, then the file cut
inside its last chunk (as a kill during a write leaves it). After recovery the mcap library
(CRC-validated), rosbags and pymcap-cli doctor open every file, the folder opens as a rosbag2
bag, and no message that the project's tolerant reader finds in the cut file is lost.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from mcap_readers import check_file, check_folder, mcap_messages
from mcap_recover_helpers import TOPICS, cdr, cut_inside_last_chunk, write_log
from ros_harness import child_env

from catenary_monitor.io.mcap_log import McapLogger
from catenary_monitor.io.mcap_read import iter_messages
from catenary_monitor.io.mcap_recover import BACKUP_SUFFIX, is_finished, recover_file


def readable(path: Path) -> set[tuple[str, int, bytes]]:
    return {(m.topic, m.log_time_ns, m.data) for m in iter_messages(path)}


@pytest.mark.parametrize('compression', ['zstd', 'lz4', 'none'])
def test_killed_log_is_finished_without_losing_a_readable_message(tmp_path, compression):
    # Chunks of 300 kB: zstd and lz4 decode a cut chunk block by block (zstd blocks are up
    # to 128 kB, lz4's 64 kB), so its first blocks' messages can be salvaged.
    path = write_log(tmp_path / 'log', compression, n=20000, chunk_size=300_000)
    cut_inside_last_chunk(path)
    assert not is_finished(path)
    before = readable(path)
    original = path.read_bytes()
    result = recover_file(path)
    assert result.status == 'recovered', result
    assert result.salvaged_from_cut_chunk > 0, result  # the cut chunk gave messages too
    assert any('ends inside a chunk' in d for d in result.damaged)
    after = check_file(path)
    assert set(after) >= before
    assert len(after) == result.messages
    assert is_finished(path)
    assert Path(result.backup).read_bytes() == original
    assert result.backup == str(path) + BACKUP_SUFFIX


def test_recovered_file_keeps_profile_schemas_channel_metadata_and_records(tmp_path):
    from mcap.reader import make_reader

    path = write_log(tmp_path / 'log', 'zstd')
    recover_file(path)
    with open(path, 'rb') as f:
        reader = make_reader(f, validate_crcs=True)
        header = reader.get_header()
        summary = reader.get_summary()
        names = [m.name for m in reader.iter_metadata()]
    assert header.profile == 'ros2'
    assert 'finished by catenary_monitor.io.mcap_recover' in header.library
    assert {c.topic for c in summary.channels.values()} == set(TOPICS)
    for c in summary.channels.values():
        assert c.message_encoding == 'cdr'
        assert 'offered_qos_profiles' in c.metadata
        assert summary.schemas[c.schema_id].name == 'std_msgs/msg/Float64'
        assert summary.schemas[c.schema_id].encoding == 'ros2msg'
    assert names == ['catenary_monitor', 'recovery']
    assert summary.statistics.message_count == 3000
    assert all(ci.message_index_offsets for ci in summary.chunk_indexes)


def test_recover_is_idempotent_and_leaves_finished_files_alone(tmp_path):
    finished = write_log(tmp_path / 'log', 'zstd', close=True)
    killed = write_log(tmp_path / 'log', 'zstd')
    cut_inside_last_chunk(killed)
    assert recover_file(finished).status == 'already_finished'
    assert recover_file(killed).status == 'recovered'
    snapshot = {p.name: p.read_bytes() for p in (tmp_path / 'log').iterdir()}
    for p in (finished, killed):
        assert recover_file(p).status == 'already_finished'
    assert {p.name: p.read_bytes() for p in (tmp_path / 'log').iterdir()} == snapshot
    assert not list((tmp_path / 'log').glob('.*recover-tmp'))


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'log', 'recover', *args],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=300,
    )


def test_cli_recovers_a_folder_into_a_bag_every_reader_opens(tmp_path):
    folder = tmp_path / 'log'
    write_log(folder, 'zstd', close=True)
    killed = write_log(folder, 'zstd')
    cut_inside_last_chunk(killed)
    r = run_cli(str(folder))
    assert r.returncode == 0, r.stderr
    assert 'recovered' in r.stdout and 'already finished' in r.stdout
    assert 'metadata.yaml written' in r.stdout
    total = check_folder(folder)
    assert total > 3000
    r = run_cli(str(folder), '--json')
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert [f['status'] for f in report['files']] == ['already_finished'] * 2
    assert report['finished'] is True and report['metadata_yaml'].endswith('metadata.yaml')


def test_cli_exit_codes(tmp_path):
    r = run_cli(str(tmp_path / 'missing'))
    assert r.returncode == 2 and 'no such MCAP file or folder' in r.stderr
    (tmp_path / 'empty').mkdir()
    r = run_cli(str(tmp_path / 'empty'))
    assert r.returncode == 2 and 'no *.mcap file' in r.stderr
    (tmp_path / 'empty' / 'junk.mcap').write_bytes(b'not an mcap file at all')
    r = run_cli(str(tmp_path / 'empty'), '--json')
    assert r.returncode == 3
    assert json.loads(r.stdout)['files'][0]['status'] == 'not_mcap'
    assert 'junk.mcap: not finished' in r.stderr
    assert 'Traceback' not in r.stderr


def test_discard_original(tmp_path):
    path = write_log(tmp_path / 'log', 'zstd')
    r = run_cli(str(path), '--discard-original')
    assert r.returncode == 0, r.stderr
    assert not list((tmp_path / 'log').glob(f'*{BACKUP_SUFFIX}'))
    assert len(mcap_messages(path)) == 3000


def test_a_file_cut_inside_the_magic_or_header_gives_an_empty_finished_file(tmp_path):
    path = write_log(tmp_path / 'log', 'zstd')
    path.write_bytes(path.read_bytes()[:5])
    result = recover_file(path)
    assert result.status == 'recovered' and result.messages == 0
    assert mcap_messages(path) == []


def test_a_file_a_running_logger_writes_is_left_alone(tmp_path):
    log = McapLogger(tmp_path, fsync=False)
    log.register('/a', 'std_msgs/msg/Float64')
    log.write('/a', cdr(1.0), 1)
    log.flush()
    path = log.current_path
    before = path.read_bytes()
    result = recover_file(path)
    assert result.status == 'in_use' and 'running logger' in result.error
    assert path.read_bytes() == before
    log.close()
    assert recover_file(path).status == 'already_finished'


def test_recover_in_child_gives_the_same_result(tmp_path):
    from catenary_monitor.io.mcap_recover import recover_in_child

    path = write_log(tmp_path / 'log', 'zstd')
    result = recover_in_child(path)
    assert result.status == 'recovered' and result.messages == 3000
    assert len(check_file(path)) == 3000
    assert recover_in_child(path).status == 'already_finished'


def test_a_damaged_region_is_skipped_to_the_next_chunk(tmp_path):
    path = write_log(tmp_path / 'log', 'zstd')
    data = bytearray(path.read_bytes())
    # Overwrite the opcode and length of the 5th chunk with garbage: walked past, reported.
    pos, chunks = 8, []
    while pos + 9 <= len(data):
        op, length = struct.unpack_from('<BQ', data, pos)
        chunks += [pos] if op == 0x06 else []
        pos += 9 + length
    data[chunks[4] : chunks[4] + 9] = b'\xee' * 9
    path.write_bytes(bytes(data))
    before = readable(path)
    result = recover_file(path)
    assert result.status == 'recovered'
    assert any('skipped' in d and 'next chunk' in d for d in result.damaged), result.damaged
    assert set(check_file(path)) >= before
    assert 0 < result.messages < 3000
