"""An MCAP file's summary, metadata and channels, read in bounded time and memory (no rclpy).

What replay, the bag's ``metadata.yaml``, playback and the console ask of a log before (or
instead of) reading its messages: the parameters the node recorded (a Metadata record), the
channels, the statistics. The ``mcap`` library's readers answer these by parsing whatever the
file declares (a crafted summary, or a non-seeking read that decompresses whole chunks); here
every record is parsed within bounds and no chunk is ever decompressed:

* :func:`read_summary` -- the summary section of a finished file (footer, CRC-checked), at
  most :data:`MAX_SUMMARY_BYTES`: Schema, Channel (with their metadata), Statistics and
  Metadata Index records. None for an unfinished file or a damaged summary.
* :func:`read_metadata` -- the Metadata records of one name: through the summary's index, else
  (an unfinished file) by walking the top-level records' heads from the start (chunks are
  stepped over by their length), at most :data:`MAX_HEADS` records; each record at most
  :data:`MAX_METADATA_BYTES`.
* :func:`channels_of` -- every channel of a file: the summary's, else the reader's tolerant
  walk of the file with no message selected (:mod:`catenary_monitor.io.mcap_scan`: its chunks
  bounded as for reading).
"""

from __future__ import annotations

import mmap
import os
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, Optional

from catenary_monitor.io.mcap_records import MAGIC, BadRecord, read_string, read_string_map

__all__ = [
    'ChannelInfo',
    'FileSummary',
    'MAX_HEADS',
    'MAX_METADATA_BYTES',
    'MAX_SUMMARY_BYTES',
    'channels_of',
    'read_metadata',
    'read_summary',
]

#: Largest summary section parsed (B): the node's is a few kB, 100 000 channels about 5 MB.
MAX_SUMMARY_BYTES = 64 << 20
#: Largest Metadata record parsed (B): the node's parameters are about 10 kB.
MAX_METADATA_BYTES = 16 << 20
#: Top-level records whose heads an unfinished file's walk reads before giving up (a node's
#: 256 MiB file has about 15 000).
MAX_HEADS = 1 << 20

_HEAD = struct.Struct('<BQ')
_OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_CHUNK = 0x02, 0x03, 0x04, 0x06
_OP_STATISTICS, _OP_METADATA, _OP_METADATA_INDEX, _OP_DATA_END = 0x0B, 0x0C, 0x0D, 0x0F
_FOOTER = 9 + 20


@dataclass(frozen=True)
class ChannelInfo:
    """A channel as its Channel record defines it (schema name '' when unknown)."""

    id: int
    topic: str
    schema_name: str
    encoding: str
    metadata: dict[str, str] = field(default_factory=dict)


@dataclass
class FileSummary:
    """The facts of a finished file's summary section."""

    channels: dict[int, ChannelInfo] = field(default_factory=dict)
    message_count: int = 0
    start_ns: int = 0
    end_ns: int = 0
    channel_counts: dict[int, int] = field(default_factory=dict)
    has_statistics: bool = False
    metadata_index: list[tuple[str, int, int]] = field(default_factory=list)  # name, at, len


def read_summary(path: str | os.PathLike[str]) -> Optional[FileSummary]:
    """The summary of a finished file, or None (unfinished, unreadable, a summary that is
    damaged, fails its CRC or is larger than :data:`MAX_SUMMARY_BYTES`)."""
    with _mapped(path) as data:
        if data is None:
            return None
        section = _summary_section(data)
        if section is None:
            return None
        try:
            return _parse_summary(data, *section)
        except (BadRecord, struct.error, UnicodeError):
            return None


def read_metadata(
    path: str | os.PathLike[str], name: str, first: bool = False
) -> list[dict[str, str]]:
    """The key/value maps of the file's Metadata records called ``name``, in file order (only
    the first with ``first``); [] when there is none, or none that can be read within the
    bounds (see the module docstring)."""
    out: list[dict[str, str]] = []
    with _mapped(path) as data:
        if data is None:
            return out
        summary = None
        section = _summary_section(data)
        if section is not None:
            try:
                summary = _parse_summary(data, *section)
            except (BadRecord, struct.error, UnicodeError):
                summary = None
        if summary is not None and summary.metadata_index:
            places: Iterator[int] = (at for n, at, _ in summary.metadata_index if n == name)
        else:
            places = _metadata_heads(data)
        for at in places:
            record = _metadata_at(data, at)
            if record is not None and record[0] == name:
                out.append(record[1])
                if first:
                    break
    return out


def channels_of(path: str | os.PathLike[str]) -> dict[int, ChannelInfo]:
    """Every channel of a file (id -> :class:`ChannelInfo`): the summary's when the file has
    one, else those the reader's walk finds (damage skipped; its bounds)."""
    summary = read_summary(path)
    if summary is not None and summary.channels:
        return summary.channels
    from catenary_monitor.io.mcap_scan import McapReadError, ReadReport, Scanner

    scanner = Scanner(Path(path), lambda channel: False, ReadReport())
    try:
        for _ in scanner.blocks():
            pass
    except McapReadError:
        return {}
    return {
        cid: ChannelInfo(cid, ch.topic, ch.schema_name, ch.encoding)
        for cid, ch in scanner.channels.items()
    }


