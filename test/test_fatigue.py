"""Chain fatigue (core/monitor/fatigue.py): the streamed rainflow count against ASTM E1049-85's
worked example and two independent libraries (rainflow, fatpack), the seed's S-N example, the
rate over the last day and the state that survives restarts."""

import math

import numpy as np
import pytest
import rainflow

from catenary_monitor.core.monitor import fatigue

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
