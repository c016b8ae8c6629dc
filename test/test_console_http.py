"""The console's HTTP as an attacker and a flood would try it, raw over sockets: a smuggled
acknowledgement, lying or missing Content-Lengths, malformed requests, slowloris and half-open
connections, clients that go away; then the operators' tokens, read-only and TLS.

The server runs in this process over a recording source (what would reach the monitor), except
where the process itself is the point (SIGPIPE: ``catenary-monitor console`` as a process).
"""

from __future__ import annotations

import json
import os
import socket
import ssl
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Optional

import pytest

from catenary_monitor.console import http_transport
from catenary_monitor.console.server import ConsoleServer
from catenary_monitor.core.alarms.requests import split_id

GOOD = b'{"line": "line_11"}'


class Recorder:
    """A live source that records the acknowledgements that would reach the monitor."""

    mode = 'live'

    def __init__(self) -> None:
        self.acks: list[tuple[str, str]] = []

    def config_json(self) -> dict[str, Any]:
        return {'mode': 'live', 'lines': []}

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        return {'now': time.time(), 'pad': 'x' * 20000}

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]:
        return {'line': line}

    def acknowledge(self, line: str, origin: str) -> str:
        self.acks.append((line, origin))
        return f'{line} {origin}'

    def wait(self, version: int, timeout: float) -> int:
        time.sleep(min(timeout, 0.05))
        return version + 1


@pytest.fixture
def served() -> Any:
    source = Recorder()
    server = ConsoleServer(source, '127.0.0.1', 0)
    server.start()
    yield server, source
    server.shutdown()


def exchange(port: int, data: bytes, host: str = '127.0.0.1', quiet: float = 1.0) -> bytes:
    """Send ``data`` on a new connection; everything received until the server closes it or
    stays quiet for ``quiet`` s (then ``<open>`` is appended)."""
    with socket.create_connection((host, port), timeout=10) as sock:
        sock.sendall(data)
        sock.settimeout(quiet)
        out = b''
        try:
            while True:
                chunk = sock.recv(65536)
                if not chunk:
                    return out
                out += chunk
        except socket.timeout:
            return out + b'<open>'
        except ConnectionResetError:
            return out + b'<reset>'


def statuses(reply: bytes) -> list[int]:
    """The status codes of the responses in ``reply``, in order (framed by Content-Length)."""
    found = []
    while reply.startswith(b'HTTP/1.1 '):
        head, _, rest = reply.partition(b'\r\n\r\n')
        found.append(int(head.split(b' ')[1]))
        fields = dict(
            line.lower().split(b': ', 1) for line in head.split(b'\r\n')[1:] if b': ' in line
        )
        reply = rest[int(fields.get(b'content-length', len(rest))) :]
    return found


def ack_request(
    port: int, body: bytes = GOOD, origin: Optional[str] = None, **extra: str
) -> bytes:
    """A raw acknowledgement POST as the console's page sends it (or with ``origin``)."""
    host = f'127.0.0.1:{port}'
    headers = {
        'Host': host,
        'Origin': origin or f'http://{host}',
        'Content-Type': 'application/json',
        'Content-Length': str(len(body)),
        **extra,
    }
    head = ''.join(f'{k}: {v}\r\n' for k, v in headers.items())
    return f'POST /api/ack HTTP/1.1\r\n{head}\r\n'.encode() + body


def test_smuggled_acknowledgement_is_refused_and_not_applied(served: Any) -> None:
    """The attack of a page on another port: a cross-origin POST whose body is 4096 bytes of
    padding and then an acknowledgement request with the console's own Host and Origin. The
    body is read whole (or refused whole), so the inner request is never parsed: one refusal,
    the connection closed, nothing acknowledged. The same inner request sent as itself is
    accepted (the recorder sees acknowledgements). A body refused unread closes the
    connection; one read whole may leave it open, its content never parsed as a request."""
    server, source = served
    inner = ack_request(server.port)
    for padding in (4096, 100):
        body = b'x' * padding + inner
        outer = ack_request(
            server.port, body, origin='http://127.0.0.1:1', **{'Content-Type': 'text/plain'}
        )
        reply = exchange(server.port, outer)
        assert statuses(reply) == [413 if len(body) > 1024 else 403], reply[:200]
        if len(body) > 1024:  # refused unread: the connection is closed
            assert not reply.endswith(b'<open>'), 'the connection must be closed'
    assert source.acks == []
    reply = exchange(server.port, inner)
    assert statuses(reply) == [202], reply[:200]
    assert source.acks == [('line_11', 'console %s client 127.0.0.1' % socket.gethostname())]


