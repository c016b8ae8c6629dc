"""Days of a dock's normal operation (and the same with injected faults): the scenes and their
truth, from the dock's own physics.

A :class:`Scene` is a moored dock (its params file: lines, chains, geometry, sensors), a real
port's tide, the weather, the load cells and the tide gauge, and the faults injected. Its truth
is computed with the package's own dock body model (:mod:`catenary_monitor.core.body`):

* **tide**: the port's M2, S2, N2, K1 and O1 (amplitude, Greenwich phase lag) summed with their
  equilibrium arguments (Schureman's V0 from the mean longitudes s, h, p; the nodal factors
  f, u left at 1 and 0: a few percent and degrees), about the scene's mean depth, plus a
  slow meteorological residual (a random walk of a few cm): slack water where the sum turns;
* **weather**: a wind whose mean and direction wander over hours, with gusts of minutes; a
  tidal current following the tide's rate (flood one way, ebb the other); waves whose drift
  grows with the wind (``dock_*`` load formulas, :func:`~catenary_monitor.core.body.loads.
  environmental_load`); optionally a storm (for the units faults: a load that lifts a line);
* **the dock's offset**: the static equilibrium (:func:`~catenary_monitor.core.body.
  equilibrium.solve_equilibrium`) under that load at that depth, every ``grid`` s (the fixed-
  length chains: tensions consistent with the tide and the offset), interpolated;
* **waves**: the dock's wave-frequency surge, sway, yaw and the hooks' heave about it (an
  irregular sum of components with periods of seconds around ``tp``, scaled by the wave
  height), and each hook tension that of its chain at the moved hook
  (:func:`~catenary_monitor.core.physics.fixed_length.statics_at_span`, exact, vectorized).

:mod:`catenary_monitor_study.normal_days_log` turns a scene into what its sensors publish (the
message types real drivers publish, at their rates, with their resolution and noise, the
faults injected) and writes the MCAP log and the params file. Scenes are drawn from seeds: the
paper's dock (:func:`paper_scene`) or a dock you have not seen (:func:`drawn_scene`: another
geometry, chain, depth, port and weather).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NamedTuple, Optional

import numpy as np

from catenary_monitor.core.body.dock_model import DockModel, line_states
from catenary_monitor.core.body.equilibrium import EquilibriumStatus, solve_equilibrium
from catenary_monitor.core.body.loads import environmental_load, push_direction
from catenary_monitor.core.config.parameters import (
    MonitorConfig,
    config_from_params,
    load_params_file,
)
from catenary_monitor.core.physics.fixed_length import statics_at_span
from catenary_monitor.core.physics.solve import solve

__all__ = [
    'PORTS',
    'GAUGES',
    'FAULT_KINDS',
    'Port',
    'Gauge',
    'Cells',
    'Weather',
    'Storm',
    'Fault',
    'Scene',
    'Coarse',
    'paper_scene',
    'drawn_scene',
    'tide_level',
    'tide_table',
    'coarse',
    'hook_tensions',
    'wave_motion',
    'scene_margins',
    'truth_statics',
    'storm_line',
    'fit_mean_depth',
]

#: The paper's 81 mm U3 chain's axial stiffness, 1.01e8 d^2 kN (config/floating_dock.yaml) [N].
PAPER_EA = 6.63e8
#: Where the logs start by default: 2025-03-01 00:00 UTC [ns].
START_NS = 1_740_787_200_000_000_000
#: 2000-01-01 12:00 UTC (J2000) as Unix time [s]: the origin of the mean longitudes.
J2000_S = 946_728_000.0
FT = 0.3048


@dataclass(frozen=True)
class Port:
    """A real port's tide: constituents (name, amplitude m, Greenwich phase lag deg, speed
    deg/h) and where they come from."""

    key: str
    name: str
    source: str
    constituents: tuple[tuple[str, float, float, float], ...]


#: Two real ports (M2, S2, N2, K1, O1). Pillar Point Harbor (Half Moon Bay, California, NOAA
#: CO-OPS 9414131, harcon.json, feet -> m, phase_GMT): a mixed tide, strong diurnal
#: inequality, spring range about 2 m. Bermuda (St. Georges, NOAA 2695540): semidiurnal,
#: spring range about 0.9 m.
PORTS = {
    'pillar_point': Port(
        'pillar_point',
        'Pillar Point Harbor, Half Moon Bay CA',
        'NOAA CO-OPS 9414131 harmonic constituents (phase_GMT)',
        (
            ('M2', 1.78 * FT, 184.1, 28.984104),
            ('S2', 0.47 * FT, 189.6, 30.0),
            ('N2', 0.39 * FT, 158.4, 28.43973),
            ('K1', 1.15 * FT, 217.3, 15.041069),
            ('O1', 0.74 * FT, 203.3, 13.943035),
        ),
    ),
    'bermuda': Port(
        'bermuda',
        'St. Georges, Bermuda',
        'NOAA 2695540 harmonic constituents (Greenwich phase lag)',
        (
            ('M2', 0.367, 358.6, 28.9841042),
            ('S2', 0.080, 25.4, 30.0),
            ('N2', 0.085, 336.9, 28.4397295),
            ('K1', 0.067, 187.0, 15.0410686),
            ('O1', 0.054, 192.7, 13.9430356),
        ),
    ),
}


def _arguments(t: np.ndarray) -> dict[str, np.ndarray]:
    """Schureman's equilibrium arguments V [deg] of M2, S2, N2, K1, O1 at Unix times ``t`` [s]
    (T the mean sun's hour angle at Greenwich, s, h, p the mean longitudes of the moon, the
    sun and the lunar perigee; Meeus's rates per day from J2000)."""
    d = (np.asarray(t, np.float64) - J2000_S) / 86400.0
    s = 218.3165 + 13.17639648 * d
    h = 280.4665 + 0.98564736 * d
    p = 83.3532 + 0.11140353 * d
    hours = np.mod(np.asarray(t, np.float64), 86400.0) / 3600.0
    big_t = 180.0 + 15.0 * hours
    return {
        'M2': 2 * big_t - 2 * s + 2 * h,
        'S2': 2 * big_t,
        'N2': 2 * big_t - 3 * s + 2 * h + p,
        'K1': big_t + h - 90.0,
        'O1': big_t - 2 * s + h + 90.0,
    }


def tide_level(port: Port, t: np.ndarray) -> np.ndarray:
    """The astronomical tide about mean sea level [m] at Unix times ``t`` [s]."""
    v = _arguments(t)
    out = np.zeros(np.shape(t))
    for name, amp, g, _ in port.constituents:
        out = out + amp * np.cos(np.radians(v[name] - g))
    return out


def tide_table(port: Port, epoch: float) -> str:
    """The port's constituents as the monitor's ``tide_table`` (``NAME AMPLITUDE PHASE SPEED``,
    the phase referred to ``epoch`` [Unix s]: ``g - V(epoch)``), to be set with
    ``tide_table_epoch = epoch``."""
    v = _arguments(np.array([epoch]))
    parts = []
    for name, amp, g, speed in port.constituents:
        phase = float(np.mod(g - v[name][0], 360.0))
        parts.append(f'{name} {amp:.4f} {phase:.4f} {speed}')
    return '; '.join(parts)


@dataclass(frozen=True)
class Gauge:
    """A tide gauge: ``kind`` ``radar`` (sensor_msgs/Range, looking down from ``height`` m
    above the mean sea level), ``pressure`` (sensor_msgs/FluidPressure, vented, ``height`` m
    above the seabed) or ``float64`` (std_msgs/Float64, the depth itself); its output
    ``resolution`` [m], white ``noise`` [m, 1 sigma] before quantizing, samples every
    ``period`` s each the mean of the last ``average`` s of water level (radar and pressure
    gauges average the waves out; a pressure gauge also sees them attenuated by
    ``attenuation``), stamped by the driver ``delay`` s before they reach the monitor;
    ``double_read``: the chance per sample that the driver publishes a second reading a few
    ms later (a retried poll)."""

    key: str
    kind: str
    resolution: float
    noise: float = 0.0
    period: float = 1.0
    average: float = 1.0
    attenuation: float = 1.0
    height: float = 8.0
    delay: float = 0.05
    double_read: float = 0.0


#: The gauges of the benchmark: a radar gauge of 1 cm (a harbour's radar: 1 Hz, 30 s average,
#: 0.5 mm of noise left after it; ``radar_1cm_still``: none, so its output steps only when the
#: tide crosses a centimetre),
#: a pressure gauge of 1 mm with 2 mm noise (1 Hz, 1 s average, waves attenuated to a fifth at
#: the seabed, an occasional double read) and an ideal 1 mm gauge without noise (the still
#: water level itself, 1 Hz).
GAUGES = {
    'radar_1cm': Gauge('radar_1cm', 'radar', 0.01, noise=0.0005, average=30.0, height=8.0),
    'radar_1cm_still': Gauge('radar_1cm_still', 'radar', 0.01, average=30.0, height=8.0),
    'pressure_1mm': Gauge(
        'pressure_1mm',
        'pressure',
        0.001,
        noise=0.002,
        average=1.0,
        attenuation=0.2,
        height=1.0,
        double_read=5e-5,
    ),
    'exact_1mm': Gauge('exact_1mm', 'float64', 0.001, noise=0.0, average=0.0),
}


@dataclass(frozen=True)
class Cells:
    """The load cells: ``rate`` [Hz] through one gateway that reads them in turn
    (``stagger`` s apart) with ``jitter`` s of timing noise and delivers ``delay`` s later
    (``late`` of the deliveries wait ``late_s`` more and come in a bunch with the next);
    ``resolution`` [N] and white ``noise`` [N, 1 sigma]; ``loss``: the chance a sample is lost
    on the network (the node counts it from the sequence gap)."""

    rate: float = 10.0
    stagger: float = 0.002
    jitter: float = 0.0005
    delay: float = 0.004
    late: float = 2e-4
    late_s: float = 0.25
    resolution: float = 100.0
    noise: float = 500.0
    loss: float = 1e-6


@dataclass(frozen=True)
class Storm:
    """A storm: from ``direction`` [deg], its centre ``arm`` m forward of midship, building
    over ``rise`` s to a load that lifts line ``line``'s anchor by ``uplift`` N at ``peak``
    s after the start, held ``hold`` s, easing over ``fall`` s."""

    peak: float
    line: str
    uplift: float = 190e3
    direction: float = 270.0
    arm: float = 30.0
    rise: float = 3600.0
    hold: float = 1800.0
    fall: float = 3600.0


@dataclass(frozen=True)
class Weather:
    """Wind [m/s] of mean ``wind`` wandering by ``wander`` (periods of hours) with gusts of
    ``gust`` (a share, minutes), from ``direction`` +- ``veer`` deg; a tidal current up to
    ``current`` m/s (flooding from ``current_from``); waves of ``hs`` m (plus ``hs_per_wind``
    per m/s of wind) with a peak period ``tp`` s; the dock's wave-frequency motion per metre
    of wave height (``sway``, ``surge`` m, ``yaw`` rad, ``heave`` m, RMS); the sea level's
    meteorological ``residual`` [m, RMS, hours]."""

    wind: float = 7.0
    wander: float = 3.0
    gust: float = 0.15
    direction: float = 250.0
    veer: float = 25.0
    current: float = 0.25
    current_from: float = 200.0
    hs: float = 0.15
    hs_per_wind: float = 0.02
    tp: float = 6.0
    sway: float = 0.12
    surge: float = 0.06
    yaw: float = 2.5e-4
    heave: float = 0.05
    residual: float = 0.03
    storm: Optional[Storm] = None


#: The faults a scene can carry (:class:`Fault`).
FAULT_KINDS = (
    'gateway_drop',
    'silent_cell',
    'silent_gauge',
    'units_dan',
    'units_tf',
    'parted',
    'pressure_step',
)


@dataclass(frozen=True)
class Fault:
    """A fault from ``at`` s after the start for ``duration`` s (inf: to the end):

    * ``gateway_drop``: the load-cell gateway publishes nothing (every line silent);
    * ``silent_cell``: line ``line``'s load cell publishes nothing;
    * ``silent_gauge``: the tide gauge publishes nothing;
    * ``units_dan``: line ``line`` is set in N (``tension_scale`` 1) but its cell reports daN
      (from the start: an installer's mistake; the scene's storm lifts the line meanwhile: by
      default one from 270 deg lifting it by 190 kN, the bench's :func:`isolating_storm`);
    * ``units_tf``: line ``line`` is set in kN (``tension_scale`` 1000) but its cell reports
      tonnes-force (likewise);
    * ``parted``: line ``line``'s chain parts ``value`` m below its hook (the dock settles on the
      other lines; the cell then carries the chain left hanging);
    * ``pressure_step``: the pressure gauge steps to read ``value`` m of depth (a sensor
      failure: the membrane, the cable)."""

    kind: str
    at: float
    duration: float = math.inf
    line: Optional[str] = None
    value: float = math.nan

    def window(self, seconds: float, after: float = 120.0) -> tuple[float, float]:
        """The fault's window [s from the start]: from its start to ``after`` s past its end."""
        start = 0.0 if self.kind in ('units_dan', 'units_tf') else self.at
        return start, min(seconds, self.at + self.duration + after)


@dataclass(frozen=True)
class Scene:
    """A day (or days) at a dock: its params (flat, as a params file holds them), the port,
    weather, cells, gauge, faults, the mean depth at the hooks [m], length [s], start [ns] and
    seed."""

    name: str
    params: tuple[tuple[str, Any], ...]
    port: Port
    gauge: Gauge
    seconds: float = 2 * 86400.0
    mean_depth: float = 20.0
    weather: Weather = field(default_factory=Weather)
    cells: Cells = field(default_factory=Cells)
    faults: tuple[Fault, ...] = ()
    start_ns: int = START_NS
    seed: int = 1
    grid: float = 20.0

    @property
    def flat(self) -> dict[str, Any]:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.params}

    @property
    def config(self) -> MonitorConfig:
        """The monitor's configuration (the scene's params file)."""
        return _config(self.params)

    @property
    def start_s(self) -> float:
        return self.start_ns * 1e-9

    def fault(self, kind: str) -> Optional[Fault]:
        return next((f for f in self.faults if f.kind == kind), None)


