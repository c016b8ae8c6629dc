"""The vectorized twin (core.twin.engine.advance) against the monitor core itself, event by event.

The scalar :class:`MonitorCore` is the oracle: the same events are stepped through it one at a
time and handed to ``advance`` as columns (in one window or several), and every output, level,
transition and snapshot must agree (values to 1e-12, everything else exactly), as must the
core's state afterwards.
"""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from replay_data import T0_NS, core_steps, dock_config, events_of, generate

from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS, VALUE_FIELDS, CoreState, LineState
from catenary_monitor.core.monitor.events import Acknowledge, Depth, Reconfigure, Tension, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.twin.window import (
    COLUMNS,
    KIND_TENSION,
    SnapshotColumns,
    Window,
    slice_window,
    tick_grid,
)
from catenary_monitor.core.twin.engine import advance, recompute, run_log
from catenary_monitor.core.physics.result import Status


def window_of(config, tensions, depth, ticks, lo=None, hi=None):
    """The columns of the events with lo <= t < hi."""

    def cut(t, *cols):
        keep = np.ones(len(t), bool)
        if lo is not None:
            keep &= t >= lo
        if hi is not None:
            keep &= t < hi
        return (t[keep], *(c[keep] for c in cols))

    empty = (np.zeros(0, np.int64), np.zeros(0))
    cols = [cut(*tensions.get(line.name, empty)) for line in config.lines]
    return Window(cols, cut(*depth), cut(ticks)[0])


def _nan_free(x):
    """``x`` comparable with ==: NaN floats as None (NaN != NaN would fail equal states),
    arrays as lists, dataclasses and named tuples field by field."""
    if isinstance(x, float) and math.isnan(x):
        return None
    if isinstance(x, np.ndarray):
        return _nan_free(tuple(map(_nan_free, x.tolist())))
    if isinstance(x, list):
        return [_nan_free(v) for v in x]
    if isinstance(x, tuple):
        return type(x)(*map(_nan_free, x)) if hasattr(x, '_fields') else tuple(map(_nan_free, x))
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (
            type(x).__name__,
            {f.name: _nan_free(getattr(x, f.name)) for f in dataclasses.fields(x)},
        )
    if hasattr(x, '__dict__') and not callable(x):
        return (type(x).__name__, {k: _nan_free(v) for k, v in vars(x).items()})
    return x


#: LineState fields fixed by the configuration (not decisions): left out of the comparison.
LINE_CONFIG_FIELDS = ('config', 'alarm', 'hardware_id')


def core_state(core):
    """Every field of the core's state (:class:`CoreState`, each line's :class:`LineState`):
    ``(per line {field: value}, {field: value})``, the solved ``values`` compared apart (to
    rounding). A field added to the state is compared here without anyone listing it."""
    lines = [
        {
            f.name: (
                getattr(line, f.name) if f.name == 'values' else _nan_free(getattr(line, f.name))
            )
            for f in dataclasses.fields(LineState)
            if f.name not in LINE_CONFIG_FIELDS
        }
        for line in core.state.lines
    ]
    rest = {
        f.name: _nan_free(getattr(core.state, f.name))
        for f in dataclasses.fields(CoreState)
        if f.name != 'lines'
    }
    return lines, rest


def assert_same_state(twin, core):
    """The twin left ``twin`` in the state stepping left ``core`` in, field by field."""
    got_lines, got_rest = core_state(twin)
    want_lines, want_rest = core_state(core)
    differ = [k for k in want_rest if got_rest[k] != want_rest[k]]
    assert not differ, {k: (got_rest[k], want_rest[k]) for k in differ}
    for k, (g, w) in enumerate(zip(got_lines, want_lines)):
        assert_same_float(g.pop('values'), w.pop('values'), 'values')
        differ = [f for f in w if g[f] != w[f]]
        assert not differ, (k, {f: (g[f], w[f]) for f in differ})


def assert_same_float(a, b, what):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, what
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9, equal_nan=True, err_msg=what)


def assert_statuses_agree(got, want, stamp):
    assert len(got) == len(want), stamp
    for g, w in zip(got, want):
        assert (g.name, g.level, g.message, g.hardware_id) == (
            w.name,
            w.level,
            w.message,
            w.hardware_id,
        ), (stamp, g.name)
        assert [k for k, _ in g.values] == [k for k, _ in w.values], (stamp, g.name)
        for (key, gv), (_, wv) in zip(g.values, w.values):
            if key == 'model':
                assert gv == wv, (stamp, g.name)
                continue
            try:
                assert_same_float(float(gv), float(wv), f'{stamp} {g.name} {key}')
            except ValueError:
                assert gv == wv, (stamp, g.name, key)


