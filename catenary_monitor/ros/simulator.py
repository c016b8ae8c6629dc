"""Dock simulator for the demo: the seed paper's floating dock through a compressed storm.

Console script ``dock_simulator`` (or ``python -m catenary_monitor.ros.simulator``). It publishes,
as a sensor driver would, ``std_msgs/Float64`` hook tensions (N) on every line's tension topic
and the tide depth (m) on the depth topic, with sensor-data QoS, then exits by itself. The
episode is :class:`catenary_monitor.sim.scenario.Scenario` (the dock's equilibrium under a storm
and the tide, wave-frequency sway, sensor noise); ``--dynamics moordyn`` takes the tensions from
MoorDyn instead (:class:`catenary_monitor.sim.scenario.MoorDynTensions`).
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any, Optional, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import (
    ConfigError,
    config_from_params,
    load_params_file,
)
from catenary_monitor.sim.scenario import MoorDynTensions, Scenario, default_config_path

__all__ = ['main']


def _moordyn_source(scenario: Scenario, table: Optional[str]) -> 'MoorDynTensions | str':
    """The MoorDyn tensions: the table file if given, else computed now; or a one-line
    error."""
    if table is not None:
        try:
            return MoorDynTensions.load(table, scenario)
        except (OSError, ValueError, KeyError) as err:
            return f'--moordyn-table: {err}'
    from catenary_monitor.sim.moordyn_dock import available

    if not available():
        return '--dynamics moordyn needs MoorDyn (pip install "catenary_monitor[dynamics]")'
    return MoorDynTensions.compute(scenario)


def _wait_for_subscribers(node: Any, pubs: Sequence[Any], timeout: float) -> None:
    """Spin until every publisher has a subscriber or ``timeout`` s have passed."""
    import rclpy

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and rclpy.ok():
        if all(pub.get_subscription_count() > 0 for pub in pubs):
            return
        rclpy.spin_once(node, timeout_sec=0.05)


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
    parser.add_argument(
        '--dynamics',
        choices=('static', 'moordyn'),
        default='static',
        help='the tensions from the dock\'s equilibrium (static) or from MoorDyn',
    )
    parser.add_argument(
        '--wait-for-subscribers',
        type=float,
        default=0.0,
        metavar='S',
        help='begin the episode once every topic has a subscriber (the monitor), waiting at '
        'most S s (0: at once); prints "waiting for subscribers" once its episode is computed, '
        'and "episode start WALL_TIME" when it begins',
    )
    parser.add_argument(
        '--moordyn-table',
        metavar='NPZ',
        help='with --dynamics moordyn: the tensions computed beforehand (demo), else computed',
    )
    argv = list(sys.argv[1:] if argv is None else argv)
    import rclpy
    from rclpy.utilities import remove_ros_args

    args = parser.parse_args(remove_ros_args(['dock_simulator', *argv])[1:])
    try:
        config = config_from_params(load_params_file(args.params_file or default_config_path()))
    except ConfigError as err:
        print(f'dock_simulator: {err}', file=sys.stderr)
        return 2
    if not config.has_dock_model:
        print(
            'dock_simulator: the params file must give the dock\'s geometry (hook_x, hook_y, '
            'heading, chain_length on every line): the tensions come from its equilibrium',
            file=sys.stderr,
        )
        return 2
    scenario = Scenario(config, duration=args.duration)
    scenario.offsets()  # the equilibrium on its grid, before the first sample
    source: Any = scenario
    if args.dynamics == 'moordyn':
        source = _moordyn_source(scenario, args.moordyn_table)
        if isinstance(source, str):
            print(f'dock_simulator: {source}', file=sys.stderr)
            return 2

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
    if args.wait_for_subscribers > 0.0:
        print('waiting for subscribers', flush=True)
        _wait_for_subscribers(node, [*pubs, depth_pub], args.wait_for_subscribers)
    t0 = clock.now().nanoseconds
    print(f'episode start {time.time():.6f}', flush=True)
    state = {'next_depth': 0.0, 'done': False}

    def tick() -> None:
        t = (clock.now().nanoseconds - t0) * 1e-9
        if t > scenario.duration:
            state['done'] = True
            return
        if t >= state['next_depth']:
            depth_pub.publish(Float64(data=scenario.depth(t)))
            state['next_depth'] += 1.0 / args.depth_rate
        for pub, value in zip(pubs, source.tensions(t, rng).tolist()):
            pub.publish(Float64(data=value))

    node.create_timer(1.0 / args.rate, tick)
    node.get_logger().info(
        f'publishing {len(pubs)} lines at {args.rate:g} Hz for '
        f'{scenario.duration:g} s (tide x{scenario.time_scale():.0f}, '
        f'{"MoorDyn" if source is not scenario else "static equilibrium"})'
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