@functools.lru_cache(maxsize=16)
def _config(params: tuple[tuple[str, Any], ...]) -> MonitorConfig:
    return config_from_params({k: (list(v) if isinstance(v, tuple) else v) for k, v in params})


def _frozen(flat: dict[str, Any]) -> tuple[tuple[str, Any], ...]:
    return tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in flat.items())


# --- scenes ---------------------------------------------------------------------------------


def _dock_yaml() -> Path:
    return Path(__file__).resolve().parents[1] / 'config' / 'floating_dock.yaml'


def _sensor_params(flat: dict[str, Any], gauge: Gauge, mean_depth: float, kinds: dict) -> None:
    """The sensors' part of the params: each line's message type and scale, the gauge's."""
    for name, (kind, scale) in kinds.items():
        flat[f'{name}.tension_type'] = (
            'geometry_msgs/msg/WrenchStamped' if kind == 'wrench' else 'std_msgs/msg/Float64'
        )
        if kind == 'wrench':
            flat[f'{name}.tension_axis'] = 'x'
        flat[f'{name}.tension_scale'] = scale
    if gauge.kind == 'radar':
        flat['depth_type'] = 'sensor_msgs/msg/Range'
        flat['gauge_height'] = round(mean_depth + gauge.height, 3)
    elif gauge.kind == 'pressure':
        flat['depth_type'] = 'sensor_msgs/msg/FluidPressure'
        flat['gauge_height'] = gauge.height
        flat['atmospheric_pressure'] = 0.0
    else:
        flat['depth_type'] = 'std_msgs/msg/Float64'
    flat['depth_resolution'] = gauge.resolution


