"""Alarm state machine: uplift, hysteresis, hold, chatter, impossible and stale input, warnings,
and the vectorized replay agreeing exactly with the scalar machine."""

import math
import subprocess
import sys
from dataclasses import fields
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig
from catenary_monitor.core.alarms.latches import (
    DIAGNOSTIC_KEYS,
    AlarmInputs,
    LineAlarm,
    Transition,
    diagnostic_values,
    replay_levels,
)
from catenary_monitor.core.rules.level import Level

ROOT = Path(__file__).resolve().parents[1]
# A line well inside every limit (SI): no uplift, margins above their warning thresholds.
CALM = dict(
    uplift_force=0.0, anchor_margin=20.0, tide_margin=3.0, load_margin=2e6, safety_factor=5.0
)


def fresh(now, **values):
    """Inputs of an update at ``now`` whose tension and depth samples just arrived."""
    return AlarmInputs(**{**CALM, **values}, tension_stamp=now, depth_stamp=now)


def in_service(alarm, now):
    """A line that has seen calm, fresh data until ``now`` (level OK)."""
    state, _ = alarm.update(alarm.initial(now - 1.0), fresh(now - 1.0), now - 1.0)
    assert state.level == Level.OK
    return state


def run(alarm, updates, state=None):
    """Feed ``[(now, inputs)]`` to the scalar machine from a line in service (or ``state``);
    return (final state, levels, events)."""
    state = in_service(alarm, updates[0][0]) if state is None else state
    levels, events = [], []
    for now, inputs in updates:
        state, new = alarm.update(state, inputs, now)
        levels.append(state.level)
        events.extend(new)
    return state, levels, events


def alarm_with(allowed_uplift=0.0, **config):
    """A line's alarm rules; a lone line's STALE at its timeout (``common_cause_window`` 0)
    unless the test says otherwise; a test's ``warn_clear_hold`` is its margins' clear hold
    too (``margin_clear_hold``) unless it gives that."""
    config.setdefault('common_cause_window', 0.0)
    if 'warn_clear_hold' in config:
        config.setdefault('margin_clear_hold', config['warn_clear_hold'])
    return LineAlarm(AlarmConfig(**config), allowed_uplift)


def as_arrays(updates):
    """The same updates as the column arrays replay_levels takes."""
    names = [f.name for f in fields(AlarmInputs) if f.name != 'status_message']
    if all(x.depth_stale is None for _, x in updates):
        names.remove('depth_stale')  # the alarm decides from the depth's age
    times = np.array([now for now, _ in updates])
    cols = {name: np.array([getattr(x, name) for _, x in updates]) for name in names}
    cols['status_message'] = np.array([x.status_message for _, x in updates], dtype=object)
    return times, cols


# --- uplift ------------------------------------------------------------------------------------


def test_uplift_raises_error_at_the_very_first_update():
    state, levels, events = run(alarm_with(), [(0.0, fresh(0.0, uplift_force=193264.0))])
    assert levels == [Level.ERROR]
    assert events == [
        Transition(0.0, Level.OK, Level.ERROR, 'anchor uplift 193.3 kN > allowed 0.0 kN', None)
    ]
    assert state.message == events[0].message


def test_uplift_raises_at_first_update_that_shows_it():
    updates = [(t, fresh(t)) for t in (0.0, 0.05, 0.1)] + [(0.15, fresh(0.15, uplift_force=1.0))]
    _, levels, events = run(alarm_with(), updates)
    assert levels == [Level.OK] * 3 + [Level.ERROR]
    assert [(e.time, e.new) for e in events] == [(0.15, Level.ERROR)]
    assert events[0].message.startswith('anchor uplift 0.001 kN > allowed 0.0 kN')


def test_uplift_within_allowance_is_not_an_error():
    _, levels, _ = run(alarm_with(allowed_uplift=5e4), [(0.0, fresh(0.0, uplift_force=5e4))])
    assert levels == [Level.OK]


def test_on_delay_is_configurable():
    alarm = alarm_with(on_delay=2.0)
    burst = [(t, fresh(t, uplift_force=1e4)) for t in (0.0, 0.5, 1.0, 1.5)]
    lasting = [(t, fresh(t, uplift_force=1e4)) for t in (3.0, 4.0, 5.0)]
    _, levels, _ = run(alarm, burst + [(2.0, fresh(2.0))] + lasting)
    assert levels == [Level.OK] * 7 + [Level.ERROR]  # raised once it has lasted 2 s (3 -> 5)


