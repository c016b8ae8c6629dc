"""Sensor rules that know the sea (core/rules/sensor_state.py, core/rules/health.py) on
generated hours of a dock's normal operation and on injected faults: the depth gauge is stuck
only when the tide must have moved it, a spike is beyond the rate, the stamps' bunching and the
gauge's own noise, the intake warns on a loss to act on; quiet on the normal days, each fault
found; the twin decides as the core. Study prototypes of the rules still to come (common
cause, first-out, units, chart) stay in catenary_monitor_study/sea_rules.py."""

import math

import numpy as np
import pytest
from replay_data import T0_NS
from test_batch import compare, ticks_for

from catenary_monitor.core.alarms.flood import first_out
from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.config.tide_constituents import parse_table
from catenary_monitor.core.rules import sensor_state, tide_trend
from catenary_monitor.core.rules.health import common_cause, intake_status, silent_groups
from catenary_monitor.core.rules.level import Level
from catenary_monitor_study import normal_days as nd
from catenary_monitor_study import normal_days_log as ndl
from catenary_monitor_study import sea_rules as sr

HOURS = 8.0


@pytest.fixture(scope='module')
def day():
    """Eight hours at the paper's dock (Pillar Point's mixed tide: a slack water and a
    mid-tide), its slow truth."""
    scene = nd.paper_scene('radar_1cm', days=HOURS / 24.0, mean_depth=18.3)
    return scene, nd.coarse(scene)


def _readings(scene, c, gauge, seed=3, t=None):
    g = nd.GAUGES[gauge]
    s = nd.Scene(scene.name, scene.params, scene.port, g, scene.seconds, scene.mean_depth,
                 scene.weather, scene.cells, (), scene.start_ns, scene.seed,
                 scene.grid)  # fmt: skip
    if t is None:
        t = 0.35 + np.arange(0.0, scene.seconds - 1.0, g.period)
    return t, ndl.gauge_levels(s, c, t, np.random.default_rng(seed))


def _config(scene, gauge, with_table, **alarm):
    if with_table:
        alarm['tide_table'] = scene.flat['tide_table']
        alarm.setdefault('tide_table_epoch', scene.flat['tide_table_epoch'])
    alarm.setdefault('depth_resolution', nd.GAUGES[gauge].resolution)
    line = LineConfig(name='line_01', weight=1300.0, anchor_distance=300.0, mbl=6e6)
    return MonitorConfig(lines=(line,), alarm=AlarmConfig(**alarm))


def depth_codes(cfg, start_s, t, v, tick=10.0):
    """The depth sensor state (code) at a tick every ``tick`` s over readings ``v`` [m] taken
    at ``t`` [s after start_s], by the core's rules as it steps them (the tide trend, then the
    depth memory at each reading; the decision at the ticks): (tick times [s], codes)."""
    a = cfg.alarm
    ns = int(round(start_s * 1e9)) + np.rint(t * 1e9).astype(np.int64)
    stamps = start_s + t
    trend, mem = tide_trend.TrendState(), sensor_state.DepthMemory()
    mems = []
    for stamp_ns, stamp, value in zip(ns.tolist(), stamps.tolist(), v.tolist()):
        trend = tide_trend.step(trend, stamp_ns, value, a.tide_trend_window)
        mem = sensor_state.sample_depth(mem, stamp, value, a, trend.rate, a.stamp_jitter)
        mems.append(mem)
    ticks = np.arange(tick, float(t[-1]), tick)
    j = np.searchsorted(t, ticks, 'right') - 1
    now = start_s + ticks
    changed, spiked, sea = sensor_state.sea_columns([mems[i] for i in j.tolist()])
    codes = sensor_state.decide_depth(
        a, now, v[j], stamps[j], changed, spiked, sea, np.full(len(now), -math.inf)
    )
    return ticks, codes


@pytest.mark.parametrize('gauge', ['radar_1cm', 'pressure_1mm', 'exact_1mm'])
@pytest.mark.parametrize('with_table', [True, False])
def test_a_moving_gauge_is_never_stuck_nor_spiked_on_a_normal_day(day, gauge, with_table):
    """Every gauge, with and without the tide table, at its true resolution and at a finer
    configured one (1 mm for the 1 cm radar: the gauge's own step counts): no state but ok."""
    scene, c = day
    t, v = _readings(scene, c, gauge)
    for res in {nd.GAUGES[gauge].resolution, 0.001}:
        cfg = _config(scene, gauge, with_table, depth_resolution=res)
        _, codes = depth_codes(cfg, scene.start_s, t, v)
        bad = codes != sensor_state.OK
        assert not bad.any(), (res, np.unique(codes[bad]), np.flatnonzero(bad)[:5] * 10.0)