def _line_kinds(names: list[str]) -> dict[str, tuple[str, float]]:
    """Each line's message type and scale: the first third WrenchStamped (N), the next third
    Float64 in kN (scale 1000), the rest Float64 in N."""
    n = len(names)
    out = {}
    for k, name in enumerate(names):
        if k < n // 3:
            out[name] = ('wrench', 1.0)
        elif k < 2 * n // 3:
            out[name] = ('kn', 1000.0)
        else:
            out[name] = ('n', 1.0)
    return out


def _apply_faults(kinds: dict[str, tuple[str, float]], faults: tuple[Fault, ...]) -> None:
    for f in faults:
        if f.kind == 'units_dan' and f.line:
            kinds[f.line] = ('n', 1.0)
        elif f.kind == 'units_tf' and f.line:
            kinds[f.line] = ('kn', 1000.0)


def paper_scene(
    gauge: str = 'radar_1cm',
    port: str = 'pillar_point',
    days: float = 2.0,
    faults: tuple[Fault, ...] = (),
    seed: int = 1,
    weather: Optional[Weather] = None,
    settings: Optional[dict[str, Any]] = None,
    mean_depth: Optional[float] = None,
) -> Scene:
    """The paper's dock (config/floating_dock.yaml, 12 lines of 81 mm U3 chain, 246 m x 51 m)
    at ``port`` read by ``gauge``, its mean depth fitted so that the fixed-length chains keep
    their margins over the port's tide (:func:`fit_mean_depth`) unless ``mean_depth`` is given."""
    flat = load_params_file(_dock_yaml())
    flat.pop('log_dir', None)
    names = list(flat['lines'])
    for name in names:  # the 81 mm chain's stiffness (the params file's note): finite storms
        flat[f'{name}.ea'] = PAPER_EA
    return _scene(f'paper-{port}-{gauge}', flat, names, PORTS[port], GAUGES[gauge], days,
                  faults, seed, weather or Weather(), settings, 20.85, mean_depth)  # fmt: skip


def _scene(
    name: str,
    flat: dict[str, Any],
    names: list[str],
    port: Port,
    gauge: Gauge,
    days: float,
    faults: tuple[Fault, ...],
    seed: int,
    weather: Weather,
    settings: Optional[dict[str, Any]],
    design: float,
    mean_depth: Optional[float] = None,
) -> Scene:
    kinds = _line_kinds(names)
    _apply_faults(kinds, faults)
    name += ''.join(f'-{f.kind}' for f in faults)
    flat['tide_table'] = tide_table(port, START_NS * 1e-9)
    flat['tide_table_epoch'] = START_NS * 1e-9
    flat.update(settings or {})
    base = Scene(name, _frozen(flat), port, gauge, days * 86400.0, 20.0, weather, Cells(),
                 faults, START_NS, seed)  # fmt: skip
    depth = _fitted(_physics(base), design) if mean_depth is None else mean_depth
    flat = dict(base.flat)
    _sensor_params(flat, gauge, depth, kinds)
    flat.update(settings or {})
    scene = replace(base, params=_frozen(flat), mean_depth=depth)
    storm_line = next((f.line for f in faults if f.kind in ('units_dan', 'units_tf')), None)
    if storm_line is not None and weather.storm is None:
        scene = replace(scene, weather=replace(weather, storm=Storm(0.5 * scene.seconds,
                                                                    storm_line)))  # fmt: skip
    return scene


