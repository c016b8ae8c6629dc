"""The recorded config hash depends only on what decides results.

``catenary-monitor run`` with the params file's ``log_dir`` and with ``--log-dir`` records the
same hash, the hash of the file as replay reads it; replaying with that file does not warn that
the log was recorded with other parameters. Subprocesses; every wait is for an event.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import time
from pathlib import Path

import pytest
from ros_harness import Client, child_env, stop, write_params

from catenary_monitor.core.config.parameters import config_hash
from catenary_monitor.replay.driver import load_config, log_parameters

pytestmark = pytest.mark.ros

LINES = {'h1': dict(weight=1300.0, anchor_distance=120.0, mbl=4.827e6)}


def _run(client: Client, params: Path, out: Path, *extra: str) -> None:
    """``catenary-monitor run`` until it has handled a depth and a tension, then SIGTERM."""
    cmd = [sys.executable, '-m', 'catenary_monitor', 'run', '--params-file', str(params), *extra]
    with open(out, 'w') as f:
        proc = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, env=child_env())
    try:
        client.wait_matched(['/tide/depth', '/mooring/h1/tension'], 30.0)
        t0 = time.monotonic()
        client.feed('/tide/depth', 20.85)
        client.feed('/mooring/h1/tension', 400e3)
        client.wait_status('catenary_monitor: h1', 15.0, 0, since=t0)
    finally:
        client.feed('/mooring/h1/tension', None)
        client.feed('/tide/depth', None)
        assert stop(proc) == 0, out.read_text()


def test_hash_is_the_same_with_and_without_log_dir_and_replay_does_not_warn(client, tmp_path):
    params = write_params(tmp_path / 'p.yaml', LINES, log_dir=str(tmp_path / 'a'))
    config = load_config(str(params))
    assert config_hash(config) == config_hash(
        dataclasses.replace(config, log_dir='/elsewhere', allow_runtime_changes=True)
    )
    _run(client, params, tmp_path / 'a.out')
    _run(client, params, tmp_path / 'b.out', '--log-dir', str(tmp_path / 'b'))
    hashes = {}
    for d in ('a', 'b'):
        files = sorted((tmp_path / d).glob('*.mcap'))
        recorded = log_parameters(files)
        assert recorded is not None, d
        hashes[d] = recorded[0]
        assert recorded[1]['log_dir'] == str(tmp_path / d)  # the parameters still say where
    assert hashes['a'] == hashes['b'] == config_hash(config)
    files = [str(f) for f in sorted((tmp_path / 'b').glob('*.mcap'))]
    r = subprocess.run(
        [sys.executable, '-m', 'catenary_monitor', 'replay', *files, '--params-file', str(params)],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert 'the same as recorded in the log' in r.stdout + r.stderr, r.stdout + r.stderr
    assert 'other parameters' not in r.stdout + r.stderr


@pytest.mark.parametrize('given', [None, 'LOCALHOST', 'SUBNET'])
def test_run_limits_discovery_to_localhost_unless_told(tmp_path, given):
    """The start line says which range the node runs with; a range the user set is kept."""
    env = child_env()
    env.pop('ROS_AUTOMATIC_DISCOVERY_RANGE', None)
    if given:
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = given
    probe = (
        'import os, sys; from catenary_monitor.cli.run import limit_discovery; '
        'print(limit_discovery(os.environ)); print(os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"])'
    )
    r = subprocess.run(
        [sys.executable, '-c', probe], capture_output=True, text=True, env=env, timeout=30
    )
    line, value = r.stdout.splitlines()
    assert value == (given or 'LOCALHOST')
    assert (given or 'LOCALHOST') in line and ('limited to this host' in line) == (not given)


def test_run_logs_the_discovery_range_once_started(client, tmp_path):
    env = child_env()
    env.pop('ROS_AUTOMATIC_DISCOVERY_RANGE', None)
    params = write_params(tmp_path / 'p.yaml', LINES, log_dir=str(tmp_path / 'a'))
    out = tmp_path / 'run.out'
    cmd = [sys.executable, '-m', 'catenary_monitor', 'run', '--params-file', str(params)]
    with open(out, 'w') as f:
        proc = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
    try:
        note = 'DDS discovery limited to this host (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST'
        client.wait_for(lambda: note in out.read_text(), 30.0, 'the start line')
    finally:
        assert stop(proc) == 0
    assert 'monitoring 1 lines' in out.read_text()


def test_log_rotation_duration_is_a_parameter(client, tmp_path):
    """``log_rotate_duration: 1.0``: the node starts new files every second, each finished
    (summary written) once closed; the rotation settings leave the config hash alone."""
    from mcap.reader import make_reader
    from ros_harness import start_monitor

    params = write_params(tmp_path / 'p.yaml', LINES, log_rotate_duration=1.0)
    log = tmp_path / 'log'
    proc = start_monitor(params, log)
    try:
        client.wait_for(lambda: len(list(log.glob('*.mcap'))) >= 3, 20.0, 'three log files')
    finally:
        assert stop(proc) == 0
    files = sorted(log.glob('*.mcap'))
    for path in files:
        with open(path, 'rb') as f:
            assert make_reader(f).get_summary() is not None, path
    recorded = log_parameters(files)
    assert recorded is not None and recorded[1]['log_rotate_duration'] == 1.0
    plain = write_params(tmp_path / 'plain.yaml', LINES)
    assert recorded[0] == config_hash(load_config(str(plain)))
