"""Hostile files in every command that reads logs: one line, bounded memory, bounded time.

The files (test/hostile_mcap.py), each an unfinished log with the floating dock's parameters
recorded as the node records them and a few good messages before and after the hostile part:

* ``declares_2gib``: a 66 KB file whose zstd chunk declares (and holds) 2 GiB of zeros (75 KB
  with the parameters);
* ``zstd_255``: three zstd chunks of 255 MiB of empty Message records (under 1 MB, inside the
  reader's size and ratio limits);
* ``lz4_255``: the same with lz4 (3.3 MB);
* ``channels_100k``: 100 000 Channel records (every 16-bit channel id defined, some twice).

``replay``, ``log recover`` and ``console --log`` run each in a child process, inside a small
wrapper that measures the child's peak RSS and CPU time (``getrusage``) and its wall time (to
the URL line for the console, which then gets SIGINT). Each must exit as documented with no
traceback and at most one line on stderr, use the good messages, name the damage, and stay
under 300 MB and 10 s of CPU (the wall-time bound is a hang guard: on a machine shared with
other test runs it is several times the CPU time). ``fleet`` (which reads through the same
driver, ``catenary_monitor.replay.driver``, as ``replay``) runs once over the four files as
four dock folders, its cluster's processes counted in.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import hostile_mcap
import pytest
from ros_harness import child_env

ROOT = Path(__file__).resolve().parents[1]
DOCK_YAML = ROOT / 'config' / 'floating_dock.yaml'
TOPICS = ('/mooring/line_01/tension', '/tide/depth')
RSS_LIMIT_MB = 300
CPU_LIMIT_S = 10.0
WALL_GUARD_S = 60.0

WRAP = r'''
import json, resource, signal, subprocess, sys, time
argv, serve = json.loads(sys.argv[1]), sys.argv[2] == 'serve'
t0 = time.monotonic()
if serve:  # the console: up when it prints its URL, then Ctrl-C
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first = p.stdout.readline()
    wall = time.monotonic() - t0
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
    try:
        out, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
        err += 'TEST: did not stop within 60 s of SIGINT'
    out = first + out
else:
    # 300 s: a guard against a hang (the limits are CPU and RSS, measured beside it)
    p = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    out, err, wall = p.stdout, p.stderr, time.monotonic() - t0
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({'rc': p.returncode, 'out': out, 'err': err, 'wall': wall,
                  'rss_mb': ru.ru_maxrss / 1024, 'cpu': ru.ru_utime + ru.ru_stime}))
'''


def _head() -> bytes:
    """The node's ``catenary_monitor`` Metadata record for the floating dock."""
    from catenary_monitor.core.config.parameters import (
        config_from_params,
        config_hash,
        config_to_params,
        load_params_file,
    )

    config = config_from_params(load_params_file(DOCK_YAML))
    return hostile_mcap.metadata(
        'catenary_monitor',
        {'parameters': json.dumps(config_to_params(config)), 'config_hash': config_hash(config)},
    )


@pytest.fixture(scope='module')
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp('hostile')
    h, head = hostile_mcap, _head()
    return {
        'declares_2gib': h.declares_2gib_file(d / 'declares_2gib.mcap', TOPICS, head),
        'zstd_255': h.empty_records_file(d / 'zstd_255.mcap', 'zstd', TOPICS, head=head),
        'lz4_255': h.empty_records_file(d / 'lz4_255.mcap', 'lz4', TOPICS, head=head),
        'channels_100k': h.many_channels_file(d / 'channels_100k.mcap', TOPICS, head=head),
    }


def test_the_files_are_what_they_claim(files: dict[str, Path]) -> None:
    sizes = {k: p.stat().st_size for k, p in files.items()}
    assert 60_000 < sizes['declares_2gib'] < 80_000  # 66 KB and the recorded parameters
    assert sizes['zstd_255'] < 1_100_000 and sizes['lz4_255'] < 4_500_000


COMMANDS = {
    'replay': ['replay', '{f}'],
    'log recover': ['log', 'recover', '{f}'],
    'console --log': ['console', '--log', '{f}', '--port', '0'],
}


