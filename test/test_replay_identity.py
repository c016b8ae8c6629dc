"""Replay's vectorized recompute gives the live node's alarm transitions, exactly.

The oracle is ``replay_data.simulate_node``: the node's three callbacks (tension, depth,
periodic tick) driving the scalar ``LineAlarm.update`` one message at a time, with the node's own
solver calls (scalar on a tension sample, one array call on a depth sample).
"""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from replay_data import T0_NS, dock_config, generate, simulate_node

from catenary_monitor.core.alarms import Level
from catenary_monitor.core.batch import (KIND_TENSION, NO_DEPTH, VALUE_FIELDS, critical_parameters,
                                         recompute, solve_updates, tick_grid)
from catenary_monitor.core.solve import solve


def _compare(config, tensions, depth, ticks):
    sim = simulate_node(config, tensions, depth, ticks)
    rep = recompute(config, tensions, depth, ticks)
    n_transitions = 0
    for res in rep.lines:
        ref = sim[res.name]
        # Transitions: time, old, new, message and episode duration, all identical.
        assert res.transitions == ref['transitions'], res.name
        n_transitions += len(ref['transitions'])
        # Level after every update and every tick.
        assert [u[0] for u in ref['updates']] == res.t_ns.tolist()
        assert [u[1] for u in ref['updates']] == res.kind.tolist()
        assert [u[2] for u in ref['updates']] == res.level.tolist()
        assert [t[1] for t in ref['ticks']] == res.tick_level.tolist()
        # Values: the node's scalar path equals the vectorized one to rounding.
        assert [u[4] for u in ref['updates']] == res.status.tolist()
        for key in VALUE_FIELDS:
            want = np.array([u[3][key] for u in ref['updates']], dtype=float)
            np.testing.assert_allclose(res.values[key], want, rtol=1e-12, atol=1e-9,
                                       err_msg=key)
    return rep, n_transitions


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_replay_equals_node_simulation(seed):
    config = dock_config(3)
    tensions, depth = generate(config, seconds=120.0, seed=seed)
    start = min(int(depth[0][0]), *(int(t[0]) for t, _ in tensions.values()))
    ticks = tick_grid(start + 250_000_000, start + 125 * 10**9, 1.0)
    rep, n = _compare(config, tensions, depth, ticks)
    levels = set()
    for res in rep.lines:
        levels |= {tr.new for tr in res.transitions}
    # The scenario exercises every level and many transitions.
    assert levels == {Level.OK, Level.WARN, Level.ERROR, Level.STALE}
    assert n >= 10


