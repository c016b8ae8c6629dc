"""Units and ranges that announce themselves, on generated scenes (catenary_monitor_study's
normal_days_log, replayed as the node's log): a load cell in daN on a line set in N, and one in
tonnes-force on a line set in kN, while a storm lifts that line's anchor, is an ``input`` ERROR
"wrong units?" naming its ``tension_scale`` from the first tick and never reads OK; a normal
stretch claims nothing; the chart range comes from the lines and refuses a depth of 0.3 m."""

import dataclasses
import math
import re

import numpy as np
import pytest

from catenary_monitor.core.config.parameters import chart_range
from catenary_monitor.core.rules import plausible
from catenary_monitor_study import normal_days as nd
from catenary_monitor_study import normal_days_log as ndl
from catenary_monitor_study.bench_alarms import replay_counts

MINUTES = 30.0
LINE = 'line_11'  # the line a storm from 270 deg lifts (catenary_monitor_study.storm_line)


def _scene(faults=(), storm=True):
    """Half an hour at the paper's dock: calm for 12 min, then a storm lifting line_11's
    anchor by 190 kN from 22 to 28 min; load cells at 2 Hz (the rules need no more)."""
    weather = nd.Weather()
    if storm:
        weather = dataclasses.replace(
            weather, storm=nd.Storm(1500.0, LINE, rise=600.0, hold=360.0, fall=600.0)
        )
    scene = nd.paper_scene('radar_1cm', days=MINUTES / 1440.0, faults=faults,
                           weather=weather, mean_depth=18.3)  # fmt: skip
    return dataclasses.replace(scene, cells=dataclasses.replace(scene.cells, rate=2.0))


@pytest.fixture(scope='module', params=['units_dan', 'units_tf'])
def units_run(request, tmp_path_factory):
    scene = _scene((nd.Fault(request.param, 0.0, math.inf, LINE),))
    facts = ndl.write_scene(scene, tmp_path_factory.mktemp(request.param))
    counter, _ = replay_counts(facts.log, facts.params)
    return request.param, scene, counter


def test_a_unit_mistake_is_an_input_error_naming_the_scale_and_never_ok(units_run):
    kind, scene, counter = units_run
    assert nd.scene_margins(scene)['uplift_max'] > 150e3  # the storm truly lifts an anchor
    # judged at the first tick (0.5 s; before it the line had one solve, 0.1 s before)
    levels = [level for t, level in counter.changes[LINE] if t >= scene.start_s + 0.5]
    assert levels and 0 not in levels, counter.changes[LINE][:10]  # never OK
    raised = [a for a in counter.heard() if a.status == LINE]
    assert raised and raised[0].after == 2, raised[:3]  # ERROR
    text = raised[0].message
    assert 'wrong units?' in text and f'{LINE}.tension_scale' in text, text
    scale = 1.0 if kind == 'units_dan' else 1000.0
    assert f'tension_scale {scale:g} -> ' in text, text
    # the headline names the mistake and the parameter; its detail both candidate units
    # (10 and 9.81 are 2 % apart)
    detail = raised[0].detail if hasattr(raised[0], 'detail') else text
    assert 'wrong units?' in detail, detail
    others = [a for a in counter.heard() if 'wrong units' in a.message and a.status != LINE]
    assert not others, others[:3]


@pytest.fixture(scope='module')
def normal_run(tmp_path_factory):
    scene = _scene(storm=False)
    facts = ndl.write_scene(scene, tmp_path_factory.mktemp('normal'))
    return scene, replay_counts(facts.log, facts.params)[0]


def test_a_normal_stretch_claims_no_unit_mistake(normal_run):
    scene, counter = normal_run
    claims = [a for a in counter.heard() if 'wrong units' in a.message]
    assert not claims, claims[:3]
    assert not [a for a in counter.heard() if a.status.startswith('line_')]


