"""Finish an unfinished MCAP file where it lies: its summary appended, its chunks untouched.

What a full disk needs: :func:`finish_in_place` costs only the room of a summary (about 100 B
per chunk), where recovery (:mod:`catenary_monitor.io.mcap_recover`) writes a whole copy. The
file is cut after its last whole record (or at ``upto``, the end of the logger's last flush,
which is always a chunk and its Message Index records), then Data End, a summary (Schema and
Channel records, Statistics, Chunk Index and Metadata Index records, Summary Offsets) and the
Footer are appended and fsynced. The chunks are indexed from their own headers and from the
Message Index records after them, never decompressed, when the caller knows the file's schemas
and channels (the logger does: it registered them); otherwise the definitions, and the message
counts of chunks without Message Index records, come from the log reader's walk
(:mod:`catenary_monitor.io.mcap_read`: its bounds, its damage rules). A damaged region is left
in place and not indexed. If the summary cannot be written (the disk still full), the file is
cut back to its data and the caller tries again later.
"""

from __future__ import annotations

import mmap
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Optional, Sequence

import numpy as np
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Channel,
    ChunkIndex,
    DataEnd,
    Footer,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)

from catenary_monitor.io.mcap_records import (
    MAGIC,
    BadRecord,
    chunk_header,
    find_chunk,
    read_bytes,
    read_string,
    read_string_map,
)
from catenary_monitor.io.mcap_scan import ReadReport, Scanner

__all__ = ['Definitions', 'finish_in_place', 'whole_records_end']

_HEAD = struct.Struct('<BQ')
_OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE, _OP_CHUNK = 0x03, 0x04, 0x05, 0x06
_OP_MESSAGE_INDEX, _OP_METADATA, _OP_DATA_END, _OP_FOOTER = 0x07, 0x0C, 0x0F, 0x02
_KNOWN = frozenset(range(0x01, 0x10))


@dataclass
class Definitions:
    """A file's schemas ``{id: (name, encoding, data)}`` and channels ``{id: (topic, message
    encoding, schema id, metadata)}``."""

    schemas: dict[int, tuple[str, str, bytes]] = field(default_factory=dict)
    channels: dict[int, tuple[str, str, int, dict[str, str]]] = field(default_factory=dict)


@dataclass
class _Index:
    """What the heads of a file's top-level records say."""

    chunks: list[ChunkIndex] = field(default_factory=list)
    metadata: list[MetadataIndex] = field(default_factory=list)
    counts: dict[int, int] = field(default_factory=dict)
    start: Optional[int] = None
    end: int = 0
    unindexed: bool = False  # a chunk without Message Index records, or top-level messages
    damaged: list[str] = field(default_factory=list)


def whole_records_end(data: bytes | mmap.mmap) -> int:
    """Where the file's last whole top-level record ends (a damaged region skipped to the next
    chunk, as the reader does; Data End, a Footer or the end of the file stop the walk)."""
    pos, end, n = len(MAGIC), len(MAGIC), len(data)
    while pos + 9 <= n:
        op, length = _HEAD.unpack_from(data, pos)
        if op in (_OP_DATA_END, _OP_FOOTER):
            break
        if (op not in _KNOWN and op < 0x80) or pos + 9 + length > n:
            found = find_chunk(data, pos + 1)  # type: ignore[arg-type]
            if found < 0:
                break
            pos = found
            continue
        pos += 9 + length
        end = pos
    return end if n >= len(MAGIC) else 0


