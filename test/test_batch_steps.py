"""The twin's C loops (catenary_monitor/core/twin/_twin_loops.c) against schedule.py's numpy
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

import catenary_monitor.core.twin.schedule as twin
from catenary_monitor.core.twin.window import Window

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
    ), 'core/twin/_twin_loops.c is not built: python setup.py build_ext --inplace'


@pytest.mark.c_extension
def test_merge_matches_numpy_with_ties_and_empty_columns() -> None:
    rng = np.random.default_rng(3)
    for trial in range(300):
        cols = []
        for _ in range(3):
            n = int(rng.integers(0, 40)) if trial % 5 else 0
            cols.append(np.sort(rng.integers(0, 30, n)).astype(np.int64))  # many equal stamps
        (tf, kf), (ts, ks) = _both(twin.merge, *cols)
        assert np.array_equal(tf, ts) and np.array_equal(kf, ks)
        assert tf.dtype == ts.dtype and kf.dtype == ks.dtype


@pytest.mark.c_extension
def test_merge_refuses_unsorted_columns() -> None:
    """(twin.merge then takes its numpy path, whose contract is sorted columns too.)"""
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
            fast, slow = _both(twin.pick, idx.astype(np.int64), column, before)
            assert fast.dtype == slow.dtype
            assert np.array_equal(fast, slow, equal_nan=True)
    with pytest.raises(IndexError):
        STEPS.pick(np.array([3], np.int64), np.zeros(3), 0.0, np.empty(1))


@pytest.mark.c_extension
def test_line_steps_match_numpy() -> None:
    """twin.line_steps' C loop (every newest index, solved, in one pass) equals its cumulative
    sums, with and without a tension known before the window, empty columns and equal stamps."""
    rng = np.random.default_rng(6)
    for trial in range(300):
        cols = [
            np.sort(rng.integers(0, 30, int(rng.integers(0, 25)))).astype(np.int64)
            for _ in range(3)
        ]
        tension = (cols[1], rng.normal(1e6, 1e4, len(cols[1])))
        window = Window([tension], (cols[0], rng.normal(20.0, 1.0, len(cols[0]))), cols[2])
        line = type('Line', (), {'tension_s': np.nan if trial % 2 else 3.0})()
        fast, slow = _both(twin.line_steps, line, cols[1], window)
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
