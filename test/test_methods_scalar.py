"""The optimised plain-float path gives the vectorized path's numbers (issue 5 speed work)."""

import math

import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics.solve import ALL_KEYS, SolveResult, Status


def scenes(n, seed=3, beyond=0.3):
    rng = np.random.default_rng(seed)
    w = 10.0 ** rng.uniform(1, 4, n)
    h = 10.0 ** rng.uniform(0, 3, n)
    t = w * (h / 10.0 ** rng.uniform(-9, 4, n) + h)
    x = cat.grounded(cat.two_prod_diff(t, w, h) / w, h).min_anchor_distance * 10.0 ** rng.uniform(
        -3, beyond, n
    )
    return w, h, t, x


def test_scalar_path_equals_vectorized_path():
    w, h, t, x = scenes(3000)
    vec = solve(w, h, tension=t, anchor_distance=x, mbl=5 * t)
    s, _, _ = cat.lifted_from_tension(
        *(np.atleast_1d(v) for v in (w, cat.two_prod_diff(t, w, h) / w, h, x))
    )
    for i in range(w.size):
        one = solve(
            float(w[i]),
            float(h[i]),
            tension=float(t[i]),
            anchor_distance=float(x[i]),
            mbl=float(5 * t[i]),
        )
        assert one.status == 0 and one.keys == vec.keys
        for k in (
            'horizontal_tension',
            'top_tension',
            'min_anchor_distance',
            'suspended_length',
            'top_angle_deg',
            'safety_factor',
        ):
            assert getattr(one, k) == pytest.approx(getattr(vec, k)[i], rel=2e-14, abs=0), k
        # differences of nearly equal terms (margins) and the uplift near x_min: a few ulps of
        # the larger term / of the anchor-end tension, as in the vectorized path itself
        scale = {
            'anchor_margin': max(x[i], vec.min_anchor_distance[i]),
            'tide_margin': h[i] + abs(vec.tide_margin[i]),
            'uplift_force': t[i],
            'anchor_angle_deg': 90.0,
            'load_margin': t[i] + abs(vec.load_margin[i]),
        }
        for k, sc in scale.items():
            assert abs(getattr(one, k) - getattr(vec, k)[i]) <= 2e-14 * sc, k


def test_fast_result_equals_constructed_result():
    r = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06, mbl=6.5e6)
    again = SolveResult(**{name: getattr(r, name) for name in SolveResult._fields})
    assert r == again and hash(r) == hash(again) and repr(r) == repr(again)
    assert r._replace(model='x').model == 'x'
    with pytest.raises(AttributeError):
        r.uplift_force = 0.0


@pytest.mark.parametrize('kind', [float, int, np.float64, np.float32, lambda v: np.array(v), bool])
def test_every_scalar_type_gives_the_same_answer(kind):
    args = (1300, 21, 1623500, 121) if kind in (int, bool) else (1300.0, 20.85, 1623.5e3, 121.06)
    if kind is bool:
        args = (True, True, 5.0, True)  # w = h = x = 1
    exact = [float(kind(a)) for a in args]  # what the input type holds (float32 rounds)
    if kind is bool:
        exact[2] = 5.0
    ref = solve(exact[0], exact[1], tension=exact[2], anchor_distance=exact[3])
    got = solve(
        *(kind(a) for a in args[:2]),
        tension=kind(args[2]) if kind is not bool else 5.0,
        anchor_distance=kind(args[3]),
    )
    assert got.status == ref.status == 0
    for k in ALL_KEYS:
        a, b = getattr(got, k), getattr(ref, k)
        assert (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=1e-15), k


def test_scalar_statuses_and_nan_rules():
    cases = {
        Status.NON_FINITE: (math.nan, 20.0, 1e6, 100.0),
        Status.WEIGHT: (0.0, 20.0, 1e6, 100.0),
        Status.DEPTH: (1300.0, -1.0, 1e6, 100.0),
        Status.TENSION: (1300.0, 20.0, 100.0, 100.0),
        Status.DISTANCE: (1300.0, 20.0, 1e6, -3.0),
    }
    for code, (w, h, t, x) in cases.items():
        r = solve(w, h, tension=t, anchor_distance=x)
        assert r.status == code and all(math.isnan(getattr(r, k)) for k in ALL_KEYS)
    r = solve(1300.0, 20.0, tension=1e6, mbl=-1.0)
    assert r.status == Status.MBL
    r = solve(1300.0, 20.85, tension=1623.5e3)  # no x: margins NaN, not in keys
    assert (
        'anchor_margin' not in r.keys
        and math.isnan(r.anchor_margin)
        and math.isnan(r.grounded_length)
    )
    assert r.uplift_force == 0.0 and r.anchor_angle_deg == 0.0


