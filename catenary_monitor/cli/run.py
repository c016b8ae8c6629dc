"""Sub-commands of the live shell: ``run`` and ``demo``.

Registered through ``cli._extensions()``. rclpy is imported only when one of them runs, so the core
commands (solve, paper) keep working without ROS.
"""

from __future__ import annotations

import argparse
import os
from typing import Any, MutableMapping

__all__ = ['register']


DISCOVERY = 'ROS_AUTOMATIC_DISCOVERY_RANGE'
PEERS = 'ROS_STATIC_PEERS'


def limit_discovery(environ: MutableMapping[str, str]) -> str:
    """Set ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` unless the user set it; the start line
    that says which range the node runs with and the static peers it names (docs/deploy.md,
    docs/node.md Security)."""
    peers = [p.strip() for p in environ.get(PEERS, '').split(';') if p.strip()]
    named = f', static peers {", ".join(peers)} (from {PEERS})' if peers else ''
    if environ.get(DISCOVERY):
        return f'DDS discovery range {environ[DISCOVERY]} (from {DISCOVERY}){named}'
    environ[DISCOVERY] = 'LOCALHOST'
    if peers:
        return f'DDS discovery limited to this host ({DISCOVERY}=LOCALHOST){named}'
    return (
        f'DDS discovery limited to this host ({DISCOVERY}=LOCALHOST; name the sensors\' '
        f'computers in {PEERS}, or set {DISCOVERY}=SUBNET, to reach other machines)'
    )


def cmd_run(args: argparse.Namespace) -> int:
    """Start the monitor node on a params file (Ctrl-C or SIGTERM stop it cleanly); DDS
    discovery stays on this host unless ROS_AUTOMATIC_DISCOVERY_RANGE says otherwise."""
    import sys

    from catenary_monitor.core.config.parameters import ConfigError, load_params_file

    try:
        load_params_file(args.params_file)  # one-line error for a missing or malformed file
    except ConfigError as err:
        print(f'catenary-monitor: {err}', file=sys.stderr)
        return 2
    note = limit_discovery(os.environ)  # before rclpy.init: the middleware reads it there
    from catenary_monitor.ros.node import main

    return main(
        ['catenary-monitor', '--ros-args', '--params-file', args.params_file, *args.ros_args],
        log_dir=args.log_dir,
        start_note=note,
    )  # later -p values win


def cmd_demo(args: argparse.Namespace) -> int:
    """Simulator + monitor as processes through a storm; leaves an MCAP log and a PNG chart."""
    from catenary_monitor.cli.demo import run_demo

    port = None if args.no_console else args.console_port
    return run_demo(args.out_dir, duration=args.duration, console_port=port, moordyn=args.moordyn)


def register(sub: Any) -> None:
    """Add ``run`` and ``demo`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'run',
        help='run the live monitor node (ROS 2)',
        description='Run the catenary_monitor node. Extra --ros-args are passed '
        'to ROS (e.g. --ros-args -p clear_hold:=10.0).',
    )
    p.add_argument(
        '--params-file',
        required=True,
        metavar='FILE',
        help='ROS 2 params YAML (top key catenary_monitor or /**)',
    )
    p.add_argument('--log-dir', metavar='DIR', help='MCAP log directory (overrides log_dir)')
    p.add_argument(
        '--ros-args',
        dest='ros_args',
        nargs=argparse.REMAINDER,
        default=[],
        metavar='ARG',
        help='the rest is passed to ROS (e.g. -p clear_hold:=10.0)',
    )
    p.set_defaults(func=cmd_run, long_running=True)

    p = sub.add_parser(
        'demo',
        help='the embedded default: the paper dock through a storm',
        description='Run the dock simulator and the monitor as processes through '
        'a storm that lifts line 11\'s anchor; print alarm '
        'transitions; leave the MCAP log and a PNG chart.',
    )
    p.add_argument(
        '--out-dir',
        default='catenary_monitor_demo',
        metavar='DIR',
        help='where the MCAP log and demo.png go (default: %(default)s)',
    )
    p.add_argument(
        '--duration',
        type=float,
        default=55.0,
        metavar='S',
        help='episode length in wall seconds (default: %(default)s)',
    )
    p.add_argument(
        '--console-port',
        type=int,
        default=8080,
        metavar='N',
        help='port of the operator\'s console (default %(default)s; busy or 0: any free port)',
    )
    p.add_argument('--no-console', action='store_true', help='do not start the console')
    p.add_argument(
        '--moordyn',
        action='store_true',
        help='the hook tensions from MoorDyn (the dynamics extra) instead of the equilibrium',
    )
    p.set_defaults(func=cmd_demo, long_running=True)
