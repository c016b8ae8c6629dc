"""The console's bounds as an attacker on its port would test them, raw over sockets: a flood of
event streams (per client address and in all) that must not blind an operator with a token nor
the newest page; the ``Host`` of every request (DNS rebinding); the request head limit of the
docs (16 KiB); certificates out of their validity; a token file that is a FIFO.

The server runs in this process over a source that streams a small frame every 0.2 s; the command
line's refusals run ``catenary-monitor console`` as a process (one line, exit 2).
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Optional

import pytest
from test_console_http import Recorder, exchange, statuses

from catenary_monitor.console import http_transport
from catenary_monitor.console.operators import load_operators
from catenary_monitor.console.server import ConsoleServer

ALICE = 'a1b2c3d4e5f6a7b8c9d0'


class Light(Recorder):
    """A live source of small frames, one every 0.2 s (many streams stay cheap)."""

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        return {'now': time.time()}

    def wait(self, version: int, timeout: float) -> int:
        time.sleep(min(timeout, 0.2))
        return version + 1


def _operators(tmp_path: Path) -> Any:
    path = tmp_path / 'operators'
    path.write_text(f'alice:{ALICE}\n')
    path.chmod(0o600)
    return load_operators(str(path))[0]


@pytest.fixture
def guarded(tmp_path: Path) -> Any:
    server = ConsoleServer(Light(), '127.0.0.1', 0, operators=_operators(tmp_path))
    server.start()
    yield server
    server.shutdown()


def open_stream(
    port: int, source: str = '127.0.0.1', token: Optional[str] = None, host: str = '127.0.0.1'
) -> socket.socket:
    """A raw ``GET /api/stream`` from ``source`` (a loopback address), left open unread."""
    sock = socket.create_connection(('127.0.0.1', port), timeout=10, source_address=(source, 0))
    auth = f'Authorization: Bearer {token}\r\n' if token else ''
    sock.sendall(f'GET /api/stream HTTP/1.1\r\nHost: {host}:{port}\r\n{auth}\r\n'.encode())
    return sock


def first_frame(sock: socket.socket, timeout: float = 10.0) -> bytes:
    """The stream's status line and its first event (b'' when closed before)."""
    sock.settimeout(timeout)
    data = b''
    deadline = time.monotonic() + timeout
    try:
        while b'\r\n\r\n' not in data or b'data: ' not in data.split(b'\r\n\r\n', 1)[1]:
            if time.monotonic() > deadline:
                break
            chunk = sock.recv(65536)
            if not chunk:
                break
            data += chunk
    except (socket.timeout, ConnectionResetError):
        pass
    return data


def closed(sock: socket.socket, timeout: float = 5.0) -> bool:
    """Whether the server closed ``sock`` (its data read and dropped meanwhile)."""
    sock.settimeout(timeout)
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            if not sock.recv(1 << 20):
                return True
    except ConnectionResetError:
        return True
    except socket.timeout:
        return False
    return False


def get(port: int, path: str = '/api/config', host: Optional[str] = None) -> int:
    host = host if host is not None else f'127.0.0.1:{port}'
    reply = exchange(port, f'GET {path} HTTP/1.1\r\nHost: {host}\r\n\r\n'.encode(), quiet=1.0)
    return statuses(reply)[0] if statuses(reply) else 0


def test_a_stream_flood_cannot_blind_the_operator_nor_the_newest_page(guarded: Any) -> None:
    """64 streams without a token from one address: that address keeps its newest
    STREAMS_PER_CLIENT, the older ones are closed; then from 16 addresses: the unreserved
    streams stay under MAX_STREAMS - RESERVED_STREAMS. Throughout, an operator's stream with
    its token is served (frames flow), a new page's stream too, and the console answers."""
    server = guarded
    port = server.port
    flood = [open_stream(port) for _ in range(64)]
    time.sleep(0.5)
    per_client = http_transport.STREAMS_PER_CLIENT
    assert server.transport.streams <= per_client
    assert all(closed(s, 2.0) for s in flood[: 64 - per_client])
    operator = open_stream(port, token=ALICE)
    assert first_frame(operator).startswith(b'HTTP/1.1 200 ')
    page = open_stream(port)  # the newest page from the flooded address
    assert first_frame(page).startswith(b'HTTP/1.1 200 ')
    assert get(port) == 200
    # from 16 addresses, 8 streams each (the bound in all)
    wide = [open_stream(port, f'127.0.0.{2 + k % 16}') for k in range(128)]
    time.sleep(1.0)
    free = [r for r in server.transport.open_streams.values() if not r]
    assert len(free) <= http_transport.MAX_STREAMS - http_transport.RESERVED_STREAMS
    assert not closed(operator, 1.5)  # the operator's stream lives on, frames flowing
    second = open_stream(port, token=ALICE)
    assert first_frame(second).startswith(b'HTTP/1.1 200 ')
    assert get(port) == 200
    assert server.transport.evicted >= 64 - per_client
    wrong = open_stream(port, token='not-a-token-of-this-console')
    assert first_frame(wrong).startswith(b'HTTP/1.1 401 ')
    for sock in flood + wide + [operator, page, second, wrong]:
        sock.close()
    time.sleep(1.0)
    assert server.transport.streams == 0


