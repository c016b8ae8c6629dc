"""The console's HTTP application: the page, its JSON API, a Server-Sent Events stream and the
one policy every state-changing request passes.

The transport (:mod:`.http_transport`: asyncio and h11, every request read whole, every wait
bounded) hands this module complete requests only. Live updates go one way (monitor -> page),
which is what Server-Sent Events are (a long GET, ``text/event-stream``, reconnected by the
browser itself); a request that changes state is a POST.

Routes (:data:`PAGES`, :data:`ACTIONS`):

``GET /``, ``GET /static/NAME``
    the page and its assets (package data; nothing from the internet);
``GET /api/config``
    lines (heading, MBL, ...), thresholds, the monitor's period, the mode (``live``/``replay``)
    and ``access`` (``open``, ``token`` or ``read-only``);
``GET /api/frame[?t=S]``
    the page's state now (replay: at log time S);
``GET /api/trend?line=NAME[&t=S][&span=S]``
    tension, uplift and anchor margin of a line and the depth, bucketed (default span 3600 s);
``GET /api/stream``
    live only: a frame at every change (at most 20 per second) and at least every 0.5 s;
``POST /api/ack``
    ``{"line": "NAME" | "all"}``: the console publishes the acknowledgement to the monitor;
``POST /api/shelve``
    ``{"line": "NAME", "condition": "all" | CONDITION, "seconds": S}`` (0 s unshelves): the
    console publishes the shelving request to the monitor and answers with the monitor's answer
    (409 with its reason when the monitor refuses, e.g. the uplift ERROR);
``POST /api/operator``
    sign in: the operator a bearer token names (changes nothing).

Every route of :data:`ACTIONS` passes :meth:`ConsoleServer.authorize` first: refused (403) on a
``--read-only`` console and, but for a program with a token (below), unless the request comes
from the console's own page (the ``Host``
header names this server: ``127.0.0.1``, ``localhost`` or ``[::1]`` with its port, or the
``--bind`` address, any host when bound to all interfaces; the ``Origin`` header is present and
equals ``SCHEME://HOST``; the body is ``application/json``, which a cross-site form cannot send
without a CORS preflight, never answered); with a token file, refused (401) without
``Authorization: Bearer TOKEN`` of one of its operators. So another web site open in the
operator's browser cannot act, nor a page that reaches the console through DNS rebinding, nor,
with a token file, anyone without a token. A program (:meth:`ConsoleServer.program_client`: no
``Origin``, which every browser sends with a POST) acts with an operator's token on a console
with a token file, in that operator's name (``catenary-monitor ack``, a button's script).
"""

from __future__ import annotations

import ipaddress
import json
import math
import socket
import ssl
import threading
import time
from dataclasses import dataclass
from http import HTTPStatus
from importlib import resources
from typing import Any, Callable, Iterator, Mapping, Optional, Protocol, Sequence

from catenary_monitor.console.frames import AckError
from catenary_monitor.console.http_transport import HttpError, HttpTransport, Request, Response
from catenary_monitor.console.operators import Operators

__all__ = [
    'Source',
    'ConsoleServer',
    'Actor',
    'STATIC_FILES',
    'PAGES',
    'ACTIONS',
    'Page',
    'Action',
    'json_body',
    'ok_response',
    'static_body',
    'stream_page',
    'favicon_page',
    'operator_page',
]

#: The page's files (package data under console/static) and their content types.
STATIC_FILES = {
    'index.html': 'text/html; charset=utf-8',
    'console.js': 'text/javascript; charset=utf-8',
    'server_link.js': 'text/javascript; charset=utf-8',
    'console.css': 'text/css; charset=utf-8',
}
_CSP = (
    "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; "
    "frame-ancestors 'none'"
)


