"""The methods side by side: interface, seed tables, and the stability facts the map shows.

The collection follows scipy's ``_tstutils`` / ``test_zeros.py::run_collection``: named scenes
on the paper's dock (w = 1300 N/m, h = 20.85 m) located by ``h/a`` (anchor-end parameter) and
``x/x_min``, and for each weaker method the outcome the stability map claims there:

* ``ok``: error <= 1e-12 (relative, divided by max(1, condition number), against the 50-digit
  mpmath solution of the paper's equations computed here);
* ``loses``: 1e-12 < error <= 1e-6 (an answer, but not to the project's accuracy);
* ``fails``: an exception, NaN, or an error above 1e-6.

Each ``fails``/``loses`` row is a region of ``docs/stability_map.png`` asserted; each method also
has an ``ok`` row so the assertion cannot pass by the method being broken everywhere.
"""

import math
from functools import lru_cache

import numpy as np
import pytest

from catenary_monitor.core.physics import catenary as cat
from catenary_monitor_study.bench_methods import FAIL, GOOD, H_DOCK, W_DOCK, scene_error
from catenary_monitor_study.methods import (
    Method,
    NoConvergence,
    all_methods,
    hou,
    paper,
    peers,
    reference,
)

METHODS = {(m.problem, m.name): m for m in all_methods(peers=True)}


def dock_scene(ha, xr=None):
    t = W_DOCK * (H_DOCK / ha + H_DOCK)
    if xr is None:
        return W_DOCK, H_DOCK, t
    b = float(cat.two_prod_diff(t, W_DOCK, H_DOCK)) / W_DOCK
    return W_DOCK, H_DOCK, t, xr * float(cat.grounded(b, H_DOCK).min_anchor_distance)


@lru_cache(maxsize=None)
def ref4(ha, xr):
    return reference.problem4(*dock_scene(ha, xr))


def dock_scene2(ha, xr):
    """Problem 2 on the dock: R = w h / (h/a), x = xr * x_min(R)."""
    r = W_DOCK * H_DOCK / ha
    return W_DOCK, H_DOCK, r, xr * float(cat.grounded(r / W_DOCK, H_DOCK).min_anchor_distance)


@lru_cache(maxsize=None)
def ref2(ha, xr):
    return reference.problem2(*dock_scene2(ha, xr))


@lru_cache(maxsize=None)
def ref3(ha):
    return reference.problem3(*dock_scene(ha))


def outcome(problem, name, ha, xr=None):
    m = METHODS.get((problem, name))
    assert m is not None, f'{name} is missing: the test extra installs every peer'
    if problem == 3:
        r = ref3(ha)
        args = dock_scene(ha)
    elif problem == 2:
        r = ref2(ha, xr)
        args = dock_scene2(ha, xr)
    elif m.given == 'length':
        r4 = ref4(ha, xr)
        w, h, t, x = dock_scene(ha, xr)
        r = reference.given_length(w, h, x, r4.length, r4.v1 / w)
        args = (w, h, x, r4.length)
    else:
        r = ref4(ha, xr)
        args = dock_scene(ha, xr)
    try:
        with np.errstate(all='ignore'), _quiet():
            val = m.scalar_fn(*args)
    except (NoConvergence, ArithmeticError, ValueError, RuntimeError) as exc:
        return 'fails', repr(exc)
    err = scene_error(val, np.array(r[:2]), np.array(r[2:4]))
    return ('ok' if err <= GOOD else 'loses' if err <= FAIL else 'fails'), err


class _quiet:
    def __enter__(self):
        import warnings

        self._w = warnings.catch_warnings()
        self._w.__enter__()
        warnings.simplefilter('ignore')

    def __exit__(self, *exc):
        return self._w.__exit__(*exc)


