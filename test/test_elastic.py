"""The elastic chain: limit, equations, an independent peer, and the model-picking rule."""

import math
import warnings

import mpmath as mp
import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core.physics import catenary as cat
from catenary_monitor.core.physics import elastic

EA_DOCK = 1.01e8 * 0.081**2 * 1e3  # U3 studlink 81 mm, N


def scenes(n, seed=3):
    rng = np.random.default_rng(seed)
    w = 10.0 ** rng.uniform(1, 4, n)
    h = 10.0 ** rng.uniform(0, 3, n)
    t = w * (h / 10.0 ** rng.uniform(-6, 3, n) + h)
    b = cat.two_prod_diff(t, w, h) / w
    x = cat.grounded(b, h).min_anchor_distance * 10.0 ** rng.uniform(-3, 0, n)
    return w, h, t, x


def test_infinitely_stiff_is_the_inextensible_catenary():
    w, h, t, x = scenes(2000)
    rigid = solve(w, h, tension=t, anchor_distance=x)
    el = elastic.elastic_state(w, h, t, x, 1e40)
    for key in ('horizontal_tension', 'min_anchor_distance', 'uplift_force', 'suspended_length'):
        ref = getattr(rigid, key)
        assert np.all(
            np.abs(el[key] - ref) <= 1e-12 * np.abs(ref) + 1e-12 * t * (key == 'uplift_force')
        ), key


def _mp_elastic(w, h, t, x, ea, stretched=False):
    """Irvine's equations solved in 50 digits: (R, V_A, L0, x_min), anchor lifted when x < x_min.

    With ``stretched``, also the stretched suspended length, L0 plus the integral of T/EA by
    quadrature.
    """
    with mp.workdps(50):
        w, h, t, ea = (mp.mpf(float(v)) for v in (w, h, t, ea))
        s = 1 + t / ea
        d = ea * (s - mp.sqrt(s * s - 2 * h * w / ea))  # h w = D (1 + (2T - D)/(2 EA))
        ta = t - d

        def state(u):
            r = ta / mp.cosh(u)
            va, vb = ta * mp.tanh(u), mp.sqrt(t * t - r * r)
            l0 = (vb - va) / w
            span = r / w * (mp.asinh(vb / r) - mp.asinh(va / r)) + r * l0 / ea
            depth = (t - mp.sqrt(r * r + va * va)) / w + (vb * vb - va * va) / (2 * ea * w)
            assert abs(depth - h) <= mp.mpf(10) ** -30 * h
            return r, va, l0, span

        def out(u):
            r, va, l0, _ = state(u)
            res = (float(r), float(va), float(l0), float(x_min))
            if not stretched:
                return res
            vb = va + w * l0  # ds = dV / w, T = sqrt(R^2 + V^2)
            return res + (
                float(l0 + mp.quad(lambda v: mp.sqrt(r * r + v * v), [va, vb]) / (ea * w)),
            )

        x_min = state(mp.mpf(0))[3]
        if x is None or x >= x_min:
            return out(mp.mpf(0))
        x = mp.mpf(float(x))
        lo, hi = mp.mpf(0), mp.mpf(1)
        while state(hi)[3] > x:
            lo, hi = hi, 2 * hi
        for _ in range(200):
            mid = (lo + hi) / 2
            if state(mid)[3] > x:
                lo = mid
            else:
                hi = mid
        return out((lo + hi) / 2)


@pytest.mark.parametrize('strain', [1e-9, 1e-5, 2.5e-3, 0.05])
def test_elastic_solution_matches_50_digit_solution(strain):
    w, h, t, x = scenes(12, seed=int(-math.log10(strain) * 10))
    ea = t / strain
    st = elastic.elastic_state(w, h, t, x, ea)
    assert np.all(st['uplift_force'] > 0)
    eps = np.finfo(float).eps
    for i in range(12):
        r, va, l0, x_min = _mp_elastic(w[i], h[i], t[i], x[i], ea[i])
        r2, va2, l02, _ = _mp_elastic(w[i], h[i], t[i], x[i] * (1 + 1e-9), ea[i])
        kappa_f = abs((va2 - va) / va / 1e-9)  # condition number of the uplift (to ~1e-6)
        kappa_l = abs((l02 - l0) / l0 / 1e-9)
        assert st['horizontal_tension'][i] == pytest.approx(r, rel=1e-12)
        assert st['min_anchor_distance'][i] == pytest.approx(x_min, rel=1e-12)
        assert abs(st['uplift_force'][i] - va) <= (1e-12 + 8 * eps * kappa_f) * va
        assert abs(st['unstretched_length'][i] - l0) <= (1e-12 + 8 * eps * kappa_l) * l0