def test_the_chart_comes_from_the_lines_and_refuses_a_gauge_at_0_3_m():
    scene = _scene(storm=False)
    lo, hi = scene.config.chart
    # the lines lift at 22.2-22.3 m: 1.25 x the deepest above, 0.05 x the shallowest below (a
    # gauge's datum or scale fault, never a low water)
    assert 1.0 < lo < 1.2 and 25.0 < hi < 30.0, (lo, hi)
    assert lo > 0.3  # a pressure gauge stepping to 0.3 m is impossible by default
    no_chain = [dataclasses.replace(x, chain_length=None) for x in scene.config.lines]
    assert chart_range(no_chain) == (0.0, 12000.0)
    assert chart_range(scene.config.lines) == (lo, hi)


def test_unit_factors_named_and_far_from_one():
    assert plausible.UNIT_FACTORS[plausible.units_factor(10.2)][0] == 10.0
    assert plausible.UNIT_FACTORS[plausible.units_factor(9.7)][0] == 9.80665
    assert plausible.UNIT_FACTORS[plausible.units_factor(1.0 / 1020.0)][0] == 0.001
    assert plausible.UNIT_FACTORS[plausible.units_factor(4.4)][0] == 4.4482216
    for ratio in (1.0, 2.5, 0.4, 30.0, math.nan, -10.0, 0.0):  # no claim
        assert plausible.units_factor(ratio) == -1, ratio
    got = plausible.units_factors(np.array([[10.0, 1.0], [1e-3, 4448.0]]))
    assert got.tolist() == [[0, -1], [8, 5]]
    text = plausible.units_text('line_11', 1.0, 0, 16e3)
    assert text.startswith('wrong units? reading x10 fits the chain\'s statics (daN?')
    assert 'line_11.tension_scale 1 -> 10 ' in text


def _run(scene, tmp_path_factory, name):
    facts = ndl.write_scene(scene, tmp_path_factory.mktemp(name))
    return replay_counts(facts.log, facts.params)[0]


def test_a_pressure_gauge_at_0_3_m_is_an_impossible_depth_and_blinds_no_line_loudly(
    tmp_path_factory,
):
    """The pressure gauge steps to 0.3 m for 10 min: the tide is ERROR "impossible depth"
    (never OK meanwhile), no line solves on it nor annunciates (each blind by it)."""
    fault = nd.Fault('pressure_step', 600.0, 600.0, None, 0.3)
    scene = nd.paper_scene('pressure_1mm', days=20 / 1440.0, faults=(fault,), mean_depth=18.3)
    assert 0.3 < scene.config.chart[0] < 17.0  # the default chart from the lines
    scene = dataclasses.replace(scene, cells=dataclasses.replace(scene.cells, rate=2.0))
    counter = _run(scene, tmp_path_factory, 'pressure')
    t0 = scene.start_s
    heard = counter.heard(t0 + 600.0, t0 + 1200.0)
    tide = [a for a in heard if a.status == 'tide']
    assert tide and tide[0].after == 2 and 'impossible depth 0.30 m' in tide[0].message
    assert not [a for a in heard if a.status.startswith('line_')], heard[:3]
    during = counter.level_at('tide', t0 + np.arange(602.0, 1199.0, 1.0))
    assert (during == 2).all()


def test_a_parted_chain_is_one_error_on_its_line(tmp_path_factory):
    """The chain parts 12 m below line_11's hook: its line raises one ERROR; the others stay
    quiet (the other lines' sum need not rise)."""
    fault = nd.Fault('parted', 600.0, math.inf, LINE, 12.0)
    scene = _scene((fault,), storm=False)
    scene = dataclasses.replace(scene, seconds=1200.0)
    counter = _run(scene, tmp_path_factory, 'parted')
    heard = counter.heard(scene.start_s + 600.0, scene.start_s + 1200.0)
    mine = [a for a in heard if a.status == LINE]
    assert len(mine) == 1 and mine[0].after == 2, heard[:4]
    assert 'suspected parted' in mine[0].message, mine[0]  # named, never an impossible input
    assert not [a for a in heard if a.status.startswith('line_') and a.status != LINE]


