"""ROS 2-profile MCAP logger: rotation, bounded loss on SIGKILL, no exceptions on disk errors.

The logger takes messages that are already serialized to CDR (``raw=True`` subscriptions or
``rclpy.serialization.serialize_message``) so this module never imports rclpy. Files open in
Foxglove and ``ros2 bag info/play``:

* header profile ``"ros2"`` (CONVENTIONS C11);
* one Schema per type: ``encoding="ros2msg"``, ``name="pkg/msg/Type"``, data = the concatenated
  ``.msg`` text rosbag2 writes (C12, :func:`catenary_monitor.io.ros_schemas.message_definition`);
* one Channel per topic: ``message_encoding="cdr"``, metadata ``offered_qos_profiles`` (rosbag2
  YAML, optional) and ``topic_type_hash`` when the ROS wheels provide it (C13);
* chunk compression only (zstd, lz4 or none), message indexes and the summary are kept (C16);
* metadata records added with :meth:`McapLogger.add_metadata` are repeated in every file (C15).

Crash safety (C17)
------------------
The mcap writer holds the open chunk in memory. The logger ends the chunk, flushes the file and
(by default) ``fsync``\\ s it as soon as the oldest unflushed message is ``flush_period`` seconds
old. The check runs in :meth:`McapLogger.write` and in :meth:`McapLogger.tick`; call ``tick()``
from a timer (period <= ``flush_period``) so that the last messages before a quiet spell are
flushed too. After a SIGKILL the file has no summary; :mod:`catenary_monitor.io.mcap_read` reads
every complete chunk of it. Call :meth:`McapLogger.close` from the node's ``finally:`` block
(SIGINT/SIGTERM) to write the summary.

Vanished or replaced file or directory
--------------------------------------
At every flush and every :meth:`tick` the logger compares the device and inode of the open
file's path and of ``log_dir`` with those it opened. A file or directory deleted, moved or
replaced under it sets :attr:`McapLogger.error` (held at least ``error_hold`` seconds, so a
status poll sees it), counts the messages of a deleted file as lost, and opens a new file at
once (``log_dir`` is recreated if ``create_dir``, else waited for). A file that was only moved
is finished with its summary where it went.

rosbag2 bag
-----------
With ``bag_metadata`` (the default) the folder is a rosbag2 bag: ``metadata.yaml``
(:mod:`catenary_monitor.io.bag_metadata`) is rewritten atomically whenever a file opens (so at
each rotation) and on :meth:`close`. It lists the folder's finished files only, so bag readers
open the folder at any time; the file being written joins it when it is finished.

Retention and free space
------------------------
With ``max_total_bytes`` and/or ``max_age`` (0: keep all), the logger deletes finished files
it wrote itself: a name ``<prefix>_<UTC stamp>_<index>.mcap`` and a Header whose library is this
module's (a user's ``storm_evidence_keep.mcap``, or a copy under another name, is neither
counted nor touched). Oldest first by the end time recorded in each file (its last message's
log time; the modification time when it has no summary), except that a file whose recorded end
lies more than :data:`FUTURE_SLACK` s ahead of the wall clock (written while the clock was wrong)
goes first: it is never kept ahead of the present. The size rule: once its files exceed
``max_total_bytes`` with the open one counted at the size it may reach before it rotates
(``max_bytes``, a sixteenth more for its summary); the age rule: a file last modified more than
``max_age`` seconds ago. The file being written is never touched, nor a file another process
holds locked (a second logger's open file). Each deletion is kept in :attr:`McapLogger.deleted`
(path, bytes, why) for the caller to report, and ``metadata.yaml`` is rewritten at once, so it
only ever lists files that exist. The check runs whenever a file is finished (in :meth:`write`
itself, so the bound holds between rotations however late the caller's timer runs) and every
``retention_period`` seconds in :meth:`tick`. With ``min_free_bytes``,
:attr:`McapLogger.warning` says so while the file system holds less than that free (checked as
often): a warning before anything is lost to a full disk.

Disk errors
-----------
No file-system error escapes: an unwritable directory, a full disk or a failing flush sets
:attr:`McapLogger.error` (a sentence for an ERROR diagnostic), counts the lost messages in
:attr:`McapLogger.dropped`, abandons the broken file and retries opening a new file every
``retry_period`` seconds. Mistakes in the call itself (unregistered topic, data that is not bytes,
negative time) raise ``ValueError`` / ``TypeError``.

Example
-------
>>> log = McapLogger('/var/log/dock', max_seconds=3600.0)          # doctest: +SKIP
>>> log.register('/chain_01/tension', 'std_msgs/msg/Float64')       # doctest: +SKIP
>>> log.write('/chain_01/tension', cdr_bytes, time.time_ns())       # doctest: +SKIP
>>> log.tick()              # from a 1 Hz timer                     # doctest: +SKIP
>>> log.close()             # in finally:                           # doctest: +SKIP
"""

from __future__ import annotations

import datetime as _dt
import os
import re
import struct
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import IO, Any, Callable, Mapping

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import LIBRARY_IDENTIFIER, CompressionType, IndexType, Writer