def assert_columns_give(items, want):
    """Snapshots in columns (``snapshots=COLUMNS``: :class:`SnapshotColumns`, else Snapshots)
    are ``want`` (the Snapshots of ``snapshots=True``), string for string, and replay's
    ``--out`` encodes both to the same DiagnosticArray bytes."""
    from types import SimpleNamespace

    from catenary_monitor.replay.outputs import snapshot_payloads

    flat = []
    for item in items:
        flat += item.snapshots() if isinstance(item, SnapshotColumns) else [item]
    flat.sort(key=lambda s: s.stamp_ns)
    assert flat == list(want)
    assert any(isinstance(item, SnapshotColumns) for item in items) or not want
    got = snapshot_payloads(SimpleNamespace(snapshots=items))
    assert got == snapshot_payloads(SimpleNamespace(snapshots=list(want)))


def run_columns(twin, window, events, want):
    """``run_log`` with ``snapshots=COLUMNS`` gives the snapshots ``want`` (see above)."""
    result, _ = run_log(twin, window, events, snapshots=COLUMNS)
    assert_columns_give(result.snapshots, want)


def compare(config, tensions, depth, ticks, cuts=(), check_snapshots=True):
    """Core event by event vs advance over windows split at ``cuts``; returns the steps.

    Snapshots are compared only where no two events share a stamp (the node's logs): with
    equal stamps the twin sees every event of that stamp at once.
    """
    start = T0_NS
    core, steps = core_steps(config, tensions, depth, ticks, start)
    twin = MonitorCore(config, start)
    bounds = [None, *cuts, None]
    results = [
        advance(twin, window_of(config, tensions, depth, ticks, lo, hi), snapshots=True)
        for lo, hi in zip(bounds[:-1], bounds[1:])
    ]
    # Outputs: every solved update of every line, in order.
    for k, line in enumerate(config.lines):
        want = [(s.stamp_ns, s.kind, o.values) for s in steps for o in s.outputs if o.line == k]
        t_ns = np.concatenate([r.lines[k].t_ns for r in results])
        assert t_ns.tolist() == [w[0] for w in want], line.name
        kinds = np.concatenate([r.lines[k].kind for r in results])
        assert [('tension' if x == KIND_TENSION else 'depth') for x in kinds] == [
            w[1] for w in want
        ], line.name
        data = np.array([w[2] for w in want]).reshape(-1, len(OUTPUT_FIELDS))
        for key in VALUE_FIELDS:
            got = np.concatenate([r.lines[k].values[key] for r in results])
            assert_same_float(got, data[:, OUTPUT_FIELDS.index(key)], f'{line.name} {key}')
        status = np.concatenate([r.lines[k].status for r in results])
        level = np.concatenate([r.lines[k].level for r in results])
        assert status.tolist() == data[:, 11].astype(int).tolist(), line.name
        assert level.tolist() == data[:, 12].astype(int).tolist(), line.name
    # Transitions, component by component.
    want_tr = [c for s in steps for c in s.transitions]
    got_tr = [c for r in results for c in r.changes()]
    assert sorted(got_tr, key=lambda c: (c.transition.time, c.component)) == sorted(
        want_tr, key=lambda c: (c.transition.time, c.component)
    )
    # The alarm journal: the same records, in the core's order (with equal stamps the twin
    # decides every event of a stamp at once: the same records of each alarm).
    want_j = [e for s in steps for e in s.alarm_events]
    got_j = [e for r in results for e in r.alarm_events]
    if not check_snapshots:
        key = lambda e: (e.time, e.alarm, e.kind)  # noqa: E731
        assert sorted(map(key, got_j)) == sorted(map(key, want_j))
        return steps
    assert got_j == want_j
    # Snapshots: the same stamps, the same statuses.
    want_sn = [s.snapshot for s in steps if s.snapshot is not None]
    got_sn = [sn for r in results for sn in r.snapshots]
    assert [s.stamp_ns for s in got_sn] == [s.stamp_ns for s in want_sn]
    for g, w in zip(got_sn, want_sn):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    # The same in columns, window by window.
    columns = MonitorCore(config, start)
    for (lo, hi), r in zip(zip(bounds[:-1], bounds[1:]), results):
        window = window_of(config, tensions, depth, ticks, lo, hi)
        assert_columns_give(advance(columns, window, snapshots=COLUMNS).snapshots, r.snapshots)
    # The state left behind.
    assert_same_state(twin, core)
    return steps


