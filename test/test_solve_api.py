"""The solve() contract: shapes, statuses, call errors, scalar == vectorized, no rclpy in core."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from catenary_monitor import ALL_KEYS, STATUS_MESSAGES, Status, solve
from catenary_monitor.core.physics import fused_kernel

W, H, T, X = 1300.0, 20.85, 1623.5e3, 121.06


@pytest.mark.parametrize('shape', [(), (7,), (3, 4), (3, 2, 2)])
def test_vectorized_equals_scalar_loop(shape):
    rng = np.random.default_rng(sum(shape) + 1)
    t = rng.uniform(0.3e6, 3e6, shape)
    h = rng.uniform(15.0, 25.0, shape)
    x = rng.uniform(60.0, 300.0, shape)
    r = solve(W, h, tension=t, anchor_distance=x, mbl=6.5e6)
    for key in r.keys:
        assert np.shape(getattr(r, key)) == shape
    flat = {k: np.ravel(getattr(r, k)) for k in r.keys}
    for i, (ti, hi, xi) in enumerate(zip(np.ravel(t), np.ravel(h), np.ravel(x))):
        s = solve(W, float(hi), tension=float(ti), anchor_distance=float(xi), mbl=6.5e6)
        for key in r.keys:
            np.testing.assert_allclose(
                flat[key][i], getattr(s, key), rtol=1e-13, atol=1e-9, err_msg=key
            )


def test_every_status_in_one_call():
    """One array call yields every input status; bad elements never spoil the good ones."""
    cases = [  # (weight, depth, tension, distance, mbl, expected status)
        (W, H, T, X, 6e6, Status.OK),
        (np.nan, H, T, X, 6e6, Status.NON_FINITE),
        (-1.0, H, T, X, 6e6, Status.WEIGHT),
        (W, 0.0, T, X, 6e6, Status.DEPTH),
        (W, H, W * H, X, 6e6, Status.TENSION),
        (W, H, T, -5.0, 6e6, Status.DISTANCE),
        (W, H, T, X, 0.0, Status.MBL),
        (W, H, np.inf, X, 6e6, Status.NON_FINITE),
    ]
    cols = [np.array(c) for c in zip(*cases)]
    r = solve(cols[0], cols[1], tension=cols[2], anchor_distance=cols[3], mbl=cols[4])
    np.testing.assert_array_equal(r.status, cols[5].astype(int))
    good = r.status == 0
    for key in r.keys:
        v = getattr(r, key)
        assert np.isfinite(v[good]).all() and np.isnan(v[~good]).all(), key
    single = solve(W, H, tension=T, anchor_distance=X, mbl=6e6)
    for key in r.keys:
        assert getattr(r, key)[0] == pytest.approx(getattr(single, key), rel=1e-13)
    assert list(r.message) == [STATUS_MESSAGES[int(c)] for c in cols[5]]


def test_chain_length_statuses():
    r = solve(25.0, 15.0, chain_length=[20.0, 10.0, 30.0, 18.7], anchor_distance=11.0)
    assert list(r.status) == [Status.OK, Status.CHAIN_TOO_SHORT, Status.CHAIN_SLACK, Status.OK]
    assert r.uplift_force[0] == 0 and r.grounded_length[0] > 0
    # 18.7 m is longer than the straight line (18.6 m) but too short to lie on the seabed.
    assert r.uplift_force[3] > 0 and r.grounded_length[3] == 0 and r.anchor_margin[3] < 0


def test_scalar_result_types_and_keys():
    r = solve(W, H, tension=T)
    assert isinstance(r.status, int) and isinstance(r.min_anchor_distance, float)
    assert r.keys == (
        'horizontal_tension',
        'top_tension',
        'min_anchor_distance',
        'suspended_length',
        'top_angle_deg',
        'anchor_angle_deg',
        'uplift_force',
    )
    assert np.isnan(r.anchor_margin)  # does not apply without a distance
    full = solve(W, H, tension=T, anchor_distance=X, mbl=6e6)
    assert set(full.keys) == set(ALL_KEYS) - {'grounded_length'}
    assert set(solve(25.0, 15.0, chain_length=20.0, anchor_distance=11.0).keys) >= {
        'grounded_length'
    }


@pytest.mark.parametrize(
    'kwargs,match',
    [
        (dict(), 'exactly one'),
        (dict(tension=T, horizontal=1e6), 'exactly one'),
        (dict(chain_length=200.0), 'needs anchor_distance'),
    ],
)
def test_call_mistakes_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        solve(W, H, **kwargs)


def test_margins_consistent_with_their_definitions():
    """At the critical tension / depth the anchor is exactly at its minimum distance."""
    r = solve(W, H, tension=1.0e6, anchor_distance=X)
    at_load = solve(W, H, tension=1.0e6 + r.load_margin, anchor_distance=X)
    assert abs(at_load.anchor_margin) < 1e-9 * X
    r_h = r.horizontal_tension
    at_tide = solve(W, H + r.tide_margin, horizontal=r_h, anchor_distance=X)
    assert abs(at_tide.anchor_margin) < 1e-9 * X


def test_uplift_grows_as_anchor_gets_closer():
    x = np.linspace(20.0, 230.0, 200)
    r = solve(W, H, tension=T, anchor_distance=x)
    assert np.all(np.diff(r.uplift_force) <= 0)
    assert r.uplift_force[-1] == 0 and r.uplift_force[0] > 0


def test_core_imports_no_rclpy():
    code = (
        "import sys; sys.modules['rclpy'] = None\n"
        "import catenary_monitor, catenary_monitor.core.physics.catenary\n"
        "import catenary_monitor.core.physics.solve\n"
        "print(catenary_monitor.solve(1300.0, 20.85, tension=1623.5e3).min_anchor_distance)"
    )
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, check=True)
    assert float(out.stdout) == pytest.approx(225.97, abs=0.01)


# ---------------------------------------------------------------------------------- CLI
def cli(*args):
    return subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli', *args], capture_output=True, text=True
    )


def test_cli_json_contract():
    p = cli(
        'solve',
        '--weight',
        '1300',
        '--depth',
        '20.85',
        '--tension',
        '1623.5e3',
        '--anchor-distance',
        '121.06',
        '--mbl',
        '6.5e6',
        '--json',
    )
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    assert data.pop('model') == 'inextensible catenary' and data.pop('anchor_lifted') is True
    assert set(data) == set(ALL_KEYS) - {'grounded_length'}
    want = solve(W, H, tension=T, anchor_distance=X, mbl=6.5e6)
    for key, value in data.items():
        assert value == getattr(want, key)  # full precision round trip
    p = cli('solve', '--weight', '1300', '--depth', '20.85', '--horizontal', '372e3', '--json')
    data = json.loads(p.stdout)
    assert data['uplift_force'] == 0 and data['anchor_angle_deg'] == 0
    assert 'anchor_margin' not in data and 'safety_factor' not in data


def test_cli_solves_problem4_far_beyond_any_chain():
    """Problem 4 with T/w some 1e198 x the anchor distance (m^2 underflowed before 1e150):
    solved, every value finite."""
    p = cli(
        'solve', '--weight', '1300', '--depth', '20.85', '--tension', '1e200',
        '--anchor-distance', '100', '--json',
    )  # fmt: skip
    assert p.returncode == 0, p.stderr
    got = json.loads(p.stdout)
    assert got['anchor_lifted'] and all(
        math.isfinite(got[k]) for k in got if k not in ('model', 'anchor_lifted')
    )


def test_cli_refuses_results_float64_cannot_hold():
    """T/w itself beyond float64 (w = 1e-300 N/m): Status.OUT_OF_RANGE, one line and exit 2,
    never a table of inf and NaN."""
    for fmt in ((), ('--json',)):
        p = cli(
            'solve', '--weight', '1e-300', '--depth', '20.85', '--tension', '1e200',
            '--anchor-distance', '100', *fmt,
        )  # fmt: skip
        assert p.returncode == 2 and p.stdout == '', p.stdout
        assert len(p.stderr.strip().splitlines()) == 1 and 'range' in p.stderr, p.stderr


def test_cli_table_default():
    p = cli('solve', '--weight', '1300', '--depth', '20.85', '--tension', '1623.5e3')
    assert p.returncode == 0
    assert 'minimum anchor distance' in p.stdout and '225.9716' in p.stdout


def test_cli_table_keeps_huge_values_readable():
    """A 1e300 N tension (no MBL given: the solver cannot call it implausible) prints in
    significant digits, not as a 300-digit fixed-point number."""
    p = cli('solve', '--weight', '1300', '--depth', '20', '--tension', '1e300')
    assert p.returncode == 0
    assert max(len(line) for line in p.stdout.splitlines()) < 80, p.stdout
    assert '1e+297' in p.stdout and '1.754116e+149' in p.stdout


@pytest.mark.parametrize(
    'args,needle',
    [
        (['--weight', 'nan', '--depth', '20', '--tension', '1e6'], 'NaN'),
        (['--weight', '-1', '--depth', '20', '--tension', '1e6'], 'weight'),
        (['--weight', '1300', '--depth', '0', '--tension', '1e6'], 'depth'),
        (['--weight', '1300', '--depth', '20.85', '--tension', '2e4'], 'T > w*h'),
        (
            ['--weight', '1300', '--depth', '20.85', '--tension', '1e6', '--anchor-distance', '0'],
            'anchor distance',
        ),
        (
            ['--weight', '25', '--depth', '15', '--chain-length', '10', '--anchor-distance', '11'],
            'chain length',
        ),
        (['--weight', '25', '--depth', '15', '--chain-length', '10'], '--anchor-distance'),
        (['--weight', '1300', '--depth', '20.85'], 'required'),
        (['--weight', '1300', '--depth', '20.85', '--tension', 'abc'], 'not a number'),
    ],
)
def test_cli_invalid_input_exit_2_one_line(args, needle):
    p = cli('solve', *args)
    assert p.returncode == 2
    assert p.stdout == ''
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], p.stderr
    assert 'Traceback' not in p.stderr and 'nan' not in p.stdout.lower()


KERNEL = fused_kernel.AVAILABLE


def test_flat_array_call_equals_the_general_path():
    """The common array call (1-D float64 arrays, floats, ints: taken without the generic
    broadcast) gives the same bits as the general path (lists, a column and a row broadcast),
    with its rows that do not apply NaN and read-only, and its length-mismatch error."""
    rng = np.random.default_rng(13)
    n = 301
    t = rng.uniform(0.3e6, 3e6, n)
    h = rng.uniform(2.0, 60.0, n)
    x = rng.uniform(20.0, 400.0, n)
    for mbl in (None, 6.5e6):
        fast = solve(1300, h, tension=t, anchor_distance=x, mbl=mbl)
        general = solve([1300.0] * n, h.tolist(), tension=t.tolist(), anchor_distance=x, mbl=mbl)
        column = solve(1300.0, h[:, None], tension=t[:, None], anchor_distance=x[:, None], mbl=mbl)
        assert fast.keys == general.keys == column.keys
        assert 0 < np.count_nonzero(fast.uplift_force > 0) < n  # lifted and grounded mixed
        for key in ALL_KEYS:
            a = getattr(fast, key)
            assert a.shape == (n,)
            np.testing.assert_array_equal(a, getattr(general, key), err_msg=key)
            np.testing.assert_array_equal(a, getattr(column, key)[:, 0], err_msg=key)
            if key not in fast.keys:  # read-only: no memory written for them (the C kernel)
                assert np.isnan(a).all() and (not a.flags.writeable or not KERNEL), key
        np.testing.assert_array_equal(fast.status, general.status)
    with pytest.raises(ValueError, match='broadcast'):
        solve(1300.0, h, tension=t[:-1], anchor_distance=x)


def test_cli_prints_a_margin_beyond_float64_as_unbounded():
    """A nearly slack chain's tide margin is beyond float64 (+inf in solve(), status 0): the
    table says so in words, the JSON has null and names it under 'unbounded' (strict JSON, no
    Infinity), exit 0; the other values are printed as they are."""
    args = ['--weight', '1300', '--depth', '20.85', '--tension', '27376.05']
    args += ['--anchor-distance', '200']
    r = solve(1300.0, 20.85, tension=27376.05, anchor_distance=200.0)
    assert r.status == 0 and r.tide_margin == np.inf
    cmd = [sys.executable, '-m', 'catenary_monitor', 'solve', *args]
    table = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert table.returncode == 0, table.stderr
    assert 'beyond float64' in table.stdout and 'inf' not in table.stdout.replace('float', '')
    p = subprocess.run([*cmd, '--json'], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout, parse_constant=lambda c: pytest.fail(f'non-JSON {c}'))
    assert data['tide_margin'] is None and data['unbounded'] == ['tide_margin']
    assert data['load_margin'] == r.load_margin and data['anchor_margin'] == r.anchor_margin