@pytest.mark.parametrize(
    'length, status',
    [('-1', 400), ('abc', 400), ('0x10', 400), ('1e3', 400), ('1000000000', 413), (None, 411)],
)
def test_content_length_refused_before_the_body(served: Any, length: Any, status: int) -> None:
    """A negative, non-numeric, huge or missing Content-Length is answered at once, before a
    byte of the body is read, and the connection closed."""
    server, source = served
    head = f'POST /api/ack HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n'
    if length is not None:
        head += f'Content-Length: {length}\r\n'
    t0 = time.monotonic()
    reply = exchange(server.port, (head + '\r\n').encode(), quiet=5.0)
    assert time.monotonic() - t0 < 3.0
    assert statuses(reply) == [status], reply[:200]
    assert not reply.endswith(b'<open>')
    assert source.acks == []


def test_malformed_requests_get_4xx_never_a_traceback(served: Any, capfd: Any) -> None:
    """Garbage, no Host, a 64 KB head, chunked bodies, deeply nested JSON, a JSON list, an
    unknown method: each one 4xx, and nothing on stderr."""
    server, source = served
    port = server.port
    nested = b'[' * 1000
    cases = [
        (b'GARBAGE\r\n\r\n', 400),
        (b'GET / HTTP/1.1\r\n\r\n', 400),
        (b'GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Pad: ' + b'a' * 65536 + b'\r\n\r\n', 431),
        (b'POST /api/ack HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n0\r\n\r\n', 411),
        (
            b'POST /api/ack HTTP/1.1\r\nHost: x\r\nContent-Length: 3\r\nContent-Length: 4\r\n\r\n',
            400,
        ),
        (ack_request(port, nested), 400),
        (ack_request(port, b'["line_11"]'), 400),
        (ack_request(port, b'{"line": "line 11 x"}'), 400),
        (ack_request(port, b'{"line": 11}'), 400),
        (b'DELETE /api/ack HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n', 405),
        (b'GET /api/ack HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n', 405),
        (b'POST /nothing HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 0\r\n\r\n', 404),
        (b'GET /api/frame?t=nan HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n', 400),
        (b'GET /static/../../etc/passwd HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n', 404),
    ]
    for data, status in cases:
        reply = exchange(port, data, quiet=0.3)
        assert statuses(reply)[:1] == [status], (data[:80], reply[:200])
    assert source.acks == []
    err = capfd.readouterr().err
    assert 'Traceback' not in err and err == '', err


def test_keep_alive_and_pipelining(served: Any) -> None:
    """Two requests on one connection, sent together, get two answers in order."""
    server, _ = served
    data = (
        b'GET /api/config HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n'
        b'GET /api/frame HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n'
    )
    reply = exchange(server.port, data, quiet=0.5)
    assert statuses(reply) == [200, 200]
    assert reply.endswith(b'<open>')  # kept alive


def _get(port: int, path: str = '/api/config', timeout: float = 5.0) -> int:
    reply = exchange(
        port,
        f'GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n'.encode(),
        quiet=timeout,
    )
    return statuses(reply)[0] if statuses(reply) else 0


