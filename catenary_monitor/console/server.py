"""The console's HTTP server: the page, its JSON API and a Server-Sent Events stream.

Standard library only (``http.server.ThreadingHTTPServer``): the console serves one page to a
few browsers on the dock PC, so a framework would add dependencies and nothing the page needs.
Live updates go one way (monitor -> page), which is what Server-Sent Events are (a long GET,
``text/event-stream``, reconnected by the browser itself); the one request that changes state,
an acknowledgement, is a plain POST.

Routes:

``GET /``, ``GET /static/NAME``
    the page and its assets (package data; nothing from the internet);
``GET /api/config``
    lines (heading, MBL, ...), thresholds, the monitor's period, the mode (``live``/``replay``);
``GET /api/frame[?t=S]``
    the page's state now (replay: at log time S);
``GET /api/trend?line=NAME[&t=S][&span=S]``
    tension, uplift and anchor margin of a line and the depth, bucketed (default span 3600 s);
``GET /api/stream``
    live only: a frame at every change (at most 20 per second) and at least every 0.5 s;
``POST /api/ack``
    ``{"line": "NAME" | "all"}``: the console publishes the acknowledgement to the monitor.

Acknowledgements are refused (403) unless the request comes from the console's own page: the
``Host`` header must name this server (``127.0.0.1``, ``localhost`` or ``[::1]`` with its port,
or the ``--bind`` address; any host when bound to all interfaces), the ``Origin`` header must be
present and equal ``http://HOST``, and the body must be ``application/json`` (which a
cross-site form cannot send without a CORS preflight, which is never answered). So another web
site open in the operator's browser cannot acknowledge an alarm, nor can a page that reaches the
console through DNS rebinding.
"""

from __future__ import annotations

import json
import math
import socket
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any, Optional, Protocol
from urllib.parse import parse_qs, urlsplit

from catenary_monitor.console.frames import AckError

__all__ = ['Source', 'ConsoleServer', 'STATIC_FILES']

#: The page's files (package data under console/static) and their content types.
STATIC_FILES = {
    'index.html': 'text/html; charset=utf-8',
    'console.js': 'text/javascript; charset=utf-8',
    'console.css': 'text/css; charset=utf-8',
}
_CSP = "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'"


class Source(Protocol):
    """What the server asks of its data source (:class:`~.live.LiveSource`,
    :class:`~.replay.ReplaySource`)."""

    mode: str

    def config_json(self) -> dict[str, Any]: ...

    def frame(self, t: Optional[float] = None) -> dict[str, Any]: ...

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]: ...

    def acknowledge(self, line: str, origin: str) -> str: ...

    def wait(self, version: int, timeout: float) -> int: ...


