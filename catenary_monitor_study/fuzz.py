"""Fuzzing what reads untrusted bytes: the MCAP reader and recovery, the CDR decoders, the
params file parser and the console's HTTP.

Each :class:`Target` turns one input (bytes) into a call of the code's public entry point and
checks what the project promises of it: only its named errors (``McapReadError``,
``ParamsFileError``, ``ValueError`` for a payload that is not one, a 4xx), never another
exception, a 500 or a traceback, every input answered within :data:`CASE_SECONDS`; a recovered
file is one the ``mcap`` library reads whole; the console answers a good request after each bad
one. Inputs are mutations of seed inputs (bytes set, flipped, deleted, inserted, cut, a length
field replaced by an extreme integer, a token of the format inserted), drawn by Hypothesis; or
by atheris (libFuzzer, coverage-guided) where it is installed.

The suite runs a bounded number of cases per target (``test/test_fuzz.py``, seconds);
``catenary-monitor fuzz --minutes N`` runs the targets in turn for N minutes, writes every
failing input to ``--out`` and prints the cases run and failures per target. docs/fuzzing.md
holds the figures.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import re
import shutil
import socket
import struct
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Optional

__all__ = ['CASE_SECONDS', 'Finding', 'TARGETS', 'Target', 'fuzz_target', 'register', 'run']

#: Longest time one input may take (s): beyond, the input is a failure (a hang).
CASE_SECONDS = 10.0
#: Integers that break length and count fields (little-endian, by width in bytes).
_EXTREMES = {
    1: (0, 1, 0x7F, 0x80, 0xFF),
    2: (0, 1, 0x7FFF, 0x8000, 0xFFFF),
    4: (0, 1, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 0xFFFFFFF0),
    8: (0, 1, 2**31, 2**32, 2**62, 2**63 - 1, 2**63, 2**64 - 1, 2**64 - 16),
}


class Finding(Exception):
    """An input the code under test mishandled: ``str()`` says how."""


@dataclass
class Target:
    """What one fuzz target reads: ``seeds`` (built in a work folder), ``check`` (one input,
    raising :class:`Finding` or an unexpected exception for a failure), ``tokens`` (pieces of
    the format that mutations insert), ``limit`` (largest input, bytes)."""

    name: str
    seeds: Callable[[Path], list[bytes]]
    check: Callable[[bytes, Path], None]
    tokens: tuple[bytes, ...] = ()
    limit: int = 1 << 16
    setup: Optional[Callable[[], Any]] = None
    teardown: Optional[Callable[[], None]] = None


# ---------------------------------------------------------------- MCAP: the reader, recovery
_TOPIC = '/mooring/a/tension'


def _mcap_seeds(work: Path) -> list[bytes]:
    """Small logs the way the node writes them: zstd, lz4 and plain chunks, a Float64 and a
    String topic, metadata; one cut as a SIGKILL leaves it (no summary)."""
    from catenary_monitor.io.cdr import string_message
    from catenary_monitor.io.mcap_log import McapLogger

    out = []
    for compression in ('zstd', 'lz4', 'none'):
        folder = work / f'seed-{compression}'
        shutil.rmtree(folder, ignore_errors=True)
        log = McapLogger(
            folder, fsync=False, compression=compression, chunk_size=300, bag_metadata=False
        )
        log.register(_TOPIC, 'std_msgs/msg/Float64', 'sensor_data')
        log.register('/catenary_monitor/events', 'std_msgs/msg/String')
        log.add_metadata('catenary_monitor', {'version': 'fuzz', 'units': 'SI'})
        for k in range(24):
            value = b'\x00\x01\x00\x00' + struct.pack('<d', 370e3 + k)
            log.write(_TOPIC, value, 1_795_000_000_000_000_000 + k * 100_000_000)
            if k % 8 == 0:
                log.write('/catenary_monitor/events', string_message('{"kind": "x"}'), 1 + k)
        log.close()
        out.append(log.files[0].read_bytes())
        shutil.rmtree(folder, ignore_errors=True)
    cut = out[0]
    out.append(cut[: len(cut) * 2 // 3])
    return out


_MCAP_TOKENS = (
    b'\x89MCAP0\r\n',
    b'\x01', b'\x02', b'\x03', b'\x04', b'\x05', b'\x06', b'\x07', b'\x08', b'\x09', b'\x0a',
    b'\x0b', b'\x0c', b'\x0d', b'\x0e', b'\x0f',
    b'zstd', b'lz4', b'cdr', b'ros2', b'ros2msg', b'std_msgs/msg/Float64',
    b'\x28\xb5\x2f\xfd',  # zstd frame magic
    b'\x04\x22\x4d\x18',  # lz4 frame magic
)  # fmt: skip


def _mcap_library_messages(data: bytes) -> Optional[set[tuple[str, int, int, bytes]]]:
    """The messages the ``mcap`` library reads from ``data`` with its CRCs checked, or None
    when it refuses the file."""
    from mcap.reader import make_reader

    try:
        reader = make_reader(io.BytesIO(data), validate_crcs=True)
        return {
            (channel.topic, m.log_time, m.sequence, bytes(m.data))
            for _, channel, m in reader.iter_messages(log_time_order=False)
        }
    except Exception:  # noqa: BLE001 - whatever it refuses, it refuses
        return None


def _check_mcap_read(data: bytes, work: Path) -> None:
    """The log reader's public entry points: only McapReadError (empty log, wrong type); and
    a message the ``mcap`` library reads (CRCs checked) is never lost without a named skip."""
    from catenary_monitor.io.mcap_read import (
        McapReadError,
        ReadReport,
        iter_messages,
        read_float64_topics,
    )
    from catenary_monitor.io.mcap_summary import read_summary

    path = work / 'case.mcap'
    path.write_bytes(data)
    report = ReadReport()
    ours = set()
    try:
        for m in iter_messages(path, None, report):
            ours.add((m.topic, m.log_time_ns, m.sequence, bytes(m.data)))
    except McapReadError:
        pass
    theirs = _mcap_library_messages(data)
    if theirs is not None and not theirs <= ours and report.complete:
        raise Finding(f'{len(theirs - ours)} message(s) the mcap library reads lost unreported')
    try:
        read_float64_topics(path, [_TOPIC])
    except McapReadError:
        pass
    from catenary_monitor.io import mcap_read

    # what replay, alarms, fleet and the console's --log stream a log with
    iter_windows: Any = getattr(mcap_read, 'iter_windows', None)
    if iter_windows is not None:
        try:
            raw = ['/catenary_monitor/events']
            for _ in iter_windows(path, [_TOPIC], raw, 16, ReadReport(), allow_empty=True):
                pass
        except McapReadError:
            pass
    read_summary(path)


_RECOVERED = ('recovered', 'finished_in_place', 'already_finished', 'not_mcap', 'failed')


def _check_mcap_recover(data: bytes, work: Path) -> None:
    """Recovery never raises; a file it says it finished, the ``mcap`` library reads whole
    (summary, every message) and it holds the count recovery gives, and every message the
    library read in the original unless recovery names damage."""
    from mcap.reader import make_reader

    from catenary_monitor.io.mcap_recover import recover_file

    src, dst = work / 'in', work / 'out'
    for folder in (src, dst):
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir()
    path = src / 'case.mcap'
    path.write_bytes(data)
    result = recover_file(path, out_dir=dst)
    if result.status not in _RECOVERED:
        raise Finding(f'recovery status {result.status!r}')
    if result.status != 'recovered':
        return
    with open(dst / 'case.mcap', 'rb') as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        count = sum(1 for _ in reader.iter_messages(log_time_order=False))
    if summary is None or summary.statistics is None:
        raise Finding('a recovered file without a summary')
    if count != result.messages or summary.statistics.message_count != count:
        raise Finding(f'recovered {result.messages} messages, the file holds {count}')
    before = _mcap_library_messages(data)
    after = _mcap_library_messages((dst / 'case.mcap').read_bytes())
    if before is not None and after is not None and not before <= after and not result.damaged:
        raise Finding(f'{len(before - after)} message(s) lost by recovery, none reported')


# ---------------------------------------------------------------- CDR
_CDR_TYPES = (
    'geometry_msgs/msg/WrenchStamped',
    'sensor_msgs/msg/FluidPressure',
    'sensor_msgs/msg/Range',
)


def _cdr_seeds(work: Path) -> list[bytes]:
    from catenary_monitor.io.cdr import string_message

    stamp = struct.pack('<iI', 1_795_000_000, 500)

    def head(frame: bytes) -> bytes:
        return b'\x00\x01\x00\x00' + stamp + struct.pack('<I', len(frame) + 1) + frame + b'\x00'

    wrench = head(b'hook')
    wrench += b'\x00' * (-(len(wrench) - 4) % 8) + struct.pack('<6d', 1, 2, 3, 4, 5, 6)
    pressure = head(b'p')
    pressure += b'\x00' * (-(len(pressure) - 4) % 8) + struct.pack('<2d', 101325.0, 0.0)
    rng = head(b'radar') + b'\x00'
    rng += b'\x00' * (-(len(rng) - 4) % 4) + struct.pack('<4f', 0.1, 0.5, 40.0, 21.3)
    big = b'\x00\x00\x00\x00' + wrench[4:]  # big-endian flag, little-endian bytes
    return [wrench, pressure, rng, big, string_message('line_11 alice'), string_message('')]


def _check_cdr(data: bytes, work: Path) -> None:
    """The decoders of untrusted payloads: ``sensor_cdr.decode`` never raises (a payload that
    is not one is ``ok`` False); ``cdr.string_text`` raises ValueError only, and reads back
    what ``string_message`` wrote."""
    import numpy as np

    from catenary_monitor.io.cdr import string_message, string_text
    from catenary_monitor.io.sensor_cdr import decode

    for type_name in _CDR_TYPES:
        cols = decode(type_name, [data, data[:-1], data + b'\x00'])
        if cols.ok.dtype != bool or len(cols.ok) != 3 or len(cols.stamps) != cols.ok.sum():
            raise Finding(f'{type_name}: columns of the wrong shape')
        for values in cols.fields.values():
            if len(values) != cols.ok.sum() or values.dtype != np.float64:
                raise Finding(f'{type_name}: a field of the wrong shape')
    try:
        text = string_text(data)
    except ValueError:
        return
    if string_text(string_message(text)) != text:
        raise Finding(f'std_msgs/String {text[:40]!r} does not read back')


# ---------------------------------------------------------------- the params file
def _params_seeds(work: Path) -> list[bytes]:
    root = Path(__file__).resolve().parents[1] / 'config'
    seeds = [p.read_bytes()[:4096] for p in sorted(root.glob('*.yaml'))]
    seeds += [
        b'catenary_monitor:\n  ros__parameters:\n    lines: [a]\n    a:\n      weight: 1300.0\n'
        b'      anchor_distance: 121.06\n      mbl: 5.17e6\n',
        b'/**:\n  ros__parameters:\n    depth_topic: "/tide/depth"\n    x: [1, 2.5, true]\n',
        b'/ns/catenary_monitor:\n  ros__parameters: {lines: [b], b.weight: 0x10}\n',
    ]
    return seeds


_YAML_TOKENS = (
    b':', b': ', b'- ', b'[', b']', b'{', b'}', b',', b'\n', b'  ', b'    ', b'"', b"'", b'#',
    b'---\n', b'...\n', b'%YAML 1.1\n', b'? ', b'&a ', b'*a', b'!!str ', b'!!int ', b'|\n',
    b'>\n', b'\t', b'\\', b'\xef\xbb\xbf', b'\x00', b'/**', b'ros__parameters', b'lines',
    b'1e400', b'0x1p-1074', b'.nan', b'-.inf', b'yes', b'~', b'null', b'<<: ',
)  # fmt: skip


def _check_params(data: bytes, work: Path) -> None:
    """The params file as the node and every command read it: only ParamsFileError (one
    line) from the parser, only ConfigError (one line) from the configuration."""
    from catenary_monitor.core.config.parameters import (
        ConfigError,
        config_from_params,
        load_params_file,
    )
    from catenary_monitor.core.config.params_file import ParamsFileError, parse_params

    try:
        parse_params(data)
    except ParamsFileError as err:
        if '\n' in str(err):
            raise Finding(f'a refusal of more than one line: {str(err)[:120]!r}')
    path = work / 'case.yaml'
    path.write_bytes(data)
    try:
        flat = load_params_file(path)
        if flat:
            config_from_params(flat)
    except ConfigError as err:
        if '\n' in str(err):
            raise Finding(f'a refusal of more than one line: {str(err)[:120]!r}')


# ---------------------------------------------------------------- the console's HTTP
class _Source:
    """A live source that answers everything at once (nothing reaches a monitor)."""

    mode = 'live'

    def config_json(self) -> dict[str, Any]:
        return {'mode': 'live', 'lines': []}

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        return {'now': time.time() if t is None else t}

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]:
        return {'line': line}

    def acknowledge(self, line: str, origin: str) -> str:
        return f'{line} {origin}'

    def shelve(self, alarm: str, condition: str, seconds: float, origin: str) -> dict[str, Any]:
        return {'sent': f'{alarm} {seconds:g}', 'answer': None}

    def wait(self, version: int, timeout: float) -> int:
        time.sleep(min(timeout, 0.2))
        return version + 1


_TOKEN = 'f0e1d2c3b4a5968778695a4b3c2d1e0f'
_HTTP: dict[str, Any] = {}


def _http_setup() -> Any:
    from catenary_monitor.console.operators import Operators
    from catenary_monitor.console.server import ConsoleServer

    server = ConsoleServer(_Source(), '127.0.0.1', 0, operators=Operators({'alice': _TOKEN}))
    server.start()
    _HTTP['server'] = server
    return server


def _http_teardown() -> None:
    server = _HTTP.pop('server', None)
    if server is not None:
        server.shutdown()


def _http_seeds(work: Path) -> list[bytes]:
    host = b'Host: 127.0.0.1:8080\r\n'
    origin = b'Origin: http://127.0.0.1:8080\r\n'
    auth = f'Authorization: Bearer {_TOKEN}\r\n'.encode()

    def post(path: bytes, body: bytes) -> bytes:
        return (
            b'POST ' + path + b' HTTP/1.1\r\n' + host + origin + auth
            + b'Content-Type: application/json\r\nContent-Length: '
            + str(len(body)).encode() + b'\r\n\r\n' + body
        )  # fmt: skip

    return [
        b'GET / HTTP/1.1\r\n' + host + b'\r\n',
        b'GET /api/frame?t=1795000000.5 HTTP/1.1\r\n' + host + b'Connection: close\r\n\r\n',
        b'GET /api/trend?line=a&span=600 HTTP/1.1\r\n' + host + b'\r\nGET /api/config HTTP/1.1'
        b'\r\n' + host + b'\r\n',
        b'GET /static/console.js HTTP/1.0\r\n\r\n',
        post(b'/api/ack', b'{"line": "line_11"}'),
        post(b'/api/shelve', b'{"line": "line_11", "condition": "anchor_margin", "seconds": 600}'),
        post(b'/api/operator', b'{}'),
    ]


_HTTP_TOKENS = (
    b'\r\n', b'\r\n\r\n', b': ', b'Content-Length: ', b'Transfer-Encoding: chunked\r\n',
    b'Host: ', b'Origin: ', b'Authorization: Bearer ', b'Connection: close\r\n', b'Expect: ',
    b'100-continue', b'HTTP/1.1', b'HTTP/1.0', b'GET ', b'POST ', b'HEAD ', b'/api/ack',
    b'/api/shelve', b'/api/stream', b'%00', b'?t=', b'&', b'{"line": ', b'[', b'"', b'\x00',
    b' ', b'\t', b'99999999999999999999',
)  # fmt: skip


def _exchange(port: int, data: bytes, wait: float = 5.0) -> bytes:
    """Send ``data``, end the sending side, read until the server closes (``wait`` s at most:
    an event stream goes on)."""
    with socket.create_connection(('127.0.0.1', port), timeout=5) as sock:
        try:
            sock.sendall(data)
            sock.shutdown(socket.SHUT_WR)
        except OSError:
            return b''
        sock.settimeout(wait)
        out = b''
        deadline = time.monotonic() + wait
        try:
            while time.monotonic() < deadline:
                chunk = sock.recv(65536)
                if not chunk:
                    break
                out += chunk
        except (socket.timeout, ConnectionResetError):
            pass
        return out


def _check_http(data: bytes, work: Path) -> None:
    """Any bytes on a connection: no 5xx but 503 (Retry-After), nothing the server reports as
    an unexpected error; a good request is answered after each case."""
    server = _HTTP.get('server') or _http_setup()
    errors = server.transport.errors
    data = data.replace(b'127.0.0.1:8080', f'127.0.0.1:{server.port}'.encode())
    reply = _exchange(server.port, data, 1.0 if b'/api/stream' in data else 5.0)
    for line in reply.split(b'\r\n'):
        if line.startswith(b'HTTP/1.1 5') and not line.startswith(b'HTTP/1.1 503'):
            raise Finding(f'answered {line[:40]!r}')
    if server.transport.errors != errors:
        raise Finding('the server reported an unexpected error (see stderr)')
    probe = _exchange(server.port, b'GET /api/config HTTP/1.1\r\nHost: localhost\r\n\r\n')
    if not probe.startswith(b'HTTP/1.1 200 '):
        raise Finding(f'the console stopped answering: {probe[:60]!r}')


# ---------------------------------------------------------------- the targets, the runner
TARGETS: dict[str, Target] = {
    t.name: t
    for t in (
        Target('mcap_read', _mcap_seeds, _check_mcap_read, _MCAP_TOKENS, 1 << 16),
        Target('mcap_recover', _mcap_seeds, _check_mcap_recover, _MCAP_TOKENS, 1 << 16),
        Target('cdr', _cdr_seeds, _check_cdr, (b'\x00', b'\x01', b'\xff\xff\xff\xff'), 512),
        Target('params', _params_seeds, _check_params, _YAML_TOKENS, 1 << 13),
        Target(
            'http', _http_seeds, _check_http, _HTTP_TOKENS, 1 << 15, _http_setup, _http_teardown
        ),
    )
}


def mutate(
    data: bytes, ops: list[tuple[int, int, int, bytes]], tokens: tuple[bytes, ...]
) -> bytes:
    """``data`` changed by ``ops``: (kind, position, number, bytes) each."""
    out = bytearray(data)
    for kind, pos, number, extra in ops:
        n = len(out)
        pos = pos % (n + 1)
        if kind == 0 and n:  # set a byte
            out[pos % n] = number & 0xFF
        elif kind == 1 and n:  # flip a bit
            out[pos % n] ^= 1 << (number % 8)
        elif kind == 2:  # delete a run
            del out[pos : pos + 1 + number % 64]
        elif kind == 3:  # insert bytes
            out[pos:pos] = extra
        elif kind == 4:  # cut
            del out[pos:]
        elif kind == 5 and n:  # an extreme integer over a field
            width = (1, 2, 4, 8)[number % 4]
            values = _EXTREMES[width]
            out[pos : pos + width] = values[(number // 4) % len(values)].to_bytes(width, 'little')
        elif kind == 6 and tokens:  # a token of the format
            out[pos:pos] = tokens[number % len(tokens)]
        elif kind == 7:  # repeat a run
            run_ = bytes(out[pos : pos + 1 + number % 256])
            out[pos:pos] = run_ * (1 + number % 3)
    return bytes(out)


def _strategy(seeds: list[bytes], target: Target) -> Any:
    from hypothesis import strategies as st

    op = st.tuples(
        st.integers(0, 7), st.integers(0, 1 << 20), st.integers(0, 1 << 16), st.binary(max_size=24)
    )
    return st.builds(
        lambda seed, ops: mutate(seed, ops, target.tokens)[: target.limit],
        st.sampled_from(seeds),
        st.lists(op, max_size=10),
    )


@dataclass
class Outcome:
    """One target's run: cases checked, and each failure (its kind, the input's file)."""

    target: str
    cases: int = 0
    seconds: float = 0.0
    failures: list[dict[str, str]] = field(default_factory=list)


def _one(target: Target, data: bytes, work: Path) -> Optional[str]:
    """None, or why ``data`` fails the target (an unexpected exception, a finding, a hang)."""
    t0 = time.monotonic()
    try:
        target.check(data, work)
    except Finding as found:
        return f'{found}'
    except Exception as exc:  # noqa: BLE001 - what the fuzzer looks for
        frame = traceback.extract_tb(exc.__traceback__)[-1]
        where = f'{Path(frame.filename).name}:{frame.lineno}'
        return f'{type(exc).__name__} at {where}: {str(exc)[:160]}'
    if time.monotonic() - t0 > CASE_SECONDS:
        return f'took {time.monotonic() - t0:.1f} s (more than {CASE_SECONDS:g} s)'
    return None


def fuzz_target(
    target: Target,
    cases: int,
    work: Path,
    seed: Optional[int] = None,
    out: Optional[Path] = None,
    stop_at: Optional[float] = None,
) -> Outcome:
    """Run ``cases`` Hypothesis examples of ``target`` (deterministic with ``seed``); every
    failing input is written to ``out`` (when given) and listed, one per kind of failure."""
    from hypothesis import HealthCheck, Phase, given, seed as hseed, settings

    outcome = Outcome(target.name)
    work.mkdir(parents=True, exist_ok=True)
    seeds = target.seeds(work)
    seen: set[str] = set()
    t0 = time.monotonic()
    if target.setup is not None:
        target.setup()

    @settings(
        max_examples=cases,
        deadline=None,
        database=None,
        derandomize=seed is None,
        phases=(Phase.explicit, Phase.generate),  # no shrinking: every failure is kept as found
        suppress_health_check=list(HealthCheck),
    )
    @given(_strategy(seeds, target))
    def case(data: bytes) -> None:
        if stop_at is not None and time.monotonic() > stop_at:
            return
        outcome.cases += 1
        why = _one(target, data, work)
        if why is None:
            return
        kind = _kind(why)
        if kind in seen:
            return
        seen.add(kind)
        entry = {'why': why}
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
            name = out / f'{target.name}-{hashlib.sha1(data).hexdigest()[:12]}.bin'
            name.write_bytes(data)
            entry['input'] = str(name)
        outcome.failures.append(entry)

    try:
        if seed is not None:
            case = hseed(seed)(case)
        with _quiet_stderr(target):
            for data in seeds:  # the seeds themselves first
                why = _one(target, data, work)
                if why is not None:
                    outcome.failures.append({'why': f'seed: {why}'})
            case()
    finally:
        if target.teardown is not None:
            target.teardown()
    outcome.seconds = time.monotonic() - t0
    return outcome


def _kind(why: str) -> str:
    """A failure's kind: its words before the first colon, numbers left out."""
    return re.sub(r'\d+', 'N', why.split(':')[0])


