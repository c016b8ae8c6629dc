"""The monitor against physics nobody here wrote, through the replay command on rosbag2
recordings of the sensor topics, and identically through the core stepped event by event (the
node's one decision path).

* A chain of fixed length whose hook stays put, the tide rising with gauge noise: MoorPy's
  catenary gives the hook tension and the true lift; ``time_to_uplift`` counts down to it.
* Slow tide rise and wave-frequency hook motion in MoorDyn (NREL's lumped-mass model): the
  uplift, the bound and the first ERROR against MoorDyn's anchor force.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from replay_data import T0_NS, events_of
from scipy.optimize import brentq
from sensor_bag import column, replay_csv, write_bag

from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.monitor.alarms import CONDITIONS, Level
from catenary_monitor.core.monitor.monitor_core import MonitorCore, Tension
from catenary_monitor.core.monitor.twin import tick_grid

os.environ.setdefault('PYTHONBREAKPOINT', '0')  # MoorPy calls breakpoint() on some errors
W, L, X = 1300.0, 122.6247, 120.0  # the paper dock's chain at its installed span


def moorpy_hook(depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MoorPy's inextensible-limit catenary of the chain at span X: hook tension and anchor
    vertical force [N] at each depth."""
    from moorpy.Catenary import catenary

    top, anchor = [], []
    for h in depth.tolist():
        f_ah, f_av, f_bh, f_bv, _ = catenary(X, h, L, 1e15, W, CB=0.0)
        top.append(math.hypot(f_bh, f_bv))
        anchor.append(f_av)
    return np.array(top), np.array(anchor)


def fixed_length_scene(rate_m_h: float, seed: int = 3, noise: float = 0.02):
    """The tide rising ``rate_m_h`` to lift the anchor 100 min in; 0.5 Hz depth with ``noise``
    (m) and a tension from MoorPy every 5 s. Returns columns and the lift's time [s from T0]."""
    from moorpy.Catenary import catenary

    lift = brentq(lambda h: catenary(X, h, L, 1e15, W, CB=0.0)[1] - 1.0, 20.0, 23.5)
    rate = rate_m_h / 3600.0
    t = np.arange(0.0, 6600.0, 2.0)
    h = lift - rate * (6000.0 - t)
    rng = np.random.default_rng(seed)
    t_ns = T0_NS + np.rint(t * 1e9).astype(np.int64)
    depth = (t_ns, h + rng.normal(0.0, noise, t.size))
    tension, _ = moorpy_hook(h[::5])
    return t, {'line_01': (t_ns[::5] + 400_000_000, tension)}, depth, 6000.0


def one_line(**alarm) -> MonitorConfig:
    line = LineConfig(name='line_01', weight=W, anchor_distance=X, mbl=4.827e6, chain_length=L)
    alarm.setdefault('tension_resolution', 0.0)  # noise-free tension: not a stuck sensor
    alarm.setdefault('diagnostic_rate', 0.2)
    alarm.setdefault('tension_timeout', 12.0)
    return MonitorConfig(lines=(line,), alarm=AlarmConfig(**alarm))


@pytest.mark.parametrize('rate_m_h', [0.35, 0.6])
def test_fixed_length_forecast_counts_down_to_the_lift(tmp_path, rate_m_h):
    config = one_line()
    t, tensions, depth, lift_s = fixed_length_scene(rate_m_h)
    rows = replay_csv(tmp_path, config, write_bag(tmp_path / 'bag', config, tensions, depth))
    time = column(rows, 'time', 'line_01') - T0_NS * 1e-9
    ttu = column(rows, 'time_to_uplift', 'line_01')
    view = [r['time_to_uplift_view'] for r in rows]
    for before in (3600.0, 1800.0, 900.0):
        at = np.abs(time - (lift_s - before)) < 30.0  # each sample of that minute
        assert np.all(np.abs(ttu[at] / (lift_s - time[at]) - 1.0) < 0.25), (before, ttu[at])
        assert np.all(np.isfinite(ttu[at]))
        assert {view[i] for i in np.flatnonzero(at)} == {'chain length held'}
    # R held, the same line would read hours (the 4.4x): the nearer view answered
    r_held = column(rows, 'tide_margin', 'line_01')[np.abs(time - (lift_s - 3600.0)) < 5.0]
    assert r_held[0] / (rate_m_h / 3600.0) > 2.0 * 3600.0
    levels = [r['level'] for r in rows]
    last = np.flatnonzero((time > lift_s - 1350.0) & (time < lift_s))
    assert all(levels[i] != 'OK' for i in last)
    # identically live: the core stepped event by event gives the same levels and values
    if rate_m_h != 0.6:
        return
    start = int(min(depth[0][0], tensions['line_01'][0][0]))
    ticks = tick_grid(start, int(depth[0][-1]) + 400_000_000, 0.2)
    core = MonitorCore(config, start)
    live, warned_at, message = [], None, ''
    at = CONDITIONS.index('time_to_uplift')
    for ev in events_of(config, tensions, depth, ticks):
        step = core.step(ev)
        state = core.state.lines[0].state
        if isinstance(ev, Tension):
            live.append(step.outputs[0].values)
        if warned_at is None and state.latches[at].active:
            warned_at, message = ev.stamp_ns * 1e-9 - T0_NS * 1e-9, state.message
    assert [Level(int(v[12])).name for v in live] == levels
    ttu_live = np.array([v[13] for v in live])
    np.testing.assert_allclose(ttu_live, ttu, rtol=1e-6, atol=2e-3)
    assert lift_s - warned_at >= 1350.0, warned_at
    assert 'anchor uplift in' in message and '(chain length held)' in message, message


