"""One cause, one alarm: inputs that fall silent together raise the one ``sensors`` alarm (their
own STALE suppressed by design), a lone silent line its own STALE; a flood's first out is an
alarm still active. The core's decisions, and its vectorized twin's equal to them (the core is
the oracle, test_batch's ``compare``)."""

import math

import numpy as np
from replay_data import T0_NS, core_steps, dock_config, generate
from test_batch import compare, ticks_for

from catenary_monitor.core.alarms import flood as alarm_flood
from catenary_monitor.core.alarms.latches import SUPPRESSED_NOTE
from catenary_monitor.core.rules.health import (
    clock_time,
    common_cause,
    common_cause_groups,
    sensors_status,
    silent_groups,
)
from catenary_monitor.core.rules.level import Level


def _cut(column, lo, hi):
    """The column without its samples in [lo, hi) s after T0."""
    t, v = column
    s = (t - T0_NS) * 1e-9
    keep = (s < lo) | (s >= hi)
    return t[keep], v[keep]


def test_silent_inputs_are_grouped_by_their_last_samples():
    last = np.array([10.0, 10.01, 10.4, 30.0, 9.9, 11.5])
    groups = silent_groups(last, np.array([1, 1, 1, 1, 1, 1], bool), 1.0)
    assert groups == [[4, 0, 1, 2], [5], [3]]  # 11.5 is 1.6 s after the first: its own
    assert silent_groups(last, np.zeros(6, bool), 1.0) == []


def test_common_cause_flags_stay_until_the_input_reports_again():
    names = ['line_01', 'line_02', 'line_03', 'depth']
    timeout = np.array([5.0, 5.0, 5.0, 60.0])
    last = np.array(
        [
            [10.0, 10.02, 30.0, 29.0],  # t = 16: two lines silent together
            [10.0, 40.00, 30.0, 39.0],  # t = 41: line_02 back, line_01 still silent
            [10.0, 40.00, 30.0, 39.0],  # t = 46: line_03 silent alone (not grouped)
            [45.0, 40.00, 30.0, 45.0],  # t = 47: line_01 back
        ]
    )
    now = np.array([16.0, 41.0, 46.0, 47.0])
    got = common_cause(last, now, timeout, 1.0, [False] * 4)
    assert got.tolist() == [
        [True, True, False, False],
        [True, False, False, False],  # still under the cause it fell silent with
        [True, False, False, False],
        [False, False, False, False],
    ]
    # row by row from the flags before: the same (the core decides one tick at a time)
    flags = [False] * 4
    for i in range(len(now)):
        flags = common_cause(last[i : i + 1], now[i : i + 1], timeout, 1.0, flags)[0].tolist()
        assert flags == got[i].tolist()
    causes = common_cause_groups(names, last[0], got[0], 1.0)
    assert causes == ((('line_01', 'line_02'), 10.0),)
    assert not np.isnan(last).any()
    assert not common_cause(np.array([[math.nan] * 4]), np.array([99.0]), timeout, 1.0,
                            [False] * 4).any()  # fmt: skip


def test_the_sensors_alarm_names_what_went_silent_and_since_when():
    names = [f'line_{k:02d}' for k in range(1, 13)]
    t0 = 1_764_979_200.0 + 8 * 3600 + 10 * 60 + 3.25  # a day at 08:10:03.25 UTC
    assert clock_time(t0) == '08:10:03.2'
    causes = ((tuple(names[:9]), t0),)
    level, text = sensors_status([], 12, t0, False, t0 + 6, 0.0, 5.0, 60.0, causes, names)
    assert level == Level.STALE
    assert text == (
        'load cells silent: 9 lines (line_01..line_09) since 08:10:03.2: gateway, network or '
        'power'
    )
    with_depth = ((tuple(names) + ('depth',), t0),)
    level, text = sensors_status([], 12, t0, True, t0 + 61, 0.0, 5.0, 60.0, with_depth, names)
    assert text.startswith('depth gauge and 12 load cells silent: 12 lines (line_01..line_12)')
    assert text.endswith('; every line blind') and 'depth sensor silent' not in text
    assert sensors_status([], 12, t0, False, t0 + 6, 0.0, 5.0, 60.0, (), names)[0] == Level.OK


def test_a_flood_names_the_first_alarm_still_active():
    recent = ((1.0, 'sensors'), (5.0, 'line_03'), (6.0, 'line_01'))
    assert alarm_flood.first_out(recent, {'line_03', 'line_01'}) == ('line_03', 5.0)
    assert alarm_flood.first_out(recent, set()) == ('', math.nan) or math.isnan(
        alarm_flood.first_out(recent, set())[1]
    )


def _gateway_scene(n_lines=5, seconds=90.0):
    """Every line silent 30-45 s (one gateway), line_04 alone 60-72 s, the depth in order."""
    config = dock_config(n_lines, tension_timeout=1.5, depth_timeout=4.0)
    tensions, depth = generate(config, seconds=seconds, seed=11, dropouts=False)
    for k, line in enumerate(config.lines):
        tensions[line.name] = _cut(tensions[line.name], 30.0, 45.0)
        if k == 3:
            tensions[line.name] = _cut(tensions[line.name], 60.0, 72.0)
    return config, tensions, depth


def _raised(steps):
    return [(round(e.time - T0_NS * 1e-9, 1), e.alarm, e.level)
            for s in steps for e in s.alarm_events if e.kind == 'raised']  # fmt: skip