@contextlib.contextmanager
def _quiet_stderr(target: Target) -> Iterator[None]:
    """The console's own one-line reports of bad requests stay out of the fuzzer's output."""
    if target.name != 'http':
        yield
        return
    saved = sys.stderr
    sys.stderr = io.StringIO()
    try:
        yield
    finally:
        sys.stderr = saved


def run(
    minutes: float,
    targets: list[str],
    out: Path,
    seed: Optional[int] = None,
    batch: int = 500,
    report: Callable[[str], None] = print,
) -> dict[str, Outcome]:
    """The targets in turn, ``batch`` cases or a slice of the time at a time (at most a
    minute, the same for each), for ``minutes``; the outcomes."""
    import random

    stop_at = time.monotonic() + minutes * 60.0
    share = min(60.0, minutes * 60.0 / max(1, len(targets)))
    rng = random.Random(seed)
    outcomes = {name: Outcome(name) for name in targets}
    with tempfile.TemporaryDirectory(prefix='catenary-fuzz-') as tmp:
        while time.monotonic() < stop_at:
            for name in targets:
                if time.monotonic() >= stop_at:
                    break
                one = fuzz_target(
                    TARGETS[name], batch, Path(tmp) / name, rng.randrange(1 << 30), out,
                    min(stop_at, time.monotonic() + share),
                )  # fmt: skip
                total = outcomes[name]
                total.cases += one.cases
                total.seconds += one.seconds
                known = {_kind(f['why']) for f in total.failures}
                for found in one.failures:
                    if _kind(found['why']) not in known:
                        total.failures.append(found)
                        report(f'fuzz {name}: FAILURE {found["why"]} ({found.get("input", "")})')
            report(
                'fuzz: '
                + ', '.join(f'{o.target} {o.cases}' for o in outcomes.values())
                + ' cases'
            )
    return outcomes