from catenary_monitor.io import bag_metadata as _bag
from catenary_monitor.io.mcap_finish import Definitions, finish_in_place
from catenary_monitor.io.ros_schemas import (
    QOS_DEFAULT,
    QOS_LATCHED,
    QOS_SENSOR_DATA,
    message_definition,
    type_description_hash,
)

__all__ = ['McapLogger', 'QOS_PRESETS', 'FUTURE_SLACK']

#: A finished file whose recorded end lies this far (s) ahead of the wall clock is dated in the
#: future (a clock error): the retention deletes it first.
FUTURE_SLACK = 600.0

#: Named QoS presets accepted by :meth:`McapLogger.register` (rosbag2 ``offered_qos_profiles``).
QOS_PRESETS: dict[str, str] = {
    'latched': QOS_LATCHED,
    'sensor_data': QOS_SENSOR_DATA,
    'default': QOS_DEFAULT,
}

_COMPRESSION = {
    'zstd': CompressionType.ZSTD,
    'lz4': CompressionType.LZ4,
    'none': CompressionType.NONE,
    '': CompressionType.NONE,
    None: CompressionType.NONE,
}
# No Attachment Index group (the logger writes no attachments): an empty group's Summary Offset
# is reported by pymcap-cli's doctor as pointing to a missing group.
_INDEX_TYPES = IndexType.CHUNK | IndexType.MESSAGE | IndexType.METADATA
_U64 = 1 << 64
_LIBRARY = f'catenary_monitor.io.mcap_log; {LIBRARY_IDENTIFIER}'
# Record overhead of one Message record in a chunk: opcode 1 + length 8 + header 22 bytes.
_MESSAGE_OVERHEAD = 31


@dataclass
class _Topic:
    type_name: str
    schema_text: bytes
    metadata: dict[str, str]
    sequence: int = 0
    channel_id: int = 0  # in the current file; 0 = not registered there yet


@dataclass
class _OpenFile:
    path: Path
    stream: IO[bytes]
    writer: Writer
    opened_at: float  # monotonic s
    dir_id: tuple[int, int] = (0, 0)  # (st_dev, st_ino) of log_dir when opened
    file_id: tuple[int, int] = (0, 0)  # (st_dev, st_ino) of the file
    schema_ids: dict[str, int] = field(default_factory=dict)
    messages: int = 0
    counts: dict[str, list[int]] = field(default_factory=dict)  # topic -> [messages, bytes]


