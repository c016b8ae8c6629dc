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
from catenary_monitor.core.alarms.latches import CONDITIONS
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.monitor.events import Tension
from catenary_monitor.core.twin.window import tick_grid

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


# --- MoorDyn: the paper's dock, one body with its 12 chains, through a tide rise and a storm -----

PERIOD = 8.0  # s, the storm's beam sea


def moordyn_dock_config(allowed=20e3):
    """The paper's dock (config/floating_dock.yaml) with MoorDyn's chain stiffness on every line
    and an allowed uplift of ``allowed`` [N]."""
    from dock_data import DOCK_YAML

    from catenary_monitor.core.config.parameters import config_from_params, load_params_file

    flat = load_params_file(DOCK_YAML)
    for name in flat['lines']:
        flat[f'{name}.ea'] = 6.63e8
        flat[f'{name}.allowed_uplift'] = allowed
    return config_from_params(flat)


@pytest.fixture(scope='module')
def dock_storm(moordyn):
    """60 s of the dock in MoorDyn: the tide rising 10 mm/s from 21.0 m, the dock drifting
    0.5 m to starboard over 30 s as the storm builds, a beam sea swaying it 0.3 m at 8 s from
    10 s on. 20 segments of 6 m per chain (MoorDyn's own touchdown error ~0.4 kN: fine for
    bounds and alarm times; ~10 s of MoorDyn)."""
    from catenary_monitor.core.body.dock_model import DockModel

    config = moordyn_dock_config()
    motion = moordyn.storm_motion(21.0, 0.01, (0.0, -0.5), 30.0, 0.3, PERIOD)
    chain = moordyn.Chain(segments=20)
    return config, moordyn.run_dock(DockModel.from_config(config), motion, 60.0, chain)


def test_dock_storm_uplift_bounds_alarms_and_estimate_against_moordyn(tmp_path, dock_storm):
    """Through ``catenary-monitor replay`` of a rosbag2 recording (12 load pins at 10 Hz, the
    gauge at 1 Hz): per line, ``uplift_force_upper`` at or above MoorDyn's anchor force in >= 95
    % of the samples above 1 kN and its peak at most 1.5 x the dynamic peak; the first ERROR
    no later than one wave period after MoorDyn's crossing of the allowed 20 kN, and none on a
    line whose anchor MoorDyn never lifts; the span solved at within the waves' reach of
    MoorDyn's; the dock estimate (the replay's /diagnostics) following the dock."""
    from catenary_monitor.core.twin.engine import recompute

    config, rec = dock_storm
    t_ns = T0_NS + np.rint(rec.t * 1e9).astype(np.int64)
    tensions = {
        line.name: (t_ns + 1000 * k, rec.tension[:, k]) for k, line in enumerate(config.lines)
    }
    depth = (t_ns[::10] - 50_000_000, rec.depth[::10])
    rows = replay_csv(tmp_path, config, write_bag(tmp_path / 'bag', config, tensions, depth))
    lifted_lines = grounded_lines = 0
    for k, line in enumerate(config.lines):
        dyn = rec.uplift[:, k]
        upper = column(rows, 'uplift_force_upper', line.name)
        level = np.array([r['level'] for r in rows if r['line'] == line.name])
        error_at = first(rec.t, level == 'ERROR')
        if dyn.max() == 0.0:
            grounded_lines += 1
            assert error_at == math.inf, line.name
            continue
        lifted = dyn > 1e3
        assert np.mean(upper[lifted] >= dyn[lifted]) >= 0.95, line.name
        assert upper.max() <= 1.5 * dyn.max(), (line.name, upper.max(), dyn.max())
        crossing = first(rec.t, dyn > 20e3)
        if crossing < math.inf:
            lifted_lines += 1
            assert error_at <= crossing + PERIOD, (line.name, error_at, crossing)
        # the span solved at: the dock estimate's, within the waves' reach of MoorDyn's
        words = np.array([r['span_source'] for r in rows if r['line'] == line.name])
        after = rec.t > 1.5  # the first tick's estimate on
        assert np.all(words[after] == 'dock_estimate'), line.name
        span = column(rows, 'span', line.name)
        assert np.max(np.abs(span - rec.span[:, k])[after]) < 0.25, line.name
    assert lifted_lines >= 4 and grounded_lines >= 4, (lifted_lines, grounded_lines)
    # the dock estimate at each tick against the dock's prescribed sway
    snaps = recompute(config, tensions, depth, snapshots=True).snapshots
    est = []
    for snap in snaps:
        values = {st.name: dict(st.values) for st in snap.statuses}['catenary_monitor: dock']
        if values['offset_y'] != 'nan':
            est.append(((snap.stamp_ns - T0_NS) * 1e-9, float(values['offset_y'])))
    t, y = np.array(est).T
    truth = np.interp(t, rec.t, rec.offset[:, 1])
    calm = t < 10.0  # before the waves: the slow drift alone
    assert calm.sum() >= 8 and np.max(np.abs(y - truth)[calm]) < 0.01
    assert np.max(np.abs(y - truth)) < 0.2  # m, the chains' own dynamics in the waves