def test_lifted_scalar_kernel_matches_vectorized_kernel():
    w, h, t, x = scenes(5000, seed=9, beyond=0.0)
    b = cat.two_prod_diff(t, w, h) / w
    vec, it_v, ok_v = cat.lifted_from_tension(w, b, h, x)
    for i in range(0, 5000, 7):
        one, it, ok = cat.lifted_from_tension_scalar(w[i], b[i], h[i], x[i])
        assert ok and ok_v[i] and it_v[i] == max(it, cat.FAST_STEPS)  # vector: >= FAST_STEPS
        assert one.horizontal_tension == pytest.approx(vec.horizontal_tension[i], rel=1e-14)
        assert one.suspended_length == pytest.approx(vec.suspended_length[i], rel=1e-14)
        assert abs(one.uplift_force - vec.uplift_force[i]) <= 1e-14 * t[i]
    a_v, _ = cat.critical_parameter(h, x)
    for i in range(0, 5000, 7):
        assert cat.critical_parameter_scalar(h[i], x[i]) == pytest.approx(a_v[i], rel=1e-14)


def test_uplift_start_leaves_two_residuals_at_the_median():
    """The model-based start of the problem-4 Newton (``cat._uplift_setup``) is what makes the
    scalar solve fast: most scenes converge after 2 residuals, none needs more than 6."""
    w, h, t, x = scenes(4000, seed=11, beyond=0.0)
    b = cat.two_prod_diff(t, w, h) / w
    counts = np.array(
        [cat.lifted_from_tension_scalar(w[i], b[i], h[i], x[i])[1] for i in range(w.size)]
    )
    assert np.median(counts) <= 2 and np.mean(counts <= 3) >= 0.9 and counts.max() <= 6


@pytest.mark.parametrize('c', np.geomspace(1e-4, 5e9, 301))
def test_load_margin_start_converges_in_one_residual(c, monkeypatch):
    """The Hermite table (0.02 <= h/x <= 7e9) and the series below it start within STEP_TOL:
    the first Newton residual already converges."""
    full = cat.critical_parameter_scalar(c * 40.0, 40.0)
    monkeypatch.setattr(cat, 'MAXITER', 1)
    assert cat.critical_parameter_scalar(c * 40.0, 40.0) == pytest.approx(full, rel=1e-15)
    monkeypatch.setattr(cat, 'MAXITER', 0)
    assert math.isnan(
        cat.critical_parameter_scalar(c * 40.0, 40.0)
    )  # not converged: NaN, not a guess


def test_load_margin_no_convergence_is_reported(monkeypatch):
    monkeypatch.setattr(cat, 'MAXITER', 0)
    one = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=300.0)
    arr = solve(1300.0, 20.85, tension=[1623.5e3], anchor_distance=[300.0])
    assert one.status == arr.status[0] == Status.NO_CONVERGENCE
    assert math.isnan(one.load_margin) and math.isnan(arr.load_margin[0])


def test_scalar_horizontal_path_equals_vectorized_path():
    """Problems 1 and 2 (R given) take the plain-float path too, with the array path's numbers."""
    w, h, t, x = scenes(2000, seed=5)
    r = cat.two_prod_diff(t, w, h)  # R = w a for a no-uplift chain at that tension
    vec = solve(w, h, horizontal=r, anchor_distance=x, mbl=5 * t)
    assert (vec.status == 0).all() and (vec.uplift_force > 0).sum() > 500
    for i in range(w.size):
        one = solve(
            float(w[i]),
            float(h[i]),
            horizontal=float(r[i]),
            anchor_distance=float(x[i]),
            mbl=float(5 * t[i]),
        )
        assert one.status == 0 and one.keys == vec.keys and one.problem == 'horizontal'
        for k in (
            'horizontal_tension',
            'top_tension',
            'min_anchor_distance',
            'suspended_length',
            'top_angle_deg',
            'safety_factor',
        ):
            assert getattr(one, k) == pytest.approx(getattr(vec, k)[i], rel=2e-14, abs=0), k
        scale = {
            'anchor_margin': max(x[i], vec.min_anchor_distance[i]),
            'tide_margin': h[i] + abs(vec.tide_margin[i]),
            'uplift_force': vec.top_tension[i],
            'anchor_angle_deg': 90.0,
            'load_margin': vec.top_tension[i] + abs(vec.load_margin[i]),
        }
        for k, sc in scale.items():
            assert abs(getattr(one, k) - getattr(vec, k)[i]) <= 2e-14 * sc, k
    for bad, code in (
        (0.0, Status.HORIZONTAL),
        (-5.0, Status.HORIZONTAL),
        (math.nan, Status.NON_FINITE),
    ):
        one = solve(1300.0, 20.0, horizontal=bad, anchor_distance=100.0)
        assert one.status == code and math.isnan(one.uplift_force)
