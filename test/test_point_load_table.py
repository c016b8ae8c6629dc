"""The surrogate of the chain-length problem with point loads (core/physics/point_load_table.py)
against the exact solve over its table's range, and the live dock estimate with clump weights
on four lines against MoorPy's System; the live core and its twin alike."""

import dataclasses
import functools
import math
import warnings

import numpy as np
import pytest
from dock_data import DOCK_YAML, dock_config, generate_dock

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.estimate import estimate_dock
from catenary_monitor.core.body.loads import push_direction
from catenary_monitor.core.config.parameters import (
    ConfigError,
    config_from_params,
    load_params_file,
    params_file_text,
)
from catenary_monitor.core.physics import point_loads as pl
from catenary_monitor.core.physics.point_load_table import build_table
from catenary_monitor_study import bench_point_loads

W, L, MBL = 1300.0, 122.6247, 4.827e6
LOW, HIGH = bench_point_loads.DEPTHS
CLUMPED = bench_point_loads.CLUMPED
LOADS = [
    pl.PointLoads.of([40.0], [30e3]),
    pl.PointLoads.of([60.0], [40e3]),
    pl.PointLoads.of([30.0, 60.0], [20e3, 20e3]),
    pl.PointLoads.of([70.0], [-20e3]),  # a buoy, where the chain is not on the seabed
]


def clumped_params(**extra):
    """The paper's dock with a 30 kN clump weight 60 m up four lines, tables over 19-23 m (as
    bench-point-loads has it)."""
    flat = bench_point_loads.clumped_params(str(DOCK_YAML))
    flat.update(extra)
    return flat


@pytest.mark.parametrize('loads', LOADS[:3])
def test_state_at_horizontal_is_the_chain_length_problem(loads):
    rng = np.random.default_rng(1)
    for _ in range(40):
        h, hor = rng.uniform(15.0, 25.0), math.exp(rng.uniform(math.log(2e3), math.log(4e6)))
        span, ans = pl.state_at_horizontal(W, h, L, hor, loads)
        assert ans.status == 0
        ref = pl.solve_length(W, h, L, span, loads)
        assert ref.horizontal == pytest.approx(hor, rel=1e-9)
        assert ref.tension == pytest.approx(ans.tension, rel=1e-9)
        assert ref.uplift == pytest.approx(ans.uplift, rel=1e-7, abs=1e-3)


@pytest.mark.parametrize('loads', LOADS[:3])
def test_table_within_its_stated_error_over_its_range(loads):
    """Random states inside the table (depth and H) against the exact one: the span from the
    tension and the tension at the span within the error measured when it was built (cell
    centres), which is under a millimetre; and the exact point-load solve (solve_length)
    agrees at random spans."""
    table = build_table(W, L, loads, MBL, LOW, HIGH)
    assert table.span_error < 1e-3 and table.tension_error < 1e-3
    rng = np.random.default_rng(2)
    n = 400
    h = rng.uniform(LOW, HIGH, n)
    hor = np.exp(rng.uniform(math.log(1e3), math.log(MBL), n))
    exact = [pl.state_at_horizontal(W, a, L, b, loads) for a, b in zip(h, hor)]
    span = np.array([s for s, _ in exact])
    tension = np.array([a.tension for _, a in exact])
    got_span, slope = table.span_at_tension(h, tension)
    got_t, got_h = table.state_at_span(h, span)
    assert np.max(np.abs(got_span - span)) <= 1.5 * table.span_error
    assert np.max(np.abs(got_t / tension - 1.0)) <= 1.5 * table.tension_error
    assert np.max(np.abs(got_h / hor - 1.0)) <= 2.0 * table.tension_error
    assert np.all(slope > 0.0)
    for k in range(0, n, 40):  # the monitor's exact solve, the other way round
        ref = pl.solve_length(W, h[k], L, float(got_span[k]), loads)
        assert abs(ref.tension / tension[k] - 1.0) <= 2.0 * table.tension_error
        ds = 1e-4
        up = pl.solve_length(W, h[k], L, float(span[k]) + ds, loads).tension
        down = pl.solve_length(W, h[k], L, float(span[k]) - ds, loads).tension
        assert slope[k] == pytest.approx((up - down) / (2 * ds), rel=2e-2)


def test_table_with_a_buoy_and_outside_the_range():
    table = build_table(W, L, LOADS[3], MBL, LOW, HIGH)
    assert table.span_error < 1e-3
    s, _ = table.span_at_tension(np.array([LOW - 0.01, HIGH + 0.01, 20.0]), np.full(3, 4e5))
    assert np.isnan(s[:2]).all() and np.isfinite(s[2])
    t, hor = table.state_at_span(np.array([20.0, 20.0]), np.array([50.0, 200.0]))
    assert np.isnan(t).all() and np.isnan(hor).all()  # a buoy: its slackest not modelled