def test_uplift_clears_with_force_hysteresis():
    alarm = alarm_with(allowed_uplift=1e5, uplift_clear_hysteresis=1e4, clear_hold=0.0)
    forces = [1.2e5, 9.5e4, 9.1e4, 9.0e4]  # 95 and 91 kN: below allowed, above the clear level
    _, levels, events = run(alarm, [(t, fresh(t, uplift_force=f)) for t, f in enumerate(forces)])
    assert levels == [Level.ERROR, Level.ERROR, Level.ERROR, Level.OK]
    assert (
        'anchor uplift alarm held: uplift 95.0 kN'
        in run(
            alarm, [(0.0, fresh(0.0, uplift_force=1.2e5)), (1.0, fresh(1.0, uplift_force=9.5e4))]
        )[0].message
    )
    assert events[-1] == Transition(3.0, Level.ERROR, Level.OK, 'OK', 3.0)


def test_zero_allowance_clears_only_with_anchor_margin_deadband():
    alarm = alarm_with(
        uplift_clear_margin=1.0, clear_hold=0.0, anchor_margin_warn=0.0, warn_clear_hold=0.0
    )
    margins = [-3.0, 0.2, 0.99, 1.0]
    updates = [(0.0, fresh(0.0, uplift_force=2e4, anchor_margin=-3.0))] + [
        (float(t), fresh(t, anchor_margin=m)) for t, m in enumerate(margins[1:], 1)
    ]
    _, levels, _ = run(alarm, updates)
    assert levels == [Level.ERROR, Level.ERROR, Level.ERROR, Level.OK]


def test_clear_hold_time_restarts_on_any_interruption():
    alarm = alarm_with(clear_hold=30.0)
    updates = [(0.0, fresh(0.0, uplift_force=1e5))]
    updates += [(t, fresh(t)) for t in np.arange(1.0, 25.0)]  # 24 s of calm
    updates += [(25.0, fresh(25.0, uplift_force=10.0))]  # a brief lift
    updates += [(t, fresh(t)) for t in np.arange(26.0, 60.0)]
    _, levels, events = run(alarm, updates)
    assert [(e.time, e.old, e.new) for e in events] == [
        (0.0, Level.OK, Level.ERROR),
        (56.0, Level.ERROR, Level.OK),
    ]  # 26 + 30 s
    assert events[-1].duration == 56.0


# --- chatter -----------------------------------------------------------------------------------


def wave_updates(period, seconds=600.0, rate=20.0, mean=5e3, amplitude=4e4):
    """Hook tension swinging at wave frequency around the onset of uplift, sampled at ``rate``.

    Uplift appears in every crest and vanishes in every trough; the anchor margin swings about 0.
    """
    updates = []
    for t in np.arange(0.0, seconds, 1.0 / rate):
        swing = mean + amplitude * math.sin(2.0 * math.pi * t / period)
        updates.append(
            (float(t), fresh(t, uplift_force=max(swing, 0.0), anchor_margin=-swing / 1e4))
        )
    return updates


@pytest.mark.parametrize('period', [8.0, 4.0, 1.0])
def test_wave_oscillation_around_uplift_gives_one_transition(period):
    updates = wave_updates(period)
    _, levels, events = run(alarm_with(), updates)
    crossings = sum(
        1
        for (_, a), (_, b) in zip(updates, updates[1:])
        if (a.uplift_force > 0) != (b.uplift_force > 0)
    )
    assert crossings > 100  # the input really does cross the threshold, many times
    assert [(e.old, e.new) for e in events] == [(Level.OK, Level.ERROR)]
    # The storm eases: one more transition, after the hold, giving the episode length (the
    # margins' clear hold as the ERROR's here: the warning under it clears with it).
    end = updates[-1][0]
    calm = [(end + k, fresh(end + k)) for k in range(1, 40)]
    _, _, events = run(alarm_with(margin_clear_hold=30.0), updates + calm)
    assert [(e.old, e.new) for e in events] == [(Level.OK, Level.ERROR), (Level.ERROR, Level.OK)]
    assert events[1].time == end + 31.0 and events[1].duration == end + 31.0 - events[0].time


def storm_margins(groups, seconds, lull_amplitude=3.0, group_amplitude=5.5):
    """A neighbour line's anchor margin in a storm (10 Hz): 10 m swinging at 8 s waves by
    ``lull_amplitude`` (never below the warning's clear level, 6 m), and by
    ``group_amplitude`` (below the 5 m warning at the crests) in wave groups of 30 s starting
    at ``groups`` [s]."""
    updates = []
    for t in np.arange(0.0, seconds, 0.1):
        grouped = any(g <= t < g + 30.0 for g in groups)
        swing = group_amplitude if grouped else lull_amplitude
        margin = 10.0 - swing * math.sin(2.0 * math.pi * t / 8.0)
        updates.append((float(t), fresh(t, anchor_margin=margin)))
    return updates


