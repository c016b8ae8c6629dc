"""Fast, damage-tolerant reading of ROS 2 MCAP logs for replay (no rclpy).

Three entry points:

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

Both accept the node's own logs (:mod:`catenary_monitor.io.mcap_log`), rotated sets and files
written by rosbag2's MCAP storage plugin (zstd, lz4 or uncompressed chunks, chunk CRCs on or
off, unchunked ``fastwrite`` files, with or without message indexes and summary).

Damage handling. Nothing readable is thrown away, and nothing unreadable is silent:

* a file cut short (writer killed: no summary, last chunk or record cut) gives every complete
  chunk, plus the complete records of a cut chunk that can be decompressed up to the cut;
* a corrupt chunk (CRC mismatch, undecompressable data, inconsistent records) is skipped;
  the number of requested-topic messages in it is reported when the Message Index records
  after it survive;
* a corrupt region between records is skipped by searching for the next valid Chunk record.

Each skip is a :class:`~catenary_monitor.io.mcap_scan.Skip` in the
:class:`~catenary_monitor.io.mcap_scan.ReadReport`. The mcap library's own reader is used
as the independent oracle in the tests; its ``NonSeekingReader`` stops at the first damaged
record, which is why the reader has its own scanner (:mod:`catenary_monitor.io.mcap_scan`;
the record format: :mod:`catenary_monitor.io.mcap_records`).

Time stamps are MCAP ``log_time`` (ns; the receive time for rosbag2 and for the node's logger).
"""

from __future__ import annotations

import os
import queue
import struct
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, NamedTuple, Optional, Union

import numpy as np

from catenary_monitor.io.mcap_records import (
    KNOWN_OPS,
    MAGIC,
    MESSAGE_HEAD,
    MESSAGE_MIN,
    OP_CHUNK,
    OP_MESSAGE,
    RECORD_HEAD,
    looks_like_header,
)
from catenary_monitor.io.mcap_scan import (
    Block,
    Channel,
    Columns,
    McapReadError,
    ReadReport,
    Scanner,
    block_columns,
)

__all__ = [
    'FLOAT64_TYPE',
    'EmptyLogError',
    'RawMessage',
    'TopicTypeError',
    'iter_messages',
    'iter_windows',
    'read_float64_topics',
]

#: Schema name required by :func:`read_float64_topics`.
FLOAT64_TYPE = 'std_msgs/msg/Float64'

_CDR_HEADER = 4  # B: every CDR payload starts with its encapsulation header

PathLike = Union[str, 'os.PathLike[str]']


# ---------------------------------------------------------------------------- public types
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


class RawMessage(NamedTuple):
    """One message as stored: CDR bytes plus its MCAP envelope."""

    topic: str
    log_time_ns: int
    schema_name: str
    data: bytes
    publish_time_ns: int
    sequence: int


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

        def accept(channel: Channel, path: str = str(path)) -> bool:
            if channel.topic not in wanted_set:
                return False
            if channel.schema_name != FLOAT64_TYPE or channel.encoding != 'cdr':
                shown = channel.schema_name or '<no schema>'
                if channel.encoding != 'cdr':
                    shown += f' (message encoding {channel.encoding!r})'
                raise TopicTypeError(channel.topic, shown, FLOAT64_TYPE, path)
            return True

        scanner = Scanner(path, accept, report)
        for block in scanner.blocks():
            for topic, (t, v) in block_columns(scanner, block).items():
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

        def accept(channel: Channel) -> bool:
            return wanted is None or channel.topic in wanted

        scanner = Scanner(path, accept, report)
        unpack = MESSAGE_HEAD.unpack_from
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
                    bytes(buf[off + MESSAGE_MIN : off + 9 + length]),
                    publish_time,
                    sequence,
                )
        scanner.finish()


def not_mcap(path: Path) -> Optional[str]:
    """Why ``path`` cannot be an MCAP file at all (its reader's own rule: neither the magic,
    nor a prefix of it, nor damaged magic before a Header record), else None; a file cut
    inside the magic (an empty one too) counts as a damaged log, not as another format."""
    try:
        with open(path, 'rb') as f:
            head = f.read(4096)
    except OSError:
        return None  # unreadable: the reader says how
    if head[: len(MAGIC)] == MAGIC or MAGIC.startswith(head) or looks_like_header(head):
        return None
    return f'{path} is not an MCAP file (bad magic)'


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
) -> Callable[[Channel], bool]:
    def accept(channel: Channel) -> bool:
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
    scanner = Scanner(path, accept, report, frozenset(raw_set))
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
                    channel_id, _, log_time, _ = MESSAGE_HEAD.unpack_from(buf, off + 9)
                    topic = scanner.channels[channel_id].topic
                    raw.setdefault(topic, []).append(
                        (log_time, bytes(buf[off + MESSAGE_MIN : off + 9 + length]))
                    )
                keep = ~(is_raw | empty)
                block = Block(
                    block.buf,
                    block.offsets[keep],
                    block.lengths[keep],
                    block.channels[keep],
                    block.file_offset,
                )
        columns = block_columns(scanner, block) if len(block.offsets) else {}
        yield FileBlocks(columns, raw, scanner.position, index)
    scanner.finish()


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
        op, length = RECORD_HEAD.unpack_from(head, pos)
        if op == OP_CHUNK and pos + 9 + 16 <= len(head):
            start, end = struct.unpack_from('<QQ', head, pos + 9)
            if start or end:
                return int(start)
        if op == OP_MESSAGE and pos + 9 + 22 <= len(head):
            return int(struct.unpack_from('<Q', head, pos + 9 + 6)[0])
        if op not in KNOWN_OPS or length > len(head):
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
