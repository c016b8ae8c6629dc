"""The default method never fails and stays within 1e-12 over 1e5 seeded random scenes (issue 5).

Scenes of the physical domain: anchor-end parameter ``h/a`` log-uniform in [1e-9, 1e4], anchor
distance ``x/x_min`` log-uniform in [1e-3, 1], depth 1-1000 m, chain weight 10 N/m-10 kN/m.
Checked three ways: every element solved (status 0, finite); all 1e5 against an independent
cross-check formulation in extended precision; a subset against the 50-digit mpmath solution of
the paper's equations.

The cross-check iterates on a different unknown (u, with ``tan(alpha) = sinh(u)``), uses a
different equation (``x/B = sech(u) [acosh((1+e) cosh u) - u]``, the difference of acosh written
as one ``log1p`` of positive terms) and runs in numpy ``longdouble`` (64-bit mantissa here).

Tolerance: 1e-12 relative, plus ``8 eps kappa`` where the problem itself is ill-conditioned
(``kappa = |x/F dF/dx|`` of the uplift force as x -> x_min), the bound the README states.
"""

import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core.physics import catenary as cat
from catenary_monitor_study.methods import reference

N = 100_000
EPS = np.finfo(float).eps
LD = np.longdouble


def random_scenes(n: int, seed: int = 20261123):
    rng = np.random.default_rng(seed)
    w = 10.0 ** rng.uniform(1, 4, n)
    h = 10.0 ** rng.uniform(0, 3, n)
    ha = 10.0 ** rng.uniform(-9, 4, n)
    t = w * (h / ha + h)
    b = cat.two_prod_diff(t, w, h) / w
    x = cat.grounded(b, h).min_anchor_distance * 10.0 ** rng.uniform(-3, 0, n)
    return w, h, t, x


def _x_over_b(u, e):
    """``sech(u) [acosh(p) - acosh(c)]``, ``c = cosh u``, ``p = (1+e) c``, without cancellation."""
    c, s = np.cosh(u), np.sinh(u)
    p = (1 + e) * c
    pm1 = 2 * np.sinh(u / 2) ** 2 + e * c  # p - 1
    sp = np.sqrt(pm1 * (p + 1))  # sqrt(p^2 - 1)
    num = e * c + e * c * c * (2 + e) / (sp + s)  # (p - c) + (sqrt(p^2-1) - sinh u)
    return np.log1p(num / (c + s)) / c


def cross_check(w, h, t, x):
    """R, F and their condition numbers from the u formulation in long double (vectorized)."""
    w, h, t, x = (np.asarray(v, dtype=LD) for v in (w, h, t, x))
    b = t / w - h
    e = h / b
    target = x / b
    lo = np.full(b.shape, LD(-70))  # bisection on log(u): u in [e^-70, e^4.2]
    hi = np.full(b.shape, LD(4.2))
    for _ in range(80):
        mid = (lo + hi) / 2
        above = _x_over_b(np.exp(mid), e) > target  # x(u) decreases with u
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    u = np.exp((lo + hi) / 2)
    du = u * LD(1e-6)
    dxdu = b * (_x_over_b(u + du, e) - _x_over_b(u - du, e)) / (2 * du)
    r, f = w * b / np.cosh(u), w * b * np.tanh(u)
    kappa_f = np.abs(x / f * (w * b / np.cosh(u) ** 2) / dxdu)
    kappa_r = np.abs(x / r * (-r * np.tanh(u)) / dxdu)
    return (r.astype(float), f.astype(float), kappa_r.astype(float), kappa_f.astype(float))


#: numpy's longdouble carries a 64-bit mantissa on x86-64 Linux; elsewhere it may be plain double.
EXTENDED = np.finfo(LD).eps < 1e-18


@pytest.fixture(scope='module')
def solved():
    w, h, t, x = random_scenes(N)
    res = solve(w, h, tension=t, anchor_distance=x)
    return (w, h, t, x), res


def test_default_never_fails(solved):
    _, res = solved
    assert np.all(res.status == 0)
    for key in (
        'horizontal_tension',
        'uplift_force',
        'anchor_angle_deg',
        'suspended_length',
        'min_anchor_distance',
        'top_angle_deg',
    ):
        assert np.all(np.isfinite(getattr(res, key))), key
    assert np.all(res.uplift_force > 0)  # every scene has x < x_min: the anchor is lifted


def test_default_within_1e12_of_cross_check_on_all_scenes(solved):
    (w, h, t, x), res = solved
    if not EXTENDED:  # no extended precision here: check a seeded subset against mpmath instead
        for i in np.random.default_rng(11).choice(N, 300, replace=False):
            ref = reference.problem4(w[i], h[i], t[i], x[i])
            assert abs(res.horizontal_tension[i] - ref.v1) <= (1e-12 + 8 * EPS * ref.c1) * ref.v1
            assert abs(res.uplift_force[i] - ref.v2) <= (1e-12 + 8 * EPS * ref.c2) * ref.v2
        return
    r, f, kr, kf = cross_check(w, h, t, x)
    err_r = np.abs(res.horizontal_tension - r) / r
    err_f = np.abs(res.uplift_force - f) / f
    assert np.all(err_r <= 1e-12 + 8 * EPS * kr), err_r.max()
    assert np.all(err_f <= 1e-12 + 8 * EPS * kf), (err_f / (1e-12 + 8 * EPS * kf)).max()
    well = kf < 1e3  # where the problem is well-conditioned the plain 1e-12 holds
    assert well.mean() > 0.9 and np.all(err_f[well] <= 1e-12)


def test_cross_check_agrees_with_mpmath_and_default_too(solved):
    """On a subset: the 50-digit reference, the cross-check (extended precision), the default."""
    (w, h, t, x), res = solved
    idx = np.random.default_rng(7).choice(N, 40, replace=False)
    r, f, kr, kf = cross_check(w[idx], h[idx], t[idx], x[idx])
    for j, i in enumerate(idx):
        ref = reference.problem4(w[i], h[i], t[i], x[i])
        tol_r, tol_f = 1e-12 + 8 * EPS * ref.c1, 1e-12 + 8 * EPS * ref.c2
        assert abs(res.horizontal_tension[i] - ref.v1) <= tol_r * ref.v1
        assert abs(res.uplift_force[i] - ref.v2) <= tol_f * ref.v2
        if EXTENDED:
            assert abs(r[j] - ref.v1) <= 1e-13 * ref.v1 * max(1, ref.c1)
            assert abs(f[j] - ref.v2) <= 1e-13 * ref.v2 * max(1, ref.c2)
            assert kf[j] == pytest.approx(ref.c2, rel=1e-3, abs=1e-6)


def test_default_problem3_on_random_scenes_subset():
    w, h, t, _ = random_scenes(2000, seed=5)
    res = solve(w, h, tension=t)
    assert np.all(res.status == 0)
    for i in range(0, 2000, 50):
        ref = reference.problem3(w[i], h[i], t[i])
        assert abs(res.horizontal_tension[i] - ref.v1) <= 1e-12 * ref.v1
        assert abs(res.min_anchor_distance[i] - ref.v2) <= 1e-12 * ref.v2
