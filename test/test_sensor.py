"""Sensor sanity (core/rules/sensor_state.py): each line state and each depth state raised by its
pattern and cleared after, live (the core event by event) and replay (the batch twin) agreeing on
every output, level, message and snapshot; the demo's storm raises none."""

import math

import numpy as np
import pytest
from replay_data import T0_NS
from test_batch import compare, ticks_for

from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.rules import sensor_state
from catenary_monitor.core.rules.plausible import UNIT_FACTORS
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.twin.engine import recompute
from catenary_monitor.core.physics.solve import solve

W, X, MBL, DEPTH = 1300.0, 120.0, 4.827e6, 20.85
SECONDS = 300
EVENT_S = (100.0, 140.0)  # the pattern's span [s]
CUTS = [T0_NS + int(s * 1e9) for s in (50.3, 120.7, 201.1)]


def scene(seed=0):
    """Three calm lines at 5 Hz (waves 1 %, noise 0.3 %) and a slowly rising tide at 1 Hz."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, SECONDS, 0.2)
    depth_t = np.arange(0.0, SECONDS, 1.0)
    depth = DEPTH + 1e-3 * depth_t + rng.normal(0.0, 0.01, depth_t.size)
    base = solve(W, DEPTH, horizontal=372e3, anchor_distance=X).top_tension
    tensions = [
        base * (1 + 0.01 * np.sin(2 * np.pi * t / 8.0 + k) + 0.003 * rng.standard_normal(t.size))
        for k in range(3)
    ]
    return t, tensions, depth_t, depth


def config(**alarm):
    alarm.setdefault('warn_clear_hold', 10.0)
    alarm.setdefault('margin_clear_hold', 10.0)
    alarm.setdefault('clear_hold', 10.0)
    alarm.setdefault('stuck_time', 20.0)
    alarm.setdefault('sensor_hold', 5.0)
    # A trend known within the scene: an unknown time to uplift would hold a warning raised
    # while a line was lifted (unknown is not "never").
    alarm.setdefault('tide_trend_window', 30.0)
    lines = tuple(
        LineConfig(name=f'line_{k:02d}', weight=W, anchor_distance=X, mbl=MBL) for k in range(3)
    )
    return MonitorConfig(lines=lines, alarm=AlarmConfig(**alarm))


def columns(t, tensions, depth_t, depth):
    ns = T0_NS + np.rint(t * 1e9).astype(np.int64) + 1000
    d_ns = T0_NS + np.rint(depth_t * 1e9).astype(np.int64)
    return {f'line_{k:02d}': (ns + 17 * k, v) for k, v in enumerate(tensions)}, (d_ns, depth)


def run(cfg, t, tensions, depth_t, depth):
    """The core and its twin on one scene (they must agree); the core's steps."""
    cols, dep = columns(t, tensions, depth_t, depth)
    ticks = ticks_for(cols, dep, rate=1.0)
    return compare(cfg, cols, dep, ticks, CUTS)


def line_codes(steps, k=0):
    """(time s, sensor_state code) of line k's outputs."""
    at = OUTPUT_FIELDS.index('sensor_state')
    return [
        ((s.stamp_ns - T0_NS) * 1e-9, int(o.values[at]))
        for s in steps
        for o in s.outputs
        if o.line == k
    ]


def line_statuses(steps, k):
    """(time s, status) of line k in every snapshot."""
    name = f'catenary_monitor: line_{k:02d}'
    return [
        ((s.stamp_ns - T0_NS) * 1e-9, st)
        for s in steps
        if s.snapshot is not None
        for st in s.snapshot.statuses
        if st.name == name
    ]


def transitions(steps, name):
    return [c.transition for s in steps for c in s.transitions if c.component == name]


def during(t):
    return (t >= EVENT_S[0]) & (t < EVENT_S[1])


