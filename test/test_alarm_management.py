"""Alarm management (ISA-18.2 / EEMUA 191): shelving, chattering, floods and the alarm journal,
in the core (core/alarms/acknowledge.py, shelving.py, flood.py, journal.py) and
in its vectorized twin, which must decide alike (the core stepped event by event is the
oracle)."""

import json

import numpy as np
import pytest
from replay_data import T0_NS, dock_config, events_of, generate
from test_batch import assert_same_state, assert_statuses_agree, run_columns, ticks_for

from catenary_monitor.core.config.parameters import (
    ALARM_CONDITIONS,
    AlarmConfig,
    ConfigError,
    config_from_params,
    config_to_params,
)
from catenary_monitor.core.alarms import acknowledge as ack
from catenary_monitor.core.alarms import flood as alarm_flood, shelving
from catenary_monitor.core.alarms.journal import entries
from catenary_monitor.core.alarms.latches import CONDITIONS
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.events import (
    Acknowledge,
    Depth,
    Shelve,
    Tension,
    Tick,
    event_record,
    parse_event_record,
)
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.twin.window import Window
from catenary_monitor.core.twin.engine import run_log

S = 10**9
ALL = ack.WHOLE


def test_the_condition_names_are_the_alarms():
    """config's list of conditions (unshelvable_conditions is checked against it) is the
    alarm's latches and ``stale``: a condition added to one must be added to the other."""
    assert ALARM_CONDITIONS == CONDITIONS + ('stale',)
    with pytest.raises(ConfigError, match='unknown alarm condition .lift'):
        AlarmConfig(unshelvable_conditions=('lift',))
    with pytest.raises(ConfigError, match='chatter_count.*whole number'):
        AlarmConfig(chatter_count=2.5)
    flat = config_to_params(dock_config(2, unshelvable_conditions=('uplift', 'input')))
    assert flat['unshelvable_conditions'] == ('uplift', 'input')
    assert config_from_params(flat).alarm.unshelvable_conditions == ('uplift', 'input')


# --- the alarm's states ----------------------------------------------------------------------


def test_a_shelved_alarm_still_active_at_expiry_comes_back_as_it_was_shelved():
    state = ack.step(ack.AckState(), Level.WARN, 1.0)
    state = ack.acknowledge(state, 2.0, 'op')
    assert state.state == ack.ACKNOWLEDGED
    state = ack.shelve(state, 3.0, 13.0, ALL, 'op', Level.OK)
    assert (state.state, ack.shelved(state)) == (ack.NORMAL, True)
    values = dict(ack.diagnostic_values(state, Level.WARN, [False] * len(CONDITIONS)))
    assert values['alarm_state'] == 'shelved' and values['shelved'] == 'true'
    assert values['shelved_until'] == '13.0' and values['acknowledged'] == 'true'
    # While shelved the alarm is computed (active) but nothing waits for an acknowledgement.
    state = ack.step(state, Level.WARN, 12.9, masked=Level.OK)
    assert state.state == ack.NORMAL and state.active_since == 1.0
    # The first step at or after the expiry: never cleared, acknowledged before: as it was.
    back = ack.step(state, Level.WARN, 13.5, masked=Level.OK)
    assert (back.state, back.raised, ack.shelved(back)) == (ack.ACKNOWLEDGED, 1.0, False)
    # More severe now than when shelved: news, raised again then.
    back = ack.step(state, Level.ERROR, 13.5, masked=Level.OK)
    assert (back.state, back.raised) == (ack.UNACKNOWLEDGED, 13.5)


