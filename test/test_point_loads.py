"""Clump weights and buoys on a chain (core/physics/point_loads.py) against MoorPy (a free point
between two lines: an independent static solver) to 1e-6 and against seed 002's two-segment
equation (6)."""

import math
import os

import numpy as np
import pytest

from catenary_monitor.core.physics import point_loads as pl

os.environ.setdefault('PYTHONBREAKPOINT', '0')  # MoorPy calls breakpoint() on some errors
W, H_DEPTH = 1300.0, 20.85  # the seed dock's chain (N/m) and depth (m)
G, RHO = 9.81, 1025.0


def _line_type(w):
    return {
        'name': 'chain', 'm': w / G, 'd_vol': 0.0, 'w': w, 'EA': 1e16, 'MBL': 1e9,
        'material': 'chain', 'd_nom': 0.0, 'input_d': 0.0, 'Cd': 0.0, 'CdAx': 0.0, 'Ca': 0.0,
        'CaAx': 0.0, 'cost': 0.0,
    }  # fmt: skip


def moorpy_scene(length, span, position, weight, depth=H_DEPTH, w=W, guess=None):
    """MoorPy (EA 1e16: inextensible to the tolerance): anchor, a free point (a clump's mass
    or a buoy's volume) ``position`` m along the chain, the hook; returns (H, hook tension,
    anchor's vertical force, the point's (x, z) from the anchor). ``guess``: where to start the
    point (x, z from the anchor)."""
    mp = pytest.importorskip('moorpy')
    ms = mp.System(depth=depth, g=G, rho=RHO)
    anchor = ms.addPoint(1, [-span, 0.0, -depth])
    mass, volume = (weight / G, 0.0) if weight >= 0 else (0.0, -weight / (RHO * G))
    gx, gz = guess if guess is not None else (position * span / length, 2.0)
    start = [-span + gx, 0.0, -depth + gz]
    point = ms.addPoint(0, start, m=mass, v=volume)
    hook = ms.addPoint(1, [0.0, 0.0, 0.0])
    ms.addLine(position, _line_type(w), pointA=anchor.number, pointB=point.number)
    ms.addLine(length - position, _line_type(w), pointA=point.number, pointB=hook.number)
    ms.initialize()
    assert ms.solveEquilibrium(tol=1e-10, maxIter=2000) is not False
    f_b = ms.lineList[1].fB
    r = point.r
    # the anchor's vertical force by balance: the hook's less the chain's and the point's weight
    v_anchor = abs(f_b[2]) - w * length - weight
    return abs(f_b[0]), float(np.linalg.norm(f_b)), v_anchor, (r[0] + span, r[2] + depth)


# (chain length, span, load position from the anchor, load weight): clumps and buoys on the
# suspended chain, anchors down and lifted (a clump resting exactly at the touchdown, or a buoy
# lifting a hump, MoorPy's points cannot follow: no seabed contact; not modelled here).
SCENES = [
    (125.0, 118.0, 100.0, 40e3),  # clump, chain grounded, anchor down
    (125.0, 122.0, 100.0, 40e3),
    (125.0, 122.0, 60.0, -30e3),  # buoy on the suspended chain
    (125.0, 122.9, 60.0, 40e3),  # taut: the anchor lifted with a clump on the chain
    (125.0, 122.9, 40.0, -20e3),  # taut: lifted with a buoy
]


@pytest.mark.parametrize('length,span,position,weight', SCENES)
def test_chain_length_problem_against_moorpy(length, span, position, weight):
    loads = pl.PointLoads.of([position], [weight])
    ans = pl.solve_length(W, H_DEPTH, length, span, loads)
    assert ans.status == 0
    h_mp, t_mp, va_mp, point_mp = moorpy_scene(length, span, position, weight, guess=ans.points[0])
    assert ans.horizontal == pytest.approx(h_mp, rel=1e-6)
    assert ans.tension == pytest.approx(t_mp, rel=1e-6)
    assert ans.uplift == pytest.approx(max(va_mp, 0.0), abs=1e-6 * t_mp)
    assert ans.points[0] == pytest.approx(point_mp, abs=1e-5)


