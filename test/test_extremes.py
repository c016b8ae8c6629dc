"""solve() at extreme inputs: problem 4 right and finite up to T/w ~ 1e300 x on all three
paths (C kernel, numpy, plain floats) against mpmath, and never status 0 with inf or NaN."""

import itertools
import math

import mpmath as mp
import numpy as np
import pytest
import reference as ref

from catenary_monitor import solve
from catenary_monitor.core.physics import fused_kernel, inextensible
from catenary_monitor.core.physics import solve as solve_module
from catenary_monitor.core.physics.result import ALL_KEYS, INF_MARGINS, Status

W, H, X = 1300.0, 20.85, 121.06


def reference(w, t, h, x, dps=700):
    """Problem 4 in mpmath from the paper's equation (1) (test/reference.py's form) at enough
    digits for x/a ~ 1e-300: R and F."""
    with mp.workdps(dps):
        w, t, h, x = (mp.mpf(v) for v in (w, t, h, x))
        b = t / w - h

        def y_minus_h(alpha):
            a = b * mp.cos(alpha)
            z = x / a
            return a * (mp.sec(alpha) * (mp.cosh(z) - 1) + mp.tan(alpha) * mp.sinh(z)) - h

        lo, hi = mp.mpf(0), mp.pi / 2
        for _ in range(120):
            mid = (lo + hi) / 2
            lo, hi = (lo, mid) if y_minus_h(mid) > 0 else (mid, hi)
        alpha = (lo + hi) / 2
        a = b * mp.cos(alpha)
        return float(w * a), float(w * a * mp.tan(alpha))


def paths(t):
    one = solve(W, H, tension=t, anchor_distance=X)
    arr = solve(np.full(3, W), H, tension=np.full(3, t), anchor_distance=X)
    numpy = inextensible._solve_arrays(
        'tension',
        {'weight': np.array([W]), 'depth': np.array([H]), 'tension': np.array([t]),
         'anchor_distance': np.array([X])},
        False,
    )  # fmt: skip
    scalar = inextensible._solve_scalar('tension', W, H, t, X)
    return {'kernel one': one, 'kernel array': arr, 'numpy': numpy, 'scalar': scalar}


@pytest.mark.parametrize('ratio', [1e60, 1e100, 1e150, 1e200, 1e300])
def test_problem4_extreme_tension_matches_mpmath_on_every_path(ratio):
    t = W * X * ratio
    r_ref, f_ref = reference(W, t, H, X)
    for name, r in paths(t).items():
        assert (np.ravel(r.status) == 0).all(), name
        for key in r.keys:
            assert np.isfinite(np.asarray(getattr(r, key), dtype=float)).all(), (name, key)
        r_got = float(np.ravel(r.horizontal_tension)[0])
        f_got = float(np.ravel(r.uplift_force)[0])
        assert abs(r_got - r_ref) <= 1e-12 * r_ref, (name, r_got, r_ref)
        assert abs(f_got - f_ref) <= 1e-12 * f_ref, (name, f_got, f_ref)


VALUES = [1e-300, 1e-150, 1e-20, 1.0, 1e3, 1e20, 1e150, 1e300]


def _no_silent_non_finite(r):
    status = np.atleast_1d(r.status)
    for key in r.keys:
        v = np.atleast_1d(np.asarray(getattr(r, key), dtype=float))
        inf_margin = (v == np.inf) & (key in INF_MARGINS)  # a real margin beyond float64
        assert not ((status == 0) & ~np.isfinite(v) & ~inf_margin).any(), key


@pytest.mark.filterwarnings('ignore::RuntimeWarning')
def test_every_non_finite_output_has_a_non_zero_status():
    """Problems 1-5 (and the elastic chain) over every combination of extreme inputs."""
    w, h, load, x = (np.array(v) for v in zip(*itertools.product(VALUES, repeat=4)))
    for ea in (None, 1e9):
        _no_silent_non_finite(solve(w, h, tension=load, anchor_distance=x, mbl=load, ea=ea))
        _no_silent_non_finite(solve(w, h, tension=load, ea=ea))
        _no_silent_non_finite(solve(w, h, chain_length=load, anchor_distance=x, ea=ea))
    _no_silent_non_finite(solve(w, h, horizontal=load, anchor_distance=x, mbl=load))
    _no_silent_non_finite(solve(w, h, horizontal=load))
    arrays = {'weight': w, 'depth': h, 'tension': load, 'anchor_distance': x}
    with np.errstate(all='ignore'):
        _no_silent_non_finite(inextensible._solve_arrays('tension', arrays, False))
    for i in range(0, w.size, 5):
        args = (float(w[i]), float(h[i]), float(load[i]), float(x[i]))
        for problem in ('tension', 'horizontal'):
            _no_silent_non_finite(solve(*args[:2], **{problem: args[2]}, anchor_distance=args[3]))
            try:
                _no_silent_non_finite(inextensible._solve_scalar(problem, *args))
            except (OverflowError, ZeroDivisionError, ValueError):
                pass  # the plain-float path hands these to numpy (solve_inextensible)


