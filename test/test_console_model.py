"""The console's model (no browser, no ROS): frames, alarm rows, history, trends, the layout."""

import json
import math
from pathlib import Path

import numpy as np

from catenary_monitor.console.foxglove import layout
from catenary_monitor.console.frames import (
    History,
    Status,
    Trend,
    alarm_rows,
    bucket,
    build_frame,
    console_config,
    statuses_by_name,
    tide_trend,
)
from catenary_monitor.core.config.parameters import config_from_params, load_params_file

ROOT = Path(__file__).resolve().parents[1]


def st(level, state, raised=100.0, message='m', **values):
    v = {'alarm_state': state, 'alarm_raised': repr(raised), 'alarm_condition': 'uplift'}
    v.update(values)
    return Status(level, message, v)


def test_alarm_rows_most_urgent_first_and_normal_left_out():
    statuses = {
        'a': st('WARN', 'unacknowledged', 50.0),
        'b': st('ERROR', 'acknowledged', 60.0),
        'c': st('OK', 'returned-unacknowledged', 40.0),
        'd': st('ERROR', 'unacknowledged', 30.0),
        'e': st('OK', 'normal'),
    }
    rows = alarm_rows(statuses, list('abcde'))
    assert [r['line'] for r in rows] == ['d', 'a', 'c', 'b']
    assert rows[0]['raised'] == 30.0 and rows[0]['condition'] == 'uplift'


def test_history_records_the_audit_trail():
    h = History()
    seq = [
        (1.0, st('OK', 'normal', math.nan)),
        (2.0, st('WARN', 'unacknowledged', 2.0)),
        (3.0, st('ERROR', 'unacknowledged', 3.0)),
        (4.0, st('ERROR', 'acknowledged', 3.0, acknowledged_by='op', acknowledged_at='3.5')),
        (5.0, st('OK', 'normal', 3.0)),
        (6.0, st('WARN', 'unacknowledged', 6.0)),
        (7.0, st('OK', 'returned-unacknowledged', 6.0)),
        (8.0, st('OK', 'normal', 6.0, acknowledged_by='op2', acknowledged_at='7.9')),
    ]
    for t, s in seq:
        h.feed(t, {'x': s}, ['x'])
    events = [(e['time'], e['event'], e['by']) for e in h.entries]
    assert events == [
        (2.0, 'raised', ''),
        (3.0, 'raised again', ''),
        (3.5, 'acknowledged', 'op'),
        (5.0, 'cleared', ''),
        (6.0, 'raised', ''),
        (7.0, 'returned to normal (unacknowledged)', ''),
        (7.9, 'acknowledged', 'op2'),
    ]


def test_bucket_keeps_every_peak():
    t = np.linspace(0.0, 100.0, 10001)
    v = np.sin(t)
    v[5000] = 9.0
    out = bucket(t, {'v_max': v, 'w_min': -v}, 0.0, 100.0, n=50)
    assert len(out['t']) == 50 and max(out['v_max']) == 9.0 and min(out['w_min']) == -9.0
    empty = bucket(t, {'v_max': v}, 200.0, 300.0)
    assert empty == {'t': [], 'v_max': []}


def test_live_trend_buckets_and_forgets():
    tr = Trend(('a_max', 'b_min'), keep_s=100.0, resolution=1.0)
    for k in range(1000):
        tr.add(k * 0.5, {'a_max': float(k), 'b_min': float(-k)})
    assert tr.t[-1] == 499.5 and len(tr.t) <= 161
    s = tr.series(400.0, 500.0)
    assert s['a_max'][-1] == 999.0 and s['b_min'][-1] == -999.0


def test_tide_trend_is_the_monitors():
    def statuses(rate):
        return statuses_by_name([('catenary_monitor: tide', 0, 'ok', {'rate': rate})])

    out = tide_trend(statuses(repr(0.5 / 3600.0)))
    assert out['trend'] == 'rising' and abs(out['rate_m_per_h'] - 0.5) < 1e-9
    assert tide_trend(statuses('-0.0001'))['trend'] == 'falling'
    assert tide_trend(statuses('nan'))['trend'] == 'unknown'
    assert tide_trend({})['trend'] == 'unknown'


