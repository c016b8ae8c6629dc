"""Margins with the sensors' accuracy (core/rules/uncertainty.py): the monotonicity the bounds
rest on, bounds that contain the solve at readings perturbed within the accuracy (the core's scalar
solve as the reference), and the uplift-within-accuracy WARN through the monitor core."""

import math

import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.events import Depth, Tension
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.rules.uncertainty import T_STAR, bounds

W, X = 1300.0, 120.0


def test_t_star_is_the_root_of_t_tanh_t():
    assert math.isclose(T_STAR * math.tanh(T_STAR), 1.0, rel_tol=1e-15)


@pytest.mark.parametrize('h', [5.0, 20.85, 60.0])
def test_margins_fall_and_uplift_grows_with_tension(h):
    t = np.linspace(W * h * 1.01, 3e6, 4000)
    r = solve(W, h, tension=t, anchor_distance=X)
    assert np.all(np.diff(r.anchor_margin) < 0)
    tide = np.asarray(r.tide_margin)
    tide = tide[np.isfinite(tide)]  # (cosh overflows for a near-vertical chain)
    assert len(tide) > 3900 and np.all(np.diff(tide) < 0)
    assert np.all(np.diff(r.uplift_force) >= 0) and r.uplift_force[-1] > 0


@pytest.mark.parametrize('t', [2e5, 4e5, 1.5e6])
def test_critical_depths_are_where_the_margins_turn(t):
    """At fixed T, x_min peaks at h = k T / (w (1 + k)) and the tide margin is lowest at
    h = T/w - x/t* (the closed forms' derivatives in the module docstring)."""
    k = math.cosh(T_STAR) - 1.0
    h = np.linspace(0.5, t / W * 0.999, 200001)
    r = solve(W, h, tension=t, anchor_distance=X)
    h_anchor = k * t / (W * (1 + k))
    assert abs(h[np.argmax(r.min_anchor_distance)] - h_anchor) < 1e-3 * h_anchor


@pytest.mark.parametrize('t', [1.6e5, 2e5])
def test_tide_margin_is_lowest_at_its_critical_depth(t):
    """A grounded chain (these T) at fixed T: the tide margin's minimum in depth lies at
    h = T/w - x/t*."""
    h_tide = t / W - X / T_STAR
    h = np.linspace(0.5 * h_tide, 1.5 * h_tide, 100001)
    r = solve(W, h, tension=t, anchor_distance=X)
    assert np.all(np.asarray(r.uplift_force) == 0)
    tide = np.asarray(r.tide_margin)
    assert abs(h[np.argmin(tide)] - h_tide) < 1e-3 * h_tide


def _scenes(rng, n):
    w = rng.uniform(200.0, 3000.0, n)
    h = rng.uniform(3.0, 80.0, n)
    x = rng.uniform(0.5, 4.0, n) * h
    # tensions around the no-uplift limit of each scene, so both sides are sampled
    t_crit = np.asarray(solve(w, h, tension=w * h * 10, anchor_distance=x).load_margin)
    t_crit = t_crit + w * h * 10
    t = t_crit * rng.uniform(0.6, 1.3, n)
    t = np.maximum(t, w * h * 1.05)
    dt = t * rng.uniform(0.0, 0.05, n)
    dh = rng.uniform(0.0, 0.5, n)
    return w, h, x, t, dt, dh


def test_bounds_contain_the_solve_within_the_accuracy():
    """Every true reading within +-dT, +-dh of the reading gives an uplift force at most the
    upper bound and margins at least the lower bounds (2000 scenes x 25 perturbations,
    corners included; reference: the scalar solve of each perturbed reading)."""
    rng = np.random.default_rng(12)
    w, h, x, t, dt, dh = _scenes(rng, 2000)
    nominal = solve(w, h, tension=t, anchor_distance=x)
    b = bounds(w, x, 1e12, math.inf, t, h, dt, dh, nominal.uplift_force)
    assert np.isfinite(b['uplift_force_upper']).all()
    lifted = 0
    for i in range(len(t)):
        signs = rng.uniform(-1, 1, (25, 2))
        signs[:4] = [[1, 1], [1, -1], [-1, 1], [-1, -1]]
        for st, sh in signs:
            ti, hi = float(t[i] + st * dt[i]), float(h[i] + sh * dh[i])
            if not ti > w[i] * hi:
                continue
            r = solve(float(w[i]), hi, tension=ti, anchor_distance=float(x[i]))
            tol = 1e-9 * ti
            assert r.uplift_force <= b['uplift_force_upper'][i] + tol, i
            assert r.anchor_margin >= b['anchor_margin_lower'][i] - 1e-9 * x[i], i
            # (a near-vertical chain's tide margin overflows to NaN: nothing to compare)
            assert not r.tide_margin < b['tide_margin_lower'][i] - 1e-9 * hi, i
            lifted += r.uplift_force > 0
    assert lifted > 1000  # not vacuous: many perturbed readings lift the anchor


