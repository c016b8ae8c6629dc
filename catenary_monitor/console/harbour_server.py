"""The harbour's HTTP application: the console's server (:class:`.server.ConsoleServer`: the
same transport, limits, Host check, origin policy, token file and TLS) with the harbour's
page and routes.

Routes:

``GET /``, ``GET /static/NAME``
    the harbour page (``harbour.html``, ``harbour.js``, ``harbour.css``, and ``server_link.js``,
    the stream reader it shares with the console's page);
``GET /api/config``
    the docks (name, domain, position, console URL, lines), the host and ``access``;
``GET /api/docks``
    a JSON array, one object per dock (docs/harbour.md lists every key);
``GET /api/alarms``
    the harbour-wide alarm list (each dock's first out first);
``GET /api/frame``
    what the stream sends: ``{now, level, counts, docks, alarms}``;
``GET /api/stream``
    Server-Sent Events: a frame at every change (at most 4 per second) and at least every
    0.5 s;
``POST /api/ack``
    ``{"dock": NAME, "line": LINE | "all" | "sensors"}``: only with ``--token-file`` (the
    harbour is read-only otherwise), in the operator's name, published in the dock's domain;
``POST /api/operator``
    sign in (changes nothing).
"""

from __future__ import annotations

import json
from http import HTTPStatus
from typing import Any, Mapping

from catenary_monitor.console.frames import AckError
from catenary_monitor.console.harbour_model import harbour_alarms
from catenary_monitor.console.http_transport import HttpError, Request, Response
from catenary_monitor.console.server import (
    Action,
    Actor,
    ConsoleServer,
    Page,
    favicon_page,
    json_body,
    ok_response,
    operator_page,
    static_body,
    stream_page,
)

__all__ = ['HarbourServer', 'HARBOUR_FILES']

#: The harbour page's files (package data under console/static) and their content types.
HARBOUR_FILES = {
    'harbour.html': 'text/html; charset=utf-8',
    'harbour.js': 'text/javascript; charset=utf-8',
    'server_link.js': 'text/javascript; charset=utf-8',
    'harbour.css': 'text/css; charset=utf-8',
}


class HarbourServer(ConsoleServer):
    """The harbour page on ``bind:port`` over a :class:`.harbour_source.HarbourSource` (the
    console's keyword arguments: ``operators``, ``read_only``, ``tls``, ``server_names``)."""

    #: A harbour frame holds every dock: at most 4 a second to each page.
    frame_interval = 0.25

    def __init__(self, source: Any, bind: str = '127.0.0.1', port: int = 8090, **kw: Any):
        # read-only unless operators are given (tokens): no "open" harbour
        kw['read_only'] = bool(kw.get('read_only')) or kw.get('operators') is None
        super().__init__(source, bind, port, **kw)

    def authorize(self, request: Request) -> Actor:
        """The console's policy; a harbour without operators says where to acknowledge."""
        if self.read_only and self.operators is None:
            raise HttpError(
                403,
                'this harbour is read-only: acknowledge at the dock\'s own console (or start '
                'the harbour with --token-file)',
            )
        return super().authorize(request)

    def routes(self) -> tuple[Mapping[str, Page], Mapping[str, tuple[int, Action]]]:
        return HARBOUR_PAGES, HARBOUR_ACTIONS

    def static_files(self) -> Mapping[str, str]:
        return HARBOUR_FILES


def _index(server: ConsoleServer, request: Request) -> Response:
    return ok_response(static_body('harbour.html'), HARBOUR_FILES['harbour.html'])


def _config(server: ConsoleServer, request: Request) -> Response:
    return ok_response(json_body({**server.source.config_json(), 'access': server.access}))


def _docks(server: ConsoleServer, request: Request) -> Response:
    return ok_response(json_body(_source(server).docks()))


def _alarms(server: ConsoleServer, request: Request) -> Response:
    return ok_response(json_body(harbour_alarms(_source(server).docks())))


def _frame(server: ConsoleServer, request: Request) -> Response:
    return ok_response(json_body(server.source.frame()))


def _source(server: ConsoleServer) -> Any:
    return server.source


def _acknowledge(server: ConsoleServer, request: Request, actor: Actor) -> Response:
    """Acknowledge one alarm of one dock, in the operator's name (the dock's monitor
    decides and records it)."""
    usage = 'body must be {"dock": NAME, "line": LINE | "all" | "sensors"}'
    try:
        body = json.loads(request.body or b'{}')
    except (ValueError, RecursionError):
        body = None
    if not isinstance(body, dict):
        raise HttpError(400, usage)
    dock, line = body.get('dock'), body.get('line')
    for value in (dock, line):
        if not isinstance(value, str) or not 0 < len(value) <= 128 or not value.isprintable():
            raise HttpError(400, usage)
        if any(c.isspace() for c in value):
            raise HttpError(400, usage)
    try:
        sent = _source(server).acknowledge(dock, line, _harbour_origin(actor.origin))
    except AckError as err:
        raise HttpError(err.status, str(err)) from None
    return ok_response(
        json_body({'sent': sent, 'dock': dock, 'operator': actor.name}),
        status=int(HTTPStatus.ACCEPTED),
    )


def _harbour_origin(origin: str) -> str:
    """The actor's origin as the dock's monitor records it: ``console HOST`` becomes
    ``harbour HOST`` (the operator's name untouched)."""
    head, sep, rest = origin.rpartition(' via console ')
    if sep:
        return f'{head} via harbour {rest}'
    return 'harbour ' + origin[len('console '):] if origin.startswith('console ') else origin


#: The harbour's GET routes (``/static/NAME`` besides).
HARBOUR_PAGES: dict[str, Page] = {
    '/': _index,
    '/index.html': _index,
    '/favicon.ico': favicon_page,
    '/api/config': _config,
    '/api/docks': _docks,
    '/api/alarms': _alarms,
    '/api/frame': _frame,
    '/api/stream': stream_page,
}
#: The harbour's state-changing routes: :meth:`ConsoleServer.authorize` passes each first
#: (refused on a harbour without a token file: it is started read-only).
HARBOUR_ACTIONS: dict[str, tuple[int, Action]] = {
    '/api/ack': (1024, _acknowledge),
    '/api/operator': (1024, operator_page),
}