def test_elastic_uplift_between_the_rigid_and_the_elastic_lift_off_distance():
    """x beyond the rigid lift-off distance (same end tensions) but short of the elastic one."""
    w, h, t = 1300.0, 20.85, 1623.5e3
    ta, d = elastic.anchor_end_tension(w, h, t, EA_DOCK)
    x_rigid = float(ta / w * np.arcsinh(np.sqrt(d * (t + ta)) / ta))
    x_el = float(elastic.elastic_state(w, h, t, None, EA_DOCK)['min_anchor_distance'])
    for x in (x_rigid + 0.5 * (x_el - x_rigid), x_el * (1 - 1e-9), x_el * 1e-4):
        st = elastic.elastic_state(w, h, t, x, EA_DOCK)
        r, va, l0, _ = _mp_elastic(w, h, t, x, EA_DOCK)
        assert float(st['horizontal_tension']) == pytest.approx(r, rel=1e-12)
        assert abs(float(st['uplift_force']) - va) <= 1e-11 * t


def test_elastic_min_distance_closed_form_matches_50_digit_solution():
    w, h, t, _ = scenes(40, seed=11)
    ea = t / 1e-3
    st = elastic.elastic_state(w, h, t, None, ea)
    assert np.all(st['uplift_force'] == 0)
    for i in range(40):
        r, _, l0, x_min = _mp_elastic(w[i], h[i], t[i], None, ea[i])
        assert st['min_anchor_distance'][i] == pytest.approx(x_min, rel=1e-12)
        assert st['horizontal_tension'][i] == pytest.approx(r, rel=1e-12)
        assert st['unstretched_length'][i] == pytest.approx(l0, rel=1e-12)


def test_agrees_with_moorpy_for_the_dock_chain():
    """MoorPy's elastic catenary, given our unstretched length and EA, gives our tensions
    (to its 1e-6 m)."""
    import os

    from moorpy.Catenary import catenary  # in the test extra: this check always runs

    os.environ.setdefault('PYTHONBREAKPOINT', '0')
    w, h, t, x = 1300.0, 20.85, 1623.5e3, 121.06
    st = {k: float(v) for k, v in elastic.elastic_state(w, h, t, x, EA_DOCK).items()}
    fah, fav, fbh, fbv, _ = catenary(x, h, st['unstretched_length'], EA_DOCK, w)
    assert fah == pytest.approx(st['horizontal_tension'], rel=1e-6)
    assert fav == pytest.approx(st['uplift_force'], rel=1e-5)
    assert math.hypot(fbh, fbv) == pytest.approx(t, rel=1e-6)


def test_rule_picks_the_elastic_model_for_the_dock_chain():
    res, corr = elastic.solve_with_correction(1300.0, 20.85, 1623.5e3, 121.06, ea=EA_DOCK)
    assert res.model == elastic.ELASTIC and corr > 1e-3
    rigid = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06)
    assert rigid.model == elastic.INEXTENSIBLE
    # the dock chain stretches 2.4e-3: x_min moves by ~0.28 m, the uplift by ~0.2 kN
    assert 0.2 < res.min_anchor_distance - rigid.min_anchor_distance < 0.4
    assert 100.0 < res.uplift_force - rigid.uplift_force < 400.0
    assert res.anchor_margin == pytest.approx(121.06 - res.min_anchor_distance, rel=1e-15)


def test_rule_keeps_the_inextensible_model_when_the_correction_is_below_tol():
    res, corr = elastic.solve_with_correction(1300.0, 20.85, 1623.5e3, 121.06, ea=1e18)
    assert res.model == elastic.INEXTENSIBLE and corr <= elastic.ELASTIC_TOL
    rigid = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06)
    assert res.uplift_force == rigid.uplift_force and res.load_margin == rigid.load_margin
    # the same scene with a looser tolerance keeps the rigid answer even for the real chain
    res, corr = elastic.solve_with_correction(
        1300.0, 20.85, 1623.5e3, 121.06, ea=EA_DOCK, tol=1e-2
    )
    assert res.model == elastic.INEXTENSIBLE and 1e-3 < corr < 1e-2


