"""A ROS 2 deployment, checked as far as this machine can: the package installed the way colcon
installs an ament_python package (``setup.py install --prefix``: scripts in
``lib/catenary_monitor``, data in ``share/catenary_monitor``), ``ros2 run``'s command run from
that install, the launch file parsed against it, package.xml against the imports, the systemd
unit's command run and stopped as systemd does, and the params template.

There is no ``ros2`` CLI nor ``launch`` on PyPI: ``ros2 run PKG EXE ARGS`` is
``<prefix>/lib/PKG/EXE ARGS`` with the workspace on the Python path, which is what runs here.
"""

from __future__ import annotations

import ast
import configparser
import os
import re
import shlex
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from ros_harness import child_env

from catenary_monitor.core.config.parameters import config_from_params, load_params_file

ROOT = Path(__file__).resolve().parent.parent
PKG = 'catenary_monitor'


@pytest.fixture(scope='module')
def install(tmp_path_factory):
    """The tracked tree installed as colcon's ament_python build does (no C accelerators)."""
    src = tmp_path_factory.mktemp('src')
    prefix = tmp_path_factory.mktemp('install')
    files = subprocess.run(
        ['git', 'ls-files', '-z'], cwd=ROOT, capture_output=True, check=True
    ).stdout.split(b'\0')
    for name in filter(None, files):
        path = ROOT / name.decode()
        if path.is_file():
            (src / name.decode()).parent.mkdir(parents=True, exist_ok=True)
            (src / name.decode()).write_bytes(path.read_bytes())
    env = dict(os.environ, CATENARY_MONITOR_NO_EXTENSIONS='1')
    record = str(prefix / 'files.txt')
    cmd = [sys.executable, 'setup.py', '-q', 'install', '--prefix', str(prefix),
           '--single-version-externally-managed', '--record', record]  # fmt: skip
    done = subprocess.run(cmd, cwd=src, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    site = next(prefix.glob('lib/python3*/site-packages'))
    return prefix, site


def _ros2_run(install, exe, *args, cwd):
    """``ros2 run catenary_monitor EXE ARGS`` in the workspace ``install``."""
    prefix, site = install
    env = child_env()
    env['PYTHONPATH'] = str(site)  # the workspace's, not this checkout
    exe_path = prefix / 'lib' / PKG / exe
    return subprocess.Popen(
        [str(exe_path), *args], cwd=cwd, env=env, stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip


def _wait_line(proc, word, timeout):
    deadline = time.monotonic() + timeout
    seen = []
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line and proc.poll() is not None:
            break
        seen.append(line)
        if word in line:
            return ''.join(seen)
    raise AssertionError(f'{word!r} not seen: {"".join(seen)}')


def test_colcon_layout_and_ros2_run(install, tmp_path):
    prefix, site = install
    lib = prefix / 'lib' / PKG
    assert {p.name for p in lib.iterdir()} >= {'catenary-monitor', 'monitor', 'dock_simulator'}
    assert not (prefix / 'bin' / 'catenary-monitor').exists()  # not on PATH: ros2 run
    share = prefix / 'share' / PKG
    assert (prefix / 'share/ament_index/resource_index/packages' / PKG).exists()
    for name in ('package.xml', 'launch/monitor.launch.xml', 'config/floating_dock.yaml',
                 'config/dock_template.yaml', 'deploy/catenary-monitor.service'):  # fmt: skip
        assert (share / name).is_file(), name
    proc = _ros2_run(
        install, 'catenary-monitor', 'run', '--params-file',
        str(share / 'config/floating_dock.yaml'), '--log-dir', str(tmp_path / 'log'),
        cwd=tmp_path,
    )  # fmt: skip
    try:
        text = _wait_line(proc, 'monitoring 12 lines', 60.0)
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=20)
    assert proc.returncode == 0, text + out
    assert list((tmp_path / 'log').glob('*.mcap'))


def _substitute(text, args, share):
    """A launch attribute with $(var X) and $(find-pkg-share catenary_monitor) resolved."""
    text = re.sub(r'\$\(var (\w+)\)', lambda m: args[m.group(1)], text)
    return text.replace(f'$(find-pkg-share {PKG})', str(share))


def test_launch_file_names_what_the_install_has(install, tmp_path):
    prefix, _ = install
    share = prefix / 'share' / PKG
    root = ET.parse(share / 'launch/monitor.launch.xml').getroot()
    assert root.tag == 'launch'
    args = {a.get('name'): a.get('default') for a in root.iter('arg')}
    assert {'params_file', 'console', 'console_port', 'console_bind'} <= set(args)
    params = _substitute(args['params_file'], args, share)
    assert Path(params).is_file()
    config_from_params(load_params_file(params))
    nodes = list(root.iter('node'))
    assert [n.get('exec') for n in nodes] == ['monitor', 'catenary-monitor']
    for node in nodes:
        assert node.get('pkg') == PKG
        assert (prefix / 'lib' / PKG / node.get('exec')).is_file()
        for p in node.iter('param'):
            assert Path(_substitute(p.get('from'), args, share)).is_file()
    # The console's command line as launch builds it is one its parser takes.
    console = shlex.split(_substitute(nodes[1].get('args'), args, share))
    assert console[0] == 'console'
    from catenary_monitor.cli.main import build_parser

    parsed = build_parser().parse_args([*console, '--ros-args', '-r', '__ns:=/'])
    assert parsed.params_file == params and parsed.bind == '127.0.0.1'


def test_package_xml_lists_every_runtime_dependency():
    root = ET.parse(ROOT / 'package.xml').getroot()
    depends = {e.text for e in root.iter('exec_depend')}
    text = (ROOT / 'package.xml').read_text()
    rosdep = {
        'numpy': 'python3-numpy', 'scipy': 'python3-scipy', 'yaml': 'python3-yaml',
        'matplotlib': 'python3-matplotlib', 'h11': 'python3-h11',
        'zstandard': 'python3-zstandard', 'lz4': 'python3-lz4',
    }  # fmt: skip
    documented = {'mcap', 'mcap_ros2'}  # no rosdep key: pip, said in package.xml
    optional = {'dask', 'distributed', 'pyarrow', 'moordyn'}  # extras, named in a comment
    imported = set()
    for path in (ROOT / PKG).rglob('*.py'):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                imported |= {a.name.split('.')[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                imported.add(node.module.split('.')[0])
    third = {m for m in imported if m not in sys.stdlib_module_names and m != PKG}
    for module in sorted(third):
        if module in optional:
            assert f'import {module}' in text or f', {module}' in text, module
            continue
        if module in documented:
            assert f'import {module.split("_")[0]}' in text or module in text, module
            continue
        assert rosdep.get(module, module) in depends, module
    assert 'pip install mcap mcap-ros2-support' in text


def test_systemd_unit_command_runs_and_stops_as_systemd_stops_it(tmp_path):
    unit = configparser.ConfigParser(strict=False, interpolation=None)
    unit.optionxform = str  # type: ignore[assignment,method-assign]
    text = (ROOT / 'deploy/catenary-monitor.service').read_text()
    unit.read_string(text)
    environment = re.findall(r'^Environment=(\S+?)=(.*)$', text, re.M)
    assert 'network-online.target' in unit['Unit']['After']
    assert 'network-online.target' in unit['Unit']['Wants']
    service = unit['Service']
    assert service['Restart'] == 'on-failure' and service['KillSignal'] == 'SIGTERM'
    assert service['RestartPreventExitStatus'] == '2'
    command = shlex.split(service['ExecStart'])
    venv_exe, params_at, log_at = command[0], command.index('--params-file') + 1, None
    assert venv_exe == '/opt/catenary_monitor/.venv/bin/catenary-monitor'
    log_at = command.index('--log-dir') + 1
    # This checkout's install stands in for /opt/catenary_monitor, a test file for /etc.
    params = tmp_path / 'dock.yaml'
    params.write_text((ROOT / 'config/dock_template.yaml').read_text())
    command[0] = str(Path(sys.executable).parent / 'catenary-monitor')
    command[params_at], command[log_at] = str(params), str(tmp_path / 'log')
    env = child_env()
    for key, value in environment:
        if key.startswith('ROS_') and key != 'ROS_DOMAIN_ID':  # the test's own domain kept
            env[key] = value.replace('192.168.1.20', '127.0.0.1')
    proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)  # fmt: skip
    try:
        text = _wait_line(proc, 'static peers', 60.0)  # the start line, once running
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=int(service['TimeoutStopSec']))
    assert proc.returncode == 0, text + out
    assert 'static peers 127.0.0.1' in text + out
    assert list((tmp_path / 'log').glob('*.mcap')) and (tmp_path / 'log/metadata.yaml').exists()


def test_params_template_is_a_valid_dock_with_a_checklist():
    text = (ROOT / 'config/dock_template.yaml').read_text()
    config = config_from_params(load_params_file(ROOT / 'config/dock_template.yaml'))
    assert len(config.lines) == 4
    for word in ('CHECK', 'tension_scale', 'depth_offset', 'hook_height', 'gauge_height',
                 'measured from', 'log_max_total_size'):  # fmt: skip
        assert word in text, word