def test_frame_says_lost_after_the_silence_limit():
    kw = dict(outputs={}, sample_t={}, depth=None, history=[], silence_limit_s=3.0)
    assert build_frame(10.0, ['x'], 8.0, {}, **kw)['connection'] == 'ok'
    assert build_frame(10.0, ['x'], 6.5, {}, **kw)['connection'] == 'lost'
    assert build_frame(10.0, ['x'], None, {}, started=9.0, **kw)['connection'] == 'waiting'
    assert build_frame(10.0, ['x'], None, {}, started=5.0, **kw)['connection'] == 'lost'


def test_shipped_foxglove_layout_is_the_generated_one():
    config = config_from_params(load_params_file(ROOT / 'config' / 'floating_dock.yaml'))
    shipped = json.loads((ROOT / 'foxglove' / 'catenary_monitor.json').read_text())
    assert shipped == layout(config)
    paths = [p['value'] for p in shipped['configById']['StateTransitions!cm4']['paths']]
    assert len(paths) == 12 and paths[10].endswith('{name=="catenary_monitor: line_11"}.level')


def test_page_config_places_hooks_where_the_params_file_puts_them():
    """The plan draws each chain from its hook (hook_x, hook_y) along its heading."""
    config = config_from_params(load_params_file(str(ROOT / 'config' / 'floating_dock.yaml')))
    page = console_config(config, [], 'live')
    by_name = {line['name']: line for line in page['lines']}
    assert (by_name['line_01']['hook_x'], by_name['line_01']['hook_y']) == (110.0, -25.5)
    assert by_name['line_01']['heading'] == 45.0
    assert page['dock_length'] == 246.4 and page['dock_beam'] == 51.0
    bare = console_config(None, ['a', 'b'], 'live')
    assert bare['lines'][0]['hook_x'] is None and bare['dock_length'] is None


def test_frame_shows_the_monitors_own_statuses():
    """The clock watchdog, intake and runtime-change statuses reach the page beside the logger
    (in the monitor's order), so a stopped clock or an overloaded node is on screen."""
    statuses = {
        'clock': Status('ERROR', 'ROS clock stopped: /clock not advancing for 12 s', {}),
        'logger': Status('OK', 'writing', {}),
        'line_01': st('OK', 'normal'),
        'intake': Status('WARN', 'node cannot keep up', {}),
    }
    kw = dict(outputs={}, sample_t={}, depth=None, history=[], silence_limit_s=3.0)
    frame = build_frame(10.0, ['line_01'], 9.5, statuses, **kw)
    assert [(r['name'], r['level']) for r in frame['monitor']] == [
        ('logger', 'OK'),
        ('clock', 'ERROR'),
        ('intake', 'WARN'),
    ]
    assert frame['monitor'][1]['message'].startswith('ROS clock stopped')


def test_tiles_carry_the_sensor_state():
    """The core's sensor_state word reaches the tile (ok when the monitor gives none)."""
    kw = dict(outputs={}, sample_t={}, depth=None, history=[], silence_limit_s=3.0)
    statuses = {'a': st('WARN', 'normal', sensor_state='stuck'), 'b': st('OK', 'normal')}
    frame = build_frame(10.0, ['a', 'b'], 9.5, statuses, **kw)
    assert [line['sensor_state'] for line in frame['lines']] == ['stuck', 'ok']


def _frame(statuses, lines=('line_01',)):
    kw = dict(outputs={}, sample_t={}, depth=None, history=[], silence_limit_s=3.0)
    return build_frame(10.0, list(lines), 9.5, statuses, **kw)


