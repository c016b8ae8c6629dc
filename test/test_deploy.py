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
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import sysconfig
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from ros_harness import child_env
from systemd_units import ETC, HARBOUR_UNIT, LOGS, STATE, UNITS, VENV, read_unit
from systemd_units import command as units_command

from catenary_monitor.cli.run import NO_RESTART

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
                 'config/dock_template.yaml', 'deploy/catenary-monitor.service',
                 'deploy/catenary-monitor-console.service', f'deploy/{HARBOUR_UNIT}',
                 'docs/deploy.md'):  # fmt: skip
        assert (share / name).is_file(), name
    # the package data: the pages' shared stream reader, the DDS announcement profile
    for name in ('console/static/server_link.js', 'ros/fastdds_announce.xml'):
        assert (site / PKG / name).is_file(), name
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
    assert args['params_file'] is None  # required: no demo dock by default
    args['params_file'] = str(share / 'config/dock_template.yaml')
    nodes = list(root.iter('node'))
    assert [n.get('exec') for n in nodes] == ['catenary-monitor', 'catenary-monitor']
    for node in nodes:
        assert node.get('pkg') == PKG
        assert (prefix / 'lib' / PKG / node.get('exec')).is_file()
        assert node.get('respawn') is None  # launch's respawn restarts after any exit
    from catenary_monitor.cli.main import build_parser

    # The monitor restarts as the unit does: after a failure, RestartSec later, not after 2.
    unit = read_unit('catenary-monitor.service')[0]['Service']
    monitor = shlex.split(_substitute(nodes[0].get('args'), args, share))
    parsed = build_parser().parse_args([*monitor, '--ros-args', '-r', '__node:=catenary_monitor'])
    assert parsed.func.__name__ == 'cmd_run' and parsed.params_file == args['params_file']
    assert parsed.restart_on_failure == float(unit['RestartSec'])
    assert unit['RestartPreventExitStatus'] == '2' and NO_RESTART == (0, 2)
    config_from_params(load_params_file(parsed.params_file))
    # The console's command line as launch builds it is one its parser takes.
    console = shlex.split(_substitute(nodes[1].get('args'), args, share))
    assert console[0] == 'console'
    parsed = build_parser().parse_args([*console, '--ros-args', '-r', '__ns:=/'])
    assert parsed.params_file == args['params_file'] and parsed.bind == '127.0.0.1'


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
    unit, environment = read_unit('catenary-monitor.service')
    assert 'network-online.target' in unit['Unit']['After']
    assert 'network-online.target' in unit['Unit']['Wants']
    service = unit['Service']
    command = shlex.split(service['ExecStart'])
    assert command[0] == '/opt/catenary_monitor/.venv/bin/catenary-monitor'
    assert command[command.index('--log-dir') + 1] == LOGS
    # This checkout's install stands in for /opt/catenary_monitor, a test file for /etc.
    params = tmp_path / 'dock.yaml'
    params.write_text((ROOT / 'config/dock_template.yaml').read_text())
    places = {VENV: str(Path(sys.executable).parent.parent), f'{ETC}/dock.yaml': str(params),
              STATE: str(tmp_path / 'state'), LOGS: str(tmp_path / 'log')}  # fmt: skip
    command, unit_env = units_command('catenary-monitor.service', places)
    command[0] = str(Path(sys.executable).parent / 'catenary-monitor')
    env = child_env()
    for key, value in unit_env.items():
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
    assert list((tmp_path / 'state/log').iterdir())  # rcl's own log, in the state directory


def test_the_two_units_share_user_state_and_restart_policy(install):
    prefix, _ = install
    (monitor, monitor_env), (console, console_env) = (read_unit(u) for u in UNITS)
    for unit, env in ((monitor, monitor_env), (console, console_env)):
        service = unit['Service']
        assert (service['User'], service['Group']) == ('catenary', 'catenary')
        assert service['StateDirectory'] == 'catenary_monitor'
        assert env['ROS_HOME'] == STATE and env['ROS_LOG_DIR'].startswith(STATE + '/')
        assert (service['Restart'], service['RestartSec']) == ('on-failure', '5')
        assert service['RestartPreventExitStatus'] == '2' and service['KillSignal'] == 'SIGTERM'
        doc = unit['Unit']['Documentation']
        assert doc.startswith(f'file://{VENV}/')
        assert (prefix / doc[len(f'file://{VENV}/'):]).is_file(), doc  # what pip installs
    assert monitor['Service']['LogsDirectory'] == 'catenary_monitor'
    assert monitor_env['ROS_DOMAIN_ID'] == console_env['ROS_DOMAIN_ID']
    assert 'catenary-monitor.service' in console['Unit']['After']
    console_cmd = shlex.split(console['Service']['ExecStart'])
    assert console_cmd[1] == 'console' and '--token-file' in console_cmd


