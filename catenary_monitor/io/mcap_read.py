"""Fast, damage-tolerant reading of ROS 2 MCAP logs for replay (no rclpy).

Two entry points:

* :func:`read_float64_topics` reads ``std_msgs/msg/Float64`` topics into numpy columns
  (log time in ns, value) at well over a million messages per second. Chunks are decompressed
  with zstandard/lz4 and gathered into batches of up to 8 MiB; their message records are
  located through the Message Index records that follow each chunk and parsed with one
  vectorised gather per batch. Every index entry is checked against the record it points to,
  and every byte that the index does not cover is walked record by record, so a missing or
  wrong index only costs speed, never data.
* :func:`iter_messages` yields every message of the chosen topics as raw CDR bytes
  (:class:`RawMessage`), in file order, through the same tolerant scanner.
* :func:`iter_windows` streams the same columns (plus raw topics, e.g. the node's events) as
  windows of log time across all the files, in bounded memory: files are memory-mapped and
  the pages behind the walk dropped; ``jobs > 1`` decodes files in worker processes.

Both accept the node's own logs (:mod:`catenary_monitor.mcap_log`), rotated sets and files
written by rosbag2's MCAP storage plugin (zstd, lz4 or uncompressed chunks, chunk CRCs on or
off, unchunked ``fastwrite`` files, with or without message indexes and summary).

Damage handling. Nothing readable is thrown away, and nothing unreadable is silent:

* a file cut short (writer killed: no summary, last chunk or record cut) gives every complete
  chunk, plus the complete records of a cut chunk that can be decompressed up to the cut;
* a corrupt chunk (CRC mismatch, undecompressable data, inconsistent records) is skipped;
  the number of requested-topic messages in it is reported when the Message Index records
  after it survive;
* a corrupt region between records is skipped by searching for the next valid Chunk record.

Each skip is a :class:`Skip` in the :class:`ReadReport`. The mcap library's own reader is used
as the independent oracle in the tests; its ``NonSeekingReader`` stops at the first damaged
record, which is why this module has its own scanner.

Time stamps are MCAP ``log_time`` (ns; the receive time for rosbag2 and for the node's logger).
"""

from __future__ import annotations

import mmap
import os
import queue
import struct
import sys
import threading
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import (
    TYPE_CHECKING,
    Any,
    Callable,
    Generator,
    Iterable,
    Iterator,
    NamedTuple,
    Optional,
    Union,
    cast,
)

import numpy as np
from numpy.lib.stride_tricks import as_strided, sliding_window_view

if TYPE_CHECKING:
    import zstandard

try:  # the per-record loops in C, next to this file (optional: else the numpy passes)
    from catenary_monitor.io import _scan  # type: ignore[attr-defined]
except ImportError:  # not built
    _scan = None
if sys.byteorder != 'little':  # the C loops read MCAP's little-endian fields natively
    _scan = None

__all__ = [
    'FLOAT64_TYPE',
    'EmptyLogError',
    'FileReport',
    'McapReadError',
    'RawMessage',
    'ReadReport',
    'Skip',
    'TopicTypeError',
    'iter_messages',
    'read_float64_topics',
]

#: Schema name required by :func:`read_float64_topics`.
FLOAT64_TYPE = 'std_msgs/msg/Float64'

MAGIC = b'\x89MCAP0\r\n'

_OP_HEADER = 0x01
_OP_FOOTER = 0x02
_OP_SCHEMA = 0x03
_OP_CHANNEL = 0x04
_OP_MESSAGE = 0x05
_OP_CHUNK = 0x06
_OP_MESSAGE_INDEX = 0x07
_OP_CHUNK_INDEX = 0x08
_OP_ATTACHMENT = 0x09
_OP_METADATA = 0x0C
_OP_STATISTICS = 0x0B
_OP_DATA_END = 0x0F
_KNOWN_OPS = frozenset(range(0x01, 0x10))

_RECORD_HEAD = struct.Struct('<BQ')  # opcode, length
_MESSAGE_HEAD = struct.Struct('<HIQQ')  # channel id, sequence, log time, publish time
_CHUNK_HEAD = struct.Struct('<QQQII')  # start, end, uncompressed size, crc, len(compression)
_MESSAGE_MIN = 9 + 22  # smallest Message record (empty payload), B
_FLOAT64_RECORD = 9 + 22 + 12  # Message record of one CDR Float64, B
_BATCH_BYTES = 8 << 20  # decompressed chunk bytes handled per numpy pass
_BATCH_PIECES = 4096  # chunks handled per numpy pass
_INDEX_ENTRY = np.dtype([('t', '<u8'), ('o', '<u8')])
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
_CDR_HEADER = 4  # B: every CDR payload starts with its encapsulation header

PathLike = Union[str, 'os.PathLike[str]']


# ---------------------------------------------------------------------------- public types
class McapReadError(Exception):
    """Base class of the errors raised by this module."""


class TopicTypeError(McapReadError, TypeError):
    """A requested topic is logged with a type other than the one asked for."""

    def __init__(self, topic: str, type_name: str, expected: str, path: str) -> None:
        super().__init__(
            f'topic {topic!r} has type {type_name!r} in {path}, expected {expected!r}'
        )
        self.topic = topic
        self.type_name = type_name
        self.expected = expected
        self.path = path


class EmptyLogError(McapReadError, ValueError):
    """None of the requested topics has a readable message in the given files."""

    def __init__(self, topics: list[str], report: 'ReadReport') -> None:
        detail = f'; {len(report.skips)} damaged part(s) skipped' if report.skips else ''
        super().__init__(
            f'no messages on topics {topics} in {len(report.files)} MCAP file(s){detail}'
        )
        self.topics = topics
        self.report = report


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