def test_bounds_are_exact_at_the_worst_corner_and_nan_without_accuracy():
    t, h, dt, dh = 5.0e5, 20.0, 2e4, 0.2
    nominal = solve(W, h, tension=t, anchor_distance=X)
    b = bounds(W, X, 1e12, math.inf, t, h, dt, dh, nominal.uplift_force)
    hs = np.linspace(h - dh, h + dh, 2001)
    corner = solve(W, hs, tension=t + dt, anchor_distance=X)
    assert math.isclose(b['anchor_margin_lower'], np.min(corner.anchor_margin), rel_tol=1e-9)
    assert b['anchor_margin_lower'] < nominal.anchor_margin
    none = bounds(W, X, 1e12, math.inf, t, h, math.nan, 0.0, nominal.uplift_force)
    assert all(math.isnan(float(v)) for v in none.values())


def _core(accuracy=30e3, depth_accuracy=0.2):
    line = LineConfig(
        name='line_01', weight=W, anchor_distance=X, mbl=4.827e6, tension_accuracy=accuracy
    )
    cfg = MonitorConfig(
        lines=(line,),
        alarm=AlarmConfig(
            depth_accuracy=depth_accuracy,
            anchor_margin_warn=0.0,
            tide_margin_warn=0.0,
            warn_clear_hold=0.0,
            margin_clear_hold=0.0,
            clear_hold=0.0,
            wave_window=1.0,  # readings 2 s apart: each its own window (no wave allowance)
            uplift_time_warn=0.0,  # no trend here: its warning would hold, unknown
        ),
    )
    return MonitorCore(cfg, 0)


def _critical_tension(h):
    r = solve(W, h, tension=W * h * 10, anchor_distance=X)
    return W * h * 10 + r.load_margin


def test_uplift_possible_warns_and_the_error_stays_on_the_nominal():
    core = _core()
    h = 20.85
    tc = _critical_tension(h)
    core.step(Depth(1, h))
    step = core.step(Tension(2_000_000_000, 0, tc - 10e3))  # nominal below uplift, bound above
    out = dict(zip(OUTPUT_FIELDS, step.outputs[0].values))
    assert out['uplift_force'] == 0.0 and out['uplift_force_upper'] > 0.0
    assert out['anchor_margin_lower'] < 0.0 < out['anchor_margin']
    assert core.state.lines[0].state.level == Level.WARN
    assert 'uplift possible within sensor accuracy' in core.state.lines[0].state.message
    core.step(Tension(4_000_000_000, 0, tc + 50e3))  # nominal uplift: ERROR, the WARN gives way
    state = core.state.lines[0].state
    assert state.level == Level.ERROR and 'within sensor accuracy' not in state.message
    core.step(Tension(6_000_000_000, 0, tc - 200e3))  # far from uplift: both clear
    assert core.state.lines[0].state.level == Level.OK


def test_default_accuracies_give_bounds():
    """Without tension_accuracy the line's load pin is taken at 0.5 % of its MBL: the bounds
    are those of that accuracy (and never NaN for a solved line)."""
    core = _core(accuracy=None, depth_accuracy=0.0)
    core.step(Depth(1, 20.85))
    t = _critical_tension(20.85) - 10e3
    step = core.step(Tension(2, 0, t))
    out = dict(zip(OUTPUT_FIELDS, step.outputs[0].values))
    f0 = solve(W, 20.85, tension=t, anchor_distance=X).uplift_force
    want = bounds(W, X, 4.827e6, math.inf, t, 20.85, 0.005 * 4.827e6, 0.0, f0)
    assert out['uplift_force_upper'] == pytest.approx(float(want['uplift_force_upper']))
    assert out['uplift_force_upper'] > 0.0 == out['uplift_force']
    assert out['anchor_margin_lower'] == pytest.approx(float(want['anchor_margin_lower']))
    assert AlarmConfig().depth_accuracy == 0.02