@pytest.mark.skipif(shutil.which('systemd-analyze') is None, reason='no systemd-analyze')
def test_systemd_analyze_verifies_the_units(tmp_path):
    """``systemd-analyze verify`` on each unit as shipped (the dock's two, the harbour PC's),
    but for ExecStart's program (it must exist): this checkout's venv's."""
    exe = str(Path(sys.executable).parent / 'catenary-monitor')
    units = (*UNITS, HARBOUR_UNIT)
    assert sorted(units) == sorted(p.name for p in (ROOT / 'deploy').glob('*.service'))
    for name in units:
        text = (ROOT / 'deploy' / name).read_text()
        (tmp_path / name).write_text(text.replace(f'{VENV}/bin/catenary-monitor', exe))
    done = subprocess.run(['systemd-analyze', 'verify', *(str(tmp_path / n) for n in units)],
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert (done.returncode, done.stdout + done.stderr) == (0, '')


def test_the_harbour_unit_runs_read_only_and_stops_as_systemd_stops_it(install, tmp_path):
    """The harbour PC's unit: the dock units' user, state and restart policy, no monitor to
    wait for, no domain of its own; its command, on this checkout's install with the docks in
    the test's domain and the static peers on this host, serves read-only and exits 0 on
    SIGTERM."""
    prefix, _ = install
    unit, environment = read_unit(HARBOUR_UNIT)
    service = unit['Service']
    assert (service['User'], service['Group']) == ('catenary', 'catenary')
    assert service['StateDirectory'] == 'catenary_monitor' and 'LogsDirectory' not in service
    assert environment['ROS_HOME'] == STATE and environment['ROS_LOG_DIR'].startswith(STATE)
    assert (service['Restart'], service['RestartSec']) == ('on-failure', '5')
    assert service['RestartPreventExitStatus'] == '2' and service['KillSignal'] == 'SIGTERM'
    assert 'ROS_DOMAIN_ID' not in environment  # each dock's domain is its --dock's
    assert unit['Unit']['After'] == 'network-online.target'
    doc = unit['Unit']['Documentation']
    assert (prefix / doc[len(f'file://{VENV}/'):]).is_file(), doc  # what pip installs
    places = {VENV: str(Path(sys.executable).parent.parent), STATE: str(tmp_path / 'state')}
    command, unit_env = units_command(HARBOUR_UNIT, places)
    assert command[1] == 'harbour' and '--token-file' not in command
    domain = os.environ['ROS_DOMAIN_ID']
    command = [domain.join(re.split(r'(?<==)\d+$', a)) if a.count('=') == 1 and
               a.split('=')[1].isdigit() else a for a in command]  # fmt: skip
    command[command.index('--port') + 1] = '0'  # any free port
    command[command.index('--bind') + 1] = '127.0.0.1'
    env = child_env()
    for key, value in unit_env.items():
        if key.startswith('ROS_'):
            env[key] = re.sub(r'10\.0\.\d+\.5', '127.0.0.1', value)
    proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)  # fmt: skip
    try:
        text = _wait_line(proc, 'harbour: http', 90.0)
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=int(service['TimeoutStopSec']))
    assert proc.returncode == 0, text + out
    assert f'3 docks in domains {domain}, {domain}, {domain}; read-only' in text
    assert list((tmp_path / 'state/log').iterdir())  # rcl's own log, in the state directory


def test_params_template_is_a_valid_dock_with_a_checklist():
    text = (ROOT / 'config/dock_template.yaml').read_text()
    config = config_from_params(load_params_file(ROOT / 'config/dock_template.yaml'))
    assert len(config.lines) == 4
    for word in ('CHECK', 'tension_scale', 'depth_offset', 'hook_height', 'gauge_height',
                 'measured from', 'log_max_total_size'):  # fmt: skip
        assert word in text, word


def _counting_child(tmp_path, *statuses: str) -> list[str]:
    """A child exiting with the next of ``statuses`` at each start (``kill``: SIGKILL)."""
    count = tmp_path / 'starts'
    script = (
        'import os, pathlib, signal, sys\n'
        f'p = pathlib.Path({str(count)!r})\n'
        'n = len(p.read_text()) if p.exists() else 0\n'
        "p.write_text('x' * (n + 1))\n"
        'status = sys.argv[n + 1]\n'
        "if status == 'kill':\n"
        '    os.kill(os.getpid(), signal.SIGKILL)\n'
        'sys.exit(int(status))\n'
    )
    return [sys.executable, '-c', script, *statuses]