def test_a_margin_warning_at_a_storms_edge_is_one_warning():
    # Wave groups reach the warning 270 s and 420 s apart, the margin back above its clear
    # level in between: with a clear hold of 30 s the same warning was raised three times.
    updates = storm_margins([100.0, 400.0, 850.0], 1600.0)
    _, _, events = run(alarm_with(), updates)
    first = next(t for t, x in updates if x.anchor_margin < 5.0)
    assert [(e.time, e.old, e.new) for e in events] == [
        (first, Level.OK, Level.WARN),  # raised at the first crest below, not delayed
        (pytest.approx(880.0 + 600.0, abs=8.0), Level.WARN, Level.OK),  # 600 s after
    ]
    assert assert_replay_matches(alarm_with(), updates) == events
    short = alarm_with(margin_clear_hold=30.0)
    assert [e.new for e in run(short, updates)[2]] == [Level.WARN, Level.OK] * 3


def test_without_hold_the_same_wave_would_chatter():
    # Proves the chatter test above is sensitive: with no hold and no deadband it flaps.
    alarm = alarm_with(clear_hold=0.0, uplift_clear_margin=0.0, anchor_margin_warn=0.0)
    _, _, events = run(alarm, wave_updates(8.0, seconds=120.0))
    assert len(events) > 20


def test_wave_oscillation_around_a_warning_gives_one_transition():
    updates = []
    for t in np.arange(0.0, 300.0, 0.1):
        margin = 5.0 + 2.0 * math.sin(2.0 * math.pi * t / 8.0)
        updates.append((float(t), fresh(t, anchor_margin=margin)))
    _, _, events = run(alarm_with(), updates)
    assert [(e.old, e.new) for e in events] == [(Level.OK, Level.WARN)]
    assert assert_replay_matches(alarm_with(), updates) == events


# --- impossible input --------------------------------------------------------------------------


def test_impossible_input_is_an_error_at_once_with_the_solvers_sentence():
    sentence = 'hook tension 2.0e+04 N is not above weight x depth 2.7e+04 N'
    bad = AlarmInputs(status=3, status_message=sentence, tension_stamp=1.0, depth_stamp=1.0)
    _, levels, events = run(
        alarm_with(clear_hold=5.0),
        [(0.0, fresh(0.0)), (1.0, bad)] + [(t, fresh(t)) for t in range(2, 9)],
    )
    assert levels == [Level.OK] + [Level.ERROR] * 6 + [Level.OK] * 2  # clear at 2 + 5 s
    assert events[0].message == f'impossible input: {sentence}'
    assert events[1].time == 7.0 and events[1].duration == 6.0


def test_impossible_input_held_message_and_default_sentence():
    alarm = alarm_with(clear_hold=5.0)
    nan_input = AlarmInputs(status=1, tension_stamp=0.0, depth_stamp=0.0)
    state, _, events = run(alarm, [(0.0, nan_input), (1.0, fresh(1.0))])
    assert events[0].message == 'impossible input: solver status 1'
    assert state.message == (
        'impossible input alarm held: last was "solver status 1" '
        '(clears after 5 s of valid input)'
    )


def test_nan_quantity_keeps_a_raised_alarm():
    alarm = alarm_with(clear_hold=0.0)
    not_applicable = fresh(1.0, uplift_force=math.nan, anchor_margin=math.nan)
    updates = [(0.0, fresh(0.0, uplift_force=1e4)), (1.0, not_applicable)]
    _, levels, _ = run(alarm, updates + [(2.0, fresh(2.0))])
    assert levels == [Level.ERROR, Level.ERROR, Level.OK]


# --- stale -------------------------------------------------------------------------------------


def test_a_lone_line_is_stale_one_common_cause_window_late_unless_grouped():
    """Alone, a line's own STALE waits ``common_cause_window`` (1 s) past its timeout (the
    common cause is found first); silent with other inputs it is STALE at its timeout,
    suppressed by design (the sensors alarm announces it)."""
    alarm = alarm_with(tension_timeout=5.0, common_cause_window=1.0)
    x = dict(CALM, tension_stamp=1.0)
    at = [(t, AlarmInputs(**x, depth_stamp=t)) for t in (0.0, 6.5, 7.0, 7.5)]
    _, levels, events = run(alarm, at)
    assert levels == [Level.OK, Level.OK, Level.OK, Level.STALE]
    assert not events[0].suppressed
    grouped = [(t, AlarmInputs(**x, depth_stamp=t, silent_group=1.0)) for t in (0.0, 6.5)]
    state, levels, events = run(alarm, grouped)
    assert levels == [Level.OK, Level.STALE] and events[0].suppressed and state.suppressed