def test_a_shelf_ends_raising_only_what_it_hid_that_is_news():
    """Raised again when the shelf ends: a condition that became active under the shelf, or
    cleared and returned under it; not one active since before it, however often a shelf is
    put on and taken off (an alarm unacknowledged when shelved returns unacknowledged, not
    raised again: the journal has no new raise)."""
    fresh = ack.shelve(ack.AckState(), 0.0, 10.0, ALL, 'op', Level.OK)
    fresh = ack.step(fresh, Level.WARN, 5.0, masked=Level.OK)  # active under the shelf
    back = ack.step(fresh, Level.WARN, 11.0, masked=Level.OK)
    assert (back.state, back.raised) == (ack.UNACKNOWLEDGED, 11.0)
    state = ack.step(ack.AckState(), Level.WARN, 1.0)
    shelf = ack.shelve(state, 2.0, 20.0, ALL, 'op', Level.OK)
    gone = ack.step(shelf, Level.OK, 3.0, masked=Level.OK)
    again = ack.step(gone, Level.WARN, 4.0, masked=Level.OK)  # cleared and returned
    back = ack.unshelve(again, 5.0, Level.WARN, Level.OK)
    assert (back.state, back.raised) == (ack.UNACKNOWLEDGED, 5.0)
    journal = []
    for k in range(34):  # the shelf toggled on and off, the warning active throughout
        t = 2.0 + k
        on = ack.shelve(state, t, t + 600.0, ALL, 'op', Level.OK)
        journal += entries('line_01', state, on, t)
        state = ack.unshelve(on, t + 0.5, Level.WARN, Level.OK)
        journal += entries('line_01', on, state, t + 0.5)
    assert (state.state, state.raised) == (ack.UNACKNOWLEDGED, 1.0)
    kinds = [e.kind for e in journal]
    assert kinds.count('shelved') == 34 and kinds.count('unshelved') == 34
    assert 'raised' not in kinds
    # Shelved again while shelved: still the state it had before the first shelf.
    twice = ack.shelve(state, 40.0, 50.0, ALL, 'a', Level.OK)
    twice = ack.shelve(twice, 41.0, 60.0, ALL, 'b', Level.OK)
    back = ack.unshelve(twice, 42.0, Level.WARN, Level.OK)
    assert (back.state, back.raised) == (ack.UNACKNOWLEDGED, 1.0)


