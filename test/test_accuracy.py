"""Accuracy against the 50-digit mpmath reference of test/reference.py (computed here, not stored).

Scenes span h/a from 1e-9 to 1e4 and x from 1e-3 of the minimum anchor distance up to it.
Bound: relative error <= 1e-12 for every quantity, except the uplift force and anchor angle where
the problem itself is ill-conditioned (x -> x_min, F -> 0): there the bound is 1e-12 + 8 eps kappa,
kappa = |x/F dF/dx| computed by the reference.  Margins: absolute error <= 1e-12 of the larger
term of their difference.
"""

import math

import mpmath as mp
import numpy as np
import pytest
import reference as ref
from hypothesis import HealthCheck, given, settings, strategies as st

from catenary_monitor import solve

EPS = np.finfo(float).eps
REL = 1e-12


def log_uniform(lo: float, hi: float):
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda v: 10.0**v)


scene = st.tuples(
    log_uniform(1.0, 1e5),  # w [N/m]
    log_uniform(1e-1, 1e4),  # a = R/w at the anchor end [m]
    log_uniform(1e-9, 1e4),  # h / a
    log_uniform(1e-3, 1.0),
)  # x / x_min


def tension_scene(w, a, ha, frac):
    h = ha * a
    t = w * (a + h)
    x_min = solve(w, h, tension=t).min_anchor_distance
    return w, h, t, frac * x_min


def rel(got, want):
    want = float(want)
    return abs(got - want) / abs(want)


def x_sensitivity(solve_ref, x, key):
    """``x |d key / dx|`` by a 50-digit central difference of the reference."""
    with mp.workdps(ref.DPS):
        xm = mp.mpf(float(x))
        step = xm * mp.mpf(10) ** -20
        return abs(solve_ref(xm + step)[key] - solve_ref(xm - step)[key]) * xm / (2 * step)


def assert_conditioned(got, want, sensitivity, what, scale):
    """|got - want| <= 1e-12 |want| + 8 eps x |d want/dx|: the relative bound 1e-12 + 8 eps kappa.

    ``scale`` (the load) times 1e-50 is the reference's own resolution (bisection to 2**-200).
    """
    err = abs(got - float(want))
    bound = REL * abs(float(want)) + 8 * EPS * float(sensitivity) + 1e-50 * scale
    assert err <= bound, (what, err, float(want))


def check_uplift(got: dict, w, t, h, x):
    want = ref.uplift_from_tension(w, t, h, x)
    for key in ('horizontal_tension', 'suspended_length', 'top_angle_deg'):
        assert rel(got[key], want[key]) <= REL, key
    for key in ('uplift_force', 'anchor_angle_deg'):
        sens = x_sensitivity(lambda xx: ref.uplift_from_tension(w, t, h, xx), x, key)
        assert_conditioned(got[key], want[key], sens, key, t)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene)
def test_problem3_min_anchor_distance(s):
    w, a, ha, _ = s
    h = ha * a
    t = w * (a + h)
    r = solve(w, h, tension=t)
    want = ref.grounded(w, h, float(ref.mp.mpf(t) / w - h))
    for key in ('min_anchor_distance', 'suspended_length', 'top_angle_deg', 'horizontal_tension'):
        assert rel(getattr(r, key), want[key]) <= REL, key


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene)
def test_problem4_uplift_scalar(s):
    w, h, t, x = tension_scene(*s)
    r = solve(w, h, tension=t, anchor_distance=x)
    assert r.status == 0
    check_uplift({k: getattr(r, k) for k in r.keys}, w, t, h, x)


def test_problem4_uplift_vectorized():
    """The same bound, element by element, for one vectorized call over seeded scenes."""
    rng = np.random.default_rng(20261123)
    n = 60
    w = 10 ** rng.uniform(0, 5, n)
    a = 10 ** rng.uniform(-1, 4, n)
    h = 10 ** rng.uniform(-9, 4, n) * a
    t = w * (a + h)
    x = 10 ** rng.uniform(-3, 0, n) * solve(w, h, tension=t).min_anchor_distance
    r = solve(w, h, tension=t, anchor_distance=x)
    assert (r.status == 0).all()
    for i in range(n):
        check_uplift({k: getattr(r, k)[i] for k in r.keys}, w[i], t[i], h[i], x[i])


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene)
def test_problem2_uplift_from_horizontal(s):
    w, a, ha, frac = s
    h = ha * a
    r_h = w * a
    x = frac * solve(w, h, horizontal=r_h).min_anchor_distance
    got = solve(w, h, horizontal=r_h, anchor_distance=x)
    want = ref.uplift_from_horizontal(w, h, r_h, x)
    for key in ('top_tension', 'suspended_length', 'top_angle_deg'):
        assert rel(getattr(got, key), want[key]) <= REL, key
    # F = R tan(alpha) -> 0 as x -> x_min: bounded by the conditioning with respect to x.
    sens = x_sensitivity(lambda xx: ref.uplift_from_horizontal(w, h, r_h, xx), x, 'uplift_force')
    assert_conditioned(got.uplift_force, want['uplift_force'], sens, 'uplift_force', r_h)