def _run(command: str, path: Path, *extra: str) -> dict:
    argv = [sys.executable, '-m', 'catenary_monitor', *COMMANDS[command], *extra]
    argv = [a.format(f=path) for a in argv]
    serve = 'serve' if command.startswith('console') else 'run'
    r = subprocess.run(
        [sys.executable, '-c', WRAP, json.dumps(argv), serve],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=240,
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.mark.parametrize('kind', ['declares_2gib', 'zstd_255', 'lz4_255', 'channels_100k'])
@pytest.mark.parametrize('command', sorted(COMMANDS))
def test_a_hostile_file_costs_one_line_bounded_memory_and_time(
    files: dict[str, Path], tmp_path: Path, command: str, kind: str
) -> None:
    path = tmp_path / files[kind].name
    shutil.copyfile(files[kind], path)  # recovery rewrites it
    got = _run(command, path)
    out, err = got['out'], got['err']
    assert got['rc'] == 0, err
    assert 'Traceback' not in err and len(err.strip().splitlines()) <= 1, err
    damaged = kind != 'channels_100k'
    if command == 'replay':
        assert 'line_01: 8 tension messages' in out, out
        assert ('corrupt_chunk' in out or 'bad_payload' in out) == damaged, out
    elif command == 'log recover':
        row = next(line for line in out.splitlines() if line.startswith(path.name))
        assert ' recovered ' in row and ' 16 ' in row, out
        assert ('@' in row or 'dropped' in row) == damaged, out
    else:
        assert out.startswith('console: http://'), (out, err)
        assert ('damaged log:' in err) == damaged, err
    print(f'{command} {kind}: {got["rss_mb"]:.0f} MB, {got["cpu"]:.2f} s CPU, {got["wall"]:.2f} s')
    assert got['rss_mb'] < RSS_LIMIT_MB, got['rss_mb']
    assert got['cpu'] < CPU_LIMIT_S, got['cpu']
    assert got['wall'] < WALL_GUARD_S, got['wall']


def test_the_fleet_replay_reads_the_hostile_files_through_the_same_driver(
    files: dict[str, Path], tmp_path: Path
) -> None:
    """``catenary-monitor fleet``, one dock folder per hostile file, one worker: every dock's
    good messages used and its damage named, in bounded memory (the cluster's processes
    included) and CPU (the four files and the cluster's start together)."""
    pytest.importorskip('distributed')
    docks = []
    for kind, src in files.items():
        (tmp_path / kind).mkdir()
        shutil.copyfile(src, tmp_path / kind / src.name)
        docks.append(str(tmp_path / kind))
    argv = [sys.executable, '-m', 'catenary_monitor', 'fleet', *docks, '--out',
            str(tmp_path / 'results'), '--workers', '1', '--quiet']  # fmt: skip
    r = subprocess.run(
        [sys.executable, '-c', WRAP, json.dumps(argv), 'run'],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=400,
    )
    got = json.loads(r.stdout)
    assert got['rc'] == 0 and 'Traceback' not in got['err'], got['err']
    for kind in files:
        row = next(line for line in got['out'].splitlines() if line.startswith(kind))
        assert ' 16 ' in row, got['out']  # the 16 good messages of each
    assert got['out'].count('bad_payload') == 6 and 'corrupt_chunk' in got['out'], got['out']
    print(f'fleet: {got["rss_mb"]:.0f} MB, {got["cpu"]:.2f} s CPU, {got["wall"]:.2f} s')
    assert got['rss_mb'] < RSS_LIMIT_MB, got['rss_mb']
    assert got['cpu'] < CPU_LIMIT_S * len(files), got['cpu']
    assert got['wall'] < 4 * WALL_GUARD_S, got['wall']


def _events_file(path: Path, kind: str) -> Path:
    """Two chunks of 8 MiB of empty records on the events channel (which replay reads raw)."""
    topics = ('/catenary_monitor/events', *TOPICS)
    return hostile_mcap.empty_records_file(
        path, 'lz4', topics, kind=kind, chunks=2, usize=8 << 20, head=_head()
    )


def test_empty_records_on_the_events_channel_are_counted_in_one_pass(tmp_path: Path) -> None:
    got = _run('replay', _events_file(tmp_path / 'events.mcap', 'messages'))
    assert got['rc'] == 0, got['err']
    assert got['out'].count('too short to be CDR') == 2 and 'line_01: 8 tension' in got['out']
    assert got['rss_mb'] < RSS_LIMIT_MB and got['cpu'] < CPU_LIMIT_S


def test_a_flood_of_messages_at_one_log_time_is_refused_in_one_line(tmp_path: Path) -> None:
    """480 000 events records of one stamp (the smallest payload CDR allows): a window cannot
    end between them, so they would all be held; more than 4 windows of them are refused
    (windows of 20 000 messages here: the rule is the same at the default 131 072)."""
    path = _events_file(tmp_path / 'flood.mcap', 'cdr_headers')
    got = _run('replay', path, '--window-messages', '20000')
    lines = got['err'].strip().splitlines()
    assert got['rc'] == 2 and len(lines) == 1, got['err']
    assert 'share log time 1000 ns' in lines[0] and 'bounded memory' in lines[0], lines[0]
    assert got['rss_mb'] < RSS_LIMIT_MB and got['cpu'] < CPU_LIMIT_S