def plateau(t, base, level, ramp=30.0):
    """``base`` moved to ``level`` during the event, ramped geometrically over ``ramp`` s on
    each side (no spike, no collapse: a factor 18 in 30 s is 0.62 per 5 s)."""
    u = np.clip(np.minimum(t - EVENT_S[0] + ramp, EVENT_S[1] + ramp - t) / ramp, 0.0, 1.0)
    return base * (level / base) ** u


def assert_raised_and_cleared(steps, state, level, what, k=0):
    codes = line_codes(steps, k)
    code = sensor_state.LINE_STATES.index(state)
    seen = [t for t, c in codes if c == code]
    assert seen and EVENT_S[0] - 30.0 <= seen[0] <= EVENT_S[1] + 25.0, (state, seen[:3])
    assert codes[-1][1] == sensor_state.OK, state
    assert all(c in (sensor_state.OK, code) for _, c in codes), (state, set(c for _, c in codes))
    shown = line_statuses(steps, k)
    raised = [t for t, st in shown if st.level.name == level and what in dict(st.values)['detail']]
    assert raised, (state, {(st.level.name, st.message) for _, st in shown})
    assert dict(shown[-1][1].values)['sensor_state'] == 'ok'
    assert {dict(st.values)['sensor_state'] for t, st in shown if t == raised[0]} == {state}
    tr = transitions(steps, f'line_{k:02d}')
    assert tr[-1].new.name == 'OK' and tr[-1].time > raised[0]
    others = [c for j in (1, 2) if j != k for _, c in line_codes(steps, j)]
    assert set(others) <= {sensor_state.OK}, state


def test_a_normal_record_raises_nothing():
    steps = run(config(), *scene())
    for k in range(3):
        assert {c for _, c in line_codes(steps, k)} == {sensor_state.OK}
    assert [x.new.name for k in range(3) for x in transitions(steps, f'line_{k:02d}')] == [
        'OK'
    ] * 3


def test_stuck_tension_sensor_while_the_dock_moves():
    t, tensions, depth_t, depth = scene(1)
    frozen = during(t)
    tensions[0][frozen] = tensions[0][np.argmax(frozen)]
    assert_raised_and_cleared(run(config(), t, tensions, depth_t, depth), 'stuck', 'WARN', 'stuck')


def test_a_still_dock_is_not_a_stuck_sensor():
    t, tensions, depth_t, depth = scene(2)
    still = t >= EVENT_S[0]
    for v in tensions:
        v[still] = v[np.argmax(still)]
    depth[depth_t >= EVENT_S[0]] = depth[int(EVENT_S[0])]
    steps = run(config(), t, tensions, depth_t, depth)
    assert {c for k in range(3) for _, c in line_codes(steps, k)} == {sensor_state.OK}


def test_spike():
    t, tensions, depth_t, depth = scene(3)
    i = int(np.argmax(t >= EVENT_S[0]))
    tensions[0][i] += 60e3  # a step above 0.02 MBL/s over the 0.2 s sample
    steps = run(config(tension_rate_max=0.02), t, tensions, depth_t, depth)
    assert_raised_and_cleared(steps, 'spike', 'WARN', 'spike')


def test_samples_delivered_in_a_bunch_are_no_spike():
    """A storm's normal 16 kN step between two 20 Hz readings that arrived 1 ms apart (DDS
    delivered them together): no spike with the default stamp_jitter; the rule without it
    would call it one. A real jump (1 MN) is still a spike."""
    a = AlarmConfig()
    rate = a.tension_rate_max * MBL
    mem = sensor_state.sample(
        sensor_state.Memory(), 10.0, 1.2e6, a.tension_resolution, rate, a.stamp_jitter
    )
    bunched = sensor_state.sample(mem, 10.001, 1.216e6, a.tension_resolution, rate, a.stamp_jitter)
    assert bunched.spiked == -math.inf
    assert (
        sensor_state.sample(mem, 10.001, 1.216e6, a.tension_resolution, rate, 0.0).spiked == 10.001
    )
    jump = sensor_state.sample(mem, 10.05, 2.2e6, a.tension_resolution, rate, a.stamp_jitter)
    assert jump.spiked == 10.05
    _, sp, _ = sensor_state.samples(
        mem,
        np.array([10.001, 10.05]),
        np.array([1.216e6, 2.216e6]),
        a.tension_resolution,
        rate,
        a.stamp_jitter,
    )
    assert sp.tolist() == [-math.inf, 10.05]