# (problem, method, h/a, x/x_min, expected outcome, the reason the map gives)
KNOWN = [
    # problem 4: the uplift solve
    (4, 'bisection', 1e-9, 0.9999, 'fails', 'cancelling formula'),
    (4, 'bisection', 1e-6, 0.1, 'loses', 'cancelling formula'),
    (4, 'bisection', 1.0, 0.1, 'ok', ''),
    (4, 'Newton', 1e-6, 0.1, 'fails', 'wrong unknown: steps past a = B'),
    (4, 'Newton', 1.0, 0.5, 'ok', ''),
    (4, 'Newton', 1.0, 0.999999, 'fails', 'wrong unknown: steps past a = B'),
    (4, 'Newton', 0.1, 1e-3, 'fails', 'wrong unknown: cycles inside the domain (iteration cap)'),
    (4, 'safeguarded Newton', 1e-8, 0.9999, 'fails', 'cancelling formula'),
    (4, 'safeguarded Newton', 1e-7, 0.1, 'loses', 'cancelling formula'),
    (4, 'safeguarded Newton', 1.0, 0.1, 'ok', ''),
    (4, 'brentq', 1e-8, 0.9999, 'fails', 'cancelling formula'),
    (4, 'brentq', 1e4, 0.01, 'loses', 'absolute xtol = 2e-12 m on a of micrometres'),
    (4, 'brentq', 1.0, 0.1, 'ok', ''),
    (
        4,
        'brentq',
        1e4,
        0.999999,
        'fails',
        'absolute xtol on micrometre a, near x_min (1.00005e-6)',
    ),
    (
        4,
        'brentq (xtol=5e-324)',
        1e4,
        0.01,
        'ok',
        'relative tolerance cures the absolute-xtol loss',
    ),
    (4, 'brentq (xtol=5e-324)', 1e-8, 0.9999, 'fails', 'but not the cancelling formula'),
    (4, 'brentq on log d', 1e-8, 0.9999, 'ok', 'the right unknown cures it'),
    (4, 'brentq on log d', 1e4, 0.001, 'ok', ''),
    (4, 'root/fsolve (R, alpha)', 1e-3, 1e-3, 'fails', 'badly scaled two-unknown system'),
    (
        4,
        'root/fsolve (R, alpha)',
        1.0,
        0.1,
        'fails',
        'converges to a wrong point and reports success',
    ),
    (4, 'root/fsolve (R, alpha)', 1.0, 0.999999, 'ok', ''),
    (4, 'Hou fixed point', 1.0, 0.5, 'fails', 'not a contraction'),
    (4, 'Hou fixed point', 1e-6, 0.1, 'fails', 'not a contraction'),
    (4, 'Hou fixed point', 1e2, 0.01, 'ok', ''),
    (4, 'Hou 0.618 search', 1e-8, 0.9999, 'fails', 'cancelling formula'),
    (4, 'Hou 0.618 search', 1e-6, 0.1, 'loses', 'cancelling formula'),
    (4, 'Hou 0.618 search', 1.0, 0.1, 'ok', ''),
    (4, 'paper stepping (Fig. 2)', 1.0, 0.5, 'fails', 'start alpha = 44 deg below the root'),
    (
        4,
        'paper stepping (Fig. 2)',
        1e-5,
        0.23,
        'fails',
        'absolute 0.1 kN steps in R: > 1e5 evaluations',
    ),
    (4, 'paper stepping (Fig. 2)', 0.1, 0.9, 'fails', 'absolute tolerances 1e-5 m, 1 N'),
    (4, 'paper stepping (Fig. 2)', 1e-3, 0.5, 'loses', 'absolute tolerances 1e-5 m, 1 N'),
    (4, 'MoorPy catenary (L given)', 1.0, 0.5, 'loses', 'absolute 1e-6 m tolerance'),
    (4, 'MoorPy catenary (L given)', 1e-3, 1e-3, 'ok', ''),
    (
        4,
        'MoorPy catenary (L given)',
        1e4,
        0.093216975178615730,
        'fails',
        'absolute 1e-6 m on a 0.3 m span',
    ),
    (4, 'pycatenary (L given)', 1e-6, 0.1, 'fails', 'bracket [1e-2, 1e10] m misses a'),
    (4, 'pycatenary (L given)', 1e4, 0.1, 'fails', 'a < 1e-2 m: silently wrong'),
    (4, 'pycatenary (L given)', 1.0, 0.1, 'ok', ''),
    (4, 'MoorPy + brentq on L', 1e-6, 0.1, 'fails', "wrapper's bracket misses the root"),
    (4, 'MoorPy + brentq on L', 1.0, 0.5, 'loses', 'absolute 1e-6 m tolerance'),
    (
        4,
        'MoorPy + brentq on L',
        1e3,
        1e-3,
        'fails',
        "wrapper's bracket misses the root (steep chain)",
    ),
    # problem 3: minimum anchor distance
    (3, 'closed form (textbook)', 1e-9, None, 'loses', 'cancelling formula acosh(1 + h/a)'),
    (3, 'closed form (textbook)', 1.0, None, 'ok', ''),
    (3, 'bisection', 1e4, None, 'fails', 'cosh overflows at the bracket end'),
    (3, 'bisection', 1e-9, None, 'loses', 'cancelling formula cosh(x/a) - 1'),
    (3, 'bisection', 1.0, None, 'ok', ''),
    (3, 'Newton', 1e-5, None, 'fails', 'cancelling formula: relative step test never met'),
    (3, 'Newton', 1e-3, None, 'fails', 'cancelling formula: relative step test never met'),
    (3, 'Newton', 1e3, None, 'ok', ''),
    (3, 'brentq', 1e3, None, 'fails', 'cosh overflows at the bracket end'),
    (3, 'brentq', 1.0, None, 'ok', ''),
    (3, 'root/fsolve (x, R)', 10.0, None, 'fails', 'badly scaled, overflowing trial steps'),
    (3, 'root/fsolve (x, R)', 1e-3, None, 'loses', 'hybr xtol 1.5e-8'),
    (3, 'paper stepping (Fig. 2)', 1e-5, None, 'fails', 'start below the root (x_min > 1000 m)'),
    (3, 'paper stepping (Fig. 2)', 1.0, None, 'fails', 'absolute tolerance 1e-5 m on a 2 m span'),
    (3, 'paper stepping (Fig. 2)', 20.85 / 1228.0, None, 'loses', 'the dock of table 4: 5 digits'),
    # problem 2: R and x given (table 3)
    (2, 'paper stepping (Fig. 2)', 1.0, 0.5, 'fails', 'start alpha = 44 deg below the root'),
    (2, 'paper stepping (Fig. 2)', 1e-2, 0.9, 'loses', 'absolute tolerance 1e-5 m in y'),
    (2, 'closed form (textbook)', 1e-3, 0.99, 'ok', 'its subtraction is the problem\'s own'),
    (2, 'closed form (textbook)', 1e2, 0.1, 'ok', ''),
]


