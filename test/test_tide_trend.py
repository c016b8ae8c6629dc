"""The tide's trend and each line's time to uplift (core.rules.tide_trend, the core, its
vectorized twin).

* the scalar trend (``step``) and its vectorized twin (``series``) give the same bits, in any
  windows;
* a tide rising at a known rate with the horizontal tension held: ``time_to_uplift`` within a
  few per cent of the exact crossing time (the catenary closed form, in mpmath), also with
  waves on the depth and the tension (the dock heaving with them: every sample) and with gauge
  noise on the depth (which the solver turns into noise on the horizontal tension and so on the
  margin: the median of each minute);
* the core and ``engine.advance`` agree event by event over such a tide (values, the new WARN
  and the ERROR after it, snapshots, the state left behind).
"""

import math

import mpmath
import numpy as np
import pytest
from replay_data import T0_NS
from test_batch import compare

from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.rules import tide_trend
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.events import Depth, Tension
from catenary_monitor.core.monitor.monitor_core import MonitorCore

W, X = 1300.0, 120.0  # chain weight N/m, anchor distance m
H = 150e3  # horizontal tension held, N
RATE = 0.31 / 3600.0  # m/s
CROSS_S = 10800.0  # the exact crossing, s after the start


def exact_crossing_depth(h: float = H, w: float = W, x: float = X) -> float:
    """Depth [m] at which a chain of horizontal tension ``h`` just lifts its anchor at ``x``:
    the touchdown reaches the anchor, ``a (cosh(x / a) - 1)`` with ``a = h / w`` (mpmath)."""
    mpmath.mp.dps = 30
    a = mpmath.mpf(h) / w
    return float(a * (mpmath.cosh(mpmath.mpf(x) / a) - 1))