def test_out_of_range_status_where_float64_cannot_hold_the_answer():
    r = solve(1e-300, 20.85, tension=1e200, anchor_distance=100.0)
    assert r.status == Status.OUT_OF_RANGE and np.isnan(r.horizontal_tension)
    assert 'float64' in r.message


# --------------------------------------------------------------------------------------------
# Grounded chains at extreme x/a: status 0, every value right (mpmath), +inf only for a margin
# beyond float64.  The kernel once made x/a in (352, 709.8) NaN (an overflowed shared
# denominator, inf * 0) and blanked the lane as OUT_OF_RANGE (test_uncertainty's T = 1.01 w h).
# --------------------------------------------------------------------------------------------
DBL_MAX = float(np.finfo(float).max)
LIFTED = (1300.0, 20.85, 1623.5e3, 121.06)  # the paper's table-4 scene: anchor lifted


def _b(w, h, t):
    return mp.mpf(t) / mp.mpf(w) - mp.mpf(h)  # anchor-end tension / w, exact at 50 digits


def _critical(w, h, x):
    """Critical hook tension: a (cosh(x/a) - 1) = h, by bisection in log(x/2a) (wide bracket:
    x/h up to 1e300 and beyond); 50 digits."""
    c = mp.mpf(h) / mp.mpf(x)

    def f(ld):
        return 2 * mp.log(mp.sinh(mp.exp(ld))) - ld - mp.log(c)

    lo, hi = mp.mpf(-1600), mp.mpf(10)
    for _ in range(400):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if f(mid) > 0 else (mid, hi)
    return w * (x / (2 * mp.exp((lo + hi) / 2)) + h)


def _float_or_inf(v):
    return math.inf if v > DBL_MAX else float(v)


def grounded_reference(w, h, t, x):
    """Every value of a grounded chain (x >= x_min) from reference.py's problem-3 solution and
    the margins' definitions, at 50 digits; a margin beyond float64 is +inf."""
    with mp.workdps(50):
        b = _b(w, h, t)
        z = mp.mpf(x) / b
        assert z > 1 and mp.mpf(x) >= b * mp.acosh(1 + mp.mpf(h) / b)  # grounded
        out = {k: float(v) for k, v in ref.grounded(w, h, b).items()}
        out['top_tension'] = float(t)
        out['anchor_angle_deg'] = out['uplift_force'] = 0.0
        out['anchor_margin'] = float(mp.mpf(x) - b * mp.acosh(1 + mp.mpf(h) / b))
        if mp.log(b / 2) + z > 720:  # a (cosh z - 1) beyond float64 by far
            out['tide_margin'] = math.inf
        else:
            out['tide_margin'] = _float_or_inf(b * (mp.cosh(z) - 1) - h)
        out['load_margin'] = _float_or_inf(_critical(w, h, x) - t)
    return out


def _near_vertical(w, h, ulps):
    """A hook tension ``ulps`` float steps above w h."""
    t = w * h
    for _ in range(ulps):
        t = math.nextafter(t, math.inf)
    return t


_B = 0.01 * 20.85  # T = 1.01 w h: a = 0.2085 m
GROUNDED = {
    'uncertainty case (x/a 575)': (1300.0, 20.85, 1.01 * 1300.0 * 20.85, 120.0),
    'x/a 400': (1300.0, 20.85, 1.01 * 1300.0 * 20.85, 400 * _B),
    'x/a 700': (1300.0, 20.85, 1.01 * 1300.0 * 20.85, 700 * _B),
    'x/a 709.9 (exp overflows, depth finite)': (1300.0, 20.85, 1.01 * 1300.0 * 20.85, 709.9 * _B),
    'x/a 1e4': (1300.0, 20.85, 1.01 * 1300.0 * 20.85, 1e4 * _B),
    'x/a 1e300 (load margin beyond float64)': (1300.0, 20.85, 1.01 * 1300.0 * 20.85, 1e300 * _B),
    'x/a 1e300 (load margin finite)': (1.0, 1e-280, 1e-280 * (1.0 + 1e-10), 1e-290 * 1e300),
    'T 2 ulps above w h': (1300.0, 20.85, _near_vertical(1300.0, 20.85, 2), 120.0),
    'T 1 ulp above w h, dock span': (1300.0, 20.85, _near_vertical(1300.0, 20.85, 1), 121.06),
}
#: relative accuracy (forces, distances, angles); margins: of the larger term
REL = 1e-12
MARGIN_SCALE = {'anchor_margin': 'x', 'tide_margin': 'h', 'load_margin': 't'}


