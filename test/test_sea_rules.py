"""The prototype sensor rules (catenary_monitor_study/sea_rules.py) on generated days of a dock's
normal operation and on injected faults: quiet on the normal days, each fault found."""

import math

import numpy as np
import pytest

from catenary_monitor.core.config.tide_constituents import parse_table
from catenary_monitor_study import normal_days as nd
from catenary_monitor_study import normal_days_log as ndl
from catenary_monitor_study import sea_rules as sr

DAY = 86400.0


@pytest.fixture(scope='module')
def day():
    """A day at the paper's dock (Pillar Point's tide), its slow truth."""
    scene = nd.paper_scene('radar_1cm', days=1.0, mean_depth=18.3)
    return scene, nd.coarse(scene)


def _readings(scene, c, gauge, seed=3):
    g = nd.GAUGES[gauge]
    s = nd.Scene(scene.name, scene.params, scene.port, g, scene.seconds, scene.mean_depth,
                 scene.weather, scene.cells, (), scene.start_ns, scene.seed, scene.grid)
    t = 0.35 + np.arange(0.0, scene.seconds - 1.0, g.period)
    return t, ndl.gauge_levels(s, c, t, np.random.default_rng(seed))


def _trend(t, v, at, window=1200.0):
    """The tide's rate [m/s] at each ``at``: least squares over the window before it."""
    out = np.full(len(at), math.nan)
    for i, x in enumerate(at):
        m = (t > x - window) & (t <= x)
        if m.sum() > 10:
            out[i] = np.polyfit(t[m] - x, v[m], 1)[0]
    return out


@pytest.mark.parametrize('gauge', ['radar_1cm', 'exact_1mm', 'pressure_1mm'])
@pytest.mark.parametrize('with_table', [True, False])
def test_a_moving_gauge_is_never_stuck_on_a_normal_day(day, gauge, with_table):
    scene, c = day
    t, v = _readings(scene, c, gauge)
    res = nd.GAUGES[gauge].resolution
    changed = sr.last_steps(t, v, res)
    ticks = np.arange(600.0, scene.seconds, 10.0)
    k = np.searchsorted(t, ticks, 'right') - 1
    table = parse_table(scene.flat['tide_table']) if with_table else ()
    rate = math.nan if with_table else _trend(t, v, changed[k])
    stuck = sr.stuck_gauge(changed[k] + scene.start_s, ticks + scene.start_s, res, table,
                           scene.flat['tide_table_epoch'], rate, seen_range=np.ptp(v))  # fmt: skip
    assert not stuck.any(), f'stuck at {ticks[stuck][:5]} s'
    # today's rule on the same readings: the gauge still for stuck_time (60 s) while the
    # lines move (they always do) -- what the monitor annunciates
    today = ticks - changed[k] >= 60.0
    if gauge != 'pressure_1mm':
        assert today.any()


@pytest.mark.parametrize('with_table', [True, False])
def test_a_frozen_gauge_is_found_once_the_tide_moves(day, with_table):
    scene, c = day
    t, v = _readings(scene, c, 'radar_1cm')
    table = parse_table(scene.flat['tide_table']) if with_table else ()
    delays = []
    for at in (3 * 3600.0, 9 * 3600.0, 14 * 3600.0, 20 * 3600.0):
        frozen = v.copy()
        frozen[t >= at] = v[t < at][-1]
        changed = sr.last_steps(t, frozen, 0.01)
        ticks = np.arange(at, min(at + 4 * 3600.0, scene.seconds - 2.0), 10.0)
        k = np.searchsorted(t, ticks, 'right') - 1
        rate = math.nan if with_table else _trend(t, frozen, changed[k])
        stuck = sr.stuck_gauge(changed[k] + scene.start_s, ticks + scene.start_s, 0.01, table,
                               scene.flat['tide_table_epoch'], rate,
                               seen_range=np.ptp(v))  # fmt: skip
        assert stuck.any(), f'frozen at {at} s not found in 4 h'
        delays.append(ticks[np.argmax(stuck)] - at)
    if with_table:
        assert max(delays) < 3600.0, delays
    else:
        # without a table a gauge frozen near slack water waits for the backstop
        assert min(delays) < 1800.0 and max(delays) <= sr.STILL_MAX, delays


