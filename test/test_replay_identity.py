"""The vectorized twin's kernels: its solve is ``solve()`` on arrays bit for bit, one row per
tension message, and the latch fast path. (The twin against the core itself: test_batch.py.)"""

import numpy as np
from replay_data import dock_config, generate

from catenary_monitor.core.rules.holding import FIELDS as HOLDING
from catenary_monitor.core.rules.channels import FIELDS as CHANNELS
from catenary_monitor.core.rules.fatigue import FIELDS as FATIGUE
from catenary_monitor.core.rules.holding import DRAG_FIELDS, LENGTH_FIELDS
from catenary_monitor.core.twin.window import KIND_TENSION
from catenary_monitor.core.monitor.state import NO_DEPTH, VALUE_FIELDS
from catenary_monitor.core.twin.solve_columns import critical_parameters, solve_updates
from catenary_monitor.core.twin.engine import recompute
from catenary_monitor.core.rules.uncertainty import FIELDS as BOUNDS
from catenary_monitor.core.physics.solve import solve

DERIVED = BOUNDS + HOLDING + LENGTH_FIELDS + DRAG_FIELDS + FATIGUE + CHANNELS  # monitor's
DERIVED += ('wave_tension', 'peak_tension', 'dynamic_uplift', 'time_to_uplift_view')
DERIVED += ('span', 'span_source')  # the span solved at, set by the monitor


def test_solve_updates_is_bit_identical_to_solve_on_arrays():
    config = dock_config(2)
    rng = np.random.default_rng(3)
    t = rng.uniform(-1e5, 3e6, 5000)
    t[::97] = np.nan
    h = rng.uniform(-1.0, 30.0, 5000)
    for line in config.lines:
        a = critical_parameters(line, h)
        got, status = solve_updates(line, t, h, a)
        ref = solve(
            np.full(t.size, line.weight),
            h,
            tension=t,
            anchor_distance=np.full(t.size, line.anchor_distance),
            mbl=np.full(t.size, line.mbl),
        )
        assert status.tolist() == ref.status.tolist()
        assert (status == 0).sum() > 1000 and (ref.uplift_force > 0).sum() > 100
        for key in VALUE_FIELDS:
            if key in ('depth', 'time_to_uplift', 'sensor_state') or key in DERIVED:  # not solved
                continue
            if key == 'top_tension':  # the measured input, also where it could not be solved
                np.testing.assert_array_equal(got[key], t)
                continue
            np.testing.assert_array_equal(got[key], getattr(ref, key), err_msg=key)


def test_rows_per_tension_message():
    config = dock_config(2)
    tensions, depth = generate(config, seconds=30.0, seed=9)
    rep = recompute(config, tensions, depth)
    for res in rep.lines:
        rows = res.tension_rows
        assert len(rows) == len(tensions[res.name][0])
        assert (res.kind[rows] == KIND_TENSION).all()
        np.testing.assert_array_equal(
            res.values['top_tension'][rows][res.status[rows] == 0],
            tensions[res.name][1][res.status[rows] == 0],
        )


def test_latch_fast_path_without_breach():
    """alarms._latch_series returns at once when no update breaches (most conditions of most
    lines in a real log); it equals the scalar latch step, with and without breaches."""
    from catenary_monitor.core.alarms import latches as alarms

    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0, 1, 400))
    cases = [
        rng.choice([alarms._HOLD, alarms._CLEAR], 400),
        np.full(400, alarms._CLEAR),
        np.full(400, alarms._HOLD),
        rng.choice([alarms._HOLD, alarms._CLEAR, alarms._BREACH], 400),
    ]
    for codes in cases:
        codes = codes.astype(np.int8)
        latch, want = alarms.Latch(), []
        for c, now in zip(codes.tolist(), t.tolist()):
            latch = alarms._step(latch, c, now, 0.5, 3.0)
            want.append(latch.active)
        assert alarms._latch_series(codes, t, 0.5, 3.0)[0].tolist() == want


def test_solve_updates_of_an_elastic_line_is_elastic_solve():
    """A line with ``ea``: replay solves it with ``elastic.solve_with_correction``, as the core."""
    from dataclasses import replace

    from catenary_monitor.core.physics import elastic

    line = replace(dock_config(2).lines[1], ea=6.6e8)
    rng = np.random.default_rng(4)
    t = rng.uniform(-1e5, 3e6, 3000)
    t[::97] = np.nan
    h = rng.uniform(-1.0, 30.0, 3000)
    h[:10] = np.nan  # before the first depth
    got, status = solve_updates(line, t, h, critical_parameters(line, h))
    ref, _ = elastic.solve_with_correction(
        line.weight, h, t, anchor_distance=line.anchor_distance, ea=line.ea, mbl=line.mbl
    )
    assert (
        status[:10].tolist() == [NO_DEPTH] * 10
        and status[10:].tolist() == ref.status[10:].tolist()
    )
    assert (ref.model[10:][status[10:] == 0] == elastic.ELASTIC).all() and (
        ref.uplift_force[10:] > 0
    ).sum() > 100
    for key in VALUE_FIELDS:
        if key in ('time_to_uplift', 'sensor_state') or key in DERIVED:  # not the solver's
            continue
        if key in ('depth', 'top_tension'):  # the measured inputs, also where unsolved
            np.testing.assert_array_equal(got[key], h if key == 'depth' else t)
            continue
        np.testing.assert_array_equal(got[key][10:], getattr(ref, key)[10:], err_msg=key)
        assert np.isnan(got[key][:10]).all()