def test_over_mbl():
    t, tensions, depth_t, depth = scene(4)
    tensions[0][:] = plateau(t, tensions[0], 1.05 * MBL)
    cfg = config(tension_rate_max=100.0)
    assert_raised_and_cleared(run(cfg, t, tensions, depth_t, depth), 'over_mbl', 'ERROR', 'MBL')


def test_slack_keeps_the_impossible_input_status_and_adds_the_state():
    t, tensions, depth_t, depth = scene(5)
    tensions[0][:] = plateau(t, tensions[0], 0.8 * W * DEPTH)
    cfg = config(tension_rate_max=100.0)
    steps = run(cfg, t, tensions, depth_t, depth)
    assert_raised_and_cleared(steps, 'slack', 'ERROR', 'own weight')
    status = OUTPUT_FIELDS.index('status')
    assert any(o.values[status] != 0 for s in steps for o in s.outputs if o.line == 0)


def test_suspected_parted_line():
    """The chain parted below the hook: the tension falls to the hanging rest's weight; the
    other lines need not rise. Named ``suspected_parted`` as long as it stays down (not slack,
    not an impossible input)."""
    t, tensions, depth_t, depth = scene(6)
    after = during(t)
    tensions[0][after] = 0.6 * W * DEPTH  # the chain left below the hook: under w*h
    cfg = config(tension_rate_max=100.0)
    steps = run(cfg, t, tensions, depth_t, depth)
    assert_raised_and_cleared(steps, 'suspected_parted', 'ERROR', 'parted')
    codes = [c for s, c in line_codes(steps) if EVENT_S[0] + 2.0 <= s < EVENT_S[1]]
    assert set(codes) == {sensor_state.PARTED}, set(codes)  # held past sensor_hold (5 s)


def test_a_line_that_falls_but_still_hangs_is_not_parted():
    t, tensions, depth_t, depth = scene(6)
    after = during(t)
    tensions[0][after] *= 0.2  # 80 kN: above the hanging chain's weight
    steps = run(config(tension_rate_max=100.0), t, tensions, depth_t, depth)
    assert sensor_state.PARTED not in {c for _, c in line_codes(steps)}


def test_a_line_that_falls_with_the_others_is_not_parted():
    t, tensions, depth_t, depth = scene(7)
    after = during(t)
    for k in range(3):
        tensions[k][after] *= 0.3
    steps = run(config(tension_rate_max=100.0), t, tensions, depth_t, depth)
    assert {c for k in range(3) for _, c in line_codes(steps, k)} == {sensor_state.OK}


def tide_words(steps):
    out = []
    for s in steps:
        if s.snapshot is not None:
            tide = [st for st in s.snapshot.statuses if st.name.endswith(': tide')][0]
            out.append(((s.stamp_ns - T0_NS) * 1e-9, dict(tide.values)['sensor_state'], tide))
    return out


@pytest.mark.parametrize(
    'state, level, what',
    [('stuck', 'WARN', 'stuck'), ('spike', 'WARN', 'spike'), ('out_of_range', 'ERROR', 'chart')],
)
def test_depth_sensor_states(state, level, what):
    t, tensions, depth_t, depth = scene(8)
    bad = during(depth_t)
    if state == 'stuck':
        depth[bad] = depth[np.argmax(bad)]
    elif state == 'spike':
        depth[np.argmax(bad)] += 3.0
    else:
        depth[:] = plateau(depth_t, depth, depth + 10.0)  # a wrong datum: 31 m on 15-25 m
    cfg = config(depth_min=15.0, depth_max=25.0)
    steps = run(cfg, t, tensions, depth_t, depth)
    words = tide_words(steps)
    hit = [x for x in words if x[1] == state]
    assert hit and EVENT_S[0] - 30.0 <= hit[0][0] <= EVENT_S[1] + 25.0
    assert hit[0][2].level.name == level and what in dict(hit[0][2].values)['detail']
    assert words[-1][1] == 'ok' and words[-1][2].level.name == 'OK'
    assert {w for _, w, _ in words} == {'ok', state}