def tide_scene(seconds, noise=0.0, wave=0.0, seed=0):
    """Depth and tension at 1 Hz (tension 0.3 s after the depth): the tide rising ``RATE``
    to cross uplift at ``CROSS_S``; ``wave`` (m) heaves the dock (depth and tension), ``noise``
    (m) is the depth gauge's own."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0)
    h0 = exact_crossing_depth() - RATE * CROSS_S
    heave = wave * np.sin(2 * np.pi * t / 9.0) + 0.5 * wave * np.sin(2 * np.pi * t / 13.7 + 1)
    h = h0 + RATE * t + heave
    depth = h + rng.normal(0.0, noise, t.size) if noise else h
    tension = H + W * (h + RATE * 0.3)  # touchdown catenary: T = H + w h
    t_ns = T0_NS + np.rint(t * 1e9).astype(np.int64)
    return t, (t_ns, depth), (t_ns + 300_000_000, tension)


def one_line(tension_accuracy=None, **alarm):
    # The scene's tension is noise-free and moves by less than the default resolution per
    # sample: resolution 0 keeps it from reading as a stuck sensor (core.rules.sensor_state).
    alarm.setdefault('tension_resolution', 0.0)
    line = LineConfig(
        name='line_11',
        weight=W,
        anchor_distance=X,
        mbl=4.8e6,
        tension_accuracy=tension_accuracy,
    )
    return MonitorConfig(lines=(line,), alarm=AlarmConfig(**alarm))


@pytest.mark.parametrize(
    'noise, wave, window',
    [(0.0, 0.0, 1200.0), (0.0, 0.05, 1200.0), (0.01, 0.05, 1200.0), (0.03, 0.15, 3600.0)],
)
def test_time_to_uplift_against_the_exact_crossing(noise, wave, window):
    """The trend's error is the waves' and the noise's left in the bin means over the
    window's rise (0.10 m in 20 min at 0.31 m/h): bigger waves need a longer window."""
    t, (dt, dv), (tt, tv) = tide_scene(CROSS_S - 3000.0, noise, wave, seed=7)
    core = MonitorCore(one_line(tide_trend_window=window), T0_NS - 1)
    ttu = OUTPUT_FIELDS.index('time_to_uplift')
    got = {}
    for k in range(t.size):
        core.step(Depth(int(dt[k]), float(dv[k])))
        out = core.step(Tension(int(tt[k]), 0, float(tv[k]))).outputs[0].values
        got[t[k]] = out[ttu]
    assert all(math.isnan(got[s]) for s in t[t < 0.45 * window])  # unknown: half a window
    for s in (1800.0, 3600.0, 5400.0, 7200.0):
        exact = CROSS_S - (s + 0.3)
        if noise:  # the median of the minute
            minute = [got[u] + u - s for u in t[(t >= s - 30) & (t < s + 30)]]
            assert np.median(minute) == pytest.approx(exact, rel=0.03), (s, exact)
        else:
            assert got[s] == pytest.approx(exact, rel=0.03), (s, got[s], exact)
    assert core.state.trend.rate == pytest.approx(RATE, rel=0.02)
    # Waves must not make it jump: every sample (with gauge noise: every minute's median)
    # from half an hour on within 5 %.
    late = t >= 1800.0
    error = np.array([got[u] for u in t[late]]) / (CROSS_S - t[late] - 0.3) - 1.0
    if noise:
        error = np.median(error[: error.size // 60 * 60].reshape(-1, 60), axis=1)
    assert np.abs(error).max() < 0.05, np.abs(error).max()


def test_falling_tide_and_a_lifted_anchor():
    assert tide_trend.time_to_uplift(2.0, 0.0, -1e-4, 0.0) == math.inf
    assert math.isnan(tide_trend.time_to_uplift(2.0, 0.0, math.nan, math.nan))  # unknown
    assert tide_trend.time_to_uplift(-0.1, 5e3, 1e-4, 0.0) == 0.0
    assert tide_trend.time_to_uplift(0.5, 0.0, 1e-4, -0.6) == 0.0  # the tide's level is past
    assert math.isnan(tide_trend.time_to_uplift(math.nan, math.nan, 1e-4, 0.0))
    got = tide_trend.uplift_times(
        np.array([2.0, 2.0, -0.1, 0.5, math.nan, 1.0]),
        np.array([0.0, 0.0, 5e3, 0.0, math.nan, 0.0]),
        np.array([-1e-4, math.nan, 1e-4, 1e-4, 1e-4, 1e-4]),
        np.array([0.0, math.nan, 0.0, -0.6, 0.0, 0.2]),
    )
    np.testing.assert_array_equal(got[:5], [math.inf, math.nan, 0.0, 0.0, math.nan])
    assert got[5] == 1.2 / 1e-4


def test_the_uplift_column_form_equals_the_scalar():
    """tide_trend.uplift_times equals time_to_uplift element by element: lifted, falling or
    unknown tides, NaN margins and excesses, signed zeros, infinities."""
    rng = np.random.default_rng(10)
    odd = [np.nan, np.inf, -np.inf, 0.0, -0.0, 1e-300]
    n = 4000
    cols = [
        rng.normal(0.5, 1.0, n),
        rng.choice([0.0, 0.0, 5e3], n),
        rng.normal(1e-4, 1e-4, n),
        rng.normal(0.0, 0.2, n),
    ]
    for c in cols:
        hit = rng.random(n) < 0.1
        c[hit] = rng.choice(odd, int(hit.sum()))
    want = [tide_trend.time_to_uplift(*v) for v in zip(*(c.tolist() for c in cols))]
    got = tide_trend.uplift_times(*cols)
    assert np.array_equal(got, want, equal_nan=True)
    number = ~np.isnan(got)
    assert np.array_equal(np.signbit(got[number]), np.signbit(np.array(want)[number]))


def test_trend_series_equals_step_in_any_windows():
    rng = np.random.default_rng(3)
    n = 6000
    t_ns = T0_NS + np.cumsum(rng.integers(200_000_000, 2_500_000_000, n))
    depth = 20.0 + 1e-4 * (t_ns - T0_NS) * 1e-9 + rng.normal(0, 0.2, n)
    depth[rng.random(n) < 0.02] = math.nan
    gap = (t_ns > t_ns[2000]) & (t_ns < t_ns[2000] + int(900e9))
    t_ns, depth = t_ns[~gap], depth[~gap]  # a gap of 15 min: the trend unknown for a while
    window = 600.0
    state, rates, excess = tide_trend.TrendState(), [], []
    for a, b in zip(t_ns.tolist(), depth.tolist()):
        state = tide_trend.step(state, a, b, window)
        rates.append(state.rate)
        excess.append(state.excess)
    for cuts in ([], [1, 17, 500, 501, 3000], list(range(0, len(t_ns), 997))):
        twin, got_r, got_e = tide_trend.TrendState(), [], []
        for lo, hi in zip([0, *cuts], [*cuts, len(t_ns)]):
            r, e, twin = tide_trend.series(twin, t_ns[lo:hi], depth[lo:hi], window)
            got_r.append(r)
            got_e.append(e)
        np.testing.assert_array_equal(np.concatenate(got_r), rates)
        np.testing.assert_array_equal(np.concatenate(got_e), excess)
        assert repr(twin) == repr(state)
    known = np.isfinite(rates)
    assert known.mean() > 0.8 and not known.all()
    assert np.nanmedian(rates) == pytest.approx(1e-4, rel=0.1)


def test_the_core_and_its_twin_agree_on_a_rising_tide():
    t, depth, tension = tide_scene(CROSS_S + 300.0, noise=0.01, wave=0.05, seed=11)
    config = one_line(  # the default hold times: the warning holds through the waves
        tension_timeout=2.5,
        depth_timeout=4.0,
        anchor_margin_warn=0.0,
        tide_margin_warn=0.0,
        tension_accuracy=1.0,  # exact sensors: the time-to-uplift warning is the first
        depth_accuracy=0.0,
    )
    ticks = depth[0][::5] + 600_000_000
    cuts = [T0_NS + int(s * 1e9) for s in (400.0, 1234.5, 3000.0, 3000.2, 8000.0, 9500.0)]
    steps = compare(config, {'line_11': tension}, depth, ticks, cuts)
    changes = [c.transition for s in steps for c in s.transitions if c.component == 'line_11']
    warn = [c for c in changes if c.new.name == 'WARN' and 'anchor uplift in' in c.message]
    error = [c for c in changes if c.new.name == 'ERROR']
    assert warn and error and warn[0].time < error[0].time
    ahead = error[0].time - warn[0].time
    assert 600.0 < ahead < 1900.0, ahead  # 30 min before the tide's crossing, wave crests first
    assert ' m/h' in warn[0].message


def test_a_spiked_bin_does_not_move_the_rate():
    t_ns = T0_NS + np.arange(0, 1800) * 1_000_000_000
    depth = 20.0 + RATE * np.arange(1800.0)
    spiked = depth.copy()
    spiked[1300:1310] += 5.0  # a gauge spike of 10 s: one bin's mean off by 0.8 m
    clean, _, _ = tide_trend.series(tide_trend.TrendState(), t_ns, depth, 1200.0)
    rates, _, _ = tide_trend.series(tide_trend.TrendState(), t_ns, spiked, 1200.0)
    np.testing.assert_allclose(clean[-300:], RATE, rtol=1e-9)
    np.testing.assert_allclose(rates[-300:], RATE, rtol=1e-6)  # the median ignores the bin
    s = np.arange(600.0, 1800.0)  # a least-squares line over the samples would not
    assert abs(np.polyfit(s, spiked[600:], 1)[0] / RATE - 1) > 0.3