def test_rule_element_by_element_and_invalid_elements():
    t = np.array([1623.5e3, 1623.5e3, 10.0])  # the last: T <= w h, invalid
    ea = np.array([EA_DOCK, 1e18, EA_DOCK])
    res, corr = elastic.solve_with_correction(1300.0, 20.85, t, 121.06, ea=ea)
    assert list(res.model) == [elastic.ELASTIC, elastic.INEXTENSIBLE, elastic.INEXTENSIBLE]
    assert list(res.status) == [0, 0, 4]
    assert np.isnan(res.uplift_force[2]) and np.isfinite(res.uplift_force[:2]).all()
    assert corr[2] == 0.0


def test_elastic_margins_are_consistent():
    """load margin: at T + load_margin the elastic x_min equals x; tide margin: depth reach - h."""
    w, h, x = 1300.0, 20.85, 240.0
    res, _ = elastic.solve_with_correction(w, h, 1623.5e3, x, ea=EA_DOCK)
    assert res.uplift_force == 0.0 and res.anchor_margin > 0
    t_crit = 1623.5e3 + res.load_margin
    x_min_crit = float(elastic.elastic_state(w, h, t_crit, None, EA_DOCK)['min_anchor_distance'])
    assert x_min_crit == pytest.approx(x, rel=1e-12)
    # tide margin: the no-uplift chain with the same R at depth h + tide_margin spans exactly x
    r, h2 = res.horizontal_tension, h + res.tide_margin
    s = 1 + r / EA_DOCK
    d = 2 * h2 * w / (s + math.sqrt(s * s + 2 * h2 * w / EA_DOCK))  # h2 w = D (1 + (2R + D)/(2EA))
    st = elastic.elastic_state(w, h2, r + d, None, EA_DOCK)
    assert res.tide_margin > 0
    assert float(st['horizontal_tension']) == pytest.approx(r, rel=1e-12)
    assert float(st['min_anchor_distance']) == pytest.approx(x, rel=1e-11)


def test_report_lines_and_magnitudes():
    rows = {r['line'].split(',')[0]: r for r in elastic.report()}
    chain, wire, poly = (
        rows['U3 studlink chain'],
        rows['six-strand steel wire'],
        rows['polyester rope'],
    )
    assert 1e-3 < chain['dx_min_rel'] < 2e-3
    assert wire['strain'] > chain['strain'] and poly['strain'] > wire['strain']
    for r in rows.values():  # elasticity moves the answers by far more than the solver's 1e-15
        assert abs(r['dx_min_rel']) > 1e-6 and abs(r['duplift_over_t']) > 1e-6


def test_bad_arguments():
    with pytest.raises(ValueError, match='ea'):
        elastic.solve_with_correction(1300.0, 20.85, 1623.5e3, 121.06, ea=-1.0)
    with pytest.raises(ValueError, match='tol'):
        elastic.solve_with_correction(1300.0, 20.85, 1623.5e3, 121.06, ea=1e9, tol=-1.0)
    res, corr = elastic.solve_with_correction(1300.0, 20.85, 1623.5e3, 121.06)
    assert res.model == elastic.INEXTENSIBLE and corr == 0.0


