"""The log reader's scanner: one MCAP file walked record by record, damage tolerated (no rclpy).

:class:`Scanner` walks a memory-mapped file and yields the Message records of the channels it
accepts as :class:`Block` s (record offsets into a decompressed batch of chunks), reporting each
damaged part as a :class:`Skip` in a :class:`ReadReport`. Chunks are bounded before they are
decompressed (:func:`chunk_size_problem`), gathered into batches of up to 8 MiB, located through
their Message Index records (checked against the records) and walked where the index does not
cover them; a chunk too large to hold is decoded and walked in pieces. :func:`block_columns`
turns a block of Float64 records into columns. The per-record loops run in C (``_scan.c`` next
to this file) where built, else in numpy passes with the same results.

Used by the readers (:mod:`catenary_monitor.io.mcap_read`), finish and recovery
(:mod:`catenary_monitor.io.mcap_finish`, :mod:`catenary_monitor.io.mcap_recover`) and the
summary reader; the record format itself is :mod:`catenary_monitor.io.mcap_records`.
"""

from __future__ import annotations

import mmap
import os
import struct
import sys
import threading
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Generator, Iterable, Iterator, NamedTuple, cast

import numpy as np
from numpy.lib.stride_tricks import as_strided, sliding_window_view

from catenary_monitor.io.mcap_records import (
    KNOWN_OPS,
    MAGIC,
    MESSAGE_MIN,
    OP_ATTACHMENT,
    OP_CHANNEL,
    OP_CHUNK,
    OP_CHUNK_INDEX,
    OP_DATA_END,
    OP_FOOTER,
    OP_HEADER,
    OP_MESSAGE,
    OP_MESSAGE_INDEX,
    OP_METADATA,
    OP_SCHEMA,
    OP_STATISTICS,
    RECORD_HEAD,
    BadRecord,
    chunk_header,
    find_chunk,
    looks_like_header,
    parse_channel,
    parse_schema,
    read_string,
    statistics_counts,
)

if TYPE_CHECKING:
    import zstandard

try:  # the per-record loops in C, next to this file (optional: else the numpy passes)
    from catenary_monitor.io import _scan  # type: ignore[attr-defined]
except ImportError:  # not built
    _scan = None
if sys.byteorder != 'little':  # the C loops read MCAP's little-endian fields natively
    _scan = None

__all__ = [
    'Block',
    'Channel',
    'FileReport',
    'McapReadError',
    'ReadReport',
    'Scanner',
    'Skip',
    'block_columns',
    'chunk_size_problem',
    'decompressed_pieces',
    'gather',
]

_BATCH_BYTES = 8 << 20  # decompressed chunk bytes handled per numpy pass
_BATCH_PIECES = 4096  # chunks handled per numpy pass
_FLOAT64_RECORD = 9 + 22 + 12  # Message record of one CDR Float64, B
# One Float64 Message record seen as a struct (offsets within the record).
_FLOAT64_ROW = np.dtype(
    {
        'names': ['op', 'length', 'channel', 'log_time', 'encaps', 'value_le', 'value_be'],
        'formats': ['u1', '<u8', '<u2', '<u8', '>u2', '<f8', '>f8'],
        'offsets': [0, 1, 9, 15, 31, 35, 35],
        'itemsize': _FLOAT64_RECORD,
    }
)
_CDR_BE = 0x0000
_CDR_LE = 0x0001

#: Float64 topic -> (log_time_ns int64, value float64).
Columns = dict[str, tuple[np.ndarray, np.ndarray]]


# ---------------------------------------------------------------------------- reports
class McapReadError(Exception):
    """Base class of the errors the log reader raises (this module and
    :mod:`catenary_monitor.io.mcap_read`)."""


@dataclass(frozen=True)
class Skip:
    """One part of a file that could not be used.

    Attributes
    ----------
    path : str
        File.
    offset : int
        Byte offset in the file where the damaged part starts.
    kind : str
        ``'truncated'`` (file ends inside a record), ``'corrupt_chunk'``, ``'corrupt_region'``,
        ``'unknown_channel'`` (messages whose Channel record was lost), ``'bad_payload'``
        (a message too short or with an unknown CDR encapsulation) or ``'not_mcap'``.
    reason : str
        Human sentence.
    messages_lost : int or None
        Messages on the requested topics lost here, when knowable (index records survived).
    """

    path: str
    offset: int
    kind: str
    reason: str
    messages_lost: int | None = None


@dataclass
class FileReport:
    """What was read from one file.

    Attributes
    ----------
    path : str
    size_bytes : int
    finished : bool
        The file ends with a valid Footer and magic (the writer called ``finish()``).
    profile : str
        Header profile (``'ros2'`` for rosbag2 and the node's logger).
    chunks : int
        Chunks read (including partly recovered ones).
    messages : int
        Messages read on the requested topics.
    messages_expected : int or None
        Messages on the requested topics according to the Statistics record, if present.
    """

    path: str
    size_bytes: int
    finished: bool = False
    profile: str = ''
    chunks: int = 0
    messages: int = 0
    messages_expected: int | None = None


@dataclass
class ReadReport:
    """Outcome of a read: per-file facts, skipped parts and per-topic counts."""

    files: list[FileReport] = field(default_factory=list)
    skips: list[Skip] = field(default_factory=list)
    messages: dict[str, int] = field(default_factory=dict)
    missing_topics: list[str] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        """True when nothing was skipped and every file was finished by its writer."""
        return not self.skips and all(f.finished for f in self.files)

    @property
    def messages_lost(self) -> int:
        """Requested-topic messages known to be lost (a lower bound, see ``loss_known``)."""
        return sum(s.messages_lost for s in self.skips if s.messages_lost is not None)

    @property
    def loss_known(self) -> bool:
        """True if every skipped part has a known loss (a cut tail never has)."""
        return all(s.messages_lost is not None for s in self.skips)

    def summary(self) -> str:
        """Multi-line human summary."""
        lines = [
            f'{len(self.files)} file(s), '
            + ', '.join(f'{t}: {n}' for t, n in self.messages.items())
        ]
        for f in self.files:
            if not f.finished:
                lines.append(f'{f.path}: not finished by its writer (no summary)')
        for s in self.skips:
            lost = '' if s.messages_lost is None else f' ({s.messages_lost} messages lost)'
            lines.append(f'{s.path} @{s.offset}: {s.kind}: {s.reason}{lost}')
        if self.missing_topics:
            lines.append(f'topics without messages: {self.missing_topics}')
        return '\n'.join(lines)


# ---------------------------------------------------------------------------- scanner
class Channel(NamedTuple):
    id: int
    topic: str
    encoding: str
    schema_id: int
    schema_name: str


