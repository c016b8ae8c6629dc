"""What-if (core/monitor/whatif_scene.py, cli/whatif.py): the monitor core's own decisions for one
scene, as a Python function and as ``catenary-monitor whatif`` (a subprocess)."""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from replay_data import T0_NS, dock_config, generate, params_yaml, write_log

import catenary_monitor
from catenary_monitor import solve
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.events import Depth, Tension
from catenary_monitor.core.monitor.monitor_core import MonitorCore

ROOT = Path(__file__).resolve().parent.parent


def test_whatif_equals_stepping_the_core():
    config = dock_config(3)
    tensions = {'line_01': 6.0e5, 'line_02': 3.9e5, 'line_03': 4.2e5}
    scene = catenary_monitor.whatif(config, 20.85, tensions)
    core = MonitorCore(config, 0)
    core.step(Depth(1, 20.85))
    for k, line in enumerate(config.lines):
        out = core.step(Tension(2 + k, k, tensions[line.name])).outputs[0].values
        got = scene.lines[k].values
        for key, v in zip(OUTPUT_FIELDS, out):
            if key != 'level':
                assert got[key] == v or (math.isnan(got[key]) and math.isnan(v)), key
    levels = [ls.level for ls in scene.lines]
    assert levels[0] == 'ERROR' and 'anchor uplift' in scene.lines[0].message
    assert levels[1] == 'OK'


def test_anchor_distance_and_tide_rate_of_the_scene():
    config = dock_config(3)
    tensions = {'line_01': 3.9e5, 'line_02': 3.9e5, 'line_03': 3.9e5}
    rate = 0.31 / 3600.0
    scene = catenary_monitor.whatif(
        config, 20.85, tensions, anchor_distances={'line_03': 110.0}, tide_rate=rate
    )
    ref = solve(1300.0, 20.85 + 0.5, tension=3.9e5, anchor_distance=110.0)
    line3 = scene.lines[2]
    assert line3.anchor_distance == 110.0
    assert math.isclose(line3.values['anchor_margin'], ref.anchor_margin, rel_tol=1e-12)
    line1 = scene.lines[0].values
    assert math.isclose(line1['time_to_uplift'], line1['tide_margin'] / rate, rel_tol=1e-6)
    assert scene.lines[0].level == 'OK'
    no_rate = catenary_monitor.whatif(config, 20.85, tensions)
    assert math.isnan(no_rate.tide_rate)  # the trend unknown: unknown (NaN), not "never"
    assert math.isnan(no_rate.lines[0].values['time_to_uplift'])


def test_whatif_names_unknown_and_missing_lines():
    config = dock_config(2)
    with pytest.raises(ValueError, match="no tension for line 'line_02': no chain_length"):
        catenary_monitor.whatif(config, 20.0, {'line_01': 4e5})
    with pytest.raises(ValueError, match="unknown line 'line_9'"):
        catenary_monitor.whatif(
            config, 20.0, {'line_01': 4e5, 'line_02': 4e5}, anchor_distances={'line_9': 100.0}
        )


def run(*args):
    return subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli', 'whatif', *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )


@pytest.fixture
def params(tmp_path):
    return params_yaml(dock_config(3), tmp_path / 'p.yaml')


def test_cli_table_and_json(params):
    args = [
        '--params-file',
        str(params),
        '--depth',
        '20.85',
        '--tension',
        'line_01=6e5',
        '--tension',
        'line_02=3.9e5',
        '--tension',
        'line_03=4.2e5',
        '--anchor-distance',
        'line_03=118',
        '--tide-rate',
        '8.6e-5',
    ]
    table = run(*args)
    assert table.returncode == 0, table.stderr
    lines = table.stdout.splitlines()
    assert lines[0] == 'what-if at depth 20.85 m, tide +0.31 m/h'
    assert any(r.startswith('line_01') and ' ERROR ' in r for r in lines)
    assert any(r.startswith('line_01: anchor uplift') for r in lines)
    out = run(*args, '--json')
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    want = catenary_monitor.whatif(
        dock_config(3),
        20.85,
        {'line_01': 6e5, 'line_02': 3.9e5, 'line_03': 4.2e5},
        {'line_03': 118.0},
        8.6e-5,
    )
    for got, ls in zip(data['lines'], want.lines):
        assert got['level'] == ls.level and got['anchor_distance'] == ls.anchor_distance
        assert got['anchor_margin'] == ls.values['anchor_margin']
        assert got['uplift_coming'] is (ls.values['time_to_uplift'] != math.inf)


def test_cli_bad_input_is_one_line(params):
    out = run('--params-file', str(params), '--depth', '20.85', '--tension', 'line_01=4e5')
    assert out.returncode == 2 and out.stdout == ''
    assert out.stderr.strip().count('\n') == 0 and 'line line_02: no tension' in out.stderr
    bad = run('--params-file', str(params), '--depth', '20.85', '--tension', 'line_01')
    assert bad.returncode == 2 and 'expected NAME=NUMBER' in bad.stderr
    for depth in ('deep', '-3'):
        out = run('--params-file', str(params), '--depth', depth)
        assert out.returncode == 2 and 'must be a positive number' in out.stderr, out.stderr
    far = run(
        '--params-file',
        str(params),
        '--depth',
        '20',
        '--tension',
        'line_01=4e5',
        '--tension',
        'line_02=4e5',
        '--tension',
        'line_03=4e5',
        '--anchor-distance',
        'line_01=-5',
    )
    assert far.returncode == 2 and 'anchor_distance' in far.stderr, far.stderr
    assert 'Traceback' not in far.stderr
    nolog = run('--params-file', str(params), '--depth', '20', '--log', str(params.parent / 'x'))
    assert nolog.returncode == 2 and nolog.stderr.startswith('catenary-monitor whatif: --log')