def test_plain_floats_and_numpy_give_the_same_bits():
    """The live core asks one element at a time (plain floats), the twin many (numpy)."""
    table = build_table(W, L, LOADS[0], MBL, LOW, HIGH)
    rng = np.random.default_rng(3)
    n = 500
    h = rng.uniform(LOW - 0.2, HIGH + 0.2, n)
    t = np.exp(rng.uniform(np.log(1e4), np.log(6e6), n))
    s = rng.uniform(95.0, 122.0, n)
    for query, y in ((table.span_at_tension, t), (table.state_at_span, s)):
        many = query(h, y)
        one = [query(h[i : i + 1], y[i : i + 1]) for i in range(n)]
        for k in range(2):
            col = np.concatenate([o[k] for o in one])
            assert np.array_equal(many[k], col, equal_nan=True)
            assert np.isfinite(col).sum() > n // 2


def test_point_loads_on_the_dock_need_the_table_depths():
    flat = clumped_params()
    del flat['dock_table_depth_min']
    with pytest.raises(ConfigError, match='dock_table_depth_min'):
        config_from_params(flat)
    with pytest.raises(ConfigError, match='dock_table_depth_max'):
        config_from_params(clumped_params(dock_table_depth_min=24.0))
    model = DockModel.from_config(config_from_params(clumped_params()))
    assert [t is not None for t in model.tables] == [n in CLUMPED for n in model.names]
    assert 0.0 < model.table_span_error < 1e-3


@functools.lru_cache(maxsize=None)
def _moorpy_scenes():
    from catenary_monitor_study.body_peer import moorpy_equilibrium

    model = DockModel.from_config(config_from_params(clumped_params()))
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        for phi in (0.0, 45.0, 100.0, 150.0, 270.0, 315.0):
            push = push_direction(phi)
            load = np.array([push[0] * 1e6, push[1] * 1e6, 0.0])
            offset, tensions, _ = moorpy_equilibrium(model, 20.85, load, tol=1e-5)
            out.append((load, offset, tensions))
    return model, out


def test_the_live_estimate_with_clump_weights_agrees_with_moorpy():
    """The twelve-line dock with a clump weight on four lines, each pushed by 1 MN from six
    directions in MoorPy (free points with the clumps' masses, solved to 1e-5 m): its hook
    tensions give the live estimate MoorPy's offset within 1 cm (in fact 0.1 mm) and its
    load; the exact point-load solve gives the same to its roots' precision."""
    model, scenes = _moorpy_scenes()
    exact = dataclasses.replace(model, tables=())
    use = np.ones((1, 12), bool)
    for load, offset, tensions in scenes:
        for m in (model, exact):
            est = estimate_dock(m, np.array([20.85]), tensions[None, :], use)
            assert est.valid[0] and not est.dropped.any()
            assert np.max(np.abs(est.offset[0, :2] - offset[:2])) < 1e-3, (load, est.offset)
            assert abs(est.offset[0, 2] - offset[2]) < 1e-5
            assert np.max(np.abs(est.load[0, :2] - load[:2])) < 2e3


def test_monitor_core_takes_the_clumped_dock_from_its_params_file(tmp_path):
    """The params file (as `run` reads it) into MonitorCore: MoorPy's tensions give the dock
    status MoorPy's offset within 1 cm, and the tables' error among its values."""
    from catenary_monitor.core.monitor.events import Depth, Tension, Tick
    from catenary_monitor.core.monitor.monitor_core import MonitorCore

    path = tmp_path / 'clumped.yaml'
    path.write_text(params_file_text(clumped_params()))
    config = config_from_params(load_params_file(path))
    _, scenes = _moorpy_scenes()
    load, offset, tensions = scenes[2]
    core = MonitorCore(config, 0)
    core.step(Depth(1, 20.85))
    for i, t in enumerate(tensions.tolist()):
        core.step(Tension(10 + i, i, t))
    core.step(Tick(1_000_000_000))
    dock = [s for s in core.snapshot(1_000_000_001).statuses if s.name.endswith(': dock')][0]
    values = dict(dock.values)
    assert abs(float(values['offset_x']) - offset[0]) < 0.01
    assert abs(float(values['offset_y']) - offset[1]) < 0.01
    assert 0.0 < float(values['table_span_error']) < 1e-3


@pytest.mark.slow
def test_the_twin_estimates_the_clumped_dock_as_the_core_does():
    from replay_data import T0_NS
    from test_batch import compare, ticks_for

    settings = clumped_params()
    settings = {k: v for k, v in settings.items() if 'point_load' in k or 'table_depth' in k}
    config = dock_config(tension_timeout=2.0, **settings)
    tensions, depth = generate_dock(config, 20.0, rate=2.0, seed=4)
    ticks = ticks_for(tensions, depth)
    steps = compare(config, tensions, depth, ticks, [T0_NS + int(7.3e9)])
    assert any(c.component == 'dock' for s in steps for c in s.transitions)