def test_a_state_for_every_code_and_a_word_for_every_state():
    assert (
        sensor_state.LINE_STATES[sensor_state.OK] == 'ok'
        and len(set(sensor_state.LINE_STATES)) == len(sensor_state.LINE_STATES)
        and len(sensor_state.LINE_STATES) == sensor_state.UNITS_BASE + len(UNIT_FACTORS) + 2
    )
    for code in range(1, 7):
        assert sensor_state.line_message(code, 1e6, MBL)
    for code in range(1, len(sensor_state.DEPTH_STATES)):
        assert sensor_state.depth_message(code, 20.0, AlarmConfig())
    assert sensor_state.line_word(sensor_state.OK, 'inconsistent') == 'inconsistent'
    assert sensor_state.line_word(sensor_state.SLACK, 'inconsistent') == 'slack'
    assert math.isinf(sensor_state.Memory().changed)


def demo_record():
    """The simulator's storm at its 20 Hz tension and 2 Hz depth rates through the monitor
    with the demo's overrides (the batch twin): (config, result)."""
    from catenary_monitor.cli.demo import DEMO_OVERRIDES
    from catenary_monitor.core.config.parameters import config_from_params, load_params_file
    from catenary_monitor.sim.scenario import Scenario, default_config_path

    params = load_params_file(default_config_path())
    params.update(DEMO_OVERRIDES)
    cfg = config_from_params(params)
    scenario = Scenario(cfg)
    rng = np.random.default_rng(scenario.seed)
    t = np.arange(0.0, scenario.duration, 0.05)
    rows = np.array([scenario.tensions(x, rng) for x in t])
    ns = T0_NS + np.rint(t * 1e9).astype(np.int64)
    tensions = {line.name: (ns, rows[:, k]) for k, line in enumerate(cfg.lines)}
    d_ns = ns[::10] - 1000
    depth = (d_ns, np.array([scenario.depth(x) for x in t[::10]]))
    return cfg, recompute(cfg, tensions, depth, start_ns=T0_NS - 10**9, snapshots=True)


def test_the_demo_storm_raises_no_sensor_state():
    """The demo's storm: every line and the depth sensor stay ok, while line 11 lifts (not
    vacuous)."""
    cfg, result = demo_record()
    for r in result.lines:
        assert set(r.values['sensor_state'].tolist()) == {0.0}, r.name
    words = {
        (st.name.endswith(': tide'), dict(st.values)['sensor_state'])
        for sn in result.snapshots
        for st in sn.statuses
        if 'sensor_state' in dict(st.values)
    }
    # (no_data: the snapshots before the first depth sample, no state to decide yet)
    assert {w for tide, w in words if tide} == {'no_data', 'ok'}
    assert {w for tide, w in words if not tide} <= {'ok', 'unchecked'}  # the dock model's
    assert len(result.snapshots) > 50
    line_11 = result.lines[[r.name for r in result.lines].index('line_11')]
    assert np.nanmax(line_11.values['uplift_force']) > 0.0