def test_stale_tension_is_detected_and_recovers():
    alarm = alarm_with(tension_timeout=5.0)
    updates = [(t, fresh(t)) for t in (0.0, 1.0)]
    updates += [(t, AlarmInputs(**CALM, tension_stamp=1.0, depth_stamp=t)) for t in range(2, 9)]
    updates += [(9.0, fresh(9.0))]
    state, levels, events = run(alarm, updates)
    assert levels == [Level.OK] * 7 + [Level.STALE] * 2 + [Level.OK]  # age 6 s > 5 s at t = 7
    assert events[0] == Transition(
        7.0, Level.OK, Level.STALE, 'tension stale: last sample 6.0 s ago (timeout 5 s)', None
    )
    assert events[1] == Transition(9.0, Level.STALE, Level.OK, 'OK', 2.0)


def test_a_line_starts_blind_and_says_what_it_misses():
    alarm = alarm_with(depth_timeout=60.0)
    start = alarm.initial(100.0)
    note = ' (suppressed by design: alarm on sensors)'
    assert (start.level, start.message, start.suppressed) == (
        Level.STALE,
        'blind: no tension received yet; no depth received yet' + note,
        True,
    )
    updates = [
        (float(t), AlarmInputs(**CALM, tension_stamp=float(t))) for t in range(110, 200, 10)
    ]
    state, levels, events = run(alarm, updates, start)
    assert levels == [Level.STALE] * 9 and events == []  # never OK without a depth
    assert state.message == 'blind: no depth received yet' + note and state.suppressed
    state, levels, events = run(alarm, [(200.0, fresh(200.0))], state)
    # Out of a STALE suppressed by design: not announced (the sensors alarm was).
    assert events == [Transition(200.0, Level.STALE, Level.OK, 'OK', 100.0, True)]


def test_only_a_line_blind_by_a_common_cause_is_suppressed():
    """STALE by the depth (or a tension never received) is suppressed by design; a tension
    that went stale after it reported is the line's own alarm, announced."""
    alarm = alarm_with(depth_timeout=60.0, tension_timeout=5.0)
    ok = [(float(t), fresh(float(t))) for t in range(0, 5)]
    depth_gone = [
        (float(t), AlarmInputs(**CALM, tension_stamp=float(t), depth_stamp=4.0))
        for t in range(5, 70)
    ]
    state, levels, events = run(alarm, ok + depth_gone)
    assert levels[-1] == Level.STALE and state.suppressed
    assert events[-1].new == Level.STALE and events[-1].suppressed
    assert state.message.startswith('blind: depth stale: last sample 65.0 s ago')
    own = [
        (float(t), AlarmInputs(**CALM, tension_stamp=4.0, depth_stamp=float(t)))
        for t in range(5, 12)
    ]
    state, levels, events = run(alarm, ok + own)
    assert levels[-1] == Level.STALE and not state.suppressed
    assert events[-1] == Transition(
        10.0, Level.OK, Level.STALE, 'tension stale: last sample 6.0 s ago (timeout 5 s)', None
    )
    assert not events[-1].suppressed


def test_depth_stale_decision_of_the_monitor_wins_over_the_age():
    alarm = alarm_with(depth_timeout=60.0)
    said_stale = AlarmInputs(**CALM, tension_stamp=5.0, depth_stamp=4.0, depth_stale=True)
    said_fresh = AlarmInputs(**CALM, tension_stamp=95.0, depth_stamp=4.0, depth_stale=False)
    _, levels, events = run(alarm, [(5.0, said_stale), (95.0, said_fresh)])
    assert levels == [Level.STALE, Level.OK]
    assert events[0].message == (
        'blind: depth stale: last sample 1.0 s ago (timeout 60 s)'
        ' (suppressed by design: alarm on sensors)'
    )