@pytest.mark.parametrize('t', [2.5e5, 8e5])
def test_uplift_bound_finds_a_peak_inside_the_depth_interval(t):
    """The uplift force peaks in depth (fixed T): with the reading anywhere within 0.9 dh of
    the peak the bound is the true maximum over the interval to 1e-6 relative, and never
    far below it (a 20001-point grid as the reference)."""
    w, x = 1000.0, 100.0
    hs = np.linspace(1.0, t / w * 0.999, 400001)
    v = np.asarray(solve(w, hs, tension=t, anchor_distance=x).uplift_force)
    peak = hs[np.nanargmax(v)]
    for dh in (0.2, 3.0):
        for off in np.linspace(-0.9, 0.9, 7):
            h = peak + off * dh
            f0 = solve(w, h, tension=t, anchor_distance=x).uplift_force
            b = bounds(w, x, 1e12, math.inf, t, h, math.nan, dh, f0)['uplift_force_upper']
            grid = np.linspace(h - dh, h + dh, 20001)
            true = np.nanmax(solve(w, grid, tension=t, anchor_distance=x).uplift_force)
            assert b >= true * (1 - 1e-6), (dh, off)
            assert b <= true * (1 + 1e-9)


# --- the worst case from the analysis (bounds) against the box sampled densely -----------------


def _readings(rng, n):
    """Readings around and beyond the uplift of random lines, boxes of every possible reading
    (``T + dT > w (h + dh)``, ``h - dh > 0``): ``w, h, x, t, dt, dh``."""
    w = rng.uniform(200.0, 3000.0, n)
    h = rng.uniform(3.0, 80.0, n)
    x = rng.uniform(0.3, 4.0, n) * h
    t_crit = np.asarray(solve(w, h, tension=w * h * 10, anchor_distance=x).load_margin)
    t = np.maximum((t_crit + w * h * 10) * rng.uniform(0.7, 2.0, n), w * h * 1.2)
    dt = t * rng.uniform(0.0, 0.05, n)
    dh = rng.choice([0.0, 0.02, 0.05, 0.2, 1.0], n)
    keep = (t + dt > w * (h + dh) * 1.0001) & (h - dh > 0.0)
    return tuple(v[keep] for v in (w, h, x, t, dt, dh))


def _dense(w, x, t, h, dh, f0, m=4001):
    """The box's worst values sampled: ``m`` depths over ``[h - dh, h + dh]`` at ``t``."""
    r = solve(w, np.linspace(h - dh, h + dh, m), tension=t, anchor_distance=x)
    return (
        max(float(np.max(r.uplift_force)), f0),
        float(np.min(r.anchor_margin)),
        float(np.min(r.tide_margin)),
    )


@pytest.mark.parametrize('seed', [3, 4])
def test_the_bounds_are_the_densely_sampled_worst_case(seed):
    """On random readings (lifted somewhere in the box for about 80 %, boxes of 0 to 2 m in
    depth) each bound is the worst value of 4001 depths at T + dT to 1e-6 relative (the
    uplift of its value, the anchor margin of x, the tide margin of h), and never on the
    unsafe side of it beyond rounding: the sampling can only miss a worst value."""
    from catenary_monitor.core.rules.uncertainty import FIELDS

    rng = np.random.default_rng(seed)
    w, h, x, t, dt, dh = _readings(rng, 700)
    f0 = np.asarray(solve(w, h, tension=t, anchor_distance=x).uplift_force)
    b = bounds(w, x, 1e12, math.inf, t, h, dt, dh, f0)
    lifted = 0
    for i in range(len(t)):
        want = _dense(w[i], x[i], t[i] + dt[i], h[i], dh[i], f0[i])
        scale = (max(want[0], 1e-9), x[i], h[i])
        lifted += want[0] > 0.0
        for key, v, s, sign in zip(FIELDS, want, scale, (1.0, -1.0, -1.0)):
            safe = sign * (float(b[key][i]) - v) / s  # >= 0 on the safe side
            assert -1e-12 <= safe <= 1e-6, (i, key, float(b[key][i]), v)
    assert lifted > 0.6 * len(t)


