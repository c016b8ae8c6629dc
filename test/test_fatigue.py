"""Chain fatigue (core/rules/fatigue.py): the streamed rainflow count against ASTM E1049-85's
worked example and two independent libraries (rainflow, fatpack), the seed's S-N example, the
rate over the last day and the state that survives restarts."""

import math

import numpy as np
import pytest
import rainflow

from catenary_monitor.core.rules import fatigue

#: ASTM E1049-85 (2011) section 5.4.4, Fig. 6 and Table 4: the series and its rainflow count.
ASTM_SERIES = [-2.0, 1.0, -3.0, 5.0, -1.0, 3.0, -4.0, 4.0, -2.0]
ASTM_COUNT = {3.0: 0.5, 4.0: 1.5, 6.0: 0.5, 8.0: 1.0, 9.0: 0.5}


def _stream(values, curve, state=None, t0=0.0, dt=1.0):
    state = fatigue.initial() if state is None else state
    out = []
    for i, v in enumerate(values):
        state, fields = fatigue.step(state, t0 + i * dt, float(v), curve)
        out.append(fields)
    return state, np.array(out)


def _miner(values, curve):
    """Independent: the rainflow library's cycles, each n / N by the S-N curve."""
    total = 0.0
    for rng, _mean, count, _i, _j in rainflow.extract_cycles(list(values)):
        total += count * (rng * curve.stress_per_tension * 1e-6) ** curve.m / 10**curve.log_a
    return total


def test_astm_e1049_worked_example_cycles():
    """The standard's Table 4 from the library (the oracle), and the same histogram from the
    streamed count: sum n r^m for m = 0..5 fixes the counts of the five ranges."""
    got = dict(rainflow.count_cycles(ASTM_SERIES))
    assert got == ASTM_COUNT
    for m in range(6):
        curve = fatigue.Curve(m=float(m), log_a=0.0, stress_per_tension=1e6)  # D = sum n r^m
        state, fields = _stream([v + 10.0 for v in ASTM_SERIES], curve)  # tensions are >= 0
        want = sum(n * r**m for r, n in ASTM_COUNT.items())
        assert fields[-1, 0] == pytest.approx(want, rel=1e-14)
    assert len(state.residue) == 7  # 4.0 closed as a full cycle, the rest half cycles


def test_seed_example_stress_range_and_life():
    """Seed 001: 12 421 kN chain cycling 3726 +- 50 kN (0.3 MBL), S/L 0.0805 MPa/kN: a stress
    range of 8.05 MPa, N = 10^13.6451 / 8.05^3.36 = 3.996e10 cycles; k cycles give k / N."""
    curve = fatigue.Curve()
    assert (curve.m, curve.log_a, curve.stress_per_tension) == (3.36, 13.6451, 80.5)
    assert fatigue.SEED_MBL * 0.3 == pytest.approx(3726.3e3)
    delta_sigma = curve.stress_per_tension * 100e3 / 1e6
    assert delta_sigma == pytest.approx(8.05)
    cycles_to_failure = 10**13.6451 / delta_sigma**3.36
    assert cycles_to_failure == pytest.approx(3.996e10, rel=1e-3)
    k = 1000
    series = [3676e3, 3776e3] * k + [3676e3]
    _, fields = _stream(series, curve)
    assert fields[-1, 0] == pytest.approx(k / cycles_to_failure, rel=1e-12)
    assert fatigue.cycle_damage(100e3, curve) == pytest.approx(1 / cycles_to_failure, rel=1e-14)


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_random_history_equals_independent_rainflow_and_miner(seed):
    rng = np.random.default_rng(seed)
    x = np.abs(2e6 + np.cumsum(rng.normal(0.0, 3e4, 5000)) + rng.normal(0.0, 5e3, 5000))
    curve = fatigue.Curve()
    out, state = fatigue.series(fatigue.initial(), np.arange(x.size) * 0.5, x, curve)
    ref = _miner(x, curve)
    assert out['fatigue_damage'][-1] == pytest.approx(ref, rel=1e-9)
    # every prefix too (the streamed damage is the whole count of the series so far)
    for n in (3, 17, 333, 2500):  # (the library yields no cycle for two points)
        assert out['fatigue_damage'][n - 1] == pytest.approx(_miner(x[:n], curve), rel=1e-9)