def test_error_outranks_stale_and_nothing_clears_on_stale_data():
    alarm = alarm_with(clear_hold=3.0, tension_timeout=2.0)
    updates = [(0.0, fresh(0.0, uplift_force=5e4))]
    # Tension stops at t = 1 with a calm sample; 10 s of ticks on that stale sample.
    updates += [(1.0, fresh(1.0))] + [
        (float(t), AlarmInputs(**CALM, tension_stamp=1.0, depth_stamp=float(t)))
        for t in range(2, 12)
    ]
    state, levels, events = run(alarm, updates)
    assert set(levels) == {Level.ERROR}  # the stale calm sample never cleared the uplift alarm
    assert state.message.startswith('anchor uplift alarm held')
    assert 'tension stale: last sample 10.0 s ago (timeout 2 s)' in state.message
    # Fresh calm data again: clears after the hold, timed from the first fresh sample.
    more = [(float(t), fresh(t)) for t in range(12, 17)]
    _, levels, events = run(alarm, updates + more)
    assert [(e.time, e.new) for e in events] == [(0.0, Level.ERROR), (15.0, Level.OK)]


def test_stale_outranks_warn_and_warn_returns_after_recovery():
    alarm = alarm_with(tension_timeout=2.0)
    updates = [(0.0, fresh(0.0, anchor_margin=4.0))]
    updates += [
        (
            float(t),
            AlarmInputs(**{**CALM, 'anchor_margin': 4.0}, tension_stamp=0.0, depth_stamp=float(t)),
        )
        for t in range(1, 5)
    ]
    updates += [(5.0, fresh(5.0, anchor_margin=4.0))]
    _, levels, events = run(alarm, updates)
    assert levels == [Level.WARN] * 3 + [Level.STALE] * 2 + [Level.WARN]
    assert events[1].message == (
        'tension stale: last sample 3.0 s ago (timeout 2 s); ' 'anchor margin 4.00 m < 5.00 m'
    )


# --- warnings ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    'name, low, between, high, text',
    [
        ('anchor_margin', 4.2, 5.5, 6.0, 'anchor margin 4.20 m < 5.00 m'),
        ('tide_margin', 0.8, 1.1, 1.2, 'tide margin 0.80 m < 1.00 m'),
        ('load_margin', -2e4, 5e3, 1e4, 'load margin -20.0 kN < 0.0 kN'),
        ('safety_factor', 1.9, 2.05, 2.1, 'safety factor 1.90 < 2.00'),
    ],
)
def test_warning_thresholds_with_deadband_and_hold(name, low, between, high, text):
    alarm = alarm_with(warn_clear_hold=10.0)
    values = [low] + [between] * 20 + [high] * 11
    updates = [(float(t), fresh(t, **{name: v})) for t, v in enumerate(values)]
    _, levels, events = run(alarm, updates)
    assert events[0] == Transition(0.0, Level.OK, Level.WARN, text, None)
    # In the deadband the warning holds; at warn + deadband it clears after the 10 s hold.
    assert levels == [Level.WARN] * 31 + [Level.OK]
    assert events[1].time == 31.0 and events[1].duration == 31.0


def test_several_conditions_are_joined_errors_first():
    x = fresh(0.0, uplift_force=193264.0, anchor_margin=-30.0, safety_factor=1.9)
    _, _, events = run(alarm_with(), [(0.0, x)])
    assert events[0].message == (
        'anchor uplift 193.3 kN > allowed 0.0 kN; '
        'anchor margin -30.00 m < 5.00 m; safety factor 1.90 < 2.00'
    )


def test_episode_durations_for_nested_levels():
    alarm = alarm_with(clear_hold=0.0, warn_clear_hold=0.0)
    updates = [
        (0.0, fresh(0.0)),
        (10.0, fresh(10.0, anchor_margin=4.0)),
        (20.0, fresh(20.0, anchor_margin=-1.0, uplift_force=1e4)),
        (25.0, fresh(25.0, safety_factor=1.9)),  # the uplift gone, another warning stands
        (40.0, fresh(40.0)),
    ]
    _, _, events = run(alarm, updates)
    assert [(e.time, e.old, e.new, e.duration) for e in events] == [
        (10.0, Level.OK, Level.WARN, None),
        (20.0, Level.WARN, Level.ERROR, None),
        (25.0, Level.ERROR, Level.WARN, 5.0),
        (40.0, Level.WARN, Level.OK, 30.0),
    ]