def test_a_shelf_toggled_on_a_warning_line_raises_nothing_in_core_and_twin():
    """A line held in WARN (its anchor margin), its whole alarm shelved and unshelved by an
    operator 34 times: one raise in the journal (before the toggling), no flood (more than 5
    raises in 600 s); the twin decides alike."""
    config = dock_config(2, tension_timeout=5.0, flood_count=5.0)
    n = 40
    t = T0_NS + np.arange(1, n + 1, dtype=np.int64) * S
    tensions = {'line_01': (t + 2, np.full(n, 450e3)), 'line_02': (t + 3, np.full(n, 372e3))}
    depth = (t + 1, np.full(n, 20.85))
    ticks = t + 4
    extra = []
    for k in range(3, 37):
        extra.append(Shelve(T0_NS + k * S + 5, 'line_01', ALL, 600.0, 'op'))
        extra.append(Shelve(T0_NS + k * S + S // 2, 'line_01', ALL, 0.0, 'op'))
    core = MonitorCore(config, T0_NS)
    steps = [core.step(e) for e in _events(config, tensions, depth, ticks, extra)]
    journal = [e for s in steps for e in s.alarm_events]
    kinds = [e.kind for e in journal if e.alarm == 'line_01']
    assert kinds.count('shelved') == 34 and kinds.count('unshelved') == 34, kinds
    assert kinds.count('raised') == 1, kinds
    assert 'flood' not in [e.kind for e in journal]
    assert core.state.lines[0].ack.state == ack.UNACKNOWLEDGED
    twin = MonitorCore(config, T0_NS)
    window = Window([tensions['line_01'], tensions['line_02']], depth, ticks)
    result, twin = run_log(twin, window, extra, snapshots=True)
    assert sorted(result.alarm_events) == sorted(journal)
    assert_same_state(twin, core)


def test_a_shelf_that_expires_on_a_quiet_alarm_leaves_it_normal():
    state = ack.shelve(ack.AckState(), 0.0, 10.0, ALL, 'op', Level.OK)
    state = ack.step(state, Level.WARN, 5.0, masked=Level.OK)  # raised while shelved: hidden
    state = ack.step(state, Level.OK, 8.0, masked=Level.OK)
    state = ack.step(state, Level.OK, 11.0, masked=Level.OK)
    assert (state.state, ack.shelved(state)) == (ack.NORMAL, False)


def test_a_condition_shelf_hides_that_condition_only():
    active = [c in ('anchor_margin', 'uplift') for c in CONDITIONS]
    hidden = shelving.hidden_conditions('anchor_margin', ('uplift',))
    assert shelving.masked_level(active, False, hidden) == Level.ERROR  # uplift is never hidden
    whole = shelving.hidden_conditions(ALL, ('uplift',))
    assert 'uplift' not in whole and 'stale' in whole
    assert shelving.masked_level(active, True, whole) == Level.ERROR
    only_warn = [c == 'anchor_margin' for c in CONDITIONS]
    assert shelving.masked_level(only_warn, True, whole) == Level.OK
    assert shelving.masked_level(only_warn, True, hidden) == Level.STALE
    # The vectorized form is the scalar one per step.
    rng = np.random.default_rng(3)
    flags = {c: rng.random(200) < 0.2 for c in CONDITIONS}
    stale = rng.random(200) < 0.3
    for h in (hidden, whole, frozenset()):
        got = shelving.masked_levels(flags, stale, h)
        want = [
            shelving.masked_level([bool(flags[c][i]) for c in CONDITIONS], bool(stale[i]), h)
            for i in range(200)
        ]
        assert got.tolist() == [int(w) for w in want]


def test_chattering_is_three_changes_within_the_window():
    state, rule = ack.AckState(), (3, 60.0)
    levels = [(0.0, Level.WARN), (20.0, Level.OK), (50.0, Level.WARN), (70.0, Level.OK)]
    flags = []
    for t, level in levels:
        state = ack.step(state, level, t, flip=True, chatter=rule)
        flags.append(state.chattering)
    assert flags == [False, False, True, True]
    state = ack.step(state, Level.OK, 79.9, chatter=rule)
    assert state.chattering  # 20, 50, 70 within 60 s of 79.9
    state = ack.step(state, Level.OK, 80.1, chatter=rule)
    assert not state.chattering and state.flips == (20.0, 50.0, 70.0)
    # The vectorized flags equal stepping every one (with changes before the window).
    rng = np.random.default_rng(5)
    times = np.cumsum(rng.uniform(0.5, 15.0, 300))
    flip = rng.random(300) < 0.3
    before = (times[0] - 30.0, times[0] - 5.0)
    got = ack.chatter_flags(before, times, flip, rule)
    s = ack.AckState(flips=before)
    want = []
    for t, f in zip(times.tolist(), flip.tolist()):
        s = ack.step(s, Level.OK, t, flip=f, chatter=rule)
        want.append(s.chattering)
    assert got.tolist() == want


def test_shelve_requests_parse_and_are_bounded():
    r = shelving.parse_request('line_11.anchor_margin 600 console dock-pc client 10.0.0.7')
    assert r == ('line_11', 'anchor_margin', 600.0, 'console dock-pc client 10.0.0.7')
    assert shelving.parse_request('line_11 0') == ('line_11', ALL, 0.0, 'ros')
    long = shelving.parse_request('line_11 60 ' + 'x' * 1_000_000)
    assert len(long.origin) == ack.ORIGIN_LIMIT and long.origin.endswith('...')
    assert shelving.parse_request('line_11 60 a\x07b\n c').origin == 'a?b c'
    for bad in ('', 'line_11', 'line_11 soon', 'line_11 -5', 'line_11 nan', 'line_11 inf'):
        with pytest.raises(ValueError):
            shelving.parse_request(bad)


# --- through the core --------------------------------------------------------------------------


def _storm_core(**alarm):
    """The 3-line storm (line_02 lifts at mid-record), stepped to ``upto`` s."""
    config = dock_config(3, tension_timeout=1.5, **alarm)
    tensions, depth = generate(config, seconds=90.0, seed=2)
    ticks = ticks_for(tensions, depth)
    return config, tensions, depth, ticks


def _status(step, name):
    return {st.name.split(': ')[1]: st for st in step.snapshot.statuses}[name]


def test_shelving_the_uplift_error_is_refused_with_a_message():
    config, tensions, depth, ticks = _storm_core()
    core = MonitorCore(config, T0_NS)
    events = [e for e in events_of(config, tensions, depth, ticks) if e.stamp_ns < T0_NS + 50 * S]
    for e in events:
        core.step(e)
    line = core.state.lines[1]
    assert line.state.level == Level.ERROR and line.state.latches[0].active  # lifted
    now = events[-1].stamp_ns
    step = core.step(Shelve(now + 1, 'line_02', 'uplift', 600.0, 'console op'))
    assert step.note == (
        'line_02.uplift: refused: line_02: the uplift ERROR cannot be shelved '
        '(unshelvable_conditions: uplift, input, sensor_error, stale, dragging, sensors)'
    )
    step = core.step(Shelve(now + 2, 'line_02', ALL, 600.0, 'console op'))
    assert 'its active uplift ERROR cannot be shelved' in step.note
    assert not ack.shelved(core.state.lines[1].ack)
    alarms = dict(_status(step, 'alarms').values)
    assert alarms['shelve_answer'] == step.note and alarms['shelve_requests'] == '2'
    assert [(e.kind, e.by) for e in step.alarm_events] == [('refused', 'console op')]
    for bad, why in (
        (Shelve(now + 3, 'line_02', ALL, 1e6, 'x'), 'longer than shelve_max (28800 s)'),
        (Shelve(now + 4, 'nope', ALL, 60.0, 'x'), "unknown alarm 'nope'"),
        (Shelve(now + 5, 'all', ALL, 60.0, 'x'), 'one alarm at a time'),
        (Shelve(now + 6, 'line_01', 'anchor', 60.0, 'x'), "unknown condition 'anchor'"),
    ):
        assert why in core.step(bad).note
    # Shelving another condition of the lifted line is allowed; the ERROR still annunciates.
    step = core.step(Shelve(now + 7, 'line_02', 'anchor_margin', 600.0, 'console op'))
    assert step.note == 'line_02.anchor_margin shelved for 600 s by console op'
    values = dict(_status(step, 'line_02').values)
    assert values['shelved'] == 'true' and values['shelved_condition'] == 'anchor_margin'
    assert values['alarm_state'] in ('unacknowledged', 'acknowledged')


def test_a_whole_line_shelf_hides_its_warning_until_it_expires():
    """A line held in WARN (its anchor margin), shelved whole for 5 s: shown WARN and
    ``shelved``, nothing waiting for an acknowledgement; at the first step after the expiry,
    still WARN: unacknowledged again, as it was shelved (raised when it first was)."""
    config = dock_config(2, tension_timeout=5.0)
    core = MonitorCore(config, T0_NS)

    journal = []

    def second(k):
        t = T0_NS + k * S
        for ev in (Depth(t + 1, 20.85), Tension(t + 2, 0, 450e3), Tension(t + 3, 1, 372e3)):
            journal.extend(core.step(ev).alarm_events)  # line_01: anchor margin 4.1 m: WARN
        return core.step(Tick(t + 4))

    for k in range(1, 4):
        step = second(k)
    assert _status(step, 'line_01').level == Level.WARN
    step = core.step(Shelve(T0_NS + 3 * S + 5, 'line_01', ALL, 5.0, 'bridge'))
    assert step.note == (
        'line_01 shelved for 5 s by bridge: anchor_margin (a new condition still annunciates)'
    )
    values = dict(_status(step, 'line_01').values)
    assert values['alarm_state'] == 'shelved' and values['acknowledged'] == 'true'
    assert float(values['shelved_until']) == pytest.approx((T0_NS + 3 * S + 5) * 1e-9 + 5.0)
    assert values['shelved_by'] == 'bridge' and values['shelved_condition'] == 'anchor_margin'
    assert _status(step, 'line_01').level == Level.WARN  # computed and shown
    for k in range(4, 8):  # 4..7 s: the shelf holds
        step = second(k)
        assert dict(_status(step, 'line_01').values)['alarm_state'] == 'shelved'
    step = second(8)  # the first steps after 8.000000005 s: back unacknowledged
    values = dict(_status(step, 'line_01').values)
    assert (values['alarm_state'], values['shelved']) == ('unacknowledged', 'false')
    assert float(values['alarm_raised']) == (T0_NS + 1 * S + 2) * 1e-9
    kinds = [(e.kind, e.by) for e in journal if e.alarm == 'line_01']
    assert ('unshelved', 'expired') in kinds and kinds.count(('raised', '')) == 1


def test_shelve_records_round_trip():
    ev = Shelve(T0_NS, 'line_02', 'anchor_margin', 600.0, 'console pc client 127.0.0.1')
    assert parse_event_record(ev.stamp_ns, json.dumps(event_record(ev))) == ev
    assert parse_event_record(0, '{"kind": "shelve", "alarm": "a", "seconds": -1}') is None
    assert parse_event_record(0, '{"kind": "shelve", "alarm": "a", "seconds": "x"}') is None


# --- the twin decides alike -------------------------------------------------------------------


def _events(config, tensions, depth, ticks, extra):
    return sorted(events_of(config, tensions, depth, ticks) + extra, key=lambda e: e.stamp_ns)


def _at(s, k=7):
    return T0_NS + int(s * 1e9) + k


def test_run_log_shelves_chatters_and_floods_as_the_core_does():
    """Shelves (whole, one condition, the sensors alarm; expiring inside a vectorized stretch,
    unshelved by an operator, refused), chattering and a flood: the twin's snapshots, journal
    and final state equal the core's event by event."""
    config, tensions, depth, ticks = _storm_core(
        flood_count=6,
        flood_window=60.0,
        chatter_window=20.0,
        shelve_max=120.0,
        unshelvable_conditions=('uplift',),  # the sensors alarm and stale shelvable here
    )
    extra = [
        Shelve(_at(5.0), 'line_01', ALL, 20.0, 'op a'),  # its WARN; expires at 25 s, in a stretch
        Shelve(_at(6.0), 'line_02', ALL, 20.0, 'op a2'),  # refused: nothing active
        Shelve(_at(9.0), 'line_02', 'uplift', 30.0, 'op b'),  # refused
        Shelve(_at(12.0), 'line_03', 'anchor_margin', 30.0, 'op c'),
        Shelve(_at(15.0), 'sensors', ALL, 60.0, 'op d'),
        Acknowledge(_at(16.0), None, 'op e'),
        Shelve(_at(50.0), 'line_03', 'anchor_margin', 100.0, 'op f'),
        Shelve(_at(60.0), 'nope', ALL, 10.0, 'op g'),  # refused
        Shelve(_at(62.0), 'line_01', ALL, 1e6, 'op h'),  # refused: too long
        Shelve(_at(70.0), 'line_03', ALL, 0.0, 'op i'),  # unshelved by an operator
        Shelve(_at(71.0), 'line_03', ALL, 0.0, 'op j'),  # not shelved
    ]
    core = MonitorCore(config, T0_NS)
    steps = [core.step(e) for e in _events(config, tensions, depth, ticks, extra)]
    twin = MonitorCore(config, T0_NS)
    empty = (np.zeros(0, np.int64), np.zeros(0))
    window = Window([tensions.get(line.name, empty) for line in config.lines], depth, ticks)
    result, twin = run_log(twin, window, extra, snapshots=True)
    want = [s.snapshot for s in steps if s.snapshot is not None]
    assert [s.stamp_ns for s in result.snapshots] == [s.stamp_ns for s in want]
    for g, w in zip(result.snapshots, want):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    run_columns(MonitorCore(config, T0_NS), window, extra, result.snapshots)
    journal = [e for s in steps for e in s.alarm_events]
    assert sorted(result.alarm_events) == sorted(journal)
    assert sorted(result.others) == sorted(
        c for s in steps for c in s.transitions if c.component in ('sensors', 'alarms')
    )
    assert_same_state(twin, core)
    # Not vacuous: every kind of record was made.
    kinds = {(e.kind, e.by) for e in journal}
    for kind, by in (('shelved', 'op a'), ('unshelved', 'expired'), ('unshelved', 'op i')):
        assert (kind, by) in kinds
    assert {'refused', 'chattering', 'chattering_end', 'flood', 'raised', 'cleared'} <= {
        k for k, _ in kinds
    }
    answers = [s.note for s in steps if s.kind == 'shelve']
    assert answers[-1] == 'line_03: not shelved, nothing to unshelve'
    # A flood names its first out, in the status and the journal.
    flood = next(e for e in journal if e.kind == 'flood')
    status = next(
        st
        for s in want
        for st in s.statuses
        if st.name == 'catenary_monitor: alarms' and st.level == Level.WARN
    )
    values = dict(status.values)
    assert values['flood'] == 'true' and values['first_out'] == flood.by
    assert status.message.startswith('ALARM FLOOD: 7 alarms raised in the last 60 s')
    assert int(values['alarms_in_window']) > 6


def test_flood_decisions_count_raises_in_the_window():
    a = AlarmConfig(flood_count=3, flood_window=10.0)
    f = alarm_flood.initial()
    f = alarm_flood.decide(f, [(1.0, 'a'), (2.0, 'b'), (3.0, 'c')], 3.0, a)
    assert f.since != f.since and alarm_flood.status(f, a)[0] == Level.OK
    f = alarm_flood.decide(f, [(4.0, 'd')], 4.0, a, active={'a', 'c', 'd'})
    assert (f.since, f.first_out) == (4.0, ('a', 1.0))
    # 'a' returned before the flood: the first out is the first raise still active
    g = alarm_flood.decide(alarm_flood.initial(), list(f.recent), 4.0, a, active={'c', 'd'})
    assert g.first_out == ('c', 3.0)
    assert alarm_flood.status(f, a) == (
        Level.WARN,
        'ALARM FLOOD: 4 alarms raised in the last 10 s (more than 3); first out: a',
    )
    f = alarm_flood.decide(f, [], 11.0, a)  # 1.0 left the window: 3 left, not more than 3
    assert f.since != f.since and len(f.recent) == 3 and f.first_out == ('', f.first_out[1])


def test_a_blind_start_is_one_raise_not_a_flood():
    """Twelve blind lines at start: the one sensors alarm is raised, nothing else counts."""
    config = dock_config(12, flood_count=1)
    core = MonitorCore(config, T0_NS)
    steps = [core.step(Tick(T0_NS + k * S)) for k in range(1, 10)]
    raised = [e for s in steps for e in s.alarm_events if e.kind == 'raised']
    assert [e.alarm for e in raised] == ['sensors']
    assert all(_status(s, 'alarms').level == Level.OK for s in steps)
    assert _status(steps[-1], 'alarms').message == (
        '1 alarm raised in the last 600 s (a flood is more than 1)'
    )


# --- nothing a shelf can hide ------------------------------------------------------------------


def _calm(seconds=200.0):
    """Three calm lines at 5 Hz and a tide gauge at 1 Hz (test_sensor's scene), as columns."""
    from test_sensor import columns, config, scene

    cfg = config(tension_rate_max=100.0)
    t, tensions, depth_t, depth = scene(3)
    keep, keep_d = t < seconds, depth_t < seconds
    return cfg, t[keep], [v[keep] for v in tensions], depth_t[keep_d], depth[keep_d], columns


def _core_and_twin(cfg, cols, dep, extra):
    """The core event by event and the twin over the whole log (must agree); the steps."""
    ticks = ticks_for(cols, dep, rate=1.0)
    core = MonitorCore(cfg, T0_NS)
    steps = [core.step(e) for e in _events(cfg, cols, dep, ticks, extra)]
    twin = MonitorCore(cfg, T0_NS)
    window = Window([cols[line.name] for line in cfg.lines], dep, ticks)
    result, twin = run_log(twin, window, extra, snapshots=True)
    want = [s.snapshot for s in steps if s.snapshot is not None]
    for g, w in zip(result.snapshots, want):
        assert_statuses_agree(g.statuses, w.statuses, g.stamp_ns)
    assert sorted(result.alarm_events) == sorted(e for s in steps for e in s.alarm_events)
    assert_same_state(twin, core)
    return steps


def _shown(steps, name):
    """(time s, level, message, values) of a status in every snapshot."""
    return [
        ((s.stamp_ns - T0_NS) * 1e-9, st.level, st.message, dict(st.values))
        for s in steps
        if s.snapshot is not None
        for st in s.snapshot.statuses
        if st.name == f'catenary_monitor: {name}'
    ]


def test_a_shelved_sensors_alarm_still_annunciates_a_silent_gauge():
    """The sensors common-cause alarm is unshelvable by default: the shelf is refused, and the
    gauge falling silent (every line blind) raises it, unacknowledged."""
    cfg, t, tensions, depth_t, depth, columns = _calm()
    silent = depth_t < 60.0  # the gauge stops at 60 s
    cols, dep = columns(t, tensions, depth_t[silent], depth[silent])
    extra = [Shelve(_at(30.0), 'sensors', ALL, 3600.0, 'night shift')]
    steps = _core_and_twin(cfg, cols, dep, extra)
    answer = next(s.note for s in steps if s.kind == 'shelve')
    assert 'sensors common-cause alarm (loss of monitoring) cannot be shelved' in answer
    late = [x for x in _shown(steps, 'sensors') if x[0] > 60.0 + cfg.alarm.depth_timeout + 1.0]
    assert late and all(x[1] == Level.STALE for x in late), late[:2]
    assert late[0][3]['alarm_state'] == 'unacknowledged' and late[0][3]['shelved'] == 'false'
    assert 'depth sensor silent' in late[0][2]
    raised = [e for s in steps for e in s.alarm_events if e.alarm == 'sensors']
    assert [e.kind for e in raised if e.kind == 'raised'] == ['raised']


def test_a_line_shelved_for_a_stuck_cell_still_annunciates_its_parted_chain():
    """A line shelved whole while its load cell is stuck shelves that condition
    (``sensor_warn``) only; its chain parting then raises the suspected_parted ERROR at once:
    unacknowledged, not shelved, named."""
    from test_sensor import DEPTH, W

    cfg, t, tensions, depth_t, depth, columns = _calm()
    stuck = (t >= 30.0) & (t < 120.0)
    tensions[0][stuck] = tensions[0][np.argmax(stuck)]  # the cell freezes at 30 s
    tensions[0][t >= 120.0] = 0.6 * W * DEPTH  # the chain parts below the hook at 120 s
    cols, dep = columns(t, tensions, depth_t, depth)
    extra = [Shelve(_at(80.0), 'line_00', ALL, 3600.0, 'night shift')]
    steps = _core_and_twin(cfg, cols, dep, extra)
    answer = next(s.note for s in steps if s.kind == 'shelve')
    assert answer == (
        'line_00 shelved for 3600 s by night shift: sensor_warn (a new condition still '
        'annunciates)'
    )
    before = [x for x in _shown(steps, 'line_00') if 85.0 < x[0] < 120.0]
    assert before and all(x[3]['alarm_state'] == 'shelved' for x in before)  # hidden
    after = [x for x in _shown(steps, 'line_00') if x[0] > 122.0]
    assert after and all(x[1] == Level.ERROR for x in after), after[:2]
    first = after[0][3]
    assert first['alarm_state'] == 'unacknowledged' and first['shelved'] == 'true'
    assert first['shelved_condition'] == 'sensor_warn'
    # its T <= w*h is an impossible input at the sample, suspected_parted from the next tick
    # on (the input condition then clears: clear_hold 10 s)
    assert first['alarm_condition'] in ('input', 'sensor_error')
    assert all('suspected parted' in x[3]['detail'] for x in after), after[0][3]['detail']
    late = [x for x in after if x[0] > 135.0]
    assert late and all(x[3]['alarm_condition'] == 'sensor_error' for x in late)
    assert all('impossible input' not in x[2] for x in late), late[0][2]