def ticks_for(tensions, depth, rate=1.0, offset_ns=123_456):
    starts = [c[0][0] for c in (*tensions.values(), depth) if len(c[0])]
    ends = [c[0][-1] for c in (*tensions.values(), depth) if len(c[0])]
    return tick_grid(int(min(starts)) + offset_ns, int(max(ends)), rate)


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_advance_equals_the_core_on_a_storm_with_dropouts(seed):
    config = dock_config(3)
    tensions, depth = generate(config, seconds=90.0, seed=seed)
    steps = compare(config, tensions, depth, ticks_for(tensions, depth))
    levels = {c.transition.new.name for s in steps for c in s.transitions}
    assert levels == {'OK', 'WARN', 'ERROR', 'STALE'}  # not vacuous: every level is reached
    assert sum(len(s.transitions) for s in steps) >= 10


def test_advance_in_several_windows_equals_one_core():
    config = dock_config(3)
    tensions, depth = generate(config, seconds=90.0, seed=4)
    ticks = ticks_for(tensions, depth)
    cuts = [T0_NS + int(s * 1e9) for s in (0.2, 17.3, 45.0, 45.5, 60.0)]
    compare(config, tensions, depth, ticks, cuts)


def test_late_first_depth_and_lines_without_tension():
    config = dock_config(3, depth_timeout=2.0)
    tensions, depth = generate(config, seconds=40.0, seed=5)
    late = depth[0] > T0_NS + int(8e9)  # the first depth 8 s after the tensions
    depth = (depth[0][late], depth[1][late])
    del tensions['line_03']  # a line that never reports
    steps = compare(config, tensions, depth, ticks_for(tensions, depth, rate=2.0))
    first = [s for s in steps if s.kind == 'depth'][0]
    assert first.snapshot is not None
    lines = {st.name.split(': ')[1]: st for st in first.snapshot.statuses}
    assert lines['line_03'].message == (
        'blind: no tension received yet (suppressed by design: alarm on sensors)'
    )
    assert lines['line_03'].level.name == 'STALE'
    # The one common-cause alarm: line_03 never reported (raised after tension_timeout).
    assert lines['sensors'].level.name == 'STALE'
    assert lines['sensors'].message.startswith('waiting for sensors: no tension from line_03')
    raised = [c for s in steps for c in s.transitions if not c.transition.suppressed]
    assert [c.component for c in raised if c.transition.new.name == 'STALE'][:1] == ['sensors']


def test_elastic_line_and_depth_loss():
    base = dock_config(2, depth_timeout=3.0)
    lines = base.lines + (LineConfig('line_03', 1300.0, 121.06, 4827000.0, ea=6.6e8),)
    config = MonitorConfig(lines=lines, alarm=base.alarm)
    tensions, depth = generate(config, seconds=60.0, seed=6, storm_line=2)
    steps = compare(config, tensions, depth, ticks_for(tensions, depth, rate=4.0))
    models = {o.values[11] for s in steps for o in s.outputs if o.line == 2}
    assert 0.0 in models


@pytest.mark.parametrize('elastic', [False, True])
def test_implausible_readings_are_impossible_inputs_in_both(elastic):
    """1e300 N, inf, 20 x MBL and a 1e6 m depth: the same status, sentence and levels in the
    core and its twin; the tide is not OK at 1e6 m."""
    base = dock_config(2, depth_timeout=3.0)
    ea = 6.6e8 if elastic else None
    lines = base.lines + (LineConfig('line_03', 1300.0, 121.06, 4827000.0, ea=ea),)
    config = MonitorConfig(lines=lines, alarm=base.alarm)
    tensions, depth = generate(config, seconds=30.0, seed=8, storm_line=2)
    t, v = tensions['line_03']
    v = v.copy()
    v[40:45], v[80], v[120:123] = 1e300, math.inf, 20 * 4827000.0
    tensions['line_03'] = (t, v)
    dv = depth[1].copy()
    dv[10] = 1e6
    depth = (depth[0], dv)
    steps = compare(config, tensions, depth, ticks_for(tensions, depth, rate=4.0))
    codes = {int(o.values[11]) for s in steps for o in s.outputs if o.line == 2}
    assert {Status.IMPLAUSIBLE_TENSION, Status.IMPLAUSIBLE_DEPTH, Status.NON_FINITE} <= codes
    assert Status.NO_CONVERGENCE not in codes
    tide = [c.transition for s in steps for c in s.transitions if c.component == 'tide']
    assert any(tr.new.name == 'ERROR' and '1e+06 m' in tr.message for tr in tide), tide
    messages = {c.transition.message for s in steps for c in s.transitions}
    assert any('above 10 x MBL' in m for m in messages), messages


