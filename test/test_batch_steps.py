"""The replay's C loops (catenary_monitor/core/monitor/_twin_loops.c) against twin.py's numpy
passes.

The step merge and the picks must give the same arrays (values, dtypes) either way; the
core-agreement tests of test_batch.py also run here on the numpy path (they run on the C path
in their own file).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_batch import (  # noqa: F401 - rerun on the numpy path
    test_advance_equals_the_core_on_a_storm_with_dropouts,
    test_advance_in_several_windows_equals_one_core,
    test_coincident_times_and_synthetic_ticks_and_on_delay,
    test_late_first_depth_and_lines_without_tension,
    test_random_schedules_with_equal_stamps,
)

import catenary_monitor.core.monitor.twin as twin

STEPS = twin._loops


@pytest.fixture(autouse=True)
def numpy_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every test of this file starts on the numpy path (the imported ones stay there)."""
    monkeypatch.setattr(twin, '_loops', None)


def _both(fn, *args):
    twin._loops = None
    slow = fn(*args)
    twin._loops = STEPS
    try:
        fast = fn(*args)
    finally:
        twin._loops = None
    return fast, slow


@pytest.mark.c_extension
def test_the_c_loops_are_built() -> None:
    assert (
        STEPS is not None
    ), 'core/monitor/_twin_loops.c is not built: python setup.py build_ext --inplace'


@pytest.mark.c_extension
def test_merge_matches_numpy_with_ties_and_empty_columns() -> None:
    rng = np.random.default_rng(3)
    for trial in range(300):
        cols = []
        for _ in range(3):
            n = int(rng.integers(0, 40)) if trial % 5 else 0
            cols.append(np.sort(rng.integers(0, 30, n)).astype(np.int64))  # many equal stamps
        (tf, kf), (ts, ks) = _both(twin._merge, *cols)
        assert np.array_equal(tf, ts) and np.array_equal(kf, ks)
        assert tf.dtype == ts.dtype and kf.dtype == ks.dtype


@pytest.mark.c_extension
def test_merge_refuses_unsorted_columns() -> None:
    """(twin._merge then takes its numpy path, whose contract is sorted columns too.)"""
    dd, tt, kk = np.array([5, 1], np.int64), np.array([2, 3], np.int64), np.zeros(0, np.int64)
    assert not STEPS.merge3(dd, tt, kk, np.empty(4, np.int64), np.empty(4, np.int8), 0, 1, 2)


@pytest.mark.c_extension
def test_pick_matches_numpy() -> None:
    rng = np.random.default_rng(4)
    for trial in range(200):
        n, m = int(rng.integers(0, 30)), int(rng.integers(0, 30))
        column = rng.normal(size=m)
        column[rng.random(m) < 0.2] = np.nan
        idx = np.sort(rng.integers(-1, m, n)) if m else np.full(n, -1)
        for before in (float('nan'), 2.5, 7, True, np.float64(-1.0)):
            fast, slow = _both(twin._pick, idx.astype(np.int64), column, before)
            assert fast.dtype == slow.dtype
            assert np.array_equal(fast, slow, equal_nan=True)
    with pytest.raises(IndexError):
        STEPS.pick(np.array([3], np.int64), np.zeros(3), 0.0, np.empty(1))


@pytest.mark.c_extension
def test_latch_matches_the_scalar_step_and_numpy(monkeypatch: pytest.MonkeyPatch) -> None:
    """alarms._latch_series in C and in numpy equal repeated alarms._step, from latches up or
    down, pending (since a past update's stamp) or not, through equal stamps and zero delays."""
    from catenary_monitor.core.monitor import alarms

    rng = np.random.default_rng(5)
    for trial in range(2000):
        n = int(rng.integers(1, 50))
        t = 10.0 + np.cumsum(rng.choice([0.0, 0.3, 1.0, 2.5], n))
        codes = rng.choice(3, n, p=rng.dirichlet([1, 1, 1])).astype(np.int8)
        since = None if trial % 2 else float(t[0] - rng.uniform(0.0, 4.0))
        start = alarms.Latch(bool(trial % 3 == 0), since)
        on_delay, hold = float(rng.choice([0.0, 0.5, 2.0])), float(rng.choice([0.0, 1.0, 3.0]))
        latch, want = start, []
        for code, now in zip(codes.tolist(), t.tolist()):
            latch = alarms._step(latch, code, now, on_delay, hold)
            want.append(latch.active)
        for steps in (STEPS, None):
            monkeypatch.setattr(alarms, '_loops', steps)
            active, end = alarms._latch_series(codes, t, on_delay, hold, start)
            assert active.dtype == bool and active.tolist() == want, (trial, steps)
            assert end == latch, (trial, steps)
    with pytest.raises(ValueError):
        STEPS.latch(np.zeros(3, np.int8), np.zeros(2), 0.0, 0.0, False, np.nan, np.empty(3, bool))


