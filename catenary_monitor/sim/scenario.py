"""The demo's episode (no rclpy): the seed paper's floating dock through a compressed storm,
as the dock simulator (:mod:`catenary_monitor.ros.simulator`) publishes it.

The episode (:class:`Scenario`, pure functions of time) is the paper's dock
(config/floating_dock.yaml) as one body (:mod:`catenary_monitor.core.body`): every tension comes
from the chains' geometry, the dock at rest where its chains balance the load, so its warnings
are the ones a real dock would give:

* tide: semi-diurnal (M2, 12.42 h) compressed into the episode, amplitude 0.5 m around the
  paper's 20.85 m, rising from low water at the start to high water half-way: the chains have a
  fixed length and their hooks rise with it, so every pretension grows with the tide;
* load: a storm from port (wind, current and waves from 270 deg, its centre 30 m forward of
  midship, so the forward port lines 10-12 take the most and line 11 first). It builds, pauses
  while the tide rises (line 11 at the edge of lifting: the monitor's bound warns first),
  builds again to a load (0.7 MN) that lifts the port sinkers, holds and eases;
* the dock's static equilibrium (:func:`~catenary_monitor.core.body.equilibrium.solve_equilibrium`)
  under that load at that tide, solved on a 0.25 s grid of the episode and interpolated;
* wave-frequency motion: the dock sways about its equilibrium (period ``wave_period``,
  amplitude growing with the storm), each line's tension that of its chain at the moved hook
  (:func:`~catenary_monitor.core.body.dock_model.line_states`), plus 0.3 % sensor noise.

:class:`MoorDynTensions` (``--dynamics moordyn``, ``catenary-monitor demo --moordyn``; the
``dynamics`` extra) takes the tensions from MoorDyn instead: the dock moved the same way, its
twelve chains lumped-mass lines with inertia, drag and seabed contact (20 segments each, the
paper chain's axial stiffness), stepped in real time; the same sensor noise.
"""

from __future__ import annotations

import functools
import math
import sys
from dataclasses import dataclass
from typing import Optional

import numpy as np

from catenary_monitor.core.body.dock_model import DockModel, line_states
from catenary_monitor.core.body.equilibrium import EquilibriumStatus, solve_equilibrium
from catenary_monitor.core.body.loads import push_direction
from catenary_monitor.core.config.parameters import MonitorConfig

__all__ = ['Scenario', 'MoorDynTensions', 'default_config_path']

#: Paper: depth at mean tide [m].
MEAN_DEPTH = 20.85
#: M2 tide period [s] (compressed into the episode).
M2_PERIOD = 12.42 * 3600.0
#: The storm: from port (deg, clockwise from the bow), its centre this far forward [m], and
#: its peak (N), which lifts the forward port sinkers at high water.
STORM_FROM = 270.0
STORM_ARM = 30.0
STORM_PEAK = 0.7e6


def default_config_path() -> str:
    """config/floating_dock.yaml, found without the ament index (source tree or pip install)."""
    from pathlib import Path

    here = Path(__file__).resolve().parent
    name = 'floating_dock.yaml'
    candidates = [
        here.parents[1] / 'config' / name,
        Path(sys.prefix) / 'share' / 'catenary_monitor' / 'config' / name,
    ]
    try:  # a colcon / ROS install
        from ament_index_python.packages import get_package_share_directory

        candidates.append(
            Path(get_package_share_directory('catenary_monitor')) / 'config' / 'floating_dock.yaml'
        )
    except Exception:  # noqa: BLE001 - no ament index on a pip install
        pass
    for path in candidates:
        if path.is_file():
            return str(path)
    raise FileNotFoundError(
        'config/floating_dock.yaml not found (looked in '
        + ', '.join(str(p) for p in candidates)
        + ')'
    )


def _span(names: list[str], order: list[str]) -> str:
    """``line_06 to line_12`` for three or more names in a run of ``order``, else the names
    joined."""
    at = [order.index(n) for n in names]
    if len(names) > 2 and at == list(range(at[0], at[0] + len(at))):
        return f'{names[0]} to {names[-1]}'
    return ', '.join(names)


def _smooth(u: float) -> float:
    """0 -> 1 cosine ramp on [0, 1], clipped."""
    u = min(max(u, 0.0), 1.0)
    return 0.5 - 0.5 * math.cos(math.pi * u)