@pytest.mark.parametrize(
    'statuses, starts, status',
    [
        (('1', 'kill', '0'), 3, 0),  # a failure and a crash restarted, then a clean stop
        (('1', '2', '0'), 2, 2),  # a bad params file: not started again
        (('0',), 1, 0),
    ],
)
def test_restart_on_failure_is_the_units_policy(tmp_path, capfd, statuses, starts, status):
    from catenary_monitor.cli.run import supervise

    assert supervise(_counting_child(tmp_path, *statuses), 0.05) == status
    assert len((tmp_path / 'starts').read_text()) == starts
    assert capfd.readouterr().err.count('starting it again in 0.05 s') == starts - 1


def test_run_restart_on_failure_stops_on_a_bad_parameter_and_on_sigterm(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text((ROOT / 'config/dock_template.yaml').read_text().replace(
        'weight: 1300.0  # CHECK N/m submerged', 'weight: -1300.0'))  # fmt: skip
    exe = str(Path(sys.executable).parent / 'catenary-monitor')
    log = ['--log-dir', str(tmp_path / 'log')]
    done = subprocess.run([exe, 'run', '--params-file', str(bad), *log, '--restart-on-failure',
                           '0.1'], capture_output=True, text=True, env=child_env(),
                          timeout=120)  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert 'starting it again' not in done.stderr and 'weight' in done.stderr
    good = ROOT / 'config/dock_template.yaml'
    proc = subprocess.Popen([exe, 'run', '--params-file', str(good), *log,
                             '--restart-on-failure', '5'], env=child_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)  # fmt: skip
    try:
        text = _wait_line(proc, 'monitoring 4 lines', 60.0)
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=20)
    assert proc.returncode == 0, text + out
    assert 'starting it again' not in out and 'MCAP log closed' in text + out


@pytest.mark.slow
def test_real_colcon_build_puts_the_commands_in_lib(tmp_path):
    """colcon itself (colcon-common-extensions in a venv of its own, with Jazzy's setuptools
    68.1.2), plain and ``--symlink-install``: the commands in ``lib/catenary_monitor`` (colcon
    reads setup.cfg's script directory; pip, through pyproject.toml, never does), none in
    ``bin``, and ``ros2 run``'s command runs from there."""
    tools = tmp_path / 'colcon'
    subprocess.run([sys.executable, '-m', 'venv', str(tools)], check=True, timeout=120)
    done = subprocess.run(
        [str(tools / 'bin/pip'), 'install', '-q', 'colcon-common-extensions',
         'setuptools==68.1.2'], capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    src = tmp_path / 'ws/src/catenary_monitor'
    files = subprocess.run(
        ['git', 'ls-files', '-z'], cwd=ROOT, capture_output=True, check=True
    ).stdout.split(b'\0')
    for name in filter(None, files):
        if (ROOT / name.decode()).is_file():
            (src / name.decode()).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name.decode(), src / name.decode())
    env = dict(os.environ, CATENARY_MONITOR_NO_EXTENSIONS='1')
    env.pop('PYTHONPATH', None)
    for flags in ([], ['--symlink-install']):
        ws = tmp_path / 'ws'
        for part in ('build', 'install', 'log'):
            shutil.rmtree(ws / part, ignore_errors=True)
        done = subprocess.run([str(tools / 'bin/colcon'), 'build', *flags], cwd=ws, env=env,
                              capture_output=True, text=True, timeout=600)  # fmt: skip
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
        prefix = ws / 'install' / PKG
        lib = prefix / 'lib' / PKG
        assert {p.name for p in lib.iterdir()} >= {'catenary-monitor', 'monitor', 'dock_simulator'}
        assert not (prefix / 'bin').exists(), flags
        site = next(prefix.glob('lib/python3*/site-packages'))
        # colcon's Python runs the command (its shebang); numpy and the rest: this suite's
        deps = sysconfig.get_paths()['purelib']
        run_env = dict(env, PYTHONPATH=os.pathsep.join([str(site), str(ws / 'build' / PKG), deps]))
        done = subprocess.run(
            [str(lib / 'catenary-monitor'), 'solve', '--weight', '1300', '--depth', '20.85',
             '--tension', '1623.5e3', '--anchor-distance', '121.06'],
            capture_output=True, text=True, env=run_env, timeout=120,
        )  # fmt: skip
        assert done.returncode == 0 and 'ANCHOR LIFTED' in done.stdout, (flags, done.stderr)
