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
import ipaddress
import signal
import socket
import ssl
import sys
import threading
from typing import Any, Optional

__all__ = [
    'register',
    'cmd_console',
    'add_server_options',
    'server_access',
    'print_urls',
    'Refused',
]


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
        return _fail(
            f'cannot listen on {args.bind}:{args.port}: {err.strerror or err} '
            '(choose --port N, or --port 0 for any free port)'
        )
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
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


def print_urls(server: Any, what: str, label: str = 'console') -> None:
    """``console: URL (...)`` for this PC, then ``console: also at URL`` for every other
    address it is reached at (each interface's when bound to all of them); ``label`` names
    the page (``harbour``)."""
    from catenary_monitor.console.addresses import reachable_urls

    print(f'{label}: {server.url} ({what}; Ctrl-C stops)', flush=True)
    for url in reachable_urls(server.scheme, server.bind, server.port):
        if url != server.url:
            print(f'{label}: also at {url}', flush=True)


class Refused(Exception):
    """A console that must not start as asked: ``str()`` is one line."""


def is_loopback(bind: str) -> bool:
    """True when ``bind`` (an address or a host name) is reachable from this PC only."""
    try:
        return ipaddress.ip_address(bind.strip('[]')).is_loopback
    except ValueError:
        pass
    try:
        found = socket.getaddrinfo(bind, None)
    except OSError:
        return False
    return bool(found) and all(ipaddress.ip_address(f[4][0]).is_loopback for f in found)


def server_access(args: argparse.Namespace) -> dict[str, Any]:
    """The server's access settings (operators, read-only, TLS) from the command line; a bind
    beyond loopback needs ``--token-file`` or ``--read-only``."""
    from catenary_monitor.console.operators import TokenFileError, load_operators

    operators = None
    if args.token_file:
        try:
            operators, warning = load_operators(args.token_file)
        except TokenFileError as err:
            raise Refused(str(err)) from None
        if warning:
            print(f'catenary-monitor console: warning: {warning}', file=sys.stderr)
    elif not args.read_only and not args.log and not is_loopback(args.bind):
        raise Refused(
            f'--bind {args.bind} reaches beyond this PC: give --token-file FILE (operators '
            'who may acknowledge) or --read-only'
        )
    tls = _tls(args.tls_cert, args.tls_key, args.allow_expired)
    if operators is not None and tls is None and not is_loopback(args.bind):
        print(
            'catenary-monitor console: warning: tokens cross the network in clear text '
            '(give --tls-cert and --tls-key)',
            file=sys.stderr,
        )
    return {
        'operators': operators,
        'read_only': bool(args.read_only or args.log),
        'tls': tls,
        'server_names': args.server_name or (),
    }


def _tls(
    cert: Optional[str], key: Optional[str], allow_expired: bool = False
) -> Optional[ssl.SSLContext]:
    """A TLS server context (TLS 1.2 at least) from a certificate and its key, or None;
    a certificate not valid now is refused unless ``allow_expired`` (a loud warning)."""
    from catenary_monitor.console.tls import CertificateError, server_context

    if not cert and not key:
        return None
    if not (cert and key):
        raise Refused('--tls-cert and --tls-key go together')
    try:
        context, warning = server_context(cert, key, allow_expired=allow_expired)
    except CertificateError as err:
        raise Refused(str(err)) from None
    if warning:
        _warn(warning)
    return context


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


def add_server_options(p: Any, what: str, port: int = 8080) -> None:
    """The HTTP server's options of a page (``what``: ``console``, ``harbour``): --port,
    --bind, --token-file, --read-only, --tls-cert, --tls-key, --allow-expired, --server-name."""
    p.add_argument('--port', type=int, default=port, help='TCP port (0: any free port)')
    p.add_argument(
        '--bind',
        default='127.0.0.1',
        metavar='ADDR',
        help='address to listen on (default %(default)s: this PC only; beyond loopback, e.g. '
        '0.0.0.0, needs --token-file or --read-only)',
    )
    p.add_argument(
        '--token-file',
        metavar='FILE',
        help='operators who may acknowledge: one NAME:TOKEN a line; every state-changing '
        'request then needs "Authorization: Bearer TOKEN" (the page asks for it)',
    )
    p.add_argument(
        '--read-only',
        action='store_true',
        help=f'nobody acknowledges from this {what} (the page only shows)',
    )
    p.add_argument('--tls-cert', metavar='FILE', help='serve HTTPS with this certificate (PEM)')
    p.add_argument('--tls-key', metavar='FILE', help='the private key of --tls-cert (PEM)')
    p.add_argument(
        '--allow-expired',
        action='store_true',
        help='serve a certificate that expired or is not valid yet (a loud warning; renew it)',
    )
    p.add_argument(
        '--server-name',
        action='append',
        metavar='NAME',
        help=f'a host name the operators open the {what} by (e.g. dockpc.local; repeatable): '
        'requests naming another host are refused (DNS rebinding); IP addresses, localhost, '
        'the --bind name and this PC\'s host name are always accepted',
    )


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
