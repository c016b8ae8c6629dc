"""The console's HTTP/1.1 transport: asyncio and h11, every request read whole, every wait bounded.

One event-loop thread reads every connection (h11, the HTTP/1.1 state machine, frames each
message), so the application sees a request only once it is complete, and a client that sends
slowly or goes away holds no thread. The bounds (module constants):

* at most :data:`MAX_CONNECTIONS` open; one more closes the connection waiting longest for its
  request (a flood of half-open connections cannot lock the operator out);
* a request head of at most :data:`HEAD_LIMIT` bytes (431), complete within
  :data:`HEAD_TIMEOUT` s (408); an idle keep-alive connection closes after :data:`IDLE_TIMEOUT` s;
* a body only with a ``Content-Length``: 411 without one (or with ``Transfer-Encoding``), 400
  for one that is not a decimal number (h11 refuses it before a byte of the body is read), 413
  above the route's limit; read whole within :data:`BODY_TIMEOUT` s. A request whose body was
  not read whole is answered with ``Connection: close`` and the connection closed, so nothing
  that follows a body is ever taken for a request (no smuggling);
* the application's handlers run on :data:`REQUEST_WORKERS` threads, event streams on at most
  :data:`MAX_STREAMS` more. A stream the application marks ``reserved`` (an operator's, with
  a valid token) may use every slot; the others at most ``MAX_STREAMS - RESERVED_STREAMS``, at
  most :data:`STREAMS_PER_CLIENT` per client address. A new stream is never refused: beyond a
  bound it closes the oldest unreserved stream of the same address, else the oldest unreserved
  one, else (reserved, every slot taken) the oldest reserved one, so a flood of streams cannot
  blind an operator, and the newest page always gets one;
* a response the client does not take within :data:`WRITE_TIMEOUT` s closes the connection; a
  client that goes away ends its stream, nothing else.

Optional TLS (an :class:`ssl.SSLContext`): the handshake must end within :data:`HEAD_TIMEOUT` s
(a connection counts toward :data:`MAX_CONNECTIONS` from then on).
"""

from __future__ import annotations

import asyncio
import socket
import ssl
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from http import HTTPStatus
from typing import Any, Iterator, Optional, Protocol

import h11

__all__ = [
    'Request',
    'Response',
    'HttpError',
    'Application',
    'HttpTransport',
    'MAX_CONNECTIONS',
    'MAX_STREAMS',
    'RESERVED_STREAMS',
    'STREAMS_PER_CLIENT',
    'HEAD_LIMIT',
    'HEAD_TIMEOUT',
    'IDLE_TIMEOUT',
    'BODY_TIMEOUT',
    'WRITE_TIMEOUT',
    'REQUEST_WORKERS',
]

#: Open connections at most (one more closes the one waiting longest for its request).
MAX_CONNECTIONS = 256
#: Event streams (Server-Sent Events) at most, each on its own worker thread.
MAX_STREAMS = 40
#: Stream slots only reserved streams (an operator's, with a valid token) may take.
RESERVED_STREAMS = 8
#: Unreserved streams of one client address at most (its oldest closes for a new one).
STREAMS_PER_CLIENT = 8
#: Threads running the application's request handlers.
REQUEST_WORKERS = 8
#: Bytes of a request head (request line and headers) at most.
HEAD_LIMIT = 16 * 1024
#: Seconds for a request head (or a TLS handshake) to arrive whole.
HEAD_TIMEOUT = 10.0
#: Seconds a keep-alive connection may wait idle for its next request.
IDLE_TIMEOUT = 30.0
#: Seconds for a declared body to arrive whole.
BODY_TIMEOUT = 10.0
#: Seconds for the client to take a response (or a stream's frame).
WRITE_TIMEOUT = 10.0
_READ = 8192


@dataclass(frozen=True)
class Request:
    """A complete request: method, path, query (last value per key), headers (lower-case
    names; a repeated header's values joined by ``, ``), body and the client's address."""

    method: str
    path: str
    query: dict[str, str]
    headers: dict[str, str]
    body: bytes
    client: str


@dataclass
class Response:
    """What a handler answers. ``stream``: a blocking iterator of chunks (an event stream),
    sent as they come until it ends or the client goes away; then ``body`` is not used.
    ``reserved``: the stream may take the slots kept for operators (see the module doc)."""

    status: int
    body: bytes = b''
    content_type: str = 'application/json'
    headers: list[tuple[str, str]] = field(default_factory=list)
    stream: Optional[Iterator[bytes]] = None
    reserved: bool = False


class HttpError(Exception):
    """A refusal: ``status``, one line of ``message``, extra response ``headers``."""

    def __init__(self, status: int, message: str, headers: Optional[list] = None) -> None:
        super().__init__(message)
        self.status = status
        self.headers = list(headers or [])