def test_before_any_input_every_line_is_stale_and_says_why():
    config = dock_config(2)
    core = MonitorCore(config, T0_NS)
    step = core.step(Tick(T0_NS + 10**9))
    messages = {st.name: (st.level.name, st.message) for st in step.snapshot.statuses}
    note = ' (suppressed by design: alarm on sensors)'
    assert messages['catenary_monitor: line_01'] == (
        'STALE',
        'blind: no tension received yet; no depth received yet' + note,
    )
    # the headline names what to do; the full text is the detail
    assert messages['catenary_monitor: tide'] == (
        'STALE',
        'no depth received yet: check the tide gauge',
    )
    tide = [st for st in step.snapshot.statuses if st.name == 'catenary_monitor: tide'][0]
    assert dict(tide.values)['detail'] == 'no depth received yet'
    step = core.step(Tension(T0_NS + 2 * 10**9, 0, 372e3))
    assert step.outputs[0].values[11] == -1 and math.isnan(step.outputs[0].values[4])
    assert core.state.lines[0].state.message == 'blind: no depth received yet' + note


def test_a_late_first_depth_gives_one_snapshot_that_agrees_with_itself():
    """The old node stepped lines one at a time and published after each change."""
    config = dock_config(3, depth_timeout=2.0)
    core = MonitorCore(config, T0_NS)
    for k in range(3):
        core.step(Tension(T0_NS + (k + 1) * 10**8, k, 372e3))
    core.step(Tick(T0_NS + 5 * 10**9))
    step = core.step(Depth(T0_NS + 6 * 10**9, 20.85))
    assert step.snapshot is not None and len(step.outputs) == 3
    levels = {st.name: st.level.name for st in step.snapshot.statuses}
    # Tensions are 5.9 s old (timeout 1.5 s): every line STALE for that, in the one snapshot.
    assert [levels[f'catenary_monitor: line_0{k}'] for k in (1, 2, 3)] == ['STALE'] * 3
    assert levels['catenary_monitor: tide'] == 'OK'


