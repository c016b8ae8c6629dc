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
from catenary_monitor_study.body_peer import moorpy_equilibrium, moorpy_system

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