class Application(Protocol):
    """What the transport asks of the application (:class:`.server.ConsoleServer`)."""

    def body_limit(self, method: str, path: str) -> int:
        """The largest body the route takes (bytes); raises :class:`HttpError` (404, 405)
        for a route that does not exist, before anything of the body is read."""
        ...

    def handle(self, request: Request) -> Response:
        """The response to a complete request (runs on a worker thread)."""
        ...

    def error_body(self, status: int, message: str) -> tuple[bytes, str, list]:
        """(body, content type, headers) of an error response."""
        ...


def _query(text: str) -> dict[str, str]:
    from urllib.parse import parse_qsl

    return dict(parse_qsl(text, keep_blank_values=True, max_num_fields=32))


class _Connection:
    """One client connection: its h11 state machine, reader and writer."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader, self.writer = reader, writer
        self.h11 = h11.Connection(h11.SERVER, max_incomplete_event_size=HEAD_LIMIT)
        peer = writer.get_extra_info('peername')
        self.client = str(peer[0]) if isinstance(peer, tuple) and peer else ''
        self.waiting_since: Optional[float] = time.monotonic()  # None: being served
        self.received = 0  # bytes read from the client so far

    def abort(self) -> None:
        transport = self.writer.transport
        if not transport.is_closing():
            transport.abort()


class HttpTransport:
    """Serves ``app`` on a listening socket ``sock`` (bound by the caller), optionally over TLS,
    in its own event-loop thread (:meth:`start`, :meth:`stop`)."""

    def __init__(
        self, app: Application, sock: socket.socket, tls: Optional[ssl.SSLContext] = None
    ) -> None:
        self.app, self.sock, self.tls = app, sock, tls
        self.loop = asyncio.new_event_loop()
        self.loop.set_exception_handler(self._loop_error)
        self.workers = ThreadPoolExecutor(REQUEST_WORKERS, thread_name_prefix='http')
        # A stream closed for a newer one holds its worker until its frame wait ends (<= 0.5 s).
        self.stream_workers = ThreadPoolExecutor(
            MAX_STREAMS + RESERVED_STREAMS, thread_name_prefix='stream'
        )
        self.connections: dict[_Connection, None] = {}  # insertion order: oldest first
        self.open_streams: dict[_Connection, bool] = {}  # -> reserved; oldest first
        self.evicted = 0  # streams closed for a newer one
        self.stopping = threading.Event()
        self.errors = 0  # unexpected errors reported (one line each, the first ten)
        self._thread: Optional[threading.Thread] = None
        self._server: Optional[asyncio.AbstractServer] = None

    @property
    def streams(self) -> int:
        """Event streams open now."""
        return len(self.open_streams)

    # ------------------------------------------------------------------ life cycle
    def start(self) -> threading.Thread:
        """Serve in a daemon thread."""
        ready = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(ready,), name='http', daemon=True)
        self._thread.start()
        ready.wait(10.0)
        return self._thread

    def _run(self, ready: threading.Event) -> None:
        asyncio.set_event_loop(self.loop)
        self._server = self.loop.run_until_complete(
            asyncio.start_server(
                self._serve,
                sock=self.sock,
                limit=HEAD_LIMIT,
                ssl=self.tls,
                ssl_handshake_timeout=HEAD_TIMEOUT if self.tls else None,
            )
        )
        ready.set()
        try:
            self.loop.run_forever()
        finally:
            self._server.close()
            for conn in list(self.connections):
                conn.abort()
            tasks = asyncio.all_tasks(self.loop)
            for task in tasks:
                task.cancel()
            self.loop.run_until_complete(asyncio.gather(*tasks, return_exceptions=True))
            self.loop.close()

    def stop(self) -> None:
        """Stop serving: close every connection and the listening socket."""
        self.stopping.set()
        if self._thread is not None and self._thread.is_alive():
            self.loop.call_soon_threadsafe(self.loop.stop)
            self._thread.join(10.0)
        else:
            self.sock.close()
        self.workers.shutdown(wait=False, cancel_futures=True)
        self.stream_workers.shutdown(wait=False, cancel_futures=True)

    def report(self, message: str) -> None:
        """One line on stderr for an unexpected error (the first ten; then they are counted)."""
        self.errors += 1
        if self.errors <= 10:
            print(f'catenary-monitor console: {message}', file=sys.stderr, flush=True)

    def _loop_error(self, loop: Any, context: dict) -> None:
        exc = context.get('exception')
        if self.stopping.is_set() or isinstance(exc, asyncio.CancelledError):
            return  # connections cut short by the stop
        if isinstance(exc, (ConnectionError, ssl.SSLError, TimeoutError, OSError)):
            return  # a client that went away or spoke no TLS: its connection is closed
        self.report(f'{context.get("message", "error")}: {exc!r}'.replace('\n', ' '))

    # ------------------------------------------------------------------ one connection
    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        conn = _Connection(reader, writer)
        self._admit(conn)
        try:
            while not self.stopping.is_set() and await self._one_request(conn):
                conn.h11.start_next_cycle()
        except (ConnectionError, TimeoutError, ssl.SSLError, OSError, asyncio.IncompleteReadError):
            pass  # the client went away, stalled or spoke no TLS: close its connection
        except Exception as exc:  # noqa: BLE001 - one line, the server goes on
            self.report(f'connection from {conn.client}: {exc!r}')
        finally:
            self.connections.pop(conn, None)
            conn.abort()

    def _admit(self, conn: _Connection) -> None:
        """Count the connection in; beyond the limit close the one waiting longest for a
        request (or, when every one is being served, this one)."""
        if len(self.connections) >= MAX_CONNECTIONS:
            idle = [c for c in self.connections if c.waiting_since is not None]
            victim = min(idle, key=lambda c: c.waiting_since or 0.0) if idle else conn
            self.connections.pop(victim, None)
            victim.abort()
            if victim is conn:
                return
        self.connections[conn] = None

    async def _receive(self, conn: _Connection, deadline: float) -> None:
        remaining = deadline - self.loop.time()
        if remaining <= 0:
            raise TimeoutError
        data = await asyncio.wait_for(conn.reader.read(_READ), remaining)
        conn.received += len(data)
        conn.h11.receive_data(data)

    async def _next_event(self, conn: _Connection, deadline: float) -> Any:
        while True:
            event = conn.h11.next_event()
            if event is not h11.NEED_DATA:
                return event
            await self._receive(conn, deadline)

    async def _one_request(self, conn: _Connection) -> bool:
        """Read, handle and answer one request; True when the connection can carry another."""
        conn.waiting_since = time.monotonic()
        try:
            head = await self._read_head(conn)
            if head is None:
                return False
            request = await self._read_body(conn, *head)
        except h11.RemoteProtocolError as exc:
            status = exc.error_status_hint if 400 <= exc.error_status_hint < 500 else 400
            if exc.error_status_hint == 400 and 'buffer' in str(exc):
                status = 431
            await self._send_error(conn, status, f'malformed request: {exc}', close=True)
            return False
        except HttpError as err:
            await self._send_error(conn, err.status, str(err), err.headers, close=True)
            return False
        except TimeoutError:
            await self._send_error(conn, 408, 'request not received in time', close=True)
            return False
        conn.waiting_since = None
        response = await self._handle(request)
        return await self._respond(conn, response)

    async def _read_head(self, conn: _Connection) -> Optional[tuple[h11.Request, int]]:
        """The request head and its body's declared length, or None at a clean end (the
        client closed, or stayed idle for :data:`IDLE_TIMEOUT` s)."""
        deadline = self.loop.time() + IDLE_TIMEOUT
        begun = False
        start = conn.received - len(conn.h11.trailing_data[0])  # where this request begins
        while True:
            event = conn.h11.next_event()
            if isinstance(event, h11.Request):
                break
            if isinstance(event, h11.ConnectionClosed) or event is h11.PAUSED:
                return None
            if not begun and conn.h11.trailing_data[0]:  # a request has begun
                begun = True
                deadline = min(deadline, self.loop.time() + HEAD_TIMEOUT)
            try:
                await self._receive(conn, deadline)
            except TimeoutError:
                if not begun:
                    return None
                raise
        # h11 checks its buffer only while a head is incomplete: a head read whole in one
        # more read could pass its limit by up to a read's size.
        size = conn.received - len(conn.h11.trailing_data[0]) - start
        if size > HEAD_LIMIT:
            raise HttpError(431, f'request head of {size} bytes (at most {HEAD_LIMIT})')
        method = event.method.decode('ascii', 'replace')
        target = event.target.decode('ascii', 'replace')
        path = target.split('?', 1)[0]
        limit = self.app.body_limit(method, path)  # HttpError 404/405 before the body
        names = {name for name, _ in event.headers}
        if b'transfer-encoding' in names:
            raise HttpError(411, 'a body needs a Content-Length (no Transfer-Encoding)')
        if b'content-length' not in names:
            if method not in ('GET', 'HEAD'):
                raise HttpError(411, 'Content-Length required')
            return event, 0
        length = int(dict(event.headers)[b'content-length'])  # h11 checked: decimal digits
        if length > limit:
            raise HttpError(413, f'body of {length} bytes refused (at most {limit} here)')
        return event, length

    async def _read_body(self, conn: _Connection, event: h11.Request, length: int) -> Request:
        deadline = self.loop.time() + BODY_TIMEOUT
        chunks, size = [], 0
        while True:
            part = await self._next_event(conn, deadline)
            if isinstance(part, h11.Data):
                size += len(part.data)
                if size > length:  # h11 frames by Content-Length: cannot happen
                    raise HttpError(400, 'body longer than declared')
                chunks.append(bytes(part.data))
            elif isinstance(part, h11.EndOfMessage):
                break
            else:
                raise HttpError(400, 'incomplete body')
        headers: dict[str, str] = {}
        for name, value in event.headers:
            key = name.decode('latin-1')
            text = value.decode('latin-1')
            headers[key] = f'{headers[key]}, {text}' if key in headers else text
        target = event.target.decode('ascii', 'replace')
        path, _, query = target.partition('?')
        return Request(
            event.method.decode('ascii', 'replace'),
            path,
            _query(query),
            headers,
            b''.join(chunks),
            conn.client,
        )

    async def _handle(self, request: Request) -> Response:
        try:
            return await self.loop.run_in_executor(self.workers, self.app.handle, request)
        except HttpError as err:
            body, ctype, headers = self.app.error_body(err.status, str(err))
            return Response(err.status, body, ctype, headers + err.headers)
        except Exception as exc:  # noqa: BLE001 - one line, a 500, the server goes on
            self.report(f'{request.method} {request.path[:100]} failed: {exc!r}')
            body, ctype, headers = self.app.error_body(500, 'internal error (see the console)')
            return Response(500, body, ctype, headers)

    # ------------------------------------------------------------------ writing
    async def _write(self, conn: _Connection, data: bytes) -> None:
        conn.writer.write(data)
        await asyncio.wait_for(conn.writer.drain(), WRITE_TIMEOUT)

    def _head(self, response: Response, length: Optional[int], close: bool) -> h11.Response:
        headers = [('Content-Type', response.content_type), *response.headers]
        if length is not None:
            headers.append(('Content-Length', str(length)))
        if close:
            headers.append(('Connection', 'close'))
        try:
            reason = HTTPStatus(response.status).phrase.encode('ascii')
        except ValueError:
            reason = b''
        return h11.Response(status_code=response.status, headers=headers, reason=reason)

    async def _respond(self, conn: _Connection, response: Response) -> bool:
        if response.stream is not None:
            await self._stream(conn, response)
            return False
        data = conn.h11.send(self._head(response, len(response.body), False)) or b''
        if response.body:
            data += conn.h11.send(h11.Data(data=response.body)) or b''
        data += conn.h11.send(h11.EndOfMessage()) or b''
        await self._write(conn, data)
        return conn.h11.our_state is h11.DONE and conn.h11.their_state is h11.DONE

    async def _send_error(
        self, conn: _Connection, status: int, message: str, headers: Any = (), close: bool = True
    ) -> None:
        """An error response (when the state machine still allows one), then close."""
        if conn.h11.our_state not in (h11.IDLE, h11.SEND_RESPONSE):
            return
        body, ctype, extra = self.app.error_body(status, message)
        response = Response(status, body, ctype, extra + list(headers))
        try:
            data = conn.h11.send(self._head(response, len(body), close)) or b''
            data += conn.h11.send(h11.Data(data=body)) or b''
            data += conn.h11.send(h11.EndOfMessage()) or b''
        except h11.LocalProtocolError:
            return
        await self._write(conn, data)

    async def _stream(self, conn: _Connection, response: Response) -> None:
        """Send a stream's chunks as its iterator yields them (on a stream worker)."""
        assert response.stream is not None
        self._admit_stream(conn, response.reserved)
        try:
            await self._write(conn, conn.h11.send(self._head(response, None, True)) or b'')
            while not self.stopping.is_set() and conn in self.open_streams:
                chunk = await self.loop.run_in_executor(
                    self.stream_workers, next, response.stream, None
                )
                if chunk is None or conn.writer.transport.is_closing():
                    break
                await self._write(conn, conn.h11.send(h11.Data(data=chunk)) or b'')
        finally:
            self.open_streams.pop(conn, None)

    def _admit_stream(self, conn: _Connection, reserved: bool) -> None:
        """Count a new stream in, closing the one it displaces beyond a bound (module doc)."""
        streams = self.open_streams
        free = [c for c, r in streams.items() if not r]
        victim = None
        if not reserved:
            mine = [c for c in free if c.client == conn.client]
            if len(mine) >= STREAMS_PER_CLIENT:
                victim = mine[0]
            elif len(free) >= MAX_STREAMS - RESERVED_STREAMS:
                victim = free[0]
        elif len(streams) >= MAX_STREAMS:
            victim = free[0] if free else next(iter(streams))
        if victim is not None:
            streams.pop(victim, None)
            self.evicted += 1
            victim.abort()
        streams[conn] = reserved
