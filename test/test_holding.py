"""Holding (core/rules/holding.py) through the monitor core: seed 001's rule, Hou et al. 2005's
table (w = 25 kgf/m, dm = 11 m, anchor 2500 kgf; consistent units kgf and m), a sinker's
holding under uplift, a dragged anchor seen in implied_anchor_distance, the drag WARN."""

import math

import numpy as np
import pytest

from catenary_monitor import solve
from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.events import Depth, Tension
from catenary_monitor.core.monitor.monitor_core import MonitorCore

LAMBDA_A, LAMBDA_C = 3.0, 0.75  # a holding coefficient and a chain friction (seed 001's form)
ANCHOR = 2500.0  # kgf, Hou's anchor


def printed(value, text):
    digits = len(text.split('.')[1]) if '.' in text else 0
    return abs(value - float(text)) <= 10.0**-digits


def run(line, depth, tensions, **alarm):
    core = MonitorCore(MonitorConfig(lines=(line,), alarm=AlarmConfig(**alarm)), 0)
    core.step(Depth(1, depth))
    outs = [core.step(Tension(2 + k, 0, t)).outputs[0].values for k, t in enumerate(tensions)]
    return core, [dict(zip(OUTPUT_FIELDS, o)) for o in outs]


def hou_line(lm, x=11.0, **extra):
    data = dict(anchor_holding=ANCHOR * LAMBDA_A, chain_friction=LAMBDA_C)
    data.update(extra)
    return LineConfig(name='hou', weight=25.0, anchor_distance=x, mbl=1e6, chain_length=lm, **data)


@pytest.mark.parametrize(
    'lm,h,lying,fh',
    [
        (20.0, 15.0, '0.563', '127.33'),
        (20.0, 13.0, '4.68', '63.09'),
        (21.0, 15.0, '2.90', '85.51'),
        (21.0, 13.0, '6.59', '37.14'),
    ],
)
def test_hou_2005_table_through_the_holding_path(lm, h, lying, fh):
    """The hook tension of Hou's horizontal force (T = Fh + w h, a grounded chain) gives the
    printed lying length, the anchor back at dm = 11 m, and seed 001's holding."""
    _, (out,) = run(hou_line(lm), h, [float(fh) + 25.0 * h])
    assert out['uplift_force'] == 0.0
    assert printed(out['grounded_length'], lying)
    assert abs(out['implied_anchor_distance'] - 11.0) < 2e-3  # Fh printed to 0.01 kgf
    capacity = ANCHOR * LAMBDA_A + 25.0 * LAMBDA_C * out['grounded_length']
    assert math.isclose(out['holding_capacity'], capacity, rel_tol=1e-12)
    assert math.isclose(out['drag_margin'], capacity - out['horizontal_tension'], rel_tol=1e-12)
    assert abs(out['horizontal_tension'] - float(fh)) < 1e-9 * float(fh)


def test_a_dragged_anchor_shows_in_the_implied_distance():
    """The anchor dragged from 11 m to 11.4 m: the tension of that chain gives 11.4 m."""
    t = solve(25.0, 15.0, chain_length=21.0, anchor_distance=11.4).top_tension
    _, (out,) = run(hou_line(21.0), 15.0, [t])
    assert abs(out['implied_anchor_distance'] - 11.4) < 1e-9


def lifted_line(**extra):
    return LineConfig(
        name='sinker',
        weight=1300.0,
        anchor_distance=100.0,
        mbl=4.8e6,
        chain_length=130.0,
        anchor_holding=200e3,
        chain_friction=0.7,
        allowed_uplift=1e9,
        **extra,
    )


def test_a_lifted_sinker_holds_by_its_remaining_weight():
    """Uplift V: grounded chain 0; a sinker's holding anchor_holding (1 - V/W); a drag anchor
    (no anchor_weight) none."""
    t = 8.0e5
    _, (out,) = run(lifted_line(anchor_weight=400e3), 20.0, [t])
    v = out['uplift_force']
    assert v > 0 and out['grounded_length'] == 0.0
    assert math.isclose(out['holding_capacity'], 200e3 * (1 - v / 400e3), rel_tol=1e-12)
    _, (drag,) = run(lifted_line(), 20.0, [t])
    assert drag['holding_capacity'] == 0.0
    assert drag['drag_margin'] == -drag['horizontal_tension']
    _, (heavy,) = run(lifted_line(anchor_weight=v / 2), 20.0, [t])
    assert heavy['holding_capacity'] == 0.0  # pulled off the seabed: no friction left


def test_without_holding_data_the_values_are_nan():
    """No chain length, no anchor holding: NaN, grounded or lifted."""
    line = LineConfig(name='plain', weight=1300.0, anchor_distance=120.0, mbl=4.8e6)
    core, (out, lifted) = run(line, 20.85, [3.7e5, 8e5])
    assert lifted['uplift_force'] > 0
    for key in ('grounded_length', 'holding_capacity', 'drag_margin', 'implied_anchor_distance'):
        assert math.isnan(out[key]) and math.isnan(lifted[key]), key