@pytest.mark.parametrize('length,span,position,weight', SCENES)
def test_uplift_from_the_hook_tension_against_moorpy(length, span, position, weight):
    """The monitor's problem: MoorPy's hook tension and the span give back MoorPy's uplift
    and horizontal tension."""
    mine = pl.solve_length(W, H_DEPTH, length, span, pl.PointLoads.of([position], [weight]))
    h_mp, t_mp, va_mp, _ = moorpy_scene(length, span, position, weight, guess=mine.points[0])
    ans = pl.solve_tension(W, H_DEPTH, t_mp, span, pl.PointLoads.of([position], [weight]))
    assert ans.status == 0
    assert ans.horizontal == pytest.approx(h_mp, rel=1e-6)
    assert ans.uplift == pytest.approx(max(va_mp, 0.0), abs=1e-6 * t_mp)
    assert (ans.uplift > 0) == (va_mp > 1e-6 * t_mp)
    assert ans.suspended_length <= length * (1 + 1e-6)


@pytest.mark.parametrize('position,weight', [(60.0, 40e3), (40.0, -20e3), (80.0, 30e3)])
def test_minimum_anchor_distance_against_moorpy(position, weight):
    """At the minimum anchor distance for a hook tension the chain, all of it hanging, leaves
    the anchor tangent to the seabed: MoorPy, given that chain and span, finds the same hook
    tension and no vertical force on the anchor; a metre closer it lifts, a metre further not."""
    tension = 450e3
    loads = pl.PointLoads.of([position], [weight])
    x_min, _ = pl.min_anchor(W, H_DEPTH, tension, loads)
    at = pl.solve_tension(W, H_DEPTH, tension, x_min, loads)
    assert at.status == 0 and at.uplift == pytest.approx(0.0, abs=1e-6 * tension)
    length = at.suspended_length
    h_mp, t_mp, va_mp, _ = moorpy_scene(length, x_min, position, weight, guess=at.points[0])
    assert t_mp == pytest.approx(tension, rel=1e-6)
    assert abs(va_mp) <= 1e-6 * tension
    assert pl.solve_tension(W, H_DEPTH, tension, x_min - 1.0, loads).uplift > 0.0
    assert pl.solve_tension(W, H_DEPTH, tension, x_min + 1.0, loads).uplift == 0.0
    plain, _ = pl.min_anchor(W, H_DEPTH, tension, pl.PointLoads((), ()))
    a = (tension - W * H_DEPTH) / W
    assert plain == pytest.approx(a * math.acosh(1.0 + H_DEPTH / a), rel=1e-12)
    assert (x_min < plain) == (weight > 0)  # a clump steepens the chain, a buoy flattens it


def _seed_002_equation_6(h0, w, g, xg, zg, span, height):
    """Guo & Li (2016), equation (6): H0 sh(...) + G on the left of the load point equals
    H0 sh(...) on its right (two catenaries through A, O and O, B with one H0)."""
    k = w / (2.0 * h0)
    left = h0 * math.sinh(w * xg / h0 + math.asinh(k * zg / math.sinh(k * xg)) - k * xg)
    right = h0 * math.sinh(
        math.asinh(k * (height - zg) / math.sinh(k * (span - xg))) - k * (span - xg)
    )
    return left + g, right


@pytest.mark.parametrize('position,weight', [(60.0, 40e3), (30.0, 80e3), (40.0, -20e3)])
def test_seed_002_two_segment_equation(position, weight):
    """The solved chain (anchor lifted: both ends fixed, as the highline's) satisfies seed 002's
    force balance at the load point, written as the paper writes it."""
    loads = pl.PointLoads.of([position], [weight])
    ans = pl.solve_length(W, H_DEPTH, 125.0, 123.0, loads)
    assert ans.status == 0 and ans.uplift > 0
    xg, zg = ans.points[0]
    left, right = _seed_002_equation_6(ans.horizontal, W, weight, xg, zg, 123.0, H_DEPTH)
    assert left == pytest.approx(right, rel=1e-9)


def test_scenes_it_does_not_model_are_named():
    """A buoy on the grounded chain would lift a hump off the seabed: status NOT_MODELLED, NaN;
    a hook tension below the hanging chain's weight: status 4."""
    ans = pl.solve_length(W, H_DEPTH, 125.0, 118.0, pl.PointLoads.of([60.0], [-30e3]))
    assert ans.status == pl.NOT_MODELLED and math.isnan(ans.tension)
    low = pl.solve_tension(W, H_DEPTH, W * H_DEPTH * 0.9, 100.0, pl.PointLoads.of([50], [1e3]))
    assert low.status == 4


# --- through the monitor ------------------------------------------------------------------------


def _loaded_config(positions, weights, **extra):
    from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig

    line = LineConfig(
        name='sinker',
        weight=W,
        anchor_distance=121.06,
        mbl=4.827e6,
        point_load_positions=tuple(positions),
        point_load_weights=tuple(weights),
        **extra,
    )
    plain = LineConfig(name='plain', weight=W, anchor_distance=121.06, mbl=4.827e6)
    return MonitorConfig(lines=(line, plain))