def test_double_reads_of_a_noisy_gauge_are_no_spikes(day):
    """The pressure gauge's 2 mm noise on readings 1-3 ms apart (a driver's retried poll):
    today's threshold (rate x dt + resolution, no bunching for stamped types) calls some of
    them spikes; with the noise and the bunching counted, none; a 2 m glitch still is one."""
    scene, c = day
    g = nd.GAUGES['pressure_1mm']
    t = np.sort(np.concatenate([np.arange(0.35, 6 * 3600.0, 1.0),
                                np.arange(100.35, 6 * 3600.0, 997.0) + 0.0018]))  # fmt: skip
    s = nd.Scene(scene.name, scene.params, scene.port, g, scene.seconds, scene.mean_depth,
                 scene.weather, scene.cells, (), scene.start_ns, scene.seed, scene.grid)
    v = ndl.gauge_levels(s, c, t, np.random.default_rng(5))
    dt, dv = np.diff(t), np.abs(np.diff(v))
    today = dv > 1.0 * dt + g.resolution
    assert today.sum() >= 3
    noise = sr.noise_estimate(v[:600])
    assert 0.001 < noise < 0.03  # the 2 mm noise and the waves left at the seabed
    assert not (dv > sr.spike_threshold(dt, 1.0, g.resolution, 0.25, noise)).any()
    v[20000] += 2.0  # a glitch (the default depth_rate_max is 1 m/s)
    assert (np.abs(np.diff(v)) > sr.spike_threshold(dt, 1.0, g.resolution, 0.25, noise)).any()


def test_intake_warns_on_a_loss_to_act_on():
    assert sr.intake_level(3, 7640) == 0
    assert sr.intake_level(1, 20) == 0
    assert sr.intake_level(400, 7640) == 1


def test_a_gateway_drop_is_one_cause_a_silent_cell_its_own():
    scene = nd.paper_scene('radar_1cm', days=0.02, mean_depth=18.3,
                           faults=(nd.Fault('gateway_drop', 600.0, 15.0),
                                   nd.Fault('silent_cell', 900.0, 600.0, 'line_04')))  # fmt: skip
    streams, _, _ = ndl.cell_streams(scene, nd.coarse(scene), 0.0, 1700.0,
                                     np.random.default_rng(1))  # fmt: skip

    def last_before(now):
        return np.array([float(s.log_ns[s.log_ns <= scene.start_ns + now * 1e9][-1])
                         for s in streams]) * 1e-9 - scene.start_s  # fmt: skip

    groups = sr.common_silence(last_before(608.0), 608.0, 5.0)
    assert [sorted(g) for g in groups] == [list(range(12))]
    groups = sr.common_silence(last_before(910.0), 910.0, 5.0)
    assert groups == [[3]]


def test_first_out_is_the_first_still_active():
    raises = [(10.0, 'sensors'), (55.0, 'line_11'), (56.0, 'line_10')]
    assert sr.first_out(raises, ['line_11', 'line_10']) == (55.0, 'line_11')


@pytest.mark.parametrize('kind,factor', [('units_dan', 10.0), ('units_tf', 9.80665)])
def test_a_unit_mistake_is_found_against_the_lines_statics(day, kind, factor):
    """daN on an N line, tonnes-force on a kN line: the line's reading against its own at-rest
    statics scaled by the dock's common loading names the factor; the other lines, over a
    normal day every 10 min, fit."""
    scene, c = day
    config = scene.config
    bad, hits, windows = 'line_11', 0, 0
    for at in np.arange(600.0, scene.seconds - 600.0, 600.0):
        t = at + np.arange(0.0, 60.0, 0.1)
        truth = nd.hook_tensions(scene, c, t)
        depth = float(np.median(nd.still_depth(scene, t)))
        reading = np.median(truth, axis=0)
        assert sr.units_check(config, reading, depth) == [None] * 12, at
        reading[10] /= factor  # the cell's unit read as the configured one
        found = sr.units_check(config, reading, depth)
        # 10 and 9.81 are 2 % apart, the dock's loads blur more: either names the mistake
        assert found[:10] + found[11:] == [None] * 11, (at, bad, found)
        hits += found[10] in (10.0, 9.80665)
        windows += 1
    assert hits >= 0.95 * windows, (hits, windows)


def test_chart_defaults_from_the_lines(day):
    scene, c = day
    lo, hi = sr.chart_range(scene.config)
    assert lo < float(np.min(c.depth)) - 5.0 and hi > float(np.max(c.depth)) + 5.0
    assert not lo <= 0.3 <= hi  # the pressure gauge stepping to 0.3 m: impossible


def test_steps_on_the_gauges_grid_are_seen_by_rounding():
    """A 1 cm radar's depths (gauge height - a float32 range) lie on the centimetre grid within
    a float's last bit: ``floor(x / 0.01)`` (today's sensor memory) puts about a third of the
    neighbouring steps in one bin -- the gauge looks still while it steps, and configuring
    ``depth_resolution: 0.01`` makes the stuck rule worse; ``round`` sees every step."""
    depth = np.round(np.arange(17.5, 19.5, 0.01), 2)
    ranges = (26.443 - depth).astype(np.float32)
    readings = 26.443 - ranges.astype(np.float64)
    by_floor, by_round = sr.hidden_steps(readings, 0.01)
    assert by_floor > 0.2 * len(depth) and by_round == 0