# --- MoorDyn: a slow tide rise, and wave-frequency hook motion ----------------------------------

LINE_11 = dict(weight=W, anchor_distance=121.06, mbl=4.827e6, ea=6.63e8, chain_length=123.6847)


def moordyn_bag(tmp_path, rec, allowed=0.0):
    """The MoorDyn record as the sensors would give it (hook tension at 10 Hz, the hook's depth
    at 1 Hz) in a rosbag2 bag, and the config of the line."""
    line = LineConfig(name='line_11', allowed_uplift=allowed, **LINE_11)
    config = MonitorConfig(lines=(line,), alarm=AlarmConfig(diagnostic_rate=1.0))
    t_ns = T0_NS + np.rint(rec.t * 1e9).astype(np.int64)
    depth = (t_ns[::10] - 50_000_000, rec.depth[::10])
    tensions = {'line_11': (t_ns, rec.tension)}
    return config, write_bag(tmp_path / 'bag', config, tensions, depth)


def first(times, mask):
    return float(times[np.argmax(mask)]) if mask.any() else math.inf


@pytest.fixture(scope='module')
def moordyn():
    pytest.importorskip('moordyn')
    from catenary_monitor_study import moordyn_scene

    return moordyn_scene


def test_slow_tide_rise_uplift_and_error_against_moordyn(tmp_path, moordyn):
    """The hook rises 7 mm/s (25 m/h) at the installed span (slow for the chain, whose own
    periods are seconds): the monitor's uplift within 5 % (or 0.3 kN) of MoorDyn's anchor
    force, the first ERROR (allowed 20 kN) within 2 s of the anchor force's crossing. 80
    segments: with 40 (3 m each) MoorDyn's own discretization near the touchdown is 0.45 kN."""
    rise = 2.1 / 300.0
    chain = moordyn.Chain(segments=80)
    hook = (lambda t: (121.06, 0.0), lambda t: (22.1 + rise * t, rise))
    rec = moordyn.run_line(chain, *hook, 270.0)
    config, bag = moordyn_bag(tmp_path, rec, allowed=20e3)
    rows = replay_csv(tmp_path, config, bag)
    uplift = column(rows, 'uplift_force', 'line_11')
    # at the readings right after a depth sample (1 Hz): the scene's rise, 50 times a tide's,
    # would otherwise put the newest depth up to 7 mm behind the hook
    fresh = (np.arange(rec.t.size) % 10 == 0) & (rec.t > 10.0)
    error = np.abs(uplift - rec.uplift)[fresh]
    assert np.all(error <= np.maximum(0.05 * rec.uplift[fresh], 300.0)), error.max()
    assert rec.uplift.max() > 30e3  # not vacuous
    # The ERROR's timing at 2 mm/s (7 m/h) through the crossing: faster, the rise over the
    # wave window would enter the wave tension (0.3 x half of it: ~3 s early at 7 mm/s)
    rise = 0.002
    rec = moordyn.run_line(
        moordyn.PAPER_CHAIN, lambda t: (121.06, 0.0), lambda t: (23.2 + rise * t, rise), 200.0
    )
    config, bag = moordyn_bag(tmp_path / 'slower', rec, allowed=20e3)
    rows = replay_csv(tmp_path / 'slower', config, bag)
    level = np.array([r['level'] for r in rows])
    crossing = first(rec.t, rec.uplift > 20e3)
    assert 60.0 < crossing < 190.0
    assert abs(first(rec.t, level == 'ERROR') - crossing) <= 2.0


@pytest.mark.parametrize('amplitude, period', [(0.3, 7.0), (0.8, 12.0)])  # the grid: dynamics.md
def test_wave_motion_bound_and_error_against_moordyn(tmp_path, moordyn, amplitude, period):
    """The hook surges ``amplitude`` at ``period`` while the tide lifts the anchor: the bound
    at or above MoorDyn's anchor force in >= 95 % of the samples above 1 kN, its peak at most
    1.5 x the dynamic peak, the first ERROR within one wave period of the first lift."""
    w = 2.0 * math.pi / period
    top = {0.3: 22.6, 0.5: 22.3, 0.8: 21.7}[amplitude]  # peaks of some 40-120 kN
    rise = (top - 21.3) / 240.0

    def surge(t):  # the waves build over 20 s (no start-up shock)
        a, da = amplitude * min(t / 20.0, 1.0), (amplitude / 20.0 if t < 20.0 else 0.0)
        return 121.06 + a * math.sin(w * t), a * w * math.cos(w * t) + da * math.sin(w * t)

    rec = moordyn.run_line(moordyn.PAPER_CHAIN, surge, lambda t: (21.3 + rise * t, rise), 240.0)
    config, bag = moordyn_bag(tmp_path, rec)
    rows = replay_csv(tmp_path, config, bag)
    upper = column(rows, 'uplift_force_upper', 'line_11')
    dyn = rec.uplift
    lifted = dyn > 1e3
    assert lifted.sum() > 50
    assert np.mean(upper[lifted] >= dyn[lifted]) >= 0.95
    assert upper.max() <= 1.5 * dyn.max(), (upper.max(), dyn.max())
    level = np.array([r['level'] for r in rows])
    assert first(rec.t, level == 'ERROR') <= first(rec.t, dyn > 100.0) + period
