"""Alarm texts an operator reads in a second: every status message the core can publish is a
headline of at most 100 characters (what, how much against what allowed, what to do), its full
text in ``detail``, its active conditions in ``conditions`` and its response text (cause,
consequence, action; shipped defaults, ``response_texts.<condition>`` parameters) in
``response``.

Driven through the core: storms to uplift with dropouts, stale and silent lines, a lost and a
late depth, impossible readings (1e300 N, inf, 20 x MBL, 1e6 m), elastic lines, the holding and
fatigue conditions, and every line condition's sentence at once with extreme values.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pytest
from replay_data import T0_NS, core_steps, dock_config, generate

from catenary_monitor.core.alarms.latches import CONDITIONS, AlarmInputs, LineAlarm
from catenary_monitor.core.alarms.texts import (
    ACTIONS,
    HEADLINE_LIMIT,
    TEXT_KEYS,
    headline,
    split_parts,
)
from catenary_monitor.core.config.parameters import (
    ALARM_CONDITIONS,
    COMPONENTS,
    AlarmConfig,
    LineConfig,
    MonitorConfig,
    config_from_params,
    config_hash,
    config_to_params,
    parameters_markdown,
)
from catenary_monitor.core.config.responses import DEFAULT_RESPONSES
from catenary_monitor.core.physics.result import STATUS_MESSAGES
from catenary_monitor.core.rules import sensor_state
from catenary_monitor.core.twin.window import tick_grid

ROOT = Path(__file__).resolve().parents[1]


def _ticks(tensions, depth, rate=2.0):
    starts = [c[0][0] for c in (*tensions.values(), depth) if len(c[0])]
    ends = [c[0][-1] for c in (*tensions.values(), depth) if len(c[0])]
    return tick_grid(int(min(starts)) + 123_456, int(max(ends)), rate)


def _statuses(config, tensions, depth):
    """Every status of every snapshot the core made, and its final snapshot's."""
    core, steps = core_steps(config, tensions, depth, _ticks(tensions, depth), T0_NS)
    out = [st for s in steps if s.snapshot is not None for st in s.snapshot.statuses]
    end = int(max(c[0][-1] for c in tensions.values() if len(c[0]))) + int(30e9)
    return out + list(core.snapshot(end).statuses)


def _scenes():
    """(name, config, tensions, depth): the core's conditions, each reached."""
    base = dock_config(3)
    tensions, depth = generate(base, seconds=90.0, seed=1)
    yield 'storm with dropouts', base, tensions, depth
    # impossible readings on an elastic line, an impossible depth
    lines = base.lines[:2] + (LineConfig('line_03', 1300.0, 121.06, 4827000.0, ea=6.6e8),)
    config = MonitorConfig(lines=lines, alarm=base.alarm)
    tensions, depth = generate(config, seconds=40.0, seed=8, storm_line=2)
    t, v = tensions['line_03']
    v = v.copy()
    v[40:45], v[80], v[120:123] = 1e300, math.inf, 20 * 4827000.0
    tensions['line_03'] = (t, v)
    dv = depth[1].copy()
    dv[10] = 1e6
    yield 'impossible inputs', config, tensions, (depth[0], dv)
    # a late depth, a line that never reports, the depth lost for good
    config = dock_config(3, depth_timeout=2.0)
    tensions, depth = generate(config, seconds=40.0, seed=5)
    late = (depth[0] > T0_NS + int(8e9)) & (depth[0] < T0_NS + int(30e9))
    del tensions['line_03']
    yield 'silent line and lost depth', config, tensions, (depth[0][late], depth[1][late])
    # holding (drag margin, dragging), accuracy bounds, fatigue, a tide table
    holding = tuple(
        LineConfig(
            line.name, 1300.0, line.anchor_distance, 4827000.0,
            anchor_holding=1.2e6, tension_accuracy=30e3,
        )
        for line in base.lines
    )  # fmt: skip
    alarm = AlarmConfig(
        clear_hold=3.0, warn_clear_hold=2.0, margin_clear_hold=2.0, tension_timeout=1.5,
        depth_timeout=4.0,
        fatigue_damage_warn=1e-12, tide_table='M2 0.6 0.0 28.98',
    )  # fmt: skip
    config = MonitorConfig(lines=holding, alarm=alarm)
    tensions, depth = generate(config, seconds=90.0, seed=3)
    yield 'holding, bounds, fatigue, tide table', config, tensions, depth


@pytest.fixture(scope='module')
def published():
    return {name: _statuses(c, t, d) for name, c, t, d in _scenes()}


def test_every_published_message_is_a_headline_of_at_most_100_characters(published):
    long_details = 0
    for scene, statuses in published.items():
        for st in statuses:
            values = dict(st.values)
            assert len(st.message) <= HEADLINE_LIMIT, (scene, st.name, st.message)
            assert '\n' not in st.message
            assert tuple(k for k, _ in st.values[-3:]) == TEXT_KEYS, (scene, st.name)
            detail = values['detail']
            # the headline is the detail's first part (not a cut: no '...'), its figures kept
            first = split_parts(detail)[0] if detail else ''
            assert not st.message.endswith('...'), (scene, st.name, detail)
            assert st.message.split(' ')[0] == first.split(' ')[0], (st.message, detail)
            long_details += len(detail) > HEADLINE_LIMIT
            if st.level != 0:
                assert values['response'].startswith('Cause: '), (scene, st.name)
                assert values['conditions'], (scene, st.name)
            else:
                assert values['response'] == ''
    assert long_details > 10  # not vacuous: long texts were published, as headlines


def test_the_scenes_reach_the_conditions(published):
    seen = {
        c
        for statuses in published.values()
        for st in statuses
        for c in dict(st.values).get('conditions', '').split(',')
        if c
    }
    want = {'uplift', 'input', 'stale', 'anchor_margin', 'drag_margin', 'fatigue', 'tide'}
    assert want <= seen, want - seen