# --- the file -----------------------------------------------------------------------------------


class _mapped:
    """``with _mapped(path) as data``: the file memory-mapped read-only (None if it cannot be
    opened or is empty); nothing is read that is not parsed."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = path
        self.map: Optional[mmap.mmap] = None

    def __enter__(self) -> Optional[mmap.mmap]:
        try:
            with open(self.path, 'rb') as f:
                if os.fstat(f.fileno()).st_size == 0:
                    return None
                self.map = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        except (OSError, ValueError):
            return None
        return self.map

    def __exit__(self, *exc: object) -> None:
        if self.map is not None:
            self.map.close()


def _summary_section(data: mmap.mmap) -> Optional[tuple[int, int]]:
    """(start, end) of the summary section of a finished file whose CRC (if any) holds."""
    n = len(data)
    footer_at = n - len(MAGIC) - _FOOTER
    if footer_at < len(MAGIC) or data[n - len(MAGIC) :] != MAGIC or data[:8] != MAGIC:
        return None
    op, length = _HEAD.unpack_from(data, footer_at)
    if op != _OP_FOOTER or length != 20:
        return None
    start, _, crc = struct.unpack_from('<QQI', data, footer_at + 9)
    if start == 0 or not len(MAGIC) <= start <= footer_at:
        return None
    if footer_at - start > MAX_SUMMARY_BYTES:
        return None
    if crc and zlib.crc32(data[start : footer_at + 9 + 16]) != crc:
        return None
    return start, footer_at


def _parse_summary(data: mmap.mmap, start: int, end: int) -> FileSummary:
    summary = FileSummary()
    schemas: dict[int, str] = {}
    channels: list[tuple[int, int, str, str, dict[str, str]]] = []
    pos = start
    while pos + 9 <= end:
        op, length = _HEAD.unpack_from(data, pos)
        body, stop = pos + 9, pos + 9 + length
        if stop > end:
            raise BadRecord('a summary record runs past the section')
        if op == _OP_SCHEMA:
            (sid,) = struct.unpack_from('<H', data, body)
            schemas.setdefault(sid, read_string(data, body + 2, stop)[0])
        elif op == _OP_CHANNEL:
            channels.append(_channel(data, body, stop))
        elif op == _OP_STATISTICS:
            _statistics(data, body, stop, summary)
        elif op == _OP_METADATA_INDEX:
            at, size = struct.unpack_from('<QQ', data, body)
            summary.metadata_index.append((read_string(data, body + 16, stop)[0], at, size))
        pos = stop
    for cid, sid, topic, encoding, metadata in channels:
        if cid not in summary.channels:
            name = schemas.get(sid, '') if sid else ''
            summary.channels[cid] = ChannelInfo(cid, topic, name, encoding, metadata)
    return summary


def _statistics(data: mmap.mmap, body: int, stop: int, summary: FileSummary) -> None:
    if stop - body < 46:
        raise BadRecord('Statistics record too short')
    summary.message_count = struct.unpack_from('<Q', data, body)[0]
    summary.start_ns, summary.end_ns = struct.unpack_from('<QQ', data, body + 26)
    (size,) = struct.unpack_from('<I', data, body + 42)
    if body + 46 + size > stop or size % 10:
        raise BadRecord('Statistics channel counts run past the record')
    for k in range(body + 46, body + 46 + size, 10):
        cid, count = struct.unpack_from('<HQ', data, k)
        summary.channel_counts[cid] = count
    summary.has_statistics = True


def _channel(
    data: mmap.mmap, body: int, stop: int
) -> tuple[int, int, str, str, dict[str, str]]:
    if stop - body < 16:
        raise BadRecord('Channel record too short')
    cid, sid = struct.unpack_from('<HH', data, body)
    topic, p = read_string(data, body + 4, stop)
    encoding, p = read_string(data, p, stop)
    return cid, sid, topic, encoding, read_string_map(data, p, stop, keep_first=True)


def _metadata_heads(data: mmap.mmap) -> Iterator[int]:
    """Offsets of the top-level Metadata records of an unfinished file, walking record heads
    from the start (at most :data:`MAX_HEADS`; the walk stops at the first record that is not
    one or runs past the end)."""
    pos, n = len(MAGIC), len(data)
    for _ in range(MAX_HEADS):
        if pos + 9 > n:
            return
        op, length = _HEAD.unpack_from(data, pos)
        if op == 0 or (op > _OP_DATA_END and op < 0x80) or op in (_OP_DATA_END, _OP_FOOTER):
            return
        if pos + 9 + length > n:
            return
        if op == _OP_METADATA:
            yield pos
        pos += 9 + length


def _metadata_at(data: mmap.mmap, at: int) -> Optional[tuple[str, dict[str, str]]]:
    """(name, map) of the Metadata record at ``at``, or None (not one, too large, damaged)."""
    if at < len(MAGIC) or at + 9 > len(data):
        return None
    op, length = _HEAD.unpack_from(data, at)
    if op != _OP_METADATA or length > MAX_METADATA_BYTES or at + 9 + length > len(data):
        return None
    try:
        name, p = read_string(data, at + 9, at + 9 + length)
        return name, read_string_map(data, p, at + 9 + length, keep_first=True)
    except (BadRecord, struct.error, UnicodeError):
        return None