@pytest.mark.parametrize(
    'problem,name,ha,xr,expected,why',
    KNOWN,
    ids=[f'p{k[0]}-{k[1]}-{k[2]:g}-{k[3]}-{k[4]}' for k in KNOWN],
)
def test_stability_map_claims(problem, name, ha, xr, expected, why):
    got, detail = outcome(problem, name, ha, xr)
    assert (
        got == expected
    ), f'{name} at h/a={ha:g}, x/x_min={xr}: {got} ({detail}); map says {expected}: {why}'


NEVER_FAIL = {
    (4, 'default kernel'),
    (3, 'closed form (stable)'),
    (4, 'brentq on log d'),
    (2, 'closed form (textbook)'),
}


def test_every_weaker_method_has_a_failure_row_and_an_ok_row():
    rows = {}
    for problem, name, _, _, expected, _ in KNOWN:
        rows.setdefault((problem, name), set()).add(expected)
    for (problem, name), m in METHODS.items():
        if m.default or (problem, name) in NEVER_FAIL:
            continue
        assert (problem, name) in rows, f'no stability row for {name} (problem {problem})'
        assert rows[(problem, name)] & {'fails', 'loses'}, name
        assert rows[(problem, name)] & {'ok', 'loses'}, f'{name}: no row where it works'


@pytest.mark.parametrize(
    'ha,xr', [(1e-9, 0.9999), (1e-9, 1e-3), (1e4, 1e-3), (1e4, 0.999999), (1.0, 0.5)]
)
def test_default_holds_where_the_others_fail(ha, xr):
    for name in ('default', 'default kernel'):
        assert outcome(4, name, ha, xr)[0] == 'ok'
    assert outcome(3, 'default', ha)[0] == 'ok'
    assert outcome(2, 'default', ha, xr)[0] == 'ok'