def test_a_headline_keeps_the_value_and_the_limit():
    msg = (
        'anchor uplift 161.0 kN > allowed 0.0 kN at the wave peak (quasi-static 152.3 kN); '
        'anchor margin -12.40 m < 5.00 m; tide margin 1.93 m, warning held (clears after 6 s '
        'at >= 1.20 m)'
    )
    head = headline(msg, 'uplift')
    assert head == (
        'anchor uplift 161.0 kN > allowed 0.0 kN at the wave peak (+2 more): '
        'reduce load or pay out chain'
    )
    assert headline('anchor margin 3.10 m < 5.00 m', 'anchor_margin') == (
        'anchor margin 3.10 m < 5.00 m: watch tide and load'
    )
    # a part naming its own advice keeps it; OK and blind lines get no action
    assert headline('OK') == 'OK'
    blind = 'blind: no tension received yet (suppressed by design: alarm on sensors)'
    assert headline(blind, 'stale') == blind
    # '; ' inside parentheses does not split
    assert split_parts('a (b; c); d') == ['a (b; c)', 'd']


def _extreme_inputs(alarm: LineAlarm, value: float, code: int, status: int) -> AlarmInputs:
    return AlarmInputs(
        uplift_force=value, anchor_margin=-value, tide_margin=-value, load_margin=-value,
        safety_factor=-value, time_to_uplift=value, tide_rate=value / 1e6, status=status,
        status_message=STATUS_MESSAGES.get(status, ''), tension_stamp=0.0, depth_stamp=0.0,
        inconsistent=1.0, dock_residual=-value, dock_expected=value, dock_sigma=-value / 1e3,
        uplift_force_upper=2 * value, drag_margin=-value, holding_capacity=value,
        sensor_state=float(code), sensor_tension=value, mbl=value, drag_state=2.0,
        implied_anchor_distance=value, fatigue_damage=value, fatigue_life_left=value,
        dynamic_uplift=1.5 * value, uplift_view=1.0, channels_healthy=1.0,
        channel_states=6.0, span=value / 2,
    )  # fmt: skip


@pytest.mark.parametrize('value', [1.0, 123456.789, 9.87e9, 4.2e13])
def test_every_line_condition_at_once_and_alone_with_extreme_values(value):
    line = LineConfig(
        'line_99', 1300.0, 121.06, 4827000.0, tension_topics=('/a', '/b', '/c'), min_channels=2
    )
    alarm = LineAlarm.for_line(line, AlarmConfig())
    codes = (sensor_state.SLACK, sensor_state.STUCK, sensor_state.PARTED, sensor_state.BAD_STAMP)
    n = len(CONDITIONS)
    masks = [[True] * n] + [[i == j for i in range(n)] for j in range(n)]
    for active, code, status, (st, sd) in itertools.product(
        masks, codes, list(STATUS_MESSAGES)[1:], ((False, False), (True, True))
    ):
        x = _extreme_inputs(alarm, value, code, status)
        text = alarm._message(active, x, 1e9, st, sd, STATUS_MESSAGES[status])
        cond = next((c for c, up in zip(CONDITIONS, active) if up), 'stale')
        head = headline(text, cond)
        assert len(head) <= HEADLINE_LIMIT, (text, head)
        assert not head.endswith('...'), (text, head)


def test_every_depth_sentence_and_solver_sentence_is_a_headline():
    class Cfg:
        depth_min, depth_max = 10.95, 27.5

    for code in range(1, len(sensor_state.DEPTH_STATES)):
        text = sensor_state.depth_message(code, 1e300, Cfg())
        assert len(headline(text, 'tide')) <= HEADLINE_LIMIT
    for code in range(1, len(sensor_state.LINE_STATES)):
        text = sensor_state.line_message(code, 4.8e8, 4.8e7)  # up to 10 x MBL: plausible
        assert not headline(text, 'sensor_error').endswith('...'), text
    for text in STATUS_MESSAGES.values():
        assert not headline(f'impossible input: {text}', 'input').endswith('...'), text


def test_every_condition_and_component_has_a_response_text_and_a_short_action():
    names = [c for c in ALARM_CONDITIONS] + [c for c in COMPONENTS if c != 'fatigue']
    names.append('fatigue_store')
    for name in names:
        text = DEFAULT_RESPONSES[name]
        assert text.startswith('Cause: ') and ' Consequence: ' in text and ' Action: ' in text
        assert 0 < len(ACTIONS[name]) <= 35, name
    assert set(DEFAULT_RESPONSES) == set(names) == set(ACTIONS)


def test_response_texts_are_parameters_published_with_the_status():
    flat = config_to_params(dock_config(3))
    default_hash = config_hash(config_from_params(flat))
    flat['response_texts.uplift'] = 'Cause: storm. Consequence: drift. Action: call the pilot.'
    config = config_from_params(flat)
    assert config.response_texts == (('uplift', flat['response_texts.uplift']),)
    assert config_to_params(config)['response_texts.uplift'] == flat['response_texts.uplift']
    assert config_hash(config) == default_hash  # a text decides no result
    tensions, depth = generate(config, seconds=90.0, seed=1)
    statuses = _statuses(config, tensions, depth)
    uplift = [v for v in map(dict, (st.values for st in statuses))
              if v.get('alarm_condition') == 'uplift']  # fmt: skip
    assert uplift and all(v['response'] == flat['response_texts.uplift'] for v in uplift)


def test_the_response_texts_page_is_generated():
    page = (ROOT / 'docs' / 'alarm_texts.md').read_text()
    begin, end = '<!-- response-texts:begin -->\n', '<!-- response-texts:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('responses')