def test_slowloris_and_half_open_connections(served: Any) -> None:
    """200 connections that send half a request head and stall: the console still answers at
    once, on a bounded number of threads; then 200 event streams whose clients vanish (RST):
    the console goes on."""
    server, _ = served
    threads = threading.active_count()
    slow = []
    for _ in range(200):
        sock = socket.create_connection(('127.0.0.1', server.port), timeout=10)
        sock.sendall(b'GET /api/config HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ')
        slow.append(sock)
    t0 = time.monotonic()
    for _ in range(20):
        assert _get(server.port) == 200
    assert time.monotonic() - t0 < 5.0
    assert threading.active_count() - threads <= http_transport.REQUEST_WORKERS + 2
    for sock in slow:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack('ii', 1, 0))
        sock.close()  # RST
    streams = []
    for k in range(200):
        sock = socket.create_connection(('127.0.0.1', server.port), timeout=10)
        sock.sendall(b'GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n')
        streams.append(sock)
        if k % 20 == 19:  # reset in waves, some while a frame is being written
            time.sleep(0.1)
            for s in streams:
                s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack('ii', 1, 0))
                s.close()
            streams = []
    assert _get(server.port) == 200
    time.sleep(0.5)
    assert server.transport.streams == 0
    assert threading.active_count() - threads <= (
        http_transport.REQUEST_WORKERS + http_transport.MAX_STREAMS + 2
    )


def test_connections_beyond_the_limit_evict_the_idle(served: Any, monkeypatch: Any) -> None:
    """When the connection limit is reached, a new client closes the one waiting longest for a
    request: a flood of idle connections cannot lock the operator out."""
    server, _ = served
    monkeypatch.setattr(http_transport, 'MAX_CONNECTIONS', 20)
    idle = [socket.create_connection(('127.0.0.1', server.port), timeout=10) for _ in range(40)]
    time.sleep(0.3)
    assert len(server.transport.connections) <= 20
    assert _get(server.port) == 200
    idle[0].settimeout(2.0)
    assert idle[0].recv(10) == b''  # the oldest was closed
    for sock in idle:
        sock.close()


def test_stalled_head_is_closed_after_its_deadline(served: Any, monkeypatch: Any) -> None:
    """A request head that does not arrive whole within HEAD_TIMEOUT gets 408 and a close; an
    idle connection closes quietly after IDLE_TIMEOUT."""
    server, _ = served
    monkeypatch.setattr(http_transport, 'HEAD_TIMEOUT', 0.5)
    monkeypatch.setattr(http_transport, 'IDLE_TIMEOUT', 0.8)
    reply = exchange(server.port, b'GET / HTTP/1.1\r\nHost', quiet=3.0)
    assert statuses(reply) == [408] and not reply.endswith(b'<open>')
    assert exchange(server.port, b'', quiet=3.0) == b''


# ---------------------------------------------------------------- SIGPIPE and the process
def test_long_running_commands_ignore_sigpipe() -> None:
    """``run``, ``demo``, ``console`` and ``replay --publish`` serve until stopped and ignore
    SIGPIPE; the one-shot commands keep its default (``| head`` ends them quietly)."""
    from catenary_monitor.cli.main import build_parser, long_running

    parser = build_parser()
    for argv, keep in (
        (['console'], True),
        (['run', '--params-file', 'p.yaml'], True),
        (['demo'], True),
        (['replay', 'x.mcap', '--publish'], True),
        (['replay', 'x.mcap'], False),
        (['solve', '--weight', '1', '--depth', '1', '--tension', '2'], False),
        (['paper'], False),
    ):
        assert long_running(parser.parse_args(argv)) is keep, argv


# ---------------------------------------------------------------- operators, read-only, TLS
def _token_file(tmp_path: Path) -> Path:
    path = tmp_path / 'operators'
    path.write_text('# dock operators\nalice:a1b2c3d4e5f6a7b8c9d0\nbob:ffeeddccbbaa99887766\n')
    path.chmod(0o600)
    return path


