"""Dock simulator for the demo: the seed paper's floating dock through a compressed storm.

Console script ``dock_simulator`` (or ``python -m catenary_monitor.ros.simulator``). It publishes,
as
a sensor driver would, ``std_msgs/Float64`` hook tensions (N) on every line's tension topic and
the tide depth (m) on the depth topic, with sensor-data QoS, then exits by itself.

The episode (:class:`Scenario`, pure: no rclpy) is the paper's dock (config/floating_dock.yaml):

* tide: semi-diurnal (M2, 12.42 h) compressed into the episode, amplitude 1.0 m around the
  paper's 20.85 m, rising from low water at the start to high water half-way;
* load: every chain at the paper's pretension R = 372 kN (table 2) when calm; a storm builds,
  pauses a little below line 11's uplift while the tide rises (``hold``, ``hold_level``: the
  rising tide brings the uplift closer, the monitor's time-to-uplift warning), builds again,
  holds and eases. Line 11 reaches the table-3 typhoon load R = 1584.6 kN (hook tension about
  1623 kN at x = 121.06 m), which lifts its anchor; its neighbours 10 and 12 take a little more,
  the lee lines 2-6 a little less;
* wave-frequency fluctuation: each line's horizontal tension swings sinusoidally (period
  ``wave_period``, amplitude growing with the storm) plus 0.3 % noise, so the monitor's alarms
  meet an oscillating load near their thresholds.

The hook tension published is the catenary's top tension for that horizontal load at the
current depth and installed anchor distance (``catenary_monitor.solve(horizontal=...)``).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import (
    ConfigError,
    MonitorConfig,
    config_from_params,
    load_params_file,
)
from catenary_monitor.core.physics.solve import solve

__all__ = ['Scenario', 'default_config_path', 'main']

#: Paper, table 2: pretension (horizontal) of every chain [N].
PRETENSION = 372e3
#: Paper, table 3: typhoon horizontal load on line 11 [N].
TYPHOON = 1584.6e3
#: Paper: depth at mean tide [m].
MEAN_DEPTH = 20.85
#: M2 tide period [s] (compressed into the episode).
M2_PERIOD = 12.42 * 3600.0


def default_config_path() -> str:
    """config/floating_dock.yaml, found without the ament index (source tree or pip install)."""
    from pathlib import Path

    here = Path(__file__).resolve().parent
    name = 'floating_dock.yaml'
    candidates = [
        here / 'data' / name,
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


def _smooth(u: float) -> float:
    """0 -> 1 cosine ramp on [0, 1], clipped."""
    u = min(max(u, 0.0), 1.0)
    return 0.5 - 0.5 * math.cos(math.pi * u)


@dataclass(frozen=True)
class Scenario:
    """The demo episode as pure functions of wall time ``t`` in [0, duration] (s).

    ``storm_share`` maps line names to the fraction of the storm's extra load they take
    (line 11: all of it, up to the typhoon load); lines not named take none.
    """

    config: MonitorConfig
    duration: float = 55.0
    wave_period: float = 4.0  # s (wall), wave-frequency tension swing
    wave_calm: float = 0.01  # relative swing amplitude when calm
    wave_storm: float = 0.05  # relative swing amplitude at the storm peak
    noise: float = 0.003  # relative noise (std)
    tide_amplitude: float = 1.0  # m
    build: tuple[float, float] = (0.12, 0.45)  # storm build from/to (fraction of duration)
    hold: tuple[float, float] = (0.25, 0.36)  # the build pauses (the tide rises) from/to
    hold_level: float = 0.055  # storm intensity during the pause (line 11 about 1 m of tide short)
    ease: tuple[float, float] = (0.60, 0.80)  # storm eases from/to
    seed: int = 11

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

    def shares(self) -> np.ndarray:
        """Storm share per line: the typhoon increment on line 11, a little on 10 and 12,
        relief on the lee lines 2-6; lines named otherwise get none."""
        table = {'line_11': 1.0, 'line_10': 0.02, 'line_12': 0.02}
        for i in range(2, 7):
            table[f'line_{i:02d}'] = -0.05
        return np.array([table.get(line.name, 0.0) for line in self.config.lines])

    def horizontal(self, t: float, rng: Optional[np.random.Generator] = None) -> np.ndarray:
        """Horizontal tension of every line [N] at ``t``."""
        s = self.storm(t)
        mean = PRETENSION + s * self.shares() * (TYPHOON - PRETENSION)
        amp = self.wave_calm + (self.wave_storm - self.wave_calm) * s
        phase = np.arange(len(self.config.lines)) * 0.7
        swing = amp * np.sin(2 * math.pi * t / self.wave_period + phase)
        if rng is not None:
            swing = swing + self.noise * rng.standard_normal(len(self.config.lines))
        return mean * (1.0 + swing)

    def tensions(self, t: float, rng: Optional[np.random.Generator] = None) -> np.ndarray:
        """Hook tension of every line [N] at ``t`` (catenary top tension for the load)."""
        lines = self.config.lines
        r = solve(
            np.array([line.weight for line in lines]),
            self.depth(t) + np.array([line.hook_height for line in lines]),
            horizontal=self.horizontal(t, rng),
            anchor_distance=np.array([line.anchor_distance for line in lines]),
        )
        return np.asarray(r.top_tension, dtype=float)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Publish the scenario in real time until ``--duration`` has passed, then exit 0."""
    parser = argparse.ArgumentParser(prog='dock_simulator', description=__doc__.splitlines()[0])
    parser.add_argument(
        '--params-file',
        default=None,
        help='monitor params YAML giving the lines (default: the paper dock)',
    )
    parser.add_argument('--duration', type=float, default=55.0, help='episode length [s]')
    parser.add_argument('--rate', type=float, default=20.0, help='tension rate per line [Hz]')
    parser.add_argument('--depth-rate', type=float, default=2.0, help='depth rate [Hz]')
    argv = list(sys.argv[1:] if argv is None else argv)
    import rclpy
    from rclpy.utilities import remove_ros_args

    args = parser.parse_args(remove_ros_args(['dock_simulator', *argv])[1:])
    try:
        config = config_from_params(load_params_file(args.params_file or default_config_path()))
    except ConfigError as err:
        print(f'dock_simulator: {err}', file=sys.stderr)
        return 2
    scenario = Scenario(config, duration=args.duration)

    from rclpy.executors import ExternalShutdownException
    from rclpy.qos import qos_profile_sensor_data
    from std_msgs.msg import Float64

    rclpy.init(args=['dock_simulator', *argv])
    node = rclpy.create_node('dock_simulator')
    pubs = [
        node.create_publisher(Float64, line.tension_topic, qos_profile_sensor_data)
        for line in config.lines
    ]
    depth_pub = node.create_publisher(Float64, config.depth_topic, qos_profile_sensor_data)
    rng = np.random.default_rng(scenario.seed)
    clock = node.get_clock()
    t0 = clock.now().nanoseconds
    state = {'next_depth': 0.0, 'done': False}

    def tick() -> None:
        t = (clock.now().nanoseconds - t0) * 1e-9
        if t > scenario.duration:
            state['done'] = True
            return
        if t >= state['next_depth']:
            depth_pub.publish(Float64(data=scenario.depth(t)))
            state['next_depth'] += 1.0 / args.depth_rate
        for pub, value in zip(pubs, scenario.tensions(t, rng).tolist()):
            pub.publish(Float64(data=value))

    node.create_timer(1.0 / args.rate, tick)
    node.get_logger().info(
        f'publishing {len(pubs)} lines at {args.rate:g} Hz for '
        f'{scenario.duration:g} s (tide x{scenario.time_scale():.0f})'
    )
    try:
        while rclpy.ok() and not state['done']:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