def test_the_monitor_and_its_replay_solve_a_line_with_a_clump_and_a_buoy():
    """A line with a clump weight and a buoy through MonitorCore and its vectorized twin:
    the same values (solve() with point_loads, equal to the bit), the point-load model named,
    a lifted anchor's ERROR; the plain line beside it unchanged."""
    from catenary_monitor import solve
    from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
    from catenary_monitor.core.monitor.events import Depth
    from catenary_monitor.core.monitor.monitor_core import MonitorCore
    from catenary_monitor.core.monitor.events import Tension, Tick
    from catenary_monitor.core.twin.engine import recompute

    config = _loaded_config([40.0, 90.0], [60e3, -25e3])
    tensions = np.linspace(3.8e5, 1.7e6, 40)
    stamps = (np.arange(tensions.size) + 1) * 10**9
    core = MonitorCore(config, 0)
    core.step(Depth(1, H_DEPTH))
    outs = []
    for t, v in zip(stamps.tolist(), tensions.tolist()):
        outs.append(dict(zip(OUTPUT_FIELDS, core.step(Tension(t, 0, v)).outputs[0].values)))
        core.step(Tick(t + 2))
    ref = solve(
        W, H_DEPTH, tension=tensions[-1], anchor_distance=121.06, mbl=4.827e6,
        point_loads=([40.0, 90.0], [60e3, -25e3]),
    )  # fmt: skip
    assert outs[-1]['uplift_force'] == ref.uplift_force > 0
    assert outs[-1]['min_anchor_distance'] == ref.min_anchor_distance
    status = core.snapshot(stamps[-1] + 3).statuses[0]
    assert dict(status.values)['model'] == pl.MODEL and status.level == 2
    replay = recompute(
        config,
        {'sinker': (stamps, tensions)},
        (np.array([1], np.int64), np.array([H_DEPTH])),
        tick_ns=stamps + 2,
        start_ns=0,
    )
    r = replay.lines[0]
    for key in ('uplift_force', 'min_anchor_distance', 'horizontal_tension', 'tide_margin'):
        assert np.array_equal(r.values[key][r.tension_rows], [o[key] for o in outs]), key
    assert {pl.MODEL} == {['none', 'x', 'y', pl.MODEL][c] for c in r.model_codes[1:]}


@pytest.mark.parametrize(
    'extra,message',
    [
        (dict(point_load_positions=(40.0,), point_load_weights=()), '0 weights for 1 positions'),
        (dict(point_load_positions=(40.0,), point_load_weights=(-1e6,)), 'lift the anchor'),
        (
            dict(point_load_positions=(130.0,), point_load_weights=(1e4,), chain_length=125.0),
            'beyond the chain',
        ),
        (dict(point_load_positions=(40.0,), point_load_weights=(1e4,), ea=6.6e8), 'inextensible'),
        (dict(point_load_positions=(-4.0,), point_load_weights=(1e4,)), 'out of range'),
    ],
)
def test_bad_point_loads_are_one_line_errors(extra, message):
    from catenary_monitor.core.config.parameters import ConfigError, LineConfig

    with pytest.raises(ConfigError, match=message):
        LineConfig(name='x', weight=W, anchor_distance=120.0, mbl=4.8e6, **extra)


def test_whatif_hangs_a_line_with_point_loads_as_installed():
    """whatif: a line not given hangs as installed, its clump and buoy included (problem 5 with
    point loads), and the scene's level follows; the dock model asks for the depths of its
    point-load lines' tables by name."""
    from catenary_monitor.core.config.parameters import ConfigError, LineConfig, MonitorConfig
    from catenary_monitor.core.monitor.whatif_scene import hanging_tensions

    config = _loaded_config([40.0], [60e3], chain_length=125.0)
    got = hanging_tensions(config, H_DEPTH, ['sinker'])['sinker']
    ref = pl.solve_length(W, H_DEPTH, 125.0, 121.06, pl.PointLoads.of([40.0], [60e3]))
    assert got == pytest.approx(ref.tension, rel=1e-12)
    line = dict(weight=W, anchor_distance=120.0, mbl=4.8e6, hook_x=1.0, hook_y=0.0)
    line.update(heading=90.0, chain_length=125.0)
    lines = (
        LineConfig(name='a', **line),
        LineConfig(name='b', point_load_positions=(50.0,), point_load_weights=(1e4,), **line),
    )
    with pytest.raises(ConfigError, match='dock_table_depth_min'):
        MonitorConfig(lines=lines)