def test_coincident_times_and_synthetic_ticks_and_on_delay():
    """Receive times that coincide with ticks and with each other (order depth, tension,
    tick), an on-delay, and the synthetic tick grid."""
    config = dock_config(2, on_delay=1.5, tension_timeout=0.9)
    tensions, depth = generate(config, seconds=60.0, rate=5.0, seed=11)
    snap = lambda t: (t // 500_000_000) * 500_000_000  # noqa: E731 - a 0.5 s grid
    tensions = {k: (snap(t), v) for k, (t, v) in tensions.items()}
    depth = (snap(depth[0]), depth[1])
    rep = recompute(config, tensions, depth)
    assert not rep.ticks_from_log and len(rep.tick_ns) > 50
    compare(config, tensions, depth, rep.tick_ns, check_snapshots=False)


def test_a_log_without_depth_and_a_line_without_tension():
    config = dock_config(2)
    tensions, depth = generate(config, seconds=20.0, seed=5, dropouts=False)
    del tensions['line_02']
    empty = (np.zeros(0, np.int64), np.zeros(0))
    rep = recompute(config, tensions, empty)
    compare(config, tensions, empty, rep.tick_ns)
    assert set(rep.lines[0].status.tolist()) == {-1}  # unsolved, as the node publishes
    assert set(rep.lines[1].step_level.tolist()) == {3}  # STALE throughout: never seen
    assert rep.lines[1].transitions == []


@st.composite
def schedules(draw, distinct):
    """Random schedules: any interleaving of tension, depth and ticks, gaps, impossible
    samples, uplift and warning crossings, on-delays and hold times; ``distinct``: no two
    events share a stamp (as in the node's logs), else a coarse grid with collisions."""
    config = dock_config(
        2,
        on_delay=draw(st.sampled_from([0.0, 0.3])),
        clear_hold=draw(st.sampled_from([0.0, 0.7])),
        warn_clear_hold=0.5,
        margin_clear_hold=draw(st.sampled_from([0.5, 1.2])),
        tension_timeout=0.6,
        depth_timeout=1.1,
    )
    grid = st.integers(0, 40).map(lambda k: T0_NS + k * 100_000_000)
    used = set()

    def stamps(max_size):
        times = sorted(draw(st.lists(grid, max_size=max_size)))
        if distinct:
            out = []
            for t in times:
                while t in used:
                    t += 1
                used.add(t)
                out.append(t)
            times = sorted(out)
        return np.array(times, np.int64)

    value = st.one_of(
        st.floats(3.0e5, 2.0e6), st.sampled_from([math.nan, -1.0, 0.0, 1e300, math.inf, 1e9])
    )
    tensions = {}
    for line in config.lines:
        t = stamps(25)
        tensions[line.name] = (
            t,
            np.array(draw(st.lists(value, min_size=len(t), max_size=len(t))), float),
        )
    d = stamps(8)
    depth = (
        d,
        np.array(
            draw(
                st.lists(
                    st.one_of(st.floats(15.0, 26.0), st.sampled_from([-1.0, 1e6])),
                    min_size=len(d),
                    max_size=len(d),
                )
            ),
            float,
        ),
    )
    ticks = np.unique(stamps(12))
    cuts = sorted(draw(st.lists(grid, max_size=3)))
    return config, tensions, depth, ticks, cuts


@settings(
    max_examples=60, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(schedules(distinct=True))
def test_random_schedules_with_distinct_stamps(case):
    compare(*case)


@settings(
    max_examples=40, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(schedules(distinct=False))
def test_random_schedules_with_equal_stamps(case):
    compare(*case, check_snapshots=False)


def test_run_log_steps_acknowledgements_as_the_core_does():
    """Acknowledgements (one line, all, an unknown name, a repeated one) between vectorized
    stretches: the same snapshots, acknowledgement keys and final state as the core."""
    config = dock_config(3, tension_timeout=1.5)
    tensions, depth = generate(config, seconds=90.0, seed=2)
    ticks = ticks_for(tensions, depth)
    acks = [
        Acknowledge(T0_NS + int(s * 1e9) + 7, line, f'op {k}')
        for k, (s, line) in enumerate(
            [
                (3.1, None),
                (30.2, 'line_01'),
                (46.0, 'line_02'),
                (46.5, 'line_02'),
                (55.3, 'nope'),
                (61.7, None),
                (80.9, 'line_03'),
            ]
        )
    ]
    core = MonitorCore(config, T0_NS)
    merged = sorted(events_of(config, tensions, depth, ticks) + acks, key=lambda e: e.stamp_ns)
    steps = [core.step(ev) for ev in merged]
    twin = MonitorCore(config, T0_NS)
    empty = (np.zeros(0, np.int64), np.zeros(0))
    window = Window([tensions.get(line.name, empty) for line in config.lines], depth, ticks)
    result, twin = run_log(twin, window, acks, snapshots=True)
    want = [s.snapshot for s in steps if s.snapshot is not None]
    run_columns(MonitorCore(config, T0_NS), window, acks, result.snapshots)
    assert [s.stamp_ns for s in result.snapshots] == [s.stamp_ns for s in want]
    for g, w in zip(result.snapshots, want):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    states = {dict(st.values).get('alarm_state') for s in want for st in s.statuses[:3]}
    assert {'unacknowledged', 'acknowledged', 'returned-unacknowledged', 'normal'} <= states
    assert_same_state(twin, core)


def _lookahead_config(**alarm):
    """dock_config(3) with accuracies and holding data: line_01 bounds (elastic), line_02 a
    sinker with grounded chain, line_03 a drag anchor with chain length only."""
    import dataclasses

    base = dock_config(3, depth_accuracy=0.3, drag_margin_warn=150e3, **alarm)
    extra = [
        dict(tension_accuracy=40e3, ea=6.0e8, chain_length=300.0),
        dict(
            tension_accuracy=20e3,
            chain_length=250.0,
            anchor_holding=500e3,
            anchor_weight=400e3,
            chain_friction=0.7,
        ),
        dict(chain_length=140.0, anchor_holding=300e3),
    ]
    lines = tuple(dataclasses.replace(lc, **e) for lc, e in zip(base.lines, extra))
    return dataclasses.replace(base, lines=lines)


@pytest.mark.parametrize('seed', [1, 2])
def test_bounds_and_holding_twin_equals_the_core(seed):
    """The bounds, holding values and their warnings: the twin equals the core, and both
    warnings (uplift possible within accuracy, drag margin) are reached."""
    config = _lookahead_config()
    tensions, depth = generate(config, seconds=90.0, seed=seed)
    steps = compare(config, tensions, depth, ticks_for(tensions, depth), cuts=[T0_NS + int(33e9)])
    messages = ' | '.join(c.transition.message for s in steps for c in s.transitions)
    assert 'uplift possible within sensor accuracy' in messages
    assert 'anchor may drag' in messages
    outs = np.array([o.values for s in steps for o in s.outputs if o.line == 1])
    for key in (
        'uplift_force_upper',
        'anchor_margin_lower',
        'grounded_length',
        'drag_margin',
        'implied_anchor_distance',
        'tide_margin_at_length',
    ):
        assert np.isfinite(outs[:, OUTPUT_FIELDS.index(key)]).any(), key


def test_run_log_flags_runtime_changes_as_the_core_does():
    """Accepted runtime changes (logged Reconfigure events) between vectorized stretches: the
    same ``parameters`` WARN, naming old and new values, until runtime_change_warn_time, then
    OK; the same snapshots and transitions as the core."""
    import dataclasses

    base = dock_config(3)
    config = dataclasses.replace(base, allow_runtime_changes=True, runtime_change_warn_time=20.0)
    tensions, depth = generate(config, seconds=90.0, seed=3)
    ticks = ticks_for(tensions, depth)

    def raised(cfg, uplift):
        lines = list(cfg.lines)
        lines[0] = dataclasses.replace(lines[0], allowed_uplift=uplift)
        return dataclasses.replace(cfg, lines=tuple(lines))

    first = raised(config, 1e9)
    changes = [
        Reconfigure(T0_NS + int(10.3e9) + 7, first),
        Reconfigure(T0_NS + int(20.1e9) + 7, first),  # nothing changed: no flag
        Reconfigure(T0_NS + int(55.7e9) + 7, raised(first, 0.0)),
    ]
    core = MonitorCore(config, T0_NS)
    merged = sorted(events_of(config, tensions, depth, ticks) + changes, key=lambda e: e.stamp_ns)
    steps = [core.step(ev) for ev in merged]
    twin = MonitorCore(config, T0_NS)
    empty = (np.zeros(0, np.int64), np.zeros(0))
    window = Window([tensions.get(line.name, empty) for line in config.lines], depth, ticks)
    result, twin = run_log(twin, window, changes, snapshots=True)
    want = [s.snapshot for s in steps if s.snapshot is not None]
    run_columns(MonitorCore(config, T0_NS), window, changes, result.snapshots)
    assert [s.stamp_ns for s in result.snapshots] == [s.stamp_ns for s in want]
    for g, w in zip(result.snapshots, want):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    flags = [(s.stamp_ns, s.statuses[-1]) for s in want]
    assert all(st.name == 'catenary_monitor: parameters' for _, st in flags)
    text = 'allowed_uplift of line_01 changed 0 N -> 1e+09 N at runtime'
    at = {round((t - T0_NS) * 1e-9): (int(st.level), dict(st.values)['detail']) for t, st in flags}
    assert at[5] == (0, 'runtime changes allowed; none made')
    assert at[15] == (1, text) and at[29] == (1, text)
    assert at[35][0] == 0 and at[70] == (1, text.replace('0 N -> 1e+09', '1e+09 N -> 0'))
    assert at[75][0] == 1 and at[80][0] == 0
    want_tr = [c for s in steps for c in s.transitions if c.component == 'parameters']
    got_tr = [c for c in result.others if c.component == 'parameters']
    assert got_tr == want_tr and [c.transition.new for c in got_tr] == [1, 1]


def test_run_log_steps_clock_and_intake_events_as_the_core_does():
    """The node's clock-watchdog and intake records (through their JSON record and back)
    between vectorized stretches: the same clock and intake statuses, snapshots and
    transitions as the core; drops age out of the 60 s window."""
    import json

    from catenary_monitor.core.monitor.events import (
        ClockHealth,
        Intake,
        event_record,
        parse_event_record,
    )

    config = dock_config(3)
    tensions, depth = generate(config, seconds=150.0, seed=4)
    ticks = ticks_for(tensions, depth)

    def at(s):
        return T0_NS + int(s * 1e9) + 11

    raw = [
        ClockHealth(at(1.0), None),
        Intake(at(2.0), (20, 20, 20, 2), (0, 0, 0, 0), 0.01, 1.0),
        Intake(at(30.0), (500, 480, 500, 28), (0, 40, 0, 0), 0.2, 28.0),  # 2.5 % dropped: WARN
        Intake(at(31.0), (20, 0, 20, 1), (0, 50, 0, 0), 0.1, 1.0),  # now 5.3 %: ERROR
        ClockHealth(at(40.0), 4.0),
        ClockHealth(at(41.0), 5.0),
        ClockHealth(at(42.0), None),
        Intake(at(95.0), (600, 600, 600, 60), (0, 0, 0, 0), 0.5, 64.0),  # drops aged out
        Intake(at(100.5), (20, 20, 20, 1), (0, 0, 0, 0), 0.9, 1.0),  # busy: WARN
    ]
    events = [parse_event_record(e.stamp_ns, json.dumps(event_record(e))) for e in raw]
    assert events == raw
    core = MonitorCore(config, T0_NS)
    merged = sorted(events_of(config, tensions, depth, ticks) + events, key=lambda e: e.stamp_ns)
    steps = [core.step(ev) for ev in merged]
    twin = MonitorCore(config, T0_NS)
    empty = (np.zeros(0, np.int64), np.zeros(0))
    window = Window([tensions.get(line.name, empty) for line in config.lines], depth, ticks)
    result, twin = run_log(twin, window, events, snapshots=True)
    want = [s.snapshot for s in steps if s.snapshot is not None]
    run_columns(MonitorCore(config, T0_NS), window, events, result.snapshots)
    assert [s.stamp_ns for s in result.snapshots] == [s.stamp_ns for s in want]
    for g, w in zip(result.snapshots, want):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    assert result.others == [
        c
        for s in steps
        for c in s.transitions
        if c.component in ('clock', 'intake', 'sensors', 'alarms')
    ]
    got = [
        (c.component, int(c.transition.new))
        for c in result.others
        if c.component in ('clock', 'intake')
    ]
    assert got == [
        ('intake', 1),
        ('intake', 2),
        ('clock', 2),
        ('clock', 0),
        ('intake', 0),
        ('intake', 1),
    ]
    last = {st.name: st for st in want[-1].statuses}
    assert last['catenary_monitor: clock'].level == 0
    intake = last['catenary_monitor: intake']
    assert dict(intake.values)['messages_dropped'] == '0' and 'busy' in intake.message
    error = next(
        st
        for s in want
        for st in s.statuses
        if st.name == 'catenary_monitor: intake' and st.level == 2
    )
    assert error.message.startswith('node cannot keep up: 5 % of tension and depth samples')
    assert dict(error.values)['line_02.messages_dropped'] == '90'
    stopped = next(
        st
        for s in want
        for st in s.statuses
        if st.name == 'catenary_monitor: clock' and st.level == 2
    )
    assert stopped.message.startswith('ROS clock stopped: /clock not advancing for 4 s')


def test_worst_is_the_first_extreme_ignoring_nan():
    """window.worst: the smallest margin and the largest force, the first of equal ones, NaN
    ignored (where the other values are infinite too), None where every value is NaN."""
    from catenary_monitor.core.twin import window

    nan, inf = math.nan, math.inf
    v = np.array([nan, 3.0, -inf, -inf, nan])
    values = {key: v for key in ('anchor_margin', 'tide_margin', 'load_margin', 'uplift_force')}
    values['safety_factor'] = np.full(5, nan)
    values['top_tension'] = np.array([nan, -inf, nan, -inf, nan])
    t = np.arange(5, dtype=np.int64) * 1_000_000_000
    empty = np.zeros(0)
    result = window.LineResult('a', t, t, values, t, t, t, t, t)
    out = window.worst(result)
    assert out['anchor_margin'] == {'value': -inf, 'time': 2.0}
    assert out['uplift_force'] == {'value': 3.0, 'time': 1.0}
    assert out['top_tension'] == {'value': -inf, 'time': 1.0}  # np.nanargmax gave index 0: NaN
    assert out['safety_factor'] is None
    nothing = window.LineResult('a', empty, empty, {key: empty for key in values}, *[empty] * 5)
    assert all(w is None for w in window.worst(nothing).values())


def test_the_state_comparison_sees_every_field():
    """The twin's check covers the whole state by construction: changing any one field of
    :class:`CoreState` or of a line's :class:`LineState` (a field the twin forgot) fails it, and
    the core keeps no decision state outside them (``__slots__``)."""
    import copy

    config = dock_config(2)
    tensions, depth = generate(config, seconds=20.0, seed=3)
    core, _ = core_steps(config, tensions, depth, ticks_for(tensions, depth), T0_NS)
    assert_same_state(copy.deepcopy(core), core)

    def spoiled(value):
        if isinstance(value, bool):
            return not value
        if isinstance(value, (int, float)):
            return value + 1.0 if math.isfinite(value) else 0.5
        if isinstance(value, np.ndarray):
            return np.append(value.astype(float), 1.0)
        if isinstance(value, (tuple, list)):
            return (7,) if not len(value) or hasattr(value, '_fields') else value[:-1]
        return object()

    for f in dataclasses.fields(CoreState):
        if f.name == 'lines':
            continue
        other = copy.deepcopy(core)
        setattr(other.state, f.name, spoiled(getattr(other.state, f.name)))
        with pytest.raises(AssertionError):
            assert_same_state(other, core)
    for f in dataclasses.fields(LineState):
        if f.name in LINE_CONFIG_FIELDS:
            continue
        other = copy.deepcopy(core)
        line = other.state.lines[1]
        setattr(line, f.name, spoiled(getattr(line, f.name)))
        with pytest.raises(AssertionError):
            assert_same_state(other, core)
    with pytest.raises(AttributeError):
        core.forgotten = 1.0  # type: ignore[attr-defined]


def test_the_twin_writes_the_core_only_through_its_typed_door(monkeypatch):
    """The twin's door: each part is a NamedTuple of its state's own fields, with their
    annotations; and a window through ``advance`` sets no field of the core's state or of a
    line's from the twin's modules (only ``take`` does, in core/monitor/state.py)."""
    import sys

    from catenary_monitor.core.monitor import state as door

    for parts, target in (
        (door.CorePart.__constraints__, CoreState),
        (door.LinePart.__constraints__, LineState),
    ):
        own = {f.name: f.type for f in dataclasses.fields(target)}
        seen = set()
        for part in parts:
            for name, annotation in part.__annotations__.items():
                text = getattr(annotation, '__forward_arg__', annotation)  # NamedTuple's
                assert own.get(name) == text, (part.__name__, name)
                assert name not in seen, name  # each field in one part
                seen.add(name)
    writers = set()

    def watch(cls):
        plain = cls.__setattr__

        def setattr_(self, name, value):
            writers.add(sys._getframe(1).f_globals['__name__'])
            plain(self, name, value)

        monkeypatch.setattr(cls, '__setattr__', setattr_)

    config = dock_config(3)
    tensions, depth = generate(config, seconds=30.0, seed=2)
    core = MonitorCore(config, T0_NS)
    watch(CoreState)
    watch(LineState)
    advance(core, window_of(config, tensions, depth, ticks_for(tensions, depth)))
    assert writers and not any(w.startswith('catenary_monitor.core.twin') for w in writers)


def _coalescing_records(config, tensions, depth, seed):
    """What a node that fell behind records: stretches of each input's samples left out
    (``Coalesced`` at 1 ns before the first of each stretch, naming the last), the newest
    sample after each stretch stepped. Returns the records, their stamps' JSON round trip
    checked."""
    import json

    from catenary_monitor.core.monitor.events import Coalesced, event_record, parse_event_record

    rng = np.random.default_rng(seed)
    columns = [(line.name, tensions[line.name][0]) for line in config.lines]
    columns.append((None, depth[0]))
    records = []
    for name, t in columns:
        i = 3
        while i < len(t) - 12:
            n = int(rng.integers(1, 9))
            records.append(Coalesced(int(t[i]) - 1, name, int(t[i + n - 1]), n))
            i += n + int(rng.integers(2, 40))
    records.sort(key=lambda e: e.stamp_ns)
    assert [parse_event_record(r.stamp_ns, json.dumps(event_record(r))) for r in records] == (
        records
    )
    return records


@pytest.mark.parametrize('cuts', [0, 7])
def test_run_log_leaves_out_what_the_node_coalesced_as_the_core_does(cuts):
    """A coalescing node's records (stretches of every input's samples logged but not
    stepped): the core, handed every sample, steps only the others; the twin, handed the
    whole columns and the records in one window or in windows cut inside the stretches,
    gives the same outputs, snapshots and final state (the bound carried across windows)."""
    config = dock_config(3)
    tensions, depth = generate(config, seconds=90.0, seed=5, depth_rate=3.0)
    ticks = ticks_for(tensions, depth)
    records = _coalescing_records(config, tensions, depth, seed=5)
    core = MonitorCore(config, T0_NS)
    merged = sorted(events_of(config, tensions, depth, ticks) + records, key=lambda e: e.stamp_ns)
    steps = [core.step(ev) for ev in merged]
    left_out = sum(r.samples for r in records)
    assert sum(s.kind == 'coalesced' for s in steps) == left_out + len(records)
    empty = (np.zeros(0, np.int64), np.zeros(0))
    whole = Window([tensions.get(line.name, empty) for line in config.lines], depth, ticks)
    inside = [r.last_ns for r in records[5 :: max(1, len(records) // max(cuts, 1))]][:cuts]
    bounds = [None, *sorted(inside), None]
    twin, results = MonitorCore(config, T0_NS), []
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        part = [
            r
            for r in records
            if (lo is None or r.stamp_ns >= lo) and (hi is None or r.stamp_ns < hi)
        ]
        result, twin = run_log(twin, slice_window(whole, lo, hi), part, snapshots=True)
        results.append(result)
    for k, line in enumerate(config.lines):
        want = [(s.stamp_ns, o.values) for s in steps for o in s.outputs if o.line == k]
        got = np.concatenate([r.lines[k].t_ns for r in results])
        assert got.tolist() == [w[0] for w in want], line.name
        assert len(want) < len(tensions[line.name][0]) + len(depth[0])
    want_sn = [s.snapshot for s in steps if s.snapshot is not None]
    got_sn = [sn for r in results for sn in r.snapshots]
    assert [s.stamp_ns for s in got_sn] == [s.stamp_ns for s in want_sn]
    for g, w in zip(got_sn, want_sn):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    assert_same_state(twin, core)
    assert core.state.depth_coalesced_until > 0