def test_drag_warning_with_deadband():
    """WARN below drag_margin_warn; held until warn + deadband is reached."""
    line = hou_line(21.0, allowed_uplift=1e9)  # the anchor may lift: only warnings here
    core, outs = run(
        line,
        15.0,
        [85.51 + 375, 900.0 + 375, 85.51 + 375],
        drag_margin_warn=7440.0,
        drag_margin_deadband=100.0,
        warn_clear_hold=0.0,
        margin_clear_hold=0.0,
        clear_hold=0.0,
    )
    # 7500 + 25*0.75*2.9 - 85.5 = 7468.8 N: above 7440 but below 7540 at the end
    assert outs[0]['drag_margin'] > 7440.0
    assert outs[1]['drag_margin'] < 7440.0
    state = core.state.lines[0].state
    assert state.level == Level.WARN and 'drag margin 7.5 kN, warning held' in state.message
    assert 'anchor may drag' in state.message
    core2, _ = run(line, 15.0, [900.0 + 375], drag_margin_warn=7440.0)
    assert (
        'drag margin' in core2.state.lines[0].state.message
        and 'kN <' in core2.state.lines[0].state.message
    )


def test_holding_doc_parameter_table_is_generated():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown

    page = (Path(__file__).resolve().parent.parent / 'docs' / 'holding.md').read_text()
    begin, end = '<!-- holding-parameters:begin -->\n', '<!-- holding-parameters:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('holding')


def paper_line(chain_length=122.6247):
    """The paper dock's line (config/floating_dock.yaml): 122.6247 m of chain to a sinker
    120 m off, the pretension R = 372 kN at the mean tide's 20.85 m."""
    return LineConfig(
        name='line_01',
        weight=1300.0,
        anchor_distance=120.0,
        mbl=4.827e6,
        chain_length=chain_length,
    )


def test_tide_margin_at_length_is_the_rise_that_lifts_the_anchor():
    """At rest the paper's dock lifts its sinkers after 1.05 m of tide (docs/dock_body.md, the
    dock as one body), where ``tide_margin`` (R held) says 4.68 m; a chain lifted already has
    a negative margin; without ``chain_length`` it is NaN."""
    from catenary_monitor.core.physics import fixed_length as fl

    w, length, h = 1300.0, 122.6247, 20.85
    t = float(fl.statics_at_span(w, h, length, 120.0).top_tension)
    _, (o,) = run(paper_line(), h, [t])
    assert printed(o['tide_margin'], '4.68') and printed(o['tide_margin_at_length'], '1.05')
    assert o['implied_anchor_distance'] == pytest.approx(120.0, rel=1e-12)
    # the state a margin deeper, the chain and span held: the anchor just lifts
    at = fl.statics_at_span(w, h + o['tide_margin_at_length'], length, 120.0)
    assert float(at.grounded_length) == pytest.approx(0.0, abs=1e-6)
    assert float(at.uplift_force) == pytest.approx(0.0, abs=1.0)
    lifted = fl.statics_at_span(w, h + 2.0, length, 120.0)
    _, (o,) = run(paper_line(), h + 2.0, [float(lifted.top_tension)])
    assert o['uplift_force'] > 0
    assert o['tide_margin_at_length'] == pytest.approx(1.0515 - 2.0, abs=1e-3)
    _, (o,) = run(paper_line(None), h, [t])
    assert math.isnan(o['tide_margin_at_length']) and printed(o['tide_margin'], '4.68')


def test_on_a_rising_tide_the_margin_at_length_counts_down_to_the_lift():
    """The paper's chain, its length and span held, the tide rising 0.5 m/h: the pretension
    rises (the scene is the fixed-length chain's own), ``tide_margin_at_length`` plus the depth
    stays the lift depth at every update, while ``tide_margin`` (R held, what
    ``time_to_uplift`` counts down) stays above it."""
    from catenary_monitor.core.physics import fixed_length as fl

    w, length, rate = 1300.0, 122.6247, 0.5 / 3600.0
    lift = float(fl.lift_depth(w, length, 120.0))
    core = MonitorCore(
        MonitorConfig(lines=(paper_line(),), alarm=AlarmConfig(tension_resolution=0.0)), 0
    )
    for k in range(0, 7200, 60):
        h = 20.85 + rate * k
        core.step(Depth(k * 1_000_000_000 + 1, h))
        t = float(fl.statics_at_span(w, h, length, 120.0).top_tension)
        o = dict(
            zip(OUTPUT_FIELDS, core.step(Tension(k * 1_000_000_000 + 2, 0, t)).outputs[0].values)
        )
        assert o['tide_margin_at_length'] + h == pytest.approx(lift, rel=1e-12, abs=1e-9)
        assert o['tide_margin'] > o['tide_margin_at_length']  # R held: the later lift
    assert o['tide_margin_at_length'] == pytest.approx(1.0515 - rate * 7140, abs=1e-3)  # 7140 s on