@pytest.mark.parametrize(
    'bind, names, host, status',
    [
        ('127.0.0.1', (), 'evil.example:{port}', 421),
        ('127.0.0.1', (), 'evil.example', 421),
        ('127.0.0.1', (), '', 421),
        ('127.0.0.1', (), '127.0.0.1:{port}', 200),
        ('127.0.0.1', (), 'localhost:{port}', 200),
        ('127.0.0.1', (), 'LOCALHOST.:{port}', 200),
        ('127.0.0.1', (), '[::1]:{port}', 200),
        ('0.0.0.0', (), 'dockpc.example:{port}', 421),
        ('0.0.0.0', ('dockpc.example',), 'dockpc.example:{port}', 200),
        ('0.0.0.0', ('dockpc.example',), 'rebind.attacker.example:{port}', 421),
        ('0.0.0.0', (), '192.0.2.7:{port}', 200),
        ('0.0.0.0', (), '{hostname}:{port}', 200),
    ],
)
def test_host_is_checked_on_every_request(bind: str, names: Any, host: str, status: int) -> None:
    """A page reaching the console through DNS rebinding sends its own name as ``Host``:
    every request (reads too) with a name not of this console is refused (421), on 0.0.0.0
    as well; IP addresses, localhost, the bound name, this PC's name and ``--server-name``
    names are served."""
    server = ConsoleServer(Light(), bind, 0, server_names=names)
    server.start()
    try:
        value = host.format(port=server.port, hostname=server.hostname)
        for path in ('/api/frame', '/', '/api/config'):
            assert get(server.port, path, value) == status, (path, value)
    finally:
        server.shutdown()


def test_request_head_limit_is_16_kib(guarded: Any) -> None:
    """A head of 16 KiB is read; one byte more is 431 (a 20 KB head was accepted when the
    last read completed it), and nothing on the connection after it."""
    port = guarded.port

    def head(size: int) -> bytes:
        start = f'GET /api/config HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nX-Pad: '.encode()
        return start + b'a' * (size - len(start) - 4) + b'\r\n\r\n'

    for size, status in ((16384, 200), (16385, 431), (20000, 431), (20480, 431)):
        data = head(size)
        assert len(data) == size
        reply = exchange(port, data, quiet=0.5)
        assert statuses(reply) == [status], (size, reply[:120])