def test_synthetic_ticks_and_on_delay_and_coincident_times():
    """Ticks on the synthetic grid (no /diagnostics in the log), an on-delay, and messages
    whose receive times coincide with ticks and with each other (order depth, tension, tick)."""
    config = dock_config(2, on_delay=1.5, tension_timeout=0.9)
    tensions, depth = generate(config, seconds=60.0, rate=5.0, seed=11)
    # Snap every receive time to a 0.5 s grid: many equal times.
    snap = lambda t: (t // 500_000_000) * 500_000_000  # noqa: E731
    tensions = {k: (snap(t), v) for k, (t, v) in tensions.items()}
    for k, (t, v) in tensions.items():
        o = np.argsort(t, kind='stable')
        tensions[k] = (t[o], v[o])
    depth = (snap(depth[0]), depth[1])
    rep = recompute(config, tensions, depth)
    assert not rep.ticks_from_log and len(rep.tick_ns) > 50
    _compare(config, tensions, depth, rep.tick_ns)


def test_line_without_tension_and_log_without_depth():
    config = dock_config(2)
    tensions, depth = generate(config, seconds=20.0, seed=5, dropouts=False)
    del tensions['line_02']
    empty = (np.zeros(0, np.int64), np.zeros(0))
    for d in (depth, empty):
        rep = recompute(config, tensions, d)
        _compare(config, tensions, d, rep.tick_ns)
        silent = rep.lines[1]
        assert len(silent.t_ns) == 0 and Level.STALE in set(silent.tick_level.tolist())
    # Without depth every tension update is unsolved (status -1), like the node's outputs.
    assert set(rep.lines[0].status.tolist()) == {-1}


def test_solve_updates_is_bit_identical_to_solve_on_arrays():
    config = dock_config(2)
    rng = np.random.default_rng(3)
    t = rng.uniform(-1e5, 3e6, 5000)
    t[::97] = np.nan
    h = rng.uniform(-1.0, 30.0, 5000)
    for line in config.lines:
        a = critical_parameters(line, h)
        got, status = solve_updates(line, t, h, a)
        ref = solve(np.full(t.size, line.weight), h, tension=t,
                    anchor_distance=np.full(t.size, line.anchor_distance),
                    mbl=np.full(t.size, line.mbl))
        assert status.tolist() == ref.status.tolist()
        assert (status == 0).sum() > 1000 and (ref.uplift_force > 0).sum() > 100
        for key in VALUE_FIELDS:
            if key == 'depth':
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
        np.testing.assert_array_equal(res.values['top_tension'][rows][res.status[rows] == 0],
                                      tensions[res.name][1][res.status[rows] == 0])


def test_latch_fast_path_without_breach():
    """alarms._latch_series returns at once when no update breaches (most conditions of most
    lines in a real log); it equals the scalar latch step, with and without breaches."""
    from catenary_monitor.core import alarms
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0, 1, 400))
    cases = [rng.choice([alarms._HOLD, alarms._CLEAR], 400),
             np.full(400, alarms._CLEAR), np.full(400, alarms._HOLD),
             rng.choice([alarms._HOLD, alarms._CLEAR, alarms._BREACH], 400)]
    for codes in cases:
        codes = codes.astype(np.int8)
        latch, want = alarms.Latch(), []
        for c, now in zip(codes.tolist(), t.tolist()):
            latch = alarms._step(latch, c, now, 0.5, 3.0)
            want.append(latch.active)
        assert alarms._latch_series(codes, t, 0.5, 3.0).tolist() == want


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_random_schedules_equal_the_node(data):
    """Short random schedules: any interleaving of tension, depth and ticks, equal times, gaps,
    impossible samples, uplift and warning crossings, on-delays and hold times."""
    on_delay = data.draw(st.sampled_from([0.0, 0.3]))
    config = dock_config(2, on_delay=on_delay, clear_hold=data.draw(st.sampled_from([0.0, 0.7])),
                         warn_clear_hold=0.5, tension_timeout=0.6, depth_timeout=1.1)
    grid = st.integers(0, 40).map(lambda k: T0_NS + k * 100_000_000)  # 0.1 s grid: collisions
    tension_value = st.one_of(st.floats(3.0e5, 2.0e6), st.sampled_from([float('nan'), -1.0, 0.0]))
    tensions = {}
    for line in config.lines:
        times = sorted(data.draw(st.lists(grid, max_size=25)))
        values = data.draw(st.lists(tension_value, min_size=len(times), max_size=len(times)))
        tensions[line.name] = (np.array(times, np.int64), np.array(values, float))
    d_times = sorted(data.draw(st.lists(grid, max_size=8)))
    d_values = data.draw(st.lists(st.one_of(st.floats(15.0, 26.0), st.just(-1.0)),
                                  min_size=len(d_times), max_size=len(d_times)))
    depth = (np.array(d_times, np.int64), np.array(d_values, float))
    ticks = np.array(sorted(set(data.draw(st.lists(grid, max_size=12)))), np.int64)
    if not any(len(t) for t, _ in tensions.values()) and not len(d_times) and not len(ticks):
        return
    _compare(config, tensions, depth, ticks)


def test_solve_updates_of_an_elastic_line_is_elastic_solve():
    """A line with ``ea``: replay solves it with ``elastic.solve_with_correction``, as the node does."""
    from dataclasses import replace

    from catenary_monitor.core import elastic
    line = replace(dock_config(2).lines[1], ea=6.6e8)
    rng = np.random.default_rng(4)
    t = rng.uniform(-1e5, 3e6, 3000)
    t[::97] = np.nan
    h = rng.uniform(-1.0, 30.0, 3000)
    h[:10] = np.nan  # before the first depth
    got, status = solve_updates(line, t, h, critical_parameters(line, h))
    ref, _ = elastic.solve_with_correction(line.weight, h, t, anchor_distance=line.anchor_distance,
                                           ea=line.ea, mbl=line.mbl)
    assert status[:10].tolist() == [NO_DEPTH] * 10 and status[10:].tolist() == ref.status[10:].tolist()
    assert (ref.model[10:][status[10:] == 0] == elastic.ELASTIC).all() and (ref.uplift_force[10:] > 0).sum() > 100
    for key in VALUE_FIELDS:
        if key in ('depth', 'top_tension'):  # the measured inputs, also where unsolved
            np.testing.assert_array_equal(got[key], h if key == 'depth' else t)
            continue
        np.testing.assert_array_equal(got[key][10:], getattr(ref, key)[10:], err_msg=key)
        assert np.isnan(got[key][:10]).all()