class Source(Protocol):
    """What the server asks of its data source (:class:`~.ros_source.LiveSource`,
    :class:`~.log_source.ReplaySource`)."""

    mode: str

    def config_json(self) -> dict[str, Any]: ...

    def frame(self, t: Optional[float] = None) -> dict[str, Any]: ...

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]: ...

    def acknowledge(self, line: str, origin: str) -> str: ...

    def shelve(
        self, alarm: str, condition: str, seconds: float, origin: str
    ) -> dict[str, Any]: ...

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
    """The console's HTTP application on ``bind:port`` (port 0: any free port).

    ``operators``: the token file's operators (every state-changing request then needs a valid
    ``Authorization: Bearer TOKEN``); ``read_only``: every state-changing request is refused;
    ``tls``: serve HTTPS with this context. Binding happens here (OSError: the port is taken).

    Another page (the harbour's) serves through the same policy and transport as a subclass
    that gives its own :meth:`routes` and :meth:`static_files`.
    """

    #: Seconds at least between two frames of an event stream.
    frame_interval = 0.05

    def __init__(
        self,
        source: Source,
        bind: str = '127.0.0.1',
        port: int = 8080,
        *,
        operators: Optional[Operators] = None,
        read_only: bool = False,
        tls: Optional[ssl.SSLContext] = None,
        server_names: Sequence[str] = (),
    ) -> None:
        self.source = source
        self.bind = bind
        self.operators = operators
        self.read_only = read_only
        self.scheme = 'https' if tls is not None else 'http'
        self.stopping = threading.Event()
        family = socket.AF_INET6 if ':' in bind else socket.AF_INET
        sock = socket.create_server((bind, port), family=family, backlog=128)
        self.port = int(sock.getsockname()[1])
        self.transport = HttpTransport(self, sock, tls)
        self.any_host = bind in ('0.0.0.0', '::', '')
        names = {'127.0.0.1', 'localhost', '[::1]', bind if ':' not in bind else f'[{bind}]'}
        self.hosts = {f'{n}:{self.port}' for n in names}
        #: The names a request's ``Host`` may give (besides any IP address): DNS rebinding.
        self.hostname = socket.gethostname()
        self.names = {'localhost', _bare(bind), _bare(self.hostname)} - {''}
        self.names |= {_bare(n) for n in server_names}

    @property
    def url(self) -> str:
        host = '127.0.0.1' if self.any_host else self.bind
        host = f'[{host}]' if ':' in host else host
        return f'{self.scheme}://{host}:{self.port}/'

    @property
    def access(self) -> str:
        """``read-only``, ``token`` (operators sign in) or ``open`` (this PC's page acts)."""
        return 'read-only' if self.read_only else ('token' if self.operators else 'open')

    def serve_forever(self) -> None:
        self.transport.start().join()

    def start(self) -> threading.Thread:
        """Serve in a daemon thread."""
        return self.transport.start()

    def shutdown(self) -> None:
        self.stopping.set()
        self.transport.stop()

    def routes(self) -> tuple[Mapping[str, Page], Mapping[str, tuple[int, Action]]]:
        """The GET routes (``/static/NAME`` besides) and the state-changing (POST) ones."""
        return PAGES, ACTIONS

    def static_files(self) -> Mapping[str, str]:
        """The files ``/static/NAME`` serves (package data under console/static): type."""
        return STATIC_FILES

    # ------------------------------------------------------------------ the policy
    def host_refusal(self, host: str) -> Optional[str]:
        """Why a request's ``Host`` header does not name this console (None: it does): a
        page reaching the console through DNS rebinding sends its own name. Accepted: an IP
        address (no rebinding there), ``localhost``, the ``--bind`` name, this PC's host name
        and the ``--server-name`` names (any port: a proxy may forward it)."""
        name = _split_host(host)[0]
        if _bare(name) in self.names or _is_address(name):
            return None
        return (
            f'Host {host[:80]!r} is not a name of this console (a page reaching it through DNS '
            f'rebinding?): open {self.url} or start it with --server-name NAME'
        )

    def refusal(self, headers: Mapping[str, str]) -> Optional[str]:
        """Why a state-changing request must be refused as not coming from this console's page
        (None: it does). ``headers``: lower-case names."""
        host = headers.get('host', '')
        if not self.any_host and host not in self.hosts:
            return f'Host {host[:80]!r} is not this console'
        origin = headers.get('origin')
        if origin is None:
            return 'no Origin header: act from the console page'
        if origin != f'{self.scheme}://{host}':
            return f'request from another origin ({origin[:80]}) refused'
        if headers.get('content-type', '').split(';')[0].strip() != 'application/json':
            return 'the body must be application/json'
        return None

    def program_client(self, headers: Mapping[str, str]) -> bool:
        """A program's request, not a browser's: no ``Origin`` header (a browser sends one with
        every POST, so a page cannot pass for a program) on a console with a token file. It
        must then carry an operator's bearer token (401 otherwise): ``catenary-monitor ack``,
        a button's script, a SCADA. ``headers``: lower-case names."""
        return self.operators is not None and 'origin' not in headers

    def authorize(self, request: Request) -> Actor:
        """Who is acting, for every state-changing request (every route of :data:`ACTIONS`
        passes here first): refused (403) on a read-only console, from another origin, a
        foreign Host or without a JSON body; with a token file, refused (401) without a valid
        bearer token. The actor's ``origin`` names the operator, the console and the client."""
        if self.read_only:
            raise HttpError(403, 'this console is read-only (started with --read-only)')
        refusal = None if self.program_client(request.headers) else self.refusal(request.headers)
        if refusal is not None:
            raise HttpError(403, refusal)
        where = f'console {self.hostname} client {request.client}'
        if self.operators is None:
            return Actor('', where)
        name = self.operators.who(request.headers.get('authorization'))
        if name is None:
            raise HttpError(
                401,
                'sign in: a valid operator token is needed (Authorization: Bearer TOKEN)',
                [('WWW-Authenticate', 'Bearer realm="catenary-monitor console"')],
            )
        return Actor(name, f'{name} via {where}')

    # ------------------------------------------------------------------ the transport's side
    def body_limit(self, method: str, path: str) -> int:
        pages, actions = self.routes()
        if method == 'POST':
            if path in actions:
                return actions[path][0]
            if path in pages:
                raise HttpError(405, f'{path} is read with GET', [('Allow', 'GET')])
            raise HttpError(404, f'no such action: {path[:100]}')
        if method == 'GET':
            if path in actions:
                raise HttpError(405, f'{path} takes a POST', [('Allow', 'POST')])
            return 0
        raise HttpError(405, f'method {method[:20]} not allowed', [('Allow', 'GET, POST')])

    def error_body(self, status: int, message: str) -> tuple[bytes, str, list]:
        return _json({'error': message}), 'application/json', _HEADERS

    def handle(self, request: Request) -> Response:
        refused = self.host_refusal(request.headers.get('host', ''))
        if refused is not None:
            raise HttpError(421, refused)
        pages, actions = self.routes()
        try:
            if request.method == 'POST':
                limit, action = actions[request.path]
                return action(self, request, self.authorize(request))
            page = pages.get(request.path)
            if page is None and request.path.startswith('/static/'):
                page = _static_page
            if page is None:
                raise HttpError(404, f'no such page: {request.path[:100]}')
            return page(self, request)
        except ValueError as err:
            raise HttpError(400, str(err)) from None

    def events(self) -> Iterator[bytes]:
        """The live event stream: a frame at every change (at most 20 per second) and at least
        every 0.5 s, until the server stops (or the client goes away)."""
        version, last = -1, 0.0
        while not self.stopping.is_set():
            version = self.source.wait(version, 0.5)
            wait = self.frame_interval - (time.monotonic() - last)
            if wait > 0:
                time.sleep(wait)
            last = time.monotonic()
            yield b'data: ' + _json(self.source.frame()) + b'\n\n'