class McapLogger:
    """Write CDR messages to rotating ROS 2-profile MCAP files.

    The first file is opened by the constructor (so an unwritable ``log_dir`` shows in
    :attr:`ok` / :attr:`error` at once); no file-system error is ever raised.

    Parameters
    ----------
    log_dir
        Directory for the files; created if missing.
    prefix
        File name prefix. Files are named ``<prefix>_<UTC YYYYmmddTHHMMSSZ>_<index>.mcap``; the
        index counts the files of this logger (0000, 0001, ...).
    max_bytes
        Rotate once the current file has about this many bytes (B). Must be > 0.
    max_seconds
        Rotate once the current file has been open this long (s, monotonic clock). Must be > 0.
    flush_period
        Largest age (s) of a message that may still be only in memory, provided ``write`` or
        ``tick`` is called at least that often. Must be > 0.
    compression
        Chunk compression: ``'zstd'``, ``'lz4'`` or ``'none'``.
    chunk_size
        Uncompressed chunk size (B) at which a chunk is ended even before ``flush_period``.
    retry_period
        After an error, wait this long (s) before trying to open a new file.
    fsync
        ``os.fsync`` the file at every flush, so the bound also holds across power loss.
    clock
        Monotonic clock in seconds used for flush, rotation and retry timing (inject for tests).
    wall_clock
        Clock in seconds since the Unix epoch used for file names.
    create_dir
        Create ``log_dir`` (and its parents) when it is missing, at start and after it
        vanished; False: wait for it to reappear (e.g. a mount point).
    error_hold
        Shortest time (s) a vanished file or directory stays in :attr:`error` although a new
        file was opened at once.
    bag_metadata
        Keep the folder's rosbag2 ``metadata.yaml`` current.
    max_total_bytes, max_age
        Retention (0: keep all): the folder's MCAP files at most this many bytes (B), finished
        files at most this old (s, wall clock); oldest finished files deleted first, never the
        open one.
    min_free_bytes
        :attr:`warning` while the file system of ``log_dir`` has less free space (B; 0: none).
    retention_period
        How often (s) :meth:`tick` applies the retention and checks the free space.

    Attributes
    ----------
    error : str or None
        Current error (None while logging works), e.g.
        ``"cannot write MCAP log in /data: [Errno 28] No space left on device"``.
    last_error : str or None
        Most recent error, kept after recovery.
    error_count : int
        Number of errors so far.
    dropped : int
        Messages accepted by :meth:`write` that did not reach a file.
    messages_written : dict[str, int]
        Messages handed to the writer, per topic (minus those later lost to an error).
    bytes_written : dict[str, int]
        CDR payload bytes handed to the writer, per topic (same accounting).
    files : list[pathlib.Path]
        Files that were finished with a summary.
    deleted : list[tuple[pathlib.Path, int, str]]
        Files deleted by the retention and not yet taken by the caller: path, bytes, why
        (``size`` or ``age``); :meth:`take_deleted` empties it.
    warning : str or None
        Low free space on the log's file system (None: enough, or not checked).
    """

    def __init__(
        self,
        log_dir: str | os.PathLike[str],
        prefix: str = 'catenary_monitor',
        *,
        max_bytes: int = 256 * 1024 * 1024,
        max_seconds: float = 3600.0,
        flush_period: float = 1.0,
        compression: str | None = 'zstd',
        chunk_size: int = 512 * 1024,
        retry_period: float = 5.0,
        fsync: bool = True,
        clock: Callable[[], float] = time.monotonic,
        wall_clock: Callable[[], float] = time.time,
        create_dir: bool = True,
        error_hold: float = 2.0,
        bag_metadata: bool = True,
        max_total_bytes: int = 0,
        max_age: float = 0.0,
        min_free_bytes: int = 0,
        retention_period: float = 5.0,
    ) -> None:
        if compression not in _COMPRESSION:
            raise ValueError(f"compression must be 'zstd', 'lz4' or 'none', got {compression!r}")
        for name, value in (
            ('max_bytes', max_bytes),
            ('max_seconds', max_seconds),
            ('flush_period', flush_period),
            ('chunk_size', chunk_size),
            ('retry_period', retry_period),
        ):
            if not value > 0:
                raise ValueError(f'{name} must be > 0, got {value!r}')
        if not prefix or os.sep in prefix:
            raise ValueError(f'prefix must be a non-empty file name part, got {prefix!r}')
        self.log_dir = Path(log_dir)
        self.prefix = prefix
        self.max_bytes = int(max_bytes)
        self.max_seconds = float(max_seconds)
        self.flush_period = float(flush_period)
        self.compression = _COMPRESSION[compression]
        self.chunk_size = int(chunk_size)
        self.retry_period = float(retry_period)
        self.fsync = bool(fsync)
        self._clock = clock
        self._wall_clock = wall_clock
        self.create_dir = bool(create_dir)
        self.error_hold = float(error_hold)
        self.bag_metadata = bool(bag_metadata)
        #: Why ``metadata.yaml`` could not be written last time (None: it is current).
        self.metadata_error: str | None = None
        #: Files lost or displaced under the logger (deleted, moved or replaced).
        self.vanished = 0
        self._bag_cache: dict[str, _bag.FileInfo | None] = {}
        self._sticky_until = float('-inf')
        for name, limit in (('max_total_bytes', max_total_bytes), ('max_age', max_age),
                            ('min_free_bytes', min_free_bytes)):  # fmt: skip
            if not limit >= 0:
                raise ValueError(f'{name} must be >= 0, got {limit!r}')
        self.max_total_bytes = int(max_total_bytes)
        self.max_age = float(max_age)
        self.min_free_bytes = int(min_free_bytes)
        self.retention_period = float(retention_period)
        self._next_retention = float('-inf')
        self.deleted: list[tuple[Path, int, str]] = []
        # name -> (size, mtime ns, written by a logger of this module, recorded end s or None)
        self._owned: dict[str, tuple[int, int, bool, float | None]] = {}
        self.deleted_files = 0
        self.deleted_bytes = 0
        self.warning: str | None = None
        self.free_bytes: int | None = None

        self.error: str | None = None
        self.last_error: str | None = None
        self.error_count = 0
        self.dropped = 0
        self.messages_written: dict[str, int] = {}
        self.bytes_written: dict[str, int] = {}
        self.files: list[Path] = []

        self._lock = threading.RLock()
        self._topics: dict[str, _Topic] = {}
        self._metadata: dict[str, dict[str, str]] = {}
        self._file: _OpenFile | None = None
        self._file_index = 0
        self._closed = False
        self._next_retry = float('-inf')
        self._finished_bytes = 0
        # Messages in the writer's open chunk (not yet flushed), per topic, with payload bytes.
        self._pending: dict[str, list[int]] = {}
        self._pending_count = 0
        self._pending_bytes = 0
        self._oldest_pending: float | None = None
        self._flushed_size = 0  # file size (B) after the last flush
        # Files abandoned after a write error (a full disk): cut to their last flush, to be
        # finished where they lie as soon as space allows (path -> (size, definitions)).
        self.unfinished: dict[Path, tuple[int, Definitions]] = {}
        self.finished_late: list[Path] = []  # finished since the caller last took them
        self._next_finish = float('-inf')
        self._ensure_open(self._clock())

    # ------------------------------------------------------------------ public API
    @property
    def ok(self) -> bool:
        """True when a file is open and the last operation on it succeeded."""
        return self.error is None and self._file is not None

    @property
    def current_path(self) -> Path | None:
        """Path of the file being written, or None."""
        return self._file.path if self._file is not None else None

    @property
    def file_bytes(self) -> int:
        """Bytes written to all files of this logger so far (B), finished and current."""
        with self._lock:
            current = 0
            if self._file is not None:
                try:
                    current = self._file.stream.tell()
                except (OSError, ValueError):
                    current = self._flushed_size
            return self._finished_bytes + current

    def register(self, topic: str, type_name: str, qos: str | None = None) -> None:
        """Declare a topic and its ROS 2 type before writing to it.

        Parameters
        ----------
        topic
            ROS topic name, e.g. ``'/chain_01/tension'``.
        type_name
            ROS 2 type, e.g. ``'std_msgs/msg/Float64'``, ``'diagnostic_msgs/msg/DiagnosticArray'``.
        qos
            Offered QoS stored as the channel's ``offered_qos_profiles``: a preset name from
            :data:`QOS_PRESETS` (``'latched'``, ``'sensor_data'``, ``'default'``), a rosbag2 YAML
            string, or None to omit it (playback then uses default QoS).

        Raises
        ------
        ValueError
            If the topic is already registered with another type.
        catenary_monitor.io.ros_schemas.SchemaNotFoundError
            If the ``.msg`` definition of ``type_name`` is not installed.
        """
        if not topic:
            raise ValueError('topic must be a non-empty string')
        with self._lock:
            known = self._topics.get(topic)
            if known is not None:
                if known.type_name != type_name:
                    raise ValueError(
                        f'topic {topic!r} is already registered as {known.type_name!r}, '
                        f'not {type_name!r}'
                    )
                return
            metadata: dict[str, str] = {}
            if qos is not None:
                metadata['offered_qos_profiles'] = QOS_PRESETS.get(qos, qos)
            type_hash = type_description_hash(type_name)
            if type_hash is not None:
                metadata['topic_type_hash'] = type_hash
            info = _Topic(type_name, message_definition(type_name).encode(), metadata)
            self._topics[topic] = info
            self.messages_written.setdefault(topic, 0)
            self.bytes_written.setdefault(topic, 0)

    def add_metadata(self, name: str, data: Mapping[str, Any]) -> None:
        """Write a file-level Metadata record now and repeat it at the start of later files.

        Parameters
        ----------
        name
            Record name, e.g. ``'catenary_monitor'`` (config hash, version, units).
        data
            Key/value pairs; values are stored as ``str(value)``.
        """
        if not name:
            raise ValueError('metadata name must be a non-empty string')
        record = {str(k): str(v) for k, v in data.items()}
        with self._lock:
            self._metadata[name] = record
            if self._ensure_open(self._clock()):
                try:
                    assert self._file is not None
                    self._file.writer.add_metadata(name, record)
                except Exception as exc:  # noqa: BLE001
                    self._fail('cannot write MCAP metadata', exc)

    def write(
        self,
        topic: str,
        data: bytes | bytearray | memoryview,
        log_time_ns: int,
        publish_time_ns: int | None = None,
        sequence: int | None = None,
    ) -> bool:
        """Append one serialized message.

        Parameters
        ----------
        topic
            A topic given to :meth:`register`.
        data
            CDR bytes (``rclpy.serialization.serialize_message(msg)``), stored unchanged.
        log_time_ns
            Receive time, ns since the Unix epoch (or the ROS clock epoch under sim time).
        publish_time_ns
            Publish or header stamp (ns); defaults to ``log_time_ns``.
        sequence
            MCAP sequence number; defaults to a per-topic counter (wraps at 2**32).

        Returns
        -------
        bool
            True if the message was handed to an open file; False if it was dropped because of
            an error (see :attr:`error`, :attr:`dropped`).
        """
        if not isinstance(data, (bytes, bytearray, memoryview)):
            raise TypeError(f'data must be bytes (serialized CDR), got {type(data).__name__}')
        log_time_ns = _check_time('log_time_ns', log_time_ns)
        publish_time_ns = (
            log_time_ns
            if publish_time_ns is None
            else _check_time('publish_time_ns', publish_time_ns)
        )
        with self._lock:
            info = self._topics.get(topic)
            if info is None:
                raise ValueError(f'topic {topic!r} is not registered; call register() first')
            if sequence is None:
                sequence = info.sequence
            info.sequence = (sequence + 1) % (1 << 32)
            now = self._clock()
            self._rotate_if_due(now)
            if not self._ensure_open(now):
                self.dropped += 1
                return False
            assert self._file is not None
            payload = bytes(data)
            try:
                if not info.channel_id:
                    # a channel is written with its first message, in the same chunk: the mcap
                    # writer drops a chunk without messages (its schemas and channels too) but
                    # keeps them in the summary, which readers then find without a definition
                    self._register_channel(self._file, topic, info)
                self._file.writer.add_message(
                    channel_id=info.channel_id,
                    log_time=log_time_ns,
                    data=payload,
                    publish_time=publish_time_ns,
                    sequence=sequence % (1 << 32),
                )
            except Exception as exc:  # noqa: BLE001
                self.dropped += 1  # this message was in the chunk that failed to write
                self._fail('cannot write MCAP message', exc)
                return False
            f = self._file
            f.messages += 1
            counts = f.counts.setdefault(topic, [0, 0])
            counts[0] += 1
            counts[1] += len(payload)
            self.messages_written[topic] += 1
            self.bytes_written[topic] += len(payload)
            slot = self._pending.setdefault(topic, [0, 0])
            slot[0] += 1
            slot[1] += len(payload)
            self._pending_count += 1
            self._pending_bytes += len(payload) + _MESSAGE_OVERHEAD
            if self._oldest_pending is None:
                self._oldest_pending = now
            if self._pending_bytes >= self.chunk_size:
                self._flush(now)
            else:
                self._flush_if_due(now)
            return True

    def flush_if_due(self, now: float | None = None) -> bool:
        """Flush if the oldest unflushed message is ``flush_period`` old; retry after errors.

        Also rotates a file that reached ``max_seconds``. ``now`` is the monotonic clock (s);
        defaults to the logger's clock. Returns True if data was flushed.
        """
        with self._lock:
            if self._closed:
                return False
            now = self._clock() if now is None else float(now)
            if self._check_place(now):
                return False
            if self.error is not None and self._file is not None and now >= self._sticky_until:
                self.error = None  # a vanished file's error, held for error_hold
            if self.unfinished and now >= self._next_finish:
                self._finish_abandoned(now)
            self._rotate_if_due(now)
            if self._file is None:
                self._ensure_open(now)
                return False
            return self._flush_if_due(now)

    def tick(self) -> bool:
        """Timer hook: ``flush_if_due()`` with the logger's clock; every ``retention_period``
        the retention and the free-space check."""
        flushed = self.flush_if_due()
        with self._lock:
            now = self._clock()
            if now >= self._next_retention:
                self._next_retention = now + self.retention_period
                self.apply_retention()
        return flushed

    def take_finished_late(self) -> list[Path]:
        """Files abandoned after a write error and finished since the last call."""
        with self._lock:
            out, self.finished_late = self.finished_late, []
            return out

    def take_deleted(self) -> list[tuple[Path, int, str]]:
        """The retention's deletions since the last call (path, bytes, ``size``, ``age`` or
        ``future``: dated ahead of the present, deleted first for the size bound)."""
        with self._lock:
            out, self.deleted = self.deleted, []
            return out

    def apply_retention(self) -> None:
        """Delete the oldest finished MCAP files this logger's kind wrote beyond
        ``max_total_bytes`` or ``max_age`` (never the open file, nor one another process holds
        locked, nor anyone else's file); check the free space."""
        with self._lock:
            self._check_free_space()
            if not (self.max_total_bytes or self.max_age):
                return
            try:
                files = self._retention_candidates()
            except OSError:
                return
            # The open file counted at the size it may reach: it rotates once its bytes (its
            # pending messages uncompressed) reach max_bytes, then its summary is added (a
            # sixteenth, and 4 KiB for the next file's start): the folder stays under the bound
            # until the next check.
            reserve = max(self._open_size(), self.max_bytes) + self.max_bytes // 16 + 4096
            total = sum(size for _, size, _, _ in files) + reserve
            wall = self._wall_clock()
            gone = False
            for path, size, mtime, future in files:  # the future-dated, then the oldest
                why = None
                if self.max_age and wall - mtime > self.max_age:
                    why = 'age'
                elif self.max_total_bytes and total > self.max_total_bytes:
                    why = 'future' if future else 'size'
                if why is None or _locked_elsewhere(path):
                    continue
                try:
                    path.unlink()
                except FileNotFoundError:
                    continue
                except OSError as exc:
                    self.metadata_error = f'retention cannot delete {path}: {exc}'
                    continue
                total -= size
                gone = True
                self._bag_cache.pop(path.name, None)
                self.deleted.append((path, size, why))
                self.deleted_files += 1
                self.deleted_bytes += size
            if gone:
                self._write_bag_metadata()

    def _retention_candidates(self) -> list[tuple[Path, int, float, bool]]:
        """The finished files this logger's kind wrote (not the open one): (path, bytes,
        mtime, dated in the future); the future-dated first, then by recorded end time."""
        current = self.current_path
        wall = self._wall_clock()
        found = []
        seen = set()
        with os.scandir(self.log_dir) as entries:
            for entry in entries:
                if not self._own_name(entry.name) or not entry.is_file(follow_symlinks=False):
                    continue
                path = self.log_dir / entry.name
                if current is not None and path == current:
                    continue
                st = entry.stat(follow_symlinks=False)
                seen.add(entry.name)
                key = (int(st.st_size), int(st.st_mtime_ns))
                known = self._owned.get(entry.name)
                if known is None or known[:2] != key:
                    known = (*key, _written_here(path), _recorded_end(path))
                    self._owned[entry.name] = known
                if not known[2]:
                    continue
                end = known[3] if known[3] is not None else float(st.st_mtime)
                found.append((end <= wall + FUTURE_SLACK, end, entry.name, path, st))
        for gone in set(self._owned) - seen:
            del self._owned[gone]
        found.sort(key=lambda item: item[:3])
        return [(p, int(st.st_size), float(st.st_mtime), not now) for now, _, _, p, st in found]

    def _own_name(self, name: str) -> bool:
        """Whether ``name`` is of the form this logger gives its files."""
        rest = name[len(self.prefix) :]
        return name.startswith(self.prefix) and _OWN_NAME.fullmatch(rest) is not None

    def _open_size(self) -> int:
        if self._file is None:
            return 0
        try:
            return int(self._file.stream.tell())
        except (OSError, ValueError):
            return self._flushed_size

    def _check_free_space(self) -> None:
        """:attr:`warning` from the free space of ``log_dir``'s file system."""
        if not self.min_free_bytes:
            return
        try:
            st = os.statvfs(self.log_dir)
        except (OSError, AttributeError):
            return
        self.free_bytes = int(st.f_bavail * st.f_frsize)
        if self.free_bytes >= self.min_free_bytes:
            self.warning = None
            return
        self.warning = (
            f'low disk space: {self.free_bytes / 2**20:.0f} MiB free for the MCAP log in '
            f'{self.log_dir} (warning below {self.min_free_bytes / 2**20:.0f} MiB): logging '
            'stops when the disk is full; free space or set log_max_total_size'
        )

    def flush(self) -> bool:
        """End the open chunk, write it and fsync now. Returns False on error."""
        with self._lock:
            if self._file is None:
                return False
            return self._flush(self._clock())

    def rotate(self) -> None:
        """Finish the current file (with summary) and open the next one."""
        with self._lock:
            if self._closed:
                return
            self._finish_current()
            if self._file is None:
                self._next_retry = float('-inf')  # the next file opens with the next message
            self.apply_retention()

    def close(self) -> None:
        """Finish the current file with its summary and write ``metadata.yaml``. Idempotent;
        later writes are dropped."""
        with self._lock:
            if self._closed:
                return
            self._check_place(self._clock(), reopen=False)
            self._finish_current()
            if self.unfinished:
                self._finish_abandoned(self._clock())
            self._closed = True
            self._write_bag_metadata()

    def refresh_metadata(self) -> None:
        """Rewrite ``metadata.yaml`` now (e.g. after files in the folder were recovered)."""
        with self._lock:
            self._write_bag_metadata()

    def diagnostic_values(self) -> dict[str, str]:
        """Key/value strings for a ``DiagnosticStatus`` about the logger (units in the keys)."""
        with self._lock:
            return {
                'file': str(self.current_path or ''),
                'messages_written': str(sum(self.messages_written.values())),
                'messages_dropped': str(self.dropped),
                'file_bytes_B': str(self.file_bytes),
                'files_finished': str(len(self.files)),
                'files_unfinished': str(len(self.unfinished)),
                'files_vanished': str(self.vanished),
                'files_deleted': str(self.deleted_files),
                'deleted_bytes_B': str(self.deleted_bytes),
                'free_bytes_B': '' if self.free_bytes is None else str(self.free_bytes),
                'error': self.error or '',
                'warning': self.warning or '',
                'bag_metadata_error': self.metadata_error or '',
            }

    def __enter__(self) -> 'McapLogger':
        """Context manager: returns the logger."""
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Context manager: :meth:`close` on exit."""
        self.close()

    # ------------------------------------------------------------------ internals
    def _rotate_if_due(self, now: float) -> None:
        f = self._file
        if f is None or f.messages == 0:
            return
        too_old = now - f.opened_at >= self.max_seconds
        too_big = self._flushed_size + self._pending_bytes >= self.max_bytes
        if too_old or too_big:
            self._finish_current()
            if self._file is None:
                # the next file opens with the next message (a file without messages is not
                # a valid MCAP to strict readers: its summary lists empty groups)
                self._next_retry = float('-inf')
            self.apply_retention()  # the bound holds at once, however late tick() runs

    def _flush_if_due(self, now: float) -> bool:
        if self._oldest_pending is None or now - self._oldest_pending < self.flush_period:
            return False
        return self._flush(now)

    def _flush(self, now: float) -> bool:
        if self._check_place(now):
            return False
        f = self._file
        if f is None:
            return False
        try:
            f.writer.flush()
            if self.fsync:
                os.fsync(f.stream.fileno())
            self._flushed_size = f.stream.tell()
        except Exception as exc:  # noqa: BLE001
            self._fail('cannot flush MCAP log', exc)
            return False
        self._clear_pending()
        if self._flushed_size >= self.max_bytes:
            self._rotate_if_due(now)
        return True

    def _clear_pending(self) -> None:
        self._pending.clear()
        self._pending_count = 0
        self._pending_bytes = 0
        self._oldest_pending = None

    def _ensure_open(self, now: float, force: bool = False) -> bool:
        """Open a file unless one is open; honours ``retry_period`` after an error."""
        if self._closed:
            return False
        if self._file is not None:
            return True
        if not force and now < self._next_retry:
            return False
        path: Path | None = None
        stream: IO[bytes] | None = None
        try:
            if self.create_dir:
                self.log_dir.mkdir(parents=True, exist_ok=True)
            elif not self.log_dir.is_dir():
                raise FileNotFoundError(
                    'the directory is missing (create_dir is off: waiting for it to reappear)'
                )
            path, stream = self._create_file()
            _lock_quietly(stream)
            # The logger ends chunks itself (size or age) so that each end is flushed at once;
            # the writer's own limit is only a backstop.
            writer = Writer(
                stream,
                chunk_size=4 * self.chunk_size,
                compression=self.compression,
                index_types=_INDEX_TYPES,
            )
            writer.start(profile='ros2', library=_LIBRARY)
            opened = _OpenFile(path, stream, writer, now)
            dir_stat, file_stat = os.stat(self.log_dir), os.fstat(stream.fileno())
            opened.dir_id = (dir_stat.st_dev, dir_stat.st_ino)
            opened.file_id = (file_stat.st_dev, file_stat.st_ino)
            for name, record in self._metadata.items():
                writer.add_metadata(name, record)
            writer.flush()
            if self.fsync:
                os.fsync(stream.fileno())
            self._flushed_size = stream.tell()
        except Exception as exc:  # noqa: BLE001
            for info in self._topics.values():
                info.channel_id = 0
            if stream is not None:
                _close_quietly(stream)
            if path is not None:
                try:  # don't leave one empty file per retry on a full disk
                    path.unlink()
                except OSError:
                    pass
            self._record_error(f'cannot open MCAP log in {self.log_dir}', exc)
            self._next_retry = now + self.retry_period
            return False
        self._file = opened
        self._file_index += 1
        self._clear_pending()
        if now >= self._sticky_until:
            self.error = None
        self._write_bag_metadata()
        return True

    def _check_place(self, now: float, reopen: bool = True) -> bool:
        """Detect the open file or ``log_dir`` deleted, moved or replaced; handle it (error,
        lost messages counted, a new file opened at once unless ``reopen`` is False). Returns
        True if it was."""
        f = self._file
        if f is None:
            return False
        problem = None
        try:
            d = os.stat(self.log_dir)
            if (d.st_dev, d.st_ino) != f.dir_id:
                problem = f'log directory {self.log_dir} was replaced'
        except OSError:
            problem = f'log directory {self.log_dir} vanished (deleted or moved)'
        if problem is None:
            try:
                st = os.stat(f.path)
                if (st.st_dev, st.st_ino) != f.file_id:
                    problem = f'log file {f.path} was replaced'
            except OSError:
                problem = f'log file {f.path} vanished (deleted or moved)'
        if problem is None:
            return False
        self._vanished(f, problem, now)
        if reopen:
            self._ensure_open(now)
        return True

    def _vanished(self, f: _OpenFile, problem: str, now: float) -> None:
        """Give up a file that is no longer where it was opened (see :meth:`_check_place`)."""
        try:
            deleted = os.fstat(f.stream.fileno()).st_nlink == 0
        except (OSError, ValueError):
            deleted = True
        outcome = ''
        if not deleted:  # moved or replaced: finish it where it went, nothing is lost
            try:
                f.writer.finish()
                f.stream.flush()
                if self.fsync:
                    os.fsync(f.stream.fileno())
                outcome = 'finished where it went'
            except Exception:  # noqa: BLE001
                deleted = True
        if deleted:
            for topic, (count, nbytes) in f.counts.items():
                self.messages_written[topic] -= count
                self.bytes_written[topic] -= nbytes
            self.dropped += f.messages
            outcome = f'{f.messages} message(s) lost with it'
        _close_quietly(f.stream)
        self._file = None
        self._flushed_size = 0
        self._clear_pending()
        for info in self._topics.values():
            info.channel_id = 0
        self.vanished += 1
        self.error = f'{problem}: {outcome}; writing a new file'
        self.last_error = self.error
        self.error_count += 1
        self._sticky_until = now + self.error_hold
        self._next_retry = now

    def _write_bag_metadata(self) -> None:
        """Rewrite ``metadata.yaml``; a failure is kept in :attr:`metadata_error`."""
        if not self.bag_metadata:
            return
        try:
            _bag.write_folder_metadata(self.log_dir, (), self._bag_cache)
            self.metadata_error = None
        except Exception as exc:  # noqa: BLE001 - never stops the logging
            self.metadata_error = f'cannot write {self.log_dir / _bag.METADATA_NAME}: {exc}'

    def _create_file(self) -> tuple[Path, IO[bytes]]:
        stamp = _dt.datetime.fromtimestamp(self._wall_clock(), _dt.timezone.utc)
        stamp_text = stamp.strftime('%Y%m%dT%H%M%SZ')
        index = self._file_index
        for _ in range(1000):
            path = self.log_dir / f'{self.prefix}_{stamp_text}_{index:04d}.mcap'
            try:
                return path, open(path, 'xb')
            except FileExistsError:
                index += 1
        raise FileExistsError(f'no free file name for {self.prefix}_{stamp_text}_*.mcap')

    def _register_channel(self, f: _OpenFile, topic: str, info: _Topic) -> None:
        schema_id = f.schema_ids.get(info.type_name)
        if schema_id is None:
            schema_id = f.writer.register_schema(
                name=info.type_name, encoding=SchemaEncoding.ROS2, data=info.schema_text
            )
            f.schema_ids[info.type_name] = schema_id
        info.channel_id = f.writer.register_channel(
            topic=topic,
            message_encoding=MessageEncoding.CDR,
            schema_id=schema_id,
            metadata=dict(info.metadata),
        )

    def _finish_current(self) -> None:
        f = self._file
        if f is None:
            return
        try:
            f.writer.finish()
            f.stream.flush()
            if self.fsync:
                os.fsync(f.stream.fileno())
            size = f.stream.tell()
            f.stream.close()
        except Exception as exc:  # noqa: BLE001
            self._fail('cannot finish MCAP log', exc)
            return
        self._finished_bytes += size
        self.files.append(f.path)
        self._file = None
        self._flushed_size = 0
        self._clear_pending()
        for info in self._topics.values():
            info.channel_id = 0
        self._next_retention = float('-inf')  # a file finished: the retention at the next tick

    def _fail(self, what: str, exc: BaseException) -> None:
        """Abandon the current file after an error; its unflushed messages are lost."""
        f = self._file
        where = f.path if f is not None else self.log_dir
        self._record_error(f'{what} {where}', exc)
        for topic, (count, nbytes) in self._pending.items():
            self.messages_written[topic] -= count
            self.bytes_written[topic] -= nbytes
        self.dropped += self._pending_count
        self._clear_pending()
        if f is not None:
            _close_quietly(f.stream)
            self._abandon(f)
        self._file = None
        self._flushed_size = 0
        for info in self._topics.values():
            info.channel_id = 0
        self._next_retry = self._clock() + self.retry_period

    def _abandon(self, f: _OpenFile) -> None:
        """Keep a file a write error left unfinished: cut it to its last flush at once (the end
        of a whole chunk and its indexes; a full disk gets that room back) and remember what it
        defines, so :meth:`_finish_abandoned` can finish it where it lies later."""
        known = Definitions()
        for topic, info in self._topics.items():
            sid = f.schema_ids.get(info.type_name)
            if sid is not None:
                known.schemas[sid] = (info.type_name, SchemaEncoding.ROS2, info.schema_text)
            if info.channel_id and sid is not None:
                known.channels[info.channel_id] = (
                    topic,
                    MessageEncoding.CDR,
                    sid,
                    dict(info.metadata),
                )
        size = self._flushed_size
        try:
            os.truncate(f.path, size)
        except OSError:
            size = min(size, f.path.stat().st_size) if f.path.exists() else size
        self.unfinished[f.path] = (size, known)
        self._finished_bytes += size
        if self.error is not None:
            self.error += (
                f'; {f.path.name} cut to its last whole chunk ({size} B), to be finished as '
                'soon as space allows'
            )
            self.last_error = self.error
        self._next_finish = self._clock() + self.retry_period

    def _finish_abandoned(self, now: float) -> None:
        """Finish the abandoned files where they lie (a summary's room needed; retried every
        ``retry_period`` while it fails)."""
        for path, (size, known) in list(self.unfinished.items()):
            try:
                finish_in_place(path, size, known)
            except FileNotFoundError:
                del self.unfinished[path]  # deleted meanwhile: nothing left to finish
                continue
            except OSError:
                self._next_finish = now + self.retry_period
                return
            del self.unfinished[path]
            self.files.append(path)
            self.finished_late.append(path)
        self._write_bag_metadata()

    def _record_error(self, what: str, exc: BaseException) -> None:
        self.error = f'{what}: {exc}'
        self.last_error = self.error
        self.error_count += 1


_OWN_NAME = re.compile(r'_\d{8}T\d{6}Z_\d{4,}\.mcap')
_MAGIC = b'\x89MCAP0\r\n'
_RECORD = struct.Struct('<BQ')


def _written_here(path: Path) -> bool:
    """Whether the file's Header names this module as its library (recovery appends to it,
    so a recovered file is still the logger's)."""
    try:
        with open(path, 'rb') as f:
            data = f.read(1024)
        if not data.startswith(_MAGIC):
            return False
        op, _ = _RECORD.unpack_from(data, len(_MAGIC))
        at = len(_MAGIC) + _RECORD.size
        (n,) = struct.unpack_from('<I', data, at)  # the profile
        at += 4 + n
        (n,) = struct.unpack_from('<I', data, at)
        library = data[at + 4 : at + 4 + n]
    except (OSError, struct.error):
        return False
    return op == 0x01 and library.startswith(_LIBRARY.split(';')[0].encode())