@dataclass
class Piece:
    """A decompressed chunk waiting in a batch."""

    data: bytes | memoryview
    file_offset: int  # offset of the Chunk record in the file
    indexes: list[tuple[int, int, int]]  # (channel id, file offset of 1st entry, entries)
    partial: bool = False  # cut by the end of the file


@dataclass
class Block:
    """Message records of accepted channels in one buffer (a chunk or the file itself)."""

    buf: bytes | memoryview
    offsets: np.ndarray  # int64, record starts in buf, file order
    lengths: np.ndarray  # int64, record body lengths
    channels: np.ndarray  # uint16
    file_offset: int  # where the buffer comes from in the file (for reports)


class Scanner:
    """Walk one file's records, tolerate damage and yield :class:`Block` s."""

    def __init__(
        self,
        path: Path,
        accept: Callable[[Channel], bool],
        report: ReadReport,
        uncounted: frozenset[str] = frozenset(),
    ) -> None:
        self.path = str(path)
        self.uncounted = uncounted  # accepted topics left out of the counts of the report
        self.accept = accept
        self.report = report
        self.data = _map_file(path)
        self.data_arr = np.frombuffer(self.data, np.uint8)
        self.position = 0  # where the walk is in the file (B), for progress
        self.batch_bytes = _BATCH_BYTES  # decompressed bytes per batch (a streamed read: less)
        self.file_report = FileReport(self.path, len(self.data))
        report.files.append(self.file_report)
        self.schemas: dict[int, str] = {}  # schema id -> name (data section)
        self.summary_schemas: dict[int, str] = {}
        # chunk start offset -> chunk record length (opcode and length included), from the
        # summary's Chunk Index records: a chunk whose opcode byte is damaged is still read
        self.summary_chunks: dict[int, int] = {}
        self.summary_channels: dict[int, tuple[int, str, str]] = {}  # id -> schema, topic, enc
        self.channels: dict[int, Channel] = {}
        self.accepted: set[int] = set()
        self.topic_names: list[str] = []  # accepted channel -> topic index
        self.topic_index: dict[str, int] = {}
        self.topic_lut = np.full(1 << 16, -1, np.int64)  # accepted channel id -> topic index
        self.known_lut = np.zeros(1 << 16, bool)  # channel id seen
        self.unknown: dict[int, tuple[int, int]] = {}  # channel id -> (count, first offset)
        self.stats_counts: dict[int, int] | None = None
        self._top_messages: list[int] = []
        self.recovered = 0  # Message records found in a chunk the end of the file cuts
        self.cut_chunk_at: int | None = None  # offset of a Chunk record the file's end cuts
        # For a caller that copies the file (recovery): every Schema and Channel record body
        # as it is met, (opcode, buf, start, end); top-level Metadata and Attachment records.
        self.on_definition: Callable[[int, bytes | memoryview, int, int], None] | None = None
        self.on_record: Callable[[int, bytes, int, int], None] | None = None

    # -- reporting
    def skip(self, offset: int, kind: str, reason: str, lost: int | None = None) -> None:
        self.report.skips.append(Skip(self.path, offset, kind, reason, lost))

    def bad_payload(
        self, offset: int, bad: int, what: str = 'not a 12-byte CDR Float64'
    ) -> None:
        """Report ``bad`` records whose payload is ``what`` in the chunk at ``offset``: one
        Skip per chunk and kind of fault (a chunk walked in pieces adds to its one)."""
        skips = self.report.skips
        last = skips[-1] if skips else None
        if (
            last is not None
            and (last.path, last.offset, last.kind) == (self.path, offset, 'bad_payload')
            and last.reason.endswith(what)
        ):
            bad += last.messages_lost or 0
            skips.pop()
        self.skip(offset, 'bad_payload', f'{bad} message(s) {what}', bad)

    def finish(self) -> None:
        for channel_id, (count, offset) in sorted(self.unknown.items()):
            self.skip(
                offset,
                'unknown_channel',
                f'{count} message(s) on channel id {channel_id} whose Channel record ' 'was lost',
                None,
            )
        if self.stats_counts is not None:
            self.file_report.messages_expected = sum(
                n for cid, n in self.stats_counts.items() if self._counted(cid)
            )

    def _counted(self, channel_id: int) -> bool:
        if channel_id not in self.accepted:
            return False
        return not self.uncounted or self.channels[channel_id].topic not in self.uncounted

    # -- channel bookkeeping
    def _add_schema(self, buf: bytes | memoryview, pos: int, end: int) -> None:
        schema_id, name = parse_schema(buf, pos, end)
        self.schemas[schema_id] = name
        if self.on_definition is not None:
            self.on_definition(OP_SCHEMA, buf, pos, end)

    def _add_channel(self, buf: bytes | memoryview, pos: int, end: int) -> None:
        self._register(*parse_channel(buf, pos, end))
        if self.on_definition is not None:
            self.on_definition(OP_CHANNEL, buf, pos, end)

    def _register(self, channel_id: int, schema_id: int, topic: str, encoding: str) -> None:
        """Make a channel known; the data section's definition wins over the summary's."""
        if channel_id in self.channels:
            return
        if schema_id == 0:
            schema_name = ''
        else:
            schema_name = self.schemas.get(schema_id, self.summary_schemas.get(schema_id, ''))
        channel = Channel(channel_id, topic, encoding, schema_id, schema_name)
        self.channels[channel_id] = channel
        self.known_lut[channel_id] = True
        if self.accept(channel):
            self.accepted.add(channel_id)
            index = self.topic_index.setdefault(topic, len(self.topic_names))
            if index == len(self.topic_names):
                self.topic_names.append(topic)
            self.topic_lut[channel_id] = index

    def _resolve(self, channel_ids: Iterable[int]) -> None:
        """Take channels not (yet) defined in the data section from the summary."""
        for cid in channel_ids:
            if cid not in self.channels and cid in self.summary_channels:
                self._register(cid, *self.summary_channels[cid])

    def _count_unknown(self, missing: np.ndarray, file_offset: int) -> None:
        for cid, n in zip(*np.unique(missing, return_counts=True)):
            count, first = self.unknown.get(int(cid), (0, file_offset))
            self.unknown[int(cid)] = (count + int(n), first)

    # -- summary (read first: it repeats every Schema and Channel; used for channels whose
    #    definition in the data section was lost)
    def _read_summary(self) -> None:
        data = self.data
        n = len(data)
        footer_at = n - len(MAGIC) - 9 - 20
        if footer_at < len(MAGIC) or data[n - len(MAGIC) :] != MAGIC:
            return
        op, length = RECORD_HEAD.unpack_from(data, footer_at)
        if op != OP_FOOTER or length != 20:
            return
        summary_start, _, summary_crc = struct.unpack_from('<QQI', data, footer_at + 9)
        self.file_report.finished = True
        if summary_start == 0 or not len(MAGIC) <= summary_start <= footer_at:
            return
        if summary_crc and zlib.crc32(data[summary_start : footer_at + 9 + 16]) != summary_crc:
            self.skip(
                summary_start,
                'corrupt_region',
                'summary section CRC mismatch; ' 'channels are taken from the data section only',
            )
            return
        pos = summary_start
        while pos + 9 <= footer_at:
            op, length = RECORD_HEAD.unpack_from(data, pos)
            body, end = pos + 9, pos + 9 + length
            if end > footer_at:
                break
            try:
                if op == OP_SCHEMA:
                    schema_id, name = parse_schema(data, body, end)
                    self.summary_schemas[schema_id] = name
                elif op == OP_CHANNEL:
                    channel_id, *rest = parse_channel(data, body, end)
                    self.summary_channels[channel_id] = tuple(rest)  # type: ignore[assignment]
                elif op == OP_STATISTICS:
                    self.stats_counts = statistics_counts(data, body, end)
                elif op == OP_CHUNK_INDEX and length >= 32:
                    start, size = struct.unpack_from('<QQ', data, body + 16)
                    self.summary_chunks[start] = size
            except BadRecord as exc:
                self.skip(pos, 'corrupt_region', f'unreadable summary record: {exc}')
            pos = end

    # -- main walk
    def blocks(self) -> Iterator[Block]:
        """Yield the accepted message records of the file in file order, batch by batch."""
        data = self.data
        n = len(data)
        if n < len(MAGIC) or data[: len(MAGIC)] != MAGIC:
            if MAGIC.startswith(data[: len(MAGIC)]):
                self.skip(0, 'truncated', f'file ends after {n} byte(s), inside the magic')
                return
            if not looks_like_header(data):
                raise McapReadError(f'{self.path} is not an MCAP file (bad magic)')
            self.skip(0, 'corrupt_region', 'damaged magic bytes before a valid Header record')
        self._read_summary()
        batch: list[Piece] = []
        batch_bytes = 0
        pos = len(MAGIC)
        while pos < n:
            self.position = pos
            if pos + 9 > n:
                self.skip(pos, 'truncated', f'file ends inside a record header ({n - pos} B)')
                break
            op, length = RECORD_HEAD.unpack_from(data, pos)
            end = pos + 9 + length
            if op != OP_CHUNK and self.summary_chunks.get(pos) == 9 + length:
                # the summary's (CRC-checked) chunk index puts a chunk here: its opcode byte is
                # damaged (an unknown opcode is skipped by the spec, and its messages with it)
                self.skip(
                    pos, 'corrupt_region', f'a chunk\'s opcode damaged (0x{op:02x}); the chunk '
                    "read through the summary's chunk index", 0,
                )  # fmt: skip
                op = OP_CHUNK
            if op not in KNOWN_OPS and op < 0x80:
                pos = self._resync(pos, f'invalid record opcode 0x{op:02x}')
                continue
            if end > n:
                # Either the writer was killed inside this record (nothing valid follows) or
                # its length field is damaged (a valid chunk follows somewhere).
                if self.file_report.finished or find_chunk(data, pos + 1) >= 0:
                    pos = self._resync(
                        pos,
                        f'record (opcode 0x{op:02x}) of {length} B runs '
                        'past the end of the file',
                    )
                    continue
                recovered = ''
                if op == OP_CHUNK:
                    self.cut_chunk_at = pos
                    yield from self._flush_top()
                    yield from self._flush_batch(batch)
                    batch = []
                    yield from self._cut_chunk(pos)
                    recovered = (
                        f'; {self.recovered} message record(s) recovered from the cut '
                        'chunk without CRC check'
                    )
                self.skip(
                    pos,
                    'truncated',
                    f'file ends inside a record (opcode 0x{op:02x}, '
                    f'{length} B, {n - pos - 9} B present){recovered}',
                )
                break
            body = pos + 9
            if op == OP_CHUNK:
                yield from self._flush_top()
                if self._streamed(pos, end):  # too large to hold: decoded and walked in pieces
                    yield from self._flush_batch(batch)
                    batch, batch_bytes = [], 0
                    pos = yield from self._big_chunk(pos, end)
                    continue
                pos, piece = self._chunk(pos, end)
                if piece is not None:
                    batch.append(piece)
                    batch_bytes += len(piece.data)
                    if batch_bytes >= self.batch_bytes or len(batch) >= _BATCH_PIECES:
                        yield from self._flush_batch(batch)
                        batch, batch_bytes = [], 0
                continue
            if batch and op in (OP_MESSAGE, OP_SCHEMA, OP_CHANNEL):
                # Keep file order: the batched chunks may define what this record uses.
                yield from self._flush_batch(batch)
                batch, batch_bytes = [], 0
            try:
                if op == OP_MESSAGE:
                    self._top_messages.append(pos)
                    if len(self._top_messages) >= _TOP_GROUP:
                        yield from self._flush_top()
                elif op == OP_SCHEMA:
                    self._add_schema(data, body, end)
                elif op == OP_CHANNEL:
                    self._add_channel(data, body, end)
                elif op in (OP_METADATA, OP_ATTACHMENT) and self.on_record is not None:
                    self.on_record(op, data, body, end)
                elif op == OP_HEADER:
                    self.file_report.profile, _ = read_string(data, body, end)
                elif op == OP_FOOTER or op == OP_DATA_END:
                    break  # the summary section was read (CRC-checked) by _read_summary
            except BadRecord as exc:
                self.skip(pos, 'corrupt_region', f'unreadable record (opcode 0x{op:02x}): {exc}')
            pos = end
        yield from self._flush_batch(batch)
        yield from self._flush_top()

    def _flush_top(self) -> Iterator[Block]:
        """Yield unchunked top-level messages collected so far (``fastwrite`` files)."""
        if not self._top_messages:
            return
        offsets = np.asarray(self._top_messages, dtype=np.int64)
        self._top_messages = []
        block = self._select(self.data, offsets, int(offsets[0]))
        if block is not None:
            yield block
        _release(self.data, int(offsets[0]))

    def _flush_batch(self, pieces: list[Piece]) -> Iterator[Block]:
        if not pieces:
            return
        buf, offsets = self._locate_messages(pieces)
        block = self._select(buf, offsets, pieces[0].file_offset)
        if block is not None:
            yield block
        _release(self.data, pieces[0].file_offset)

    def _resync(self, pos: int, reason: str) -> int:
        """Skip a damaged region: continue at the next plausible Chunk record."""
        found = find_chunk(self.data, pos + 1)
        if found < 0:
            self.skip(
                pos,
                'corrupt_region' if self.file_report.finished else 'truncated',
                f'{reason}; no readable chunk after it',
            )
            return len(self.data)
        self.skip(pos, 'corrupt_region', f'{reason}; skipped {found - pos} B to the next chunk')
        return found

    def _message_indexes(self, pos: int) -> tuple[int, list[tuple[int, int, int]]]:
        """Find the Message Index records after a chunk: (channel, first entry, entries)."""
        data, n = self.data, len(self.data)
        indexes: list[tuple[int, int, int]] = []
        while pos + 15 <= n:
            op, length = RECORD_HEAD.unpack_from(data, pos)
            if op != OP_MESSAGE_INDEX or pos + 9 + length > n or length < 6:
                break
            channel_id, nbytes = struct.unpack_from('<HI', data, pos + 9)
            if nbytes % 16 or 6 + nbytes > length:
                break
            indexes.append((channel_id, pos + 15, nbytes // 16))
            pos += 9 + length
        return pos, indexes

    def _lost_in(self, indexes: list[tuple[int, int, int]]) -> int | None:
        """Requested-topic messages listed by the indexes of a lost chunk, if knowable."""
        self._resolve(cid for cid, _, _ in indexes)
        if not indexes or any(cid not in self.channels for cid, _, _ in indexes):
            return None
        return sum(count for cid, _, count in indexes if self._counted(cid))

    def _chunk(self, pos: int, end: int) -> tuple[int, Piece | None]:
        data = self.data
        after, indexes = self._message_indexes(end)
        header = chunk_header(data, pos + 9, end)
        if header is None:
            self.skip(
                pos,
                'corrupt_chunk',
                'chunk header is inconsistent with its length',
                self._lost_in(indexes),
            )
            return after, None
        usize, crc, compression, rec_start, rec_end = header
        problem = chunk_size_problem(usize, rec_end - rec_start, compression)
        if problem is not None:
            self.skip(pos, 'corrupt_chunk', f'chunk {problem}', self._lost_in(indexes))
            return after, None
        try:
            records = _decompress(data, rec_start, rec_end, compression, usize)
        except Exception as exc:  # noqa: BLE001 - any decoder error means a corrupt chunk
            self.skip(
                pos,
                'corrupt_chunk',
                f'{compression} chunk cannot be decompressed: ' f'{type(exc).__name__}: {exc}',
                self._lost_in(indexes),
            )
            return after, None
        if len(records) != usize:
            self.skip(
                pos,
                'corrupt_chunk',
                f'chunk decompresses to {len(records)} B, header ' f'says {usize} B',
                self._lost_in(indexes),
            )
            return after, None
        if crc and zlib.crc32(records) != crc:
            self.skip(pos, 'corrupt_chunk', 'chunk CRC mismatch', self._lost_in(indexes))
            return after, None
        self.file_report.chunks += 1
        return after, Piece(records, pos, indexes)

    def _streamed(self, pos: int, end: int) -> bool:
        """Whether the Chunk record at ``pos`` declares more than :data:`WHOLE_CHUNK_BYTES`
        uncompressed (decoded in pieces, never whole)."""
        header = chunk_header(self.data, pos + 9, end)
        return header is not None and header[0] > WHOLE_CHUNK_BYTES

    def _big_chunk(self, pos: int, end: int) -> Generator[Block, None, int]:
        """A chunk too large to hold, in bounded memory: checked in a first streaming pass
        (decodes to exactly its size, CRC), then decoded again and walked piece by piece
        (:meth:`_walk_pieces`). Returns where the file's walk goes on."""
        data = self.data
        after, indexes = self._message_indexes(end)
        header = chunk_header(data, pos + 9, end)
        assert header is not None  # _streamed read it
        usize, crc, compression, rec_start, rec_end = header
        problem = chunk_size_problem(usize, rec_end - rec_start, compression)
        if problem is not None:
            problem = f'chunk {problem}'
        else:
            problem = _stream_problem(data, rec_start, rec_end, compression, usize, crc)
        if problem is not None:
            self.skip(pos, 'corrupt_chunk', problem, self._lost_in(indexes))
            return after
        self.file_report.chunks += 1
        pieces = decompressed_pieces(
            data, rec_start, rec_end, compression, usize, max(_READ_STEP, self.batch_bytes)
        )
        walked, _ = yield from self._walk_pieces(pieces, pos, usize, False)
        if walked != usize:
            self.skip(
                pos,
                'corrupt_chunk',
                f'chunk records unreadable from byte {walked} of {usize}; the messages '
                'before it are used',
            )
        _release(data, pos)
        return after

    def _cut_chunk(self, pos: int) -> Iterator[Block]:
        """The decodable start of a chunk cut by the end of the file (walked, not indexed; no
        CRC to check), decoded and walked piece by piece."""
        data = self.data
        self.recovered = 0
        header = chunk_header(data, pos + 9, len(data), partial=True)
        if header is None:
            return
        usize, _, compression, rec_start, rec_end = header
        if chunk_size_problem(usize, rec_end - rec_start, compression) is not None:
            return  # implausible: nothing is decompressed (reported as the cut)
        pieces = decompressed_pieces(
            data,
            rec_start,
            min(rec_end, len(data)),
            compression,
            usize,
            max(_READ_STEP, self.batch_bytes),
        )
        _, self.recovered = yield from self._walk_pieces(pieces, pos, usize, True)
        if self.recovered:
            self.file_report.chunks += 1

    def _walk_pieces(
        self, pieces: Iterator[bytes | memoryview], pos: int, size: int, cut: bool
    ) -> Generator[Block, None, tuple[int, int]]:
        """Walk a chunk's records from its decompressed ``pieces`` (``size`` B declared), about
        a reader batch at a time, yielding the accepted messages of each stretch as a block;
        a record that a stretch cuts waits for the next. A record longer than
        :data:`LONG_RECORD_BYTES` is dropped as it streams past (never held; reported when it
        is a Message, Schema or Channel). ``cut``: the pieces end in a decoder error or too
        early (the chunk was cut by the end of the file). Returns (bytes walked up to the
        first that is not a record, or ``size``; Message records found)."""
        pending: list[bytes | memoryview] = []
        have = done = drop = found = 0
        need = self.batch_bytes
        source = iter(pieces)
        while True:
            try:
                piece: bytes | memoryview | None = next(source)
            except StopIteration:
                piece = None
            except Exception:  # noqa: BLE001 - a cut chunk ends in a decoder error
                if not cut:
                    raise
                piece = None
            if piece is not None:
                if drop:
                    cut_off = min(drop, len(piece))
                    piece, drop, done = piece[cut_off:], drop - cut_off, done + cut_off
                if len(piece):
                    pending.append(piece)
                    have += len(piece)
                if have < need:
                    continue
            if not pending:
                return done, found
            buf = pending[0] if len(pending) == 1 else b''.join(pending)
            offsets, stop = self._walk(buf, 0, len(buf))
            found += len(offsets)
            if len(offsets):
                block = self._select(buf, offsets, pos)
                if block is not None:
                    yield block
            pending, have, need = [], 0, self.batch_bytes
            want = _record_want(buf, stop)
            if stop == len(buf):
                done += stop
            elif want == 0 or done + stop + want > size or piece is None:
                return done + stop, found  # not a record, or one past the chunk's end
            elif want > LONG_RECORD_BYTES:
                self._long_record(buf, stop, pos, want)
                drop, done = want - (len(buf) - stop), done + len(buf)
            else:
                pending, have = [buf[stop:]], len(buf) - stop
                need, done = max(want, self.batch_bytes), done + stop
            if piece is None and not pending:
                return done, found

    def _long_record(self, buf: bytes | memoryview, at: int, pos: int, want: int) -> None:
        """Report a record of a streamed chunk too long to hold (dropped unread)."""
        op = buf[at]
        if op in (OP_MESSAGE, OP_SCHEMA, OP_CHANNEL):
            what = {OP_MESSAGE: 'Message', OP_SCHEMA: 'Schema', OP_CHANNEL: 'Channel'}[op]
            self.skip(
                pos,
                'corrupt_chunk',
                f'a {what} record of {want} B dropped unread (more than the '
                f'{LONG_RECORD_BYTES} B a record of a large chunk may hold)',
            )

    def _walk(self, buf: bytes | memoryview, start: int, end: int) -> tuple[np.ndarray, int]:
        """Walk the records of ``buf[start:end]``: the starts of its Message records (int64, in
        order) and where the walk stopped (``end`` when every record fit). Schema and Channel
        records are registered on the way; a record that is not one (or a bad Schema or
        Channel) stops the walk. One C loop (``_scan.walk``) where built, else a Python loop
        that takes a run of equal records (same opcode and length) in numpy passes."""
        parts: list[np.ndarray] = []
        pos = start
        while pos + 9 <= end:
            if _scan is not None:
                out = np.empty(min((end - pos) // MESSAGE_MIN + 1, 1 << 20), np.int64)
                n, pos, status = _scan.walk(buf, pos, end, out)
                if n:
                    parts.append(out[:n].copy())
                if status == 3:
                    continue  # out was full
                if status != 1:
                    break
            else:
                pos, stopped_at_definition = self._walk_py(buf, pos, end, parts)
                if not stopped_at_definition:
                    break
            op, length = RECORD_HEAD.unpack_from(buf, pos)
            try:  # a Schema or Channel record
                if op == OP_SCHEMA:
                    self._add_schema(buf, pos + 9, pos + 9 + length)
                else:
                    self._add_channel(buf, pos + 9, pos + 9 + length)
            except BadRecord:
                break
            pos += 9 + length
        if not parts:
            return np.empty(0, np.int64), pos
        return (parts[0] if len(parts) == 1 else np.concatenate(parts)), pos

    @staticmethod
    def _walk_py(
        buf: bytes | memoryview, pos: int, end: int, parts: list[np.ndarray]
    ) -> tuple[int, bool]:
        """:meth:`_walk`'s loop without the C one: up to the next Schema or Channel record
        (True) or to where the walk stops (False). A record equal in opcode and length to the
        one before it starts a run, measured in numpy passes of growing size (so a chunk of
        millions of equal records costs a few passes, and records that differ cost no more
        than one comparison each)."""
        unpack = RECORD_HEAD.unpack_from
        arr = np.frombuffer(buf, np.uint8)
        found: list[int] = []
        last: tuple[int, int] = (-1, -1)
        while pos + 9 <= end:
            op, length = unpack(buf, pos)
            stop = pos + 9 + length
            if stop > end or op == 0 or (op not in KNOWN_OPS and op < 0x80):
                break
            if op == OP_SCHEMA or op == OP_CHANNEL:
                parts.append(np.asarray(found, np.int64))
                return pos, True
            if op == OP_MESSAGE and length < 22:
                break
            if (op, length) == last:
                run = _equal_run(arr, pos, end, 9 + length)
                if op == OP_MESSAGE:
                    parts.append(np.asarray(found, np.int64))
                    parts.append(pos + (9 + length) * np.arange(run, dtype=np.int64))
                    found = []
                pos += run * (9 + length)
                continue
            if op == OP_MESSAGE:
                found.append(pos)
            last = (op, length)
            pos = stop
        parts.append(np.asarray(found, np.int64))
        return pos, False

    def _locate_messages(self, pieces: list[Piece]) -> tuple[bytes | memoryview, np.ndarray]:
        """Concatenate decompressed chunks; return the buffer and its Message record offsets.

        Message Index entries are checked in one vectorised pass over the batch: each must
        point inside its chunk at a Message record of its channel, and records must not
        overlap. Chunks whose entries fail are walked record by record, and so is every byte
        range that valid entries do not cover (Schema/Channel records, or messages of a
        channel whose index is missing). Offsets come back sorted, i.e. in file order.
        """
        k = len(pieces)
        sizes = np.fromiter((len(p.data) for p in pieces), np.int64, k)
        starts = np.zeros(k, np.int64)
        np.cumsum(sizes[:-1], out=starts[1:])
        piece_ends = starts + sizes
        buf = pieces[0].data if k == 1 else b''.join(p.data for p in pieces)
        arr = np.frombuffer(buf, np.uint8)
        indexed = np.fromiter((bool(p.indexes) for p in pieces), bool, k)
        entries = [
            (i, cid, at, count)
            for i, p in enumerate(pieces)
            for cid, at, count in p.indexes
            if count
        ]
        if _scan is not None:
            g, gaps, bad = self._locate_c(arr, entries, starts, sizes)
            indexed &= ~bad
            return self._walk_gaps(pieces, buf, g, gaps, starts, sizes, piece_ends, indexed)
        g = np.empty(0, np.int64)
        e = np.empty(0, np.int64)
        owner = np.empty(0, np.int64)
        if entries:
            table = np.array(entries, np.int64)
            counts = table[:, 3]
            which = np.repeat(np.arange(len(table)), counts)
            within = np.arange(len(which)) - np.repeat(np.cumsum(counts) - counts, counts)
            entry_at = table[which, 2] + 16 * within + 8
            off = gather(self.data_arr, entry_at, 8).view('<u8').ravel()
            owner = table[which, 0]
            ok = off < sizes[owner].astype(np.uint64)
            off = np.where(ok, off, 0).astype(np.int64)
            ok &= off + MESSAGE_MIN <= sizes[owner]
            g = np.where(ok, starts[owner] + off, 0)
            if len(arr) >= MESSAGE_MIN:
                head = gather(arr, np.minimum(g, len(arr) - MESSAGE_MIN), 11)
                ok &= head[:, 0] == OP_MESSAGE
                ok &= head[:, 9:11].copy().view('<u2').ravel() == table[which, 1]
                length = head[:, 1:9].copy().view('<u8').ravel()
                ok &= (length >= 22) & (length <= sizes[owner].astype(np.uint64))
                e = g + 9 + np.where(ok, length, 0).astype(np.int64)
                ok &= e <= piece_ends[owner]
            else:
                ok[:] = False
                e = g.copy()
            bad = np.zeros(k, bool)
            bad[owner[~ok]] = True
            keep = ~bad[owner]
            g, e, owner = g[keep], e[keep], owner[keep]
            if len(g) > 1 and np.any(g[1:] < g[:-1]):
                order = np.argsort(g, kind='stable')
                g, e, owner = g[order], e[order], owner[order]
            overlap = np.flatnonzero(e[:-1] > g[1:])
            if len(overlap):
                bad[owner[overlap]] = True
                keep = ~bad[owner]
                g, e, owner = g[keep], e[keep], owner[keep]
            indexed &= ~bad
        # Byte ranges to walk: between consecutive covered records and at chunk edges; a
        # chunk without (valid) index entries is one whole range.
        edge_s = np.concatenate((g, starts, piece_ends))
        edge_e = np.concatenate((e, starts, piece_ends))
        order = np.lexsort((edge_e, edge_s))
        edge_s, edge_e = edge_s[order], edge_e[order]
        at = np.flatnonzero(edge_e[:-1] < edge_s[1:])
        gaps = np.stack((edge_e[at], edge_s[at + 1]), axis=1)
        return self._walk_gaps(pieces, buf, g, gaps, starts, sizes, piece_ends, indexed)

    def _locate_c(
        self, arr: np.ndarray, entries: list[tuple[int, int, int, int]], starts: np.ndarray,
        sizes: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The index check of :meth:`_locate_messages` in C (``_scan.locate``): the covered
        record starts (sorted), the byte ranges between them to walk (n, 2) and the chunks
        whose entries failed."""
        k = len(starts)
        table = np.array(entries, np.int64).reshape(-1, 4)
        total = int(table[:, 3].sum())
        g = np.empty(total, np.int64)
        bad = np.zeros(k, np.uint8)
        gaps = np.empty((total + k, 2), np.int64)
        ng, ngaps = _scan.locate(arr, self.data_arr, table, starts, sizes, g, bad, gaps)
        return g[:ng], gaps[:ngaps], bad.view(bool)

    def _walk_gaps(
        self,
        pieces: list[Piece],
        buf: bytes | memoryview,
        g: np.ndarray,
        gaps: np.ndarray,
        starts: np.ndarray,
        sizes: np.ndarray,
        piece_ends: np.ndarray,
        indexed: np.ndarray,
    ) -> tuple[bytes | memoryview, np.ndarray]:
        """Walk the byte ranges that no checked index entry covers; return the buffer and
        every Message record start (sorted)."""
        k = len(pieces)
        found: list[np.ndarray] = []
        rewalk: set[int] = set()
        for a, b in gaps.tolist():
            piece = int(np.searchsorted(starts, a, 'right')) - 1
            offsets, stop = self._walk(buf, a, b)
            found.append(offsets)
            if stop != b:
                if indexed[piece]:
                    rewalk.add(piece)  # the index and the records disagree: trust neither
                else:
                    self._unreadable(pieces[piece], stop - int(starts[piece]), int(sizes[piece]))
        walked = np.concatenate(found) if found else np.empty(0, np.int64)
        if rewalk:
            drop = np.zeros(k, bool)
            drop[list(rewalk)] = True
            g = g[~drop[np.searchsorted(starts, g, 'right') - 1]]
            walked = walked[~drop[np.searchsorted(starts, walked, 'right') - 1]]
            found = [walked]
            for piece in sorted(rewalk):
                a, b = int(starts[piece]), int(piece_ends[piece])
                offsets, stop = self._walk(buf, a, b)
                found.append(offsets)
                if stop != b:
                    self._unreadable(pieces[piece], stop - a, b - a)
            walked = np.concatenate(found)
        if len(walked):
            g = np.concatenate((g, walked))
            g.sort(kind='stable')
        return buf, g

    def _unreadable(self, piece: Piece, stop: int, size: int) -> None:
        if piece.partial:
            return  # that is the cut itself, reported as 'truncated'
        self.skip(
            piece.file_offset,
            'corrupt_chunk',
            f'chunk records unreadable from byte '
            f'{stop} of {size}; the messages before it are used',
        )

    def _select(
        self, buf: bytes | memoryview, offsets: np.ndarray, file_offset: int
    ) -> Block | None:
        """Keep the message records of accepted channels; count unknown channels."""
        if len(offsets) == 0:
            return None
        arr = np.frombuffer(buf, np.uint8)
        channels = gather(arr, offsets + 9, 2).view('<u2').ravel()
        known = self.known_lut[channels]
        if not known.all() and self.summary_channels:
            self._resolve(np.unique(channels[~known]).tolist())
            known = self.known_lut[channels]
        if not known.all():
            self._count_unknown(channels[~known], file_offset)
        keep = self.topic_lut[channels] >= 0
        if not keep.any():
            return None
        if not keep.all():
            offsets, channels = offsets[keep], channels[keep]
        lengths = gather(arr, offsets + 1, 8).view('<u8').ravel().astype(np.int64)
        return Block(buf, offsets, lengths, channels, file_offset)


#: Largest uncompressed chunk accepted (B). The node's chunks are 0.5-2 MiB and rosbag2's
#: default is 4 MiB; a larger declaration is taken as damage, not allocated.
MAX_CHUNK_BYTES = 256 << 20
#: Largest plausible ratio of declared uncompressed to compressed chunk size. Telemetry
#: compresses 3-30x; only crafted data (long runs of one byte) goes past 1000x.
MAX_CHUNK_RATIO = 1000
_RATIO_SLACK = 4096  # B: a tiny chunk may compress by more than the ratio
_READ_STEP = 1 << 20  # B decompressed per step of a bounded streaming read
#: Chunks declaring more (B uncompressed) are decoded in pieces and walked as they come, never
#: held whole: the node's chunks are 0.5-2 MiB, rosbag2's 4 MiB.
WHOLE_CHUNK_BYTES = 16 << 20
#: A record of a chunk decoded in pieces longer than this (B) is dropped as it streams past:
#: no Float64 or event record comes near it, and holding it would undo the bound.
LONG_RECORD_BYTES = 16 << 20
_TOP_GROUP = 1 << 16  # top-level Message records handed on together (unchunked files)


def _record_want(buf: bytes | memoryview, at: int) -> int:
    """The bytes (head included) of the record at ``at`` that the end of ``buf`` cuts (9 when
    not even its head is there), or 0 when what is there cannot be a record."""
    if len(buf) - at < 9:
        return 9
    op, length = RECORD_HEAD.unpack_from(buf, at)
    if op == 0 or (op not in KNOWN_OPS and op < 0x80) or (op == OP_MESSAGE and length < 22):
        return 0
    if at + 9 + length <= len(buf):
        return 0  # whole, and refused (a bad Schema or Channel)
    return 9 + length


def _stream_problem(
    data: bytes, start: int, end: int, compression: str, usize: int, crc: int
) -> str | None:
    """Why a chunk's records (``data[start:end]``, ``usize`` B declared) cannot be used, or
    None: decoded in a streaming pass (bounded memory) and discarded."""
    total = running = 0
    try:
        if compression == 'zstd':  # into one reused buffer: no allocation per piece
            import zstandard

            view = memoryview(data)[start:end]
            reader = zstandard.ZstdDecompressor().stream_reader(view, read_across_frames=True)
            space = memoryview(bytearray(_STREAM_STEP))
            pieces: Iterable[bytes | memoryview] = iter(
                lambda: space[: reader.readinto(space[: max(1, usize + 1 - total)])], space[:0]
            )
        else:
            pieces = decompressed_pieces(data, start, end, compression, usize + 1, _STREAM_STEP)
        for piece in pieces:
            total += len(piece)
            if crc:
                running = zlib.crc32(piece[: max(0, usize - (total - len(piece)))], running)
            if total > usize:
                break
    except Exception as exc:  # noqa: BLE001 - any decoder error means a corrupt chunk
        return f'{compression} chunk cannot be decompressed: {type(exc).__name__}: {exc}'
    if total > usize:
        return (
            f'{compression} chunk cannot be decompressed: {compression} data decompresses to '
            f'more than the {usize} B declared'
        )
    if total != usize:
        return f'chunk decompresses to {total} B, header says {usize} B'
    if crc and running != crc:
        return 'chunk CRC mismatch'
    return None


_STREAM_STEP = 8 << 20  # B per piece of the checking pass of a chunk decoded in pieces


def chunk_size_problem(usize: int, compressed: int, compression: str) -> str | None:
    """Why a chunk's declared uncompressed size ``usize`` (B) is implausible, or None.

    ``compressed`` is the length of its compressed records (B). Checked before anything is
    decompressed, so a crafted chunk costs no memory.
    """
    if usize > MAX_CHUNK_BYTES:
        return f'declares {usize} B uncompressed, more than the {MAX_CHUNK_BYTES} B accepted'
    if compression == '' and usize != compressed:
        return f'uncompressed chunk declares {usize} B but holds {compressed} B'
    if compression and usize > MAX_CHUNK_RATIO * compressed + _RATIO_SLACK:
        return (
            f'declares {usize} B from {compressed} B of {compression}, more than '
            f'{MAX_CHUNK_RATIO}x: implausible'
        )
    return None


def _decompress(
    data: bytes, start: int, end: int, compression: str, usize: int
) -> bytes | memoryview:
    """Decompress a whole chunk's records, producing at most ``usize`` + 1 bytes.

    Raises McapReadError when the data decompresses to more than declared (bounded: the
    decoder stops one byte past ``usize``); fewer bytes come back as they are.
    """
    if compression == '':
        return memoryview(data)[start:end]
    if compression == 'zstd':
        import zstandard

        view = memoryview(data)[start:end]
        declared = zstandard.frame_content_size(view)
        if declared >= 0 and declared != usize:
            # zstandard allocates a frame's own content size whatever max_output_size says.
            raise McapReadError(f'zstd frame declares {declared} B, the chunk {usize} B')
        if declared == usize:
            return _zstd().decompress(view, max_output_size=usize)
        return _bounded(data, start, end, compression, usize + 1, exceeded=usize)
    if compression == 'lz4':
        return _bounded(data, start, end, compression, usize + 1, exceeded=usize)
    raise McapReadError(f'unsupported chunk compression {compression!r}')


_ZSTD = threading.local()


def _zstd() -> 'zstandard.ZstdDecompressor':
    """A per-thread zstd decompressor (creating one per chunk costs ~10 us)."""
    decompressor = getattr(_ZSTD, 'decompressor', None)
    if decompressor is None:
        import zstandard

        decompressor = _ZSTD.decompressor = zstandard.ZstdDecompressor()
    return decompressor


def _bounded(
    data: bytes, start: int, end: int, compression: str, limit: int, exceeded: int | None = None
) -> bytes:
    """Stream-decompress ``data[start:end]`` to at most ``limit`` bytes (time and memory
    bounded by ``limit``). With ``exceeded``, producing more than that many bytes raises
    McapReadError; a decoder error after some output returns what was decoded only when
    ``exceeded`` is None (a cut chunk)."""
    out = bytearray()
    try:
        for piece in decompressed_pieces(data, start, end, compression, limit):
            out += piece
    except Exception:  # noqa: BLE001 - a cut chunk ends in a decoder error
        if exceeded is not None or not out:
            raise
    if exceeded is not None and len(out) > exceeded:
        raise McapReadError(
            f'{compression} data decompresses to more than the {exceeded} B declared'
        )
    return bytes(out)


def decompressed_pieces(
    data: bytes | memoryview,
    start: int,
    end: int,
    compression: str,
    limit: int,
    step: int = _READ_STEP,
) -> Iterator[bytes | memoryview]:
    """The decompressed bytes of ``data[start:end]`` as pieces of at most ``step`` B, at most
    ``limit`` B in all: a chunk decoded in bounded memory whatever it declares. A decoder
    error is raised where it occurs (after the pieces before it)."""
    view = memoryview(data)[start:end]
    produced = 0
    piece: bytes | memoryview
    if compression == '':
        while produced < min(limit, len(view)):
            piece = view[produced : produced + min(step, limit - produced)]
            produced += len(piece)
            yield piece
    elif compression == 'zstd':
        import zstandard

        reader = zstandard.ZstdDecompressor().stream_reader(view, read_across_frames=True)
        while produced < limit:
            piece = reader.read(min(step, limit - produced))
            if not piece:
                return
            produced += len(piece)
            yield piece
    elif compression == 'lz4':
        import lz4.frame

        lz4_dec = lz4.frame.LZ4FrameDecompressor()
        pending = bytes(view)
        while produced < limit and not lz4_dec.eof:
            piece = lz4_dec.decompress(pending, max_length=min(step, limit - produced))
            pending = b''
            if not piece:
                return
            produced += len(piece)
            yield piece
    else:
        raise McapReadError(f'unsupported chunk compression {compression!r}')


def _decompress_partial(
    data: bytes, start: int, end: int, compression: str, usize: int = MAX_CHUNK_BYTES
) -> bytes | memoryview:
    """Decompress as much of a cut chunk as the decoder can produce, at most ``usize`` B."""
    if compression == '':
        return memoryview(data)[start:end]
    return _bounded(data, start, end, compression, min(usize, MAX_CHUNK_BYTES))


def _map_file(path: Path) -> bytes:
    """The file's bytes, memory-mapped (read-only) so that a large file is paged in as it is
    walked and released behind the walk (:func:`_release`), not held whole in memory."""
    with open(path, 'rb') as f:
        size = os.fstat(f.fileno()).st_size
        if size == 0:
            return b''
        # an mmap reads like bytes (slices, find, struct, numpy) for everything done here
        return cast(bytes, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ))


def _release(data: bytes, upto: int) -> None:
    """Drop the mapped pages before ``upto`` from the process (they are read again from the
    page cache if a later step needs them): the reader's memory stays one batch deep."""
    if isinstance(data, mmap.mmap) and hasattr(mmap, 'MADV_DONTNEED'):
        end = upto - upto % mmap.PAGESIZE
        if end > 0:
            data.madvise(mmap.MADV_DONTNEED, 0, end)


def _equal_run(arr: np.ndarray, pos: int, end: int, step: int) -> int:
    """How many records of ``step`` B from ``pos`` (before ``end``) have the 9-byte head of the
    one at ``pos`` (opcode and length): at least 1, measured in passes of growing size."""
    most = (end - pos) // step
    head = arr[pos : pos + 9]
    done, size = 1, 16
    while done < most:
        upto = min(most, done + size)
        heads = as_strided(arr[pos + done * step :], (upto - done, 9), (step, 1), writeable=False)
        differs = np.flatnonzero((heads != head).any(axis=1))
        if len(differs):
            return done + int(differs[0])
        done, size = upto, size * 4
    return done


def gather(arr: np.ndarray, positions: np.ndarray, width: int) -> np.ndarray:
    """The ``width`` bytes at each position as an (n, width) uint8 array: a strided view (no
    copy) when the positions are evenly spaced (one topic type, one chunk run), else a copy."""
    n = len(positions)
    if _scan is not None:
        out = np.empty((n, width), np.uint8)
        _scan.gather(arr, np.ascontiguousarray(positions, np.int64), width, out)
        return out
    if n > 1:
        first, step = int(positions[0]), int(positions[1] - positions[0])
        if step >= width and int(positions[-1]) == first + step * (n - 1):
            if np.array_equal(np.diff(positions), np.full(n - 1, step, positions.dtype)):
                return as_strided(arr[first:], (n, width), (step, 1), writeable=False)
    return sliding_window_view(arr, width)[positions]


def _extract_float64(
    block: Block, topic_lut: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Log times, values and topic indexes of the Float64 records in a block.

    Returns ``(log_time_ns int64, value float64, topic index int64, number of bad records)``.
    A record is bad if its payload is not 12 bytes of CDR (``00 01`` little or ``00 00`` big
    endian encapsulation).
    """
    arr = np.frombuffer(block.buf, np.uint8)
    offsets, lengths = block.offsets, block.lengths
    fits = (lengths >= _FLOAT64_RECORD - 9) & (offsets + _FLOAT64_RECORD <= len(arr))
    if not fits.all():
        offsets, lengths = offsets[fits], lengths[fits]
        channel_ids = block.channels[fits]
    else:
        channel_ids = block.channels
    rows = gather(arr, offsets, _FLOAT64_RECORD).view(_FLOAT64_ROW).ravel()
    encaps = rows['encaps']
    little = encaps == _CDR_LE
    good = little | (encaps == _CDR_BE)
    bad = int(len(block.offsets) - len(offsets)) + int(np.count_nonzero(~good))
    if not good.all():
        rows, little, channel_ids = rows[good], little[good], channel_ids[good]
    values = np.where(little, rows['value_le'], rows['value_be'].astype(np.float64))
    times = rows['log_time'].astype(np.int64)
    return times, values, topic_lut[channel_ids], bad


def _split_topics(
    t: np.ndarray, v: np.ndarray, topic_of_row: np.ndarray, names: list[str]
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Columns per topic (file order kept within each): one stable sort by topic and slices,
    not one mask pass per topic."""
    order = np.argsort(topic_of_row, kind='stable')
    counts = np.bincount(topic_of_row)
    return _slices_by_topic(names, counts, t[order], v[order])


def _slices_by_topic(
    names: list[str], counts: np.ndarray, t: np.ndarray, v: np.ndarray
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Columns per topic from times and values grouped by topic (``counts`` per topic index)."""
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    start = 0
    for topic, count in enumerate(counts.tolist()):
        if count:
            out[names[topic]] = (t[start : start + count], v[start : start + count])
            start += count
    return out


def block_columns(scanner: 'Scanner', block: 'Block') -> Columns:
    """A block's Float64 messages as (log time ns, value) per topic (file order within each);
    payloads that are not a CDR Float64 are reported as damage and counted out."""
    names = scanner.topic_names
    if _scan is not None:  # one C pass: the same columns, grouped by topic
        n = len(block.offsets)
        t, v = np.empty(n, np.int64), np.empty(n, np.float64)
        counts = np.empty(len(names), np.int64)
        good, bad = _scan.float64_columns(
            block.buf,
            np.ascontiguousarray(block.offsets, np.int64),
            np.ascontiguousarray(block.lengths, np.int64),
            np.ascontiguousarray(block.channels, np.uint16),
            scanner.topic_lut,
            len(names),
            t,
            v,
            counts,
        )
        if bad:
            scanner.bad_payload(block.file_offset, bad)
        scanner.file_report.messages += good
        return _slices_by_topic(names, counts, t, v)
    t, v, topic_of_row, bad = _extract_float64(block, scanner.topic_lut)
    if bad:
        scanner.bad_payload(block.file_offset, bad)
    scanner.file_report.messages += len(t)
    first = int(topic_of_row[0]) if len(t) else -1
    if len(t) and np.all(topic_of_row == first):
        return {names[first]: (t, v)}
    return _split_topics(t, v, topic_of_row, names)