@dataclass(frozen=True)
class Actor:
    """Who acts: the operator's name (empty without a token file) and the ``origin`` the
    monitor records (``NAME via console HOST client ADDRESS``, or ``console HOST client
    ADDRESS``)."""

    name: str
    origin: str


_HEADERS = [
    ('Cache-Control', 'no-store'),
    ('X-Content-Type-Options', 'nosniff'),
    ('Content-Security-Policy', _CSP),
    ('Referrer-Policy', 'no-referrer'),
]


def _ok(body: bytes, ctype: str = 'application/json', status: int = 200) -> Response:
    return Response(status, body, ctype, list(_HEADERS))


def _index(server: ConsoleServer, request: Request) -> Response:
    return _ok(_static('index.html'), STATIC_FILES['index.html'])


def _static_page(server: ConsoleServer, request: Request) -> Response:
    name = request.path[len('/static/') :]
    files = server.static_files()
    if name not in files:
        raise HttpError(404, f'no such file: {name[:100]}')
    return _ok(_static(name), files[name])


def _config(server: ConsoleServer, request: Request) -> Response:
    return _ok(_json({**server.source.config_json(), 'access': server.access}))


def _frame(server: ConsoleServer, request: Request) -> Response:
    return _ok(_json(server.source.frame(_time(request.query.get('t')))))


def _trend(server: ConsoleServer, request: Request) -> Response:
    span = _time(request.query.get('span')) or 3600.0
    line = request.query.get('line', '')
    data = server.source.trend(line, _time(request.query.get('t')), min(span, 7200.0))
    return _ok(_json(data))


def _stream(server: ConsoleServer, request: Request) -> Response:
    """The live stream; with an operator's token (``Authorization: Bearer``) a reserved one,
    which a flood of streams without a token cannot displace (401 for a token that is not
    one of the token file's)."""
    if server.source.mode != 'live':
        raise HttpError(409, 'replay has no live stream: use /api/frame?t=')
    reserved = False
    authorization = request.headers.get('authorization')
    if authorization is not None and server.operators is not None:
        if server.operators.who(authorization) is None:
            raise HttpError(
                401,
                'not an operator token of this console (stream without it, or sign in again)',
                [('WWW-Authenticate', 'Bearer realm="catenary-monitor console"')],
            )
        reserved = True
    return Response(
        200, b'', 'text/event-stream', list(_HEADERS), stream=server.events(), reserved=reserved
    )