def _recorded_end(path: Path) -> float | None:
    """The log time (s) of the file's last message, from its summary (None without one)."""
    info = _bag.file_info(path)
    if info is None or not info.message_count:
        return None
    return (info.starting_time_ns + info.duration_ns) * 1e-9


def _check_time(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        try:
            value = int(value.__index__())  # numpy integers
        except AttributeError:
            raise TypeError(f'{name} must be an int (ns), got {type(value).__name__}') from None
    if not 0 <= value < _U64:
        raise ValueError(f'{name} must be in [0, 2**64) ns, got {value}')
    return value


def _lock_quietly(stream: IO[bytes]) -> None:
    """Hold an advisory lock on the file being written (released when the process dies), so
    that recovery (:mod:`catenary_monitor.io.mcap_recover`) leaves a live file alone."""
    try:
        import fcntl

        fcntl.flock(stream.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except (ImportError, OSError):
        pass


def _locked_elsewhere(path: Path) -> bool:
    """Whether another process holds ``path`` locked (a live writer's open file)."""
    try:
        import fcntl
    except ImportError:
        return False
    try:
        with open(path, 'rb') as f:
            try:
                fcntl.flock(f.fileno(), fcntl.LOCK_SH | fcntl.LOCK_NB)
            except OSError:
                return True
            fcntl.flock(f.fileno(), fcntl.LOCK_UN)
    except OSError:
        return False
    return False


def _close_quietly(stream: IO[bytes]) -> None:
    try:
        stream.close()
    except Exception:  # noqa: BLE001 - closing a broken file may fail again
        try:
            os.close(stream.fileno())
        except (OSError, ValueError):
            pass