# ---------------------------------------------------------------- atheris (coverage-guided)
def _atheris_main(name: str, argv: list[str]) -> None:
    """libFuzzer on one target through atheris (``python -m catenary_monitor_study.fuzz
    atheris TARGET [libFuzzer options]``): the package's modules instrumented for coverage."""
    import atheris

    with atheris.instrument_imports(include=['catenary_monitor']):
        import catenary_monitor.console.server  # noqa: F401
        import catenary_monitor.core.config.params_file  # noqa: F401
        import catenary_monitor.io.mcap_read  # noqa: F401
        import catenary_monitor.io.mcap_recover  # noqa: F401
        import catenary_monitor.io.sensor_cdr  # noqa: F401
    target = TARGETS[name]
    work = Path(tempfile.mkdtemp(prefix=f'catenary-atheris-{name}-'))
    corpus = work / 'corpus'
    corpus.mkdir()
    for k, data in enumerate(target.seeds(work)):
        (corpus / f'seed-{k}').write_bytes(data)
    if target.setup is not None:
        target.setup()

    def one(data: bytes) -> None:
        why = _one(target, data[: target.limit], work)
        if why is not None:
            raise Finding(why)

    atheris.Setup([sys.argv[0], *argv, str(corpus)], one)
    atheris.Fuzz()