def _clean(value: Any) -> Any:
    """JSON-safe: non-finite floats become None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _json(value: Any) -> bytes:
    return json.dumps(_clean(value), allow_nan=False, separators=(',', ':')).encode('utf-8')


def _static(name: str) -> bytes:
    return resources.files('catenary_monitor.console').joinpath('static', name).read_bytes()


class ConsoleServer:
    """The HTTP server of one console on ``bind:port`` (port 0: any free port)."""

    def __init__(self, source: Source, bind: str = '127.0.0.1', port: int = 8080) -> None:
        self.source = source
        self.bind = bind
        self.stopping = threading.Event()
        self.httpd = ThreadingHTTPServer((bind, port), _handler(self))
        self.httpd.daemon_threads = True
        self.port = int(self.httpd.server_address[1])
        self.any_host = bind in ('0.0.0.0', '::', '')
        names = {'127.0.0.1', 'localhost', '[::1]', bind if ':' not in bind else f'[{bind}]'}
        self.hosts = {f'{n}:{self.port}' for n in names}
        self.hostname = socket.gethostname()

    @property
    def url(self) -> str:
        host = '127.0.0.1' if self.any_host else self.bind
        return f'http://{host}:{self.port}/'

    def serve_forever(self) -> None:
        self.httpd.serve_forever(poll_interval=0.2)

    def start(self) -> threading.Thread:
        """Serve in a daemon thread."""
        thread = threading.Thread(target=self.serve_forever, name='http', daemon=True)
        thread.start()
        return thread

    def shutdown(self) -> None:
        self.stopping.set()
        self.httpd.shutdown()
        self.httpd.server_close()

    def refusal(self, headers: Any) -> Optional[str]:
        """Why a state-changing request must be refused (None: it comes from our page)."""
        host = headers.get('Host', '')
        if not self.any_host and host not in self.hosts:
            return f'Host {host!r} is not this console'
        origin = headers.get('Origin')
        if origin is None:
            return 'no Origin header: acknowledge from the console page'
        if origin != f'http://{host}':
            return f'request from another origin ({origin}) refused'
        if headers.get('Content-Type', '').split(';')[0].strip() != 'application/json':
            return 'the body must be application/json'
        return None


def _handler(server: ConsoleServer) -> type:
    class Handler(BaseHTTPRequestHandler):
        server_version = 'catenary-console'
        protocol_version = 'HTTP/1.1'

        def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - stdlib name
            pass  # one line per request would drown the terminal

        def _send(self, status: int, body: bytes, ctype: str = 'application/json') -> None:
            self.send_response(status)
            self.send_header('Content-Type', ctype)
            self.send_header('Content-Length', str(len(body)))
            self.send_header('Cache-Control', 'no-store')
            self.send_header('X-Content-Type-Options', 'nosniff')
            self.send_header('Content-Security-Policy', _CSP)
            self.end_headers()
            self.wfile.write(body)

        def _error(self, status: int, message: str) -> None:
            self._send(status, _json({'error': message}))

        def do_GET(self) -> None:  # noqa: N802 - stdlib name
            url = urlsplit(self.path)
            query = {k: v[-1] for k, v in parse_qs(url.query).items()}
            path = url.path
            try:
                if path in ('/', '/index.html'):
                    self._send(200, _static('index.html'), STATIC_FILES['index.html'])
                elif path.startswith('/static/') and path[8:] in STATIC_FILES:
                    self._send(200, _static(path[8:]), STATIC_FILES[path[8:]])
                elif path == '/favicon.ico':
                    self._send(204, b'', 'image/x-icon')
                elif path == '/api/config':
                    self._send(200, _json(server.source.config_json()))
                elif path == '/api/frame':
                    self._send(200, _json(server.source.frame(_time(query.get('t')))))
                elif path == '/api/trend':
                    span = _time(query.get('span')) or 3600.0
                    data = server.source.trend(
                        query.get('line', ''), _time(query.get('t')), min(span, 7200.0)
                    )
                    self._send(200, _json(data))
                elif path == '/api/stream':
                    self._stream()
                else:
                    self._error(404, f'no such page: {path}')
            except (BrokenPipeError, ConnectionResetError):
                pass
            except ValueError as err:
                self._error(400, str(err))

        def _stream(self) -> None:
            if server.source.mode != 'live':
                self._error(409, 'replay has no live stream: use /api/frame?t=')
                return
            self.send_response(200)
            self.send_header('Content-Type', 'text/event-stream')
            self.send_header('Cache-Control', 'no-store')
            self.send_header('Connection', 'close')
            self.end_headers()
            self.close_connection = True
            version, last = -1, 0.0
            while not server.stopping.is_set():
                version = server.source.wait(version, 0.5)
                wait = 0.05 - (time.monotonic() - last)
                if wait > 0:
                    time.sleep(wait)
                last = time.monotonic()
                self.wfile.write(b'data: ' + _json(server.source.frame()) + b'\n\n')
                self.wfile.flush()

        def do_POST(self) -> None:  # noqa: N802 - stdlib name
            path = urlsplit(self.path).path
            if path != '/api/ack':
                self._error(404, f'no such action: {path}')
                return
            length = int(self.headers.get('Content-Length') or 0)
            body = self.rfile.read(min(length, 4096)) if length else b''
            refusal = server.refusal(self.headers)
            if refusal is not None:
                self._error(403, refusal)
                return
            try:
                line = str(json.loads(body or b'{}').get('line', ''))
            except (ValueError, AttributeError):
                self._error(400, 'body must be {"line": "NAME" | "all"}')
                return
            if not line or any(c.isspace() for c in line):
                self._error(400, 'body must be {"line": "NAME" | "all"}')
                return
            origin = f'console {server.hostname} client {self.client_address[0]}'
            try:
                sent = server.source.acknowledge(line, origin)
            except AckError as err:
                self._error(err.status, str(err))
                return
            self._send(int(HTTPStatus.ACCEPTED), _json({'sent': sent}))

    return Handler


def _time(text: Optional[str]) -> Optional[float]:
    if text is None or text == '':
        return None
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f'not a finite time: {text!r}')
    return value