class RawMessage(NamedTuple):
    """One message as stored: CDR bytes plus its MCAP envelope."""

    topic: str
    log_time_ns: int
    schema_name: str
    data: bytes
    publish_time_ns: int
    sequence: int


Columns = dict[str, tuple[np.ndarray, np.ndarray]]


# ---------------------------------------------------------------------------- public functions
def read_float64_topics(
    paths: PathLike | Iterable[PathLike],
    topics: Iterable[str],
) -> tuple[Columns, ReadReport]:
    """Read ``std_msgs/msg/Float64`` topics from MCAP files into numpy columns.

    Parameters
    ----------
    paths
        One path or several (a rotated set, in any order). A directory stands for the
        ``*.mcap`` files in it.
    topics
        Topic names, e.g. ``['/chain_01/tension', '/tide/depth']``.

    Returns
    -------
    columns : dict[str, tuple[numpy.ndarray, numpy.ndarray]]
        For every requested topic ``(log_time_ns, value)``: ``int64`` ns and ``float64`` in the
        message's own unit, sorted by log time (stable, so equal stamps keep file order).
        A topic without messages gets two empty arrays and is listed in
        ``report.missing_topics``.
    report : ReadReport
        Files read, parts skipped (with reasons and known losses), per-topic counts.

    Raises
    ------
    TopicTypeError
        If a requested topic is logged with another schema name or a non-``cdr`` encoding.
    EmptyLogError
        If none of the requested topics has a readable message.
    FileNotFoundError
        If a path does not exist.
    """
    wanted = _unique(topics)
    if not wanted:
        raise ValueError('topics must name at least one topic')
    wanted_set = set(wanted)
    report = ReadReport()
    times: dict[str, list[np.ndarray]] = {t: [] for t in wanted}
    values: dict[str, list[np.ndarray]] = {t: [] for t in wanted}

    for path in expand_paths(paths):

        def accept(channel: _Channel, path: str = str(path)) -> bool:
            if channel.topic not in wanted_set:
                return False
            if channel.schema_name != FLOAT64_TYPE or channel.encoding != 'cdr':
                shown = channel.schema_name or '<no schema>'
                if channel.encoding != 'cdr':
                    shown += f' (message encoding {channel.encoding!r})'
                raise TopicTypeError(channel.topic, shown, FLOAT64_TYPE, path)
            return True

        scanner = _Scanner(path, accept, report)
        for block in scanner.blocks():
            for topic, (t, v) in _block_columns(scanner, block).items():
                times[topic].append(t)
                values[topic].append(v)
        scanner.finish()

    columns: Columns = {}
    for topic in wanted:
        t = np.concatenate(times[topic]) if times[topic] else np.empty(0, np.int64)
        v = np.concatenate(values[topic]) if values[topic] else np.empty(0, np.float64)
        if len(t) > 1 and not np.all(t[1:] >= t[:-1]):
            order = np.argsort(t, kind='stable')
            t, v = t[order], v[order]
        columns[topic] = (t, v)
        report.messages[topic] = len(t)
        if len(t) == 0:
            report.missing_topics.append(topic)
    if all(len(columns[t][0]) == 0 for t in wanted):
        raise EmptyLogError(wanted, report)
    return columns, report


def iter_messages(
    paths: PathLike | Iterable[PathLike],
    topics: Iterable[str] | None = None,
    report: ReadReport | None = None,
) -> Iterator[RawMessage]:
    """Yield the messages of ``topics`` (all topics if None) from MCAP files, in file order.

    Slower than :func:`read_float64_topics` (one Python object per message) but works for any
    message type; decode ``data`` with ``rclpy.serialization.deserialize_message`` or
    ``mcap_ros2``. Files are read in the order given (a directory's files sorted by name);
    messages are not re-sorted by time. Damaged parts are skipped as in
    :func:`read_float64_topics` and recorded in ``report`` if one is given.

    Raises
    ------
    FileNotFoundError
        If a path does not exist.
    McapReadError
        If a file is not MCAP at all.
    """
    wanted = None if topics is None else set(_unique(topics))
    report = ReadReport() if report is None else report
    for path in expand_paths(paths):

        def accept(channel: _Channel) -> bool:
            return wanted is None or channel.topic in wanted

        scanner = _Scanner(path, accept, report)
        unpack = _MESSAGE_HEAD.unpack_from
        for block in scanner.blocks():
            buf = block.buf
            for off, length in zip(block.offsets.tolist(), block.lengths.tolist()):
                channel_id, sequence, log_time, publish_time = unpack(buf, off + 9)
                channel = scanner.channels[channel_id]
                scanner.file_report.messages += 1
                report.messages[channel.topic] = report.messages.get(channel.topic, 0) + 1
                yield RawMessage(
                    channel.topic,
                    log_time,
                    channel.schema_name,
                    bytes(buf[off + _MESSAGE_MIN : off + 9 + length]),
                    publish_time,
                    sequence,
                )
        scanner.finish()


# ---------------------------------------------------------------------------- scanner
class _Channel(NamedTuple):
    id: int
    topic: str
    encoding: str
    schema_id: int
    schema_name: str


class _BadRecord(Exception):
    """A record whose fields do not fit its length."""


@dataclass
class _Piece:
    """A decompressed chunk waiting in a batch."""

    data: bytes | memoryview
    file_offset: int  # offset of the Chunk record in the file
    indexes: list[tuple[int, int, int]]  # (channel id, file offset of 1st entry, entries)
    partial: bool = False  # cut by the end of the file


@dataclass
class _Block:
    """Message records of accepted channels in one buffer (a chunk or the file itself)."""

    buf: bytes | memoryview
    offsets: np.ndarray  # int64, record starts in buf, file order
    lengths: np.ndarray  # int64, record body lengths
    channels: np.ndarray  # uint16
    file_offset: int  # where the buffer comes from in the file (for reports)