def _atheris_run(name: str, seconds: int, out: Path) -> tuple[int, list[str]]:
    """One target under atheris for ``seconds`` in a child process: (cases, crash files)."""
    import subprocess

    out.mkdir(parents=True, exist_ok=True)
    cmd = [
        sys.executable, '-m', 'catenary_monitor_study.fuzz', 'atheris', name,
        f'-max_total_time={seconds}', f'-artifact_prefix={out}/{name}-', '-rss_limit_mb=3072',
        f'-max_len={TARGETS[name].limit}', '-print_final_stats=1',
    ]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=seconds + 120)
    cases = 0
    for line in done.stderr.splitlines():
        if line.startswith('stat::number_of_executed_units:'):
            cases = int(line.split(':')[-1])
    crashes = sorted(str(p) for p in out.glob(f'{name}-crash-*'))
    return cases, crashes


def has_atheris() -> bool:
    try:
        import atheris  # noqa: F401
    except ImportError:
        return False
    return True


# ---------------------------------------------------------------- the command
def cmd_fuzz(args: argparse.Namespace) -> int:
    """``catenary-monitor fuzz``: exit 0 when no target failed, 1 otherwise."""
    names = args.target or list(TARGETS)
    unknown = [n for n in names if n not in TARGETS]
    if unknown:
        print(f'catenary-monitor fuzz: no target {unknown[0]!r} ({", ".join(TARGETS)})',
              file=sys.stderr)  # fmt: skip
        return 2
    out = Path(args.out)
    before = _limit_memory(args.memory_mib)
    try:
        outcomes = run(args.minutes, names, out, args.seed, report=lambda s: print(s, flush=True))
    finally:
        _restore_memory(before)
    atheris_cases: dict[str, int] = {}
    if args.atheris:
        if not has_atheris():
            print('catenary-monitor fuzz: --atheris needs atheris (pip install atheris)',
                  file=sys.stderr)  # fmt: skip
            return 2
        share = max(10, int(args.atheris * 60 / len(names)))
        for name in names:
            cases, crashes = _atheris_run(name, share, out)
            atheris_cases[name] = cases
            for crash in crashes:
                outcomes[name].failures.append({'why': 'atheris crash', 'input': crash})
    rows: dict[str, dict[str, Any]] = {
        name: {
            'cases': o.cases,
            'atheris_cases': atheris_cases.get(name, 0),
            'seconds': round(o.seconds, 1),
            'failures': o.failures,
        }
        for name, o in outcomes.items()
    }
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        for name, row in rows.items():
            extra = f' + {row["atheris_cases"]} atheris' if args.atheris else ''
            print(f'{name:14s} {row["cases"]:8d} cases{extra} in {row["seconds"]:7.1f} s, '
                  f'{len(row["failures"])} failure(s)')  # fmt: skip
            for found in row['failures']:
                print(f'    {found["why"]}  {found.get("input", "")}')
    return 1 if any(row['failures'] for row in rows.values()) else 0