def test_fatpack_agrees_on_closed_cycles():
    """fatpack (a second library; its own reversals are binned, so it is handed the exact
    ones) closes the same full cycles and leaves the same residue."""
    fatpack = pytest.importorskip('fatpack')
    rng = np.random.default_rng(7)
    x = 1e6 + rng.normal(0.0, 1e5, 3000)
    curve = fatigue.Curve()
    reversals = np.array([v for _, v in rainflow.reversals(list(x))])
    cycles, residue = fatpack.find_rainflow_cycles(reversals)
    closed = sum(fatigue.cycle_damage(b - a, curve) for a, b in cycles)
    state, _ = _stream(x, curve)
    assert state.closed == pytest.approx(closed, rel=1e-9)
    assert np.array_equal(np.array(state.residue), residue)
    assert state.closed + sum(state.halves) == pytest.approx(_miner(x, curve), rel=1e-9)


def test_windows_restarts_and_the_c_loop_equal_one_stream():
    rng = np.random.default_rng(11)
    x = 3e6 + rng.normal(0.0, 2e5, 4000)
    x[100] = math.nan  # skipped, as a negative reading
    x[200] = -5.0
    t = np.arange(x.size) * 2.0
    curve = fatigue.Curve(3.0, 12.0, 50.0)
    whole, end = fatigue.series(fatigue.initial(0.25), t, x, curve)
    state, parts = fatigue.initial(0.25), []
    for lo, hi in ((0, 1), (1, 999), (999, 1000), (1000, 4000)):
        out, state = fatigue.series(state, t[lo:hi], x[lo:hi], curve)
        parts.append(out['fatigue_damage'])
    assert np.array_equal(np.concatenate(parts), whole['fatigue_damage'])
    assert state == end
    # the scalar step (the live core) gives the same bits as series (the C loop where built)
    scalar, fields = _stream(x, curve, fatigue.initial(0.25), dt=2.0)
    assert scalar == end
    for j, key in enumerate(fatigue.FIELDS):
        assert np.array_equal(fields[:, j], whole[key], equal_nan=True)
    # a restart through the store's record continues the count
    record = fatigue.to_record(fatigue.series(fatigue.initial(0.25), t[:1500], x[:1500], curve)[1])
    back = fatigue.from_record(record, curve)
    assert back is not None
    out, _ = fatigue.series(back, t[1500:], x[1500:], curve)
    assert out['fatigue_damage'][-1] == pytest.approx(whole['fatigue_damage'][-1], rel=1e-12)
    assert whole['fatigue_damage'][0] == 0.25  # starts from the initial damage


def test_rate_over_the_last_day_and_life_left():
    """Constant amplitude at 0.1 Hz: the rate is the cycle's damage x 0.1 once an hour of marks
    is kept (NaN before), the life left (1 - D) / rate."""
    curve = fatigue.Curve()
    hours = 30
    n = hours * 3600 // 5
    x = np.where(np.arange(n) % 2 == 0, 3676e3, 3776e3)
    t = np.arange(n) * 5.0
    out, state = fatigue.series(fatigue.initial(0.5), t, x, curve)
    per_cycle = fatigue.cycle_damage(100e3, curve)
    early = t < fatigue.RATE_MIN_SPAN
    assert np.isnan(out['fatigue_damage_rate'][early]).all()
    assert np.isnan(out['fatigue_life_left'][early]).all()
    assert out['fatigue_damage_rate'][-1] == pytest.approx(per_cycle / 10.0, rel=1e-3)
    d = out['fatigue_damage'][-1]
    assert out['fatigue_life_left'][-1] == pytest.approx((1 - d) / (per_cycle / 10), rel=1e-3)
    assert state.marks[0][0] >= t[-1] - fatigue.RATE_WINDOW - fatigue.MARK_EVERY
    assert len(state.marks) <= fatigue.RATE_WINDOW / fatigue.MARK_EVERY + 2
    assert fatigue.life_left(1.2, 1e-9) == 0.0
    assert fatigue.life_left(0.2, 0.0) == math.inf