def _holding_scenes(n, seed):
    """Chains of the dock's kind and far beyond: grounded and lifted, inextensible and
    elastic, holding data given or not (NaN), a few solves missing (NaN)."""
    import numpy as np

    from catenary_monitor.core.physics import fixed_length

    rng = np.random.default_rng(seed)
    w = 10.0 ** rng.uniform(1, 4, n)
    h = 10.0 ** rng.uniform(0, 2.5, n)
    length = h * 10.0 ** rng.uniform(0.05, 1.5, n)
    ea = np.where(rng.random(n) < 0.5, np.inf, w * length * 10.0 ** rng.uniform(1, 6, n))
    slack = np.asarray(fixed_length.slack_span(w, h, length, ea))
    reach = np.where(np.isinf(ea), fixed_length.taut_span(h, length), 1.3 * length)
    span = slack + (reach - slack) * rng.uniform(0.01, 0.999, n)
    st = fixed_length.statics_at_span(w, h, length, span, ea)
    given = rng.random((4, n)) < 0.7
    holding = np.where(given[0], w * h * rng.uniform(1, 50, n), np.nan)
    anchor_weight = np.where(given[1], holding * rng.uniform(0.2, 3, n), np.nan)
    friction = np.where(given[2], rng.uniform(0.3, 1.5, n), np.nan)
    length = np.where(given[3] | np.isnan(holding), length, np.nan)
    r = np.where(rng.random(n) < 0.05, np.nan, st.horizontal_tension)
    return (
        w,
        ea,
        length,
        holding,
        anchor_weight,
        friction,
        st.top_tension,
        h,
        r,
        st.suspended_length,
        st.uplift_force,
    )


@pytest.mark.parametrize('seed', [1, 2])
def test_the_plain_float_holding_path_gives_the_array_path_numbers(seed):
    """holding_scalar (the monitor's per-sample path, about 20x faster on one line) against
    holding() on the same scenes as one array. The implied span agrees to a few ulps; the lift
    depth, at the same span and at the implied one, to the problem's own conditioning (near the
    taut limit a relative change e of the span moves it by about e / (2 (1 - span / length));
    the elastic chain's Newton in R is as sensitive, and the array path itself differs by as
    much between batch sizes, as it iterates until every element has converged); NaN where
    NaN."""
    import numpy as np

    from catenary_monitor.core.rules.holding import (
        FIELDS,
        LENGTH_FIELDS,
        HoldingInputs,
        holding,
        holding_scalar,
    )
    from catenary_monitor.core.physics import fixed_length

    scenes = _holding_scenes(2000, seed)
    w, ea, length, h = scenes[0], scenes[1], scenes[2], scenes[7]
    vec = holding(HoldingInputs(*scenes))
    implied = vec['implied_anchor_distance']
    lift = fixed_length.lift_depth(w, length, implied, ea)
    lifted = 0
    for i in range(len(w)):
        one = holding_scalar(HoldingInputs(*(float(c[i]) for c in scenes)))
        lifted += scenes[-1][i] > 0
        if np.isfinite(implied[i]):
            assert one['implied_anchor_distance'] == pytest.approx(implied[i], rel=1e-15, abs=0)
            at_same = fixed_length.lift_depth_scalar(w[i], length[i], implied[i], ea[i])
            cond = 1.0 / (1.0 - implied[i] / length[i])
            assert at_same == pytest.approx(lift[i], rel=2e-15 * cond, abs=0) or (
                math.isnan(at_same) and math.isnan(lift[i])
            )
        for key in FIELDS + LENGTH_FIELDS:
            want = float(vec[key][i])
            scale = abs(want)
            if key == 'tide_margin_at_length':
                scale = (abs(lift[i]) + h[i]) / (1.0 - implied[i] / length[i])
            if math.isnan(want):
                assert math.isnan(one[key]), (i, key, one[key])
            else:
                assert abs(one[key] - want) <= 1e-14 * scale, (i, key, one[key], want)
    assert 200 < lifted < 1800  # both regimes are in the sweep (no pass by construction)
    assert np.isfinite(vec['tide_margin_at_length']).sum() > 500


