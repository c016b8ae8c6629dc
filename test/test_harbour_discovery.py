"""The harbour over Fast DDS discovery servers (docks on other subnets, docs/deploy.md).

Through a discovery server the ROS domain no longer keeps docks apart: a harbour given one
process-wide ``ROS_DISCOVERY_SERVER`` listing two docks' servers showed a dock with no monitor
at all as alive, with the other dock's twelve lines. Each dock's own server
(``--discovery-server NAME=HOST:PORT``, set only while that dock's participant is made) keeps
them apart; the process-wide one with several docks is refused in one line.

The servers are Fast DDS's ``fast-discovery-server`` of the PyPI wheels (its libraries beside
it); the test is skipped where it cannot run.
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
from typing import Any, Iterator, Optional

import pytest
from ros_harness import child_env, start_monitor, stop, write_params

pytestmark = [pytest.mark.ros, pytest.mark.slow]

LINES = {'l1': dict(weight=1300.0, anchor_distance=121.06, mbl=4.827e6)}


def _server_command() -> Optional[tuple[list[str], dict[str, str]]]:
    """The discovery server and the environment it runs in, or None."""
    binary = Path(sys.executable).parent / 'fast-discovery-server'
    if not binary.exists():
        return None
    site = Path(__import__('rclpy').__file__).parents[1]
    libs = [Path(sys.prefix) / 'lib', *site.glob('ros_fastrtps*.libs')]
    env = dict(os.environ)
    env['LD_LIBRARY_PATH'] = os.pathsep.join(
        [str(p) for p in libs] + [env.get('LD_LIBRARY_PATH', '')]
    )
    try:
        ok = subprocess.run([str(binary), '-h'], env=env, capture_output=True, timeout=20)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return ([str(binary)], env) if b'server-id' in ok.stdout + ok.stderr else None


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(('127.0.0.1', 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope='module')
def servers() -> Iterator[list[int]]:
    """Two discovery servers on this host (ids 0 and 1): their UDP ports."""
    found = _server_command()
    if found is None:
        pytest.skip('fast-discovery-server does not run here')
    cmd, env = found
    ports = [_free_udp_port(), _free_udp_port()]
    procs = [
        subprocess.Popen(
            [*cmd, '-i', str(k), '-l', '127.0.0.1', '-p', str(port)],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        for k, port in enumerate(ports)
    ]
    try:
        time.sleep(1.0)
        assert all(p.poll() is None for p in procs)
        yield ports
    finally:
        for p in procs:
            p.terminate()
            p.wait(10)


def _harbour(args: list[str], out: Path, env: dict[str, str]) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'harbour', *args, '--port', '0'],
        stdout=open(out, 'w+'),
        stderr=subprocess.STDOUT,
        env=env,
    )


def _docks(url: str) -> dict[str, Any]:
    with urllib.request.urlopen(url + 'api/docks', timeout=10) as res:
        return {d['name']: d for d in json.loads(res.read())}


def test_each_dock_on_its_own_server_is_kept_apart(servers: list[int], tmp_path: Path) -> None:
    """Dock a's monitor on server 0 (domain D), dock b (domain D + 1) without a monitor on
    server 1: the harbour with each dock's own server shows a alive and b silent (STALE, not
    alive), for longer than b's silence limit."""
    base = (int(os.environ['ROS_DOMAIN_ID']) + 7) % 233
    a = f'127.0.0.1:{servers[0]}'
    b = f';127.0.0.1:{servers[1]}'
    params = write_params(tmp_path / 'a.yaml', LINES, key='/**', diagnostic_rate=2.0)
    monitor_env = {'ROS_DISCOVERY_SERVER': a}
    saved = {k: os.environ.get(k) for k in monitor_env}
    os.environ.update(monitor_env)  # start_monitor's child_env() takes this process's
    try:
        monitor = start_monitor(params, tmp_path / 'log', domain_id=base)
    finally:
        for k, v in saved.items():
            os.environ.pop(k) if v is None else os.environ.__setitem__(k, v)
    out = tmp_path / 'harbour.out'
    harbour = _harbour(
        ['--dock', f'a={base}', '--dock', f'b={base + 1}',
         '--discovery-server', f'a={a}', '--discovery-server', f'b={b}'],
        out, child_env(),
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 90.0
        url = None
        while url is None and time.monotonic() < deadline:
            assert harbour.poll() is None, out.read_text()
            found = re.search(r'harbour: (http://\S+)', out.read_text())
            url = found.group(1) if found else None
            time.sleep(0.1)
        assert url, out.read_text()
        seen: dict[str, Any] = {}
        while time.monotonic() < deadline:
            seen = _docks(url)
            if seen['a']['monitor_alive'] and seen['a']['lines']:
                break
            time.sleep(0.2)
        assert seen['a']['monitor_alive'] and [ln['name'] for ln in seen['a']['lines']] == ['l1']
        time.sleep(6.0)  # past any silence limit: b never heard a's monitor
        seen = _docks(url)
        assert seen['a']['monitor_alive'] is True
        assert seen['b']['monitor_alive'] is False and seen['b']['level'] == 'STALE'
        assert seen['b']['lines'] == [] or all(ln['level'] == 'STALE' for ln in seen['b']['lines'])
    finally:
        assert stop(harbour, signal.SIGINT) == 0, out.read_text()
        stop(monitor, signal.SIGTERM)


def test_one_server_for_the_whole_harbour_is_refused_in_one_line(tmp_path: Path) -> None:
    """``ROS_DISCOVERY_SERVER`` in the harbour's environment and two docks without their own:
    exit 2 with one line naming the option (a silent dock would show another's statuses)."""
    env = {**child_env(), 'ROS_DISCOVERY_SERVER': '127.0.0.1:11811'}
    out = tmp_path / 'harbour.out'
    proc = _harbour(['--dock', 'a=40', '--dock', 'b=41'], out, env)
    assert proc.wait(60) == 2
    text = out.read_text().strip()
    assert len(text.splitlines()) == 1 and '--discovery-server NAME=HOST:PORT' in text, text
    one = _harbour(['--dock', 'a=40', '--discovery-server', 'a=127.0.0.1:11811'], out, env)
    time.sleep(0.1)
    assert stop(one, signal.SIGINT) in (0, -signal.SIGINT)  # one dock: not refused


@pytest.mark.parametrize(
    'bad', ['a', 'a=', 'a=host:99999', 'a=ho st:1', 'zz=127.0.0.1:11811', 'a=;;']
)
def test_a_bad_discovery_server_is_one_line(bad: str, capsys: Any) -> None:
    from catenary_monitor.cli.main import main

    code = main(['harbour', '--dock', 'a=40', '--discovery-server', bad, '--port', '0'])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and '--discovery-server' in err, err
