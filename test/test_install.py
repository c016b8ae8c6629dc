"""The package installed as an installer installs it: ``python3 -m venv V && V/bin/pip install
.`` with the machine's own Debian ``/usr/bin/python3`` (Debian 12: pip 23.0.1, which ran the
legacy ``setup.py install`` before pyproject.toml and left the commands out of ``bin/``) and with
Python 3.12 (Jazzy's Ubuntu 24.04 Python), each followed by a smoke: ``solve``, the replay of a
small log and the node for a few seconds, all from the venv's ``bin/``.

The venvs live in a folder every user may read (not pytest's own, which is root's only): the
systemd units' commands run from the Debian venv as an unprivileged user without a home (the
last tests here). An interpreter this machine lacks is skipped with its reason (``-ra`` lists
it); ``tools/install-test-tools.sh`` installs Debian's python3-venv where it is missing.
"""

from __future__ import annotations

import glob
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Optional

import pytest
from replay_data import dock_config, generate, params_yaml, write_log

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ('catenary-monitor', 'monitor', 'dock_simulator')
DEBIAN_PYTHON = '/usr/bin/python3'


def _version(python: str) -> Optional[tuple[int, int]]:
    """(major, minor) of an interpreter that runs and has venv with ensurepip, else None."""
    code = 'import sys, venv, ensurepip; print(*sys.version_info[:2])'
    try:
        done = subprocess.run([python, '-c', code], capture_output=True, text=True, timeout=60)
    except OSError:
        return None
    if done.returncode:
        return None
    major, minor = done.stdout.split()
    return int(major), int(minor)


def python312() -> Optional[str]:
    """A Python 3.12 of this machine: the system's, pyenv's, or one on PATH (a pyenv shim
    answers only when its version is selected: it is tried last)."""
    pyenv = os.environ.get('PYENV_ROOT', os.path.expanduser('~/.pyenv'))
    candidates = [
        '/usr/bin/python3.12',
        '/usr/local/bin/python3.12',
        *sorted(glob.glob(f'{pyenv}/versions/3.12*/bin/python3.12'), reverse=True),
        shutil.which('python3.12') or '',
    ]
    for path in filter(None, candidates):
        if os.access(path, os.X_OK) and _version(path) == (3, 12):
            return path
    return None


def interpreter(kind: str) -> str:
    """The interpreter of ``kind`` (``debian``, ``python3.12``), or skip saying what is missing."""
    if kind == 'debian':
        if not os.access(DEBIAN_PYTHON, os.X_OK):
            pytest.skip(f'no {DEBIAN_PYTHON} on this machine')
        if _version(DEBIAN_PYTHON) is None:
            pytest.skip(f'{DEBIAN_PYTHON} has no venv (sh tools/install-test-tools.sh)')
        return DEBIAN_PYTHON
    found = python312()
    if found is None:
        pytest.skip('no Python 3.12 on this machine (pyenv install 3.12, or apt on Ubuntu 24.04)')
    return found


class Installs:
    """The venvs of this run, built once each in a folder every user may read."""

    def __init__(self) -> None:
        self.base = Path(tempfile.mkdtemp(prefix='catenary-install-'))
        self.base.chmod(0o755)
        self.src = self.base / 'src'
        self.venvs: dict[str, Path] = {}
        self.seconds: dict[str, float] = {}

    def source(self) -> Path:
        """The tracked tree, copied (no in-place build comes along)."""
        if not self.src.exists():
            files = subprocess.run(
                ['git', 'ls-files', '-z'], cwd=ROOT, capture_output=True, check=True
            ).stdout.split(b'\0')
            for name in filter(None, files):
                path = ROOT / name.decode()
                if path.is_file():
                    (self.src / name.decode()).parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(path, self.src / name.decode())
        return self.src

    def venv(self, kind: str) -> Path:
        """README command 1's install with the interpreter of ``kind``: the venv."""
        if kind not in self.venvs:
            python = interpreter(kind)
            venv = self.base / f'venv-{kind}'
            start = time.monotonic()
            done = subprocess.run([python, '-m', 'venv', str(venv)], capture_output=True,
                                  text=True, timeout=300)  # fmt: skip
            assert done.returncode == 0, done.stderr
            done = subprocess.run(
                [str(venv / 'bin/pip'), 'install', '-q', str(self.source())],
                capture_output=True, text=True, timeout=900, cwd=self.base,
            )  # fmt: skip
            assert done.returncode == 0, done.stderr[-3000:]
            self.seconds[kind] = time.monotonic() - start
            self.venvs[kind] = venv
        return self.venvs[kind]

    def cleanup(self) -> None:
        shutil.rmtree(self.base, ignore_errors=True)


