"""The HTTP server's options shared by the pages (``console``, ``harbour``): the command line
(:func:`add_server_options`), the access settings they give (:func:`server_access`: operators,
read-only, TLS; a bind beyond loopback needs a token file or read-only) and the URLs printed.
"""

from __future__ import annotations

import argparse
import ipaddress
import socket
import signal
import ssl
import sys
import threading
from typing import Any, Optional

__all__ = [
    'add_server_options',
    'server_access',
    'print_urls',
    'tls_context',
    'is_loopback',
    'Refused',
    'cannot_listen',
    'stop_on_signal',
]


def _warn(message: str, what: str = 'console') -> None:
    print(f'catenary-monitor {what}: {message}', file=sys.stderr, flush=True)


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


def server_access(args: argparse.Namespace, what: str = 'console') -> dict[str, Any]:
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
            _warn(f'warning: {warning}', what)
    elif not args.read_only and not args.log and not is_loopback(args.bind):
        raise Refused(
            f'--bind {args.bind} reaches beyond this PC: give --token-file FILE (operators '
            'who may acknowledge) or --read-only'
        )
    tls = tls_context(args.tls_cert, args.tls_key, args.allow_expired, what)
    if operators is not None and tls is None and not is_loopback(args.bind):
        print(
            f'catenary-monitor {what}: warning: tokens cross the network in clear text '
            '(give --tls-cert and --tls-key)',
            file=sys.stderr,
        )
    return {
        'operators': operators,
        'read_only': bool(args.read_only or args.log),
        'tls': tls,
        'server_names': args.server_name or (),
    }


def tls_context(
    cert: Optional[str], key: Optional[str], allow_expired: bool = False, what: str = 'console'
) -> Optional[ssl.SSLContext]:
    """A TLS server context (TLS 1.2 at least) from a certificate and its key, or None;
    a certificate not valid now is refused unless ``allow_expired`` (a loud warning, naming
    the page ``what``)."""
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
        _warn(warning, what)
    return context


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


def cannot_listen(bind: str, port: int, err: OSError) -> str:
    """The one line of a server that cannot bind ``bind:port``."""
    return (
        f'cannot listen on {bind}:{port}: {err.strerror or err} '
        '(choose --port N, or --port 0 for any free port)'
    )


def stop_on_signal() -> threading.Event:
    """An event set by SIGINT or SIGTERM (the page's server then stops cleanly)."""
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    return stop
