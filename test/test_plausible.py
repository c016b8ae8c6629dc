"""The plausibility bounds of a reading (core/rules/plausible.py): scalar and array alike, and
the status sentences name the bounds the code applies."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catenary_monitor.core.rules.plausible import (
    MAX_DEPTH,
    MAX_TENSION_PER_MBL,
    reading_status,
    reading_status_array,
)
from catenary_monitor.core.physics.result import STATUS_MESSAGES, Status

MBL = 4.827e6


@pytest.mark.parametrize(
    'tension, depth, code',
    [
        (400e3, 20.85, 0),
        (MAX_TENSION_PER_MBL * MBL, 20.85, 0),  # the bound itself is plausible
        (math.nextafter(MAX_TENSION_PER_MBL * MBL, math.inf), 20.85, Status.IMPLAUSIBLE_TENSION),
        (1e300, 20.85, Status.IMPLAUSIBLE_TENSION),
        (400e3, MAX_DEPTH, 0),
        (400e3, 1e6, Status.IMPLAUSIBLE_DEPTH),
        (1e300, 1e6, Status.IMPLAUSIBLE_DEPTH),  # the depth wins
        (math.inf, 20.85, 0),  # non-finite: the solver's NON_FINITE
        (math.nan, 1e6, 0),
        (-5.0, 20.85, 0),  # too small: the solver's own rules
    ],
)
def test_scalar_and_array_agree(tension, depth, code):
    assert reading_status(tension, depth, MBL) == code
    assert reading_status_array([tension], [depth], MBL).tolist() == [code]


def test_array_broadcasts_per_line_mbl():
    got = reading_status_array(np.array([[1e8, 1e8]]), np.array([[20.0, 20.0]]), [MBL, 1e9])
    assert got.tolist() == [[Status.IMPLAUSIBLE_TENSION, 0]]


def test_messages_name_the_bounds():
    assert f'{MAX_TENSION_PER_MBL:g} x MBL' in STATUS_MESSAGES[Status.IMPLAUSIBLE_TENSION]
    assert f'{MAX_DEPTH:g} m' in STATUS_MESSAGES[Status.IMPLAUSIBLE_DEPTH]
    assert 'please report' not in STATUS_MESSAGES[Status.IMPLAUSIBLE_TENSION]


def test_array_equals_scalar_on_long_columns():
    """The array form's two-pass shortcut (no value beyond a bound: all plausible) and its full
    path give the scalar's code for every element: rare outliers, NaN and inf among them."""
    rng = np.random.default_rng(8)
    for trial in range(200):
        n = int(rng.integers(1, 300))
        limit = MAX_TENSION_PER_MBL * MBL
        t, h = rng.uniform(0.0, limit, n), rng.uniform(1.0, MAX_DEPTH, n)
        above = (math.nextafter(limit, math.inf), 1e300, np.nan, np.inf, -np.inf)
        for column, odd in ((t, above), (h, (np.nan, np.inf, np.nextafter(MAX_DEPTH, 1e9)))):
            hit = rng.random(n) < (0.02 if trial % 3 else 0.0)
            column[hit] = rng.choice(odd, int(hit.sum()))
        want = [reading_status(a, b, MBL) for a, b in zip(t.tolist(), h.tolist())]
        assert reading_status_array(t, h, MBL).tolist() == want, trial
