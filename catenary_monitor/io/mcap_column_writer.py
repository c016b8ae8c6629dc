"""A column-oriented MCAP writer: whole arrays of messages at once, records built with numpy.

The mcap library's ``Writer.add_message`` costs a few microseconds per message; replay writes a
million. Here messages of one batch share a payload size, so a chunk's Message records are one
numpy structured array (opcode, length, channel, sequence, log time, publish time, payload) and
its Message Index records are built the same way. Header, Schema, Channel, Chunk, Chunk Index,
Statistics, Metadata and the summary use ``mcap.records`` (one object per chunk, not per
message). Output: ROS 2 profile, zstd (or lz4, or no) chunk compression, chunk CRCs, message
indexes and a summary with chunk indexes and statistics -- what ``mcap.reader``, rosbag2 and
Foxglove expect.

Schema and Channel records are written top-level before the first chunk that uses them. The
Chunk Index records wait for the summary in a temporary file, not in memory (a long replay
writes tens of thousands of chunks; kept as objects, they scattered the heap and its peak grew
with the log).
"""

from __future__ import annotations

import shutil
import tempfile
import zlib
from collections import OrderedDict
from typing import IO, Any, Mapping, Optional, Sequence

import numpy as np
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.writer import LIBRARY_IDENTIFIER

__all__ = ['ColumnWriter']

MAGIC = b'\x89MCAP0\r\n'
_HEAD = 9 + 22  # opcode + length + channel, sequence, log time, publish time


def _record_dtype(payload: int) -> np.dtype:
    return np.dtype(
        [
            ('op', 'u1'),
            ('length', '<u8'),
            ('channel', '<u2'),
            ('sequence', '<u4'),
            ('log_time', '<u8'),
            ('publish_time', '<u8'),
            ('data', 'u1', (payload,)),
        ],
        align=False,
    )


_INDEX_ENTRY = np.dtype([('t', '<u8'), ('o', '<u8')])


