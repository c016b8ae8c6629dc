"""Live consistency: the dock's offset and load from all tensions, the residual per line, and
a drifting sensor flagged, alone; the vectorized twin computes the same (event by event)."""

import math

import numpy as np
import pytest
from dock_data import ACCURACY, dock_config, generate_dock, true_tensions
from replay_data import T0_NS, core_steps
from test_batch import compare, ticks_for

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.estimate import estimate_dock
from catenary_monitor.core.alarms import components
from catenary_monitor.core.alarms.latches import CONDITIONS
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.monitor.events import Tick
from catenary_monitor.core.twin.engine import recompute

DRIFTING = 8  # line_09, on the windward side of the generated wind


def _inconsistent(step_list, config):
    """Per line: stamps (s) at which its 'inconsistent' condition appears in a message."""
    out = {line.name: [] for line in config.lines}
    for s in step_list:
        for c in s.transitions:
            if 'tension inconsistent' in c.transition.message and c.component in out:
                out[c.component].append(c.transition.time)
    return out


def _latched(core):
    k = CONDITIONS.index('inconsistent')
    return [line.config.name for line in core.state.lines if line.state.latches[k].active]


@pytest.mark.parametrize('drifting', [DRIFTING, 4])  # line_09 windward, line_05 lee
def test_a_drifting_sensor_is_flagged_and_only_that_line(drifting):
    from replay_data import events_of

    config = dock_config(tension_timeout=2.0)
    seconds = 180.0
    tensions, depth = generate_dock(config, seconds, drifting=drifting, seed=3)
    ticks = ticks_for(tensions, depth)
    bad = config.lines[drifting].name
    core = MonitorCore(config, T0_NS)
    latched_by_line = {line.name: 0 for line in config.lines}
    flagged_at = None
    for ev in events_of(config, tensions, depth, ticks):
        core.step(ev)
        if isinstance(ev, Tick):
            for name in _latched(core):
                latched_by_line[name] += 1
                if name == bad and flagged_at is None:
                    flagged_at = (ev.stamp_ns - T0_NS) * 1e-9
    assert [n for n, c in latched_by_line.items() if c] == [bad], latched_by_line
    # Raised after the drift began (25 % of the record) and held to the end.
    assert flagged_at is not None and 0.25 * seconds < flagged_at < 0.6 * seconds
    assert _latched(core) == [bad]
    snap = core.snapshot(core.state.last_ns)
    status = {st.name: st for st in snap.statuses}
    line = status[f'catenary_monitor: {bad}']
    values = dict(line.values)
    assert values['sensor_state'] == 'inconsistent'
    detail = values['detail']  # the full text; the message is its headline
    assert 'check the tension sensor' in detail and 'anchor (dragging)' in detail
    assert float(values['residual']) > 0.1 * float(values['expected_tension'])
    assert float(values['residual_sigma']) > config.dock.residual_limit
    others = [dict(status[f'catenary_monitor: {n.name}'].values) for n in config.lines]
    assert sum(v['sensor_state'] == 'inconsistent' for v in others) == 1
    # The dock status: OK, the offset and load of the generating equilibrium.
    dock = status['catenary_monitor: dock']
    assert dock.level.name == 'OK' and bad in dict(dock.values)['detail']
    d = dict(dock.values)
    grid, _, offsets = true_tensions(config, seconds)
    assert abs(float(d['offset_y']) - offsets[-1, 1]) < 0.06  # m; sigma of the fit ~0.01 m
    assert abs(float(d['offset_x']) - offsets[-1, 0]) < 0.25  # surge: sigma ~0.05 m
    assert float(d['load_y']) < -1e6  # a wind from about port beam pushes to starboard


@pytest.mark.parametrize('seed', [11, 12, 13])
def test_consistent_sensors_are_never_flagged(seed):
    config = dock_config(tension_timeout=2.0)
    tensions, depth = generate_dock(config, 180.0, seed=seed)
    ticks = ticks_for(tensions, depth)
    core, steps = core_steps(config, tensions, depth, ticks, T0_NS)
    assert _inconsistent(steps, config) == {line.name: [] for line in config.lines}
    assert _latched(core) == []
    values = {st.name: dict(st.values) for st in core.snapshot(core.state.last_ns).statuses}
    states = [values[f'catenary_monitor: {n.name}']['sensor_state'] for n in config.lines]
    # 'unchecked': a line whose last sample is older than tension_timeout at the record's end
    assert set(states) <= {'ok', 'unchecked'} and states.count('ok') >= 10


