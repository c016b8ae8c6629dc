"""Component statuses (tide, logger, ...) acknowledged as alarms (core/alarms/components.py),
through the monitor core, and the vectorized twin equal to it on an impossible depth."""

import numpy as np
from replay_data import T0_NS, dock_config, generate
from test_batch import compare

from catenary_monitor.core.alarms import components
from catenary_monitor.core.monitor.events import Acknowledge, Depth, LoggerHealth, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.rules.level import Level

S = 10**9


def tide_of(step):
    """The tide's alarm keys in a step's snapshot."""
    st = next(s for s in step.snapshot.statuses if s.name == 'catenary_monitor: tide')
    return st.level, {k: v for k, v in st.values if k in components.KEYS}


class Run:
    """A core of 3 lines fed a depth (no tensions) and ticks, one a second."""

    def __init__(self):
        self.core = MonitorCore(dock_config(3), T0_NS)
        self.t = T0_NS
        self.log = []

    def seconds(self, n, depth):
        step = None
        for _ in range(n):
            self.t += S
            self.log += self.core.step(Depth(self.t, depth)).alarm_events
            step = self.core.step(Tick(self.t + 1))
            self.log += step.alarm_events
        return tide_of(step)

    def ack(self, name):
        self.t += S
        step = self.core.step(Acknowledge(self.t, name, 'op', 'gid 1'))
        self.log += step.alarm_events
        return step


def test_a_tide_error_is_acknowledged_clears_and_re_alarms():
    run = Run()
    level, keys = run.seconds(3, 20.85)
    assert level == Level.OK and keys['alarm_state'] == 'normal'
    level, keys = run.seconds(2, -1.0)  # an impossible depth
    assert level == Level.ERROR
    assert (keys['alarm_state'], keys['acknowledged']) == ('unacknowledged', 'false')
    raised = float(keys['alarm_raised'])
    step = run.ack('tide')
    level, keys = tide_of(step)
    assert (keys['alarm_state'], keys['acknowledged']) == ('acknowledged', 'true')
    assert (keys['acknowledged_by'], keys['acknowledged_publisher']) == ('op', 'gid 1')
    assert [(e.alarm, e.kind, e.value) for e in step.alarm_events] == [
        ('tide', 'acknowledged', raised)
    ]
    level, keys = run.seconds(2, -1.0)
    assert keys['alarm_state'] == 'acknowledged'  # an acknowledgement never clears it
    level, keys = run.seconds(3, 20.85)  # the spike's WARN after it: no news
    assert (level, keys['alarm_state']) == (Level.WARN, 'acknowledged')
    level, keys = run.seconds(35, 20.85)  # acknowledged, then normal: cleared
    assert level == Level.OK and keys['alarm_state'] == 'normal'
    assert keys['alarm_raised'] == 'nan'
    level, keys = run.seconds(1, -1.0)  # re-alarms: unacknowledged again
    assert (keys['alarm_state'], float(keys['alarm_raised'])) == ('unacknowledged', run.t * 1e-9)
    level, keys = run.seconds(35, 20.85)  # returned before anyone acknowledged it
    assert (level, keys['alarm_state'], keys['acknowledged']) == (
        Level.OK, 'returned-unacknowledged', 'false'
    )
    level, keys = tide_of(run.ack(None))  # "all" covers the components
    assert keys['alarm_state'] == 'normal'
    kinds = [e.kind for e in run.log if e.alarm == 'tide']
    assert kinds.count('raised') == 2 and kinds.count('acknowledged') == 2


def test_blind_start_is_suppressed_and_logger_is_acknowledgeable():
    run = Run()
    step = run.core.step(Tick(T0_NS + S // 2))
    level, keys = tide_of(step)
    assert (level, keys['alarm_state'], keys['acknowledged']) == (
        Level.STALE, 'suppressed', 'true'
    )
    step = run.core.step(LoggerHealth(T0_NS + S, 'disk full', '/tmp/x.mcap'))
    logger = dict(next(s for s in step.snapshot.statuses if s.name.endswith(': logger')).values)
    assert logger['alarm_state'] == 'unacknowledged'
    step = run.core.step(Acknowledge(T0_NS + 2 * S, 'logger', 'op'))
    logger = dict(next(s for s in step.snapshot.statuses if s.name.endswith(': logger')).values)
    assert logger['alarm_state'] == 'acknowledged'
    step = run.core.step(Acknowledge(T0_NS + 3 * S, 'nonsense', 'op'))
    assert step.kind == 'refused' and 'logger' in step.note


def test_the_twin_follows_the_tide_alarm_as_the_core():
    config = dock_config(3)
    tensions, (dt, dv) = generate(config, seconds=60.0, seed=3, dropouts=False)
    s = (dt - T0_NS) * 1e-9
    dv = np.where((s > 20) & (s < 25) | (s > 40) & (s < 43), -1.0, dv)  # impossible twice
    ticks = np.arange(T0_NS + S // 3, T0_NS + 60 * S, S)
    steps = compare(config, tensions, (dt, dv), ticks, cuts=(T0_NS + 22 * S, T0_NS + 41 * S))
    tide = [c.transition.new for s in steps for c in s.transitions if c.component == 'tide']
    assert tide.count(Level.ERROR) == 2


def test_a_flag_expiring_between_events_shows_returned():
    """The runtime-change flag's WARN expires at a time, not at an event: its alarm shows
    returned (unacknowledged), or normal once acknowledged."""
    from catenary_monitor.core.alarms import acknowledge

    ack = components.follow(acknowledge.AckState(), 'parameters', Level.WARN, 1.0)
    assert dict(components.values(ack, 'parameters', Level.WARN))['alarm_state'] == (
        'unacknowledged'
    )
    shown = dict(components.values(ack, 'parameters', Level.OK))
    assert (shown['alarm_state'], shown['acknowledged']) == ('returned-unacknowledged', 'false')
    ack = acknowledge.acknowledge(ack, 2.0, 'op')
    assert dict(components.values(ack, 'parameters', Level.OK))['alarm_state'] == 'normal'