@pytest.mark.parametrize('with_table', [True, False])
def test_a_frozen_gauge_is_found_once_the_tide_moves(day, with_table):
    """The radar frozen at two times of the scene (mid-tide and near the slack water): found
    within the design's delays (with the table < 1 h; without, < 1 h at mid-tide and at most
    depth_still_max near slack water), held until it moves again."""
    scene, c = day
    t, v = _readings(scene, c, 'radar_1cm')
    cfg = _config(scene, 'radar_1cm', with_table)
    delays = []
    for at in (1.5 * 3600.0, 4.5 * 3600.0):
        frozen = v.copy()
        frozen[t >= at] = v[t < at][-1]
        ticks, codes = depth_codes(cfg, scene.start_s, t, frozen)
        stuck = (codes == sensor_state.STUCK) & (ticks >= at)
        assert not (codes[ticks < at] != sensor_state.OK).any()
        assert stuck.any(), f'frozen at {at} s not found'
        first = ticks[np.argmax(stuck)]
        assert stuck[ticks >= first].all()  # held while frozen
        delays.append(first - at)
    if with_table:
        assert max(delays) < 3600.0, delays
    else:
        assert min(delays) < 3600.0 and max(delays) <= cfg.alarm.depth_still_max, delays


def test_double_reads_of_a_noisy_gauge_are_no_spikes_a_glitch_is_one(day):
    """The pressure gauge's 2 mm noise on readings 1.8 ms apart (a driver's retried poll), at
    their header stamps: no spike (the old threshold, rate x dt + resolution without the
    bunching, called some of them spikes); a 2 m glitch is one spike, held sensor_hold."""
    scene, c = day
    g = nd.GAUGES['pressure_1mm']
    t = np.sort(np.concatenate([np.arange(0.35, 3 * 3600.0, 1.0),
                                np.arange(100.35, 3 * 3600.0, 97.0) + 0.0018]))  # fmt: skip
    _, v = _readings(scene, c, 'pressure_1mm', seed=5, t=t)
    dt, dv = np.diff(t), np.abs(np.diff(v))
    assert (dv > 1.0 * dt + g.resolution).sum() >= 3  # the old threshold's spikes
    cfg = _config(scene, 'pressure_1mm', True)
    ticks, codes = depth_codes(cfg, scene.start_s, t, v)
    assert not (codes != sensor_state.OK).any(), np.unique(codes)
    glitch = v.copy()
    i = int(np.searchsorted(t, 2 * 3600.0))
    glitch[i] += 2.0
    ticks, codes = depth_codes(cfg, scene.start_s, t, glitch)
    spike = codes == sensor_state.SPIKE
    assert spike.any() and not (codes[~spike] != sensor_state.OK).any()
    on = ticks[spike]
    assert on[0] >= t[i] and on[-1] - on[0] <= cfg.alarm.sensor_hold + 10.0  # one spike


def test_the_noise_estimate_follows_the_gauge():
    """The depth memory's online noise (mean absolute successive difference, time constant
    spike_noise_time) of white noise sigma: about sigma x 2 / sqrt(pi) after a few time
    constants; spikes do not enter it, nor the quantum, nor the day's range."""
    rng = np.random.default_rng(4)
    cfg = AlarmConfig(spike_noise_time=60.0)
    mem = sensor_state.DepthMemory()
    for k in range(1200):
        x = 10.0 + rng.normal(0.0, 0.002) + (3.0 if k == 900 else 0.0)
        mem = sensor_state.sample_depth(mem, float(k), x, cfg, math.nan, 0.25)
    assert 0.7 < mem.noise / (0.002 * 2 / math.sqrt(math.pi)) < 1.3, mem.noise
    assert mem.spiked == 901.0  # the glitch and the return: spikes, not in the memory's range
    _, _, sea = sensor_state.sea_columns([mem])
    assert sea.seen[0] < 0.05 and 0.0 < sea.quantum[0] < 0.001