def test_point_loads_doc_parameter_table_is_generated():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown

    page = (Path(__file__).resolve().parent.parent / 'docs' / 'point_loads.md').read_text()
    begin, end = '<!-- point-loads-parameters:begin -->\n', '<!-- point-loads-parameters:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('point_loads')


def test_bounds_and_holding_of_a_line_with_point_loads_live_and_in_replay():
    """A clump and a buoy on a line with a chain length and an anchor's holding: the bounds,
    the dynamic uplift and every holding value are numbers (no NaN once solved), the core's
    and the replay twin's to the bit; the implied anchor distance gives back the tension
    (solve_length) and the tide margin at length is where that chain lifts its anchor."""
    from catenary_monitor.core.rules.holding import FIELDS as HOLD
    from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
    from catenary_monitor.core.monitor.events import Depth
    from catenary_monitor.core.monitor.monitor_core import MonitorCore
    from catenary_monitor.core.monitor.events import Tension, Tick
    from catenary_monitor.core.twin.engine import recompute

    config = _loaded_config(
        [40.0, 90.0], [60e3, -25e3], chain_length=125.0, anchor_holding=6e5, chain_friction=1.0
    )
    tensions = np.linspace(3.8e5, 9e5, 12)
    stamps = (np.arange(tensions.size) + 1) * 10**9
    core = MonitorCore(config, 0)
    core.step(Depth(1, H_DEPTH))
    outs = []
    for t, v in zip(stamps.tolist(), tensions.tolist()):
        outs.append(dict(zip(OUTPUT_FIELDS, core.step(Tension(t, 0, v)).outputs[0].values)))
        core.step(Tick(t + 2))
    keys = ('uplift_force_upper', 'anchor_margin_lower', 'tide_margin_lower', 'dynamic_uplift')
    keys += (*HOLD, 'tide_margin_at_length', 'drag_state')
    for key in keys:
        assert all(math.isfinite(o[key]) for o in outs), key
    replay = recompute(
        config,
        {'sinker': (stamps, tensions)},
        (np.array([1], np.int64), np.array([H_DEPTH])),
        tick_ns=stamps + 2,
        start_ns=0,
    )
    r = replay.lines[0]
    for key in keys:
        assert np.array_equal(r.values[key][r.tension_rows], [o[key] for o in outs]), key
    loads = pl.PointLoads.of([40.0, 90.0], [60e3, -25e3])
    last = outs[-1]
    back = pl.solve_length(W, H_DEPTH, 125.0, last['implied_anchor_distance'], loads)
    assert back.tension == pytest.approx(tensions[-1], rel=1e-9)
    lift = H_DEPTH + last['tide_margin_at_length']
    assert pl.solve_length(W, lift - 1e-3, 125.0, 121.06, loads).uplift == 0.0
    assert pl.solve_length(W, lift + 1e-3, 125.0, 121.06, loads).uplift > 0.0
    assert last['uplift_force_upper'] >= last['dynamic_uplift'] >= last['uplift_force']
    assert last['anchor_margin_lower'] <= last['anchor_margin']


@pytest.mark.parametrize('tension', [4.5e5, 1.2e6])
def test_point_load_bounds_contain_every_reading_within_the_accuracy(tension):
    """uncertainty.loaded_bounds: the solve at random readings within +-dT and +-dh stays
    inside the bounds (the uplift below its upper bound, both margins above their lower)."""
    from catenary_monitor.core.rules.uncertainty import loaded_bounds

    loads = ([40.0, 90.0], [60e3, -25e3])
    d_t, d_h, x = 2e4, 0.05, 121.06
    nominal = pl.solve_tension(W, H_DEPTH, tension, x, pl.PointLoads.of(*loads)).uplift
    b = loaded_bounds(W, x, 4.827e6, loads, tension, H_DEPTH, d_t, d_h, nominal)
    rng = np.random.default_rng(7)
    for t, h in zip(tension + rng.uniform(-d_t, d_t, 12), H_DEPTH + rng.uniform(-d_h, d_h, 12)):
        a = pl.solve_tension(W, h, t, x, pl.PointLoads.of(*loads))
        assert a.uplift <= b['uplift_force_upper'] * (1 + 1e-12)
        assert x - a.min_anchor_distance >= b['anchor_margin_lower'] - 1e-9
        tide = pl.walk(W, a.horizontal, 0.0, pl.PointLoads.of(*loads), span=x)
        assert tide is None or tide.z - h >= b['tide_margin_lower'] - 1e-9