def test_elastic_load_margin_matches_50_digit_solution_also_below_w_h():
    """At T + load_margin the 50-digit elastic x_min is x, also where that tension is below w h
    (a stretched chain reaches the depth with less than its weight; the rigid one cannot)."""
    w, h, t, x = scenes(60, seed=5)
    ea = t / 10.0 ** np.random.default_rng(6).uniform(-6, math.log10(5e-2), 60)
    res, _ = elastic.solve_with_correction(w, h, t, x, ea=ea)
    elastic_rows = np.flatnonzero(res.model == elastic.ELASTIC)
    t_crit = t + res.load_margin
    assert np.any(t_crit[elastic_rows] < w[elastic_rows] * h[elastic_rows])
    for i in elastic_rows:
        x_min = _mp_elastic(w[i], h[i], t_crit[i], None, ea[i])[3]
        x_min2 = _mp_elastic(w[i], h[i], t_crit[i] * (1 + 1e-9), None, ea[i])[3]
        kappa = abs((x_min2 - x_min) / x_min / 1e-9)  # d log x_min / d log T (to ~1e-6)
        cancel = (t[i] + abs(res.load_margin[i])) / t_crit[i]  # T + margin rounds relative to T
        assert abs(x_min - x[i]) <= (1e-13 + 4 * np.finfo(float).eps * kappa * cancel) * x[i]


def _random_elastic_scenes(n, seed):
    """Lifted and grounded scenes (x from 1e-3 to 3 rigid x_min), strain T/EA from 1e-6 to 5e-2."""
    w, h, t, _ = scenes(n, seed=seed)
    rng = np.random.default_rng(seed + 100)
    b = cat.two_prod_diff(t, w, h) / w
    x = cat.grounded(b, h).min_anchor_distance * 10.0 ** rng.uniform(-3, 0.5, n)
    ea = t / 10.0 ** rng.uniform(-6, math.log10(5e-2), n)
    return w, h, t, x, ea


# relative scale of each key's rounding: itself, or what it is a margin / component of
_SCALE = {'uplift_force': 't', 'load_margin': 't', 'anchor_margin': 'x', 'tide_margin': 'h'}


def _dock_scenes_near_lift_off():
    """The dock chain with x between the rigid and the elastic lift-off distance (same end
    tensions), where the uplift solve cannot start from the rigid chain, and just short of both."""
    w, h, t = 1300.0, 20.85, 1623.5e3
    ta, d = elastic.anchor_end_tension(w, h, t, EA_DOCK)
    x_rigid = float(ta / w * np.arcsinh(np.sqrt(d * (t + ta)) / ta))
    x_el = float(elastic.elastic_state(w, h, t, None, EA_DOCK)['min_anchor_distance'])
    x = np.array(
        [x_rigid + f * (x_el - x_rigid) for f in (1e-3, 0.5, 1 - 1e-6)] + [x_rigid * (1 - 1e-6)]
    )
    return np.full(4, w), np.full(4, h), np.full(4, t), x, np.full(4, EA_DOCK)


@pytest.mark.parametrize('with_x', [True, False])
def test_scalar_path_matches_the_arrays(with_x):
    """Plain-float scalar calls give the vectorized results to rounding, model and correction
    included."""
    random = _random_elastic_scenes(300, seed=21 if with_x else 22)
    w, h, t, x, ea = (np.concatenate(v) for v in zip(random, _dock_scenes_near_lift_off()))
    n = w.size
    mbl = 3.0 * t
    res, corr = elastic.solve_with_correction(w, h, t, x if with_x else None, ea=ea, mbl=mbl)
    assert {elastic.ELASTIC, elastic.INEXTENSIBLE} <= set(res.model)
    if with_x:
        lifted = res.uplift_force > 0
        assert 0.2 < lifted.mean() < 0.9 and np.any(lifted & (res.model == elastic.ELASTIC))
    for i in range(n):
        one, c = elastic.solve_with_correction(
            float(w[i]),
            float(h[i]),
            float(t[i]),
            float(x[i]) if with_x else None,
            ea=float(ea[i]),
            mbl=float(mbl[i]),
        )
        assert type(c) is float and type(one.model) is str and one.keys == res.keys
        assert abs(c - corr[i]) <= 1e-13  # a relative change: its rounding is absolute
        if abs(corr[i] - elastic.ELASTIC_TOL) > 1e-12:
            assert one.model == res.model[i]
        assert one.status == res.status[i] == 0
        scale = {'t': t[i], 'x': x[i], 'h': h[i]}
        for key in one.keys:
            got, ref = getattr(one, key), getattr(res, key)[i]
            assert type(got) is float, key
            tol = 1e-13 * max(
                abs(ref), scale.get(_SCALE.get(key), 0.0), 90.0 if key.endswith('_deg') else 0.0
            )
            assert abs(got - ref) <= tol, (i, key, got, ref)