@pytest.mark.c_extension
def test_line_steps_match_numpy() -> None:
    """twin._line_steps' C loop (every newest index, solved, in one pass) equals its cumulative
    sums, with and without a tension known before the window, empty columns and equal stamps."""
    rng = np.random.default_rng(6)
    for trial in range(300):
        cols = [
            np.sort(rng.integers(0, 30, int(rng.integers(0, 25)))).astype(np.int64)
            for _ in range(3)
        ]
        tension = (cols[1], rng.normal(1e6, 1e4, len(cols[1])))
        window = twin.Window([tension], (cols[0], rng.normal(20.0, 1.0, len(cols[0]))), cols[2])
        line = type('Line', (), {'tension_s': np.nan if trial % 2 else 3.0})()
        fast, slow = _both(twin._line_steps, line, cols[1], window)
        for name in fast.__dataclass_fields__:
            a, b = getattr(fast, name), getattr(slow, name)
            assert a.dtype == b.dtype and np.array_equal(a, b), (trial, name)
    with pytest.raises(ValueError):
        STEPS.newest(
            np.array([7], np.int8),
            0,
            1,
            2,
            False,
            *[np.empty(1, np.int64)] * 4,
            np.empty(1, bool),
            np.empty(1, np.int64),
        )


@pytest.mark.c_extension
def test_sensor_samples_match_numpy_and_the_scalar_sample(monkeypatch: pytest.MonkeyPatch) -> None:
    """sensor_state.samples in C and in numpy equal repeated sensor_state.sample, memory included:
    steps within and across the resolution, spikes, non-finite readings, equal stamps, a fresh
    memory (NaN reading, never changed) and one with history."""
    from catenary_monitor.core.monitor import sensor_state

    assert sensor_state._loops is STEPS
    rng = np.random.default_rng(9)
    for trial in range(600):
        n = int(rng.integers(0, 40))
        stamps = 100.0 + np.cumsum(rng.choice([0.0, 0.05, 0.5, 3.0], n))
        values = 1e5 + np.cumsum(rng.choice([0.0, 3.0, -40.0, 2e4], n))
        bad = rng.random(n) < 0.15
        values[bad] = rng.choice([np.nan, np.inf, -np.inf], int(bad.sum()))
        mem = sensor_state.Memory() if trial % 2 else sensor_state.Memory(1e5, 99.0, 50.0, -np.inf)
        resolution = float(rng.choice([0.0, 10.0, 100.0]))
        want_ch, want_sp, m = [], [], mem
        for stamp, value in zip(stamps.tolist(), values.tolist()):
            m = sensor_state.sample(m, stamp, value, resolution, 500.0, 0.1)
            want_ch.append(m.changed)
            want_sp.append(m.spiked)
        for loops in (sensor_state._loops, None):
            monkeypatch.setattr(sensor_state, '_loops', loops)
            ch, sp, end = sensor_state.samples(mem, stamps, values, resolution, 500.0, 0.1)
            assert ch.tolist() == want_ch and sp.tolist() == want_sp, (trial, loops)
            assert end == m, (trial, loops)


@pytest.mark.c_extension
def test_uplift_times_match_numpy_and_the_scalar(monkeypatch: pytest.MonkeyPatch) -> None:
    """tide_trend.uplift_times in C and in numpy equal time_to_uplift element by element:
    lifted, falling or unknown tides, NaN margins and excesses, signed zeros, infinities."""
    from catenary_monitor.core.monitor import tide_trend

    assert tide_trend._loops is STEPS
    rng = np.random.default_rng(10)
    odd = [np.nan, np.inf, -np.inf, 0.0, -0.0, 1e-300]
    n = 4000
    cols = [
        rng.normal(0.5, 1.0, n),
        rng.choice([0.0, 0.0, 5e3], n),
        rng.normal(1e-4, 1e-4, n),
        rng.normal(0.0, 0.2, n),
    ]
    for c in cols:
        hit = rng.random(n) < 0.1
        c[hit] = rng.choice(odd, int(hit.sum()))
    want = [tide_trend.time_to_uplift(*v) for v in zip(*(c.tolist() for c in cols))]
    for loops in (STEPS, None):
        monkeypatch.setattr(tide_trend, '_loops', loops)
        got = tide_trend.uplift_times(*cols)
        assert np.array_equal(got, want, equal_nan=True), loops
        number = ~np.isnan(got)
        assert np.array_equal(np.signbit(got[number]), np.signbit(np.array(want)[number]))