def _favicon(server: ConsoleServer, request: Request) -> Response:
    return _ok(b'', 'image/x-icon', 204)


def _line_request(request: Request) -> str:
    """The line of a ``{"line": "NAME" | "all"}`` body (400 otherwise)."""
    try:
        line = json.loads(request.body or b'{}').get('line', '')
    except (ValueError, AttributeError, RecursionError):
        line = None
    if not isinstance(line, str) or not line or len(line) > 128 or not line.isprintable():
        raise HttpError(400, 'body must be {"line": "NAME" | "all"}')
    if any(c.isspace() for c in line):
        raise HttpError(400, 'body must be {"line": "NAME" | "all"}')
    return line


def _acknowledge(server: ConsoleServer, request: Request, actor: Actor) -> Response:
    line = _line_request(request)
    try:
        sent = server.source.acknowledge(line, actor.origin)
    except AckError as err:
        raise HttpError(err.status, str(err)) from None
    return _ok(_json({'sent': sent, 'operator': actor.name}), status=int(HTTPStatus.ACCEPTED))


def _shelve(server: ConsoleServer, request: Request, actor: Actor) -> Response:
    """Shelve (or unshelve, 0 s) one alarm or one condition of it, in the actor's name; the
    monitor decides and answers (409 with its reason when it refuses)."""
    try:
        body = json.loads(request.body or b'{}')
    except (ValueError, RecursionError):
        body = None
    usage = 'body must be {"line": "NAME", "condition": "all" | CONDITION, "seconds": S}'
    if not isinstance(body, dict):
        raise HttpError(400, usage)
    line = _line_request(request)
    condition = body.get('condition', 'all')
    seconds = body.get('seconds')
    if not isinstance(condition, str) or not condition.isidentifier() or len(condition) > 64:
        raise HttpError(400, usage)
    if isinstance(seconds, bool) or not isinstance(seconds, (int, float)):
        raise HttpError(400, usage)
    if not math.isfinite(seconds) or seconds < 0:
        raise HttpError(400, f'seconds must be finite and >= 0, got {seconds!r}')
    try:
        answer = server.source.shelve(line, condition, float(seconds), actor.origin)
    except AckError as err:
        raise HttpError(err.status, str(err)) from None
    return _ok(_json({**answer, 'operator': actor.name}), status=int(HTTPStatus.ACCEPTED))


def _operator(server: ConsoleServer, request: Request, actor: Actor) -> Response:
    """Sign in: who the token names (the page then shows the operator and enables its
    actions); changes nothing."""
    return _ok(_json({'operator': actor.name, 'access': server.access}))


#: A GET route's handler(server, request).
Page = Callable[[ConsoleServer, Request], Response]
#: A state-changing route's handler(server, request, actor).
Action = Callable[[ConsoleServer, Request, Actor], Response]

#: GET routes: path -> handler(server, request) (``/static/NAME`` besides).
PAGES: dict[str, Page] = {
    '/': _index,
    '/index.html': _index,
    '/favicon.ico': _favicon,
    '/api/config': _config,
    '/api/frame': _frame,
    '/api/trend': _trend,
    '/api/stream': _stream,
}
#: The state-changing routes (POST): path -> (largest body in bytes, handler(server, request,
#: actor)). The server calls :meth:`ConsoleServer.authorize` before every one of them: a new
#: action is added here and nowhere else.
ACTIONS: dict[str, tuple[int, Action]] = {
    '/api/ack': (1024, _acknowledge),
    '/api/shelve': (1024, _shelve),
    '/api/operator': (1024, _operator),
}

# What another page served through this policy (the harbour's) builds on.
json_body = _json
ok_response = _ok
static_body = _static
stream_page = _stream
favicon_page = _favicon
operator_page = _operator


def _split_host(host: str) -> tuple[str, str]:
    """(name, port) of a ``Host`` value: ``NAME[:PORT]`` or ``[V6][:PORT]`` (port '' when
    none)."""
    if host.startswith('['):
        name, _, rest = host[1:].partition(']')
        return name, rest[1:] if rest.startswith(':') else rest
    if host.count(':') == 1:
        name, _, port = host.partition(':')
        return name, port
    return host, ''


def _bare(name: str) -> str:
    """A host name as compared: lower case, no brackets, no trailing dot."""
    return name.strip().lower().strip('[]').rstrip('.')


def _is_address(name: str) -> bool:
    try:
        ipaddress.ip_address(_bare(name))
    except ValueError:
        return False
    return True


def _time(text: Optional[str]) -> Optional[float]:
    if text is None or text == '':
        return None
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f'not a finite time: {text!r}')
    return value