class ColumnWriter:
    """Write MCAP files from numpy columns.

    Parameters
    ----------
    stream : binary stream opened for writing (not closed by :meth:`finish`).
    compression : ``'zstd'``, ``'lz4'`` or ``'none'``.
    chunk_bytes : uncompressed chunk size to aim for (B).
    level : zstd compression level.
    """

    def __init__(
        self,
        stream: IO[bytes],
        *,
        compression: str = 'zstd',
        chunk_bytes: int = 1 << 20,
        level: int = 1,
        profile: str = 'ros2',
        library: str = '',
    ) -> None:
        if compression not in ('zstd', 'lz4', 'none'):
            raise ValueError(f"compression must be 'zstd', 'lz4' or 'none', got {compression!r}")
        self.stream = stream
        self.compression = '' if compression == 'none' else compression
        if self.compression == 'zstd':
            import zstandard

            self._zstd = zstandard.ZstdCompressor(level=level)
        self.chunk_bytes = int(chunk_bytes)
        self._schemas: OrderedDict[int, Schema] = OrderedDict()
        self._channels: OrderedDict[int, Channel] = OrderedDict()
        self._written: set[tuple[int, int]] = set()
        self._chunk_indexes = tempfile.TemporaryFile()  # the Chunk Index records, serialized
        self._chunk_count = 0
        self._metadata_indexes: list[MetadataIndex] = []
        self._attachment_indexes: list[AttachmentIndex] = []
        self._counts: dict[int, int] = {}
        self._sequence: dict[int, int] = {}
        self._start: Optional[int] = None
        self._end = 0
        self.messages = 0
        stream.write(MAGIC)
        self._record(
            Header(
                profile,
                library or f'catenary_monitor.io.mcap_column_writer; {LIBRARY_IDENTIFIER}',
            )
        )

    # ------------------------------------------------------------------ set-up records
    def _record(self, record: Any) -> int:
        builder = RecordBuilder()
        record.write(builder)
        data = builder.end()
        offset = self.stream.tell()
        self.stream.write(data)
        return offset

    def register_schema(
        self, name: str, encoding: str, data: bytes, schema_id: Optional[int] = None
    ) -> int:
        """Add a Schema; returns its id (1, 2, ... unless ``schema_id`` is given)."""
        if schema_id is None:
            schema_id = len(self._schemas) + 1
        self._schemas[schema_id] = Schema(id=schema_id, name=name, encoding=encoding, data=data)
        return schema_id

    def register_channel(
        self,
        topic: str,
        message_encoding: str,
        schema_id: int,
        metadata: Optional[Mapping[str, str]] = None,
        channel_id: Optional[int] = None,
    ) -> int:
        """Add a Channel; returns its id (1, 2, ... unless ``channel_id`` is given, as a copy of
        a file keeps its ids: 65536 of them at most, where the ``mcap`` Writer stops at 65535)."""
        if channel_id is None:
            channel_id = len(self._channels) + 1
        self._channels[channel_id] = Channel(
            id=channel_id,
            topic=topic,
            message_encoding=message_encoding,
            schema_id=schema_id,
            metadata=dict(metadata or {}),
        )
        self._counts[channel_id] = 0
        self._sequence[channel_id] = 0
        return channel_id

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        """A Metadata record (and its index in the summary)."""
        record = Metadata(name=name, metadata={str(k): str(v) for k, v in data.items()})
        builder = RecordBuilder()
        record.write(builder)
        raw = builder.end()
        offset = self.stream.tell()
        self.stream.write(raw)
        self._metadata_indexes.append(MetadataIndex(offset=offset, length=len(raw), name=name))

    def add_attachment(
        self, name: str, media_type: str, data: bytes, log_time: int, create_time: int
    ) -> None:
        """An Attachment record (and its index in the summary)."""
        record = Attachment(
            log_time=log_time, create_time=create_time, name=name, media_type=media_type, data=data
        )
        builder = RecordBuilder()
        record.write(builder)
        raw = builder.end()
        offset = self.stream.tell()
        self.stream.write(raw)
        self._attachment_indexes.append(
            AttachmentIndex(
                offset=offset,
                length=len(raw),
                log_time=log_time,
                create_time=create_time,
                data_size=len(data),
                name=name,
                media_type=media_type,
            )
        )

    def _define(self, channel_ids: Sequence[int]) -> None:
        for cid in channel_ids:
            channel = self._channels[cid]
            if channel.schema_id and (0, channel.schema_id) not in self._written:
                self._record(self._schemas[channel.schema_id])
                self._written.add((0, channel.schema_id))
            if (1, cid) not in self._written:
                self._record(channel)
                self._written.add((1, cid))

    # ------------------------------------------------------------------ messages
    def write_columns(
        self,
        channel: np.ndarray,
        log_time: np.ndarray,
        payload: np.ndarray,
        publish_time: Optional[np.ndarray] = None,
    ) -> None:
        """Write ``n`` messages whose payloads have one size, in the order given.

        ``channel`` (n,) channel ids; ``log_time`` (n,) ns; ``payload`` (n, size) uint8;
        ``publish_time`` defaults to ``log_time``. Sequence numbers count per channel.
        """
        n = len(log_time)
        if n == 0:
            return
        channel = np.broadcast_to(np.asarray(channel, np.uint16), (n,))
        log_time = np.asarray(log_time, np.int64)
        publish = log_time if publish_time is None else np.asarray(publish_time, np.int64)
        size = payload.shape[1]
        self._define(np.unique(channel).tolist())
        seq = np.empty(n, np.int64)
        for cid in np.unique(channel).tolist():
            where = np.flatnonzero(channel == cid)
            seq[where] = self._sequence[cid] + np.arange(len(where))
            self._sequence[cid] += len(where)
            self._counts[cid] += len(where)
        per_chunk = max(1, self.chunk_bytes // (_HEAD + size))
        dtype = _record_dtype(size)
        for lo in range(0, n, per_chunk):
            hi = min(n, lo + per_chunk)
            rec = np.empty(hi - lo, dtype)
            rec['op'] = Opcode.MESSAGE
            rec['length'] = 22 + size
            rec['channel'] = channel[lo:hi]
            rec['sequence'] = seq[lo:hi] % (1 << 32)
            rec['log_time'] = log_time[lo:hi]
            rec['publish_time'] = publish[lo:hi]
            rec['data'] = payload[lo:hi]
            offsets = np.arange(hi - lo, dtype=np.int64) * (_HEAD + size)
            self._chunk(rec.tobytes(), channel[lo:hi], log_time[lo:hi], offsets)
        self.messages += n

    def write_records(
        self,
        data: bytes | memoryview,
        channel: np.ndarray,
        log_time: np.ndarray,
        offsets: np.ndarray,
    ) -> None:
        """One chunk of whole Message records as they are (their sequence numbers kept):
        ``data`` the records back to back, ``channel`` / ``log_time`` / ``offsets`` (in
        ``data``) of each; every channel registered."""
        n = len(offsets)
        if n == 0:
            return
        channel = np.asarray(channel, np.uint16)
        ids, counts = np.unique(channel, return_counts=True)
        self._define(ids.tolist())
        for cid, count in zip(ids.tolist(), counts.tolist()):
            self._counts[cid] += count
        self._chunk(data, channel, np.asarray(log_time, np.int64), np.asarray(offsets, np.int64))
        self.messages += n

    def write_messages(
        self, channel_id: int, log_times: Sequence[int], payloads: Sequence[bytes]
    ) -> None:
        """Write messages of one channel with payloads of any size (few messages)."""
        if not payloads:
            return
        self._define([channel_id])
        n = len(payloads)
        heads = np.zeros(n, _record_dtype(0))  # every message's record head at once
        heads['op'] = Opcode.MESSAGE
        heads['length'] = 22 + np.fromiter(map(len, payloads), np.int64, n)
        heads['channel'] = channel_id
        heads['sequence'] = (self._sequence[channel_id] + np.arange(n)) % (1 << 32)
        heads['log_time'] = heads['publish_time'] = np.asarray(log_times, np.int64)
        self._sequence[channel_id] += n
        raw = heads.tobytes()
        parts, offsets, pos = [], [], 0
        for i, data in enumerate(payloads):
            parts += [raw[i * _HEAD : (i + 1) * _HEAD], data]
            offsets.append(pos)
            pos += _HEAD + len(data)
            if pos >= self.chunk_bytes:
                self._flush_variable(parts, offsets, channel_id, log_times)
                log_times = log_times[len(offsets) :]
                parts, offsets, pos = [], [], 0
        if parts:
            self._flush_variable(parts, offsets, channel_id, log_times)
        self._counts[channel_id] += len(payloads)
        self.messages += len(payloads)

    def _flush_variable(
        self, parts: list[bytes], offsets: list[int], channel_id: int, log_times: Sequence[int]
    ) -> None:
        k = len(offsets)
        self._chunk(
            b''.join(parts),
            np.full(k, channel_id, np.uint16),
            np.asarray(log_times[:k], np.int64),
            np.asarray(offsets, np.int64),
        )

    def _chunk(
        self,
        data: bytes | memoryview,
        channel: np.ndarray,
        log_time: np.ndarray,
        offsets: np.ndarray,
    ) -> None:
        if self.compression == 'zstd':
            compressed = self._zstd.compress(data)
        elif self.compression == 'lz4':
            import lz4.frame

            compressed = lz4.frame.compress(data)
        else:
            compressed = bytes(data)
        start, end = int(log_time.min()), int(log_time.max())
        self._start = start if self._start is None else min(self._start, start)
        self._end = max(self._end, end)
        chunk = Chunk(
            compression=self.compression,
            data=compressed,
            message_start_time=start,
            message_end_time=end,
            uncompressed_crc=zlib.crc32(data),
            uncompressed_size=len(data),
        )
        chunk_start = self.stream.tell()
        self._record(chunk)
        chunk_length = self.stream.tell() - chunk_start
        index_start = self.stream.tell()
        offsets_by_channel: dict[int, int] = {}
        order = np.argsort(channel, kind='stable')
        ch_sorted = channel[order]
        bounds = np.flatnonzero(np.diff(ch_sorted.astype(np.int64))) + 1
        pieces = []
        pos = index_start
        for sel in np.split(order, bounds):
            cid = int(channel[sel[0]])
            entries = np.empty(len(sel), _INDEX_ENTRY)
            entries['t'] = log_time[sel]
            entries['o'] = offsets[sel]
            body = entries.tobytes()
            head = np.zeros(1, [('op', 'u1'), ('len', '<u8'), ('ch', '<u2'), ('n', '<u4')])
            head['op'], head['len'], head['ch'], head['n'] = (
                Opcode.MESSAGE_INDEX,
                6 + len(body),
                cid,
                len(body),
            )
            offsets_by_channel[cid] = pos
            raw = head.tobytes() + body
            pieces.append(raw)
            pos += len(raw)
        self.stream.write(b''.join(pieces))
        index = RecordBuilder()
        ChunkIndex(
            message_start_time=start,
            message_end_time=end,
            chunk_start_offset=chunk_start,
            chunk_length=chunk_length,
            message_index_offsets=offsets_by_channel,
            message_index_length=pos - index_start,
            compression=self.compression,
            compressed_size=len(compressed),
            uncompressed_size=len(data),
        ).write(index)
        self._chunk_indexes.write(index.end())
        self._chunk_count += 1

    # ------------------------------------------------------------------ summary
    def finish(self) -> None:
        """Data end, summary (schemas, channels, statistics, chunk and metadata indexes,
        summary offsets), footer and closing magic."""
        self._define(list(self._channels))
        self._record(DataEnd(data_section_crc=0))
        summary_start = self.stream.tell()
        pos = summary_start
        offsets: list[SummaryOffset] = []

        def group(opcode: int, data: bytes) -> None:
            nonlocal pos
            if not data:
                return
            offsets.append(
                SummaryOffset(group_opcode=opcode, group_start=pos, group_length=len(data))
            )
            self.stream.write(data)
            pos += len(data)

        def encode(records: Sequence[Any]) -> bytes:
            builder = RecordBuilder()
            for r in records:
                r.write(builder)
            return builder.end()

        group(Opcode.SCHEMA, encode(list(self._schemas.values())))
        group(Opcode.CHANNEL, encode(list(self._channels.values())))
        group(
            Opcode.STATISTICS,
            encode(
                [
                    Statistics(
                        message_count=self.messages,
                        schema_count=len(self._schemas),
                        channel_count=len(self._channels),
                        attachment_count=len(self._attachment_indexes),
                        metadata_count=len(self._metadata_indexes),
                        chunk_count=self._chunk_count,
                        message_start_time=self._start or 0,
                        message_end_time=self._end,
                        channel_message_counts={k: v for k, v in self._counts.items() if v},
                    )
                ]
            ),
        )
        length = self._chunk_indexes.tell()
        if length:
            chunk_group = dict(group_opcode=Opcode.CHUNK_INDEX, group_start=pos)
            offsets.append(SummaryOffset(**chunk_group, group_length=length))
            self._chunk_indexes.seek(0)
            shutil.copyfileobj(self._chunk_indexes, self.stream, 1 << 20)
            pos += length
        self._chunk_indexes.close()
        group(Opcode.ATTACHMENT_INDEX, encode(self._attachment_indexes))
        group(Opcode.METADATA_INDEX, encode(self._metadata_indexes))
        offset_start = pos
        self.stream.write(encode(offsets))
        footer = RecordBuilder()
        Footer(
            summary_start=summary_start, summary_offset_start=offset_start, summary_crc=0
        ).write(footer)
        self.stream.write(footer.end())
        self.stream.write(MAGIC)