def test_a_normal_day_lists_no_component():
    """Every component OK (and the flood status, the sensors alarm normal): no row."""
    statuses = {
        name: Status('OK', 'ok', {'alarm_state': 'normal'} if name in ('tide', 'dock') else {})
        for name in ('tide', 'intake', 'logger', 'fatigue', 'dock', 'clock', 'parameters')
    }
    statuses['line_01'] = st('OK', 'normal')
    statuses['sensors'] = st('OK', 'normal')
    statuses['alarms'] = Status('OK', 'no flood', {'flood': 'false'})
    assert _frame(statuses)['alarms'] == []


def test_component_statuses_not_ok_are_listed_active_by_level():
    """The tide's impossible depth (ERROR), the fatigue store, the dock, the intake, the logger,
    the clock and the parameters are rows of kind ``component``, state ``active`` (not
    acknowledgeable), ERROR before STALE before WARN, each after the unacknowledged line alarms
    of its level; the lines' rows keep their fields and say ``kind``."""
    statuses = {
        'line_01': st('ERROR', 'unacknowledged', 5.0),
        'line_02': st('WARN', 'acknowledged', 4.0),
        'sensors': st('WARN', 'unacknowledged', 3.0),
        'tide': Status(
            'ERROR',
            'depth 0.300 m impossible: outside the chart 18.0-26.0 m',
            {
                'alarm_state': 'active',
                'conditions': 'tide',
                'detail': 'depth 0.300 m impossible: outside the chart 18.0-26.0 m (depth_min)',
                'response': 'Cause: the depth gauge ...',
            },
        ),
        'intake': Status('WARN', 'node cannot keep up', {}),
        'fatigue': Status('WARN', 'fatigue store not written', {'conditions': 'fatigue_store'}),
        'logger': Status('STALE', 'not writing', {}),
        'dock': Status('WARN', 'dock estimate off', {'alarm_state': 'active'}),
    }
    rows = _frame(statuses, ['line_01', 'line_02'])['alarms']
    order = [(r['line'], r['kind'], r['state'], r['level']) for r in rows]
    assert order == [
        ('line_01', 'line', 'unacknowledged', 'ERROR'),
        ('tide', 'component', 'active', 'ERROR'),
        ('logger', 'component', 'active', 'STALE'),
        ('sensors', 'sensors', 'unacknowledged', 'WARN'),
        ('intake', 'component', 'active', 'WARN'),
        ('fatigue', 'component', 'active', 'WARN'),
        ('dock', 'component', 'active', 'WARN'),
        ('line_02', 'line', 'acknowledged', 'WARN'),
    ]
    tide = rows[1]
    assert tide['condition'] == 'tide' and tide['response'].startswith('Cause:')
    assert tide['detail'].endswith('(depth_min)') and tide['raised'] is None
    assert rows[5]['condition'] == 'fatigue_store' and rows[4]['condition'] == 'intake'
    assert set(rows[0]) == set(tide)  # the same fields on every row


def test_a_suppressed_stale_tide_is_not_listed_twice():
    """The tide STALE under the sensors alarm (alarm_state suppressed) is the sensors' row
    only; the harbour's list (alarm_rows without components) is the lines' and sensors'."""
    statuses = {
        'line_01': st('STALE', 'suppressed'),
        'sensors': st('STALE', 'unacknowledged', 7.0),
        'tide': Status('STALE', 'depth silent', {'alarm_state': 'suppressed'}),
        'dock': Status('STALE', 'no estimate', {'alarm_state': 'suppressed'}),
        'intake': Status('WARN', 'node cannot keep up', {}),
    }
    rows = _frame(statuses)['alarms']
    assert [(r['line'], r['kind']) for r in rows] == [
        ('sensors', 'sensors'),
        ('intake', 'component'),
    ]
    assert [r['line'] for r in alarm_rows(statuses, ['line_01'])] == ['sensors']


