"""Hand-built MCAP files for the damage tests: records packed with struct, no writer library.

``hostile_file`` builds the crafted file of issue 10: a 69 KB zstd chunk that declares (or
holds) 2 GiB of zeros, then a good chunk of Float64 messages. The files every command that
reads logs must survive in bounded time and memory: ``declares_2gib_file`` (66 KB),
``empty_records_file`` (three zstd chunks of 255 MiB of empty records, under 1 MB; or lz4,
3.3 MB) and ``many_channels_file`` (100 000 Channel records).
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


# ---------------------------------------------------------------- bounded work in every command
#: Uncompressed size of each chunk of :func:`empty_records_file`: just inside MAX_CHUNK_BYTES.
CHUNK_255 = 255 << 20
_PIECE = 8 << 20  # B of records handed to the compressor at a time


def _empty_records_piece(kind: str, channel_id: int) -> bytes:
    """About 8 MiB of "empty" records: Message records with no payload (or only a CDR header),
    or 9-byte private records of length 0 (opcode 0x80, which readers skip)."""
    if kind == 'messages':
        one = record(0x05, struct.pack('<HIQQ', channel_id, 0, 1_000, 1_000))
    elif kind == 'cdr_headers':  # the smallest payload that may be CDR: its 4-byte header
        one = record(0x05, struct.pack('<HIQQ', channel_id, 0, 1_000, 1_000) + b'\0\1\0\0')
    elif kind == 'private':
        one = record(0x80, b'')
    else:
        raise ValueError(kind)
    return one * (_PIECE // len(one))


def _filler(size: int) -> bytes:
    """A private record of ``size`` incompressible bytes (keeps a chunk under 1000x)."""
    import random

    return record(0x81, random.Random(size).randbytes(size))


def empty_records_chunk(
    compression: str, kind: str = 'messages', channel_id: int = 1, usize: int = CHUNK_255
) -> bytes:
    """A Chunk record of about ``usize`` B of empty records, compressed (streamed: never
    ``usize`` B in memory) so that its ratio stays under the reader's 1000x (zstd needs an
    incompressible filler for that), without Message Index records."""
    import lz4.frame
    import zstandard

    filler = _filler(usize // 880) if compression == 'zstd' else b''
    piece = _empty_records_piece(kind, channel_id)
    n_pieces = (usize - len(filler)) // len(piece)
    crc = zlib.crc32(filler)
    out: list[bytes] = []
    if compression == 'zstd':
        size = len(filler) + n_pieces * len(piece)
        obj = zstandard.ZstdCompressor().compressobj(size=size)
        out.append(obj.compress(filler))
        for _ in range(n_pieces):
            out.append(obj.compress(piece))
            crc = zlib.crc32(piece, crc)
        out.append(obj.flush())
    elif compression == 'lz4':
        comp = lz4.frame.LZ4FrameCompressor()
        out.append(comp.begin())
        for _ in range(n_pieces):
            out.append(comp.compress(piece))
            crc = zlib.crc32(piece, crc)
        out.append(comp.flush())
    else:
        raise ValueError(compression)
    size = len(filler) + n_pieces * len(piece)
    data = b''.join(out)
    head = struct.pack('<QQQI', 1_000, 1_000, size, crc)
    body = head + string(compression) + struct.pack('<Q', len(data)) + data
    return record(0x06, body)


def good_topics_chunk(topics: list[str], t0: int, n: int = 4) -> bytes:
    """A zstd chunk of ``n`` Float64 messages per channel (ids 1.. in ``topics`` order)."""
    import zstandard

    records = b''.join(
        message(10.0 + k, t0 + 10 * k + c, channel_id=c + 1, seq=k)
        for k in range(n)
        for c in range(len(topics))
    )
    data = zstandard.ZstdCompressor().compress(records)
    return chunk(records, 'zstd', data, len(records), t0, t0 + 10 * n)


def metadata(name: str, values: dict[str, str]) -> bytes:
    """A Metadata record (the node writes ``catenary_monitor`` with its parameters)."""
    body = b''.join(string(k) + string(v) for k, v in values.items())
    return record(0x0C, string(name) + struct.pack('<I', len(body)) + body)


def empty_records_file(
    path: Path,
    compression: str,
    topics: tuple[str, ...] = (TOPIC,),
    kind: str = 'messages',
    chunks: int = 3,
    usize: int = CHUNK_255,
    head: bytes = b'',
) -> Path:
    """``chunks`` chunks of ``usize`` B of empty records (on the first topic's channel) between
    good Float64 chunks on ``topics``; unfinished (no summary). ``head``: records put after the
    Header (a Metadata record)."""
    parts = [MAGIC, header(), head, schema()]
    parts += [channel(i + 1, topic=t) for i, t in enumerate(topics)]
    parts.append(good_topics_chunk(list(topics), 1_000))
    bad = empty_records_chunk(compression, kind, 1, usize)
    parts += [bad] * chunks
    parts.append(good_topics_chunk(list(topics), 2_000))
    path.write_bytes(b''.join(parts))
    return path


def declares_2gib_file(
    path: Path, topics: tuple[str, ...] = (TOPIC,), head: bytes = b''
) -> Path:
    """The 66 KB file: one zstd chunk declaring (and holding) 2 GiB of zeros, between good
    chunks on ``topics``; unfinished."""
    bad = chunk(b'', 'zstd', zeros_zstd(GIB2, True), GIB2, 0, 0, crc=False)
    parts = [MAGIC, header(), head, schema()]
    parts += [channel(i + 1, topic=t) for i, t in enumerate(topics)]
    parts += [good_topics_chunk(list(topics), 1_000), bad, good_topics_chunk(list(topics), 2_000)]
    path.write_bytes(b''.join(parts))
    return path


def many_channels_file(
    path: Path,
    topics: tuple[str, ...] = (TOPIC,),
    n: int = 100_000,
    finished: bool = False,
    head: bytes = b'',
) -> Path:
    """A file of ``n`` Channel records (ids wrap around the 16-bit id space, so every id is
    defined, some twice) after the real ``topics`` (ids 1..), then good chunks."""
    parts = [MAGIC, header(), head, schema()]
    parts += [channel(i + 1, topic=t) for i, t in enumerate(topics)]
    first = len(topics) + 1
    parts += [channel((first + i) & 0xFFFF, topic=f'/spam/{i}') for i in range(n)]
    parts += [good_topics_chunk(list(topics), 1_000), good_topics_chunk(list(topics), 2_000)]
    if finished:
        parts += [
            record(0x0F, struct.pack('<I', 0)),
            record(0x02, struct.pack('<QQI', 0, 0, 0)),
            MAGIC,
        ]
    path.write_bytes(b''.join(parts))
    return path
