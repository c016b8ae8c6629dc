"""The demo promises what its episode has: the banner's storm load, the anchors it lifts and
the tension it names are the episode's, it says how fast its time runs, and the monitor (the
batch twin on the simulator's 20 Hz tensions and 2 Hz depth, the demo's parameters) raises no
alarm outside that story: the uplift ERRORs on exactly the lines it names, warnings only on
lines coming close, the flood's first out one of them, every line back to OK as it eases."""

from __future__ import annotations

import re

import numpy as np
import pytest

from catenary_monitor.cli.demo import DEMO_OVERRIDES
from catenary_monitor.core.config.parameters import config_from_params, load_params_file
from catenary_monitor.core.twin.engine import recompute
from catenary_monitor.sim.scenario import M2_PERIOD, Scenario, default_config_path

T0_NS = 1_700_000_000 * 10**9


@pytest.fixture(scope='module')
def demo():
    params = load_params_file(default_config_path())
    params.update(DEMO_OVERRIDES)
    cfg = config_from_params(params)
    scenario = Scenario(cfg)
    rng = np.random.default_rng(scenario.seed)
    t = np.arange(0.0, scenario.duration, 0.05)
    rows = np.array([scenario.tensions(x, rng) for x in t])
    ns = T0_NS + np.rint(t * 1e9).astype(np.int64)
    tensions = {line.name: (ns, rows[:, k]) for k, line in enumerate(cfg.lines)}
    depth = (ns[::10] - 1000, np.array([scenario.depth(x) for x in t[::10]]))
    result = recompute(cfg, tensions, depth, start_ns=T0_NS - 10**9, snapshots=True)
    return scenario, rows, result


def test_the_banner_says_what_the_episode_has_and_how_fast_it_runs(demo):
    scenario, rows, _ = demo
    head, clock = scenario.story()
    assert 'typhoon' not in head
    load = re.search(r'a storm of ([\d.]+) MN', head)
    assert load and float(load.group(1)) * 1e6 == pytest.approx(scenario.storm_peak, rel=0.01)
    peak = re.search(r'(line_\d+) the most, its hook tension up to about (\d+) kN', head)
    assert peak, head
    k = [line.name for line in scenario.config.lines].index(peak.group(1))
    assert float(peak.group(2)) * 1e3 == pytest.approx(rows[:, k].max(), rel=0.02)
    speed = re.search(r'time x(\d+): one ([\d.]+) h tide in (\d+) s', clock)
    assert speed, clock
    assert float(speed.group(1)) == pytest.approx(M2_PERIOD / scenario.duration, abs=0.5)
    assert float(speed.group(2)) == pytest.approx(M2_PERIOD / 3600.0, abs=0.01)


def test_the_monitor_raises_no_alarm_outside_the_story(demo):
    scenario, _, result = demo
    head = scenario.story()[0]
    names = [line.name for line in scenario.config.lines]
    run = re.search(r'lifts the anchors of (line_\d+) to (line_\d+)', head)
    assert run, head
    told = set(names[names.index(run.group(1)) : names.index(run.group(2)) + 1])
    errors, warned = set(), set()
    for r in result.lines:
        levels = [x.new.name for x in r.transitions if 'STALE' not in (x.old.name, x.new.name)]
        if 'ERROR' in levels:
            errors.add(r.name)
        elif 'WARN' in levels:
            warned.add(r.name)
        if levels:
            assert levels[0] == 'WARN' and levels[-1] == 'OK', (r.name, levels)  # eased
    assert errors == told, (errors, told)
    assert len(warned) <= 1 and warned.isdisjoint({'line_01', 'line_02', 'line_03', 'line_04'})
    # the components: nothing but the flood (its first out a lifted line) once data flows
    firsts, others = set(), set()
    for sn in result.snapshots:
        for st in sn.statuses:
            name = st.name.split(': ')[1]
            if name.startswith('line_') or st.level == 0:
                continue
            values = dict(st.values)
            if name == 'alarms':
                firsts.add(values.get('first_out'))
            elif (sn.stamp_ns - T0_NS) * 1e-9 > 2.0:  # the start, before the first depth
                others.add((name, st.message))
    assert firsts and firsts <= told, firsts
    assert not others, others
