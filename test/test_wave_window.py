"""The wave window (core/rules/wave_window.py): its column form (series, the twin's; its C loop
and its numpy sparse table) against its scalar step (the core's) on random readings in pieces,
invalid ones among them: the same peak and wave tensions after every reading and the same
queues after each piece."""

import math

import numpy as np
import pytest

from catenary_monitor.core.rules import wave_window


@pytest.mark.parametrize('seed', [1, 2, 3])
@pytest.mark.parametrize('loop', ['C', 'numpy'])
def test_series_equals_the_step_reading_by_reading(seed, loop, monkeypatch):
    if loop == 'numpy':
        monkeypatch.setattr(wave_window, '_wave_loop', None)
    elif wave_window._wave_loop is None:
        pytest.skip('the C loop is not built')
    rng = np.random.default_rng(seed)
    n, mbl, window = 3000, 4.8e6, 30.0
    t = np.cumsum(rng.uniform(0.0, 0.2, n))  # equal stamps too
    t[rng.random(n) < 0.05] = 0.0
    t = np.maximum.accumulate(t)
    v = 372e3 + 60e3 * np.sin(t / 1.6) + rng.normal(0, 5e3, n)
    v[rng.random(n) < 0.02] = math.nan
    v[rng.random(n) < 0.01] = -5.0
    v[rng.random(n) < 0.01] = 10 * mbl
    v[rng.random(n) < 0.05] = 372e3  # ties
    one = wave_window.WaveState.empty()
    want = np.array([wave_window.step(one, a, b, mbl, window) for a, b in zip(t, v)])
    state = wave_window.WaveState.empty()
    got, cuts = [], np.sort(rng.choice(np.arange(1, n), 6, replace=False))
    for a, b in zip(np.r_[0, cuts], np.r_[cuts, n]):
        peak, wave, state = wave_window.series(state, t[a:b], v[a:b], mbl, window)
        got.append(np.c_[peak, wave])
    np.testing.assert_array_equal(np.concatenate(got), want)
    assert list(state.high) == list(one.high) and list(state.low) == list(one.low)
    assert state.number == one.number
