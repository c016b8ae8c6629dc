"""``catenary-monitor harbour``: every dock of a port live on one page.

``catenary-monitor harbour --dock NAME=DOMAIN_ID[:PARAMS_FILE][@LAT,LON] ... [--console-url
NAME=URL ...] [--discovery-server NAME=SERVERS ...]
[--fleet-dataset DIR] [--port 8090] [--bind 127.0.0.1] [--token-file FILE]
[--tls-cert F --tls-key F]``.
One process joins each dock's ROS domain (:mod:`.harbour_source`) and serves the harbour page
(:mod:`.harbour_server`). Read-only unless ``--token-file`` names operators, who may then
acknowledge a dock's alarm from it. Prints ``harbour: URL (...)`` once it listens and serves
until Ctrl-C or SIGTERM. Exit 2 with one line on a bad ``--dock``, params file, token file or
certificate, a dock named twice, a fleet dataset that is not one, or a port in use.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from typing import Any

from catenary_monitor.console.server_options import (
    Refused,
    add_server_options,
    cannot_listen,
    print_urls,
    server_access,
    stop_on_signal,
)

__all__ = ['register', 'cmd_harbour', 'dock_specs']


def _fail(message: str, code: int = 2) -> int:
    print(f'catenary-monitor harbour: {message}', file=sys.stderr)
    return code


#: The process-wide discovery server: on one, the ROS domains no longer keep docks apart.
SHARED_SERVER = (
    'ROS_DISCOVERY_SERVER is set for the whole harbour: through a discovery server every '
    'domain hears every monitor (a silent dock would show another\'s statuses); give each '
    'dock its own with --discovery-server NAME=SERVERS, or unset it'
)


def dock_specs(docks: list[str], consoles: list[str], servers: Any = ()) -> list[Any]:
    """The ``--dock``, ``--console-url`` and ``--discovery-server`` options as dock specs,
    each params file read. Raises Refused with one line."""
    from catenary_monitor.console.harbour_model import (
        parse_console_url,
        parse_discovery_server,
        parse_dock,
    )
    from catenary_monitor.core.config.parameters import (
        ConfigError,
        config_from_params,
        load_params_file,
    )

    try:
        specs = [parse_dock(text) for text in docks]
        urls = dict(parse_console_url(text) for text in consoles)
        found = dict(parse_discovery_server(text) for text in servers)
    except ValueError as err:
        raise Refused(str(err)) from None
    names = [s.name for s in specs]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise Refused(f'--dock {twice[0]} given twice: every dock needs its own name')
    for option, given in (('--console-url', urls), ('--discovery-server', found)):
        unknown = sorted(set(given) - set(names))
        if unknown:
            raise Refused(f'{option} {unknown[0]}: no --dock of that name')
    if os.environ.get('ROS_DISCOVERY_SERVER') and len(names) > 1 and set(found) != set(names):
        raise Refused(SHARED_SERVER)
    out = []
    for spec in specs:
        config = None
        if spec.params_file:
            try:
                config = config_from_params(load_params_file(spec.params_file))
            except ConfigError as err:
                raise Refused(f'dock {spec.name}: {spec.params_file}: {err}') from None
        out.append(
            dataclasses.replace(
                spec,
                config=config,
                console_url=urls.get(spec.name),
                discovery_server=found.get(spec.name),
            )
        )
    return out


def fleet_kpis(folder: str, docks: list[str]) -> Any:
    """The docks' daily KPIs from the fleet dataset ``folder`` (:mod:`.harbour_fleet`).
    Raises Refused with one line: no such folder, or no pyarrow."""
    from pathlib import Path

    if not (Path(folder) / 'daily').is_dir():
        raise Refused(
            f'--fleet-dataset {folder}: no daily/ folder there (the RESULTS folder of '
            'catenary-monitor fleet --out RESULTS)'
        )
    try:
        import pyarrow  # noqa: F401 - the extra's, checked before serving
    except ImportError:
        raise Refused('--fleet-dataset needs pyarrow: pip install "catenary_monitor[fleet]"')
    from catenary_monitor.console.harbour_fleet import FleetKpis

    return FleetKpis(folder, docks)


def cmd_harbour(args: argparse.Namespace) -> int:
    """Join every dock's domain and serve the harbour page until a signal."""
    from catenary_monitor.console.harbour_server import HarbourServer
    from catenary_monitor.console.harbour_source import HarbourSource

    args.log = None
    args.read_only = bool(args.read_only or not args.token_file)
    try:
        specs = dock_specs(args.dock, args.console_url or [], args.discovery_server or [])
        access = server_access(args, 'harbour')
    except Refused as err:
        return _fail(str(err))
    kpis = None
    if args.fleet_dataset:
        try:
            kpis = fleet_kpis(args.fleet_dataset, [s.name for s in specs])
        except Refused as err:
            return _fail(str(err))
    source = HarbourSource(
        specs, acknowledge=not access['read_only'], kpis=kpis, ros_args=args.ros_args
    )
    try:
        server = HarbourServer(source, args.bind, args.port, **access)
    except OSError as err:
        return _fail(cannot_listen(args.bind, args.port, err))
    stop = stop_on_signal()
    try:
        source.start()
    except Exception as err:  # noqa: BLE001 - rclpy's errors: one line, exit 2
        server.shutdown()
        source.stop()
        return _fail(f'cannot join the docks\' ROS domains: {err}')
    server.start()
    domains = ', '.join(str(s.domain_id) for s in specs)
    what = (
        f'1 dock in domain {domains}'
        if len(specs) == 1
        else f'{len(specs)} docks in domains {domains}'
    )
    if server.access == 'token':
        what += f'; {len(access["operators"].names)} operators sign in to acknowledge'
    else:
        what += '; read-only'
    print_urls(server, what, label='harbour')
    try:
        while not stop.wait(0.5):
            pass
    finally:
        server.shutdown()
        source.stop()
    return 0