def _drawn(faults, minutes=10.0):
    """A dock none of the rules was written on (drawn:2: 8 lines of 48 mm chain, Bermuda),
    load cells at 2 Hz; a units fault brings a storm lifting its line's anchor throughout."""
    scene = nd.drawn_scene(2, 'radar_1cm', days=minutes / 1440.0, faults=faults)
    return dataclasses.replace(scene, cells=dataclasses.replace(scene.cells, rate=2.0))


@pytest.mark.parametrize('kind', ['units_dan', 'units_tf'])
def test_a_unit_mistake_in_a_storm_is_named_on_a_drawn_dock(kind, tmp_path_factory):
    """No calm window: the dock estimate is the witness. The line is one ERROR "wrong units?"
    naming its tension_scale from the first tick, never OK; no other line is claimed."""
    line = nd.storm_line(_drawn(()))
    scene = _drawn((nd.Fault(kind, 0.0, math.inf, line),))
    assert nd.scene_margins(scene)['uplift_max'] > 150e3  # the storm lifts its anchor
    counter = _run(scene, tmp_path_factory, f'drawn-{kind}')
    levels = [level for t, level in counter.changes[line] if t >= scene.start_s + 0.5]
    assert levels and 0 not in levels, counter.changes[line][:10]
    mine = [a for a in counter.heard() if a.status == line]
    assert len(mine) == 1 and mine[0].after == 2, mine[:3]
    assert 'wrong units?' in mine[0].message and f'{line}.tension_scale' in mine[0].message
    assert not [a for a in counter.heard() if 'wrong units' in a.message and a.status != line]


def test_a_parted_chain_is_named_on_a_drawn_dock(tmp_path_factory):
    line = nd.storm_line(_drawn(()))
    scene = _drawn((nd.Fault('parted', 300.0, math.inf, line, 12.0),))
    counter = _run(scene, tmp_path_factory, 'drawn-parted')
    heard = counter.heard(scene.start_s + 300.0, scene.start_s + 600.0)
    assert heard and heard[0].status == line, heard[:3]  # first out
    assert heard[0].after == 2 and 'suspected parted' in heard[0].message, heard[0]
    assert len([a for a in heard if a.status == line]) == 1, heard[:4]


def test_the_dock_witness_claims_a_flagged_line_off_by_a_unit_factor():
    rule = plausible.UnitsRule()
    tension = np.array([[100e3, 100e3, 100e3, 12e3, 100e3, 100e3]])
    fresh = np.ones_like(tension, bool)
    inputs = np.zeros((1, 6, 4))
    inputs[..., 2] = 100e3  # the expected tensions
    inputs[0, 3, 0] = 1.0  # line 3 flagged: 100 / 12 = 8.3, within 25 % of 9.81
    idx, fits = plausible.dock_units(inputs, tension, fresh, rule)
    assert plausible.UNIT_FACTORS[idx[0, 3]][0] == 9.80665 and (np.delete(idx, 3) == -1).all()
    assert fits[0].tolist() == [True, True, True, False, True, True]
    inputs[0, 3, 2] = 40e3  # 3.3x: near no factor within 25 %
    assert (plausible.dock_units(inputs, tension, fresh, rule)[0] == -1).all()
    inputs[0, 3, 2] = 100e3
    inputs[0, :3, 0] = 1.0  # four of six flagged: the estimate does not stand
    assert (plausible.dock_units(inputs, tension, fresh, rule)[0] == -1).all()