def test_the_bounds_are_never_less_safe_than_the_sampled_box():
    """The analysis takes the worst of the whole box; the sampled box (five depths and the
    uplift's parabola) the worst of some of its points: the upper bound is at least the
    sampled one and the lower bounds at most theirs (to rounding)."""
    from catenary_monitor.core.rules.uncertainty import sampled_bounds

    rng = np.random.default_rng(5)
    w, h, x, t, dt, dh = _readings(rng, 3000)
    f0 = np.asarray(solve(w, h, tension=t, anchor_distance=x).uplift_force)
    b = bounds(w, x, 1e12, math.inf, t, h, dt, dh, f0)
    s = sampled_bounds(w, x, 1e12, math.inf, t, h, dt, dh, f0)
    keys = ('uplift_force_upper', 'anchor_margin_lower', 'tide_margin_lower')
    up, am, tm = (np.asarray(b[k]) for k in keys)
    assert np.all(up >= s['uplift_force_upper'] * (1 - 1e-12))
    assert np.all(am <= s['anchor_margin_lower'] + 1e-12 * x)
    assert np.all(tm <= s['tide_margin_lower'] + 1e-12 * h)


def test_one_line_in_plain_floats_gives_the_arrays_numbers():
    """bounds_one (the monitor's per-sample path) against bounds() on the same readings as
    arrays: the analysis, the sampled box of an elastic chain and of a box reaching impossible
    readings, no accuracy, no nominal solve."""
    from catenary_monitor.core.rules.uncertainty import FIELDS, bounds_one

    rng = np.random.default_rng(6)
    w, h, x, t, dt, dh = _readings(rng, 1500)
    n = len(t)
    ea = np.where(rng.random(n) < 0.1, 6.63e8, math.inf)
    dt = np.where(rng.random(n) < 0.05, math.nan, dt)
    h = np.where(rng.random(n) < 0.05, t / w - 0.5 * dh, h)  # some boxes reach T <= w h
    f0 = np.asarray(solve(w, h, tension=t, anchor_distance=x).uplift_force)
    f0 = np.where(rng.random(n) < 0.03, math.nan, f0)
    b = bounds(w, x, 4.8e6, ea, t, h, dt, dh, f0)
    for i in range(n):
        one = bounds_one(
            float(w[i]), float(x[i]), 4.8e6, float(ea[i]), float(t[i]), float(h[i]),
            float(dt[i]), float(dh[i]), float(f0[i]),
        )  # fmt: skip
        for key, v in zip(FIELDS, one):
            want = float(b[key][i])
            assert (math.isnan(v) and math.isnan(want)) or v == pytest.approx(
                want, rel=1e-12, abs=1e-9
            ), (i, key, v, want)


def test_the_lifted_chains_critical_depths_against_mpmath():
    """The depths where a lifted chain's uplift force peaks and its tide margin is lowest at
    fixed hook tension (the table and its Newton step) against the same family in 30 digits:
    the force and the tide margin maximized and minimized over the depth directly."""
    mpmath = pytest.importorskip('mpmath')
    from catenary_monitor.core.rules.uncertainty import lifted_critical_depths_one

    mp = mpmath.mp
    mp.dps = 30
    w, x = 1300.0, 121.06
    for c in (1.52, 1.6, 2.0, 3.0, 10.0, 100.0, 1000.0):
        t = c * w * x

        def family(big_x):
            u = mp.acosh(c * big_x) - big_x
            return x * (c - mp.cosh(u) / big_x), w * x * mp.sinh(u) / big_x, u

        def depth_at(big_x):
            return family(big_x)[0]

        def force(big_x):
            return family(big_x)[1]

        def tide(big_x):  # a (cosh X - 1) - h, a = x / X
            return x / big_x * (mp.cosh(big_x) - 1) - depth_at(big_x)

        def bisect(f, lo, hi):
            f_lo = f(lo) > 0
            for _ in range(120):
                mid = (lo + hi) / 2
                lo, hi = (mid, hi) if (f(mid) > 0) == f_lo else (lo, mid)
            return (lo + hi) / 2

        low = mp.mpf(1) / c * (1 + mp.mpf(10) ** -20)  # the family's shallowest member
        x_peak = bisect(lambda z: mp.diff(force, z), low, mp.sqrt(1 + 1 / mp.mpf(c) ** 2))
        x_off = bisect(lambda z: mp.cosh(z) - c * z, mp.mpf(T_STAR), 2 + 2 * mp.log(2 * c))
        x_trough = bisect(lambda z: mp.diff(tide, z), x_peak, x_off)
        h_f, h_t = lifted_critical_depths_one(w, x, t)
        assert h_f == pytest.approx(float(depth_at(x_peak)), rel=1e-9), c
        assert h_t == pytest.approx(float(depth_at(x_trough)), rel=1e-9), c
        assert family(x_peak)[2] > 0 and family(x_trough)[2] > 0  # both lifted


