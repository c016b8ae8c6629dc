"""The package as it installs on a machine without a C compiler: no accelerator is built, the
numpy paths answer, and the tests of those paths pass against that install.

The source is copied (tracked files only: no in-place build comes along), installed with
``CC=/bin/false`` into a folder of its own, and the tests run with that folder first on the
path and ``CATENARY_MONITOR_NO_EXTENSIONS=1`` (the conftest builds nothing); the tests that
compare the C code with numpy (marker ``c_extension``) are left out.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: The tests of the numpy paths: solve() without the kernel, the twin without its loops, the
#: reader without its scan, and the streamed replay over all of them (test_batch_steps.py is
#: test_batch.py's numpy rerun: nothing new here).
NUMPY_PATH_TESTS = (
    'test_solve_api.py',
    'test_seed_tables.py',
    'test_kernels.py',
    'test_batch.py',
    'test_sensor.py',
    'test_tide_trend.py',
    'test_mcap_scan.py',
    'test_fatigue.py',
    'test_replay_stream.py',
)
#: Left out here (about 4 minutes of the 7 on the numpy path): long scenes that test the
#: forecast's or the sensor check's arithmetic, not a path the compiler changes; each of their
#: modules keeps a core-against-twin test in this run, and they all run in the main suite.
LEFT_OUT = (
    'exact_crossing',
    'test_over_mbl',
    'test_a_still_dock_is_not_a_stuck_sensor',
    'test_slack_keeps_the_impossible_input_status',
    'test_a_line_that_falls_with_the_others',
    'test_spike',
    'test_a_normal_record_raises_nothing',
    'test_depth_sensor_states',
    'test_elastic_line_and_depth_loss',
    'test_run_log_steps_clock_and_intake_events',
)


@pytest.fixture(scope='module')
def installed(tmp_path_factory) -> Path:
    src = tmp_path_factory.mktemp('src')
    files = subprocess.run(
        ['git', 'ls-files', '-z'], cwd=ROOT, capture_output=True, check=True
    ).stdout.split(b'\0')
    for name in filter(None, files):
        target = src / name.decode()
        if (ROOT / name.decode()).is_file():
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name.decode(), target)
    where = tmp_path_factory.mktemp('site')
    env = dict(os.environ, CC='/bin/false', CXX='/bin/false')
    done = subprocess.run(
        [sys.executable, '-m', 'pip', 'install', '-q', '--no-deps', '--target', str(where), '.'],
        cwd=src,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return where


def test_it_installs_without_a_compiler_and_runs_on_numpy(installed):
    assert not list(installed.rglob('*.so')), 'an accelerator was built without a compiler'
    code = (
        'import catenary_monitor as cm\n'
        'from catenary_monitor.core.physics import fused_kernel\n'
        'from catenary_monitor.core.twin import schedule\n'
        'from catenary_monitor.core.rules import fatigue, wave_window\n'
        'from catenary_monitor.io import mcap_scan\n'
        'print(cm.__file__)\n'
        'print(fused_kernel.AVAILABLE, schedule._loops, fatigue._fatigue_loop, mcap_scan._scan,'
        ' wave_window._wave_loop)\n'
        'print(cm.solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06).uplift_force)\n'
    )
    out = subprocess.run(
        [sys.executable, '-c', code], cwd=installed, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    where, loaded, uplift = out.stdout.splitlines()
    assert Path(where).resolve().is_relative_to(installed.resolve())
    assert loaded == 'False None None None None'
    assert float(uplift) == pytest.approx(193267.5, rel=1e-5)  # the seed's Table 4 answer


@pytest.mark.timeout(900)  # a test session of its own: 2-3 minutes on a quiet machine
def test_the_numpy_path_tests_pass_on_that_install(installed):
    env = dict(os.environ, CATENARY_MONITOR_NO_EXTENSIONS='1')
    done = subprocess.run(
        [
            sys.executable,
            '-m',
            'pytest',
            '-q',
            '-p',
            'no:cacheprovider',
            '-c',
            str(ROOT / 'pytest.ini'),
            '-m',
            'not c_extension',
            '-k',
            ' and '.join(f'not {name}' for name in LEFT_OUT),
            *(str(ROOT / 'test' / name) for name in NUMPY_PATH_TESTS),
        ],
        cwd=installed,
        env=env,
        capture_output=True,
        text=True,
        timeout=800,
    )
    tail = done.stdout[-3000:]
    assert done.returncode == 0, tail
    assert ' passed' in tail and 'failed' not in tail