def test_a_gateway_drop_is_one_cause_a_silent_cell_its_own():
    scene = nd.paper_scene('radar_1cm', days=0.02, mean_depth=18.3,
                           faults=(nd.Fault('gateway_drop', 600.0, 15.0),
                                   nd.Fault('silent_cell', 900.0, 600.0, 'line_04')))  # fmt: skip
    streams, _, _ = ndl.cell_streams(scene, nd.coarse(scene), 0.0, 1700.0,
                                     np.random.default_rng(1))  # fmt: skip

    def last_before(now):
        return np.array([float(s.log_ns[s.log_ns <= scene.start_ns + now * 1e9][-1])
                         for s in streams]) * 1e-9 - scene.start_s  # fmt: skip

    def grouped(now):
        last = last_before(now)[None, :]
        return common_cause(last, np.array([now]), np.full(12, 5.0), 1.0, [False] * 12)[0]

    assert grouped(608.0).all()  # the gateway's twelve lines: one cause
    assert not grouped(910.0).any()  # line_04 alone: its own alarm
    assert silent_groups(last_before(910.0), last_before(910.0) < 905.0, 1.0) == [[3]]


def test_first_out_is_the_first_still_active():
    raises = [(10.0, 'sensors'), (55.0, 'line_11'), (56.0, 'line_10')]
    assert first_out(raises, ['line_11', 'line_10']) == ('line_11', 55.0)


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
    # the lines bound the depth far below the lowest water (a gauge's datum or scale fault),
    # a quarter above their deepest lift depth
    assert 0.3 < lo < 0.1 * float(np.min(c.depth)) and hi > float(np.max(c.depth)) + 5.0


def test_the_depth_column_loop_is_the_scalar_sample():
    """The twin's one loop over a window's depths (depth_samples) gives the memory and the sea
    columns that sample_depth reading by reading and sea_columns give: a gauge on a 1 cm grid
    over two days (the hours' window full), with glitches, NaNs, repeated stamps and a
    memory carried in."""
    rng = np.random.default_rng(7)
    n = 6000
    t = np.sort(rng.uniform(0.0, 2.2 * 86_400.0, n))
    t[100:104] = t[100]
    v = np.round(12.0 + 1.5 * np.sin(t / 7000.0) + rng.normal(0.0, 0.004, n), 2)
    v[rng.integers(0, n, 25)] += 4.0
    v[rng.integers(0, n, 25)] = math.nan
    rates = rng.normal(0.0, 1e-4, n).tolist()
    cfg = AlarmConfig(depth_resolution=0.01, spike_noise_time=120.0)
    start = sensor_state.DepthMemory()
    for k in range(50):  # a memory carried in from an earlier window
        start = sensor_state.sample_depth(start, k - 50.0, 12.0, cfg, 0.0, 0.25)
    mems = [start]
    for s, x, r in zip(t.tolist(), v.tolist(), rates):
        mems.append(sensor_state.sample_depth(mems[-1], s, x, cfg, r, 0.25))
    (ch, sp, sea), mem = sensor_state.depth_samples(
        start, t.tolist(), v.tolist(), cfg, rates, 0.25
    )
    assert mem == mems[-1]
    want_ch, want_sp, want = sensor_state.sea_columns(mems)
    assert ch.tolist() == want_ch.tolist() and sp.tolist() == want_sp.tolist()
    for got, expected in zip(sea, want):
        assert got.dtype == expected.dtype and np.array_equal(got, expected, equal_nan=True)
    assert want.seen_day.any() and not want.seen_day.all() and np.isfinite(want_sp).any()
    (_, _, empty), same = sensor_state.depth_samples(start, [], [], cfg, [], 0.25)
    assert same is start and len(empty.quantum) == 1