def test_uplift_error_never_steps_down_into_the_margin_warning():
    # The anchor lifts at the wave peaks of a margin hovering inside the warning band: the
    # ERROR clears only at the warning's clear level (anchor_margin_warn + deadband, 6 m),
    # so it does not fall to WARN and re-escalate with the next wave group.
    alarm = alarm_with(clear_hold=5.0, warn_clear_hold=5.0)
    updates = [(0.0, fresh(0.0))]
    for t in np.arange(60.0, 420.0, 1.0):
        group = int(t) // 60 % 2 == 0  # a wave group lifting the anchor every other minute
        margin = 3.0 + 2.0 * math.sin(2.0 * math.pi * t / 8.0)
        lift = 5e3 if group and margin > 4.9 else 0.0
        updates.append((float(t), fresh(t, anchor_margin=margin, uplift_force=lift)))
    updates += [(float(t), fresh(t)) for t in np.arange(420.0, 440.0, 1.0)]
    _, _, events = run(alarm, updates)
    assert [(e.old, e.new) for e in events] == [
        (Level.OK, Level.WARN), (Level.WARN, Level.ERROR), (Level.ERROR, Level.OK)
    ]
    assert 'anchor margin >= 6.0 m' in run(alarm, updates[:142])[0].message  # t 200 s
    assert assert_replay_matches(alarm, updates) == events
    old = alarm_with(clear_hold=5.0, warn_clear_hold=5.0, anchor_margin_warn=0.0)
    assert len(run(old, updates)[2]) > 3  # a warning band below the clear margin: it flaps


def test_time_going_backwards_restarts_pending_timers():
    alarm = alarm_with(clear_hold=5.0)
    updates = [
        (100.0, fresh(100.0, uplift_force=1e4)),
        (101.0, fresh(101.0)),
        (0.0, fresh(0.0)),
        (4.0, fresh(4.0)),
        (5.0, fresh(5.0)),
    ]
    _, levels, _ = run(alarm, updates)
    assert levels == [Level.ERROR] * 4 + [Level.OK]


def test_rejects_non_finite_time():
    with pytest.raises(ValueError, match='now must be finite'):
        alarm_with().update(LineAlarm().initial(0.0), fresh(0.0), math.nan)


def test_for_line_takes_the_lines_allowance():
    line = LineConfig('line_11', 1300.0, 121.06, 4827000.0, allowed_uplift=2e5)
    assert LineAlarm.for_line(line, AlarmConfig()).allowed_uplift == 2e5


# --- scalar == vectorized ----------------------------------------------------------------------

NAN = math.nan


@st.composite
def scenarios(draw):
    """Config and updates built from values at, just around and far from every threshold."""
    allowed = draw(st.sampled_from([0.0, 5e4]))
    config = AlarmConfig(
        on_delay=draw(st.sampled_from([0.0, 0.5, 2.0])),
        clear_hold=draw(st.sampled_from([0.0, 1.0, 3.0])),
        warn_clear_hold=draw(st.sampled_from([0.0, 0.75, 2.5])),
        margin_clear_hold=draw(st.sampled_from([0.0, 1.5, 2.5])),
        tension_timeout=draw(st.sampled_from([0.5, 2.0])),
        depth_timeout=draw(st.sampled_from([1.0, 5.0])),
        uplift_clear_hysteresis=draw(st.sampled_from([0.0, 1e4, 1e5])),
        anchor_margin_deadband=draw(st.sampled_from([0.0, 1.0])),
    )
    n = draw(st.integers(1, 60))
    pick = lambda pool: draw(st.lists(st.sampled_from(pool), min_size=n, max_size=n))  # noqa
    dts = pick([0.0, 0.1, 0.25, 0.5, 1.0, 1.9, 2.0, 3.0])
    cols = dict(
        uplift_force=pick([0.0, 1.0, allowed, allowed - 1e4, allowed + 1.0, 4e4, 1e5, NAN]),
        anchor_margin=pick([-5.0, 0.0, 0.999, 1.0, 4.999, 5.0, 5.5, 6.0, 20.0, NAN]),
        tide_margin=pick([0.5, 1.0, 1.1, 1.2, 3.0, NAN]),
        load_margin=pick([-1.0, 0.0, 5e3, 1e4, 1e5, NAN]),
        safety_factor=pick([1.5, 2.0, 2.05, 2.1, 5.0, NAN]),
        status=pick([0, 0, 0, 0, 1, 3]),
        tension_fresh=pick([True, True, True, False]),
        depth_fresh=pick([True, True, False]),
    )
    return LineAlarm(config, allowed), dts, cols


