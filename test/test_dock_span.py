"""The dock's offset in each line's span: a dock pushed off its reference position is judged at
its real anchor distances.

MoorPy (a static mooring model nobody here wrote) holds the paper's dock, one body with its
twelve chains, under a load that steps up: its body equilibrium gives the offset, each hook's
tension and each anchor's vertical force. The hook tensions and the depth go, as a rosbag2
recording of the sensor topics, through ``catenary-monitor replay BAG --params-file F --csv
--csv-columns all`` and, event by event, through the core (the node's one decision path): from
the tick after each step on, every line is solved at the span the dock estimate gives, which is
MoorPy's span, and its uplift is MoorPy's anchor force; at the installed spans it would not be.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from dock_data import DOCK_YAML
from replay_data import T0_NS, events_of
from sensor_bag import column, replay_csv, write_bag

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.config.parameters import config_from_params, load_params_file
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.monitor_core import MonitorCore
from catenary_monitor.core.monitor.events import Reconfigure, Tension, Tick
from catenary_monitor.core.twin.window import tick_grid
from catenary_monitor.core.physics.solve import solve

STEP_S = 20.0  # s at each load
RATE = 2.0  # tension samples per second per line
UPLIFT_TOL = 100.0  # N: MoorPy's lines are solved to its own tolerance (1e-6 m here)


def moorpy_scene(config, depth, loads):
    """MoorPy's equilibrium of the dock under each load (Fx, Fy, Mz): offsets (n, 3), hook
    tensions, anchor vertical forces and spans (n, 12)."""
    pytest.importorskip('moorpy')
    from catenary_monitor_study.body_peer import moorpy_equilibrium, moorpy_lines, moorpy_system

    model = DockModel.from_config(config)
    system = moorpy_system(model, depth)
    rows = []
    for load in loads:
        q, _, system = moorpy_equilibrium(model, depth, np.asarray(load), tol=1e-6, system=system)
        rows.append((q, *moorpy_lines(system)))
    return tuple(np.array(part) for part in zip(*rows))


def moorpy_lift_depth(line, span):
    """The depth [m] at which MoorPy's catenary of ``line``'s chain at ``span`` [m] first puts
    1 N on the anchor (its inextensible limit; the fixed-length lift, found by brentq)."""
    from moorpy.Catenary import catenary
    from scipy.optimize import brentq

    def force(h):
        return catenary(span, h, line.chain_length, 1e14, line.weight, CB=0.0)[1] - 1.0

    return brentq(force, 5.0, 0.99 * math.sqrt(line.chain_length**2 - span**2), xtol=1e-7)


def sensor_columns(config, depth, tensions):
    """The tension samples (RATE per line, each load held STEP_S) and the depth (1 Hz) as the
    sensors give them, as (receive time ns, value) columns."""
    n = int(STEP_S * RATE)
    t = np.arange(len(tensions) * n) / RATE
    out = {}
    for k, line in enumerate(config.lines):
        t_ns = T0_NS + np.rint((t + 0.01 * (k + 1)) * 1e9).astype(np.int64)
        out[line.name] = (t_ns, np.repeat(tensions[:, k], n))
    td = T0_NS + np.rint((np.arange(int(t[-1]) + 1) + 0.005) * 1e9).astype(np.int64)
    return out, (td, np.full(td.size, depth))


def settled(time_s):
    """The samples at least two ticks after their load's step (the estimate of the first tick
    after the step is taken by the samples after it), and each sample's load index."""
    level = (time_s // STEP_S).astype(int)
    return (time_s - level * STEP_S) >= 2.5, level


@pytest.fixture(scope='module')
def config():
    return config_from_params(load_params_file(DOCK_YAML))


# A storm from port at mean tide (the port anchors lift as the dock drifts off them), and a
# push from the starboard bow with a yaw moment at a high tide (every anchor near its lift: the
# ones the dock drifts toward lift more at their shorter spans, and the installed span says less).
SCENES = {
    'storm_from_port': (20.85, [(0.0, -f, 0.0) for f in (0.0, 0.8e6, 1.4e6, 2.0e6)]),
    'high_tide_yawed': (
        21.7,
        [(0.0, 0.0, 0.0)] + [(-0.4 * f, 0.9 * f, 3e7 * f / 1e6) for f in (0.3e6, 0.7e6, 1.1e6)],
    ),
}


@pytest.mark.parametrize('scene', sorted(SCENES))
def test_uplift_at_the_dock_estimate_span_equals_moorpy(tmp_path, config, scene):
    depth, loads = SCENES[scene]
    offsets, tensions, uplift, spans = moorpy_scene(config, depth, loads)
    assert np.hypot(offsets[-1, 0], offsets[-1, 1]) > 0.4  # the dock was pushed off
    columns, depth_column = sensor_columns(config, depth, tensions)
    rows = replay_csv(tmp_path, config, write_bag(tmp_path / 'bag', config, columns, depth_column))
    worst_uplift = worst_lift = 0.0
    for k, line in enumerate(config.lines):
        time = column(rows, 'time', line.name) - T0_NS * 1e-9
        ok, level = settled(time)
        got = column(rows, 'uplift_force', line.name)[ok]
        span = column(rows, 'span', line.name)[ok]
        source = {r['span_source'] for r in rows if r['line'] == line.name}
        assert source <= {'installed', 'dock_estimate'}
        words = [r['span_source'] for r in rows if r['line'] == line.name]
        assert all(words[i] == 'dock_estimate' for i in np.flatnonzero(ok)), line.name
        np.testing.assert_allclose(span, spans[level[ok], k], atol=6e-4, err_msg=line.name)  # mm
        np.testing.assert_allclose(got, uplift[level[ok], k], atol=UPLIFT_TOL, err_msg=line.name)
        # the margins and the bound at the same span
        margin = column(rows, 'anchor_margin', line.name)[ok]
        x_min = column(rows, 'min_anchor_distance', line.name)[ok]
        np.testing.assert_allclose(margin, span - x_min, atol=2e-3)
        assert np.all(column(rows, 'uplift_force_upper', line.name)[ok] >= got)
        # the tide rise that lifts the anchor, the chain's length held (the forecast's view),
        # at the span MoorPy has: its catenary's own lift depth there
        lift = np.array([moorpy_lift_depth(line, s) for s in spans[:, k]])
        margin = column(rows, 'tide_margin_at_length', line.name)[ok]
        np.testing.assert_allclose(margin, lift[level[ok]] - depth, atol=3e-3, err_msg=line.name)
        # at the installed span, the same readings give another uplift and lift depth
        at_installed = solve(
            line.weight, depth, tension=tensions[:, k], anchor_distance=line.anchor_distance
        ).uplift_force
        worst_uplift = max(worst_uplift, float(np.max(np.abs(at_installed - uplift[:, k]))))
        installed = moorpy_lift_depth(line, line.anchor_distance)
        worst_lift = max(worst_lift, float(np.max(np.abs(lift - installed))))
    # not vacuous: anchors lifted, and the installed span is off by more than the tolerances
    assert uplift.max() > 30e3 and worst_uplift > 3 * UPLIFT_TOL, (uplift.max(), worst_uplift)
    assert worst_lift > 0.8, worst_lift  # m of tide


def test_the_core_stepped_live_gives_the_replay_values_and_falls_back(tmp_path, config):
    """Identically live: the core stepped event by event solves every sample at the same span
    as the replay (the newest tick's estimate); before the first tick, and after a change of
    configuration that removes the dock's geometry, at the installed span."""
    depth, loads = SCENES['storm_from_port']
    _, tensions, uplift, spans = moorpy_scene(config, depth, loads[-2:])
    columns, depth_column = sensor_columns(config, depth, tensions)
    rows = replay_csv(tmp_path, config, write_bag(tmp_path / 'bag', config, columns, depth_column))
    start = int(min(depth_column[0][0], *(c[0][0] for c in columns.values())))
    end = int(max(c[0][-1] for c in columns.values()))
    ticks = tick_grid(start, end, config.alarm.diagnostic_rate)
    core = MonitorCore(config, start)
    live = []
    for ev in events_of(config, columns, depth_column, ticks):
        step = core.step(ev)
        if isinstance(ev, Tension):
            live.append(dict(zip(OUTPUT_FIELDS, step.outputs[0].values)))
    assert len(rows) == len(live)  # one row per tension sample, in time order
    for r, v in zip(rows, live):
        assert r['span_source'] == ('dock_estimate' if v['span_source'] == 1.0 else 'installed')
        assert abs(float(r['span']) - v['span']) <= 1e-3
        assert abs(float(r['uplift_force']) - v['uplift_force']) <= 1e-3
    first = live[: len(config.lines)]
    assert all(v['span_source'] == 0.0 for v in first)  # no estimate before the first tick
    assert all(v['span'] == line.anchor_distance for v, line in zip(first, config.lines))
    # /diagnostics: the span and its source per line
    snap = core.snapshot(core.state.last_ns)
    values = {st.name: dict(st.values) for st in snap.statuses}
    line_11 = values['catenary_monitor: line_11']
    assert line_11['span_source'] == 'dock_estimate'
    assert abs(float(line_11['span']) - spans[-1, 10]) < 1e-4
    assert line_11['anchor_distance'] == repr(121.06)  # the installed one, still shown
    # without the dock's geometry the next samples are solved at the installed span
    plain = dataclasses.replace(
        config, lines=tuple(
            dataclasses.replace(lc, hook_x=None, hook_y=None, heading=None) for lc in config.lines
        ),
    )
    core.step(Reconfigure(core.state.last_ns + 1, plain))
    now = core.state.last_ns + 10
    step = core.step(Tension(now, 10, float(tensions[-1, 10])))
    out = dict(zip(OUTPUT_FIELDS, step.outputs[0].values))
    assert out['span_source'] == 0.0 and out['span'] == 121.06
    core.step(Tick(now + 1))  # no dock estimate any more: nothing changes it back
    step = core.step(Tension(now + 2, 10, float(tensions[-1, 10])))
    assert dict(zip(OUTPUT_FIELDS, step.outputs[0].values))['span_source'] == 0.0
    assert math.isfinite(uplift[-1, 10])


def test_a_line_that_disagrees_keeps_its_installed_span(config):
    """A load pin reading 30 % high is flagged by the dock estimate: its line falls back to
    the installed span (its own reading is not to be trusted), the others keep theirs."""
    depth, loads = SCENES['storm_from_port']
    _, tensions, _, spans = moorpy_scene(config, depth, loads[2:3])
    columns, depth_column = sensor_columns(config, depth, np.repeat(tensions, 3, axis=0))
    t, v = columns['line_03']
    columns['line_03'] = (t, v * np.where((t - T0_NS) * 1e-9 > 10.0, 1.3, 1.0))
    start = int(depth_column[0][0])
    ticks = tick_grid(start, int(t[-1]), config.alarm.diagnostic_rate)
    core = MonitorCore(config, start)
    for ev in events_of(config, columns, depth_column, ticks):
        core.step(ev)
    snap = {st.name: dict(st.values) for st in core.snapshot(core.state.last_ns).statuses}
    bad = snap['catenary_monitor: line_03']
    assert bad['sensor_state'] == 'inconsistent', bad
    assert bad['span_source'] == 'installed' and float(bad['span']) == 120.0
    for k, line in enumerate(config.lines):
        if line.name != 'line_03':
            good = snap[f'catenary_monitor: {line.name}']
            assert good['span_source'] == 'dock_estimate', (line.name, good)
            assert abs(float(good['span']) - spans[0, k]) < 0.05, line.name


@pytest.mark.parametrize('kernel', [True, False])
@pytest.mark.parametrize('ea', [None, 6.63e8])
def test_the_twins_solve_at_changing_spans_equals_solve(monkeypatch, config, kernel, ea):
    """The twin's solve of one line's updates at a span per update (the C kernel's path and
    the numpy one, inextensible and elastic) equals solve() on the same arrays."""
    from catenary_monitor.core.physics import fused_kernel
    from catenary_monitor.core.twin.solve_columns import critical_parameters, solve_updates

    if kernel and not fused_kernel.AVAILABLE:
        pytest.skip('the C kernel is not built')
    monkeypatch.setattr(fused_kernel, 'AVAILABLE', kernel and fused_kernel.AVAILABLE)
    line = dataclasses.replace(config.lines[10], ea=ea)
    rng = np.random.default_rng(4)
    n = 400
    tension = rng.uniform(3e5, 9e5, n)
    depth = rng.uniform(19.0, 23.0, n)
    depth[:3] = np.nan  # before the first depth
    span = line.anchor_distance + rng.uniform(-1.5, 1.5, n)
    values, status = solve_updates(
        line, tension, depth, critical_parameters(line, depth, span), span
    )
    good = ~np.isnan(depth)
    want = solve(
        line.weight, depth[good], tension=tension[good], anchor_distance=span[good],
        mbl=line.mbl, ea=ea,
    )  # fmt: skip
    assert np.all(status[good] == want.status) and np.all(status[~good] == -1)
    assert np.count_nonzero(np.asarray(want.uplift_force) > 0) > 50  # lifted and grounded
    keys = ('uplift_force', 'anchor_margin', 'tide_margin', 'load_margin', 'min_anchor_distance')
    for key in keys:
        np.testing.assert_allclose(
            values[key][good], getattr(want, key), rtol=1e-9, atol=1e-6, err_msg=key
        )