def finish_in_place(
    path: str | os.PathLike[str], upto: Optional[int] = None, known: Optional[Definitions] = None
) -> tuple[int, list[str]]:
    """Finish the file at ``path`` where it lies (see the module docstring): cut at ``upto``
    (else after its last whole record), summary and footer appended. ``known``: its schemas
    and channels, when the caller knows them. Returns (messages indexed, damaged parts left in
    place). Raises OSError when it cannot be written (the file is then cut back to its data)."""
    path = Path(path)
    with open(path, 'r+b') as f:
        size = os.fstat(f.fileno()).st_size
        if size < len(MAGIC):
            raise OSError(f'{path}: {size} B, not even the MCAP magic')
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
            end = whole_records_end(data) if upto is None else min(upto, size)
            index, top = _index(data, end)
        f.truncate(end)
        definitions = known if known is not None else Definitions()
        definitions.schemas = {**top.schemas, **definitions.schemas}
        definitions.channels = {**top.channels, **definitions.channels}
        if known is None or index.unindexed:
            _walk_definitions(path, definitions, index)
        try:
            _append_summary(f, end, index, definitions)
        except OSError:
            f.truncate(end)
            raise
    return sum(index.counts.values()), index.damaged


def _index(data: mmap.mmap, end: int) -> tuple[_Index, Definitions]:
    """Chunk and Metadata indexes, message counts and top-level definitions of ``data[:end]``,
    from record heads, chunk headers and Message Index records."""
    index, top = _Index(), Definitions()
    pos = len(MAGIC)
    while pos + 9 <= end:
        op, length = _HEAD.unpack_from(data, pos)
        stop = pos + 9 + length
        if (op not in _KNOWN and op < 0x80) or stop > end:
            found = find_chunk(data, pos + 1)  # type: ignore[arg-type]
            index.damaged.append(f'@{pos}: not a record; left in place, not indexed')
            if not 0 <= found < end:
                break
            pos = found
            continue
        if op == _OP_CHUNK:
            pos = _chunk(data, pos, stop, end, index)
            continue
        if op == _OP_METADATA and length >= 4:
            (n,) = struct.unpack_from('<I', data, pos + 9)
            if 4 + n <= length:
                name = data[pos + 13 : pos + 13 + n].decode('utf-8', 'replace')
                index.metadata.append(MetadataIndex(offset=pos, length=9 + length, name=name))
        elif op in (_OP_SCHEMA, _OP_CHANNEL):
            _definition(op, data[pos + 9 : stop], top)
        elif op == _OP_MESSAGE:
            index.unindexed = True
        pos = stop
    return index, top


def _chunk(data: mmap.mmap, pos: int, stop: int, end: int, index: _Index) -> int:
    """Index the Chunk record at ``pos`` and the Message Index records after it; return where
    the walk goes on."""
    header = chunk_header(data, pos + 9, stop)  # type: ignore[arg-type]
    if header is None:
        index.damaged.append(f'@{pos}: chunk header inconsistent; left in place, not indexed')
        return stop
    usize, _, compression, rec_start, rec_end = header
    t0, t1 = struct.unpack_from('<QQ', data, pos + 9)
    offsets: dict[int, int] = {}
    at = stop
    while at + 15 <= end:
        op, length = _HEAD.unpack_from(data, at)
        if op != _OP_MESSAGE_INDEX or at + 9 + length > end or length < 6:
            break
        cid, nbytes = struct.unpack_from('<HI', data, at + 9)
        if nbytes % 16 or 6 + nbytes > length:
            break
        offsets[cid] = at
        index.counts[cid] = index.counts.get(cid, 0) + nbytes // 16
        at += 9 + length
    if not offsets:
        index.unindexed = True
    elif any(index.counts.get(c) for c in offsets):
        index.start = t0 if index.start is None else min(index.start, t0)
        index.end = max(index.end, t1)
    index.chunks.append(
        ChunkIndex(
            message_start_time=t0,
            message_end_time=t1,
            chunk_start_offset=pos,
            chunk_length=stop - pos,
            message_index_offsets=offsets,
            message_index_length=at - stop,
            compression=compression,
            compressed_size=rec_end - rec_start,
            uncompressed_size=usize,
        )
    )
    return at


