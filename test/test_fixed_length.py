"""core.physics.fixed_length: the fixed-length chain at a span (the dock model's line, problem 5
with EA), against the core's problem 5, 40-digit mpmath and MoorPy; its stiffness against
differences."""

import math
import os

import mpmath as mp
import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core.physics import fixed_length as fl
from catenary_monitor.core.physics.fixed_length import LineRegime
from catenary_monitor.core.physics.result import Status

W, H = 1300.0, 20.85
L = 122.8915  # the paper's table-3 chain (suspended length at the typhoon load)
EA = 6.63e8  # U3 81 mm, ~1.01e8 d^2 kN


def _spans(length, h):
    slack, taut = length - h, math.sqrt(length * length - h * h)
    return np.concatenate([np.linspace(slack + 0.05, taut - 1e-3, 40), [taut - 1e-6, taut - 1e-9]])


def test_inextensible_matches_the_core_problem_5():
    for h in (H, 21.85, 5.0):
        s = _spans(L, h)
        st = fl.statics_at_span(W, h, L, s)
        ref = solve(W, h, chain_length=L, anchor_distance=s)
        assert (ref.status == 0).all()
        for key in ('horizontal_tension', 'top_tension', 'uplift_force', 'grounded_length'):
            np.testing.assert_allclose(
                getattr(st, key), getattr(ref, key), rtol=1e-11, err_msg=key
            )
        assert set(st.regime.tolist()) == {LineRegime.GROUNDED, LineRegime.LIFTED}


def test_regimes_slack_and_taut():
    st = fl.statics_at_span(W, H, L, [L - H - 1.0, L, 130.0])
    assert st.regime.tolist() == [LineRegime.SLACK, LineRegime.TAUT, LineRegime.TAUT]
    assert st.horizontal_tension[0] == 0.0 and st.top_tension[0] == pytest.approx(W * H)
    assert math.isinf(st.horizontal_tension[1])
    bad = fl.statics_at_span([W, -1.0, W], [H, H, 30.0], [L, L, 20.0], [110.0, 110.0, 10.0])
    assert bad.regime.tolist() == [LineRegime.GROUNDED, LineRegime.INVALID, LineRegime.INVALID]


def _mp_elastic(w, h, length, s, ea, h0, v0):
    """(H, V) of the elastic fixed-length chain (no seabed friction), 40 digits."""
    mp.mp.dps = 40
    w, h, length, s, ea = (mp.mpf(x) for x in (w, h, length, s, ea))

    def equations(hh, vv):
        va = vv - w * length
        if va <= 0:
            x = length - vv / w + hh / w * mp.asinh(vv / hh) + hh * length / ea
            z = hh / w * (mp.sqrt(1 + (vv / hh) ** 2) - 1) + vv**2 / (2 * ea * w)
        else:
            x = hh / w * (mp.asinh(vv / hh) - mp.asinh(va / hh)) + hh * length / ea
            z = (
                hh / w * (mp.sqrt(1 + (vv / hh) ** 2) - mp.sqrt(1 + (va / hh) ** 2))
                + (vv * length - w * length**2 / 2) / ea
            )
        return [x - s, z - h]

    root = mp.findroot(equations, (mp.mpf(h0), mp.mpf(v0)), tol=mp.mpf(10) ** -30)
    return float(root[0]), float(root[1])


@pytest.mark.parametrize('ea', [EA, 1e7, 1e11])
def test_elastic_matches_40_digit_mpmath(ea):
    s = np.array([100.0, 103.0, 110.0, 118.0, 120.5, 121.06, 121.6, 122.5, 125.0, 135.0])
    st = fl.statics_at_span(W, H, L, s, ea)
    for i in range(s.size):
        if st.regime[i] == LineRegime.SLACK:
            continue
        hh, vv = _mp_elastic(W, H, L, s[i], ea, st.horizontal_tension[i], st.top_vertical[i])
        assert st.horizontal_tension[i] == pytest.approx(hh, rel=1e-11)
        assert st.top_vertical[i] == pytest.approx(vv, rel=1e-11)
        assert st.top_tension[i] == pytest.approx(math.hypot(hh, vv), rel=1e-11)
        assert st.uplift_force[i] == pytest.approx(max(vv - W * L, 0.0), rel=1e-9, abs=1e-6)
    assert set(st.regime.tolist()) == {LineRegime.SLACK, LineRegime.GROUNDED, LineRegime.LIFTED}