def test_cli_lines_not_given_take_the_logs_newest_sample(params, tmp_path):
    config = dock_config(3)
    tensions, depth = generate(config, seconds=60.0, seed=3, dropouts=False)
    log = write_log(tmp_path / 'log.mcap', config, tensions, depth)
    out = run(
        '--params-file',
        str(params),
        '--depth',
        '20.85',
        '--log',
        str(log),
        '--tension',
        'line_02=4.1e5',
        '--json',
    )
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    got = {ls['line']: ls['tension'] for ls in data['lines']}
    assert got['line_02'] == 4.1e5
    assert got['line_01'] == float(tensions['line_01'][1][-1])
    assert got['line_03'] == float(tensions['line_03'][1][-1])
    assert np.isfinite(depth[1]).all() and T0_NS > 0


def test_a_scene_held_for_on_delay_raises_its_alarm():
    """With on_delay the scene is held that long: the uplift ERROR is raised, as live."""
    config = dock_config(3, on_delay=10.0)
    scene = catenary_monitor.whatif(
        config, 20.85, {'line_01': 6e5, 'line_02': 3.9e5, 'line_03': 4.3e5}, tide_rate=8.6e-5
    )
    assert [ls.level for ls in scene.lines] == ['ERROR', 'OK', 'OK']
    assert scene.lines[0].values['time_to_uplift'] == 0.0
    assert 0 < scene.lines[2].values['time_to_uplift'] < scene.lines[1].values['time_to_uplift']


def test_cli_on_the_shipped_dock():
    """The shipped params file (dock model, chain lengths): every line, implied distances."""
    names = [f'line_{k:02d}' for k in range(1, 13)]
    args = [a for n in names for a in ('--tension', f'{n}=3.9e5')]
    out = run('--params-file', 'config/floating_dock.yaml', '--depth', '20.85', *args, '--json')
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert [ls['line'] for ls in data['lines']] == names
    assert all(
        abs(ls['implied_anchor_distance'] - ls['anchor_distance']) < 1.0 for ls in data['lines']
    )


def test_lines_not_given_hang_as_installed():
    """A line without a tension but with a chain_length hangs at its anchor distance in still
    water: its tension is problem 5's (the catenary's chain length equals the one paid out),
    and the command says where each tension came from."""
    out = run(
        '--params-file',
        'config/floating_dock.yaml',
        '--depth',
        '20.85',
        '--tension',
        'line_11=1.6e6',
        '--json',
    )
    assert out.returncode == 0, out.stderr
    lines = {ls['line']: ls for ls in json.loads(out.stdout)['lines']}
    assert lines['line_11']['tension_source'] == 'given'
    assert lines['line_11']['tension'] == 1.6e6
    hung = lines['line_01']
    assert hung['tension_source'] == 'hanging'
    # Independent check: the installed chain's length from the catenary at that tension.
    r = solve(weight=1300.0, depth=20.85, tension=hung['tension'], anchor_distance=120.0)
    length = r.suspended_length + (120.0 - r.min_anchor_distance)
    assert math.isclose(length, 122.6247, rel_tol=1e-9)
    table = run(
        '--params-file',
        'config/floating_dock.yaml',
        '--depth',
        '20.85',
        '--tension',
        'line_11=1.6e6',
    )
    assert table.returncode == 0 and 'hanging' in table.stdout and 'given' in table.stdout


def test_a_chain_that_cannot_hang_says_why():
    """The shipped dock has chain lengths: a line that cannot hang as installed (too deep, or
    its anchor moved beyond reach) says its chain is taut, not that it has no chain_length."""
    for extra in (['--depth', '1000'], ['--depth', '20.85', '--anchor-distance', 'line_01=500']):
        out = run('--params-file', 'config/floating_dock.yaml', *extra)
        assert out.returncode == 2 and out.stdout == '', out.stdout
        assert 'line line_01: no tension given' in out.stderr and 'taut' in out.stderr
        assert 'no chain_length' not in out.stderr and out.stderr.count('\n') == 1
    out = run(
        '--params-file',
        'config/floating_dock.yaml',
        '--depth',
        '20.85',
        '--anchor-distance',
        'nosuch=50',
    )
    assert out.returncode == 2 and "unknown line 'nosuch'" in out.stderr, out.stderr


def test_a_lifted_anchor_is_said_once():
    """While the uplift ERROR says the anchor is lifted, the time-to-uplift warning adds no
    second sentence; lifted within the allowed uplift, it says so instead of '0 min'."""
    import dataclasses

    config = dock_config(3)
    tensions = {'line_01': 6e5, 'line_02': 3.9e5, 'line_03': 4.3e5}
    lifted = catenary_monitor.whatif(config, 20.85, tensions, tide_rate=8.6e-5).lines[0]
    assert lifted.level == 'ERROR' and lifted.values['time_to_uplift'] == 0.0
    assert 'anchor uplift' in lifted.message and 'time to uplift' not in lifted.message
    allowed = dataclasses.replace(config.lines[0], allowed_uplift=5e5)
    config = dataclasses.replace(config, lines=(allowed, *config.lines[1:]))
    within = catenary_monitor.whatif(config, 20.85, tensions, tide_rate=8.6e-5).lines[0]
    assert within.level == 'WARN', within.message
    assert 'anchor off the seabed (uplift' in within.message
    assert 'within the allowed 500.0 kN' in within.message
