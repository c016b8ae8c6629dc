"""A parted chain's consequences: the margin warnings it brings about on the lines left are
suppressed by design (shown, not annunciated), an ERROR never is, and a warning of another
kind, or raised before the part or long after it, still annunciates. Scalar and vectorized
machines agree (seconds)."""

import math

import numpy as np

from replay_data import T0_NS, dock_config, generate
from test_batch import compare, ticks_for

from catenary_monitor.console.frames import Status, alarm_rows
from catenary_monitor.core.alarms import acknowledge as ack
from catenary_monitor.core.alarms.texts import headline
from catenary_monitor.core.alarms.latches import AlarmInputs, LineAlarm, replay_levels
from catenary_monitor.core.config.parameters import AlarmConfig
from catenary_monitor.core.rules import sensor_state
from catenary_monitor.core.rules.level import Level
from test_alarms import CALM, as_arrays, assert_replay_matches, fresh, in_service, run

NAN = math.nan
PEERS = ('ml1', 'ml7', 'ml8')


def alarm(window=300.0, **config):
    """ml8's rules (warning at 6 m of anchor margin, clearing at 7 m)."""
    cfg = AlarmConfig(
        common_cause_window=0.0,
        anchor_margin_warn=6.0,
        anchor_margin_deadband=1.0,
        parted_consequence_window=window,
        **config,
    )
    return LineAlarm(cfg, 0.0, name='ml8', peers=PEERS)


def scene(part_at, warn_at, lift_at=None, end=120.0, dt=0.5, parted_until=None, **extra):
    """ml8's updates: ml7 (index 1) suspected parted from ``part_at`` (until ``parted_until``),
    ml8's anchor margin below its warning from ``warn_at``, its anchor lifting from
    ``lift_at``."""
    updates = []
    for now in np.arange(0.0, end, dt).tolist():
        parted = part_at is not None and now >= part_at
        parted = parted and (parted_until is None or now < parted_until)
        values = dict(parted_other=1.0 if parted else NAN, **extra)
        if now >= warn_at:
            values['anchor_margin'] = 5.0
        if lift_at is not None and now >= lift_at:
            values['uplift_force'] = 1e3
            values['anchor_margin'] = 0.5
        updates.append((now, fresh(now, **values)))
    return updates


def annunciated(events):
    """The (time, new level) of every announced rise."""
    return [(e.time, e.new) for e in events if not e.suppressed and e.new != Level.OK]


def test_a_margin_warning_after_a_part_is_its_consequence_and_the_uplift_annunciates():
    a = alarm()
    state, _, events = run(a, scene(10.0, 25.0, lift_at=27.0))
    assert [(e.time, e.new, e.suppressed) for e in events] == [
        (25.0, Level.WARN, True),
        (27.0, Level.ERROR, False),
    ]
    assert events[0].message.startswith(
        "consequence of ml7's parted chain (suppressed by design): anchor margin 5.00 m < 6.00 m"
    )
    assert state.level == Level.ERROR and not state.suppressed
    assert_replay_matches(a, scene(10.0, 25.0, lift_at=27.0))


def test_the_consequence_is_shown_not_active():
    a = alarm()
    state, _, _ = run(a, scene(10.0, 25.0, end=60.0))
    assert state.level == Level.WARN and state.suppressed
    assert state.message.startswith("consequence of ml7's parted chain")
    assert headline(state.message, 'anchor_margin') == (
        "consequence of ml7's parted chain (suppressed by design): anchor margin 5.00 m < 6.00 m"
    )
    alarm_state = ack.step(ack.AckState(), state.level, 60.0, state.suppressed)
    assert alarm_state.state == ack.NORMAL and alarm_state.suppressed
    values = dict(ack.diagnostic_values(alarm_state, state.level, [False] * 20))
    assert values['alarm_state'] == ack.SUPPRESSED
    # an ERROR is never suppressed, whatever the flag says
    error = ack.step(ack.AckState(), Level.ERROR, 61.0, True)
    assert error.state == ack.UNACKNOWLEDGED


def test_a_warning_before_the_part_long_after_it_or_without_one_annunciates():
    for part_at, warn_at, window in ((30.0, 20.0, 300.0), (10.0, 80.0, 60.0), (None, 25.0, 300.0)):
        updates = scene(part_at, warn_at)
        _, _, events = run(alarm(window), updates)
        assert annunciated(events) == [(warn_at, Level.WARN)], (part_at, warn_at)
        assert_replay_matches(alarm(window), updates)


def test_a_warning_of_another_kind_annunciates():
    for values in (dict(sensor_state=float(sensor_state.STUCK)), dict(inconsistent=1.0)):
        updates = scene(10.0, 200.0, end=60.0)
        for i, (now, x) in enumerate(updates):
            if now >= 25.0:  # a stuck cell, a drift: after the part, beside no margin warning
                updates[i] = (now, fresh(now, parted_other=1.0, **values))
        _, _, events = run(alarm(), updates)
        assert annunciated(events) == [(25.0, Level.WARN)], values
        assert_replay_matches(alarm(), updates)