def test_scalar_path_public_behaviour(monkeypatch):
    """Errors, invalid elements, int inputs and the array fallback are those of the array path."""
    args = (1300.0, 20.85, 1623.5e3, 121.06)
    for bad in (-1.0, 0.0, 0, math.nan, np.float64(-2.0)):
        with pytest.raises(ValueError, match='ea'):
            elastic.solve_with_correction(*args, ea=bad)
    with pytest.raises(ValueError, match='tol'):
        elastic.solve_with_correction(*args, ea=EA_DOCK, tol=-1.0)
    res, corr = elastic.solve_with_correction(1300.0, 20.85, 10.0, 121.06, ea=EA_DOCK)  # T <= w h
    ref = solve(1300.0, 20.85, tension=10.0, anchor_distance=121.06)
    assert res.status == ref.status == 4 and corr == 0.0 and res.model == elastic.INEXTENSIBLE
    assert all(math.isnan(getattr(res, k)) for k in res.keys)
    res_int, corr_int = elastic.solve_with_correction(1300, 21, 1623500, 121, ea=int(EA_DOCK))
    res_f, corr_f = elastic.solve_with_correction(
        1300.0, 21.0, 1623500.0, 121.0, ea=float(int(EA_DOCK))
    )
    assert res_int == res_f and corr_int == corr_f
    scalar, c1 = elastic.solve_with_correction(*args, ea=EA_DOCK, mbl=4.8e6)
    arrays, c2 = elastic.solve_with_correction(
        *(np.array([v]) for v in args), ea=np.array([EA_DOCK]), mbl=np.array([4.8e6])
    )
    assert scalar.to_dict() == pytest.approx(
        {k: v[0] for k, v in arrays.to_dict().items()}, rel=1e-13
    )
    assert c1 == pytest.approx(c2[0], rel=1e-12)

    def overflow(*_):
        raise OverflowError('math range error')

    monkeypatch.setattr(
        elastic, '_solve_scalar', overflow
    )  # plain math out of range: numpy answers
    fallback, c3 = elastic.solve_with_correction(*args, ea=EA_DOCK, mbl=4.8e6)
    assert (
        type(fallback.uplift_force) is float and type(fallback.model) is str and type(c3) is float
    )
    assert fallback.to_dict() == pytest.approx(
        scalar.to_dict(), rel=1e-13
    ) and c3 == pytest.approx(c1, rel=1e-12)


def test_stretched_length_matches_50_digit_solution_also_for_nearly_straight_chains():
    """The stretch is a sum of positive terms: full accuracy where V_A ~ V_B (T >> w h)."""
    w, h, t, x, ea = _random_elastic_scenes(40, seed=23)
    t = w * h * 10.0 ** np.linspace(0.01, 6, 40)  # up to nearly straight chains
    x = np.minimum(
        x, 0.9 * elastic.elastic_state(w, h, t, None, ea)['min_anchor_distance']
    )  # all lifted
    st = elastic.elastic_state(w, h, t, x, ea)
    for i in range(40):
        *_, length = _mp_elastic(w[i], h[i], t[i], x[i], ea[i], stretched=True)
        assert st['suspended_length'][i] == pytest.approx(length, rel=1e-14)


def test_uplift_solve_closes_its_bracket(monkeypatch):
    """Residual count of the uplift solve: once regula falsi reaches the root from one side the
    bracket closes (it used to stall there and bisect ~40 more times; up to 53 residuals)."""
    w, h, t, x, ea = _random_elastic_scenes(400, seed=24)
    calls = []
    span = elastic._span
    monkeypatch.setattr(elastic, '_span', lambda *a: calls.append(1) or span(*a))
    counts = []
    for i in range(400):
        calls.clear()
        r, _, va, *_ = elastic._elastic_state_scalar(*(float(v[i]) for v in (w, h, t, x, ea)))
        if va > 0:
            counts.append(len(calls))
    assert len(counts) > 200 and max(counts) <= 30 and np.mean(counts) < 10


