"""solve() at extreme inputs: problem 4 right and finite up to T/w ~ 1e300 x on all three
paths (C kernel, numpy, plain floats) against mpmath, and never status 0 with inf or NaN."""

import itertools

import mpmath as mp
import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core import inextensible
from catenary_monitor.core.result import INF_MARGINS, Status

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