@pytest.mark.ros
@pytest.mark.slow
def test_run_watches_the_clumped_dock_within_a_centimetre_of_moorpy(tmp_path):
    """`catenary-monitor run` on the clumped dock's params file: MoorPy's hook tensions
    published live give the dock status MoorPy's offset within 1 cm."""
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import QoSProfile
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64

    from catenary_monitor.io.mcap_read import iter_messages

    root = Path(__file__).resolve().parents[1]
    params = tmp_path / 'clumped.yaml'
    flat = clumped_params(log_dir=str(tmp_path / 'logs'), diagnostic_rate=4.0)
    params.write_text(params_file_text(flat))
    model, scenes = _moorpy_scenes()
    _, offset, tensions = scenes[1]
    env = dict(os.environ, PYTHONPATH=str(root), PYTHONUNBUFFERED='1')
    out_path = tmp_path / 'node.out'
    with open(out_path, 'w+') as out:
        cmd = [sys.executable, '-m', 'catenary_monitor', 'run', '--params-file', str(params)]
        proc = subprocess.Popen(cmd, env=env, stdout=out, stderr=subprocess.STDOUT)
        try:
            if not rclpy.ok():
                rclpy.init()
            client = rclpy.create_node('point_load_run_test')
            qos = QoSProfile(depth=10)
            topics = [f'/mooring/{n}/tension' for n in model.names]
            pubs = [client.create_publisher(Float64, t, qos) for t in topics]
            depth_pub = client.create_publisher(Float64, '/tide/depth', qos)
            deadline = time.monotonic() + 60.0
            while time.monotonic() < deadline and proc.poll() is None:
                if all(p.get_subscription_count() for p in [*pubs, depth_pub]):
                    break
                time.sleep(0.05)
            assert depth_pub.get_subscription_count(), out_path.read_text()
            start = time.monotonic()
            while time.monotonic() - start < 4.0:
                depth_pub.publish(Float64(data=20.85))
                for pub, v in zip(pubs, tensions.tolist()):
                    pub.publish(Float64(data=v))
                time.sleep(0.1)
            time.sleep(1.0)
            client.destroy_node()
        finally:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
            code = proc.wait(30)
    assert code == 0, out_path.read_text()
    files = sorted((tmp_path / 'logs').glob('*.mcap'))
    arrays = [
        deserialize_message(m.data, DiagnosticArray)
        for m in iter_messages(files, ['/diagnostics'])
    ]
    dock = [s for s in arrays[-1].status if s.name == 'catenary_monitor: dock'][0]
    values = {kv.key: kv.value for kv in dock.values}
    assert abs(float(values['offset_x']) - offset[0]) < 0.01, (values, offset)
    assert abs(float(values['offset_y']) - offset[1]) < 0.01, (values, offset)
    assert 0.0 < float(values['table_span_error']) < 1e-3


def test_a_tide_outside_the_tables_leaves_those_lines_out_in_words():
    """A depth beyond dock_table_depth_max: the clumped lines are not used (the plain eight
    still place the dock), and the dock status says why its load is not estimated."""
    from catenary_monitor.core.monitor.events import Depth, Tension, Tick
    from catenary_monitor.core.monitor.monitor_core import MonitorCore

    config = config_from_params(clumped_params())
    core = MonitorCore(config, 0)
    core.step(Depth(1, HIGH + 0.5))
    for i in range(12):
        core.step(Tension(10 + i, i, 3.9e5))
    core.step(Tick(1_000_000_000))
    dock = [s for s in core.snapshot(1_000_000_001).statuses if s.name.endswith(': dock')][0]
    assert dock.level == 0 and dict(dock.values)['readings'] == '8', dock
    assert "outside its table's depths" in dict(dock.values)['detail']


@pytest.mark.slow
def test_bench_point_loads_runs_and_reports_its_baseline():
    """The benchmark's figures exist and are sane (no timing asserted: ratios are read)."""
    from catenary_monitor.sim.scenario import default_config_path

    r = bench_point_loads.run(str(default_config_path()), ticks=3, exact_ticks=1)
    assert set(r['ms_per_tick']) == {'plain', 'tables', 'exact'} and r['exact_over_tables'] > 0
    assert r['clumped'] == 4 and 0.0 < r['table_span_error_m'] < 1e-3
    assert max(r['moorpy']['offset_error_m'].values()) < 0.01
    text = bench_point_loads._text(r)
    assert 'exact / tables' in text and 'MoorPy' in text