def test_a_gateway_drop_is_one_alarm_and_a_lone_line_its_own():
    config, tensions, depth = _gateway_scene()
    ticks = ticks_for(tensions, depth)
    core, steps = core_steps(config, tensions, depth, ticks, T0_NS)
    raised = [r for r in _raised(steps) if 20.0 < r[0]]
    gateway = [r for r in raised if r[0] < 50.0]
    # the storm line's own alarms aside, the silence is the sensors' one raise
    silent = [r for r in gateway if r[2] == 'STALE']
    assert [r[1] for r in silent] == ['sensors'], raised
    texts = [c.transition.message for s in steps for c in s.transitions
             if c.component == 'sensors' and c.transition.new == Level.STALE]  # fmt: skip
    assert any(t.startswith('load cells silent: 5 lines (line_01..line_05) since ') for t in texts)
    lone = [r for r in raised if 60.0 < r[0] < 75.0 and r[2] == 'STALE']
    assert [r[1] for r in lone] == ['line_04']
    # its own STALE a common_cause_window after its timeout: 60 + 1.5 + 1 s
    assert 62.4 < lone[0][0] < 63.8
    # every line's STALE in the drop was shown suppressed
    shown = [(st.level, dict(st.values)['detail']) for s in steps if s.snapshot is not None
             and 37.0 < s.stamp_ns * 1e-9 - T0_NS * 1e-9 < 44.0
             for st in s.snapshot.statuses if st.name.endswith('line_01')]  # fmt: skip
    assert shown and {level for level, _ in shown} == {Level.STALE}
    assert all(text.endswith(SUPPRESSED_NOTE) for _, text in shown), shown[0]


def test_the_twin_decides_the_common_cause_as_the_core(tmp_path):
    config, tensions, depth = _gateway_scene()
    ticks = ticks_for(tensions, depth)
    cuts = [T0_NS + int(s * 1e9) for s in (31.7, 36.0, 44.9, 61.0, 63.05)]
    compare(config, tensions, depth, ticks, cuts)


def test_the_depth_with_the_lines_is_one_cause_and_the_twin_agrees():
    config = dock_config(4, tension_timeout=1.5, depth_timeout=4.0)
    tensions, depth = generate(config, seconds=60.0, seed=12, dropouts=False)
    for line in config.lines:
        tensions[line.name] = _cut(tensions[line.name], 20.0, 35.0)
    depth = _cut(depth, 20.0, 35.0)
    ticks = ticks_for(tensions, depth)
    steps = compare(config, tensions, depth, ticks, [T0_NS + int(25.5e9)])
    texts = [c.transition.message for s in steps for c in s.transitions
             if c.component == 'sensors']  # fmt: skip
    assert [r[1] for r in _raised(steps) if 20.0 < r[0] < 40.0 and r[2] == 'STALE'] == [
        'sensors'
    ]
    assert texts  # the depth joins the group once its own timeout passed
    final = [s.snapshot for s in steps if s.snapshot is not None
             and 26.0 < s.stamp_ns * 1e-9 - T0_NS * 1e-9 < 34.0]  # fmt: skip
    words = {st.message for sn in final for st in sn.statuses if st.name.endswith('sensors')}
    assert any(w.startswith('depth gauge and 4 load cells silent') for w in words), words


def test_a_flood_first_out_is_active_in_core_and_twin():
    """A flood (flood_count 2) begun by a storm line's alarms while a returned one is in the
    window: the first out is an active alarm, the same in the twin."""
    config = dock_config(4, flood_count=2.0)
    tensions, depth = generate(config, seconds=90.0, seed=3)
    ticks = ticks_for(tensions, depth)
    steps = compare(config, tensions, depth, ticks, [T0_NS + int(40e9)])
    floods = [e for s in steps for e in s.alarm_events if e.kind == 'flood']
    assert floods
    for f in floods:
        assert f.by  # an alarm still active names it


def test_a_line_disagreeing_under_the_common_cause_is_shown_not_its_alarm():
    """The dock estimate's disagreement while the sensors alarm stands (two load cells silent
    together) is its consequence: the line's ``inconsistent`` condition holds (neither raised
    nor cleared) meanwhile; the dock status shows the residuals. The twin agrees."""
    from dock_data import dock_config as body_config
    from dock_data import generate_dock

    config = body_config(tension_timeout=2.0)
    tensions, depth = generate_dock(
        config, 120.0, drifting=8, drift_from=0.1, drift_to=0.3, seed=5
    )
    for name in ('line_01', 'line_02'):
        tensions[name] = _cut(tensions[name], 5.0, 70.0)
    ticks = ticks_for(tensions, depth)
    steps = compare(config, tensions, depth, ticks, [T0_NS + int(s * 1e9) for s in (9.5, 40.0)])
    seen = []
    for s in steps:
        if s.snapshot is None:
            continue
        st = {x.name.split(': ')[-1]: x for x in s.snapshot.statuses}
        stands = st['sensors'].level != Level.OK
        seen.append((stands, 'tension inconsistent' in dict(st['line_09'].values)['detail']))
    assert any(stands for stands, _ in seen)
    # never newly flagged while the cause stands; flagged once the lines are back
    first = [i for i, (stands, flagged) in enumerate(seen) if flagged]
    assert first and not seen[first[0]][0]
