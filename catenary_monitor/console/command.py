"""``catenary-monitor console``: serve the operator's page, live or over a recorded log.

Live: ``catenary-monitor console [--params-file F] [--port 8080] [--bind 127.0.0.1]
[--token-file FILE | --read-only] [--tls-cert F --tls-key F]``.
Replay: ``catenary-monitor console --log FILE|DIR [--params-file F]``. Prints the URL on one line
(``console: http://HOST:PORT/ ...``; then ``console: also at URL`` for each other address it is
reached at) and serves until Ctrl-C or SIGTERM. Exit 2 with one line on a
bad params file, token file or certificate, an unreadable log, a port in use, or a bind beyond
loopback with neither ``--token-file`` nor ``--read-only``.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from catenary_monitor.console.server_options import (
    Refused,
    add_server_options,
    cannot_listen,
    print_urls,
    server_access,
    stop_on_signal,
    tls_context,
)

__all__ = ['register', 'cmd_console']

#: The TLS context of --tls-cert/--tls-key (:func:`.server_options.tls_context`).
_tls = tls_context


def _fail(message: str, code: int = 2) -> int:
    print(f'catenary-monitor console: {message}', file=sys.stderr)
    return code


def _warn(message: str) -> None:
    print(f'catenary-monitor console: {message}', file=sys.stderr, flush=True)


def cmd_console(args: argparse.Namespace) -> int:
    """Start the console's source and HTTP server; serve until a signal."""
    from catenary_monitor.console.server import ConsoleServer
    from catenary_monitor.core.config.parameters import (
        ConfigError,
        config_from_params,
        load_params_file,
    )

    if args.foxglove_layout:
        return _write_layout(args)
    source: Any
    if args.log:
        from catenary_monitor.console.log_source import LogError, ReplaySource, load_log

        try:
            config, result, depth, files = load_log(
                args.log, args.params_file, on_damage=_warn
            )
        except LogError as err:
            return _fail(str(err), err.code)
        source = ReplaySource(config, result, depth, files)
    else:
        config = None
        if args.params_file:
            try:
                config = config_from_params(load_params_file(args.params_file))
            except ConfigError as err:
                return _fail(f'{args.params_file}: {err}')
        from catenary_monitor.console.ros_source import LiveSource

        source = LiveSource(config, args.ros_args)
    try:
        access = server_access(args)
    except Refused as err:
        return _fail(str(err))
    try:
        server = ConsoleServer(source, args.bind, args.port, **access)
    except OSError as err:
        return _fail(cannot_listen(args.bind, args.port, err))
    stop = stop_on_signal()
    if source.mode == 'live':
        source.start()
    server.start()
    what = 'live' if source.mode == 'live' else f'replay of {", ".join(args.log)}'
    if server.access == 'token':
        what += f'; {len(access["operators"].names)} operators sign in to act'
    elif server.access == 'read-only':
        what += '; read-only'
    print_urls(server, what)
    try:
        while not stop.wait(0.5):
            pass
    finally:
        server.shutdown()
        if source.mode == 'live':
            source.stop()
    return 0


def _write_layout(args: argparse.Namespace) -> int:
    """Write the Foxglove / Lichtblick layout for the params file's lines."""
    import json

    from catenary_monitor.console.foxglove import layout
    from catenary_monitor.core.config.parameters import (
        ConfigError,
        config_from_params,
        load_params_file,
    )
    from catenary_monitor.sim.scenario import default_config_path

    path = args.params_file or default_config_path()
    try:
        config = config_from_params(load_params_file(path))
    except ConfigError as err:
        return _fail(f'{path}: {err}')
    try:
        with open(args.foxglove_layout, 'w', encoding='utf-8') as f:
            json.dump(layout(config), f, indent=2)
            f.write('\n')
    except OSError as err:
        return _fail(f'cannot write {args.foxglove_layout}: {err.strerror or err}')
    print(f'Foxglove / Lichtblick layout for {len(config.lines)} lines: {args.foxglove_layout}')
    return 0


def register(sub: Any) -> None:
    """Add ``console`` (and ``harbour``, :mod:`.harbour_command`) to the ``catenary-monitor``
    parser."""
    from catenary_monitor.console import harbour_command

    p = sub.add_parser(
        'console',
        help="the operator's page in a browser: live, or over a recorded log",
        description="Serve the operator's console: dock plan, a tile per line, tide, trends, "
        'alarm list with acknowledgement and history. Live it is a ROS client of the monitor; '
        'with --log it replays a recorded log with a time slider.',
    )
    p.add_argument(
        '--params-file',
        metavar='FILE',
        help='the monitor\'s params YAML (lines, headings, MBL); live default: the lines the '
        'monitor names on /diagnostics; replay default: the parameters recorded in the log',
    )
    add_server_options(p, 'console')
    p.add_argument(
        '--log', nargs='+', metavar='FILE|DIR', help='replay a recorded MCAP log (files or dirs)'
    )
    p.add_argument(
        '--foxglove-layout',
        metavar='OUT.json',
        help='write a Foxglove / Lichtblick layout for the params file\'s lines and exit',
    )
    p.add_argument(
        '--ros-args',
        dest='ros_args',
        nargs=argparse.REMAINDER,
        default=[],
        metavar='ARG',
        help='the rest is passed to ROS',
    )
    p.set_defaults(func=cmd_console, long_running=True)
    harbour_command.register(sub)
