"""Alarm acknowledgement (core/alarms/acknowledge.py): ISA-18.2 states, through the monitor
core."""

import json
import math

import numpy as np
from replay_data import (  # noqa: F401 - the oracle's helpers
    T0_NS,
    core_steps,
    dock_config,
    events_of,
    generate,
)

from catenary_monitor.core.alarms import acknowledge as ack
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.events import (
    Acknowledge,
    Tick,
    event_record,
    parse_event_record,
)
from catenary_monitor.core.monitor.monitor_core import MonitorCore

S = 10**9


def walk(levels, suppressed=(), start=0.0, dt=1.0, state=None):
    """Step the machine through levels at 1 s spacing from t = start + dt; ``suppressed``:
    the step numbers whose level is suppressed by design."""
    state = state or ack.initial(start)
    out = []
    for k, level in enumerate(levels):
        state = ack.step(state, level, start + dt * (k + 1), k in suppressed)
        out.append(state.state)
    return state, out


def test_raise_acknowledge_clear():
    state, seen = walk([Level.OK, Level.WARN, Level.WARN])
    assert seen == ['normal', 'unacknowledged', 'unacknowledged']
    assert state.raised == 2.0
    state = ack.acknowledge(state, 3.5, 'console 127.0.0.1')
    assert (state.state, state.acknowledged_by, state.acknowledged_at) == (
        'acknowledged',
        'console 127.0.0.1',
        3.5,
    )
    # An acknowledgement never clears an active alarm; the condition does.
    state = ack.step(state, Level.WARN, 4.0)
    assert state.state == 'acknowledged'
    state = ack.step(state, Level.OK, 5.0)
    assert state.state == 'normal'


def test_return_unacknowledged_stays_until_acknowledged():
    state, seen = walk([Level.OK, Level.ERROR, Level.OK, Level.OK])
    assert seen == ['normal', 'unacknowledged', 'returned-unacknowledged'] + [
        'returned-unacknowledged'
    ]
    state = ack.acknowledge(state, 9.0, 'ros')
    assert state.state == 'normal'
    # Acknowledging a normal alarm changes nothing.
    assert ack.acknowledge(state, 10.0, 'x') == state


def test_escalation_re_raises_an_acknowledged_alarm():
    state, _ = walk([Level.OK, Level.WARN])
    state = ack.acknowledge(state, 2.5, 'op')
    state = ack.step(state, Level.ERROR, 3.0)
    assert (state.state, state.level, state.raised) == ('unacknowledged', Level.ERROR, 3.0)
    state = ack.acknowledge(state, 4.0, 'op')
    # Severity falling back keeps it acknowledged; rising again re-raises it.
    state = ack.step(state, Level.WARN, 5.0)
    assert state.state == 'acknowledged'
    state = ack.step(state, Level.ERROR, 6.0)
    assert state.state == 'unacknowledged'


def test_a_suppressed_stale_is_no_alarm_and_says_so():
    # Blind by a common cause (suppressed by design), then data: never an alarm.
    state, seen = walk([Level.STALE, Level.STALE, Level.OK], suppressed={0, 1})
    assert seen == ['normal'] * 3 and not state.suppressed
    state, _ = walk([Level.STALE] * 7, suppressed=set(range(7)))
    assert state.state == 'normal' and state.suppressed
    values = dict(ack.diagnostic_values(state, Level.STALE, [False] * 12))
    assert (values['alarm_state'], values['acknowledged']) == ('suppressed', 'true')
    # STALE of its own (a tension stale after it reported) is an alarm at once.
    _, seen = walk([Level.STALE, Level.OK, Level.STALE], suppressed={0})
    assert seen == ['normal', 'normal', 'unacknowledged']
    # An unacknowledged alarm that becomes suppressed waits for its acknowledgement.
    state, seen = walk([Level.WARN, Level.STALE, Level.STALE], suppressed={1, 2})
    assert seen == ['unacknowledged'] + ['returned-unacknowledged'] * 2
    assert dict(ack.diagnostic_values(state, Level.STALE, [False] * 12))['alarm_state'] == (
        'returned-unacknowledged'
    )
    state = ack.acknowledge(state, 9.0, 'op')
    assert dict(ack.diagnostic_values(state, Level.STALE, [False] * 12))['alarm_state'] == (
        'suppressed'
    )


def test_replay_acks_equals_stepping_every_update():
    rng = np.random.default_rng(3)
    for trial in range(200):
        n = int(rng.integers(1, 40))
        levels = rng.choice([0, 1, 2, 3], size=n, p=[0.5, 0.2, 0.1, 0.2]).astype(np.int8)
        if trial % 3 == 0:
            levels[: int(rng.integers(0, n))] = Level.STALE
        times = np.cumsum(rng.uniform(0.1, 2.0, n))
        before = ack.initial(0.0)
        if trial % 4 == 1:
            before, _ = walk([Level.OK, Level.ERROR], start=-10.0)
        quiet = (levels == Level.STALE) & (rng.uniform(size=n) < 0.6)
        series = ack.replay_acks(before, times, levels, quiet)
        state = before
        for i in range(n):
            state = ack.step(state, Level(int(levels[i])), float(times[i]), bool(quiet[i]))
            assert series.at(i) == state, (trial, i)
        assert series.final == state


def test_parse_request():
    assert ack.parse_request('line_11') == ('line_11', 'ros')
    assert ack.parse_request('  all console 127.0.0.1:8080 ') == (None, 'console 127.0.0.1:8080')
    try:
        ack.parse_request('  ')
    except ValueError as err:
        assert 'LINE' in str(err)
    else:
        raise AssertionError('an empty acknowledgement must be refused')


def test_event_record_round_trip():
    for line in ('line_02', None):
        ev = Acknowledge(T0_NS + 5, line, 'console 127.0.0.1 (operator)')
        text = json.dumps(event_record(ev))
        assert parse_event_record(ev.stamp_ns, text) == ev
    assert json.loads(text)['line'] == 'all' and json.loads(text)['kind'] == 'acknowledge'


def values_of(snapshot, line):
    for st in snapshot.statuses:
        if st.name == f'catenary_monitor: {line}':
            return dict(st.values)
    raise KeyError(line)


def test_core_acknowledge_event_shows_at_once_in_diagnostics():
    config = dock_config(3)
    tensions, depth = generate(config, seconds=90.0, seed=1, dropouts=False)
    core = MonitorCore(config, T0_NS)
    events = events_of(config, tensions, depth, np.arange(T0_NS, T0_NS + 90 * S, S))
    raised = None
    for ev in events:
        step = core.step(ev)
        if (
            core.state.lines[1].ack.state == 'unacknowledged'
            and core.state.lines[1].state.level == 2
        ):
            raised = ev.stamp_ns
            break
    assert raised is not None, 'the storm must lift line_02'
    values = values_of(core.step(Tick(raised + 1)).snapshot, 'line_02')
    assert values['acknowledged'] == 'false' and values['alarm_state'] == 'unacknowledged'
    assert values['alarm_condition'] == 'uplift'
    assert float(values['alarm_raised']) == raised * 1e-9
    step = core.step(Acknowledge(raised + 2, 'line_02', 'test'))
    assert step.kind == 'acknowledge' and step.snapshot is not None
    values = values_of(step.snapshot, 'line_02')
    assert (values['acknowledged'], values['alarm_state'], values['acknowledged_by']) == (
        'true',
        'acknowledged',
        'test',
    )
    assert core.state.lines[1].state.level == Level.ERROR  # still lifted: the alarm stays
    assert not math.isnan(float(values['acknowledged_at']))