def test_at_a_lift_point_the_statics_name_no_factor_they_cannot_tell():
    """A daN cell on a line at its anchor's lift point (drawn:2, a storm lifting ml5 by 5 kN:
    the line carries 1.7 x the common loading) reads 6.0 x below its statics x that loading,
    the lines spread by 0.22 (the calm measure): lbf (x4.45) and daN (x10) both fit. The claim
    is "wrong units?" naming ml5.tension_scale but no factor, until the dock estimate (once it
    flags the line) names x10; never OK meanwhile."""
    from catenary_monitor.core.alarms.texts import HEADLINE_LIMIT, headline

    rule = plausible.UnitsRule()
    low, high = plausible.UNSURE_LOW, plausible.UNSURE_HIGH
    factor = {i: f for i, (f, _) in enumerate(plausible.UNIT_FACTORS)}
    cases = [  # (ratio, calm): the claim
        ((5.995, 0.2213), low), ((6.336, 0.2015), low), ((1 / 6.0, 0.22), high),
        ((10.0, 0.22), 10.0), ((4.45, 0.22), 4.4482216), ((6.0, 0.03), 4.4482216),
        ((8.3, 0.03), 9.80665), ((20.0, 0.02), None), ((2.5, 0.3), None), ((1000.0, 0.3), 1000.0),
    ]  # fmt: skip
    for (ratio, calm), want in cases:
        got = int(plausible.units_claims(np.array([ratio]), np.array([calm]), rule)[0])
        got_f = got if got in (low, high) else factor.get(got)
        assert got_f == want, (ratio, calm, got)
    # the latch at the first ticks (ml5 of 8 lines; the others fit), then the dock's witness
    ratio = np.ones((3, 8))
    ratio[:, 4] = [5.995, 6.069, 5.718]
    calm = np.array([0.2213, 0.2235, 0.2047])
    judged = np.ones((3, 8), bool)
    memory = [plausible.UnitsMemory()] * 8
    now = np.array([0.5, 1.5, 2.5])
    out, memory = plausible.units_latch(memory, now, ratio, calm, judged, rule)
    assert (out[:, 4] == low).all() and (np.delete(out, 4, axis=1) == -1).all()
    text = plausible.units_text('ml5', 1.0, low, 21.5e3)
    head = headline(text, 'input')
    assert len(head) <= HEADLINE_LIMIT and 'ml5.tension_scale' in head, head
    assert 'wrong units?' in head and not re.search(r'reading [x/][0-9]', text), text
    dock = (np.full((1, 8), -1), np.zeros((1, 8), bool))
    dock[0][0, 4] = 0  # the estimate flags ml5 at 9.5 s: expected / reading 9.9, x10
    out, _ = plausible.units_latch(memory, np.array([9.5]), ratio[:1], calm[:1],
                                   judged[:1], rule, dock)  # fmt: skip
    assert out[0, 4] == 0 and factor[int(out[0, 4])] == 10.0


def test_on_a_dock_of_four_lines_the_line_off_by_ten_is_claimed_and_no_other():
    """drawn:11 (four lines, 18.5 m) with ml4's daN cell at its lift point in a storm: the
    lines read 0.83, 0.96, 0.71 and 0.215 x their at-rest statics. All four spread by 0.48
    (log, the 75th percentile takes a quarter of ml4's own deviation): never calm, never
    claimed (the lines' 'inconsistent' WARNs the only witness). The others without ml4 are
    calm: ml4 is claimed, its factor unsure (lbf and daN both within the band of all four);
    for the other lines ml4 is among the others, so the dock is not calm: no claim."""
    rule = plausible.UnitsRule()
    depths = np.array([10.0, 30.0])
    table = (depths, np.full((2, 4), 150.3e3))
    tension = np.array([[124.9e3, 144.1e3, 107.2e3, 32.3e3]])
    depth = np.array([18.51])
    ratio, calm = plausible.units_ratios(table, depth, tension)
    assert calm[0] > math.log(rule.calm)  # the dock of all four lines: never calm
    apart = plausible.others_calm(table, depth, tension)
    assert apart[0, 3] < math.log(rule.calm) < apart[0, :3].min()
    memory = [plausible.UnitsMemory()] * 4
    judged = np.ones((1, 4), bool)
    out, _ = plausible.units_latch(memory, np.array([0.5]), ratio, calm, judged, rule)
    assert (out == -1).all()  # before: no claim
    out, _ = plausible.units_latch(memory, np.array([0.5]), ratio, calm, judged, rule,
                                   apart=apart)  # fmt: skip
    assert out[0].tolist() == [-1, -1, -1, plausible.UNSURE_LOW]