def test_the_lifted_critical_depths_grow_with_the_tension():
    """Over the span, both critical depths are least at C_MIN (c - 1/t*) and grow with c = T/(w
    x) (every node of the table): a box shallower than that takes neither from the table."""
    from catenary_monitor.core.rules import uncertainty as u

    c = np.exp(u._S0 + u._DS * np.arange(u._N + 1))
    h_f, h_t = u.lifted_critical_depths(1.0, 1.0, c)
    assert h_f[0] == pytest.approx(u._ETA0, rel=1e-12) == h_t[0]
    assert np.all(np.diff(h_f) > 0) and np.all(np.diff(h_t) > 0)


@pytest.mark.parametrize('c', [1.509, 1.6, 3.0, 20.0, 1000.0])
def test_the_lifted_force_is_concave_and_the_tide_margin_convex_in_depth(c):
    """What the tangent bound rests on: over the depths at which a chain of fixed hook tension
    lifts its anchor the uplift force is concave and the tide margin convex (second
    differences of the solve on a fine grid, to rounding)."""
    w, x = 1300.0, 121.06
    t = c * w * x
    h = np.linspace(0.01, t / w * 0.9999, 200001)
    r = solve(w, h, tension=t, anchor_distance=x)
    f = np.asarray(r.uplift_force)
    lifted = np.flatnonzero(f > 0)
    assert lifted.size > 100
    f, tide = f[lifted], np.asarray(r.tide_margin)[lifted]
    assert np.all(np.diff(f, 2) <= 1e-12 * f.max() * 64)
    assert np.all(np.diff(tide, 2) >= -1e-12 * np.abs(tide).max() * 64)


def test_the_dynamic_uplift_solves_only_where_the_anchor_lifts(monkeypatch):
    """dynamic_uplift (arrays) and dynamic_uplift_one: the solve's uplift force at the dynamic
    tension (at least the nominal), a grounded chain's 0 without a solve."""
    from catenary_monitor.core.rules import uncertainty

    rng = np.random.default_rng(7)
    w, h, x, t, _, _ = _readings(rng, 2000)
    f0 = np.asarray(solve(w, h, tension=0.9 * t, anchor_distance=x).uplift_force)
    want = np.fmax(np.asarray(solve(w, h, tension=t, anchor_distance=x).uplift_force), f0)
    got = uncertainty.dynamic_uplift(w, x, 4.8e6, math.inf, t, h, f0)
    assert np.array_equal(got, want)
    for i in range(0, len(t), 7):
        one = uncertainty.dynamic_uplift_one(
            float(w[i]), float(x[i]), 4.8e6, math.inf, float(t[i]), float(h[i]), float(f0[i])
        )
        assert one == pytest.approx(want[i], rel=1e-12, abs=1e-9)
    solved = []
    monkeypatch.setattr(uncertainty, 'solve', lambda *a, **k: solved.append(1) or solve(*a, **k))
    grounded = ~(want > 0)
    uncertainty.dynamic_uplift(w[grounded], x[grounded], 4.8e6, math.inf, t[grounded],
                               h[grounded], f0[grounded])  # fmt: skip
    assert grounded.sum() > 100 and solved == []


def test_an_elastic_chain_takes_the_sampled_box():
    from catenary_monitor.core.rules.uncertainty import sampled_bounds

    t, h, dt, dh = 1.2e6, 20.85, 24e3, 0.02
    f0 = solve(W, h, tension=t, anchor_distance=X, ea=6.63e8).uplift_force
    b = bounds(W, X, 4.8e6, 6.63e8, t, h, dt, dh, f0)
    s = sampled_bounds(W, X, 4.8e6, 6.63e8, t, h, dt, dh, f0)
    assert all(float(b[k]) == float(s[k]) for k in b)