def drawn_scene(
    seed: int,
    gauge: Optional[str] = None,
    days: float = 2.0,
    faults: tuple[Fault, ...] = (),
    settings: Optional[dict[str, Any]] = None,
) -> Scene:
    """A dock you have not seen, drawn from ``seed``: a pontoon of 80-250 m by 20-50 m moored
    by 4-12 lines of U3 stud-link chain of 48-90 mm (elastic: EA = 1.01e8 d^2 kN) at 8-30 m
    depth, a pretension of 5-9 % of
    the MBL with 10-25 m of chain on the seabed; one of the ports; the weather drawn too; the gauge
    drawn unless given."""
    rng = np.random.default_rng(10_000 + seed)
    length = float(rng.uniform(80.0, 250.0))
    beam = float(rng.uniform(20.0, min(50.0, length / 2.5)))
    per_side = int(rng.integers(2, 7))
    d_mm = float(rng.uniform(48.0, 90.0))
    depth = float(rng.uniform(8.0, 30.0))
    weight = round(0.0219 * d_mm**2 * 9.80665 * 0.87, 1)  # stud link, N/m in water
    mbl = round(0.01961 * d_mm**2 * (44.0 - 0.08 * d_mm) * 1e3, -2)  # U3, N
    pretension = float(rng.uniform(0.05, 0.09)) * mbl
    reach = solve(weight, depth, tension=pretension, anchor_distance=1e4).min_anchor_distance
    x_anchor = round(float(reach) + float(rng.uniform(10.0, 25.0)), 2)
    names = [f'ml{k + 1}' for k in range(2 * per_side)]
    xs = np.linspace(-0.42 * length, 0.42 * length, per_side)
    flat: dict[str, Any] = {'lines': names, 'depth_topic': '/harbour/tide'}
    fix = solve(weight, depth, tension=pretension, anchor_distance=x_anchor)
    chain = round(float(fix.suspended_length) + x_anchor - float(fix.min_anchor_distance), 4)
    hooks = [(float(x), -beam / 2) for x in xs[::-1]] + [(float(x), beam / 2) for x in xs]
    for name, (x, y) in zip(names, hooks):
        # anchors abeam (90 deg starboard, 270 port), the end lines splayed 45 deg outward
        splay = 45.0 * (abs(x) / max(float(np.max(np.abs(xs))), 1.0)) ** 2
        toward_bow = 1.0 if x > 0 else -1.0
        heading = 90.0 - toward_bow * splay if y < 0 else 270.0 + toward_bow * splay
        flat.update({
            f'{name}.weight': weight,
            f'{name}.anchor_distance': x_anchor,
            f'{name}.mbl': mbl,
            f'{name}.hook_x': round(x, 2),
            f'{name}.hook_y': round(y, 2),
            f'{name}.heading': round(heading % 360.0, 2),
            f'{name}.chain_length': chain,
            f'{name}.ea': round(1.01e11 * (d_mm / 1000.0) ** 2, -4),
            f'{name}.tension_topic': f'/cells/{name}/force',
        })  # fmt: skip
    freeboard, walls = float(rng.uniform(1.5, 3.0)), float(rng.uniform(0.0, 10.0))
    draft = float(rng.uniform(2.0, 5.0))
    flat.update({
        'dock_length': round(length, 2),
        'dock_beam': round(beam, 2),
        'dock_wind_area_x': round(beam * 0.2 * walls, 2),
        'dock_hull_area_x': round(beam * freeboard, 2),
        'dock_wind_area_y': round(length * walls, 2),
        'dock_hull_area_y': round(length * freeboard, 2),
        'dock_wetted_area': round(length * beam + 2 * (length + beam) * draft, 2),
        'anchor_margin_warn': round(0.4 * (x_anchor - float(fix.min_anchor_distance)), 2),
        'clear_hold': 30.0,
    })  # fmt: skip
    port = PORTS[('pillar_point', 'bermuda')[int(rng.integers(0, 2))]]
    weather = Weather(
        wind=float(rng.uniform(3.0, 9.0)),
        wander=float(rng.uniform(1.0, 3.0)),
        direction=float(rng.uniform(0.0, 360.0)),
        current=float(rng.uniform(0.0, 0.4)),
        current_from=float(rng.uniform(0.0, 360.0)),
        hs=float(rng.uniform(0.05, 0.3)),
        tp=float(rng.uniform(3.5, 8.0)),
    )
    gauge_key = gauge or tuple(GAUGES)[int(rng.integers(0, len(GAUGES)))]
    return _scene(f'drawn{seed}-{port.key}-{gauge_key}', flat, names, port, GAUGES[gauge_key],
                  days, faults, seed, weather, settings, depth)  # fmt: skip


# --- the truth ------------------------------------------------------------------------------


class Coarse(NamedTuple):
    """A scene's slow truth on its grid: times [s from the start], still-water depth at the
    hooks [m], wind [m/s] and its direction [deg from], current [m/s, signed], wave height
    [m], the load (n, 3) and the dock's offset (n, 3); ``parted``: from which grid row a
    parted line is gone (n: never)."""

    t: np.ndarray
    depth: np.ndarray
    wind: np.ndarray
    wind_from: np.ndarray
    current: np.ndarray
    hs: np.ndarray
    load: np.ndarray
    offset: np.ndarray
    parted: int


def _ou(rng: np.random.Generator, n: int, dt: float, tau: float) -> np.ndarray:
    """A unit-variance Ornstein-Uhlenbeck series of time constant ``tau`` [s]."""
    a = math.exp(-dt / tau)
    e = rng.standard_normal(n) * math.sqrt(1 - a * a)
    out = np.empty(n)
    x = rng.standard_normal()
    for i in range(n):  # n is the coarse grid: a few 10k
        x = a * x + e[i]
        out[i] = x
    return out