# ---------------------------------------------------------------- certificates, token files
def _ca_certificate(folder: Path, start: str, end: str) -> tuple[Path, Path]:
    """A self-signed certificate valid from ``start`` to ``end`` (openssl ca dates)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / 'index.txt').write_text('')
    (folder / 'serial').write_text('01\n')
    (folder / 'ca.cnf').write_text(
        '[ca]\ndefault_ca = local\n[local]\ndir = .\ndatabase = ./index.txt\n'
        'new_certs_dir = .\nserial = ./serial\ndefault_md = sha256\npolicy = any\n'
        '[any]\ncommonName = supplied\n'
    )
    run = dict(cwd=folder, check=True, capture_output=True, timeout=60)
    subprocess.run(
        ['openssl', 'req', '-new', '-newkey', 'rsa:2048', '-nodes', '-keyout', 'key.pem',
         '-out', 'req.csr', '-subj', '/CN=127.0.0.1'],
        **run,
    )  # fmt: skip
    subprocess.run(
        ['openssl', 'ca', '-config', 'ca.cnf', '-selfsign', '-keyfile', 'key.pem', '-in',
         'req.csr', '-out', 'cert.pem', '-startdate', start, '-enddate', end, '-batch'],
        **run,
    )  # fmt: skip
    return folder / 'cert.pem', folder / 'key.pem'


def _console(*args: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
    from ros_harness import child_env

    return subprocess.run(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'console', '--port', '0', *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=child_env(),
    )


def test_certificates_out_of_their_dates_are_refused(tmp_path: Path) -> None:
    """Expired in 2020, or valid only from 2055 (a GeneralizedTime): one line, exit 2; the
    dates read from the DER equal openssl's."""
    from catenary_monitor.console.tls import certificate_dates

    old = _ca_certificate(tmp_path / 'old', '20190101000000Z', '20200101000000Z')
    future = _ca_certificate(tmp_path / 'future', '20550101000000Z', '20600101000000Z')
    assert certificate_dates(old[0].read_bytes()) == (1546300800.0, 1577836800.0)
    assert certificate_dates(future[0].read_bytes()) == (2682374400.0, 2840140800.0)
    for (cert, key), words in ((old, 'expired on 2020-01-01'), (future, 'not valid before 2055')):
        done = _console('--tls-cert', str(cert), '--tls-key', str(key))
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1, done
        assert words in lines[0] and '--allow-expired' in lines[0], lines


def test_allow_expired_serves_with_a_loud_warning(tmp_path: Path) -> None:
    from browser_harness import stop, wait_for
    from ros_harness import child_env

    cert, key = _ca_certificate(tmp_path / 'old', '20190101000000Z', '20200101000000Z')
    out = tmp_path / 'console.out'
    proc = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'console', '--port', '0',
         '--tls-cert', str(cert), '--tls-key', str(key), '--allow-expired', '--read-only'],
        stdout=open(out, 'w+'), stderr=subprocess.STDOUT, env=child_env(),
    )  # fmt: skip
    try:
        wait_for('the console URL', lambda: 'console: https://127.0.0.1:' in out.read_text(), 90)
        text = out.read_text()
        assert 'WARNING: the certificate' in text and 'expired on 2020-01-01' in text, text
    finally:
        assert stop(proc) == 0


def test_a_fifo_as_token_file_is_one_line_never_a_hang(tmp_path: Path) -> None:
    """A FIFO (or a directory) given as the token file, certificate or key: one line, exit 2,
    at once (a plain open of a FIFO waits for a writer forever)."""
    fifo = tmp_path / 'operators'
    os.mkfifo(fifo)
    for args, words in (
        (['--token-file', str(fifo)], 'is not a regular file'),
        (['--token-file', str(tmp_path)], 'is not a regular file'),
        (['--tls-cert', str(fifo), '--tls-key', str(fifo)], 'is not a regular file'),
    ):
        t0 = time.monotonic()
        done = _console(*args, timeout=30.0)
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1 and words in lines[0], done
        assert time.monotonic() - t0 < 25.0


def test_the_flooded_console_process_stays_alive(tmp_path: Path) -> None:
    """``catenary-monitor console`` with a token file, hit by 64 streams without a token from
    one address and 64 from 16 others: the operator's stream is served, the page too."""
    from browser_harness import PARAMS, start_console, stop

    tokens = tmp_path / 'operators'
    tokens.write_text(f'alice:{ALICE}\n')
    tokens.chmod(0o600)
    proc, url = start_console(
        ['--params-file', str(PARAMS), '--token-file', str(tokens)], tmp_path / 'console.out'
    )
    port = int(url.rstrip('/').rsplit(':', 1)[1])
    socks: list[socket.socket] = []
    try:
        socks += [open_stream(port) for _ in range(64)]
        socks += [open_stream(port, f'127.0.0.{2 + k % 16}') for k in range(64)]
        time.sleep(1.0)
        operator = open_stream(port, token=ALICE)
        socks.append(operator)
        assert first_frame(operator, 20.0).startswith(b'HTTP/1.1 200 ')
        page = open_stream(port)
        socks.append(page)
        assert first_frame(page, 20.0).startswith(b'HTTP/1.1 200 ')
        assert get(port) == 200 and proc.poll() is None
    finally:
        for sock in socks:
            sock.close()
        assert stop(proc) == 0
    out = (tmp_path / 'console.out').read_text()
    assert 'Traceback' not in out and ALICE not in out, out