def register(sub: Any) -> None:
    """Add ``harbour`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'harbour',
        help='every dock of a port live on one page (one ROS domain per dock)',
        description='Serve the harbour page: a tile per dock (worst level, lines in alarm, '
        'worst uplift and anchor margin, time to uplift, monitor alive, age of its newest '
        'status), a map, the harbour-wide alarm list with each dock\'s first out. One process '
        'joins every dock\'s ROS domain and takes its /diagnostics only.',
    )
    p.add_argument(
        '--dock',
        action='append',
        required=True,
        metavar='NAME=DOMAIN_ID[:PARAMS_FILE][@LAT,LON]',
        help='a dock: its name, its monitor\'s ROS domain, optionally the monitor\'s params '
        'file (its lines and /diagnostics rate) and its position in degrees (repeatable)',
    )
    p.add_argument(
        '--console-url',
        action='append',
        metavar='NAME=URL',
        help='the dock\'s own console, linked from its tile (repeatable)',
    )
    p.add_argument(
        '--discovery-server',
        action='append',
        metavar='NAME=SERVERS',
        help='the Fast DDS discovery server(s) of that dock (its ROS_DISCOVERY_SERVER value, '
        'e.g. north=10.0.21.5:11811): the harbour\'s participant in that dock\'s domain is a '
        'client of these alone (repeatable; a process-wide ROS_DISCOVERY_SERVER would match '
        'every dock in every domain)',
    )
    p.add_argument(
        '--fleet-dataset',
        metavar='DIR',
        help='the fleet\'s results (catenary-monitor fleet --out DIR): each dock\'s daily KPIs '
        '(alarms per 10 min, time in alarm, fatigue) on its tile, for the docks of that name',
    )
    add_server_options(p, 'harbour', port=8090)
    p.add_argument(
        '--ros-args',
        dest='ros_args',
        nargs=argparse.REMAINDER,
        default=[],
        metavar='ARG',
        help='the rest is passed to ROS (in every domain)',
    )
    p.set_defaults(func=cmd_harbour, long_running=True)
