"""Logs of the paper's dock generated from the dock model itself (the oracle is the equilibrium).

The dock (config/floating_dock.yaml, its 12 lines with a tension accuracy) moves under a wind
whose speed and direction change; each line's hook tension is the equilibrium tension at that
instant plus sensor noise of the stated accuracy; one sensor may drift.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import numpy as np
from replay_data import T0_NS

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.body.equilibrium import EquilibriumStatus, solve_equilibrium
from catenary_monitor.core.body.loads import environmental_load
from catenary_monitor.core.config.parameters import (
    MonitorConfig,
    config_from_params,
    load_params_file,
)

DOCK_YAML = Path(__file__).resolve().parents[1] / 'config' / 'floating_dock.yaml'
#: Tension sensor accuracy of the generated logs (1 sigma) [N].
ACCURACY = 20e3


def dock_config(accuracy: Optional[float] = ACCURACY, **settings: Any) -> MonitorConfig:
    """The paper's dock with ``tension_accuracy`` on every line (None: not given)."""
    flat = load_params_file(DOCK_YAML)
    for name in flat['lines']:
        if accuracy is not None:
            flat[f'{name}.tension_accuracy'] = accuracy
    flat.update(settings)
    return config_from_params(flat)


def wind_at(s: np.ndarray, seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """Wind speed [m/s] and direction [deg from] over the record: building from 8 to 26 m/s,
    veering +-30 deg around port beam."""
    return 8.0 + 18.0 * s / seconds, 270.0 + 30.0 * np.sin(2 * np.pi * s / (0.6 * seconds))


def true_tensions(
    config: MonitorConfig, seconds: float, grid: float = 1.0, depth: float = 20.85
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Equilibrium hook tensions (n, m) on a time grid [s], and the offsets (n, 3)."""
    model = DockModel.from_config(config)
    s = np.arange(0.0, seconds + grid, grid)
    speed, direction = wind_at(s, seconds)
    tensions, offsets = [], []
    start = None
    for v, phi in zip(speed, direction):
        load = environmental_load(config.dock, wind=float(v), wind_from=float(phi)).total
        eq = solve_equilibrium(model, depth, load, start=start)
        assert eq.status == EquilibriumStatus.CONVERGED and eq.lines is not None
        start = eq.offset
        tensions.append(eq.lines.statics.top_tension)
        offsets.append(eq.offset)
    return s, np.array(tensions), np.array(offsets)


def generate_dock(
    config: MonitorConfig,
    seconds: float = 180.0,
    rate: float = 4.0,
    seed: int = 1,
    drifting: Optional[int] = None,
    drift: float = 0.2,
    drift_from: float = 0.25,
    drift_to: float = 0.5,
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], tuple[np.ndarray, np.ndarray]]:
    """Tension per line and depth as (receive time ns, value) columns, as ``generate`` gives.

    Tensions at ``rate`` per line (jittered receive times): the dock's equilibrium tension
    (interpolated from a 1 s grid) plus Gaussian noise of ``ACCURACY``; line ``drifting`` reads
    high by up to ``drift`` (ramping from ``drift_from`` to ``drift_to`` of the record). Depth
    20.85 m at 1 Hz.
    """
    rng = np.random.default_rng(seed)
    grid, truth, _ = true_tensions(config, seconds)
    out = {}
    n = int(seconds * rate)
    for k, line in enumerate(config.lines):
        t = T0_NS + np.cumsum(rng.integers(int(0.6e9 / rate), int(1.4e9 / rate), n))
        s = (t - T0_NS) * 1e-9
        keep = s <= seconds
        t, s = t[keep], s[keep]
        v = np.interp(s, grid, truth[:, k]) + rng.normal(0.0, ACCURACY, s.size)
        if k == drifting:
            ramp = np.clip((s / seconds - drift_from) / (drift_to - drift_from), 0.0, 1.0)
            v = v * (1.0 + drift * ramp)
        out[line.name] = (t.astype(np.int64), v)
    td = T0_NS + int(0.35e9) + np.arange(int(seconds)) * 1_000_000_000
    return out, (td.astype(np.int64), np.full(td.size, 20.85))