def test_elastic_matches_moorpy():
    os.environ.setdefault('PYTHONBREAKPOINT', '0')
    from moorpy.Catenary import catenary

    for ea in (EA, 1e8):
        for s in (105.0, 115.0, 120.0, 121.06, 122.0, 123.5):
            st = fl.statics_at_span(W, H, L, s, ea)
            _, _, fbh, fbv, _ = catenary(s, H, L, ea, W, CB=0, Tol=1e-10)
            # MoorPy's tolerance is on the end position [m]: the forces agree to dR/ds * Tol.
            tol = 10 * float(st.dr_ds) * 1e-10 + 1e-9 * float(st.top_tension)
            assert float(st.horizontal_tension) == pytest.approx(abs(fbh), abs=tol)
            assert float(st.top_vertical) == pytest.approx(abs(fbv), abs=tol)


@pytest.mark.parametrize('ea', [math.inf, EA, 1e7])
def test_stiffness_is_the_derivative(ea):
    s = np.array([103.0, 110.0, 118.0, 120.5, 121.06, 121.5])
    if math.isinf(ea):
        s = s[s < fl.taut_span(H, L) - 0.05]
    st = fl.statics_at_span(W, H, L, s, ea)
    e = 1e-5
    up = fl.statics_at_span(W, H, L, s + e, ea)
    down = fl.statics_at_span(W, H, L, s - e, ea)
    fd_r = (up.horizontal_tension - down.horizontal_tension) / (2 * e)
    fd_t = (up.top_tension - down.top_tension) / (2 * e)
    np.testing.assert_allclose(st.dr_ds, fd_r, rtol=1e-6)
    np.testing.assert_allclose(st.dt_ds, fd_t, rtol=1e-6)


def test_span_from_tension_inverts_the_state():
    for ea in (math.inf, EA):
        s = np.array([104.0, 112.0, 119.0, 120.9, 121.1])  # the rigid chain is taut at 121.11
        st = fl.statics_at_span(W, H, L, s, ea)
        np.testing.assert_allclose(
            fl.span_from_tension(W, H, L, st.top_tension, ea), s, rtol=1e-13
        )
        span, dt_ds = fl.span_and_sensitivity(W, H, L, st.top_tension, ea)
        np.testing.assert_allclose(span, s, rtol=1e-13)
        np.testing.assert_allclose(dt_ds, st.dt_ds, rtol=1e-9)


def test_warm_start_gives_the_same_state():
    s = np.array([110.0, 121.0, 121.5])
    for ea in (math.inf, EA):
        cold = fl.statics_at_span(W, H, L, s, ea)
        warm = fl.statics_at_span(W, H, L, s, ea, t_start=cold.top_tension * 1.3)
        np.testing.assert_allclose(warm.top_tension, cold.top_tension, rtol=1e-12)


