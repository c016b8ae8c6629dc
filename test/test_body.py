"""core.body: the dock as one body. The paper's tables 2 and 3 through a one-line body, the
analytic stiffness, the statuses, the paper's load formulas, the uplift envelope."""

import dataclasses
import math

import numpy as np
import pytest
from dock_data import DOCK_YAML

from catenary_monitor import solve
from catenary_monitor.core.body.dock_model import DockModel, line_states
from catenary_monitor.core.body.envelope import first_lift, lift_indicator, uplift_envelope
from catenary_monitor.core.body.equilibrium import (
    EquilibriumStatus,
    line_report,
    solve_equilibrium,
)
from catenary_monitor.core.body.loads import environmental_load, push_direction
from catenary_monitor.core.config.parameters import (
    ConfigError,
    DockConfig,
    LineConfig,
    MonitorConfig,
    config_from_params,
    load_params_file,
)

W, H = 1300.0, 20.85


def one_line(chain_length, anchor_distance=120.0, heading=0.0, ea=None):
    line = LineConfig(
        'line_11',
        W,
        anchor_distance,
        4.827e6,
        hook_x=0.0,
        hook_y=0.0,
        heading=heading,
        chain_length=chain_length,
        ea=ea,
    )
    return DockModel.from_config(MonitorConfig(lines=(line,)))


def paper_dock():
    return config_from_params(load_params_file(DOCK_YAML))


def test_table_2_through_the_body_model():
    """Pretension R = 372 kN: the chain that gives it at x = 120 m sits at its reference."""
    ref = solve(W, H, horizontal=372e3, anchor_distance=120.0)
    chain = ref.suspended_length + 120.0 - ref.min_anchor_distance
    model = one_line(chain)
    eq = solve_equilibrium(model, H, np.array([-372e3, 0.0, 0.0]))  # a push aft, the line fore
    assert eq.status == EquilibriumStatus.CONVERGED
    assert abs(eq.offset_x) < 1e-9 and abs(eq.offset_y) < 1e-9
    row = line_report(model, eq.lines)[0]
    # The paper's table 2: T = 399.1048 kN, x = 108.5839 m (to its printed digits).
    assert row['top_tension'] == pytest.approx(399.1048e3, abs=1.0)
    assert row['min_anchor_distance'] == pytest.approx(108.5839, abs=1e-3)
    assert row['top_tension'] == pytest.approx(ref.top_tension, rel=1e-12)
    assert row['uplift_force'] == 0.0 and row['state'] == 'grounded'


def test_table_3_through_the_body_model():
    """Typhoon, line 11: R = 1584.6 kN at x = 121.06 m lifts the sinker by 193.26 kN."""
    ref = solve(W, H, horizontal=1584.6e3, anchor_distance=121.06)
    model = one_line(ref.suspended_length, anchor_distance=120.0)
    eq = solve_equilibrium(model, H, np.array([-1584.6e3, 0.0, 0.0]))
    assert eq.status == EquilibriumStatus.CONVERGED
    row = line_report(model, eq.lines)[0]
    assert row['anchor_distance'] == pytest.approx(121.06, abs=1e-9)  # dock moved 1.06 m aft
    assert eq.offset_x == pytest.approx(-1.06, abs=1e-9)
    assert row['state'] == 'lifted'
    for key in ('top_tension', 'uplift_force', 'anchor_angle_deg', 'top_angle_deg'):
        assert row[key] == pytest.approx(getattr(ref, key), rel=1e-9), key
    # The paper's digits (exact: alpha 6.95347 deg, F 193.258 kN, T 1623.446 kN; SEEDS errata).
    assert row['uplift_force'] == pytest.approx(193.26e3, abs=20.0)
    assert row['top_tension'] == pytest.approx(1623.448e3, abs=5.0)
    assert row['anchor_angle_deg'] == pytest.approx(6.9537, abs=1e-3)


def test_stiffness_is_the_derivative_of_the_restoring_force():
    model = DockModel.from_config(paper_dock())
    for q0 in (np.zeros(3), np.array([0.05, -0.4, 0.002]), np.array([-0.1, 0.5, -0.003])):
        k = line_states(model, H, q0).stiffness
        for j, e in enumerate((1e-6, 1e-6, 1e-8)):
            dq = np.zeros(3)
            dq[j] = e
            fd = -(
                line_states(model, H, q0 + dq).restoring - line_states(model, H, q0 - dq).restoring
            )
            fd /= 2 * e
            np.testing.assert_allclose(k[:, j], fd, rtol=2e-6, atol=1e-6 * np.abs(k).max())


def test_the_paper_dock_at_rest_and_symmetric_loads():
    model = DockModel.from_config(paper_dock())
    rest = solve_equilibrium(model, H, np.zeros(3))
    assert rest.status == EquilibriumStatus.CONVERGED and np.abs(rest.offset).max() < 1e-6
    assert rest.lines.statics.horizontal_tension == pytest.approx(372e3, rel=1e-3)
    a = solve_equilibrium(model, H, np.array([0.0, 1e6, 0.0]))
    b = solve_equilibrium(model, H, np.array([0.0, -1e6, 0.0]))
    assert a.offset_y == pytest.approx(-b.offset_y, rel=1e-2)  # line_11 is 1.06 m farther
    assert a.offset_y > 0  # pushed to port, moves to port


