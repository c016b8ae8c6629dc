"""Every numeric option of every catenary-monitor sub-command reads a negative number in any
float syntax as its value (argparse alone takes only ``-5`` and ``-.5``)."""

import json
from pathlib import Path

import pytest

from catenary_monitor.cli.main import NEGATIVE_VALUE, build_parser, main

ROOT = Path(__file__).resolve().parents[1]
SOLVE = ['solve', '--weight', '1300', '--depth', '20.85']


def run(capsys, *args):
    try:
        code = main([*map(str, args)])
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    return code, capsys.readouterr()


@pytest.mark.parametrize('text', ['-1e6', '-.5e3', '-5', '-1E+06', '-2.5e-3', '-1_000.5', '-7.'])
def test_solve_reads_a_negative_tension_as_its_value(capsys, text):
    code, out = run(capsys, *SOLVE, '--tension', text)
    assert code == 2 and out.out == ''
    lines = out.err.strip().splitlines()
    assert len(lines) == 1, out.err
    assert 'hook tension must exceed weight x depth' in lines[0]
    assert f'T = {float(text):g} N' in lines[0]


@pytest.mark.parametrize(
    'option, says',
    [
        ('--anchor-distance', 'anchor distance must be > 0 m'),
        ('--mbl', 'minimum breaking load must be > 0 N'),
    ],
)
def test_solve_negative_distance_and_mbl_get_their_rule(capsys, option, says):
    code, out = run(capsys, *SOLVE, '--tension', '1623.5e3', option, '-1.2e2')
    assert code == 2 and out.err.strip().endswith(says), out.err


def test_solve_negative_infinity_is_an_input_not_an_option(capsys):
    code, out = run(capsys, *SOLVE, '--tension', '-inf')
    assert code == 2 and 'an input is NaN or infinite' in out.err


def test_an_unknown_option_is_still_an_option(capsys):
    code, out = run(capsys, *SOLVE, '--tension', '1e6', '-x')
    assert code == 2 and 'unrecognized arguments: -x' in out.err


def test_equilibrium_reads_a_negative_load_list_and_wind_direction(capsys):
    params = ROOT / 'config' / 'floating_dock.yaml'
    code, out = run(
        capsys, 'equilibrium', '--params-file', params, '--depth', '20.85',
        '--load', '-1e5,0,-2.5E4', '--json',
    )
    assert code == 0, out.err
    got = json.loads(out.out)
    assert got['load_x'] == -1e5 and got['load_mz'] == -2.5e4
    code, out = run(
        capsys, 'equilibrium', '--params-file', params, '--depth', '20.85',
        '--wind', '30', '--wind-from', '-9e1',
    )
    assert code == 0 and 'from -90 deg' in out.out, out.err


def test_every_sub_command_parser_reads_negative_numbers():
    """Every parser under catenary-monitor (nested ones too) uses the matcher."""
    parser = build_parser()
    seen = 0
    stack = [parser]
    while stack:
        p = stack.pop()
        assert p._negative_number_matcher is NEGATIVE_VALUE, p.prog
        seen += 1
        for action in p._actions:
            if hasattr(action, 'choices') and isinstance(action.choices, dict):
                stack.extend(action.choices.values())
    assert seen > 10


@pytest.mark.parametrize('text', ['-1e6', '-.5e3', '-5', '-inf', '-1e5,0,2e6', '-1, -2'])
def test_negative_values(text):
    assert NEGATIVE_VALUE.match(text)


@pytest.mark.parametrize('text', ['-x', '--tension', '-1e', '-e5', '-1e5,x', '-'])
def test_options_stay_options(text):
    assert not NEGATIVE_VALUE.match(text)


def test_a_closed_pipe_ends_the_command_quietly():
    """`catenary-monitor paper | head -0`: the reader is gone before the first write; the
    command ends by SIGPIPE, as Unix tools do, with no traceback."""
    import os
    import subprocess
    import sys

    read, write = os.pipe()
    os.close(read)  # no reader: every write fails, deterministically
    try:
        p = subprocess.run(
            [sys.executable, '-m', 'catenary_monitor.cli.main', 'paper'],
            stdout=write, stderr=subprocess.PIPE, text=True, timeout=120,
        )
    finally:
        os.close(write)
    assert 'Traceback' not in p.stderr and p.stderr == '', p.stderr
    assert p.returncode != 0