def test_paper_method_reproduces_its_own_tables():
    """Fig. 2 as printed gives the tables' numbers to their printed precision."""
    assert paper.p1_stepping(1300.0, 20.85, 372e3) == pytest.approx(108.5839, abs=1e-4)  # table 2
    assert paper.p1_stepping(517.0, 80.0, 89.63e3) == pytest.approx(160.74, abs=0.015)  # table 1
    alpha, f = paper.p2_stepping(1300.0, 20.85, 1584.6e3, 121.06)  # table 3
    assert math.degrees(alpha) == pytest.approx(6.9535, abs=2e-4)
    assert f == pytest.approx(193.26e3, rel=1e-4)
    r, x = paper.p3_stepping(1300.0, 20.85, 1623.5e3)  # table 4 (x = 225.97: the erratum)
    assert r == pytest.approx(1596.4e3, abs=100.0)
    assert x == pytest.approx(225.9716, abs=2e-3)


def test_paper_method_needs_its_start_above_the_root():
    # w h < 2 kN: the R search starts at T - 2 kN, already below R = T - w h, and only steps down
    with pytest.raises(NoConvergence, match='start R = T - 2 kN is already below the root'):
        paper.p3_stepping(50.0, 20.0, 50.0 * 20.0 + 5e3)


def test_hou_reproduces_his_table():
    """Hou 2005's check table: w = 25 kg/m, dm = 11 m; Fh in kgf, lying length in m."""
    for lm, h, lying, fh in [
        (20, 15, 0.563, 127.33),
        (20, 13, 4.68, 63.09),
        (21, 15, 2.90, 85.51),
        (21, 13, 6.59, 37.14),
    ]:
        for r, g in (
            hou.p5_fixed_point(25.0, h, lm, 11.0),
            hou.p5_golden(25.0, h, lm, 11.0, 400.0),
        ):
            assert r == pytest.approx(fh, abs=0.04)
            assert g == pytest.approx(lying, abs=0.006)


def test_interface():
    names = {m.family for m in all_methods(peers=False)}
    assert names == {'closed', 'roots', 'hou', 'paper'}
    for m in all_methods():
        assert isinstance(m, Method) and m.problem in (2, 3, 4) and m.why
    assert sum(m.default for m in all_methods() if m.problem == 4) == 1


def test_vectorized_forms_match_scalar_on_good_scenes():
    scenes = [dock_scene(ha, xr) for ha in (1e-2, 1.0, 1e2) for xr in (0.01, 0.5)]
    cols = [np.array(c) for c in zip(*scenes)]
    for m in all_methods(peers=False):
        if m.vector_fn is None or m.problem != 4 or m.name == 'Newton':
            continue
        r, f = m.vector_fn(*(c.copy() for c in cols))
        for i, s in enumerate(scenes):
            rs, fs = m.scalar_fn(*s)
            assert r[i] == pytest.approx(rs, rel=1e-12) and f[i] == pytest.approx(
                fs, rel=1e-11
            ), m.name


def test_peers_absent_are_reported(monkeypatch):
    import builtins

    real = builtins.__import__

    def fake(name, *a, **k):
        if name in ('moorpy', 'pycatenary'):
            raise ImportError(name)
        return real(name, *a, **k)

    monkeypatch.setattr(builtins, '__import__', fake)
    assert peers.available_methods() == []


def test_bench_smoke(tmp_path):
    """A reduced benchmark run writes its four files and the same-run ratios."""
    from catenary_monitor_study.bench_methods import run

    res = run(quick=True, out_dir=str(tmp_path), only='kernel', stream=None)
    for f in ('methods.csv', 'methods.md', 'speed_accuracy.png', 'stability_map.png'):
        assert (tmp_path / f).stat().st_size > 0
    assert res['ratios']['vector_p4_over_floor'] > 0
    default = [r for r in res['rows'] if r['method'] == 'default' and r['problem'] == 4][0]
    assert default['failures'] == 0 and default['error_worst'] <= GOOD


def test_cli_registers_bench_methods():
    from catenary_monitor.cli.main import build_parser

    args = build_parser().parse_args(['bench-methods', '--quick', '--out', ''])
    assert args.quick and args.func.__name__ == 'cmd_bench_methods'