def test_bench_dynamics_dock_runs_and_answers_in_json(moordyn, capsys):
    """``catenary-monitor bench-dynamics --dock --duration 15 --json``: one object, a row per
    line of the params, the dock estimate's figures (the long scene is docs/dynamics.md's)."""
    import json

    from catenary_monitor.cli.main import main

    assert main(['bench-dynamics', '--dock', '--duration', '15', '--json']) == 0
    out = json.loads(capsys.readouterr().out)
    assert [r['line'] for r in out['lines']] == [f'line_{k:02d}' for k in range(1, 13)]
    assert out['scene']['duration'] == 15.0 and out['dock']['ticks'] >= 14
    assert out['dock']['sway_error_calm_m'] < 0.01  # before the waves (from 20 s)
    assert all(r['span_error_m'] is not None for r in out['lines'])


def test_the_demo_on_moordyn_gives_the_storms_warnings(moordyn, tmp_path):
    """``catenary-monitor demo --moordyn``: the simulator's storm with its tensions from MoorDyn
    (the table the demo computes before the monitor starts) through the monitor with the demo's
    params (the chain's EA on every line): line 11 among the first to ERROR, its WARN (the
    bound) first; the lee side quiet; no line taken for a bad sensor. Not the static tensions:
    MoorDyn's differ by the chains' dynamics."""
    from catenary_monitor.cli.demo import DEMO_OVERRIDES, MOORDYN_EA
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.core.twin.engine import recompute
    from catenary_monitor.sim.scenario import MoorDynTensions, Scenario, default_config_path

    params = {**load_params_file(default_config_path()), **DEMO_OVERRIDES}
    params.update({f'{name}.ea': MOORDYN_EA for name in params['lines']})
    cfg = config_from_params(params)
    scenario = Scenario(cfg)
    MoorDynTensions.compute(scenario).save(str(tmp_path / 'table.npz'))
    source = MoorDynTensions.load(str(tmp_path / 'table.npz'), scenario)
    rng = np.random.default_rng(scenario.seed)
    t = np.arange(0.0, scenario.duration, 0.1)  # the demo's 10 Hz
    rows = np.array([source.tensions(x, rng) for x in t])
    static = np.array([scenario.tensions(x) for x in t])
    assert np.max(np.abs(rows - static)) > 50e3  # the chains' dynamics, not the equilibrium
    ns = T0_NS + np.rint(t * 1e9).astype(np.int64)
    tensions = {line.name: (ns, rows[:, k]) for k, line in enumerate(cfg.lines)}
    depth = (ns[::5] - 1000, np.array([scenario.depth(x) for x in t[::5]]))
    result = recompute(cfg, tensions, depth, start_ns=T0_NS - 10**9, snapshots=True)
    first_error = {
        r.name: min((x.time for x in r.transitions if x.new.name == 'ERROR'), default=math.inf)
        for r in result.lines
    }
    order = sorted(first_error, key=first_error.get)
    port = {'line_09', 'line_10', 'line_11', 'line_12'}
    assert 'line_11' in order[:3] and set(order[:3]) <= port, order
    assert all(first_error[f'line_{k:02d}'] == math.inf for k in (1, 2, 3, 4)), first_error
    line_11 = result.lines[[r.name for r in result.lines].index('line_11')]
    tr = [x for x in line_11.transitions if 'STALE' not in (x.old.name, x.new.name)]
    assert tr[0].new.name == 'WARN' and tr[1].new.name == 'ERROR', [x.message for x in tr]
    words = {
        dict(st.values).get('sensor_state')
        for sn in result.snapshots
        for st in sn.statuses
        if not st.name.endswith(': tide')
    }
    assert 'inconsistent' not in words and 'suspect' not in words, words


def test_the_simulator_refuses_a_bad_moordyn_table_in_one_line(tmp_path, capsys):
    from catenary_monitor.ros.simulator import main

    bad = tmp_path / 'table.npz'
    np.savez(bad, times=np.arange(3.0), tensions=np.ones((3, 5)))  # 5 lines, not 12
    assert main(['--dynamics', 'moordyn', '--moordyn-table', str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'not a table of 12 lines' in err[0], err
    bad.write_bytes(b'not an npz')
    assert main(['--dynamics', 'moordyn', '--moordyn-table', str(bad)]) == 2
    assert capsys.readouterr().err.startswith('dock_simulator: --moordyn-table:')


def test_without_moordyn_the_demo_and_the_simulator_say_so_in_one_line(
    tmp_path, capsys, monkeypatch
):
    """``demo --moordyn`` and ``--dynamics moordyn`` where MoorDyn is not installed: exit 2 and
    one line naming the extra, before anything starts."""
    from catenary_monitor.cli.demo import run_demo
    from catenary_monitor.sim import moordyn_dock
    from catenary_monitor.ros.simulator import main

    monkeypatch.setattr(moordyn_dock, 'available', lambda: False)
    assert run_demo(str(tmp_path / 'demo'), moordyn=True) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'needs MoorDyn' in err[0] and '[dynamics]' in err[0], err
    assert not (tmp_path / 'demo').exists()
    assert main(['--dynamics', 'moordyn']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'needs MoorDyn' in err[0], err