@pytest.fixture(scope='session')
def installs():
    found = Installs()
    yield found
    found.cleanup()


KINDS = ('debian', 'python3.12')


def _env() -> dict[str, str]:
    """The child's environment: this test's DDS domain, nothing of this checkout's path."""
    env = {k: v for k, v in os.environ.items() if k not in ('PYTHONPATH', 'VIRTUAL_ENV')}
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env['PYTHONUNBUFFERED'] = '1'
    return env


def _run(venv: Path, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([str(venv / 'bin/catenary-monitor'), *args], capture_output=True,
                          text=True, timeout=timeout, env=_env(), cwd=venv.parent)  # fmt: skip


@pytest.mark.parametrize('kind', KINDS)
def test_readme_install_puts_the_commands_in_the_venvs_bin(installs, kind):
    venv = installs.venv(kind)
    for name in COMMANDS:
        assert (venv / 'bin' / name).is_file(), name
    assert not (venv / 'lib/catenary_monitor').exists()  # where the legacy install put them
    share = venv / 'share/catenary_monitor'
    for name in ('config/floating_dock.yaml', 'launch/monitor.launch.xml', 'package.xml'):
        assert (share / name).is_file(), name
    print(f'{kind}: venv and pip install in {installs.seconds[kind]:.0f} s')


@pytest.mark.parametrize('kind', KINDS)
def test_solve_from_the_install(installs, kind):
    venv = installs.venv(kind)
    done = _run(venv, 'solve', '--weight', '1300', '--depth', '20.85', '--tension', '1623.5e3',
                '--anchor-distance', '121.06', '--json')  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)['uplift_force'] == pytest.approx(193267.5, abs=1.0)


@pytest.mark.parametrize('kind', KINDS)
def test_replay_of_a_small_log_from_the_install(installs, kind, tmp_path):
    venv = installs.venv(kind)
    config = dock_config(3)
    tensions, depth = generate(config, seconds=60.0)
    log = write_log(tmp_path / 'small.mcap', config, tensions, depth)
    params = params_yaml(config, tmp_path / 'dock.yaml')
    done = _run(venv, 'replay', str(log), '--params-file', str(params), '--json')
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert sorted(summary['lines']) == ['line_01', 'line_02', 'line_03'], summary.keys()


@pytest.mark.parametrize('kind', KINDS)
def test_the_node_runs_from_the_install(installs, kind, tmp_path):
    venv = installs.venv(kind)
    params = venv / 'share/catenary_monitor/config/floating_dock.yaml'
    proc = subprocess.Popen(
        [str(venv / 'bin/catenary-monitor'), 'run', '--params-file', str(params),
         '--log-dir', str(tmp_path / 'log')],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=_env(), cwd=tmp_path,
    )  # fmt: skip
    seen = []
    try:
        deadline = time.monotonic() + 90.0
        while time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line and proc.poll() is not None:
                break
            seen.append(line)
            if 'monitoring 12 lines' in line:
                break
        time.sleep(3.0)  # a few seconds of running: timers, diagnostics, the log's flushes
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
    text = ''.join(seen) + out
    assert 'monitoring 12 lines' in text, text
    assert proc.returncode == 0, text
    assert list((tmp_path / 'log').glob('*.mcap')) and (tmp_path / 'log/metadata.yaml').exists()


# ------------------------------------------------- the systemd units, as a user without a home
NOBODY = 65534


def _owned(path: Path, mode: int = 0o755) -> Path:
    """A folder (or file) of the service user, as systemd's StateDirectory= makes it."""
    if not path.exists():
        path.mkdir(parents=True)
    os.chown(path, NOBODY, NOBODY)
    path.chmod(mode)
    return path


def _free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return int(sock.getsockname()[1])