def _definition(op: int, body: bytes, into: Definitions) -> None:
    """Keep a Schema or Channel record body's definition (the first of each id)."""
    try:
        (key,) = struct.unpack_from('<H', body, 0)
        if op == _OP_SCHEMA and key and key not in into.schemas:
            name, p = read_string(body, 2, len(body))
            encoding, p = read_string(body, p, len(body))
            into.schemas[key] = (name, encoding, read_bytes(body, p, len(body)))
        elif op == _OP_CHANNEL and key not in into.channels:
            (sid,) = struct.unpack_from('<H', body, 2)
            topic, p = read_string(body, 4, len(body))
            encoding, p = read_string(body, p, len(body))
            into.channels[key] = (topic, encoding, sid, read_string_map(body, p, len(body)))
    except (BadRecord, struct.error):
        pass


def _walk_definitions(path: Path, into: Definitions, index: _Index) -> None:
    """The definitions inside the chunks (and, where the file has no Message Index records or
    has unchunked messages, the message counts), from the reader's walk of the (cut) file."""
    scanner = Scanner(path, lambda channel: True, ReadReport())
    scanner.on_definition = lambda op, buf, a, b: _definition(op, bytes(buf[a:b]), into)
    counts: dict[int, int] = {}
    times: list[tuple[int, int]] = []
    try:
        for block in scanner.blocks():
            if not index.unindexed:
                continue
            ids, n = np.unique(block.channels, return_counts=True)
            for cid, k in zip(ids.tolist(), n.tolist()):
                counts[cid] = counts.get(cid, 0) + k
            arr = np.frombuffer(block.buf, np.uint8)
            stamps = arr[block.offsets[:, None] + 15 + np.arange(8)].copy().view('<u8')
            times.append((int(stamps.min()), int(stamps.max())))
    except Exception as exc:  # noqa: BLE001 - the reader's own failure: counts as far as read
        index.damaged.append(f'the reader stopped: {exc}')
    if index.unindexed:
        index.counts = counts
        if times:
            index.start = min(t for t, _ in times)
            index.end = max(t for _, t in times)


def _append_summary(f: IO[bytes], at: int, index: _Index, defs: Definitions) -> None:
    """Data End, the summary section, Summary Offsets, Footer and magic at ``at``; fsynced."""
    channels = [
        Channel(
            id=cid,
            topic=topic,
            message_encoding=encoding,
            schema_id=sid if sid in defs.schemas else 0,
            metadata=metadata,
        )
        for cid, (topic, encoding, sid, metadata) in sorted(defs.channels.items())
    ]
    schemas = [
        Schema(id=sid, name=name, encoding=encoding, data=data)
        for sid, (name, encoding, data) in sorted(defs.schemas.items())
    ]
    stats = Statistics(
        message_count=sum(index.counts.values()),
        schema_count=len(schemas),
        channel_count=len(channels),
        attachment_count=0,
        metadata_count=len(index.metadata),
        chunk_count=len(index.chunks),
        message_start_time=index.start or 0,
        message_end_time=index.end,
        channel_message_counts={c: n for c, n in index.counts.items() if n},
    )
    out = bytearray(_encode([DataEnd(data_section_crc=0)]))
    summary_start = at + len(out)
    offsets: list[SummaryOffset] = []
    for opcode, records in (
        (Opcode.SCHEMA, schemas),
        (Opcode.CHANNEL, channels),
        (Opcode.STATISTICS, [stats]),
        (Opcode.CHUNK_INDEX, index.chunks),
        (Opcode.METADATA_INDEX, index.metadata),
    ):
        if records:
            raw = _encode(records)
            start = at + len(out)
            offsets.append(
                SummaryOffset(group_opcode=opcode, group_start=start, group_length=len(raw))
            )
            out += raw
    offset_start = at + len(out)
    out += _encode(offsets)
    out += _encode(
        [Footer(summary_start=summary_start, summary_offset_start=offset_start, summary_crc=0)]
    )
    out += MAGIC
    f.seek(at)
    f.write(out)
    f.flush()
    os.fsync(f.fileno())


def _encode(records: Sequence[Any]) -> bytes:
    builder = RecordBuilder()
    for record in records:
        record.write(builder)
    return builder.end()