def test_the_demo_warns_of_the_uplift_before_line_11_lifts():
    """The demo's dock in equilibrium under the storm, the tide rising: line 11 is the first to
    lift, its first alarm a WARN (the bound: waves and sensor accuracy) before its ERROR; the
    lee lines stay quiet; the chart's uplift mark (from the outputs) is not before the ERROR."""
    from catenary_monitor.cli.demo import uplift_warning_times

    cfg, result = demo_record()
    names = [r.name for r in result.lines]
    line = result.lines[names.index('line_11')]
    tr = [x for x in line.transitions if 'STALE' not in (x.old.name, x.new.name)]
    assert tr[0].new.name == 'WARN' and tr[1].new.name == 'ERROR', [x.message for x in tr]
    assert 'uplift possible' in tr[0].message or 'anchor uplift in' in tr[0].message
    first_error = {
        r.name: min((x.time for x in r.transitions if x.new.name == 'ERROR'), default=math.inf)
        for r in result.lines
    }
    assert min(first_error, key=first_error.get) == 'line_11'
    assert all(first_error[f'line_{k:02d}'] == math.inf for k in (1, 2, 3, 4))  # lee side
    t = (line.t_ns - T0_NS) * 1e-9
    data = np.column_stack([line.values[k] for k in ('time_to_uplift', 'uplift_force')])
    idx = {'time_to_uplift': 0, 'uplift_force': 1}
    _, first_lift = uplift_warning_times(t, data, idx, cfg.alarm.uplift_time_warn)
    assert first_lift >= tr[1].time - T0_NS * 1e-9 - 1e-6  # the dynamic ERROR comes first


def test_node_md_sensor_parameter_table_is_generated():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown

    page = (Path(__file__).resolve().parents[1] / 'docs' / 'node.md').read_text()
    begin, end = '<!-- sensor-parameters:begin -->\n', '<!-- sensor-parameters:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('sensor')


def test_moved_since_is_the_other_lines_newest_change():
    """sensor_state._moved_since (two reductions per row) against its definition, line by line:
    with ties, never-changed lines (-inf), NaN, one line and no ticks."""
    rng = np.random.default_rng(7)
    for trial in range(300):
        n, m = int(rng.integers(0, 20)), int(rng.integers(1, 14))
        changed = rng.choice([-np.inf, 1.0, 2.0, 3.0, np.nan], (n, m), p=[0.2, 0.3, 0.2, 0.2, 0.1])
        depth = rng.choice([-np.inf, 1.5, 2.0, np.nan], n)
        want = np.zeros((n, m), bool)
        for k in range(m):
            others = np.delete(changed, k, axis=1)
            newest = np.max(others, axis=1) if m > 1 else np.full(n, -np.inf)
            with np.errstate(invalid='ignore'):
                want[:, k] = np.maximum(newest, depth) > changed[:, k]
        assert np.array_equal(sensor_state._moved_since(changed, depth), want), trial


def test_the_memory_column_loop_equals_the_scalar_sample():
    """sensor_state.samples (the memory's column loop) equals repeated sensor_state.sample,
    memory included: steps within and across the resolution, spikes, non-finite readings,
    equal stamps, a fresh memory (NaN reading, never changed) and one with history."""
    rng = np.random.default_rng(9)
    for trial in range(600):
        n = int(rng.integers(0, 40))
        stamps = 100.0 + np.cumsum(rng.choice([0.0, 0.05, 0.5, 3.0], n))
        values = 1e5 + np.cumsum(rng.choice([0.0, 3.0, -40.0, 2e4], n))
        bad = rng.random(n) < 0.15
        values[bad] = rng.choice([np.nan, np.inf, -np.inf], int(bad.sum()))
        mem = sensor_state.Memory() if trial % 2 else sensor_state.Memory(1e5, 99.0, 50.0, -np.inf)
        resolution = float(rng.choice([0.0, 10.0, 100.0]))
        want_ch, want_sp, m = [], [], mem
        for stamp, value in zip(stamps.tolist(), values.tolist()):
            m = sensor_state.sample(m, stamp, value, resolution, 500.0, 0.1)
            want_ch.append(m.changed)
            want_sp.append(m.spiked)
        ch, sp, end = sensor_state.samples(mem, stamps, values, resolution, 500.0, 0.1)
        assert ch.tolist() == want_ch and sp.tolist() == want_sp, trial
        assert end == m, trial