def test_history_records_a_component_raised_and_cleared_and_dates_its_row():
    """A component status listed as an alarm enters the history (raised, raised again when its
    level rises, cleared when OK or suppressed again); its row's time raised is when the
    console saw it leave OK."""
    h = History()
    seq = [
        (1.0, Status('OK', 'depth 21.9 m', {'alarm_state': 'normal'})),
        (2.0, Status('WARN', 'depth sensor stuck', {'alarm_state': 'active'})),
        (3.0, Status('ERROR', 'depth 0.300 m impossible', {'alarm_state': 'active'})),
        (4.0, Status('WARN', 'depth sensor stuck', {'alarm_state': 'active'})),
        (5.0, Status('STALE', 'depth silent', {'alarm_state': 'suppressed'})),
        (6.0, Status('ERROR', 'depth 0.300 m impossible', {'alarm_state': 'active'})),
    ]
    for t, s in seq:
        h.feed(t, {'tide': s, 'line_01': st('OK', 'normal')}, ['line_01'])
    events = [(e['time'], e['line'], e['event'], e['level']) for e in h.entries]
    assert events == [
        (2.0, 'tide', 'raised', 'WARN'),
        (3.0, 'tide', 'raised again', 'ERROR'),
        (5.0, 'tide', 'cleared', 'STALE'),
        (6.0, 'tide', 'raised', 'ERROR'),
    ]
    frame = _frame({'tide': seq[-1][1]})
    assert frame['alarms'][0]['raised'] is None  # no history given: not known
    kw = dict(outputs={}, sample_t={}, depth=None, history=h.entries, silence_limit_s=3.0)
    frame = build_frame(10.0, ['line_01'], 9.5, {'tide': seq[-1][1]}, **kw)
    assert frame['alarms'][0]['raised'] == 6.0


def test_the_cores_impossible_depth_is_an_error_row_and_nothing_before_it():
    """The monitor core's own statuses (3 lines, a gauge stepping to 0.3 m at half time, the
    chart 15-30 m): no component row before the step; after it the tide's ERROR "impossible
    depth" is a component row, unacknowledged (raised when the monitor says); the tide's STALE
    under the sensors alarm (the gauge then silent to the core's rules) is never a row of its
    own: only the ERROR's, returned unacknowledged, until an operator acknowledges it."""
    from replay_data import T0_NS, core_steps, dock_config, generate

    from catenary_monitor.core.twin.window import tick_grid

    config = dock_config(3, depth_min=15.0, depth_max=30.0)
    tensions, depth = generate(config, seconds=40.0, seed=2)
    values = depth[1].copy()
    values[len(values) // 2 :] = 0.3
    step = depth[0][len(values) // 2] * 1e-9
    inputs = [c[0] for c in (*tensions.values(), depth)]
    start, end = int(min(c[0] for c in inputs)), int(max(c[-1] for c in inputs))
    ticks = tick_grid(start + 123_456, end, 2.0)
    _, steps = core_steps(config, tensions, (depth[0], values), ticks, T0_NS)
    names = [line.name for line in config.lines]
    history = History()
    seen = []
    for snap in (s.snapshot for s in steps if s.snapshot is not None):
        statuses = statuses_by_name(
            (c.name, int(c.level), c.message, c.values) for c in snap.statuses
        )
        t = snap.stamp_ns * 1e-9
        history.feed(t, statuses, names)
        frame = build_frame(t, names, t, statuses, {}, {}, None, history.entries, 3.0)
        rows = [r for r in frame['alarms'] if r['kind'] == 'component']
        seen.append((t, statuses['tide'].level, rows))
    assert all(not rows for t, _, rows in seen if t < step)
    after = [rows for t, _, rows in seen if t >= step and rows]
    first = after[0][0]
    assert (first['line'], first['level'], first['state']) == ('tide', 'ERROR', 'unacknowledged')
    assert first['message'].startswith('impossible depth 0.30 m') and first['raised'] >= step
    assert first['response'] and first['condition'] == 'tide'
    stale = [r['state'] for _, level, rows in seen if level == 'STALE' for r in rows]
    assert set(stale) <= {'returned-unacknowledged'}