def test_steps_on_the_gauges_grid_are_seen_by_rounding():
    """A 1 cm radar's depths (gauge height - a float32 range) lie on the centimetre grid within
    a float's last bit: ``floor(x / 0.01)`` puts about a third of the neighbouring steps in
    one bin (the gauge looked still while it stepped); the memory's ``round`` sees every step,
    in the scalar sample and the column loop alike."""
    depth = np.round(np.arange(17.5, 19.5, 0.01), 2)
    ranges = (26.443 - depth).astype(np.float32)
    readings = 26.443 - ranges.astype(np.float64)
    assert np.sum(np.diff(np.floor(readings / 0.01)) == 0) > 0.2 * len(depth)
    stamps = np.arange(len(readings)) * 100.0
    ch, _, _ = sensor_state.samples(sensor_state.Memory(), stamps, readings, 0.01, 1.0, 0.25)
    assert ch.tolist() == stamps.tolist()
    mem, cfg = sensor_state.DepthMemory(), AlarmConfig(depth_resolution=0.01)
    for s, x in zip(stamps.tolist(), readings.tolist()):
        mem = sensor_state.sample_depth(mem, s, x, cfg, math.nan, 0.25)
        assert mem.changed == s


def test_intake_warns_on_a_loss_to_act_on():
    assert intake_status(7637, 3, math.nan, 60.0)[0] == Level.OK
    assert intake_status(19, 1, math.nan, 60.0)[0] == Level.ERROR  # 5 %: ERROR as ever
    assert intake_status(7440, 200, math.nan, 60.0)[0] == Level.WARN
    assert intake_status(7640, 9, math.nan, 60.0)[0] == Level.OK  # 9 < intake_warn_count


@pytest.mark.parametrize('with_table', [True, False])
def test_the_twin_decides_the_sea_rules_as_the_core(day, with_table):
    """The radar over 1.5 h of a rising tide, a 2 m glitch at 10 min, frozen from 15 min: the
    twin (over windows cut anywhere) leaves the core's states and memories, the depth
    memory's hourly range, noise, quantum and rate included; both find the spike and the
    stuck gauge. (A line without tension: the depth sensor's rules are the test.)"""
    scene, c = day
    t, v = _readings(scene, c, 'radar_1cm')
    begin = 3 * 3600.0  # the scene's hour 3: mid-tide, rising
    keep = (t >= begin) & (t < begin + 5400.0)
    t, v = t[keep] - begin, v[keep].copy()
    v[t >= 900.0] = v[t < 900.0][-1]
    v[600] += 2.0
    shift = T0_NS * 1e-9 - (scene.start_s + begin)  # the test's clock against the scene's
    epoch = scene.flat['tide_table_epoch'] + shift
    cfg = _config(scene, 'radar_1cm', with_table, tide_trend_window=600.0, tide_table_epoch=epoch)
    cols = {'line_01': (np.zeros(0, np.int64), np.zeros(0))}
    dep = (T0_NS + np.rint(t * 1e9).astype(np.int64), v)
    cuts = [T0_NS + int(x * 1e9) for x in (601.5, 1700.2, 3000.0)]
    steps = compare(cfg, cols, dep, ticks_for(cols, dep), cuts)
    words = [
        dict(st.values)['sensor_state']
        for s in steps
        if s.snapshot is not None
        for st in s.snapshot.statuses
        if st.name.endswith(': tide')
    ]
    assert {'spike', 'stuck', 'ok'} <= set(words), set(words)


def test_the_table_in_the_scene_is_the_generated_tide(day):
    """The params file's table is the scene's tide (the stuck rule's forecast): the table the
    with-table tests use parses and has the port's constituents."""
    scene, _ = day
    assert len(parse_table(scene.flat['tide_table'])) >= 5


def test_the_study_keeps_only_the_rules_to_come():
    """The prototypes now in the core are gone from the study (no duplicate to drift)."""
    for name in ('stuck_gauge', 'tide_motion', 'last_steps', 'spike_threshold',
                 'noise_estimate', 'intake_level', 'hidden_steps'):  # fmt: skip
        assert not hasattr(sr, name), name


def test_an_hour_of_the_radar_replayed_annunciates_no_tide_nor_intake(tmp_path):
    """The bench's path end to end: an hour at the paper's dock (Pillar Point, the radar of
    1 cm at 1 cm, the table in the params file), written as the node logs it and replayed: no
    tide or intake status leaves OK (the old rule warned 'stuck' about 10 times an hour)."""
    from catenary_monitor_study.bench_alarms import replay_counts

    scene = nd.paper_scene('radar_1cm', days=1 / 24, mean_depth=18.3)
    facts = ndl.write_scene(scene, tmp_path)
    counter, _ = replay_counts(facts.log, facts.params)
    heard = [(a.status, a.message) for a in counter.heard()]
    assert not [h for h in heard if h[0].endswith(('tide', 'intake'))], heard