class _Scanner:
    """Walk one file's records, tolerate damage and yield :class:`_Block` s."""

    def __init__(
        self,
        path: Path,
        accept: Callable[[_Channel], bool],
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
        self.summary_channels: dict[int, tuple[int, str, str]] = {}  # id -> schema, topic, enc
        self.channels: dict[int, _Channel] = {}
        self.accepted: set[int] = set()
        self.topic_names: list[str] = []  # accepted channel -> topic index
        self.topic_index: dict[str, int] = {}
        self.topic_lut = np.full(1 << 16, -1, np.int64)  # accepted channel id -> topic index
        self.known_lut = np.zeros(1 << 16, bool)  # channel id seen
        self.unknown: dict[int, tuple[int, int]] = {}  # channel id -> (count, first offset)
        self.stats_counts: dict[int, int] | None = None
        self._top_messages: list[int] = []
        self._recovered = 0
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
        schema_id, name = _parse_schema(buf, pos, end)
        self.schemas[schema_id] = name
        if self.on_definition is not None:
            self.on_definition(_OP_SCHEMA, buf, pos, end)

    def _add_channel(self, buf: bytes | memoryview, pos: int, end: int) -> None:
        self._register(*_parse_channel(buf, pos, end))
        if self.on_definition is not None:
            self.on_definition(_OP_CHANNEL, buf, pos, end)

    def _register(self, channel_id: int, schema_id: int, topic: str, encoding: str) -> None:
        """Make a channel known; the data section's definition wins over the summary's."""
        if channel_id in self.channels:
            return
        if schema_id == 0:
            schema_name = ''
        else:
            schema_name = self.schemas.get(schema_id, self.summary_schemas.get(schema_id, ''))
        channel = _Channel(channel_id, topic, encoding, schema_id, schema_name)
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
        op, length = _RECORD_HEAD.unpack_from(data, footer_at)
        if op != _OP_FOOTER or length != 20:
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
            op, length = _RECORD_HEAD.unpack_from(data, pos)
            body, end = pos + 9, pos + 9 + length
            if end > footer_at:
                break
            try:
                if op == _OP_SCHEMA:
                    schema_id, name = _parse_schema(data, body, end)
                    self.summary_schemas[schema_id] = name
                elif op == _OP_CHANNEL:
                    channel_id, *rest = _parse_channel(data, body, end)
                    self.summary_channels[channel_id] = tuple(rest)  # type: ignore[assignment]
                elif op == _OP_STATISTICS:
                    self.stats_counts = _statistics_counts(data, body, end)
            except _BadRecord as exc:
                self.skip(pos, 'corrupt_region', f'unreadable summary record: {exc}')
            pos = end

    # -- main walk
    def blocks(self) -> Iterator[_Block]:
        """Yield the accepted message records of the file in file order, batch by batch."""
        data = self.data
        n = len(data)
        if n < len(MAGIC) or data[: len(MAGIC)] != MAGIC:
            if MAGIC.startswith(data[: len(MAGIC)]):
                self.skip(0, 'truncated', f'file ends after {n} byte(s), inside the magic')
                return
            if not _looks_like_header(data):
                raise McapReadError(f'{self.path} is not an MCAP file (bad magic)')
            self.skip(0, 'corrupt_region', 'damaged magic bytes before a valid Header record')
        self._read_summary()
        batch: list[_Piece] = []
        batch_bytes = 0
        pos = len(MAGIC)
        while pos < n:
            self.position = pos
            if pos + 9 > n:
                self.skip(pos, 'truncated', f'file ends inside a record header ({n - pos} B)')
                break
            op, length = _RECORD_HEAD.unpack_from(data, pos)
            end = pos + 9 + length
            if op not in _KNOWN_OPS and op < 0x80:
                pos = self._resync(pos, f'invalid record opcode 0x{op:02x}')
                continue
            if end > n:
                # Either the writer was killed inside this record (nothing valid follows) or
                # its length field is damaged (a valid chunk follows somewhere).
                if self.file_report.finished or _find_chunk(data, pos + 1) >= 0:
                    pos = self._resync(
                        pos,
                        f'record (opcode 0x{op:02x}) of {length} B runs '
                        'past the end of the file',
                    )
                    continue
                recovered = ''
                if op == _OP_CHUNK:
                    self.cut_chunk_at = pos
                    yield from self._flush_top()
                    yield from self._flush_batch(batch)
                    batch = []
                    yield from self._cut_chunk(pos)
                    recovered = (
                        f'; {self._recovered} message record(s) recovered from the cut '
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
            if op == _OP_CHUNK:
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
            if batch and op in (_OP_MESSAGE, _OP_SCHEMA, _OP_CHANNEL):
                # Keep file order: the batched chunks may define what this record uses.
                yield from self._flush_batch(batch)
                batch, batch_bytes = [], 0
            try:
                if op == _OP_MESSAGE:
                    self._top_messages.append(pos)
                    if len(self._top_messages) >= _TOP_GROUP:
                        yield from self._flush_top()
                elif op == _OP_SCHEMA:
                    self._add_schema(data, body, end)
                elif op == _OP_CHANNEL:
                    self._add_channel(data, body, end)
                elif op in (_OP_METADATA, _OP_ATTACHMENT) and self.on_record is not None:
                    self.on_record(op, data, body, end)
                elif op == _OP_HEADER:
                    self.file_report.profile, _ = _string(data, body, end)
                elif op == _OP_FOOTER or op == _OP_DATA_END:
                    break  # the summary section was read (CRC-checked) by _read_summary
            except _BadRecord as exc:
                self.skip(pos, 'corrupt_region', f'unreadable record (opcode 0x{op:02x}): {exc}')
            pos = end
        yield from self._flush_batch(batch)
        yield from self._flush_top()

    def _flush_top(self) -> Iterator[_Block]:
        """Yield unchunked top-level messages collected so far (``fastwrite`` files)."""
        if not self._top_messages:
            return
        offsets = np.asarray(self._top_messages, dtype=np.int64)
        self._top_messages = []
        block = self._select(self.data, offsets, int(offsets[0]))
        if block is not None:
            yield block
        _release(self.data, int(offsets[0]))

    def _flush_batch(self, pieces: list[_Piece]) -> Iterator[_Block]:
        if not pieces:
            return
        buf, offsets = self._locate_messages(pieces)
        block = self._select(buf, offsets, pieces[0].file_offset)
        if block is not None:
            yield block
        _release(self.data, pieces[0].file_offset)

    def _resync(self, pos: int, reason: str) -> int:
        """Skip a damaged region: continue at the next plausible Chunk record."""
        found = _find_chunk(self.data, pos + 1)
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
            op, length = _RECORD_HEAD.unpack_from(data, pos)
            if op != _OP_MESSAGE_INDEX or pos + 9 + length > n or length < 6:
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

    def _chunk(self, pos: int, end: int) -> tuple[int, _Piece | None]:
        data = self.data
        after, indexes = self._message_indexes(end)
        header = _chunk_header(data, pos + 9, end)
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
        return after, _Piece(records, pos, indexes)

    def _streamed(self, pos: int, end: int) -> bool:
        """Whether the Chunk record at ``pos`` declares more than :data:`WHOLE_CHUNK_BYTES`
        uncompressed (decoded in pieces, never whole)."""
        header = _chunk_header(self.data, pos + 9, end)
        return header is not None and header[0] > WHOLE_CHUNK_BYTES

    def _big_chunk(self, pos: int, end: int) -> Generator[_Block, None, int]:
        """A chunk too large to hold, in bounded memory: checked in a first streaming pass
        (decodes to exactly its size, CRC), then decoded again and walked piece by piece
        (:meth:`_walk_pieces`). Returns where the file's walk goes on."""
        data = self.data
        after, indexes = self._message_indexes(end)
        header = _chunk_header(data, pos + 9, end)
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

    def _cut_chunk(self, pos: int) -> Iterator[_Block]:
        """The decodable start of a chunk cut by the end of the file (walked, not indexed; no
        CRC to check), decoded and walked piece by piece."""
        data = self.data
        self._recovered = 0
        header = _chunk_header(data, pos + 9, len(data), partial=True)
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
        _, self._recovered = yield from self._walk_pieces(pieces, pos, usize, True)
        if self._recovered:
            self.file_report.chunks += 1

    def _walk_pieces(
        self, pieces: Iterator[bytes | memoryview], pos: int, size: int, cut: bool
    ) -> Generator[_Block, None, tuple[int, int]]:
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
        if op in (_OP_MESSAGE, _OP_SCHEMA, _OP_CHANNEL):
            what = {_OP_MESSAGE: 'Message', _OP_SCHEMA: 'Schema', _OP_CHANNEL: 'Channel'}[op]
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
                out = np.empty(min((end - pos) // _MESSAGE_MIN + 1, 1 << 20), np.int64)
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
            op, length = _RECORD_HEAD.unpack_from(buf, pos)
            try:  # a Schema or Channel record
                if op == _OP_SCHEMA:
                    self._add_schema(buf, pos + 9, pos + 9 + length)
                else:
                    self._add_channel(buf, pos + 9, pos + 9 + length)
            except _BadRecord:
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
        unpack = _RECORD_HEAD.unpack_from
        arr = np.frombuffer(buf, np.uint8)
        found: list[int] = []
        last: tuple[int, int] = (-1, -1)
        while pos + 9 <= end:
            op, length = unpack(buf, pos)
            stop = pos + 9 + length
            if stop > end or op == 0 or (op not in _KNOWN_OPS and op < 0x80):
                break
            if op == _OP_SCHEMA or op == _OP_CHANNEL:
                parts.append(np.asarray(found, np.int64))
                return pos, True
            if op == _OP_MESSAGE and length < 22:
                break
            if (op, length) == last:
                run = _equal_run(arr, pos, end, 9 + length)
                if op == _OP_MESSAGE:
                    parts.append(np.asarray(found, np.int64))
                    parts.append(pos + (9 + length) * np.arange(run, dtype=np.int64))
                    found = []
                pos += run * (9 + length)
                continue
            if op == _OP_MESSAGE:
                found.append(pos)
            last = (op, length)
            pos = stop
        parts.append(np.asarray(found, np.int64))
        return pos, False

    def _locate_messages(self, pieces: list[_Piece]) -> tuple[bytes | memoryview, np.ndarray]:
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
            off = _gather(self.data_arr, entry_at, 8).view('<u8').ravel()
            owner = table[which, 0]
            ok = off < sizes[owner].astype(np.uint64)
            off = np.where(ok, off, 0).astype(np.int64)
            ok &= off + _MESSAGE_MIN <= sizes[owner]
            g = np.where(ok, starts[owner] + off, 0)
            if len(arr) >= _MESSAGE_MIN:
                head = _gather(arr, np.minimum(g, len(arr) - _MESSAGE_MIN), 11)
                ok &= head[:, 0] == _OP_MESSAGE
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
        pieces: list[_Piece],
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

    def _unreadable(self, piece: _Piece, stop: int, size: int) -> None:
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
    ) -> _Block | None:
        """Keep the message records of accepted channels; count unknown channels."""
        if len(offsets) == 0:
            return None
        arr = np.frombuffer(buf, np.uint8)
        channels = _gather(arr, offsets + 9, 2).view('<u2').ravel()
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
        lengths = _gather(arr, offsets + 1, 8).view('<u8').ravel().astype(np.int64)
        return _Block(buf, offsets, lengths, channels, file_offset)


# ---------------------------------------------------------------------------- record helpers
def _string(buf: bytes | memoryview, pos: int, end: int) -> tuple[str, int]:
    """Read a uint32-length-prefixed UTF-8 string; return it and the position after it."""
    if pos + 4 > end:
        raise _BadRecord('string length runs past its record')
    (length,) = struct.unpack_from('<I', buf, pos)
    stop = pos + 4 + length
    if stop > end:
        raise _BadRecord(f'string of {length} B runs past its record')
    return bytes(buf[pos + 4 : stop]).decode('utf-8', 'replace'), stop


def _parse_schema(buf: bytes | memoryview, pos: int, end: int) -> tuple[int, str]:
    """(schema id, name) of a Schema record body."""
    if end - pos < 2 + 4 + 4 + 4:
        raise _BadRecord(f'Schema record of {end - pos} B is too short')
    (schema_id,) = struct.unpack_from('<H', buf, pos)
    name, p = _string(buf, pos + 2, end)
    _string(buf, p, end)  # encoding
    return schema_id, name


def _parse_channel(buf: bytes | memoryview, pos: int, end: int) -> tuple[int, int, str, str]:
    """(channel id, schema id, topic, message encoding) of a Channel record body."""
    if end - pos < 4 + 4 + 4 + 4:
        raise _BadRecord(f'Channel record of {end - pos} B is too short')
    channel_id, schema_id = struct.unpack_from('<HH', buf, pos)
    topic, p = _string(buf, pos + 4, end)
    encoding, _ = _string(buf, p, end)
    return channel_id, schema_id, topic, encoding


def not_mcap(path: Path) -> Optional[str]:
    """Why ``path`` cannot be an MCAP file at all (its reader's own rule: neither the magic,
    nor a prefix of it, nor damaged magic before a Header record), else None; a file cut
    inside the magic (an empty one too) counts as a damaged log, not as another format."""
    try:
        with open(path, 'rb') as f:
            head = f.read(4096)
    except OSError:
        return None  # unreadable: the reader says how
    if head[: len(MAGIC)] == MAGIC or MAGIC.startswith(head) or _looks_like_header(head):
        return None
    return f'{path} is not an MCAP file (bad magic)'


def _looks_like_header(data: bytes) -> bool:
    """True if a Header record (two strings filling its length) follows the 8 magic bytes."""
    if len(data) < len(MAGIC) + 9 + 8:
        return False
    op, length = _RECORD_HEAD.unpack_from(data, len(MAGIC))
    body, end = len(MAGIC) + 9, len(MAGIC) + 9 + length
    if op != _OP_HEADER or end > len(data):
        return False
    try:
        _, p = _string(data, body, end)
        _, p = _string(data, p, end)
    except _BadRecord:
        return False
    return p == end


def _statistics_counts(buf: bytes, pos: int, end: int) -> dict[int, int] | None:
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


def _chunk_header(
    data: bytes, body: int, end: int, partial: bool = False
) -> tuple[int, int, str, int, int] | None:
    """Parse a Chunk body; return (uncompressed size, crc, compression, records start, end)."""
    if body + _CHUNK_HEAD.size > len(data):
        return None
    _, _, usize, crc, comp_len = _CHUNK_HEAD.unpack_from(data, body)
    p = body + _CHUNK_HEAD.size
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


def _find_chunk(data: bytes, start: int) -> int:
    """Offset of the next byte sequence that parses as a complete, consistent Chunk record."""
    n = len(data)
    pos = data.find(b'\x06', start)
    while 0 <= pos and pos + 9 <= n:
        _, length = _RECORD_HEAD.unpack_from(data, pos)
        end = pos + 9 + length
        if end <= n and length >= _CHUNK_HEAD.size + 8:
            header = _chunk_header(data, pos + 9, end)
            if header is not None and header[2] in ('', 'zstd', 'lz4'):
                return pos
        pos = data.find(b'\x06', pos + 1)
    return -1


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
    op, length = _RECORD_HEAD.unpack_from(buf, at)
    if op == 0 or (op not in _KNOWN_OPS and op < 0x80) or (op == _OP_MESSAGE and length < 22):
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


def _gather(arr: np.ndarray, positions: np.ndarray, width: int) -> np.ndarray:
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
    block: _Block, topic_lut: np.ndarray
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
    rows = _gather(arr, offsets, _FLOAT64_RECORD).view(_FLOAT64_ROW).ravel()
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


def _unique(items: Iterable[str]) -> list[str]:
    if isinstance(items, str):
        items = [items]
    out: list[str] = []
    for item in items:
        if item not in out:
            out.append(item)
    return out


def expand_paths(paths: PathLike | Iterable[PathLike]) -> list[Path]:
    """MCAP files named by ``paths``: files as given, directories as their sorted ``*.mcap``."""
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    out: list[Path] = []
    for p in paths:
        path = Path(p)
        if path.is_dir():
            out.extend(sorted(path.glob('*.mcap')))
        elif path.exists():
            out.append(path)
        else:
            raise FileNotFoundError(f'no such MCAP file or directory: {path}')
    return out


# ---------------------------------------------------------------------------- streaming
#: Windows' worth of messages that may wait at one log time (the node's stamps are distinct;
#: a flood of messages of one stamp is refused, not held).
FLOOD_WINDOWS = 4


class LogFloodError(McapReadError):
    """More messages share a log time than :data:`FLOOD_WINDOWS` windows hold."""


class UnorderedLogError(McapReadError):
    """A message arrived with a log time before a window already handed out (the files, or
    the chunks of a file, overlap in time): the log cannot be streamed in windows."""


@dataclass
class FileBlocks:
    """One batch of a file as columns: ``columns`` (Float64 topic -> (log_time_ns, value), file
    order), ``raw`` (raw topic -> list of (log_time_ns, CDR bytes)), where the file's walk is
    (``position``, B) and the file's index in the set."""

    columns: dict[str, tuple[np.ndarray, np.ndarray]]
    raw: dict[str, list[tuple[int, bytes]]]
    position: int
    file: int


def _float64_accept(
    wanted: set[str], raw: set[str], path: str, typed: Optional[dict[str, str]] = None
) -> Callable[[_Channel], bool]:
    def accept(channel: _Channel) -> bool:
        if channel.topic in raw:
            expected = (typed or {}).get(channel.topic)
            if expected is not None and (
                channel.schema_name != expected or channel.encoding != 'cdr'
            ):
                shown = channel.schema_name or '<no schema>'
                raise TopicTypeError(channel.topic, shown, expected, path)
            return True
        if channel.topic not in wanted:
            return False
        if channel.schema_name != FLOAT64_TYPE or channel.encoding != 'cdr':
            shown = channel.schema_name or '<no schema>'
            if channel.encoding != 'cdr':
                shown += f' (message encoding {channel.encoding!r})'
            raise TopicTypeError(channel.topic, shown, FLOAT64_TYPE, path)
        return True

    return accept


def iter_file_blocks(
    path: Path,
    index: int,
    topics: list[str],
    raw_topics: list[str],
    report: ReadReport,
    batch_bytes: int | None = None,
    typed: Optional[dict[str, str]] = None,
) -> Iterator[FileBlocks]:
    """The batches of one file (file order) as :class:`FileBlocks`: the Float64 ``topics``
    decoded into columns, the ``raw_topics`` as bytes (of the type ``typed`` names for a
    topic, else any); damage goes to ``report`` exactly as :func:`read_float64_topics`
    reports it."""
    raw_set = set(raw_topics)
    accept = _float64_accept(set(topics), raw_set, str(path), typed)
    scanner = _Scanner(path, accept, report, frozenset(raw_set))
    if batch_bytes is not None:
        scanner.batch_bytes = min(scanner.batch_bytes, batch_bytes)
    for block in scanner.blocks():
        names = scanner.topic_names
        raw_ids = [i for i, name in enumerate(names) if name in raw_set]
        raw: dict[str, list[tuple[int, bytes]]] = {}
        if raw_ids:
            rows = scanner.topic_lut[block.channels]
            is_raw = np.isin(rows, raw_ids)
            if is_raw.any():
                buf = block.buf
                # Not even a CDR encapsulation header: damage, counted without a Python step
                # each (a chunk of millions of empty records costs one numpy pass).
                empty = is_raw & (block.lengths < 22 + _CDR_HEADER)
                if empty.any():
                    scanner.bad_payload(
                        block.file_offset, int(np.count_nonzero(empty)), 'too short to be CDR'
                    )
                    is_raw &= ~empty
                for off, length in zip(
                    block.offsets[is_raw].tolist(), block.lengths[is_raw].tolist()
                ):
                    channel_id, _, log_time, _ = _MESSAGE_HEAD.unpack_from(buf, off + 9)
                    topic = scanner.channels[channel_id].topic
                    raw.setdefault(topic, []).append(
                        (log_time, bytes(buf[off + _MESSAGE_MIN : off + 9 + length]))
                    )
                keep = ~(is_raw | empty)
                block = _Block(
                    block.buf,
                    block.offsets[keep],
                    block.lengths[keep],
                    block.channels[keep],
                    block.file_offset,
                )
        columns = _block_columns(scanner, block) if len(block.offsets) else {}
        yield FileBlocks(columns, raw, scanner.position, index)
    scanner.finish()


def _block_columns(scanner: '_Scanner', block: '_Block') -> Columns:
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


def _decode_file(
    args: tuple[str, int, list[str], list[str], int | None, Optional[dict[str, str]]]
) -> tuple[list[FileBlocks], ReadReport, tuple[str, tuple[Any, ...]] | None]:
    """Worker of ``jobs > 1``: a whole file's batches, its report, or the error it raised."""
    path, index, topics, raw_topics, batch, typed = args
    report = ReadReport()
    try:
        blocks = list(
            iter_file_blocks(Path(path), index, topics, raw_topics, report, batch, typed)
        )
    except TopicTypeError as err:
        return [], report, ('type', (err.topic, err.type_name, err.expected, err.path))
    except McapReadError as err:
        return [], report, ('read', (str(err),))
    return blocks, report, None


def _merge_report(into: ReadReport, part: ReadReport) -> None:
    into.files += part.files
    into.skips += part.skips
    for topic, n in part.messages.items():
        into.messages[topic] = into.messages.get(topic, 0) + n


def _parallel_blocks(
    paths: list[Path],
    topics: list[str],
    raw_topics: list[str],
    report: ReadReport,
    jobs: int,
    batch: int | None,
    typed: Optional[dict[str, str]] = None,
) -> Iterator[FileBlocks]:
    """:func:`iter_file_blocks` of every file, decoded by ``jobs`` worker processes (at most
    ``jobs + 1`` files in flight), handed on in file order."""
    import multiprocessing

    ctx = multiprocessing.get_context('spawn' if os.name != 'posix' else 'forkserver')
    with ctx.Pool(jobs) as pool:
        pending: list[Any] = []
        todo = iter(enumerate(paths))

        def submit() -> None:
            nxt = next(todo, None)
            if nxt is not None:
                task = (str(nxt[1]), nxt[0], topics, raw_topics, batch, typed)
                pending.append(pool.apply_async(_decode_file, (task,)))

        for _ in range(jobs + 1):
            submit()
        while pending:
            blocks, part, error = pending.pop(0).get()
            submit()
            _merge_report(report, part)
            if error is not None:
                if error[0] == 'type':
                    raise TopicTypeError(*error[1])
                raise McapReadError(*error[1])
            yield from blocks


@dataclass
class LogWindow:
    """A stretch of the log in time: every message with ``lo <= log time < hi`` of all the
    files (``hi`` None: up to the end; ``final`` for the last window). ``columns``: Float64
    topic -> (log_time_ns, value) sorted (stable: file order at equal stamps); ``raw``: raw
    topic -> (log_time_ns array, list of CDR bytes), sorted alike; ``bytes_done``: bytes of the
    files walked so far (for progress)."""

    columns: dict[str, tuple[np.ndarray, np.ndarray]]
    raw: dict[str, tuple[np.ndarray, list[bytes]]]
    hi: int | None
    final: bool
    bytes_done: int
    messages: int


class _Pending:
    """Messages read but not handed out yet, per topic, in read order."""

    def __init__(self, topics: list[str], raw_topics: list[str]) -> None:
        self.times: dict[str, list[np.ndarray]] = {t: [] for t in topics}
        self.values: dict[str, list[np.ndarray]] = {t: [] for t in topics}
        self.raw: dict[str, list[tuple[int, bytes]]] = {t: [] for t in raw_topics}
        self.count = 0

    def add(self, blocks: FileBlocks) -> int | None:
        """Take a batch; return its earliest log time (None: empty)."""
        low = None
        for topic, (t, v) in blocks.columns.items():
            if len(t):
                self.times[topic].append(t)
                self.values[topic].append(v)
                self.count += len(t)
                m = int(t.min())
                low = m if low is None else min(low, m)
        for topic, items in blocks.raw.items():
            if items:
                self.raw[topic] += items
                self.count += len(items)
                m = min(t for t, _ in items)
                low = m if low is None else min(low, m)
        return low

    def at(self, stamp: int) -> int:
        """How many waiting messages have log time ``stamp``."""
        n = sum(int(np.count_nonzero(t == stamp)) for parts in self.times.values() for t in parts)
        return n + sum(1 for items in self.raw.values() for t, _ in items if t == stamp)

    def take(self, hi: int | None) -> tuple[dict[str, Any], dict[str, Any], int]:
        """Hand out every message before ``hi`` (all with None), sorted by time (stable)."""
        columns: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        taken = 0
        for topic in self.times:
            parts_t, parts_v = self.times[topic], self.values[topic]
            t = np.concatenate(parts_t) if parts_t else np.empty(0, np.int64)
            v = np.concatenate(parts_v) if parts_v else np.empty(0, np.float64)
            if len(t) > 1 and not np.all(t[1:] >= t[:-1]):
                order = np.argsort(t, kind='stable')
                t, v = t[order], v[order]
            cut = len(t) if hi is None else int(np.searchsorted(t, hi, 'left'))
            columns[topic] = (t[:cut], v[:cut])
            self.times[topic] = [t[cut:]] if cut < len(t) else []
            self.values[topic] = [v[cut:]] if cut < len(t) else []
            taken += cut
        raw: dict[str, tuple[np.ndarray, list[bytes]]] = {}
        for topic, items in self.raw.items():
            items.sort(key=lambda item: item[0])  # stable: file order at equal stamps
            cut = len(items) if hi is None else next(
                (i for i, (t, _) in enumerate(items) if t >= hi), len(items)
            )
            raw[topic] = (
                np.array([t for t, _ in items[:cut]], np.int64),
                [d for _, d in items[:cut]],
            )
            self.raw[topic] = items[cut:]
            taken += cut
        self.count -= taken
        return columns, raw, taken


def iter_windows(
    paths: PathLike | Iterable[PathLike],
    topics: Iterable[str],
    raw_topics: Iterable[str] = (),
    window_messages: int | None = 1 << 18,
    report: ReadReport | None = None,
    jobs: int = 1,
    typed: Optional[dict[str, str]] = None,
    allow_empty: bool = False,
) -> Iterator[LogWindow]:
    """Stream a log (one file, a rotated set, directories) as :class:`LogWindow` s in time
    order, merged across topics and files, each of about ``window_messages`` messages (None:
    one window, the whole log).

    Files are walked in the order of their first message (a rotated set in any order); a
    window ends at the earliest log time of the newest batch read, so every message of a
    window precedes every later one. Messages come out exactly as :func:`read_float64_topics`
    sorts them (stable on time, file order at equal stamps); a log whose files or chunks overlap
    in time so much that a message comes after its window was handed out raises
    :class:`UnorderedLogError` (read it with ``window_messages=None``). ``jobs > 1`` decodes
    files in that many worker processes (the hand-out stays in order). ``typed``: raw topics
    that are inputs of a given type (``topic -> type name``; e.g. a stamped sensor message):
    their type is checked as the Float64 topics' is, and they count as inputs (the report's
    messages, EmptyLogError). Raises as :func:`read_float64_topics` (TopicTypeError,
    EmptyLogError at the end, McapReadError); ``allow_empty``: a log without any input message
    is one final window of what it has (a piece of a longer log: its raw topics may matter).
    """
    typed = dict(typed or {})
    wanted = [t for t in _unique(topics) if t not in typed]
    raw_wanted = [t for t in _unique([*raw_topics, *typed]) if t not in wanted]
    inputs = wanted + list(typed)
    if not inputs:
        raise ValueError('topics must name at least one topic')
    report = ReadReport() if report is None else report
    files = order_by_start(expand_paths(paths))
    sizes = [p.stat().st_size for p in files]
    done_before = [sum(sizes[:i]) for i in range(len(files))]
    pending = _Pending(wanted, raw_wanted)
    handed: int | None = None  # every message before this was handed out
    counts = {t: 0 for t in inputs}
    # reader batches of about a window (43 B per Float64 record decompressed)
    batch = None if window_messages is None else max(1 << 16, 40 * window_messages)
    if jobs > 1 and len(files) > 1:
        source: Iterator[FileBlocks] = _parallel_blocks(
            files, wanted, raw_wanted, report, jobs, batch, typed
        )
    else:
        source = _read_ahead(
            b
            for i, p in enumerate(files)
            for b in iter_file_blocks(p, i, wanted, raw_wanted, report, batch, typed)
        )
    for blocks in source:
        low = pending.add(blocks)
        if low is None:
            continue
        if handed is not None and low < handed:
            raise UnorderedLogError(
                f'{files[blocks.file]}: a message at {low} ns comes after the window that '
                f'ended at {handed} ns was handed out (files or chunks overlap in time)'
            )
        if window_messages is not None and pending.count >= window_messages:
            columns, raw, n = pending.take(low)
            handed = low
            if not n:
                if pending.count > FLOOD_WINDOWS * window_messages:
                    same = pending.at(low)
                    if same > FLOOD_WINDOWS * window_messages:
                        raise LogFloodError(
                            f'{files[blocks.file]}: {same} messages share log time {low} ns, '
                            f'more than {FLOOD_WINDOWS} windows of {window_messages}, and a '
                            'window cannot end between messages of one stamp: not a log '
                            'replay can stream in bounded memory'
                        )
                continue
            _count(counts, columns, raw)
            done = done_before[blocks.file] + blocks.position
            yield LogWindow(columns, raw, low, False, done, n)
    columns, raw, n = pending.take(None)
    _count(counts, columns, raw)
    _reorder_report(report, [str(p) for p in expand_paths(paths)])
    for topic in inputs:
        report.messages[topic] = counts[topic]
        if counts[topic] == 0:
            report.missing_topics.append(topic)
    if all(counts[t] == 0 for t in inputs) and not allow_empty:
        raise EmptyLogError(inputs, report)
    yield LogWindow(columns, raw, None, True, sum(sizes), n)


def _count(counts: dict[str, int], columns: dict[str, Any], raw: dict[str, Any]) -> None:
    """Add a window's messages per input topic (Float64 columns and typed raw topics)."""
    for topic in counts:
        if topic in columns:
            counts[topic] += len(columns[topic][0])
        elif topic in raw:
            counts[topic] += len(raw[topic][0])


#: Batches a reader thread may decode ahead of the windows handed out (0: no thread).
READ_AHEAD = 1


def _read_ahead(source: Iterator[FileBlocks]) -> Iterator[FileBlocks]:
    """``source``'s batches, in order, decoded up to :data:`READ_AHEAD` batches ahead by a
    thread of this process: the next batch is decompressed (zstd and the CRC run without the
    GIL) while the caller recomputes the last window. Its errors are raised here, at the batch
    where they occurred; when the caller stops early, the thread stops after its batch."""
    if READ_AHEAD <= 0:
        yield from source
        return
    slots: queue.Queue[tuple[bool, Any]] = queue.Queue(maxsize=READ_AHEAD)
    stop = threading.Event()
    end = object()

    def put(item: tuple[bool, Any]) -> bool:
        while not stop.is_set():
            try:
                slots.put(item, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def run() -> None:
        try:
            for blocks in source:
                if not put((True, blocks)):
                    return
            put((True, end))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller, raised there
            put((False, exc))

    thread = threading.Thread(target=run, name='mcap-read-ahead', daemon=True)
    thread.start()
    try:
        while True:
            ok, item = slots.get()
            if not ok:
                raise item
            if item is end:
                return
            yield item
    finally:
        stop.set()
        thread.join()


def _reorder_report(report: ReadReport, given: list[str]) -> None:
    """Files and skips in the order the paths were given (as :func:`read_float64_topics`)."""
    rank = {p: i for i, p in enumerate(given)}
    report.files.sort(key=lambda f: rank.get(f.path, len(rank)))
    report.skips.sort(key=lambda s: rank.get(s.path, len(rank)))


def first_log_time(path: Path) -> int | None:
    """The earliest log time a file declares (its Statistics, else its first Chunk or Message
    record in the first MiB), None if none is found: for ordering a rotated set."""
    try:
        with open(path, 'rb') as f:
            head = f.read(1 << 20)
    except OSError:
        return None
    pos = len(MAGIC)
    while pos + 9 <= len(head):
        op, length = _RECORD_HEAD.unpack_from(head, pos)
        if op == _OP_CHUNK and pos + 9 + 16 <= len(head):
            start, end = struct.unpack_from('<QQ', head, pos + 9)
            if start or end:
                return int(start)
        if op == _OP_MESSAGE and pos + 9 + 22 <= len(head):
            return int(struct.unpack_from('<Q', head, pos + 9 + 6)[0])
        if op not in _KNOWN_OPS or length > len(head):
            return None
        pos += 9 + length
    return None


def order_by_start(paths: list[Path]) -> list[Path]:
    """Files in the order of their first log time (stable; files without one keep their
    place after the others): a rotated set given in any order is read in time order."""
    keyed = [(first_log_time(p), i, p) for i, p in enumerate(paths)]
    if all(k is not None for k, _, _ in keyed):
        return [p for _, _, p in sorted(keyed, key=lambda k: (k[0], k[1]))]
    return list(paths)