def test_token_file_rules(tmp_path: Path) -> None:
    """A token file: NAME:TOKEN lines; short tokens, duplicates and malformed lines are one
    line naming the file and line, never showing a token; others' read access is a warning."""
    from catenary_monitor.console.operators import TokenFileError, load_operators

    operators, warning = load_operators(str(_token_file(tmp_path)))
    assert operators.names == ['alice', 'bob'] and warning is None
    assert operators.who('Bearer a1b2c3d4e5f6a7b8c9d0') == 'alice'
    assert operators.who('bearer ffeeddccbbaa99887766') == 'bob'
    for bad in (None, '', 'Bearer', 'Basic a1b2c3d4e5f6a7b8c9d0', 'Bearer a1b2c3d4e5f6a7b8c9d'):
        assert operators.who(bad) is None
    for text, where in (
        ('alice:short\n', ':1: the token'),
        ('alice a1b2c3d4e5f6a7b8c9d0\n', ':1: expected NAME:TOKEN'),
        ('alice:a1b2c3d4e5f6a7b8c9d0\nalice:ffeeddccbbaa99887766\n', ":2: 'alice' again"),
        ('alice:a1b2c3d4e5f6a7b8c9d0\nbob:a1b2c3d4e5f6a7b8c9d0\n', ':2: the same token'),
        ('# nobody\n', 'no NAME:TOKEN'),
    ):
        path = tmp_path / 'bad'
        path.write_text(text)
        with pytest.raises(TokenFileError) as err:
            load_operators(str(path))
        assert where in str(err.value) and 'a1b2c3d4' not in str(err.value), str(err.value)
    path.write_text('alice:a1b2c3d4e5f6a7b8c9d0\n')
    path.chmod(0o644)
    assert 'chmod 600' in (load_operators(str(path))[1] or '')


def _console_process(args: list[str], tmp_path: Path) -> tuple[subprocess.Popen, str]:
    from browser_harness import start_console

    return start_console(args, tmp_path / 'console.out')


def test_console_on_another_loopback_address_with_tokens(tmp_path: Path) -> None:
    """``console --bind 127.0.0.2 --token-file F``: an acknowledgement without a token is
    refused (401), with a token accepted and attributed to its operator (the origin the
    monitor records); a cross-origin request is refused (403) with or without the token.
    The console process is then hit by 200 half-open connections and 50 reset streams and
    still answers (SIGPIPE ignored)."""
    from browser_harness import stop
    from browser_harness import AckRecorder

    recorder = AckRecorder()
    tokens = _token_file(tmp_path)
    proc, url = _console_process(
        [
            '--params-file',
            str(Path(__file__).parents[1] / 'config' / 'floating_dock.yaml'),
            '--bind',
            '127.0.0.2',
            '--token-file',
            str(tokens),
        ],
        tmp_path,
    )
    try:
        assert url.startswith('http://127.0.0.2:')
        port = int(url.rstrip('/').rsplit(':', 1)[1])
        recorder.wait_for_publisher()
        alice = {'Authorization': 'Bearer a1b2c3d4e5f6a7b8c9d0'}

        def post(origin: Optional[str] = None, **headers: str) -> list[int]:
            data = ack_request(port, origin=origin, Connection='close', **headers).replace(
                b'127.0.0.1:', b'127.0.0.2:'
            )
            return statuses(exchange(port, data, host='127.0.0.2', quiet=5.0))

        assert post() == [401]
        assert post(**{'Authorization': 'Bearer wrong-token-0000000000'}) == [401]
        assert post(origin='http://127.0.0.1:1') == [403]
        assert post(origin='http://127.0.0.1:1', **alice) == [403]
        time.sleep(0.5)
        assert recorder.messages == []
        assert post(**alice) == [202]
        recorder.wait(1)
        assert recorder.messages[0].startswith('line_11 alice via console '), recorder.messages
        text, rid = split_id(recorder.messages[0])  # the request's id ends it
        assert text.endswith(' client 127.0.0.1') and len(rid) == 12, recorder.messages
        # 200 half-open connections and 50 streams reset under the writer
        for _ in range(200):
            sock = socket.create_connection(('127.0.0.2', port), timeout=10)
            sock.sendall(b'GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n')
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack('ii', 1, 0))
            sock.close()
        time.sleep(1.0)
        assert proc.poll() is None, (tmp_path / 'console.out').read_text()
        assert _get_host(port, '127.0.0.2') == 200
    finally:
        recorder.close()
        assert stop(proc) == 0
    out = (tmp_path / 'console.out').read_text()
    assert 'Traceback' not in out and 'a1b2c3d4' not in out, out


