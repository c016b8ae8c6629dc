"""Every bad params file, whatever its bytes, gives exit 2 and one line naming the problem.

For each command that reads a params file through ``core.config.load_params_file``: ``run``,
the node itself, ``replay``, ``equilibrium``, ``envelope``, ``console`` and the demo's
simulator. Each runs as a subprocess; no traceback, one stderr line.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from replay_data import dock_config, generate, write_log
from ros_harness import child_env

NEEDLE = {
    'non_utf8': 'UTF-8',
    'garbage': 'YAML syntax',
    'empty': "'lines': missing",
    'not_a_mapping': 'Sequences cannot be key',
    'scalar': "'lines': missing",
    'directory': 'Is a directory',
    'missing': 'No such file',
    'unreadable': 'Not a directory',
    'dangling_link': 'No such file',
    'pipe': 'not a regular file',
    'huge': 'more than a params file holds',
    'duplicate': "'line_01.mbl' is given twice, at line 5 and line 7",
}


def bad_file(tmp: Path, case: str) -> Path:
    """A params file of the given kind of badness."""
    path = tmp / f'{case}.yaml'
    head = b'catenary_monitor:\n  ros__parameters:\n'
    if case == 'non_utf8':
        path.write_bytes(head + b'    lines: [\xff\xfe]\n')
    elif case == 'garbage':
        path.write_bytes(bytes(np.random.default_rng(3).integers(128, 256, 400, dtype=np.uint8)))
    elif case == 'empty':
        path.write_bytes(b'')
    elif case == 'not_a_mapping':
        path.write_bytes(b'- 1\n- 2\n')
    elif case == 'scalar':
        path.write_bytes(b'hello\n')
    elif case == 'directory':
        path.mkdir()
    elif case == 'unreadable':  # root reads a chmod 000 file: a path through a file instead
        (tmp / 'plain').write_bytes(b'x')
        path = tmp / 'plain' / 'p.yaml'
    elif case == 'dangling_link':
        os.symlink(tmp / 'nowhere', path)
    elif case == 'pipe':  # nobody writes: reading it would block
        os.mkfifo(path)
    elif case == 'duplicate':  # a copy-paste slip: rcl would monitor the line with 1 N
        path.write_bytes(
            head + b'    lines: [line_01]\n    line_01:\n      mbl: 4.8e6\n      weight: 1300.0\n'
            b'      mbl: 1.0\n      anchor_distance: 120.0\n'
        )
    elif case == 'huge':  # sparse: 17 MiB of zeros, no disk used
        with open(path, 'wb') as f:
            f.truncate(17 * 1024 * 1024)
    return path


@pytest.fixture(scope='module')
def log(tmp_path_factory) -> Path:
    """A small valid log, so replay gets as far as the params file."""
    config = dock_config(2)
    tensions, depth = generate(config, seconds=5.0)
    return write_log(tmp_path_factory.mktemp('log') / 'in.mcap', config, tensions, depth)


COMMANDS = {
    'run': ['-m', 'catenary_monitor', 'run', '--params-file', '{f}'],
    'node': ['-m', 'catenary_monitor.ros.node', '--ros-args', '--params-file', '{f}'],
    'replay': ['-m', 'catenary_monitor', 'replay', '{log}', '--params-file', '{f}'],
    'equilibrium': ['-m', 'catenary_monitor', 'equilibrium', '--params-file', '{f}', '--depth=20'],
    'envelope': ['-m', 'catenary_monitor', 'envelope', '--params-file', '{f}', '--depth=20'],
    'simulator': ['-m', 'catenary_monitor.ros.simulator', '--params-file', '{f}'],
    'console': ['-m', 'catenary_monitor', 'console', '--params-file', '{f}', '--port', '0'],
}


@pytest.mark.parametrize('case', sorted(NEEDLE))
@pytest.mark.parametrize('command', sorted(COMMANDS))
def test_bad_params_file_exits_2_with_one_line(tmp_path, log, command, case):
    path = bad_file(tmp_path, case)
    argv = [a.format(f=path, log=log) for a in COMMANDS[command]]
    r = subprocess.run(
        [sys.executable, *argv], capture_output=True, text=True, env=child_env(), timeout=60
    )
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr
    assert len(lines) == 1 and 'Traceback' not in r.stderr, r.stderr
    assert r.stdout.strip() == '', r.stdout
    assert NEEDLE[case] in lines[0], lines[0]
    if 'lines' not in NEEDLE[case] or command in ('run', 'node', 'replay', 'equilibrium'):
        assert path.name in lines[0], lines[0]


@pytest.mark.parametrize('command', ['run', 'replay'])
def test_a_tide_table_past_its_bounds_stops_every_command_at_once(tmp_path, log, command):
    """A 100 000-constituent table (2.6 MB) once made replay take minutes and run deaf to
    Ctrl-C: now one line and exit 2 before any work (the CPU time of the child is measured)."""
    import resource

    table = '; '.join(f'C{i} 0.01 10.0 28.98' for i in range(100_000))
    path = tmp_path / 'tide.yaml'
    path.write_text(
        'catenary_monitor:\n  ros__parameters:\n    lines: [a]\n    a:\n      weight: 1300.0\n'
        '      anchor_distance: 120.0\n      mbl: 4.8e6\n'
        f'    tide_table: "{table}"\n'
    )
    argv = [a.format(f=path, log=log) for a in COMMANDS[command]]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    r = subprocess.run(
        [sys.executable, *argv], capture_output=True, text=True, env=child_env(), timeout=60
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert "'tide_table'" in lines[0] and 'more than the 65536' in lines[0], lines[0]
    assert cpu < 5.0, cpu