def test_the_twin_computes_the_same_dock_estimate_event_by_event():
    config = dock_config(tension_timeout=2.0)
    tensions, depth = generate_dock(
        config, 120.0, drifting=DRIFTING, drift_from=0.1, drift_to=0.3, seed=5
    )
    ticks = ticks_for(tensions, depth)
    cuts = [T0_NS + int(s * 1e9) for s in (10.3, 40.0, 40.6, 77.7)]
    steps = compare(config, tensions, depth, ticks, cuts)
    # Not vacuous: the drifting line is flagged, and the dock status changes level.
    assert any(
        'tension inconsistent' in dict(st.values)['detail']
        for s in steps
        if s.snapshot is not None
        for st in s.snapshot.statuses
    )
    assert any(c.component == 'dock' for s in steps for c in s.transitions)


def test_replay_flags_the_same_line():
    config = dock_config(tension_timeout=2.0)
    tensions, depth = generate_dock(
        config, 120.0, drifting=DRIFTING, drift_from=0.1, drift_to=0.3, seed=6
    )
    rep = recompute(config, tensions, depth, snapshots=True)
    last = {st.name: dict(st.values) for st in rep.snapshots[-1].statuses}
    states = {n: v.get('sensor_state') for n, v in last.items() if 'sensor_state' in v}
    assert [n for n, s in states.items() if s == 'inconsistent'] == ['catenary_monitor: line_09']
    assert 'catenary_monitor: dock' in last


def test_without_accuracy_the_default_accuracy_flags_the_drifting_line():
    """No tension_accuracy in the params: every load pin is taken at 0.5 % of its MBL, so the
    consistency check works out of the box and flags the drifting line (and only it)."""
    config = dock_config(accuracy=None, tension_timeout=2.0)
    tensions, depth = generate_dock(
        config, 90.0, drifting=DRIFTING, drift_from=0.1, drift_to=0.3, seed=7
    )
    ticks = ticks_for(tensions, depth)
    core, steps = core_steps(config, tensions, depth, ticks, T0_NS)
    values = {st.name: dict(st.values) for st in core.snapshot(core.state.last_ns).statuses}
    lines = [values[f'catenary_monitor: {n.name}'] for n in config.lines]
    words = [v['sensor_state'] for v in lines]
    assert words[DRIFTING] == 'inconsistent', words
    assert 'inconsistent' not in words[:DRIFTING] + words[DRIFTING + 1 :], words
    assert all(math.isfinite(float(v['residual'])) for v in lines)
    assert values['catenary_monitor: dock']['offset_y'] != 'nan'


def test_the_dock_is_stale_until_three_lines_report():
    config = dock_config()
    core = MonitorCore(config, T0_NS)
    step = core.step(Tick(T0_NS + 10**9))
    dock = {st.name: st for st in step.snapshot.statuses}['catenary_monitor: dock']
    assert dock.level.name == 'STALE' and 'needs 3' in dict(dock.values)['detail']
    assert [k for k, _ in dock.values] == [
        'offset_x',
        'offset_y',
        'yaw_deg',
        'load_x',
        'load_y',
        'load_mz',
        'readings',
        *components.KEYS,  # its alarm's (acknowledgeable): alarm_state first, as before
        'conditions',
        'detail',
        'response',
    ]
    # blind lines: a consequence, shown and not annunciated (the sensors alarm's)
    assert dict(dock.values)['alarm_state'] == 'suppressed'


def test_no_dock_status_without_the_dock_geometry():
    from replay_data import dock_config as line_config

    core = MonitorCore(line_config(3), T0_NS)
    names = [st.name for st in core.step(Tick(T0_NS + 10**9)).snapshot.statuses]
    assert 'catenary_monitor: dock' not in names
    keys = dict(core.snapshot(T0_NS).statuses[0].values)
    assert keys['sensor_state'] == 'ok' and 'residual' not in keys  # the line's own state only