def test_solve_chain_length_with_ea():
    r = solve(W, H, chain_length=L, anchor_distance=121.06, ea=EA, mbl=4.827e6)
    st = fl.statics_at_span(W, H, L, 121.06, EA)
    assert r.status == 0 and r.problem == 'chain_length' and r.model == 'elastic catenary'
    # The tension problem at that hook tension gives the same uplift state.
    assert r.top_tension == pytest.approx(float(st.top_tension), rel=1e-14)
    assert r.uplift_force == pytest.approx(float(st.uplift_force), rel=1e-9)
    assert r.horizontal_tension == pytest.approx(float(st.horizontal_tension), rel=1e-9)
    assert r.grounded_length == 0.0 and r.anchor_margin < 0
    # A stiff chain gives the inextensible answer back.
    stiff = solve(W, H, chain_length=L, anchor_distance=121.06, ea=1e30)
    rigid = solve(W, H, chain_length=L, anchor_distance=121.06)
    assert stiff.uplift_force == pytest.approx(rigid.uplift_force, rel=1e-9)
    arr = solve(W, H, chain_length=[L, L, L], anchor_distance=[121.06, 90.0, -1.0], ea=EA)
    assert arr.status.tolist() == [0, Status.CHAIN_SLACK, Status.DISTANCE]
    assert np.isnan(arr.top_tension[1:]).all()
    with pytest.raises(ValueError, match='anchor_distance'):
        solve(W, H, chain_length=L, ea=EA)


def _mp_lift_depth(w, length, s, ea=None):
    """40-digit depth at which the chain of length L at span s lifts its anchor (bisection)."""
    mp.mp.dps = 40
    w, length, s = mp.mpf(w), mp.mpf(length), mp.mpf(s)

    def root(f, lo, hi):
        for _ in range(300):
            mid = (lo + hi) / 2
            lo, hi = (lo, mid) if f(mid) > 0 else (mid, hi)
        return (lo + hi) / 2

    theta = root(lambda t: mp.sinh(t) / t - length / s, mp.mpf(10) ** -30, mp.mpf(60))
    if ea is None:
        return float(s / theta * (mp.cosh(theta) - 1))
    ea = mp.mpf(ea)
    r = root(
        lambda r: r / w * mp.asinh(w * length / r) + r * length / ea - s,
        mp.mpf(10) ** -30,
        w * s / theta,
    )
    z = w * length / r
    return float(r / w * (mp.sqrt(1 + z * z) - 1) + w * length**2 / (2 * ea))


@pytest.mark.parametrize('ea', [None, EA, 1e7])
def test_lift_depth_matches_40_digit_mpmath(ea):
    """From a chain hanging almost straight down (s = 1 m) to one almost taut along the seabed
    (s = L - 1e-7 m, where the inextensible lift depth tends to 0)."""
    s = np.array([1.0, 30.0, 60.0, 100.0, 120.0, 122.0, 122.8, 122.89, L - 1e-4, L - 1e-7])
    got = fl.lift_depth(W, L, s, math.inf if ea is None else ea)
    for i in range(s.size):
        assert got[i] == pytest.approx(_mp_lift_depth(W, L, s[i], ea), rel=1e-12), s[i]


@pytest.mark.parametrize('ea', [math.inf, EA])
def test_at_the_lift_depth_the_anchor_just_lifts(ea):
    """The state at (lift depth, span): no chain on the seabed, no pull on the anchor; a
    centimetre deeper the anchor lifts, a centimetre shallower it is down."""
    s = np.array([60.0, 100.0, 120.0])
    h = fl.lift_depth(W, L, s, ea)
    at = fl.statics_at_span(W, h, L, s, ea)
    np.testing.assert_allclose(at.grounded_length, 0.0, atol=1e-6)
    np.testing.assert_allclose(at.uplift_force, 0.0, atol=1e-3 * W)
    assert (fl.statics_at_span(W, h + 0.01, L, s, ea).uplift_force > 0).all()
    assert (fl.statics_at_span(W, h - 0.01, L, s, ea).grounded_length > 0).all()


def test_lift_depth_without_a_state_is_nan():
    got = fl.lift_depth(W, L, np.array([L, L + 1.0, 0.0, -1.0, math.nan]))
    assert np.isnan(got).all()
    assert np.isnan(fl.lift_depth(0.0, L, 100.0)) and np.isnan(fl.lift_depth(W, L, 100.0, 0.0))