@dataclass(frozen=True)
class Scenario:
    """The demo episode as pure functions of wall time ``t`` in [0, duration] (s).

    ``config`` must give the dock's geometry (``hook_x``, ``hook_y``, ``heading``,
    ``chain_length`` on every line), as config/floating_dock.yaml does.
    """

    config: MonitorConfig
    duration: float = 55.0
    wave_period: float = 4.0  # s (wall), the dock's wave-frequency sway
    wave_calm: float = 0.03  # m, sway amplitude when calm
    wave_storm: float = 0.15  # m, sway amplitude at the storm's peak
    noise: float = 0.003  # relative sensor noise (std)
    tide_amplitude: float = 0.5  # m
    build: tuple[float, float] = (0.12, 0.45)  # storm build from/to (fraction of duration)
    hold: tuple[float, float] = (0.25, 0.36)  # the build pauses (the tide rises) from/to
    hold_level: float = 0.35  # storm intensity during the pause (line 11 at the edge)
    ease: tuple[float, float] = (0.60, 0.80)  # storm eases from/to
    seed: int = 11
    grid: float = 0.25  # s, the equilibrium's grid
    storm_peak: float = STORM_PEAK  # N
    storm_arm: float = STORM_ARM  # m, the storm's centre forward of midship

    def storm(self, t: float) -> float:
        """Storm intensity 0..1 at time ``t``: up to ``hold_level`` by ``hold[0]``, kept there
        to ``hold[1]``, up to 1 by ``build[1]``, eased over ``ease``."""
        u = t / self.duration
        (b0, b1), (h0, h1) = self.build, self.hold
        first = self.hold_level * _smooth((u - b0) / (h0 - b0))
        second = (1.0 - self.hold_level) * _smooth((u - h1) / (b1 - h1))
        eased = 1.0 - _smooth((u - self.ease[0]) / (self.ease[1] - self.ease[0]))
        return (first + second) * eased

    def depth(self, t: float) -> float:
        """Tide depth [m]: one compressed M2 cycle from low water at the start, rising through
        the storm's build (fastest at the pause) to high water half-way."""
        phase = 2 * math.pi * t / self.duration
        return MEAN_DEPTH - self.tide_amplitude * math.cos(phase)

    def time_scale(self) -> float:
        """Simulated seconds of tide per wall second."""
        return M2_PERIOD / self.duration

    def episode(self, step: float = 0.25) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The episode on a grid: times [s], each line's hook tension [N] (waves, no sensor
        noise) and its anchor's uplift force [N] as the monitor's uplift alarm takes it: at
        the peak tension of the last ``wave_window`` plus ``wave_allowance`` x its half-range
        (the dynamic uplift), at the tide of the moment and the installed anchor distance."""
        from catenary_monitor.core.physics.solve import solve

        times = np.arange(0.0, self.duration + 1e-9, step)
        tensions = np.array([self.tensions(float(t)) for t in times])
        depth = np.array([self.depth(float(t)) for t in times])
        alarm = self.config.alarm
        n = max(int(round(alarm.wave_window / step)), 1)
        peak, low = tensions.copy(), tensions.copy()
        for i in range(len(times)):
            window = tensions[max(i - n + 1, 0) : i + 1]
            peak[i], low[i] = window.max(axis=0), window.min(axis=0)
        dynamic = peak + alarm.wave_allowance * (peak - low) / 2.0
        uplift = np.zeros_like(tensions)
        for k, line in enumerate(self.config.lines):
            r = solve(
                line.weight,
                depth - line.hook_height,
                tension=dynamic[:, k],
                anchor_distance=line.anchor_distance,
            )
            uplift[:, k] = np.nan_to_num(np.asarray(r.uplift_force, dtype=float))
        return times, tensions, uplift

    def story(self, moordyn: bool = False) -> list[str]:
        """The demo's banner, from the episode itself: the storm's load, the anchors it lifts
        (the most lifted one's peak tension) and how fast its time runs."""
        _, tensions, uplift = self.episode()
        names = [line.name for line in self.config.lines]
        allowed = np.array([line.allowed_uplift for line in self.config.lines])
        lifted = [names[k] for k in np.flatnonzero((uplift > allowed).any(axis=0))]
        hours = M2_PERIOD / 3600.0
        head = (
            f'a storm of {self.storm_peak / 1e6:.2f} MN from port builds while the tide rises, '
            'then eases'
        )
        if lifted:
            k = int(np.argmax(uplift.max(axis=0)))
            note = ' in the static episode; MoorDyn\'s differ' if moordyn else ''
            head += (
                f'; near high water it lifts the anchors of {_span(lifted, names)} at the wave '
                f'peaks ({names[k]} the most, its hook tension up to about '
                f'{tensions[:, k].max() / 1e3:.0f} kN{note}): warnings first on the lines '
                'coming close, then the uplift alarms, an alarm flood as they add up, and '
                'back to OK as the storm eases'
            )
        return [
            head,
            f'time x{self.time_scale():.0f}: one {hours:.2f} h tide in {self.duration:g} s of '
            'wall time (the alarm timings shortened to match)',
        ]

    def load(self, t: float) -> np.ndarray:
        """The storm's load on the dock at ``t``: (Fx, Fy, Mz) [N, N, N m]."""
        push = push_direction(STORM_FROM) * self.storm_peak * self.storm(t)
        return np.array([push[0], push[1], self.storm_arm * push[1]])

    def offsets(self) -> np.ndarray:
        """The dock's equilibrium offset (X, Y, psi) at every grid time (rows), solved once."""
        return _offsets(self)

    def offset(self, t: float) -> np.ndarray:
        """The dock's equilibrium offset at ``t`` (interpolated on the grid)."""
        table = self.offsets()
        u = min(max(t / self.grid, 0.0), len(table) - 1.0)
        k = min(int(u), len(table) - 2)
        return table[k] + (u - k) * (table[k + 1] - table[k])

    def position(self, t: float) -> np.ndarray:
        """The dock at ``t``: its equilibrium moved by the waves' sway, (X, Y, psi) [m, m,
        rad]."""
        amp = self.wave_calm + (self.wave_storm - self.wave_calm) * self.storm(t)
        sway = amp * math.sin(2 * math.pi * t / self.wave_period)
        return self.offset(t) + np.array([0.0, sway, 0.0])

    def motion(self, t: float, h: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
        """The dock's motion at ``t`` as MoorDyn takes it: ``(X, Y, psi, depth)`` and its rates
        (central differences over ``h`` s)."""

        def at(x: float) -> np.ndarray:
            return np.append(self.position(x), self.depth(x))

        return at(t), (at(t + h) - at(t - h)) / (2.0 * h)

    def noisy(self, tension: np.ndarray, rng: Optional[np.random.Generator]) -> np.ndarray:
        """The load pins' readings of ``tension`` [N] (relative noise ``noise``; none without
        ``rng``)."""
        if rng is None:
            return tension
        return tension * (1.0 + self.noise * rng.standard_normal(len(tension)))

    def tensions(self, t: float, rng: Optional[np.random.Generator] = None) -> np.ndarray:
        """Hook tension of every line [N] at ``t``: each chain at its hook, the dock at its
        equilibrium moved by the waves' sway."""
        lines = line_states(_model(self.config), self.depth(t), self.position(t))
        return self.noisy(np.asarray(lines.statics.top_tension, dtype=float), rng)


class MoorDynTensions:
    """The scenario's hook tensions from MoorDyn (:mod:`catenary_monitor.sim.moordyn_dock`):
    the dock moved as :meth:`Scenario.motion` says, its chains dynamic. The whole episode is
    computed once, every ``step`` s (MoorDyn is not real-time safe on a busy machine: a late
    step would make the body jump), and looked up by time, interpolated; :meth:`save` and
    :meth:`load` keep it in an ``.npz`` file (the demo computes it before the monitor starts).
    """

    def __init__(self, times: np.ndarray, table: np.ndarray, scenario: Scenario) -> None:
        self.times, self.table, self.scenario = times, table, scenario

    @classmethod
    def compute(
        cls, scenario: Scenario, segments: int = 20, step: float = 0.05
    ) -> 'MoorDynTensions':
        """Run MoorDyn over the episode (a few seconds of CPU for the demo's minute)."""
        from catenary_monitor.sim.moordyn_dock import PAPER_CHAIN, Chain, MoorDynDock

        chain = Chain(ea=PAPER_CHAIN.ea, segments=segments)
        times = np.arange(0.0, scenario.duration + 2.0 * step, step)
        q, v = scenario.motion(0.0)
        rows = []
        with MoorDynDock(_model(scenario.config), q, v, chain) as dock:
            for t in times.tolist():
                q, v = scenario.motion(t)
                dock.step(t, q, v)
                rows.append(dock.lines()[0])
        return cls(times, np.array(rows), scenario)

    def save(self, path: str) -> None:
        """The table as ``.npz`` (``times`` s, ``tensions`` N, lines in config order)."""
        np.savez(path, times=self.times, tensions=self.table)

    @classmethod
    def load(cls, path: str, scenario: Scenario) -> 'MoorDynTensions':
        """A table :meth:`save` wrote; ValueError naming what is wrong with it."""
        with np.load(path, allow_pickle=False) as data:
            times = np.asarray(data['times'], dtype=float)
            table = np.asarray(data['tensions'], dtype=float)
        lines = len(scenario.config.lines)
        if times.ndim != 1 or table.shape != (times.size, lines) or times.size < 2:
            raise ValueError(f'{path}: not a table of {lines} lines\' tensions over time')
        if not (np.all(np.isfinite(table)) and np.all(np.diff(times) > 0)):
            raise ValueError(f'{path}: tensions not finite or times not increasing')
        return cls(times, table, scenario)

    def tensions(self, t: float, rng: Optional[np.random.Generator] = None) -> np.ndarray:
        """Hook tension of every line [N] at ``t`` (the table interpolated, sensor noise
        added)."""
        u = float(np.clip(t, self.times[0], self.times[-1]))
        k = min(int(np.searchsorted(self.times, u, 'right')) - 1, len(self.times) - 2)
        w = (u - self.times[k]) / (self.times[k + 1] - self.times[k])
        return self.scenario.noisy((1.0 - w) * self.table[k] + w * self.table[k + 1], rng)


@functools.lru_cache(maxsize=8)
def _model(config: MonitorConfig) -> DockModel:
    return DockModel.from_config(config)


@functools.lru_cache(maxsize=8)
def _offsets(scenario: Scenario) -> np.ndarray:
    model = _model(scenario.config)
    rows, q = [], np.zeros(3)
    for t in np.arange(0.0, scenario.duration + 2 * scenario.grid, scenario.grid).tolist():
        eq = solve_equilibrium(model, scenario.depth(t), scenario.load(t), start=q)
        q = eq.offset if eq.status == EquilibriumStatus.CONVERGED else q
        rows.append(q)
    return np.array(rows)