def _get_host(port: int, host: str) -> int:
    data = f'GET /api/config HTTP/1.1\r\nHost: {host}\r\n\r\n'.encode()
    reply = exchange(port, data, host=host, quiet=2.0)
    return statuses(reply)[0] if statuses(reply) else 0


@pytest.mark.parametrize(
    'args, message',
    [
        (['--bind', '0.0.0.0'], 'give --token-file FILE'),
        (['--token-file', '/nonexistent/tokens'], 'cannot read the token file'),
        (['--tls-cert', 'x.pem'], '--tls-cert and --tls-key go together'),
        (['--tls-cert', 'x.pem', '--tls-key', 'y.pem'], 'cannot use the certificate'),
    ],
)
def test_console_refuses_to_start(args: list[str], message: str) -> None:
    """Exit 2 with one line: a bind beyond loopback without --token-file or --read-only, an
    unreadable token file, half a TLS pair, a certificate that cannot be loaded."""
    from ros_harness import child_env

    done = subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'console', '--port', '0', *args],
        capture_output=True,
        text=True,
        timeout=60,
        env=child_env(),
    )
    assert done.returncode == 2, done
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], done.stderr


def test_read_only_and_tls(tmp_path: Path) -> None:
    """A read-only console refuses every action (403) and says so in its config; over TLS the
    page's origin is https and a client speaking plain HTTP to it is closed, not a traceback."""
    cert, key = tmp_path / 'cert.pem', tmp_path / 'key.pem'
    subprocess.run(
        [
            'openssl',
            'req',
            '-x509',
            '-newkey',
            'rsa:2048',
            '-nodes',
            '-days',
            '1',
            '-subj',
            '/CN=127.0.0.1',
            '-addext',
            'subjectAltName=IP:127.0.0.1',
            '-keyout',
            str(key),
            '-out',
            str(cert),
        ],
        check=True,
        capture_output=True,
        timeout=60,
    )
    from catenary_monitor.console.command import _tls
    from catenary_monitor.console.operators import load_operators

    source = Recorder()
    server = ConsoleServer(source, '127.0.0.1', 0, read_only=True)
    server.start()
    try:
        assert statuses(exchange(server.port, ack_request(server.port))) == [403]
        data = b'GET /api/config HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n'
        reply = exchange(server.port, data, quiet=0.5)
        assert (
            json.loads(reply.split(b'\r\n\r\n', 1)[1].split(b'<open>')[0])['access'] == 'read-only'
        )
    finally:
        server.shutdown()
    operators, _ = load_operators(str(_token_file(tmp_path)))
    server = ConsoleServer(
        source, '127.0.0.1', 0, operators=operators, tls=_tls(str(cert), str(key))
    )
    server.start()
    try:
        assert server.url.startswith('https://127.0.0.1:')
        assert exchange(server.port, b'GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n', quiet=3.0) in (
            b'',
            b'<reset>',
        )
        context = ssl.create_default_context(cafile=str(cert))
        with socket.create_connection(('127.0.0.1', server.port), timeout=10) as raw:
            with context.wrap_socket(raw, server_hostname='127.0.0.1') as tls:
                host = f'127.0.0.1:{server.port}'
                data = ack_request(
                    server.port,
                    origin=f'https://{host}',
                    Authorization='Bearer ffeeddccbbaa99887766',
                )
                tls.sendall(data)
                reply = tls.recv(65536)
        assert statuses(reply) == [202], reply[:200]
        assert source.acks[-1][1].startswith('bob via console ')
    finally:
        server.shutdown()
    assert os.path.exists(cert)