def _check_values(name, r, expect, inputs):
    w, h, t, x = inputs
    assert r.status == 0, (name, r.message)
    for key in r.keys:
        got, want = float(getattr(r, key)), expect[key]
        if math.isinf(want):
            assert got == want, (name, key, got)
            assert key in INF_MARGINS
            continue
        assert math.isfinite(got), (name, key, got)
        scale = max(abs(want), {'x': x, 'h': h, 't': t}.get(MARGIN_SCALE.get(key, ''), 0.0))
        assert abs(got - want) <= REL * scale, (name, key, got, want)


@pytest.fixture
def kernel_off(monkeypatch):
    """solve() without the C kernel: arrays take the numpy path (catenary.py), one element the
    plain-float path; a kernel call fails the test (no pass by construction)."""

    def no_kernel(*args, **kwargs):
        raise AssertionError('the C kernel was called')

    monkeypatch.setattr(fused_kernel, 'AVAILABLE', False)
    monkeypatch.setattr(fused_kernel, 'solve_arrays', no_kernel)
    monkeypatch.setattr(fused_kernel, 'solve_one', no_kernel)
    monkeypatch.setattr(solve_module, '_ONE', None)
    monkeypatch.setattr(inextensible, '_ONE', None)
    return solve.__wrapped__  # the Python solve(): the kernel's Entry would take one element


def _array_with_lifted_lanes(inputs, n=600, at=(0, 257, 599)):
    """The scene at a few places of an array of lifted dock lanes (several blocks, a partial
    one, gathered lifted lanes next to the grounded one)."""
    cols = [np.full(n, v) for v in LIFTED]
    for c, v in zip(cols, inputs):
        c[list(at)] = v
    return cols, at


def _each_in_array(r, at):
    for i in at:
        yield r._replace(**{k: float(getattr(r, k)[i]) for k in ALL_KEYS}, status=int(r.status[i]))


@pytest.mark.parametrize('name', list(GROUNDED))
def test_grounded_extreme_span_kernel(name, isa):
    """One element (solve_one) and arrays on every instruction set: status 0, values right."""
    inputs = GROUNDED[name]
    w, h, t, x = inputs
    expect = grounded_reference(*inputs)
    _check_values(name, solve(w, h, tension=t, anchor_distance=x), expect, inputs)
    cols, at = _array_with_lifted_lanes(inputs)
    r = solve(cols[0], cols[1], tension=cols[2], anchor_distance=cols[3])
    assert (r.status == 0).all() and (r.uplift_force[1:-1:100] > 0).all()
    for one in _each_in_array(r, at):
        _check_values(name + ' (array)', one, expect, inputs)


@pytest.mark.parametrize('name', list(GROUNDED))
def test_grounded_extreme_span_without_the_kernel(name, kernel_off):
    """The numpy path (arrays) and the plain-float path (one element), the kernel off."""
    inputs = GROUNDED[name]
    w, h, t, x = inputs
    expect = grounded_reference(*inputs)
    one = kernel_off(w, h, tension=t, anchor_distance=x)
    _check_values(name + ' (plain floats)', one, expect, inputs)
    # the plain-float path itself (no OverflowError handed on to numpy): the same result
    direct = inextensible._solve_scalar('tension', w, h, t, x)
    assert direct.status == 0 and all(getattr(direct, k) == getattr(one, k) for k in one.keys)
    cols, at = _array_with_lifted_lanes(inputs)
    r = kernel_off(cols[0], cols[1], tension=cols[2], anchor_distance=cols[3])
    assert (r.status == 0).all()
    for one in _each_in_array(r, at):
        _check_values(name + ' (numpy)', one, expect, inputs)


def test_uncertainty_scene_keeps_its_values():
    """test_uncertainty's grounded near-vertical chain: status 0 and a finite tide margin
    (~9.4e248 m) on the kernel, not OUT_OF_RANGE with NaN."""
    r = solve(1300.0, 20.85, tension=1.01 * 1300.0 * 20.85, anchor_distance=120.0)
    assert r.status == 0 and 9e248 < r.tide_margin < 1e249


def test_one_out_of_range_lane_among_solved_ones(isa):
    """The kernel finds a lane beyond float64 in a block of ordinary ones (a block's sum of
    outputs stops being finite; then each lane is classified): that lane OUT_OF_RANGE, the
    others unchanged, bit for bit."""
    cols, at = _array_with_lifted_lanes((1e-300, 20.85, 1e200, 100.0), at=(300,))
    r = solve(cols[0], cols[1], tension=cols[2], anchor_distance=cols[3])
    clean = solve(*(np.delete(c, 300) for c in cols[:2]), tension=np.delete(cols[2], 300),
                  anchor_distance=np.delete(cols[3], 300))  # fmt: skip
    assert r.status[300] == Status.OUT_OF_RANGE and np.isnan(r.horizontal_tension[300])
    assert (np.delete(r.status, 300) == 0).all() and (clean.status == 0).all()
    for k in r.keys:
        np.testing.assert_array_equal(np.delete(getattr(r, k), 300), getattr(clean, k))
