"""Hand-built MCAP files for the damage tests: records packed with struct, no writer library.

``hostile_file`` builds the crafted file of issue 10: a 69 KB zstd chunk that declares (or
holds) 2 GiB of zeros, then a good chunk of Float64 messages.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

MAGIC = b'\x89MCAP0\r\n'
TOPIC = '/chain/tension'
FLOAT64 = 'std_msgs/msg/Float64'
FLOAT64_MSG = b'float64 data\n'
GIB2 = 2 << 30


def record(op: int, body: bytes) -> bytes:
    return struct.pack('<BQ', op, len(body)) + body


def string(text: str) -> bytes:
    raw = text.encode()
    return struct.pack('<I', len(raw)) + raw


def header() -> bytes:
    return record(0x01, string('ros2') + string('hostile test'))


def schema(schema_id: int = 1) -> bytes:
    body = struct.pack('<H', schema_id) + string(FLOAT64) + string('ros2msg')
    return record(0x03, body + struct.pack('<I', len(FLOAT64_MSG)) + FLOAT64_MSG)


def channel(channel_id: int = 1, schema_id: int = 1, topic: str = TOPIC) -> bytes:
    body = struct.pack('<HH', channel_id, schema_id) + string(topic) + string('cdr')
    return record(0x04, body + struct.pack('<I', 0))


def message(value: float, t: int, channel_id: int = 1, seq: int = 0) -> bytes:
    cdr = b'\x00\x01\x00\x00' + struct.pack('<d', value)
    return record(0x05, struct.pack('<HIQQ', channel_id, seq, t, t) + cdr)


def chunk(
    records: bytes,
    compression: str,
    compressed: bytes,
    usize: int,
    t0: int,
    t1: int,
    crc: bool = True,
) -> bytes:
    head = struct.pack('<QQQI', t0, t1, usize, zlib.crc32(records) if crc else 0)
    body = head + string(compression) + struct.pack('<Q', len(compressed)) + compressed
    return record(0x06, body)


def good_chunk(values: list[float], t0: int) -> bytes:
    import zstandard

    records = b''.join(message(v, t0 + i, seq=i) for i, v in enumerate(values))
    data = zstandard.ZstdCompressor().compress(records)
    return chunk(records, 'zstd', data, len(records), t0, t0 + len(values) - 1)


def zeros_zstd(size: int, content_size: bool) -> bytes:
    """zstd of ``size`` zero bytes, streamed (never ``size`` bytes in memory)."""
    import zstandard

    cctx = zstandard.ZstdCompressor(write_content_size=content_size)
    obj = cctx.compressobj(size=size if content_size else -1)
    block = bytes(1 << 20)
    out = [obj.compress(block) for _ in range(size >> 20)]
    out.append(obj.flush())
    return b''.join(out)


def zeros_lz4(size: int) -> bytes:
    import lz4.frame

    block = bytes(1 << 20)
    comp = lz4.frame.LZ4FrameCompressor()
    out = [comp.begin()]
    out.extend(comp.compress(block) for _ in range(size >> 20))
    out.append(comp.flush())
    return b''.join(out)


def hostile_file(path: Path, kind: str, values: list[float], finished: bool = False) -> Path:
    """A file whose first chunk is hostile (``kind``), followed by a good chunk of ``values``.

    kinds: ``declares_2gib`` (header and frame say 2 GiB), ``lies_small`` (header says 64 KiB,
    the zstd frame holds 2 GiB and says so), ``lies_small_nosize`` (the same without a content
    size in the frame), ``lz4_lies`` (header 64 KiB, lz4 frame of 256 MiB), ``cut`` (the good
    chunk, then the 2 GiB-declaring chunk cut by the end of the file).
    """
    small = 64 << 10
    if kind == 'declares_2gib':
        bad = chunk(b'', 'zstd', zeros_zstd(GIB2, True), GIB2, 0, 0, crc=False)
    elif kind == 'lies_small':
        bad = chunk(b'', 'zstd', zeros_zstd(GIB2, True), small, 0, 0, crc=False)
    elif kind == 'lies_small_nosize':
        bad = chunk(b'', 'zstd', zeros_zstd(GIB2, False), small, 0, 0, crc=False)
    elif kind == 'lz4_lies':
        bad = chunk(b'', 'lz4', zeros_lz4(256 << 20), small, 0, 0, crc=False)
    elif kind == 'cut':
        bad = chunk(b'', 'zstd', zeros_zstd(GIB2, True), GIB2, 0, 0, crc=False)
    else:
        raise ValueError(kind)
    good = good_chunk(values, 1_000)
    parts = [MAGIC, header(), schema(), channel()]
    if kind == 'cut':
        parts += [good, bad[: len(bad) // 2]]
    else:
        parts += [bad, good]
    if finished:
        parts += [
            record(0x0F, struct.pack('<I', 0)),
            record(0x02, struct.pack('<QQI', 0, 0, 0)),
            MAGIC,
        ]
    path.write_bytes(b''.join(parts))
    return path
