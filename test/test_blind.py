"""A blind start-up and a silent depth sensor are one alarm (core, console model, batch twin).

The monitor core is fed nothing, then data, then loses its depth sensor, then one load cell:
each common cause is ONE ``sensors`` alarm (raised after its timeout, not at t = 0), every line
stays STALE meanwhile with its STALE suppressed by design (said in its message and its
``alarm_state``), and only the sensors alarm is announced; a load cell that goes silent after
it reported is its own line's alarm. The console's alarm list and history follow (no flood),
and the vectorized replay twin gives the same steps.
"""

from replay_data import T0_NS, dock_config, generate
from test_batch import compare

from catenary_monitor.console.frames import History, alarm_rows, statuses_by_name
from catenary_monitor.core.monitor.events import Acknowledge, Depth, Tension, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.twin.window import tick_grid

S = 10**9
NOTE = ' (suppressed by design: alarm on sensors)'


class Run:
    """A core of 12 lines (tension_timeout 1.5 s, depth_timeout 4 s) stepped by hand, its
    announced changes and the console's view of its snapshots."""

    def __init__(self) -> None:
        self.config = dock_config(12)
        self.core = MonitorCore(self.config, T0_NS)
        self.names = [line.name for line in self.config.lines]
        self.history = History()
        self.changes: list = []
        self.snapshot = None

    def step(self, event):
        step = self.core.step(event)
        self.changes += list(step.transitions)
        if step.snapshot is not None:
            self.snapshot = step.snapshot
            items = ((s.name, int(s.level), s.message, s.values) for s in step.snapshot.statuses)
            self.history.feed(step.stamp_ns * 1e-9, statuses_by_name(items), self.names)
        return step

    def seconds(self, lo, hi, depth=True, silent=()):
        """Samples of every line (but ``silent``) and the depth at 5 Hz, a tick each second."""
        for ms in range(int(lo * 1000), int(hi * 1000), 200):
            t = T0_NS + ms * 10**6
            if depth:
                self.step(Depth(t + 1, 20.85 + 0.01 * (ms % 3000) / 1000))
            for k in range(12):
                if self.names[k] not in silent:
                    self.step(Tension(t + 2 + k, k, 372e3 + 2000.0 * ((ms // 200) % 5)))
            if ms % 1000 == 0:
                self.step(Tick(t + 100))

    def announced(self):
        """(component, old, new) of the changes not suppressed by design (the ALARM lines)."""
        out = [
            (c.component, c.transition.old.name, c.transition.new.name)
            for c in self.changes
            if not c.transition.suppressed
        ]
        self.changes = []
        return out

    def statuses(self):
        return {st.name.split(': ')[1]: st for st in self.snapshot.statuses}

    def rows(self):
        items = ((s.name, int(s.level), s.message, s.values) for s in self.snapshot.statuses)
        return [(r['line'], r['state']) for r in alarm_rows(statuses_by_name(items), self.names)]


def test_a_blind_start_up_is_one_alarm_raised_after_the_timeout():
    run = Run()
    run.step(Tick(T0_NS + S))  # 1 s: within tension_timeout, no alarm at all
    assert run.announced() == [] and run.rows() == []
    sensors = run.statuses()['sensors']
    assert (sensors.level.name, dict(sensors.values)['detail']) == (
        'OK',
        'starting: no tension from all 12 lines and no depth yet (an alarm if still silent '
        '1.5 s after start for tensions, 4 s for the depth)',
    )
    for t in range(2, 10):
        run.step(Tick(T0_NS + t * S))
    assert run.announced() == [('sensors', 'OK', 'STALE')]
    statuses = run.statuses()
    sensors = statuses['sensors']
    assert dict(sensors.values)['detail'] == (
        'waiting for sensors: no tension from all 12 lines within 1.5 s of start, '
        'no depth within 4 s: all 12 lines blind'
    )
    values = dict(sensors.values)
    assert (values['alarm_state'], values['lines_waiting']) == ('unacknowledged', '12')
    for name in run.names:  # every line STALE, never OK blind, suppressed by design
        line = statuses[name]
        assert line.level.name == 'STALE'
        assert line.message == 'blind: no tension received yet; no depth received yet' + NOTE
        assert dict(line.values)['alarm_state'] == 'suppressed'
    tide = statuses['tide']
    assert (tide.level.name, dict(tide.values)['sensor_state']) == ('STALE', 'no_data')
    # The console: one row, one raise in the history (EEMUA 191: a flood is 10 in 10 min).
    assert run.rows() == [('sensors', 'unacknowledged')]
    assert [(e['line'], e['event']) for e in run.history.entries] == [('sensors', 'raised')]
    # Data: every line OK, no line announces its return, the sensors alarm returns.
    run.seconds(10.0, 13.0)
    statuses = run.statuses()
    assert {statuses[name].level.name for name in run.names} == {'OK'}
    assert dict(statuses['tide'].values)['sensor_state'] == 'ok'
    assert run.announced() == [('sensors', 'STALE', 'OK')]
    assert run.rows() == [('sensors', 'returned-unacknowledged')]
    run.step(Acknowledge(T0_NS + 13 * S + 500, 'sensors', 'test'))
    assert run.rows() == []
    raised = [e for e in run.history.entries if e['event'].startswith('raised')]
    assert len(raised) == 1


def test_a_silent_depth_sensor_is_one_alarm_and_a_silent_load_cell_its_own():
    run = Run()
    run.seconds(0.0, 10.0)
    run.announced()
    assert run.statuses()['sensors'].message == 'every sensor reporting'
    run.seconds(10.0, 16.0, depth=False)  # the depth goes silent past its 4 s timeout
    assert run.announced() == [('sensors', 'OK', 'STALE')]
    statuses = run.statuses()
    assert statuses['sensors'].message.startswith(
        'depth sensor silent: all 12 lines blind (last depth '
    )
    for name in run.names:
        line = statuses[name]
        assert line.level.name == 'STALE'
        assert line.message.startswith('blind: depth stale: last sample') and NOTE in line.message
    assert statuses['tide'].level.name == 'STALE'
    assert run.rows() == [('sensors', 'unacknowledged')]
    run.seconds(16.0, 18.0)
    assert run.announced() == [('sensors', 'STALE', 'OK')]
    # One load cell goes silent after it reported: its own alarm, announced; not the sensors'.
    run.seconds(18.0, 24.0, silent=('line_05',))
    assert run.announced() == [('line_05', 'OK', 'STALE')]
    statuses = run.statuses()
    assert statuses['line_05'].message.startswith('tension stale: last sample')
    assert statuses['sensors'].level.name == 'OK'
    assert ('line_05', 'unacknowledged') in run.rows()


def test_the_replay_twin_recomputes_a_blind_start_and_a_silent_depth():
    """Nothing for 6 s, then a storm with a 6 s depth gap (4 s timeout) and a line that never
    reports: the batch twin's outputs, transitions (suppressed flags too), snapshots and state
    equal the core's, event by event."""
    config = dock_config(3)
    tensions, depth = generate(config, seconds=60.0, seed=9)
    shift = 6 * S
    tensions = {k: (t + shift, v) for k, (t, v) in tensions.items() if k != 'line_03'}
    depth = (depth[0] + shift, depth[1])
    last = max(int(t[-1]) for t, _ in (*tensions.values(), depth))
    ticks = tick_grid(T0_NS + 123_456, last, 2.0)
    steps = compare(config, tensions, depth, ticks, cuts=[T0_NS + 3 * S, T0_NS + 40 * S])
    announced = [
        (c.component, c.transition.new.name, c.transition.message)
        for s in steps
        for c in s.transitions
        if not c.transition.suppressed
    ]
    waiting = [a for a in announced if a[0] == 'sensors' and a[1] == 'STALE']
    assert waiting and waiting[0][2].startswith('waiting for sensors: no tension from all 3')
    assert not any(a[0] == 'line_03' for a in announced)
    silent = [
        dict(st.values)['detail']
        for s in steps
        if s.snapshot is not None
        for st in s.snapshot.statuses
        if st.name == 'catenary_monitor: sensors'
        and 'depth sensor silent' in dict(st.values)['detail']
    ]
    assert silent and silent[0].startswith('waiting for sensors: no tension from line_03')
