"""The harbour over docks that each run a Fast DDS discovery server (with the PyPI wheels'
``fast-discovery-server``): two monitors in two domains, each a client of its own dock's server.

``--discovery-server NAME=SERVERS`` makes the harbour's participant in that dock's domain a
client of that dock's servers alone: each dock is heard at its own rate, apart. The trap beside
it: one ``ROS_DISCOVERY_SERVER`` naming both servers for the whole harbour process matches
every monitor in every domain (a server does not keep domains apart): the harbour refuses it
in one line.
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

import pytest
from ros_harness import child_env, start_monitor, stop, write_params

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.usefixtures('no_callback_errors')]

VENV = Path(sys.executable).parent.parent
SERVER = VENV / 'bin' / 'fast-discovery-server'
LINES = {'l1': dict(weight=1300.0, anchor_distance=121.06, mbl=4.827e6)}
RATE = 2.0  # Hz: each monitor's /diagnostics


def _server_env() -> dict[str, str]:
    """The wheel's server finds its libraries beside the venv's (the ``fastdds discovery``
    wrapper does not find the tool in a venv)."""
    wheel = VENV.glob('lib/python3*/site-packages/ros_fastrtps.libs')
    libs = [str(VENV / 'lib'), *map(str, wheel)]
    return dict(os.environ, LD_LIBRARY_PATH=os.pathsep.join(libs))


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def _get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=10) as res:
        return json.loads(res.read())


@pytest.fixture(scope='module')
def docks(tmp_path_factory: Any) -> Any:
    """Two discovery servers (ids 0 and 1), two monitors each a client of its own: yields the
    docks' (name, domain, ROS_DISCOVERY_SERVER value)."""
    if not SERVER.exists():
        pytest.skip('no fast-discovery-server in this venv')
    tmp = tmp_path_factory.mktemp('ds')
    base = int(os.environ['ROS_DOMAIN_ID'])
    procs: list[subprocess.Popen] = []
    out: list[tuple[str, int, str]] = []
    try:
        for k, name in enumerate(('east', 'west')):
            port = _free_udp_port()
            cmd = [str(SERVER), '-i', str(k), '-l', '127.0.0.1', '-p', str(port)]
            log = tmp / f'{name}.srv'
            server = subprocess.Popen(cmd, env=_server_env(), stdout=open(log, 'w'),
                                      stderr=subprocess.STDOUT)  # fmt: skip
            procs.append(server)
            time.sleep(0.5)
            if server.poll() is not None:
                pytest.skip(f'fast-discovery-server does not start: {log.read_text()}')
            servers = ';' * k + f'127.0.0.1:{port}'  # its place in the list is its id
            domain = (base + 20 + 5 * k) % 233
            params = write_params(tmp / f'{name}.yaml', LINES, diagnostic_rate=RATE)
            os.environ['ROS_DISCOVERY_SERVER'] = servers  # the monitor's (start_monitor copies)
            try:
                procs.append(start_monitor(params, tmp / f'log_{name}', domain_id=domain))
            finally:
                del os.environ['ROS_DISCOVERY_SERVER']
            out.append((name, domain, servers))
        yield out
    finally:
        for proc in reversed(procs):
            if proc.poll() is None:
                stop(proc, signal.SIGTERM)


def _harbour(tmp_path: Path, args: list[str], env: dict[str, str]) -> tuple[Any, str]:
    out = tmp_path / 'harbour.out'
    proc = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'harbour', *args, '--port', '0'],
        stdout=open(out, 'w+'), stderr=subprocess.STDOUT, env=env,
    )  # fmt: skip
    deadline = time.monotonic() + 90.0
    while time.monotonic() < deadline:
        assert proc.poll() is None, out.read_text()
        found = re.search(r'harbour: (http://\S+)', out.read_text())
        if found:
            return proc, found.group(1)
        time.sleep(0.1)
    proc.kill()
    raise AssertionError(f'no harbour URL: {out.read_text()}')


def _rates(url: str, seconds: float = 4.0) -> dict[str, Any]:
    """Each dock's arrays per second over ``seconds`` once both are heard, and its view."""
    deadline = time.monotonic() + 60.0
    while not all(d['received']['arrays'] > 2 for d in _get(url + 'api/docks')):
        assert time.monotonic() < deadline, _get(url + 'api/docks')
        time.sleep(0.2)
    time.sleep(2.5)  # past the publishers check (every 2 s)
    first, t0 = _get(url + 'api/docks'), time.monotonic()
    time.sleep(seconds)
    last, t1 = _get(url + 'api/docks'), time.monotonic()
    return {
        b['name']: (round((b['received']['arrays'] - a['received']['arrays']) / (t1 - t0), 2), b)
        for a, b in zip(first, last)
    }


def test_each_dock_through_its_own_discovery_server(docks, tmp_path):
    args = [a for name, domain, servers in docks for a in
            ('--dock', f'{name}={domain}', '--discovery-server', f'{name}={servers}')]  # fmt: skip
    env = child_env()
    env.pop('ROS_AUTOMATIC_DISCOVERY_RANGE', None)
    proc, url = _harbour(tmp_path, args, env)
    try:
        rates = _rates(url)
    finally:
        assert stop(proc, signal.SIGINT) == 0
    for name, (rate, view) in rates.items():
        assert rate < 1.5 * RATE, (name, rate)  # its own monitor's arrays only
        assert 'monitors' not in view and view['monitor_alive'], (name, view['message'])


def test_one_discovery_server_setting_for_the_whole_harbour_is_refused(docks, tmp_path):
    """One ``ROS_DISCOVERY_SERVER`` naming both servers for the whole harbour would match every
    monitor in every domain (measured: each domain heard both monitors; with one monitor
    silent, its dock showed the other's lines as its own, alive): refused in one line."""
    args = [a for name, domain, _ in docks for a in ('--dock', f'{name}={domain}')]
    env = child_env()
    env['ROS_DISCOVERY_SERVER'] = ';'.join(s.lstrip(';') for _, _, s in docks)
    out = tmp_path / 'refused.out'
    proc = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'harbour', *args, '--port', '0'],
        stdout=open(out, 'w+'), stderr=subprocess.STDOUT, env=env,
    )  # fmt: skip
    assert proc.wait(60) == 2
    text = out.read_text().strip()
    assert len(text.splitlines()) == 1 and '--discovery-server NAME=SERVERS' in text, text


@pytest.mark.parametrize(
    'bad', ['a', 'a=', 'a=host:99999', 'a=ho st:1', 'zz=127.0.0.1:11811', 'a=;;']
)
def test_a_bad_discovery_server_is_one_line(bad, capsys):
    from catenary_monitor.cli.main import main

    code = main(['harbour', '--dock', 'a=40', '--discovery-server', bad, '--port', '0'])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and '--discovery-server' in err, err