def build_updates(dts, cols):
    updates, now, t_stamp, d_stamp = [], 10.0, NAN, NAN
    for k, dt in enumerate(dts):
        now += dt
        t_stamp = now if cols['tension_fresh'][k] else t_stamp
        d_stamp = now if cols['depth_fresh'][k] else d_stamp
        status = cols['status'][k]
        updates.append(
            (
                now,
                AlarmInputs(
                    **{name: cols[name][k] for name in CALM},
                    status=status,
                    status_message=f'bad input {status}' if status else '',
                    tension_stamp=t_stamp,
                    depth_stamp=d_stamp,
                ),
            )
        )
    return updates


def assert_replay_matches(alarm, updates, initial=None, **kwargs):
    start = in_service(alarm, updates[0][0]) if initial is None else initial
    state, levels, events = run(alarm, updates, start)
    result = replay_levels(*as_arrays(updates), alarm, initial=start, **kwargs)
    assert result.levels.tolist() == [int(level) for level in levels]
    assert result.transitions == events
    assert result.final_state() == state
    for i in (0, len(updates) // 2, len(updates) - 1):
        want, _, _ = run(alarm, updates[: i + 1], start)
        assert result.message_at(i) == want.message
    return events


@settings(
    max_examples=120, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(scenarios())
def test_vectorized_replay_equals_scalar_machine(scenario):
    alarm, dts, cols = scenario
    assert_replay_matches(alarm, build_updates(dts, cols))


def test_vectorized_equals_scalar_on_a_long_random_sequence():
    rng = np.random.default_rng(7)
    n = 4000
    alarm = LineAlarm(
        AlarmConfig(
            on_delay=0.3,
            clear_hold=2.0,
            warn_clear_hold=1.0,
            margin_clear_hold=1.5,
            tension_timeout=0.6,
            depth_timeout=3.0,
        ),
        2e4,
    )
    dts = rng.choice([0.05, 0.05, 0.1, 0.7, 3.5], n).tolist()
    cols = dict(
        uplift_force=np.where(rng.random(n) < 0.5, 0.0, rng.normal(2e4, 2e4, n)).tolist(),
        anchor_margin=rng.normal(6.0, 4.0, n).tolist(),
        tide_margin=rng.normal(1.6, 0.3, n).tolist(),
        load_margin=rng.normal(3e4, 2e4, n).tolist(),
        safety_factor=rng.normal(2.5, 0.3, n).tolist(),
        status=np.where(rng.random(n) < 0.01, 2, 0).tolist(),
        tension_fresh=(rng.random(n) < 0.95).tolist(),
        depth_fresh=(rng.random(n) < 0.3).tolist(),
    )
    events = assert_replay_matches(alarm, build_updates(dts, cols))
    # Not vacuous: many transitions, into every level.
    assert len(events) > 50 and {e.new for e in events} == set(Level)


def test_vectorized_wave_and_status_table():
    updates = wave_updates(8.0, seconds=120.0)
    assert len(assert_replay_matches(alarm_with(), updates)) == 1
    times, cols = as_arrays(
        [(0.0, fresh(0.0)), (1.0, AlarmInputs(status=1, tension_stamp=1.0, depth_stamp=1.0))]
    )
    del cols['status_message']
    result = replay_levels(
        times,
        cols,
        alarm_with(),
        status_messages={1: 'tension is NaN'},
        initial=in_service(alarm_with(), 0.0),
    )
    assert result.transitions[0].message == 'impossible input: tension is NaN'


def test_replay_accepts_scalars_and_rejects_bad_calls():
    result = replay_levels(
        [0.0, 1.0, 2.0],
        {
            'uplift_force': [0.0, 1.0, 0.0],
            'anchor_margin': 20.0,
            'tension_stamp': [0, 1, 2],
            'depth_stamp': 0.0,
        },
        alarm_with(),
    )
    assert result.levels.tolist() == [Level.OK, Level.ERROR, Level.ERROR]
    assert replay_levels([], {}, alarm_with()).levels.size == 0
    with pytest.raises(ValueError, match='non-decreasing'):
        replay_levels([1.0, 0.0], {}, alarm_with())
    with pytest.raises(ValueError, match='unknown input fields'):
        replay_levels([0.0], {'uplift': 1.0}, alarm_with())


# --- diagnostics values and purity ---------------------------------------------------------------


def test_diagnostic_values_keys_and_exact_strings():
    fields_ = {key: 1.0 / (k + 3) for k, key in enumerate(DIAGNOSTIC_KEYS)}
    fields_['uplift_force'] = np.float64(193258.123456789)
    values = diagnostic_values(fields_)
    assert [key for key, _ in values] == [
        'top_tension',
        'depth',
        'horizontal_tension',
        'min_anchor_distance',
        'anchor_margin',
        'uplift_force',
        'tide_margin',
        'load_margin',
        'safety_factor',
        'time_to_uplift',
        'uplift_force_upper',
        'anchor_margin_lower',
        'tide_margin_lower',
        'grounded_length',
        'holding_capacity',
        'drag_margin',
        'implied_anchor_distance',
        'tide_margin_at_length',
        'drag_state',
        'fatigue_damage',
        'fatigue_damage_rate',
        'fatigue_life_left',
        'wave_tension',
        'peak_tension',
        'dynamic_uplift',
        'channels_healthy',
        'channel_states',
    ]
    assert all(isinstance(v, str) and float(v) == float(fields_[k]) for k, v in values)
    from_object = dict(diagnostic_values(SimpleNamespace(depth=20.85)))
    assert from_object['depth'] == '20.85'
    assert from_object['top_tension'] == 'nan' and math.isnan(float(from_object['top_tension']))


def test_core_modules_import_without_rclpy():
    code = (
        "import sys; sys.modules['rclpy'] = None; "
        "import catenary_monitor.core.config.parameters, catenary_monitor.core.alarms.latches; "
        "print('ok')"
    )
    out = subprocess.run(
        [sys.executable, '-c', code],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={'PYTHONPATH': str(ROOT)},
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == 'ok'


def test_margin_codes_match_the_scalar() -> None:
    """The warnings with a deadband classified on columns give LineAlarm._classify's code for
    every update: values at, below and between the limits, NaN and infinities, stale and fresh
    inputs; None where the latch is down and nothing breaches."""
    from catenary_monitor.core.alarms import latches as alarms

    alarm = alarms.LineAlarm(AlarmConfig(), 0.0)
    rng = np.random.default_rng(11)
    n = 3000
    x = {}
    for cond in alarms._MARGINS:
        low, high = alarm._warn_limits(cond)
        x[cond] = rng.choice(
            [
                low,
                high,
                np.nextafter(low, -np.inf),
                (low + high) / 2,
                high * 2 + 1,
                np.nan,
                np.inf,
                -np.inf,
            ],
            n,
        )
    keys = ('uplift_force', 'uplift_force_upper', 'inconsistent', 'sensor_state', 'drag_state')
    keys += ('fatigue_damage', 'channel_states', 'channels_healthy')
    for key in keys:
        x[key] = np.zeros(n)
    x['dynamic_uplift'] = np.full(n, np.nan)
    stale = rng.random(n) < 0.3
    status = np.zeros(n, np.int64)
    quiet = {cond: x[cond].copy() for cond in alarms._MARGINS}
    for column in quiet.values():
        column[:] = np.inf  # no breach anywhere
    down = [alarms.Latch()] * len(alarms.CONDITIONS)
    got = alarms._classify_columns(alarm, x, status, stale, down)
    for cond in alarms._MARGINS:
        want = [
            alarm._classify(cond, alarms.AlarmInputs(**{cond: v}), s)
            for v, s in zip(x[cond].tolist(), stale.tolist())
        ]
        assert got[cond] is not None and got[cond].tolist() == want, cond
    none = alarms._classify_columns(alarm, {**x, **quiet}, status, stale, down)
    assert all(none[cond] is None for cond in alarms._MARGINS)


def test_the_latch_column_loop_equals_the_scalar_step():
    """alarms._latch_series (the latch's column loop) equals repeated alarms._step, from latches
    up or down, pending (since a past update's stamp) or not, through equal stamps and zero
    delays."""
    from catenary_monitor.core.alarms import latches as alarms

    rng = np.random.default_rng(5)
    for trial in range(2000):
        n = int(rng.integers(1, 50))
        t = 10.0 + np.cumsum(rng.choice([0.0, 0.3, 1.0, 2.5], n))
        codes = rng.choice(3, n, p=rng.dirichlet([1, 1, 1])).astype(np.int8)
        since = None if trial % 2 else float(t[0] - rng.uniform(0.0, 4.0))
        start = alarms.Latch(bool(trial % 3 == 0), since)
        on_delay, hold = float(rng.choice([0.0, 0.5, 2.0])), float(rng.choice([0.0, 1.0, 3.0]))
        latch, want = start, []
        for code, now in zip(codes.tolist(), t.tolist()):
            latch = alarms._step(latch, code, now, on_delay, hold)
            want.append(latch.active)
        active, end = alarms._latch_series(codes, t, on_delay, hold, start)
        assert active.dtype == bool and active.tolist() == want, trial
        assert end == latch, trial
