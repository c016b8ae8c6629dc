"""The MCAP record format (no I/O): magic, opcodes, record heads and the readers of a record's
fields, shared by the log reader, its scanner, finish, recovery and the summary reader.

Every reader takes a buffer (bytes, memoryview or mmap), the position of the field and the end
of its record, and raises :class:`BadRecord` when the field does not fit the record.
"""

from __future__ import annotations

import mmap
import struct
from typing import Union

__all__ = [
    'BadRecord',
    'MAGIC',
    'chunk_header',
    'find_chunk',
    'looks_like_header',
    'parse_channel',
    'parse_schema',
    'read_bytes',
    'read_string',
    'read_string_map',
    'statistics_counts',
]

#: What the field readers read: a record's bytes, a view of them or the mapped file.
Buffer = Union[bytes, memoryview, mmap.mmap]

MAGIC = b'\x89MCAP0\r\n'

OP_HEADER = 0x01
OP_FOOTER = 0x02
OP_SCHEMA = 0x03
OP_CHANNEL = 0x04
OP_MESSAGE = 0x05
OP_CHUNK = 0x06
OP_MESSAGE_INDEX = 0x07
OP_CHUNK_INDEX = 0x08
OP_ATTACHMENT = 0x09
OP_STATISTICS = 0x0B
OP_METADATA = 0x0C
OP_METADATA_INDEX = 0x0D
OP_DATA_END = 0x0F
KNOWN_OPS = frozenset(range(0x01, 0x10))

RECORD_HEAD = struct.Struct('<BQ')  # opcode, length
MESSAGE_HEAD = struct.Struct('<HIQQ')  # channel id, sequence, log time, publish time
CHUNK_HEAD = struct.Struct('<QQQII')  # start, end, uncompressed size, crc, len(compression)
MESSAGE_MIN = 9 + 22  # smallest Message record (empty payload), B


class BadRecord(Exception):
    """A record whose fields do not fit its length."""


def read_string(buf: Buffer, pos: int, end: int) -> tuple[str, int]:
    """Read a uint32-length-prefixed UTF-8 string; return it and the position after it."""
    if pos + 4 > end:
        raise BadRecord('string length runs past its record')
    (length,) = struct.unpack_from('<I', buf, pos)
    stop = pos + 4 + length
    if stop > end:
        raise BadRecord(f'string of {length} B runs past its record')
    return bytes(buf[pos + 4 : stop]).decode('utf-8', 'replace'), stop


def read_bytes(buf: Buffer, pos: int, end: int) -> bytes:
    """Read a uint32-length-prefixed byte array."""
    if pos + 4 > end:
        raise BadRecord('byte array length runs past its record')
    (n,) = struct.unpack_from('<I', buf, pos)
    if pos + 4 + n > end:
        raise BadRecord(f'byte array of {n} B runs past its record')
    return bytes(buf[pos + 4 : pos + 4 + n])


def read_string_map(
    buf: Buffer, pos: int, end: int, keep_first: bool = False
) -> dict[str, str]:
    """Read a uint32-byte-length-prefixed map<string, string>; a key given twice keeps its last
    value (``keep_first``: its first)."""
    if pos + 4 > end:
        raise BadRecord('map length runs past its record')
    (n,) = struct.unpack_from('<I', buf, pos)
    p, stop = pos + 4, pos + 4 + n
    if stop > end:
        raise BadRecord(f'map of {n} B runs past its record')
    out: dict[str, str] = {}
    while p < stop:
        key, p = read_string(buf, p, stop)
        value, p = read_string(buf, p, stop)
        if keep_first:
            out.setdefault(key, value)
        else:
            out[key] = value
    return out


def parse_schema(buf: bytes | memoryview, pos: int, end: int) -> tuple[int, str]:
    """(schema id, name) of a Schema record body."""
    if end - pos < 2 + 4 + 4 + 4:
        raise BadRecord(f'Schema record of {end - pos} B is too short')
    (schema_id,) = struct.unpack_from('<H', buf, pos)
    name, p = read_string(buf, pos + 2, end)
    read_string(buf, p, end)  # encoding
    return schema_id, name


def parse_channel(buf: bytes | memoryview, pos: int, end: int) -> tuple[int, int, str, str]:
    """(channel id, schema id, topic, message encoding) of a Channel record body."""
    if end - pos < 4 + 4 + 4 + 4:
        raise BadRecord(f'Channel record of {end - pos} B is too short')
    channel_id, schema_id = struct.unpack_from('<HH', buf, pos)
    topic, p = read_string(buf, pos + 4, end)
    encoding, _ = read_string(buf, p, end)
    return channel_id, schema_id, topic, encoding


def looks_like_header(data: bytes) -> bool:
    """True if a Header record (two strings filling its length) follows the 8 magic bytes."""
    if len(data) < len(MAGIC) + 9 + 8:
        return False
    op, length = RECORD_HEAD.unpack_from(data, len(MAGIC))
    body, end = len(MAGIC) + 9, len(MAGIC) + 9 + length
    if op != OP_HEADER or end > len(data):
        return False
    try:
        _, p = read_string(data, body, end)
        _, p = read_string(data, p, end)
    except BadRecord:
        return False
    return p == end


def statistics_counts(buf: bytes, pos: int, end: int) -> dict[int, int] | None:
    """Messages per channel id of a Statistics record body, None when its map does not fit."""
    # message_count u64, schema u16, channel u32, attachment u32, metadata u32, chunk u32,
    # start u64, end u64, then a uint32-prefixed map<uint16, uint64>.
    head = struct.calcsize('<QHIIIIQQ')
    if pos + head + 4 > end:
        return None
    (nbytes,) = struct.unpack_from('<I', buf, pos + head)
    p = pos + head + 4
    if p + nbytes > end or nbytes % 10:
        return None
    return {cid: count for cid, count in struct.iter_unpack('<HQ', buf[p : p + nbytes])}


def chunk_header(
    data: bytes, body: int, end: int, partial: bool = False
) -> tuple[int, int, str, int, int] | None:
    """Parse a Chunk body; return (uncompressed size, crc, compression, records start, end)."""
    if body + CHUNK_HEAD.size > len(data):
        return None
    _, _, usize, crc, comp_len = CHUNK_HEAD.unpack_from(data, body)
    p = body + CHUNK_HEAD.size
    if comp_len > 16 or p + comp_len + 8 > len(data):
        return None
    compression = bytes(data[p : p + comp_len]).decode('ascii', 'replace')
    p += comp_len
    (rec_len,) = struct.unpack_from('<Q', data, p)
    p += 8
    if not partial and p + rec_len != end:
        return None
    if compression not in ('', 'zstd', 'lz4'):
        return None if partial else (usize, crc, compression, p, p + rec_len)
    return usize, crc, compression, p, p + rec_len


def find_chunk(data: bytes, start: int) -> int:
    """Offset of the next byte sequence that parses as a complete, consistent Chunk record."""
    n = len(data)
    pos = data.find(b'\x06', start)
    while 0 <= pos and pos + 9 <= n:
        _, length = RECORD_HEAD.unpack_from(data, pos)
        end = pos + 9 + length
        if end <= n and length >= CHUNK_HEAD.size + 8:
            header = chunk_header(data, pos + 9, end)
            if header is not None and header[2] in ('', 'zstd', 'lz4'):
                return pos
        pos = data.find(b'\x06', pos + 1)
    return -1