def test_the_consequence_annunciates_when_the_part_no_longer_stands():
    a = alarm()
    updates = scene(10.0, 25.0, end=80.0, parted_until=50.0)
    state, _, events = run(a, updates)
    assert annunciated(events) == []  # the level stays WARN: no transition at 50 s
    assert state.level == Level.WARN and not state.suppressed
    series = replay_levels(*as_arrays(updates), a, initial=in_service(a, 0.0))
    acks = ack.replay_acks(ack.AckState(), series.times, series.levels, series.suppressed)
    raised = [(s.state, s.raised) for s in acks.states if s.state == ack.UNACKNOWLEDGED]
    assert raised[:1] == [(ack.UNACKNOWLEDGED, 50.0)]  # raised when its cause is gone
    assert_replay_matches(a, updates)


def test_vectorized_equals_scalar_across_windows_and_random_parts():
    rng = np.random.default_rng(36)
    a = alarm(window=20.0, warn_clear_hold=2.0, margin_clear_hold=2.0)
    n, now, updates = 3000, 0.0, []
    parted, low, lift = False, False, False
    for _ in range(n):
        now += float(rng.choice([0.1, 0.5, 1.0, 3.0]))
        parted = parted != (rng.random() < 0.01)
        low = low != (rng.random() < 0.05)
        lift = lift != (rng.random() < (0.2 if lift else 0.01))
        values = {**CALM, 'anchor_margin': 5.0 if low else 8.0}
        if lift:
            values['uplift_force'] = 1e3
        updates.append(
            (
                now,
                AlarmInputs(
                    **values,
                    tension_stamp=now,
                    depth_stamp=now,
                    parted_other=float(rng.integers(0, 3)) if parted else NAN,
                ),
            )
        )
    events = assert_replay_matches(a, updates)
    assert any(e.suppressed for e in events) and any(not e.suppressed for e in events)
    # in two windows, the second starting from the first's final state
    start = in_service(a, updates[0][0])
    first = replay_levels(*as_arrays(updates[:1700]), a, initial=start)
    assert_replay_matches(a, updates[1700:], initial=first.final_state())


def test_parted_others_names_another_line():
    codes = np.array([[0, 5, 0, 5], [0, 0, 0, 0], [5, 0, 0, 0], [5, 0, 0, 5]])
    got = sensor_state.parted_others(codes)
    want = [[1, 3, 1, 1], [NAN] * 4, [NAN, 0, 0, 0], [3, 0, 0, 0]]
    np.testing.assert_array_equal(got, np.array(want, float))


def test_the_console_lists_the_consequences_under_the_parted_alarm():
    part = "suspected parted chain: tension collapsed to 5.3 kN, at or below the hanging chain's"
    warn = "consequence of ml7's parted chain (suppressed by design): anchor margin 5.9 m < 6 m"
    statuses = {
        'ml7': Status('ERROR', part, {'alarm_state': 'unacknowledged', 'alarm_raised': '10.0'}),
        'ml8': Status('WARN', warn, {'alarm_state': 'suppressed'}),
        'ml1': Status('WARN', 'anchor margin 5.0 m < 6.0 m', {'alarm_state': 'unacknowledged'}),
    }
    rows = {r['line']: r for r in alarm_rows(statuses, ['ml1', 'ml7', 'ml8'])}
    assert sorted(rows) == ['ml1', 'ml7']  # the consequence is not an alarm row of its own
    assert rows['ml7']['consequences'] == ['ml8'] and rows['ml1']['consequences'] == []


def test_the_twin_equals_the_core_on_a_part_and_its_consequences():
    """line_01's chain parts at 5 s; line_02's storm brings its margin warning (suppressed)
    and its uplift (annunciated): the twin and the core agree, in one window and in two."""
    config = dock_config(3)
    tensions, depth = generate(config, seconds=90.0, seed=1, dropouts=False)
    t, v = tensions['line_01']
    v = np.where(t >= T0_NS + 5e9, 2e3, v)  # the rest of the chain still hangs from the hook
    tensions['line_01'] = (t, v)
    ticks = ticks_for(tensions, depth)
    steps = compare(config, tensions, depth, ticks)
    compare(config, tensions, depth, ticks, cuts=(T0_NS + 40e9,))
    changes = [c for s in steps for c in s.transitions if c.component == 'line_02']
    assert any(c.transition.suppressed and c.transition.new == Level.WARN for c in changes)
    assert any(not c.transition.suppressed and c.transition.new == Level.ERROR for c in changes)


def test_a_tide_or_dock_warning_is_announced_only_its_blind_stale_is_quiet():
    """The suppression of a line's consequence never reaches the tide's or the dock's status:
    a WARN (also out of a blind STALE) is announced; into or out of that STALE is not."""
    from catenary_monitor.core.alarms.latches import blind_quiet

    assert blind_quiet(Level.OK, Level.STALE) and blind_quiet(Level.STALE, Level.OK)
    assert not blind_quiet(Level.STALE, Level.WARN)
    assert not blind_quiet(Level.OK, Level.WARN) and not blind_quiet(Level.WARN, Level.OK)
    assert not blind_quiet(Level.OK, Level.ERROR)
