"""The dock model against MoorPy's System with one free body (surge, sway, yaw) and the same
twelve lines: offsets and hook tensions within MoorPy's own position tolerance."""

import dataclasses

import numpy as np
import pytest
from dock_data import DOCK_YAML

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.equilibrium import EquilibriumStatus, solve_equilibrium
from catenary_monitor.core.body.loads import environmental_load, push_direction
from catenary_monitor.core.config.parameters import config_from_params, load_params_file
from catenary_monitor_study.body_peer import moorpy_equilibrium, moorpy_lines, moorpy_system

TOL = 1e-4  # MoorPy's position tolerance [m] (solveEquilibrium(tol=...)), lines at 0.01 tol


def _models():
    config = config_from_params(load_params_file(DOCK_YAML))
    rigid = DockModel.from_config(config)
    return config, {
        'inextensible': rigid,
        'elastic': dataclasses.replace(rigid, ea=np.full(12, 6.63e8)),
    }


def _loads(config):
    out = []
    for phi in (0.0, 45.0, 100.0, 200.0, 270.0, 315.0):
        push = push_direction(phi)
        out.append(np.array([push[0] * 1.5e6, push[1] * 1.5e6, 0.0]))
    out.append(np.array([2e5, -5e5, 4e7]))  # with a yaw moment
    out.append(environmental_load(config.dock, wind=25.0, wind_from=290.0, hs=1.5).total)
    return out


@pytest.mark.parametrize('kind', ['elastic', 'inextensible'])
def test_offsets_and_tensions_agree_with_moorpy(kind):
    config, models = _models()
    model = models[kind]
    depth = 20.85
    system = moorpy_system(model, depth)
    for load in _loads(config):
        q_mp, t_mp, system = moorpy_equilibrium(model, depth, load, tol=TOL, system=system)
        eq = solve_equilibrium(model, depth, load)
        assert eq.status == EquilibriumStatus.CONVERGED
        assert abs(eq.offset_x - q_mp[0]) <= TOL and abs(eq.offset_y - q_mp[1]) <= TOL, load
        assert abs(eq.offset[2] - q_mp[2]) <= TOL / np.max(np.hypot(*model.hook.T)) * 2, load
        # A hook within 2 TOL of ours (translation and yaw) and lines solved to 0.01 TOL.
        st = eq.lines.statics
        slack = 2.02 * TOL * st.dt_ds + 1e-6 * st.top_tension
        assert np.all(np.abs(st.top_tension - t_mp) <= slack), (load, st.top_tension - t_mp)


def _with_point_loads():
    """The dock with a 40 kN clump weight 60 m up line_01 and a 20 kN buoy 70 m up line_06."""
    flat = load_params_file(DOCK_YAML)
    flat.update({'line_01.point_load_positions': [60.0], 'line_01.point_load_weights': [40e3]})
    flat.update({'line_06.point_load_positions': [70.0], 'line_06.point_load_weights': [-20e3]})
    return DockModel.from_config(config_from_params(flat, body_only=True))


@pytest.mark.parametrize('phi', [30.0, 210.0, 270.0, 330.0])
def test_point_loads_on_the_dock_agree_with_moorpy(phi):
    """Clump weight and buoy (MoorPy: free points between line pieces): both chains grounded
    and lifted across the rays, the clump down to half a metre above the seabed; the plain
    chains' tolerance (MoorPy's free points solved to TOL / 100: at TOL their position error
    alone moves a lifted chain's tension by ~3e-4)."""
    model = _with_point_loads()
    depth = 20.85
    push = push_direction(phi)
    load = np.array([push[0] * 1.0e6, push[1] * 1.0e6, 0.0])
    q_mp, t_mp, system = moorpy_equilibrium(model, depth, load, tol=TOL / 100)
    _, uplift_mp, _ = moorpy_lines(system)
    eq = solve_equilibrium(model, depth, load)
    assert eq.status == EquilibriumStatus.CONVERGED
    assert abs(eq.offset_x - q_mp[0]) <= TOL and abs(eq.offset_y - q_mp[1]) <= TOL
    assert abs(eq.offset[2] - q_mp[2]) <= TOL / np.max(np.hypot(*model.hook.T)) * 2
    st = eq.lines.statics
    slack = 2.02 * TOL * st.dt_ds + 1e-6 * st.top_tension
    assert np.all(np.abs(st.top_tension - t_mp) <= slack), st.top_tension - t_mp
    assert np.all(np.abs(st.uplift_force - uplift_mp) <= slack), st.uplift_force - uplift_mp


def test_uplift_envelope_with_a_buoy_lifts_where_moorpy_does():
    """The envelope's first lift from 180 deg (line_06, its buoy): MoorPy's anchor stays down
    at 0.99 of that load and lifts at 1.01."""
    from catenary_monitor.core.body.envelope import first_lift

    model = _with_point_loads()
    push = push_direction(180.0)
    pattern = np.array([push[0], push[1], 0.0])
    lift = first_lift(model, 20.85, pattern, 1e5, 1e7)
    assert lift.status == 'lifts' and lift.line == 'line_06'
    i = model.names.index('line_06')
    for factor, lifted in ((0.99, False), (1.01, True)):
        _, _, system = moorpy_equilibrium(model, 20.85, factor * lift.scale * pattern, TOL / 100)
        assert bool(moorpy_lines(system)[1][i] > 10.0) is lifted, factor
