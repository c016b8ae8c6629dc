"""``catenary-monitor equilibrium`` and ``envelope``: contract keys, tables, exit statuses."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from dock_data import DOCK_YAML

from catenary_monitor.cli.main import main
from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.equilibrium import solve_equilibrium
from catenary_monitor.core.body.loads import environmental_load
from catenary_monitor.core.config.parameters import config_from_params, load_params_file

ROOT = Path(__file__).resolve().parents[1]
LINE_KEYS = {'line', 'top_tension', 'horizontal_tension', 'uplift_force', 'anchor_margin'}


def run(capsys, *args):
    code = main([*map(str, args)])
    return code, capsys.readouterr()


def test_equilibrium_json_has_the_contract_keys_and_the_core_values(capsys):
    code, out = run(
        capsys,
        'equilibrium',
        '--params-file',
        DOCK_YAML,
        '--depth',
        20.85,
        '--load',
        '0,-1.5e6,2e6',
        '--json',
    )
    assert code == 0, out.err
    data = json.loads(out.out)
    assert {'offset_x', 'offset_y', 'yaw_deg', 'lines'} <= set(data)
    assert len(data['lines']) == 12
    for row in data['lines']:
        assert LINE_KEYS | {'grounded_length', 'safety_factor', 'load_margin'} <= set(row)
    model = DockModel.from_config(config_from_params(load_params_file(DOCK_YAML)))
    eq = solve_equilibrium(model, 20.85, np.array([0.0, -1.5e6, 2e6]))
    assert data['offset_y'] == pytest.approx(eq.offset_y, rel=1e-12)
    assert data['yaw_deg'] == pytest.approx(eq.yaw_deg, rel=1e-9)
    tensions = [row['top_tension'] for row in data['lines']]
    np.testing.assert_allclose(tensions, eq.lines.statics.top_tension, rtol=1e-12)
    assert data['status'] == 'converged'


def test_equilibrium_from_wind_current_and_waves_prints_a_table(capsys):
    code, out = run(
        capsys,
        'equilibrium',
        '--params-file',
        DOCK_YAML,
        '--depth',
        20.85,
        '--wind',
        25,
        '--wind-from',
        270,
        '--current',
        1.5,
        '--current-from',
        250,
        '--hs',
        1.5,
    )
    assert code == 0, out.err
    text = out.out
    assert 'from wind 25 m/s from 270 deg' in text and 'equilibrium found' in text
    assert 'line_12' in text and 'uplift kN' in text and 'grounded m' in text
    config = config_from_params(load_params_file(DOCK_YAML))
    load = environmental_load(config.dock, 25.0, 270.0, 1.5, 250.0, 1.5).total
    assert f'Fy {load[1] / 1e3:.1f} kN' in text


@pytest.mark.parametrize(
    'args, says',
    [
        (['--load', '1,2'], '--load must be 3 finite numbers'),
        (['--wind', '20'], 'give --load FX,FY,MZ or --wind V --wind-from DEG'),
        (['--load', '0,0,0', '--wind', '3', '--wind-from', '0'], 'not both'),
        (['--wind', '20', '--wind-from', '0', '--current', '1'], '--current needs'),
        (['--wind', '-3', '--wind-from', '0'], 'wind must be a finite number >= 0'),
    ],
)
def test_equilibrium_bad_input_is_one_line_exit_2(capsys, args, says):
    code, out = run(capsys, 'equilibrium', '--params-file', DOCK_YAML, '--depth', 20.85, *args)
    assert code == 2 and out.out == ''
    assert says in out.err and len(out.err.strip().splitlines()) == 1


def test_a_params_file_without_the_dock_is_refused_in_one_line(tmp_path, capsys):
    plain = tmp_path / 'plain.yaml'
    plain.write_text(
        'catenary_monitor:\n  ros__parameters:\n    lines: [a]\n'
        '    a:\n      weight: 1300.0\n      anchor_distance: 120.0\n      mbl: 4.8e6\n'
    )
    code, out = run(capsys, 'envelope', '--params-file', plain, '--depth', 20.85)
    assert code == 2 and 'hook_x, hook_y, heading and chain_length' in out.err
    assert len(out.err.strip().splitlines()) == 1
    code, out = run(
        capsys, 'equilibrium', '--params-file', DOCK_YAML, '--depth', -1, '--load', '0,0,0'
    )
    assert code == 2 and '--depth must be > 0' in out.err


def test_no_equilibrium_exits_3(tmp_path, capsys):
    one = tmp_path / 'one.yaml'
    one.write_text(
        'catenary_monitor:\n  ros__parameters:\n    lines: [a]\n'
        '    a:\n      weight: 1300.0\n      anchor_distance: 120.0\n      mbl: 4.8e6\n'
        '      hook_x: 0.0\n      hook_y: 0.0\n      heading: 0.0\n      chain_length: 122.6\n'
    )
    code, out = run(
        capsys,
        'equilibrium',
        '--params-file',
        one,
        '--depth',
        20.85,
        '--load',
        '1e5,0,0',
        '--json',
    )
    assert code == 3 and json.loads(out.out)['status'] == 'no_equilibrium'
    assert 'drifts' in out.err


def test_envelope_table_json_and_chart(tmp_path, capsys):
    png = tmp_path / 'env.png'
    code, out = run(
        capsys,
        'envelope',
        '--params-file',
        DOCK_YAML,
        '--depth',
        '20.85,21.85',
        '--step',
        90,
        '--json',
        '--plot',
        png,
    )
    assert code == 0, out.err
    data = json.loads(out.out)
    assert [d['depth'] for d in data['depths']] == [20.85, 21.85]
    rows = data['depths'][0]['directions']
    assert [r['direction_deg'] for r in rows] == [0.0, 90.0, 180.0, 270.0]
    for r in rows:
        assert r['force'] > 0 and r['force_line'].startswith('line_') and r['wind'] > 0
    high = data['depths'][1]['directions']
    assert all(h['wind'] < m['wind'] for h, m in zip(high, rows))
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    code, out = run(capsys, 'envelope', '--params-file', DOCK_YAML, '--depth', 20.85, '--step', 90)
    assert code == 0 and 'weakest:' in out.out and 'wind m/s' in out.out


def test_equilibrium_beyond_the_breaking_load_says_so(capsys):
    """1 GN of surge: the chains find an equilibrium on paper, far above their MBL."""
    code, out = run(capsys, 'equilibrium', '--params-file', DOCK_YAML, '--depth', 20.85,
                    '--load', '1e9,0,0')  # fmt: skip
    assert code == 0, out.err
    assert 'ABOVE ITS BREAKING LOAD' in out.out
    code, out = run(capsys, 'equilibrium', '--params-file', DOCK_YAML, '--depth', 20.85,
                    '--load', '1e5,0,0')  # fmt: skip
    assert code == 0 and 'BREAKING' not in out.out


def test_envelope_where_there_is_none_says_why_and_exits_3(capsys):
    """At 40 m the chains cannot reach their anchors (taut): no equilibrium even unloaded,
    so no direction has an envelope; the table says it in words, stderr in one line."""
    code, out = run(capsys, 'envelope', '--params-file', DOCK_YAML, '--depth', 40, '--step', 90,
                    '--quiet')  # fmt: skip
    assert code == 3, out.err
    assert 'line_failed' not in out.out and 'no equilibrium' in out.out
    assert 'no envelope at this depth' in out.out
    assert len(out.err.strip().splitlines()) == 1 and 'depth 40 m' in out.err


def test_the_commands_run_as_a_user_runs_them():
    """The console script's module, in its own process: table out, nothing on stderr."""
    proc = subprocess.run(
        [
            sys.executable,
            '-m',
            'catenary_monitor',
            'equilibrium',
            '--params-file',
            str(DOCK_YAML),
            '--depth',
            '20.85',
            '--wind',
            '20',
            '--wind-from',
            '300',
        ],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        env={'PYTHONPATH': str(ROOT), 'PATH': '/usr/bin:/bin'},
    )
    assert proc.returncode == 0, proc.stderr
    assert 'equilibrium found' in proc.stdout and proc.stderr == ''