def test_estimate_recovers_offset_and_load_and_is_batch_invariant():
    config = dock_config()
    model = DockModel.from_config(config)
    _, truth, offsets = true_tensions(config, 60.0, grid=10.0)
    rng = np.random.default_rng(1)
    measured = truth + rng.normal(0.0, ACCURACY, truth.shape)
    n = len(truth)
    est = estimate_dock(model, np.full(n, 20.85), measured, np.ones(truth.shape, bool))
    assert est.valid.all()
    # The sway estimate's sigma is ~0.02 m at light wind (0.01 m in a gale): 5 sigma.
    assert np.max(np.abs(est.offset[:, 1] - offsets[:, 1])) < 0.12
    # Noise-free tensions give the offset back to the fit's precision.
    exact = estimate_dock(model, np.full(n, 20.85), truth, np.ones(truth.shape, bool))
    np.testing.assert_allclose(exact.offset, offsets, atol=1e-6)
    np.testing.assert_allclose(exact.residual, 0.0, atol=1e-3 * ACCURACY)
    # One estimate at a time gives exactly the same numbers as all at once.
    for i in range(n):
        one = estimate_dock(model, np.full(1, 20.85), measured[i : i + 1], np.ones((1, 12), bool))
        assert np.array_equal(one.offset[0], est.offset[i])
        assert np.array_equal(one.normalized[0], est.normalized[i], equal_nan=True)


def test_implausible_readings_are_left_out_of_the_dock_estimate_alike():
    """1e300 N, 100 MN (> 10 x MBL) and a 1e6 m depth: left out of the fit in the core and
    its twin alike; the dock estimate goes on from the other lines."""
    config = dock_config(tension_timeout=2.0)
    tensions, depth = generate_dock(config, 40.0, seed=6)
    name = config.lines[3].name
    t, v = tensions[name]
    v = v.copy()
    v[50:60], v[100:110] = 1e300, 1e8
    tensions[name] = (t, v)
    dv = depth[1].copy()
    dv[5] = 1e6
    depth = (depth[0], dv)
    steps = compare(config, tensions, depth, ticks_for(tensions, depth))
    for lo, hi in ((t[52], t[59]), (t[102], t[109])):  # the 100 MN stretch broke the fit before
        dock = [
            st
            for s in steps
            if s.snapshot is not None and s.kind == 'tick' and lo < s.stamp_ns < hi
            for st in s.snapshot.statuses
            if st.name == 'catenary_monitor: dock'
        ]
        assert dock and all(st.level.name == 'OK' for st in dock), dock


def test_an_estimate_flagging_more_than_a_third_of_the_lines_tests_none():
    """One wrong reading (a cell reading a tenth) is flagged alone; readings so wrong that
    more than a third of the lines disagree leave the estimate standing for none of them: no
    line is flagged (a four-line dock's one wrong cell biased the fit so that the three good
    lines disagreed with it)."""
    from catenary_monitor.core.rules.dock_watch import Smoothing, decide_dock, most_flagged

    config = dock_config(tension_timeout=2.0)
    grid, tens, _ = true_tensions(config, 40.0)
    model = DockModel.from_config(config)
    n, m = tens.shape
    stamps = np.repeat(grid[:, None], m, axis=1)
    args = (grid, np.full(n, 20.85), np.ones(n, bool))

    def decide(readings):
        return decide_dock(model, config, *args, readings, stamps, Smoothing.initial(m))[0]

    one = tens.copy()
    one[:, DRIFTING] *= 0.1
    d = decide(one)
    assert np.flatnonzero(d.flagged[-1]).tolist() == [DRIFTING]
    many = tens.copy()
    many[:, : m // 2] *= 0.5  # half the lines read half (still above the chain's weight)
    d = decide(many)
    beyond = np.sum(np.abs(d.line_inputs[..., 3]) > config.dock.residual_limit, axis=1)
    assert (beyond > most_flagged(m)).any()  # not vacuous: the fit would blame many lines
    assert not d.flagged[beyond > most_flagged(m)].any()
    assert np.isnan(d.line_inputs[beyond > most_flagged(m)][..., 0]).all()
    assert (d.flagged.sum(axis=1) <= most_flagged(m)).all()