def still_depth(scene: Scene, t: np.ndarray, rng_seed: Optional[int] = None) -> np.ndarray:
    """The still-water depth at the hooks [m] at ``t`` [s from the start]: the mean depth, the
    port's tide and the residual (interpolated from its own 60 s random walk)."""
    t = np.asarray(t, np.float64)
    tide = tide_level(scene.port, scene.start_s + t)
    return scene.mean_depth + tide + _residual(scene)(t)


@functools.lru_cache(maxsize=8)
def _residual_table(seed: int, seconds: float, rms: float) -> tuple[np.ndarray, np.ndarray]:
    """The sea level's meteorological residual [m] every 60 s: six slow swells of periods
    3-30 h (random phases), ``rms`` in all: smooth, as a surge is (at most about rms x 2 pi /
    3 h ~ 2e-5 m/s for 3 cm)."""
    rng = np.random.default_rng(seed * 7919 + 17)
    grid = np.arange(0.0, seconds + 120.0, 60.0)
    periods = rng.uniform(3.0, 30.0, 6) * 3600.0
    phases = rng.uniform(0.0, 2 * np.pi, 6)
    walk = np.cos(2 * np.pi * grid[:, None] / periods[None, :] + phases[None, :]).sum(axis=1)
    return grid, rms * walk / math.sqrt(3.0)


def _residual(scene: Scene) -> Any:
    grid, walk = _residual_table(scene.seed, scene.seconds, scene.weather.residual)
    return lambda t: np.interp(t, grid, walk)


def _model(scene: Scene, without: Optional[str] = None) -> DockModel:
    return _cached_model(scene.params, without)


@functools.lru_cache(maxsize=16)
def _cached_model(params: tuple[tuple[str, Any], ...], without: Optional[str]) -> DockModel:
    config = _config(params)
    if without is not None:
        flat = config_to_flat(params)
        names = [n for n in flat['lines'] if n != without]
        flat = {k: v for k, v in flat.items() if not k.startswith(f'{without}.')}
        flat['lines'] = names
        config = config_from_params(flat)
    return DockModel.from_config(config)


def config_to_flat(params: tuple[tuple[str, Any], ...]) -> dict[str, Any]:
    return {k: (list(v) if isinstance(v, tuple) else v) for k, v in params}


def _storm_shape(storm: Storm, t: np.ndarray) -> np.ndarray:
    """0..1: the storm's intensity at ``t`` [s]."""
    u0 = storm.peak - storm.hold / 2 - storm.rise
    up = np.clip((t - u0) / storm.rise, 0.0, 1.0)
    down = np.clip((t - storm.peak - storm.hold / 2) / storm.fall, 0.0, 1.0)
    return (0.5 - 0.5 * np.cos(np.pi * up)) * (0.5 + 0.5 * np.cos(np.pi * down))


def _loads(scene: Scene, c: dict[str, np.ndarray]) -> np.ndarray:
    dock = scene.config.dock
    rows = []
    for v, phi, cur, hs in zip(c['wind'], c['wind_from'], c['current'], c['hs']):
        cur_from = scene.weather.current_from + (0.0 if cur >= 0 else 180.0)
        wind_part = environmental_load(dock, wind=float(v), wind_from=float(phi), hs=float(hs))
        cur_part = environmental_load(dock, current=abs(float(cur)), current_from=cur_from)
        rows.append(wind_part.total + cur_part.total)
    return np.array(rows)


def _weather_series(scene: Scene, t: np.ndarray) -> dict[str, np.ndarray]:
    """Wind, its direction, the current and the wave height at ``t`` [s from the start]: one
    realization per scene (drawn on its grid, interpolated), whatever times are asked."""
    grid, table = _weather_table(scene.weather, scene.seed, scene.seconds, scene.grid)
    out = {k: np.interp(t, grid, v) for k, v in table.items()}
    w = scene.weather
    rate = _tide_rate(scene.port, scene.start_s, t)
    peak = max(float(np.max(np.abs(_tide_rate(scene.port, scene.start_s, grid)))), 1e-9)
    out['current'] = w.current * rate / peak
    return out


def _tide_rate(port: Port, start: float, t: np.ndarray) -> np.ndarray:
    """The tide's rate [m/s] at ``t`` [s from ``start``] (central difference over 60 s)."""
    t = np.asarray(t, np.float64)
    return (tide_level(port, start + t + 30.0) - tide_level(port, start + t - 30.0)) / 60.0