def test_residue_is_bounded():
    """A series whose ranges keep growing then shrinking would keep every point: the oldest
    range is counted as a half cycle for good beyond RESIDUE_MAX points."""
    k = np.arange(1, 2000)
    grow = np.where(k % 2 == 0, 1e6 + k * 100.0, 1e6 - k * 100.0)
    x = np.concatenate([grow, 1e6 + (grow[::-1][1:] - 1e6) * 0.999])
    curve = fatigue.Curve()
    out, state = fatigue.series(fatigue.initial(), np.arange(x.size) * 1.0, x, curve)
    assert len(state.residue) <= fatigue.RESIDUE_MAX
    assert out['fatigue_damage'][-1] == pytest.approx(_miner(x, curve), rel=1e-9)


@pytest.mark.parametrize(
    'record',
    [None, [], {'closed': 'x', 'residue': [], 'marks': []}, {'closed': -1.0, 'residue': [],
     'marks': []}, {'closed': 0.1, 'residue': [math.inf], 'marks': []}, {'closed': 0.1}],
)
def test_damaged_records_are_refused(record):
    assert fatigue.from_record(record, fatigue.Curve()) is None


# --- through the monitor: live, replay, the store ------------------------------------------------


def _config(**line):
    from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig

    base = dict(name='ch', weight=1300.0, anchor_distance=120.0, mbl=4.827e6)
    base.update(line)
    return MonitorConfig(lines=(LineConfig(**base),))


def _tensions(n, seed=5):
    rng = np.random.default_rng(seed)
    return 4.0e5 + 6e4 * np.sin(np.arange(n) * 0.7) + rng.normal(0.0, 8e3, n)


def test_the_monitor_counts_every_tension_and_its_replay_agrees():
    """Every tension sample through MonitorCore: fatigue_damage in the outputs is the
    independent rainflow + Miner count of the samples so far (1e-9); the vectorized twin
    (replay) gives the same bits; the seed's curve scaled to this MBL."""
    from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
    from catenary_monitor.core.monitor.events import Depth
    from catenary_monitor.core.monitor.monitor_core import MonitorCore
    from catenary_monitor.core.monitor.events import Tension, Tick
    from catenary_monitor.core.twin.engine import recompute

    config = _config()
    line = config.lines[0]
    assert line.stress_per_tension == pytest.approx(80.5 * 12421e3 / 4.827e6)
    curve = fatigue.Curve.of(line)
    x = _tensions(1500)
    stamps = (np.arange(x.size) + 1) * 500_000_000
    core = MonitorCore(config, 0)
    core.step(Depth(1, 20.85))
    got = []
    for k, (t, v) in enumerate(zip(stamps.tolist(), x.tolist())):
        got.append(dict(zip(OUTPUT_FIELDS, core.step(Tension(t, 0, v)).outputs[0].values)))
        if k % 2:
            core.step(Tick(t + 1))
    damage = np.array([g['fatigue_damage'] for g in got])
    for n in (3, 100, 1499):
        assert damage[n - 1] == pytest.approx(_miner(x[:n], curve), rel=1e-9)
    assert damage[-1] > damage[100] > 0
    replay = recompute(
        config,
        {'ch': (stamps, x)},
        (np.array([1], np.int64), np.array([20.85])),
        tick_ns=stamps[1::2] + 1,
        start_ns=0,
    )
    r = replay.lines[0]
    assert np.array_equal(r.values['fatigue_damage'][r.tension_rows], damage)
    assert core.state.lines[0].fatigue.closed > 0


