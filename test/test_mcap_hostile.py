"""Hostile chunks (issue 10): implausible or lying sizes cost bounded time and memory.

Each file is read in a child process (so its peak RSS is its own, measured with
``resource``); the hostile chunk must be reported as a Skip and the good chunk's messages
read. The child's timeout is a hang guard, not a timing assertion.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
from pathlib import Path

import hostile_mcap
import pytest
from ros_harness import child_env

KINDS = ['declares_2gib', 'lies_small', 'lies_small_nosize', 'lz4_lies', 'cut']
VALUES = [1.5, 2.5, 3.5, 4.5]
RSS_LIMIT_KB = 300 * 1024

CHILD = r'''
import json, sys
from catenary_monitor.io.mcap_read import read_float64_topics, iter_messages
def peak_kb():  # VmHWM starts afresh at exec; ru_maxrss keeps the forking pytest's peak
    line = [ln for ln in open('/proc/self/status') if ln.startswith('VmHWM:')][0]
    return int(line.split()[1])
cols, report = read_float64_topics(sys.argv[1], [sys.argv[2]])
n_iter = sum(1 for _ in iter_messages(sys.argv[1]))
out = {
    'values': cols[sys.argv[2]][1].tolist(),
    'iter': n_iter,
    'skips': [[s.kind, s.reason] for s in report.skips],
    'rss_kb': peak_kb(),
}
if len(sys.argv) > 3:
    from catenary_monitor.io.mcap_recover import recover_file
    result = recover_file(sys.argv[1])
    out['recover'] = result.to_dict()
    out['rss_kb'] = peak_kb()
print(json.dumps(out))
'''


def run_child(path: Path, *extra: str) -> dict:
    r = subprocess.run(
        [sys.executable, '-c', CHILD, str(path), hostile_mcap.TOPIC, *extra],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.fixture(scope='module', params=KINDS)
def hostile(request, tmp_path_factory) -> tuple[str, Path]:
    path = tmp_path_factory.mktemp('hostile') / f'{request.param}.mcap'
    return request.param, hostile_mcap.hostile_file(path, request.param, VALUES)


def test_crafted_file_is_small(hostile):
    kind, path = hostile
    assert path.stat().st_size < (2 << 20)  # a 69 KB (lz4: 1.1 MB) file declaring GiBs


def test_hostile_chunk_is_skipped_in_bounded_memory_and_the_rest_read(hostile):
    kind, path = hostile
    out = run_child(path)
    assert out['values'] == VALUES
    assert out['iter'] == len(VALUES)
    kinds = {k for k, _ in out['skips']}
    assert kinds == ({'truncated'} if kind == 'cut' else {'corrupt_chunk'}), out['skips']
    assert out['rss_kb'] < RSS_LIMIT_KB, f'{kind}: peak RSS {out["rss_kb"] / 1024:.0f} MB'


def test_recover_skips_the_hostile_chunk_in_bounded_memory_and_keeps_the_rest(hostile):
    from mcap_readers import mcap_messages

    kind, path = hostile
    out = run_child(path, 'recover')
    assert out['recover']['status'] == 'recovered', out
    assert out['recover']['messages'] == len(VALUES)
    assert out['recover']['damaged'], out
    assert out['rss_kb'] < RSS_LIMIT_KB, f'{kind}: peak RSS {out["rss_kb"] / 1024:.0f} MB'
    values = [struct.unpack('<d', data[4:])[0] for _, _, data in mcap_messages(path)]
    assert values == VALUES