def test_the_core_takes_the_plain_float_path_on_a_tension_and_the_array_path_on_a_depth(
    monkeypatch,
):
    """A tension event (one line: plain floats, the array path never called) and a depth
    event (every line: the array path) give the same holding values for the same tension and
    depth."""
    import dataclasses

    from catenary_monitor.core.rules import holding as holding_rule

    calls = []
    array_path = holding_rule.holding
    monkeypatch.setattr(holding_rule, 'holding', lambda *a: calls.append(1) or array_path(*a))
    line = hou_line(20.5)
    other = dataclasses.replace(line, name='b', tension_topic='')
    core = MonitorCore(MonitorConfig(lines=(line, other)), 0)
    core.step(Depth(1, 14.0))
    one = core.step(Tension(2, 0, 120.0 + 25.0 * 14.0)).outputs[0].values
    core.step(Tension(3, 1, 120.0 + 25.0 * 14.0))
    assert calls == []
    both = core.step(Depth(4, 14.0)).outputs
    assert calls == [1]
    for k in (
        'grounded_length',
        'holding_capacity',
        'implied_anchor_distance',
        'tide_margin_at_length',
    ):
        i = OUTPUT_FIELDS.index(k)
        assert math.isfinite(one[i]), k
        assert one[i] == pytest.approx(both[0].values[i], rel=1e-13)
        assert both[0].values[i] == both[1].values[i]


def _storm(spans, line, **alarm):
    """The core and its twin through one tension a second at those spans (Hou's depth 13 m,
    a tick a second): the core's outputs and transitions, and the twin's."""
    from catenary_monitor.core.monitor.events import Tick
    from catenary_monitor.core.twin.engine import recompute

    config = MonitorConfig(lines=(line,), alarm=AlarmConfig(clear_hold=0.0, **alarm))
    tensions = [solve(25.0, 13.0, chain_length=21.0, anchor_distance=x).top_tension for x in spans]
    core = MonitorCore(config, 0)
    core.step(Depth(1, 13.0))
    outs, changes = [], []
    for k, t in enumerate(tensions):
        step = core.step(Tension(10**9 * (k + 1), 0, t))
        outs.append(dict(zip(OUTPUT_FIELDS, step.outputs[0].values)))
        changes += [c.transition for c in step.transitions if c.component == 'hou']
        changes += [
            c.transition
            for c in core.step(Tick(10**9 * (k + 1) + 5)).transitions
            if c.component == 'hou'
        ]
    stamps = [10**9 * (k + 1) for k in range(len(spans))]
    result = recompute(
        config,
        {'hou': (np.array(stamps, np.int64), np.array(tensions))},
        (np.array([1], np.int64), np.array([13.0])),
        tick_ns=np.array(stamps, np.int64) + 5,
        start_ns=0,
    )
    return outs, changes, result.lines[0]


def test_a_dragging_anchor_in_a_storm_raises_its_error():
    """Hou's ship (chain 21 m, 13 m deep, anchor 11 m away) in a scripted storm: the span opens
    from 11 m to 14 m while the anchor slides; past 13.4 m the load exceeds the holding (40 +
    chain friction) with the anchor 2.4 m beyond its place: drag_state 2 and the ERROR, live and
    in replay alike; it clears once the anchor holds again."""
    spans = list(np.linspace(11.0, 14.0, 31)) + [14.0] * 5 + [11.2] * 5
    line = hou_line(21.0, allowed_uplift=1e9, anchor_holding=40.0)
    outs, changes, replayed = _storm(spans, line)
    states = [o['drag_state'] for o in outs]
    assert states[0] == 0.0 and 2.0 in states and states[-1] == 0.0
    first = states.index(2.0)
    assert outs[first]['drag_margin'] < 0 and outs[first]['implied_anchor_distance'] > 12.0
    assert 1.0 not in states[:first]  # the span is beyond the tolerance when the load passes
    errors = [c for c in changes if c.new == Level.ERROR]
    assert errors and 'anchor dragging: horizontal load' in errors[0].message
    assert 'beyond its installed 11.0 m' in errors[0].message
    assert changes[-1].new in (Level.OK, Level.WARN)
    assert np.array_equal(replayed.values['drag_state'], np.array(states))
    assert [(t.time, t.new, t.message) for t in replayed.transitions] == [
        (t.time, t.new, t.message) for t in changes
    ]


def test_a_steady_overload_without_drag_warns_but_raises_no_error():
    """The load above a conservative holding (30 < 37.1) with the anchor where it was
    installed: overloaded (drag_state 1), the drag-margin WARN, no ERROR."""
    line = hou_line(21.0, allowed_uplift=1e9, anchor_holding=30.0, chain_friction=0.0)
    outs, changes, replayed = _storm([11.0] * 40, line)
    assert {o['drag_state'] for o in outs} == {1.0}
    assert all(o['drag_margin'] < 0 for o in outs)
    assert Level.ERROR not in [c.new for c in changes]
    assert changes[-1].new == Level.WARN and 'anchor may drag' in changes[-1].message
    assert [t.new for t in replayed.transitions] == [t.new for t in changes]