def test_statuses_are_named_never_silent():
    model = DockModel.from_config(paper_dock())
    assert solve_equilibrium(model, H, np.array([math.nan, 0, 0])).status == (
        EquilibriumStatus.BAD_INPUT
    )
    assert solve_equilibrium(model, -1.0, np.zeros(3)).status == EquilibriumStatus.BAD_INPUT
    # One line holds only toward its anchor: pulled the other way, the dock drifts off.
    single = one_line(122.6)
    eq = solve_equilibrium(single, H, np.array([1e5, 0.0, 0.0]))
    assert eq.status == EquilibriumStatus.NO_EQUILIBRIUM and 'drifts' in eq.message
    # A huge load on inextensible chains: the offset is found to rounding next to taut.
    eq = solve_equilibrium(model, H, np.array([0.0, -2e8, 0.0]))
    assert eq.status == EquilibriumStatus.CONVERGED


def test_elastic_lines_move_more_than_rigid_ones():
    config = paper_dock()
    rigid = DockModel.from_config(config)
    elastic = dataclasses.replace(rigid, ea=np.full(12, 6.63e8))
    load = np.array([0.0, -3e6, 0.0])
    a, b = solve_equilibrium(rigid, H, load), solve_equilibrium(elastic, H, load)
    assert b.status == a.status == EquilibriumStatus.CONVERGED
    assert b.offset_y < a.offset_y < 0


def test_the_paper_load_formulas_on_its_example_ship():
    """Example 1 (97 m ship): R1 = 83.93 kN printed (the formula gives 84.43: the paper's
    arithmetic slip), R2 = 5.70 kN (5.67), R3 = 11.96 kN, head on."""
    ship = DockConfig(
        length=97.0,
        beam=15.8,
        wind_area_x=107.0,
        hull_area_x=61.6,
        wind_area_y=1.0,
        hull_area_y=1.0,
        wetted_area=1500.0,
    )
    loads = environmental_load(ship, wind=30.0, wind_from=0.0, current=1.5, hs=1.5)
    assert -loads.wind[0] == pytest.approx(0.006 * 0.124 * 900 * (107 + 0.31 * 61.6) * 1e3)
    assert -loads.wind[0] == pytest.approx(84.43e3, abs=10.0)
    assert -loads.current[0] == pytest.approx(0.01 * 0.18 * 1500 * 1.5**1.83 * 1e3)
    assert -loads.current[0] == pytest.approx(5.67e3, abs=5.0)
    assert -loads.waves[0] == pytest.approx(11.96e3, abs=5.0)
    assert np.abs(loads.total[1:]).max() < 1e-9
    beam = environmental_load(ship, wind=30.0, wind_from=90.0)
    assert beam.wind[1] > 0 and abs(beam.wind[0]) < 1e-9  # from starboard: pushed to port
    with pytest.raises(ValueError, match='dock_wetted_area'):
        environmental_load(DockConfig(), current=1.0)
    assert push_direction(270.0) == pytest.approx([0.0, -1.0], abs=1e-12)


def test_first_lift_is_where_the_lowest_line_leaves_the_seabed():
    model = DockModel.from_config(paper_dock())
    pattern = np.array([*push_direction(270.0), 0.0])
    lift = first_lift(model, H, pattern, 1e5, 1e9)
    assert lift.status == 'lifts' and lift.line in {'line_09', 'line_10'}
    below = solve_equilibrium(model, H, lift.scale * 0.999 * pattern)
    above = solve_equilibrium(model, H, lift.scale * 1.001 * pattern)
    assert lift_indicator(model, below).min() > 0 > lift_indicator(model, above).min()


def test_envelope_of_the_paper_dock():
    model = DockModel.from_config(paper_dock())
    rows = uplift_envelope(model, H, np.arange(0.0, 360.0, 45.0))
    force = {r.direction_deg: r.force for r in rows}
    assert force[90.0] == pytest.approx(force[270.0], rel=1e-3)  # port/starboard symmetric
    assert force[90.0] > force[0.0]  # beam-on holds more force than head-on
    wind = {r.direction_deg: r.wind for r in rows}
    assert min(wind, key=wind.get) in (90.0, 270.0)  # the beam wind is the worst
    high = uplift_envelope(model, H + 1.0, np.array([270.0]))
    assert high[0].wind < wind[270.0]  # at high tide the sinkers lift earlier


def test_config_needs_the_whole_geometry():
    flat = load_params_file(DOCK_YAML)
    del flat['line_03.chain_length']
    with pytest.raises(ConfigError, match='line_03.chain_length'):
        config_from_params(flat)
    config = paper_dock()
    assert config.has_dock_model
    plain = MonitorConfig(lines=(LineConfig('a', W, 120.0, 4.8e6, heading=90.0),))
    assert not plain.has_dock_model
    with pytest.raises(ValueError, match='hook_x'):
        DockModel.from_config(plain)


def test_the_docs_page_parameter_table_is_generated_from_the_parameter_table():
    from pathlib import Path

    from catenary_monitor.core.config.parameters import parameters_markdown

    page = (Path(__file__).resolve().parents[1] / 'docs' / 'dock_body.md').read_text()
    begin, end = '<!-- dock-parameters:begin -->\n', '<!-- dock-parameters:end -->'
    assert page.split(begin, 1)[1].split(end, 1)[0] == parameters_markdown('dock')