def _limit_memory(mib: int) -> tuple[int, int] | None:
    """An address-space limit: an input that makes a reader allocate without bound is a
    MemoryError (a failure), not a machine brought down. Returns the limit it replaced."""
    if not mib:
        return None
    try:
        import resource

        before = resource.getrlimit(resource.RLIMIT_AS)
        resource.setrlimit(resource.RLIMIT_AS, (mib << 20, before[1]))
        return before
    except (ImportError, ValueError, OSError):
        return None


def _restore_memory(before: tuple[int, int] | None) -> None:
    """Put back the limit :func:`_limit_memory` replaced (a caller in the same process, such as
    the test suite, starts browsers and nodes afterwards)."""
    if before is not None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, before)


def register(sub: Any) -> None:
    """Add ``fuzz`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'fuzz',
        help='fuzz the MCAP reader and recovery, the CDR decoders, the params file and the '
        "console's HTTP",
        description='Run the fuzz targets in turn for a while (Hypothesis mutations of seed '
        'inputs; with --atheris, also libFuzzer through atheris); every failing input is '
        'written to --out. Exit 0 when nothing failed, 1 otherwise (docs/fuzzing.md).',
    )
    p.add_argument('--minutes', type=float, default=5.0, help='how long (default: 5)')
    p.add_argument('--target', action='append', metavar='NAME',
                   help=f'a target ({", ".join(TARGETS)}; repeatable; default: all)')  # fmt: skip
    p.add_argument('--out', default='fuzz-findings', metavar='DIR',
                   help='where failing inputs are written (default: fuzz-findings)')  # fmt: skip
    p.add_argument('--seed', type=int, default=None, help='a seed, for a run repeated exactly')
    p.add_argument('--atheris', type=float, default=0.0, metavar='MIN',
                   help='also MIN minutes of coverage-guided atheris (shared by the targets)')
    p.add_argument('--memory-mib', type=int, default=3072, metavar='MIB',
                   help='address-space limit of the run (default: 3072; 0: none)')  # fmt: skip
    p.add_argument('--json', action='store_true', help='print the outcome as JSON')
    p.set_defaults(func=cmd_fuzz)


if __name__ == '__main__':  # python -m catenary_monitor_study.fuzz atheris TARGET [libFuzzer args]
    if len(sys.argv) > 2 and sys.argv[1] == 'atheris':
        _atheris_main(sys.argv[2], sys.argv[3:])
    else:
        print(__doc__)