def test_the_store_carries_the_count_across_a_restart_and_replay_follows(tmp_path):
    """Run, save the store, restart (a new core and the store's FatigueStore event): the count
    goes on as if never stopped; replaying the log's events (Start, FatigueStore) gives the
    restarted core's bits."""
    from catenary_monitor.core.monitor.events import Depth, FatigueStore
    from catenary_monitor.core.monitor.monitor_core import MonitorCore
    from catenary_monitor.core.monitor.events import Start, Tension, event_record
    from catenary_monitor.core.monitor.events import parse_event_record
    from catenary_monitor.core.twin.window import Window
    from catenary_monitor.core.twin.engine import run_log
    from catenary_monitor.io import fatigue_store

    config = _config(fatigue_damage_initial=0.125)
    x = _tensions(1000, seed=9)
    stamps = (np.arange(x.size) + 10) * 10**9
    first = MonitorCore(config, 0)
    first.step(Depth(1, 20.85))
    loaded = fatigue_store.load(tmp_path, ['ch'])
    assert loaded.state == 'new'
    first.step(FatigueStore(2, loaded.state, loaded.message, (('ch', None),)))
    for t, v in zip(stamps[:600].tolist(), x[:600].tolist()):
        first.step(Tension(t, 0, v))
    fatigue_store.save(tmp_path, {'ch': fatigue.to_record(first.state.lines[0].fatigue)})
    loaded = fatigue_store.load(tmp_path, ['ch'])
    assert loaded.state == 'loaded'
    restart = int(stamps[600]) - 5
    event = FatigueStore(restart + 1, 'loaded', loaded.message, (('ch', loaded.lines['ch']),))
    event = parse_event_record(event.stamp_ns, __import__('json').dumps(event_record(event)))
    second = MonitorCore(config, restart)
    second.step(Depth(restart + 2, 20.85))
    second.step(event)
    for t, v in zip(stamps[600:].tolist(), x[600:].tolist()):
        second.step(Tension(t, 0, v))
    whole = _miner(x, fatigue.Curve.of(config.lines[0])) + 0.125
    assert second.state.lines[0].fatigue_values[0] == pytest.approx(whole, rel=1e-9)
    # replay: the same events through the twin
    core = MonitorCore(config, 0)
    window = Window(
        [(stamps, x)],
        (np.array([1, restart + 2], np.int64), np.array([20.85, 20.85])),
        np.zeros(0, np.int64),
    )
    first_event = FatigueStore(2, 'new', 'new', (('ch', None),))
    _, end = run_log(core, window, [first_event, Start(restart), event])
    assert end.state.lines[0].fatigue == second.state.lines[0].fatigue
    assert end.state.lines[0].fatigue_values[0] == second.state.lines[0].fatigue_values[0]
    assert np.isnan(end.state.lines[0].fatigue_values[1:]).all()  # under an hour: no rate


def test_store_states_are_named(tmp_path):
    from catenary_monitor.io import fatigue_store

    record = {'closed': 0.25, 'residue': [1e5, 2e5], 'marks': [[0.0, 0.2]]}
    assert fatigue_store.load(tmp_path / 'none', ['a']).state == 'new'
    (tmp_path / 'catenary_monitor_0.mcap').write_bytes(b'')
    missing = fatigue_store.load(tmp_path, ['a'])
    assert missing.state == 'missing' and 'replay the log folder' in missing.message
    fatigue_store.save(tmp_path, {'a': record})
    fatigue_store.save(tmp_path, {'a': dict(record, closed=0.5)})
    assert fatigue_store.load(tmp_path, ['a', 'b']).lines['a']['closed'] == 0.5
    assert 'b not in it' in fatigue_store.load(tmp_path, ['a', 'b']).message
    (tmp_path / 'chain_fatigue.json').write_text('{"version": 1, "lines": {"a": {"closed": "x"}}')
    damaged = fatigue_store.load(tmp_path, ['a'])
    assert damaged.state == 'damaged' and damaged.lines['a']['closed'] == 0.25  # the copy
    assert (tmp_path / 'chain_fatigue.json.damaged-1').exists()
    (tmp_path / 'chain_fatigue.json.prev').write_text('garbage')
    (tmp_path / 'chain_fatigue.json').write_text('{"version": 1, "lines": {"a": 3}}')
    worse = fatigue_store.load(tmp_path, ['a'])
    assert worse.state == 'damaged' and worse.lines == {}
    assert 'damaged record of a' in worse.message and 'restarted from' in worse.message
    assert (tmp_path / 'chain_fatigue.json.damaged-2').exists()


def test_fatigue_doc_parameter_table_is_generated():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown

    page = (Path(__file__).resolve().parent.parent / 'docs' / 'fatigue.md').read_text()
    begin, end = '<!-- fatigue-parameters:begin -->\n', '<!-- fatigue-parameters:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('fatigue')
