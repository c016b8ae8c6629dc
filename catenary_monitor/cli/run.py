"""Sub-commands of the live shell: ``run`` and ``demo``.

Registered through ``cli._extensions()``. rclpy is imported only when one of them runs, so the core
commands (solve, paper) keep working without ROS.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any, MutableMapping, Sequence

__all__ = ['register', 'supervise', 'NO_RESTART']

#: Exit statuses after which the node is not started again: 0 (stopped) and 2 (a bad params
#: file: the same error again), as the unit's ``RestartPreventExitStatus=2``.
NO_RESTART = (0, 2)


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
    from catenary_monitor.core.config.parameters import ConfigError, load_params_file

    try:
        load_params_file(args.params_file)  # one-line error for a missing or malformed file
    except ConfigError as err:
        print(f'catenary-monitor: {err}', file=sys.stderr)
        return 2
    if args.restart_on_failure is not None:
        return supervise(_child_command(args), args.restart_on_failure)
    note = limit_discovery(os.environ)  # before rclpy.init: the middleware reads it there
    from catenary_monitor.ros.node import main

    return main(
        ['catenary-monitor', '--ros-args', '--params-file', args.params_file, *args.ros_args],
        log_dir=args.log_dir,
        start_note=note,
    )  # later -p values win


def _child_command(args: argparse.Namespace) -> list[str]:
    """``run`` as a child process: the same arguments but ``--restart-on-failure``."""
    command = [sys.executable, '-m', 'catenary_monitor', 'run', '--params-file', args.params_file]
    if args.log_dir:
        command += ['--log-dir', args.log_dir]
    return command + (['--ros-args', *args.ros_args] if args.ros_args else [])


def _die_with_parent() -> None:
    """In the child (Linux): SIGTERM when the supervisor dies, even by SIGKILL."""
    import ctypes
    import signal

    try:
        ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def supervise(command: Sequence[str], delay: float) -> int:
    """Run ``command`` and start it again ``delay`` s after each failure (an exit status other
    than 0 and 2, or a signal), as systemd's ``Restart=on-failure`` with
    ``RestartPreventExitStatus=2`` does; SIGINT and SIGTERM go to the child and end the loop.
    Returns the child's last exit status (128 + N for signal N)."""
    import signal
    import subprocess
    import threading

    stop = threading.Event()
    child: list[subprocess.Popen] = []  # the running one

    def forward(signum: int, _frame: Any) -> None:
        stop.set()
        if child and child[-1].poll() is None:
            child[-1].send_signal(signum)

    previous = {sig: signal.signal(sig, forward) for sig in (signal.SIGINT, signal.SIGTERM)}
    linux = sys.platform.startswith('linux')
    try:
        while True:
            # its own session: a terminal's Ctrl-C reaches it once, through forward()
            child[:] = [subprocess.Popen(command, start_new_session=True,
                                         preexec_fn=_die_with_parent if linux else None)]
            if stop.is_set() and child[-1].poll() is None:
                child[-1].send_signal(signal.SIGTERM)
            status = child[-1].wait()
            status = 128 - status if status < 0 else status
            if stop.is_set() or status in NO_RESTART:
                return status
            print(
                f'catenary-monitor run: the node failed (exit status {status}); '
                f'starting it again in {delay:g} s',
                file=sys.stderr,
                flush=True,
            )
            if stop.wait(delay):
                return status
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def cmd_demo(args: argparse.Namespace) -> int:
    """Simulator + monitor as processes through a storm; leaves an MCAP log and a PNG chart."""
    from catenary_monitor.cli.demo import run_demo

    port = None if args.no_console else args.console_port
    return run_demo(args.out_dir, duration=args.duration, console_port=port, moordyn=args.moordyn)


def _seconds(text: str) -> float:
    """A finite delay >= 0 s (argparse type)."""
    import math

    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f'expected seconds >= 0, got {text!r}')
    return value


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
        '--restart-on-failure',
        type=_seconds,
        metavar='S',
        help='run the node as a child and start it again S seconds after it fails, but not '
        'after exit status 2 (a bad params file), as the systemd unit does (ros2 launch)',
    )
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