def _as_unit(name: str, places: dict, port: int, log: Path) -> subprocess.Popen:
    """The unit's ExecStart as the unprivileged user (setpriv), with systemd's environment for a
    user without a home and the unit's Environment=, from /."""
    from systemd_units import BASE_ENV, command

    argv, unit_env = command(name, places)
    if '--port' in argv:
        argv[argv.index('--port') + 1] = str(port)
    env = dict(BASE_ENV, **unit_env)
    env['ROS_DOMAIN_ID'] = os.environ['ROS_DOMAIN_ID']  # this test's domain
    env['ROS_STATIC_PEERS'] = '127.0.0.1'
    setpriv = ['setpriv', f'--reuid={NOBODY}', f'--regid={NOBODY}', '--clear-groups', '--']
    out = open(log, 'w')
    return subprocess.Popen([*setpriv, *argv], env=env, cwd='/', stdout=out,
                            stderr=subprocess.STDOUT)  # fmt: skip


def _wait_for(log: Path, proc: subprocess.Popen, pattern: str, timeout: float) -> str:
    import re

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        text = log.read_text()
        match = re.search(pattern, text)
        if match:
            return match.group(0)
        assert proc.poll() is None, text
        time.sleep(0.2)
    raise AssertionError(f'{pattern!r} not seen: {log.read_text()}')


def test_the_units_run_as_a_user_without_a_home(installs):
    """Each unit's ExecStart from the Debian venv as ``nobody`` (home /nonexistent), with the
    unit's Environment= and the state and log folders systemd would make: the monitor logs and
    writes its MCAP log, the console serves, and a program acknowledges through it with an
    operator's token (202 in her name; 401 without it)."""
    import urllib.error
    import urllib.request

    from systemd_units import ETC, LOGS, STATE, VENV

    if shutil.which('setpriv') is None or os.geteuid() != 0:
        pytest.skip('needs setpriv and root')
    venv = installs.venv('debian')
    base = installs.base / 'units'
    etc = base / 'etc'
    etc.mkdir(parents=True)
    (etc / 'dock.yaml').write_text((ROOT / 'config/dock_template.yaml').read_text())
    token = 'b0a7d1e5c3f9e2d4a6b8c0d2'
    (etc / 'operators').write_text(f'alice:{token}\n')
    _owned(etc / 'operators', 0o600)
    places = {VENV: str(venv), f'{ETC}/dock.yaml': str(etc / 'dock.yaml'),
              f'{ETC}/operators': str(etc / 'operators'), STATE: str(_owned(base / 'state')),
              LOGS: str(_owned(base / 'logs'))}  # fmt: skip
    port = _free_port()
    monitor = _as_unit('catenary-monitor.service', places, port, base / 'monitor.out')
    console = _as_unit('catenary-monitor-console.service', places, port, base / 'console.out')
    try:
        _wait_for(base / 'monitor.out', monitor, r'monitoring 4 lines', 90.0)
        _wait_for(base / 'monitor.out', monitor, r'static peers 127\.0\.0\.1', 5.0)
        url = _wait_for(base / 'console.out', console, r'http://127\.0\.0\.1:\d+/', 90.0)
        assert 'also at http://' in (base / 'console.out').read_text()  # bound to 0.0.0.0
        with urllib.request.urlopen(url, timeout=10) as reply:
            assert reply.status == 200
        # a program: no Origin; without a token 401, then `catenary-monitor ack` as alice
        request = urllib.request.Request(url + 'api/ack', b'{"line": "all"}',
                                         {'Content-Type': 'application/json'})  # fmt: skip
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(request, timeout=10)
        assert refused.value.code == 401
        button = base / 'button.token'
        button.write_text(token + '\n')
        button.chmod(0o600)
        deadline = time.monotonic() + 30.0
        while True:  # until the console's publisher has met the monitor (503 before)
            done = _run(venv, 'ack', 'all', '--console', url, '--token-file', str(button))
            if done.returncode == 0 or time.monotonic() > deadline:
                break
            time.sleep(1.0)
        assert done.returncode == 0, done.stderr
        assert done.stdout.startswith('acknowledged all as alice: all alice via console')
    finally:
        for proc in (console, monitor):
            proc.send_signal(signal.SIGTERM)
        statuses = [proc.wait(timeout=30) for proc in (console, monitor)]
    assert statuses == [0, 0], [(base / f).read_text() for f in ('console.out', 'monitor.out')]
    assert list((base / 'logs').glob('*.mcap')) and (base / 'logs/metadata.yaml').exists()
    assert list((base / 'state/log').iterdir())  # rcl's own log files, in the state folder
    text = (base / 'monitor.out').read_text() + (base / 'console.out').read_text()
    assert 'Traceback' not in text and token not in text, text
