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