@settings(max_examples=100, deadline=None)
@given(scene)
def test_margins(s):
    w, h, t, x = tension_scene(*s)
    r = solve(w, h, tension=t, anchor_distance=x)
    t_crit = ref.critical_tension(w, h, x)
    assert abs(r.load_margin - float(t_crit - t)) <= REL * max(float(t_crit), t)
    want = ref.uplift_from_tension(w, t, h, x)
    x_min = ref.grounded(w, h, float(mp.mpf(t) / w - h))['min_anchor_distance']
    assert abs(r.anchor_margin - float(x - x_min)) <= REL * float(x_min)
    with mp.workdps(ref.DPS):
        a_now = want['horizontal_tension'] / w
        y_crit = a_now * (mp.cosh(mp.mpf(x) / a_now) - 1)
    assert abs(r.tide_margin - float(y_crit - h)) <= REL * max(float(y_crit), h)


def test_near_minimum_distance_tiny_uplift():
    """x within a few ulps of x_min: uplift tiny, positive or zero, never NaN, never negative."""
    w, h, t = 1300.0, 20.85, 1623.5e3
    x_min = solve(w, h, tension=t).min_anchor_distance
    xs = x_min * (1 - np.array([0, 1e-16, 1e-15, 1e-12, 1e-9, 1e-6]))
    r = solve(w, h, tension=t, anchor_distance=xs)
    assert (r.status == 0).all() and np.isfinite(r.uplift_force).all()
    assert (r.uplift_force >= 0).all()
    assert np.all(np.diff(r.uplift_force) >= 0)  # more uplift as the anchor gets closer
    for xi, fi in zip(xs[3:], r.uplift_force[3:]):
        want = ref.uplift_from_tension(w, t, h, xi)['uplift_force']
        assert abs(fi - float(want)) <= 1e-8 * t  # absolute: the force itself is ~0


@pytest.mark.parametrize('frac', [1e-6, 1e-9])
def test_anchor_right_under_the_hook(frac):
    """Outside the stated domain (x << x_min) the solve still converges and stays accurate."""
    w, h, t = 1300.0, 20.85, 1623.5e3
    x = frac * solve(w, h, tension=t).min_anchor_distance
    r = solve(w, h, tension=t, anchor_distance=x)
    want = ref.uplift_from_tension(w, t, h, x)
    assert rel(r.uplift_force, want['uplift_force']) <= 1e-10
    assert rel(r.horizontal_tension, want['horizontal_tension']) <= 1e-10


@settings(max_examples=80, deadline=None)
@given(st.tuples(log_uniform(1e-1, 1e3), log_uniform(1e-3, 1e3), log_uniform(1e-6, 1e3)))
def test_problem5_chain_length(s):
    """Chain lying on the seabed: R and grounded length from the paid-out length.

    Scenes are built from a = R/w, h/a and the grounded length g/a. As Lm - x -> h the chain goes
    slack (R -> 0) and R becomes ill-conditioned in Lm: the bound is stated for h/a <= 1e3.
    """
    a, ha, ga = s
    h, g = ha * a, ga * a
    x_s = a * math.acosh(1 + ha)
    x, length = x_s + g, math.sqrt(h * h + 2 * a * h) + g
    r = solve(10.0, h, chain_length=length, anchor_distance=x)
    assert r.status == 0 and r.uplift_force == 0
    want = ref.grounded_from_length(10.0, h, length, x)
    assert rel(r.horizontal_tension, want['horizontal_tension']) <= REL
    assert abs(r.grounded_length - float(want['grounded_length'])) <= REL * length