def test_solve_with_ea_is_the_elastic_model_through_the_one_entry():
    """``catenary_monitor.solve(..., ea=EA)`` returns the elastic rule's result itself."""
    direct, _ = elastic.solve_with_correction(
        1300.0, 20.85, 1623.5e3, 121.06, ea=EA_DOCK, mbl=4.8e6
    )
    one = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06, mbl=4.8e6, ea=EA_DOCK)
    assert one == direct and one.model == elastic.ELASTIC
    stiff = solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06, ea=math.inf)
    assert stiff.model == elastic.INEXTENSIBLE
    assert stiff == solve(1300.0, 20.85, tension=1623.5e3, anchor_distance=121.06)
    with pytest.raises(ValueError, match='measured hook tension'):
        solve(1300.0, 20.85, horizontal=1.5e6, ea=EA_DOCK)


def _depth_reach_50(w, r, x, ea):
    """Depth a no-uplift elastic chain of horizontal tension R spans over x, 50 digits:
    x = a nu + a k sinh(nu), depth = 2 a sinh(nu/2)^2 + a k sinh(nu)^2 / 2 (a = R/w, k = R/EA)."""
    with mp.workdps(50):
        w, r, x, ea = (mp.mpf(v) for v in (w, r, x, ea))
        a, k = r / w, r / ea
        lo, hi = mp.mpf(0), min(x / a, mp.asinh(x / (a * k)))  # the root lies below both
        for _ in range(400):
            mid = (lo + hi) / 2
            lo, hi = (lo, mid) if a * mid + a * k * mp.sinh(mid) > x else (mid, hi)
        nu = (lo + hi) / 2
        return 2 * a * mp.sinh(nu / 2) ** 2 + a * k * mp.sinh(nu) ** 2 / 2


@pytest.mark.parametrize('tension_over_wh', [1.01, 1.000001])
@pytest.mark.parametrize('ea', [1e7, EA_DOCK, 1e12])
def test_nearly_slack_chain_tide_margin_is_finite_and_silent(tension_over_wh, ea):
    """A nearly slack grounded chain (x/a ~ 500 and beyond): the tide margin is the finite depth
    the elastic chain reaches (its stretch bounds sinh(nu) by x/(a k)), with no numpy warning;
    Newton from x/a once crept down ~1 a step, stopped at 100 steps and squared sinh(~475) into
    +inf with 'overflow encountered in square'."""
    w, h, x = 1300.0, 20.85, 120.0
    t = tension_over_wh * w * h
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        one = solve(w, h, tension=t, anchor_distance=x, ea=ea)
        arr = solve(np.full(2, w), h, tension=np.full(2, t), anchor_distance=x, ea=ea)
        direct = elastic._elastic_depth_reach(*(np.array([v]) for v in (w, 271.05, x, ea)))
    want = _depth_reach_50(w, 271.05, x, ea)
    assert math.isfinite(direct[0]) and abs(direct[0] - want) <= 1e-12 * want
    for r in (one, arr):
        assert np.all(r.status == 0) and np.all(r.model == elastic.ELASTIC)
        r_now, tide = float(np.ravel(r.horizontal_tension)[0]), float(np.ravel(r.tide_margin)[0])
        want = _depth_reach_50(w, r_now, x, ea) - h
        assert math.isfinite(tide) and abs(tide - want) <= 1e-12 * want, (tide, want)


def test_elastic_depth_beyond_float64_is_inf_without_a_warning():
    w, r, x, ea = 1300.0, 271.05, 1e200, 1e9
    assert _depth_reach_50(w, r, x, ea) > np.finfo(float).max
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        got = elastic._elastic_depth_reach(*(np.array([v]) for v in (w, r, x, ea)))
    assert got[0] == math.inf
    assert elastic._elastic_depth_reach_scalar(w, r, x, ea) == math.inf


def test_depth_reach_of_an_infinitely_stiff_chain_is_the_rigid_one_without_a_warning():
    """EA = inf (replay's inextensible lines): k = 0, no stretch bound on the start."""
    w, r, x = 1300.0, 1.58e6, 121.06
    rigid = float(cat.depth_reached(r / w, x))
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        got = elastic._elastic_depth_reach(*(np.array([v]) for v in (w, r, x, math.inf)))
        assert elastic._elastic_depth_reach_scalar(w, r, x, math.inf) == pytest.approx(rigid)
    assert got[0] == pytest.approx(rigid, rel=1e-14)
