"""CI runs the README's test command verbatim (.ci/run holds the same line), and that command's
system step installs only what a machine lacks (tools/install-test-tools.sh)."""

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / 'tools' / 'install-test-tools.sh'


def readme_test_command() -> str:
    readme = ROOT.joinpath('README.md').read_text(encoding='utf-8')
    block = re.search(r'# 2\..*?\n((?:#.*\n)*)(.+)\n```', readme)
    assert block, 'README command 2 not found'
    return block.group(2).strip()


def test_ci_runs_the_readme_test_command():
    command = readme_test_command()
    run = ROOT.joinpath('.ci', 'run').read_text(encoding='utf-8').strip().splitlines()
    assert run[-1].strip() == command
    # the browser tests' and the JS reader tests' tools come from the installer, not from one
    # apt line that asks for nodejs and npm whatever the machine has
    assert command.startswith('sh tools/install-test-tools.sh && ')
    assert 'apt-get' not in command


def _fake_path(tmp_path: Path, tools: tuple[str, ...]) -> Path:
    """A PATH holding the given tools (stubs), the shell's basics and a recording apt-get."""
    bin_dir = tmp_path / 'bin'
    bin_dir.mkdir()
    for tool in tools:
        stub = bin_dir / tool
        stub.write_text('#!/bin/sh\nexit 0\n')
        stub.chmod(0o755)
    for tool in ('id', 'grep', 'cat', 'sh'):
        os.symlink(shutil.which(tool), bin_dir / tool)
    apt = bin_dir / 'apt-get'
    apt.write_text(f'#!/bin/sh\necho "$@" >> {tmp_path / "apt.log"}\nexit 0\n')
    apt.chmod(0o755)
    dpkg = bin_dir / 'dpkg-query'
    dpkg.write_text('#!/bin/sh\necho 20.20.2-1nodesource1\n')
    dpkg.chmod(0o755)
    return bin_dir


#: What every machine here has besides the tools a test names: Debian's python3 with venv, and
#: systemd-analyze.
BASE = ('python3', 'systemd-analyze')


def _install(
    tmp_path: Path, tools: tuple[str, ...], base: tuple[str, ...] = BASE
) -> tuple[int, str, list[str]]:
    bin_dir = _fake_path(tmp_path, tools + base)
    env = {'PATH': str(bin_dir), 'APT_SIMULATE': '1', 'DEBIAN_PYTHON': str(bin_dir / 'python3')}
    done = subprocess.run(
        ['/bin/sh', str(SCRIPT)], env=env, capture_output=True, text=True, timeout=60
    )
    log = tmp_path / 'apt.log'
    asked = log.read_text().splitlines() if log.exists() else []
    return done.returncode, done.stderr, asked


@pytest.mark.parametrize(
    'have, wanted',
    [
        # a fresh machine with nodesource's Node.js: Chromium only, its npm left alone
        (('node', 'npm'), 'chromium chromium-driver'),
        (('node', 'npm', 'chromium'), 'chromium-driver'),
        ((), 'chromium chromium-driver nodejs npm'),
        (('chromium', 'chromedriver'), 'nodejs npm'),
    ],
)
def test_only_what_is_missing_is_asked_for(tmp_path, have, wanted):
    rc, err, asked = _install(tmp_path, have)
    assert rc == 0, err
    assert asked == [f'install -s -y -qq {wanted}']


def test_debian_python_without_venv_and_no_systemd_analyze(tmp_path):
    """Debian's python3 without python3-venv (no ensurepip), no systemd-analyze: both asked."""
    bin_dir = _fake_path(tmp_path, ('node', 'npm', 'chromium', 'chromedriver', 'python3'))
    (bin_dir / 'python3').write_text('#!/bin/sh\nexit 1\n')
    env = {'PATH': str(bin_dir), 'APT_SIMULATE': '1', 'DEBIAN_PYTHON': str(bin_dir / 'python3')}
    done = subprocess.run(['/bin/sh', str(SCRIPT)], env=env, capture_output=True, text=True,
                          timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    asked = (tmp_path / 'apt.log').read_text().splitlines()
    assert asked == ['install -s -y -qq python3-venv systemd']


def test_a_complete_machine_asks_apt_for_nothing(tmp_path):
    rc, err, asked = _install(tmp_path, ('node', 'npm', 'chromium', 'chromedriver'))
    assert (rc, asked) == (0, [])


def test_a_foreign_node_without_npm_is_not_replaced(tmp_path):
    rc, err, asked = _install(tmp_path, ('chromium', 'chromedriver', 'node'))
    assert rc == 1 and asked == []
    assert 'not Debian' in err and err.count('\n') == 1


@pytest.mark.skipif(shutil.which('apt-get') is None, reason='not a Debian machine')
def test_this_machines_apt_accepts_what_the_installer_asks(tmp_path):
    """Real apt in simulate mode, with this machine's node and npm but no Chromium on the PATH:
    what the installer asks must resolve (the old 'chromium ... nodejs npm' line did not where
    Node.js came from nodesource)."""
    bin_dir = tmp_path / 'bin'
    bin_dir.mkdir()
    for tool in ('node', 'npm', 'apt-get', 'dpkg-query', 'id', 'grep'):
        if shutil.which(tool):
            os.symlink(shutil.which(tool), bin_dir / tool)
    env = {'PATH': f'{bin_dir}', 'APT_SIMULATE': '1', 'LC_ALL': 'C'}
    done = subprocess.run(
        ['/bin/sh', str(SCRIPT)], env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr + done.stdout