@functools.lru_cache(maxsize=8)
def _weather_table(
    w: Weather, seed: int, seconds: float, grid: float
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    rng = np.random.default_rng(seed * 104729 + 3)
    t = np.arange(0.0, seconds + 3 * grid, grid)
    n = len(t)
    wander = _ou(rng, n, grid, 4 * 3600.0)
    gust = _ou(rng, n, grid, 90.0)
    veer = _ou(rng, n, grid, 3 * 3600.0)
    wind = np.clip(w.wind + w.wander * wander, min(0.5, w.wind), None) * (1.0 + w.gust * gust)
    wind = np.clip(wind, 0.0, None)
    table = {
        'wind': wind,
        'wind_from': w.direction + w.veer * veer,
        'hs': w.hs + w.hs_per_wind * wind,
    }
    return t, table


#: The params that make a scene's physics (the others are its sensors' and the monitor's).
_PHYSICS = ('lines', 'weight', 'anchor_distance', 'mbl', 'hook_x', 'hook_y', 'hook_height',
            'heading', 'chain_length', 'ea', 'allowed_uplift')  # fmt: skip


def _physics(scene: Scene) -> Scene:
    """The scene as its physics sees it (the sensors, the monitor's settings and the faults
    but a parted chain left out): the key of what is computed once per dock and weather."""
    kept = ('anchor_margin_warn', 'anchor_margin_deadband', 'tide_margin_warn',
            'tide_margin_deadband', 'tension_accuracy')  # fmt: skip
    physics = tuple(
        (k, v)
        for k, v in scene.params
        if k.split('.')[-1] in _PHYSICS + kept
        or k.split('.')[-1].startswith(('dock_', 'point_load'))
    )
    return replace(scene, name='', params=physics, gauge=GAUGES['exact_1mm'], cells=Cells(),
                   faults=tuple(f for f in scene.faults if f.kind == 'parted'))  # fmt: skip


@functools.lru_cache(maxsize=8)
def _fitted(scene: Scene, design: float) -> float:
    return fit_mean_depth(scene, design)


def coarse(scene: Scene, grid: Optional[float] = None) -> Coarse:
    """The scene's slow truth every ``grid`` s (default the scene's): the dock at rest where
    its chains balance wind, current and wave drift (and the storm) at the still-water depth;
    after a parted fault, on the remaining lines. Scenes that differ only in their sensors
    share it (computed once)."""
    return _coarse(_physics(scene), grid or scene.grid)


@functools.lru_cache(maxsize=4)
def _coarse(scene: Scene, grid: float) -> Coarse:
    t = np.arange(0.0, scene.seconds + 2 * grid, grid)
    depth = still_depth(scene, t)
    c = _weather_series(scene, t)
    load = _loads(scene, c)
    storm = scene.weather.storm
    if storm is not None:
        peak = _storm_peak(scene, storm)
        push = push_direction(storm.direction)
        shape = _storm_shape(storm, t)
        load = load + shape[:, None] * peak * np.array([push[0], push[1], storm.arm * push[1]])
    parted = scene.fault('parted')
    cut = len(t) if parted is None else int(np.searchsorted(t, parted.at))
    offsets = np.zeros((len(t), 3))
    q = np.zeros(3)
    for i in range(len(t)):
        model = _model(scene, parted.line if parted is not None and i >= cut else None)
        eq = solve_equilibrium(model, float(depth[i]), load[i], start=q)
        if eq.status == EquilibriumStatus.CONVERGED:
            q = eq.offset
        offsets[i] = q
    return Coarse(t, depth, c['wind'], c['wind_from'], c['current'], c['hs'], load, offsets, cut)


def _storm_peak(scene: Scene, storm: Storm) -> float:
    """The storm's load [N] that lifts ``storm.line``'s anchor by ``storm.uplift`` at its peak
    (bisection on the dock's equilibrium at the still-water depth then; no wind besides)."""
    model = _model(scene)
    k = list(model.names).index(storm.line)
    depth = float(still_depth(scene, np.array([storm.peak]))[0])
    push = push_direction(storm.direction)
    unit = np.array([push[0], push[1], storm.arm * push[1]])

    def uplift(p: float) -> float:
        eq = solve_equilibrium(model, depth, p * unit)
        if eq.status != EquilibriumStatus.CONVERGED or eq.lines is None:
            return math.inf
        return float(eq.lines.statics.uplift_force[k])

    lo, hi = 0.0, 1e5
    while uplift(hi) < storm.uplift and hi < 1e9:
        lo, hi = hi, 2 * hi
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if uplift(mid) < storm.uplift else (lo, mid)
    return hi


def storm_line(scene: Scene, direction: Optional[float] = None) -> str:
    """The line a storm from ``direction`` [deg; default the weather's storm's, else 270]
    loads most (its tension under 0.5 MN at the mean depth): the line it lifts first."""
    storm = scene.weather.storm
    direction = direction if direction is not None else (storm.direction if storm else 270.0)
    push = push_direction(direction)
    model = _model(scene)
    arm = 30.0 if storm is None else storm.arm
    load = 0.5e6 * np.array([push[0], push[1], arm * push[1]])
    eq = solve_equilibrium(model, scene.mean_depth, load)
    if eq.lines is None:
        return model.names[0]
    return model.names[int(np.nanargmax(eq.lines.statics.top_tension))]


#: The uplift [N] at its peak of the storm a units scene's line is read in: its anchor lifts, the
#: other lines' anchors keep their margins (:func:`isolating_storm`). A storm that lifts one
#: chain by 190 kN (the paper's typhoon) drags a rigid dock far enough that its neighbours lift
#: or warn too: on ``drawn:2`` the best direction and centre leave the nearest other line no
#: grounded chain to spare (1.7 m); at 5 kN they keep an anchor margin of 11 m.
UNITS_UPLIFT = 5e3


def isolating_storm(
    scene: Scene, uplift: float = UNITS_UPLIFT, lines: Optional[tuple[str, ...]] = None
) -> Storm:
    """A storm at the scene's half-time lifting one line's anchor by ``uplift`` N at its peak
    while the other lines keep the largest anchor margin: the line (of ``lines``, default the
    end lines, the hooks farthest fore and aft: a storm loads an inner line together with its
    neighbours), the direction and the centre's arm searched (every 30 deg, arms -1, -0.5, 0,
    0.5, 1 x half the dock's length; then 10 deg and 0.1 x about the best), each storm's load by
    bisection on the dock's equilibrium at the still-water depth of its peak (no wind besides),
    the margins the monitor's (:func:`~catenary_monitor.core.physics.solve.solve` at the lines'
    tensions)."""
    return _isolating(_physics(scene), scene.seconds, uplift, lines)


@functools.lru_cache(maxsize=8)
def _isolating(
    scene: Scene, seconds: float, uplift: float, lines: Optional[tuple[str, ...]]
) -> Storm:
    model = _model(scene)
    names = list(model.names)
    peak = 0.5 * seconds
    depth = float(still_depth(scene, np.array([peak]))[0])
    x = np.array([line.anchor_distance for line in scene.config.lines])
    length = scene.config.dock.length or 0.0
    half = 0.5 * length if length > 0.0 else 50.0

    def least(k: int, direction: float, arm: float, steps: int) -> float:
        """The other lines' least anchor margin [m] when the storm lifts line k by ``uplift``."""
        push = push_direction(direction)
        unit = np.array([push[0], push[1], arm * push[1]])

        def at(p: float) -> Any:
            eq = solve_equilibrium(model, depth, p * unit)
            if eq.status != EquilibriumStatus.CONVERGED or eq.lines is None:
                return None
            return eq.lines.statics

        lo, hi = 0.0, 2e4
        while True:
            st = at(hi)
            if st is None or hi > 1e9:
                return -math.inf
            if st.uplift_force[k] >= uplift:
                break
            lo, hi = hi, 2 * hi
        for _ in range(steps):
            mid = 0.5 * (lo + hi)
            st = at(mid)
            if st is None:
                return -math.inf
            lo, hi = (mid, hi) if st.uplift_force[k] < uplift else (lo, mid)
        st = at(hi)
        if st is None:
            return -math.inf
        r = solve(model.weight, depth + model.hook_height, tension=st.top_tension,
                  anchor_distance=x)  # fmt: skip
        with np.errstate(invalid='ignore'):
            margin = np.where(np.isfinite(r.anchor_margin), r.anchor_margin, -np.inf)
        return float(np.min(np.delete(margin, k)))

    if lines is None:
        hook_x = np.array([abs(line.hook_x or 0.0) for line in scene.config.lines])
        lines = tuple(n for n, h in zip(names, hook_x) if h >= float(np.max(hook_x)) - 1e-6)
    candidates = [names.index(n) for n in lines]
    coarse_grid = [(least(k, d, a * half, 8), k, d, a * half) for k in candidates
                   for d in range(0, 360, 30) for a in (-1.0, -0.5, 0.0, 0.5, 1.0)]
    _, k, d0, a0 = max(coarse_grid)
    fine = [(least(k, (d0 + d) % 360, a0 + a * half, 14), k, (d0 + d) % 360, a0 + a * half)
            for d in (-20, -10, 0, 10, 20) for a in (-0.1, 0.0, 0.1)
            if abs(a0 + a * half) <= half]  # fmt: skip
    _, k, direction, arm = max(fine)
    return Storm(peak, names[k], uplift, float(direction), float(arm))


def fit_mean_depth(scene: Scene, design: float, clearance: float = 1.5) -> float:
    """The mean depth [m] at which the scene's chains keep, over its port's tide (three days or
    the scene, every 30 min: an M2 crest sampled there is within 0.2 % of its amplitude) and
    weather (its 200 strongest winds also at high water; no storm), an anchor margin of
    ``anchor_margin_warn + anchor_margin_deadband + clearance`` and a tide margin of
    ``tide_margin_warn + tide_margin_deadband + clearance``: the depth the fixed-length chains
    were laid for, so that a normal day alarms nothing: the margins taken at each line's
    wave-peak tension (four standard deviations of the waves' motion, :func:`_wave_peak`) plus
    its sensor accuracy, as the monitor's bounds take them (bisection in ``[0.6, 1.2] x
    design``)."""
    config = scene.config
    a = config.alarm
    need_anchor = a.anchor_margin_warn + a.anchor_margin_deadband + clearance
    need_tide = a.tide_margin_warn + a.tide_margin_deadband + clearance
    grid, table = _weather_table(scene.weather, scene.seed, scene.seconds, scene.grid)
    # the tide over at least three days (a short scene's dock was laid for its port, not for
    # its hours), the weather where it is; the 200 strongest winds also at high water
    span = max(scene.seconds, 3 * 86400.0)
    t_tide = np.arange(0.0, span, 1800.0)
    level = tide_level(scene.port, scene.start_s + t_tide) + _residual(scene)(t_tide)
    strongest = grid[np.argsort(table['wind'])[-200:]]
    t = np.concatenate([np.mod(t_tide, scene.seconds), strongest])
    tide = np.concatenate([level, np.full(len(strongest), float(np.max(level)))])
    weather = _weather_series(scene, t)
    loads = _loads(scene, weather)
    model = _model(scene)
    x = np.array([line.anchor_distance for line in config.lines])
    hs = scene.weather.hs + scene.weather.hs_per_wind * weather['wind']
    accuracy = model.tension_accuracy

    def worst(mean: float) -> float:
        q, least = np.zeros(3), math.inf
        for d, load, h_s in zip(mean + tide, loads, hs):
            eq = solve_equilibrium(model, float(d), load, start=q)
            if eq.status != EquilibriumStatus.CONVERGED or eq.lines is None:
                return -math.inf
            q = eq.offset
            peak = _wave_peak(scene, model, eq.lines, float(d), float(h_s)) + accuracy
            r = solve(model.weight, d + model.hook_height, tension=peak, anchor_distance=x)
            with np.errstate(invalid='ignore'):
                m = min(float(np.min(r.anchor_margin)) - need_anchor,
                        float(np.min(r.tide_margin)) - need_tide)  # fmt: skip
            least = min(least, m if math.isfinite(m) else -math.inf)
        return least

    lo, hi = 0.6 * design, 1.2 * design
    if worst(lo) < 0:
        return round(lo, 3)
    for _ in range(11):  # 0.6 x design / 2^11: 6 mm at 20 m, the shallow side kept
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if worst(mid) >= 0 else (lo, mid)
    return round(lo, 3)


def _wave_peak(scene: Scene, model: DockModel, lines: Any, depth: float, hs: float) -> np.ndarray:
    """Each line's hook tension [N] four standard deviations up the waves' motion (surge,
    sway, yaw and heave RMS of the weather at wave height ``hs``, each through the chain's
    own statics: finite differences of :func:`statics_at_span`)."""
    w = scene.weather
    jr = np.stack([-lines.arm[:, 1], lines.arm[:, 0]], axis=1)
    s_span = np.sqrt((lines.unit[:, 0] * w.surge * hs) ** 2 + (lines.unit[:, 1] * w.sway * hs)
                     ** 2 + (np.sum(lines.unit * jr, axis=1) * w.yaw * hs) ** 2)  # fmt: skip
    h = depth + model.hook_height
    t0 = lines.statics.top_tension
    d_span = statics_at_span(model.weight, h, model.chain_length, lines.span + s_span,
                             model.ea).top_tension - t0  # fmt: skip
    d_heave = statics_at_span(model.weight, h + w.heave * hs, model.chain_length, lines.span,
                              model.ea).top_tension - t0  # fmt: skip
    return t0 + 4.0 * np.hypot(d_span, d_heave)


class WaveMotion(NamedTuple):
    """The dock's wave-frequency motion about its offset at times ``t``: surge, sway [m], yaw
    [rad] and the hooks' heave [m]."""

    surge: np.ndarray
    sway: np.ndarray
    yaw: np.ndarray
    heave: np.ndarray


@functools.lru_cache(maxsize=8)
def wave_components(seed: int, tp: float, n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] (n,) and phases [rad] (4, n) of the wave components: periods drawn
    around ``tp`` (a narrow, JONSWAP-like peak; no two commensurate, so the sum never
    repeats)."""
    rng = np.random.default_rng(seed * 31 + 5)
    f = np.clip((1.0 / tp) * (1.0 + 0.18 * rng.standard_normal(n)), 1 / 16.0, 1 / 2.0)
    return f, rng.uniform(0.0, 2 * np.pi, (4, n))


def wave_motion(scene: Scene, t: np.ndarray, hs: np.ndarray) -> WaveMotion:
    """The wave-frequency motion at ``t`` [s], scaled by the wave height ``hs`` [m] there."""
    w = scene.weather
    f, phi = wave_components(scene.seed, w.tp)
    amp = math.sqrt(2.0 / len(f))
    arg = 2 * np.pi * np.asarray(t)[:, None] * f[None, :]
    unit = [amp * np.cos(arg + phi[d][None, :]).sum(axis=1) for d in range(4)]
    return WaveMotion(w.surge * hs * unit[0], w.sway * hs * unit[1], w.yaw * hs * unit[2],
                      w.heave * hs * unit[3])  # fmt: skip


def dock_offset(scene: Scene, c: Coarse, t: np.ndarray) -> np.ndarray:
    """The dock's slow offset (len(t), 3) at ``t`` [s], between the grid's equilibria; with a
    parted chain, at the intact dock's until the chain parts, then settling over one grid step
    onto the other lines (never moving before it parts: on the grid alone the row after the
    parting would pull the dock away from the parting line's anchor during the step before,
    loading that chain towards uplift before it parts)."""
    parted = scene.fault('parted')
    if parted is None or not 0 < c.parted < len(c.t) - 1:
        return np.stack([np.interp(t, c.t, c.offset[:, j]) for j in range(3)], axis=1)
    i, at = c.parted, parted.at
    before = t < at
    after_t = np.concatenate([[at], c.t[i + 1 :]])
    out = np.empty((len(t), 3))
    for j in range(3):
        out[before, j] = np.interp(t[before], c.t[:i], c.offset[:i, j])
        after_q = np.concatenate([[np.interp(at, c.t[:i], c.offset[:i, j])], c.offset[i + 1 :, j]])
        out[~before, j] = np.interp(t[~before], after_t, after_q)
    return out


def hook_tensions(scene: Scene, c: Coarse, t: np.ndarray) -> np.ndarray:
    """True hook tensions [N] (len(t), lines) at ``t`` [s from the start]: every chain at its
    hook, the dock at its equilibrium moved by the waves, the hooks at the still-water depth
    plus their heave; a parted line carries the chain hanging below its hook."""
    model = _model(scene)
    q = dock_offset(scene, c, t)
    hs = np.interp(t, c.t, c.hs)
    wave = wave_motion(scene, t, hs)
    q[:, 0] += wave.surge
    q[:, 1] += wave.sway
    q[:, 2] += wave.yaw
    depth = np.interp(t, c.t, c.depth) + wave.heave
    cos, sin = np.cos(q[:, 2]), np.sin(q[:, 2])
    hx, hy = model.hook[:, 0][None, :], model.hook[:, 1][None, :]
    px = q[:, 0:1] + cos[:, None] * hx - sin[:, None] * hy
    py = q[:, 1:2] + sin[:, None] * hx + cos[:, None] * hy
    span = np.hypot(model.anchor[None, :, 0] - px, model.anchor[None, :, 1] - py)
    h = depth[:, None] + model.hook_height[None, :]
    st = statics_at_span(model.weight[None, :], h, model.chain_length[None, :], span,
                         model.ea[None, :])  # fmt: skip
    out = np.array(st.top_tension)
    parted = scene.fault('parted')
    if parted is not None and parted.line in model.names:
        k = model.names.index(parted.line)
        gone = t >= parted.at
        hanging = np.minimum(parted.value, h[:, k])
        out[gone, k] = model.weight[k] * hanging[gone]
    return out


def truth_statics(scene: Scene) -> tuple[np.ndarray, Any]:
    """The scene's quasi-static truth on its grid (no waves): times [s] and the monitor's
    solve of every line's true hook tension at the true depth (``SolveResult`` of shape
    (times, lines); a parted line NaN after it parted)."""
    c = coarse(scene)
    model = _model(scene)
    x = np.array([line.anchor_distance for line in scene.config.lines])
    tens = hook_tensions_static(scene, c)
    parted = scene.fault('parted')
    if parted is not None and parted.line in model.names:
        tens[c.parted :, model.names.index(parted.line)] = math.nan
    h = c.depth[:, None] + model.hook_height[None, :]
    r = solve(model.weight[None, :], h, tension=tens, anchor_distance=x[None, :],
              mbl=model.mbl[None, :])  # fmt: skip
    return c.t, r


def scene_margins(scene: Scene) -> dict[str, float]:
    """The scene's truth against the monitor's thresholds, on its grid (no waves): the least
    anchor margin [m], tide margin [m] and safety factor, the largest uplift [N], the tide's
    range [m] and the longest slack water (the tide within 1 cm for) [s]."""
    c = coarse(scene)
    _, r = truth_statics(scene)
    tide = c.depth
    with np.errstate(invalid='ignore'):
        return {
            'anchor_margin_min': float(np.nanmin(r.anchor_margin)),
            'tide_margin_min': float(np.nanmin(r.tide_margin)),
            'safety_factor_min': float(np.nanmin(r.safety_factor)),
            'uplift_max': float(np.nanmax(r.uplift_force)),
            'tide_range': float(np.ptp(tide)),
            'slack_water_max_s': _longest_within(c.t, tide, 0.01),
        }


def hook_tensions_static(scene: Scene, c: Coarse) -> np.ndarray:
    """Quasi-static hook tensions [N] on the grid (no waves)."""
    model = _model(scene)
    rows = [line_states(model, float(d), q).statics.top_tension for d, q in zip(c.depth, c.offset)]
    return np.array(rows)


def _longest_within(t: np.ndarray, x: np.ndarray, band: float) -> float:
    """Longest stretch [s] over which ``x`` stays within ``band`` of its value at the
    stretch's start (the tide's slack water at that resolution)."""
    best, i = 0.0, 0
    n = len(t)
    while i < n:
        j = i
        while j + 1 < n and abs(x[j + 1] - x[i]) <= band:
            j += 1
        best = max(best, float(t[j] - t[i]))
        i = j + 1 if j > i else i + 1
    return best
