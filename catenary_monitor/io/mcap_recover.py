"""Finish MCAP files left unfinished (writer killed): summary, indexes, statistics, CRCs.

A file whose writer was SIGKILLed has no summary and no footer and may end inside a chunk.
:func:`recover_file` walks its records one at a time (memory bounded by one chunk), keeps every
Schema, Channel, Metadata and Attachment record and every complete message (also those of a
chunk cut by the end of the file, decompressed as far as it goes), and writes them again with
the ``mcap`` library's :class:`~mcap.writer.Writer` (same profile, same chunk compression):
chunk indexes, message indexes, statistics, summary offsets and CRCs come from the library. A
``recovery`` Metadata record says what was done.

Steps, so that a crash at any point leaves a readable state and a rerun finishes the job:
the new file is written to ``.NAME.recover-tmp`` in the same folder and fsynced; it is read
back (CRC-validated summary, message count checked); the original is kept as
``NAME.unfinished`` (a hard link; copied where links are not supported); the new file replaces
``NAME`` atomically (``os.replace``) and the folder is fsynced. A finished file (valid footer
and magic at its end) is left alone (``already_finished``), so recovering twice changes
nothing. Chunks are checked as :mod:`catenary_monitor.io.mcap_read` checks them (size bounds,
bounded decompression, CRC): a damaged chunk is skipped and reported, the rest is used.

For a folder, :func:`recover_path` also writes the folder's rosbag2 ``metadata.yaml``
(:mod:`catenary_monitor.io.bag_metadata`).
"""

from __future__ import annotations

import datetime as _dt
import os
import shutil
import struct
import zlib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import IO, Iterator, Optional

from mcap.writer import CompressionType, IndexType, Writer

from catenary_monitor.io import bag_metadata
from catenary_monitor.io.mcap_read import (
    MAGIC,
    MAX_CHUNK_BYTES,
    _chunk_header,
    _decompress,
    _decompress_partial,
    _find_chunk,
    chunk_size_problem,
)

__all__ = [
    'RecoverResult',
    'is_finished',
    'recover_file',
    'recover_in_child',
    'recover_path',
    'unfinished_files',
    'BACKUP_SUFFIX',
]

#: Suffix of the kept original of a recovered file (not ``*.mcap``: no reader picks it up).
BACKUP_SUFFIX = '.unfinished'

_HEAD = struct.Struct('<BQ')
_FOOTER_LEN = 9 + 20
_OP_HEADER, _OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE = 0x01, 0x02, 0x03, 0x04, 0x05
_OP_CHUNK, _OP_ATTACHMENT, _OP_METADATA, _OP_DATA_END = 0x06, 0x09, 0x0C, 0x0F
_KNOWN = frozenset(range(0x01, 0x10))
_COMPRESSION = {'zstd': CompressionType.ZSTD, 'lz4': CompressionType.LZ4, '': CompressionType.NONE}
_NO_ATTACHMENT_INDEX = IndexType.CHUNK | IndexType.MESSAGE | IndexType.METADATA
_CHUNK_SIZE = 1 << 20  # B, chunks of the recovered file (uncompressed)


class _Bad(Exception):
    """A record whose fields do not fit its length."""


@dataclass
class RecoverResult:
    """What :func:`recover_file` did with one file.

    status: ``recovered``, ``already_finished``, ``in_use`` (a running logger holds its lock:
    left alone), ``not_mcap`` or ``failed`` (``error`` says why).
    messages: messages in the finished file; chunks: chunks read from the original;
    damaged: one sentence per damaged part skipped (a cut tail included); lost: messages
    known lost in them (a lower bound: a cut tail's count is unknown); backup: the kept
    original.
    """

    path: str
    status: str
    messages: int = 0
    chunks: int = 0
    salvaged_from_cut_chunk: int = 0
    damaged: list[str] = field(default_factory=list)
    lost: int = 0
    backup: Optional[str] = None
    error: Optional[str] = None

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def is_finished(path: str | os.PathLike[str]) -> bool:
    """True if the file starts with the MCAP magic and ends with a Footer record and magic."""
    try:
        with open(path, 'rb') as f:
            head = f.read(len(MAGIC))
            f.seek(0, os.SEEK_END)
            size = f.tell()
            if head != MAGIC or size < 2 * len(MAGIC) + _FOOTER_LEN:
                return False
            f.seek(size - len(MAGIC) - _FOOTER_LEN)
            tail = f.read(len(MAGIC) + _FOOTER_LEN)
    except OSError:
        return False
    op, length = _HEAD.unpack_from(tail, 0)
    return tail[-len(MAGIC):] == MAGIC and op == _OP_FOOTER and length == 20


def recover_in_child(path: str | os.PathLike[str], niceness: int = 10) -> RecoverResult:
    """:func:`recover_file` in a child process at a lower CPU priority (``nice``), so that a
    live node recovering a large file keeps its own interpreter (and its GIL) to itself. Falls
    back to recovering in this process if the child cannot be run."""
    import json
    import subprocess
    import sys

    def lower_priority() -> None:
        try:
            os.nice(niceness)
        except (AttributeError, OSError):
            pass

    try:
        done = subprocess.run(
            [sys.executable, '-m', 'catenary_monitor.io.mcap_recover', str(path)],
            capture_output=True,
            text=True,
            preexec_fn=lower_priority if os.name == 'posix' else None,
        )
        return RecoverResult(**json.loads(done.stdout.splitlines()[-1]))
    except (OSError, ValueError, TypeError, IndexError):
        return recover_file(path)


def unfinished_files(folder: str | os.PathLike[str]) -> list[Path]:
    """The ``*.mcap`` files of ``folder`` without a footer, by name ([] if no folder)."""
    try:
        return [p for p in sorted(Path(folder).glob('*.mcap')) if not is_finished(p)]
    except OSError:
        return []


def recover_path(
    path: str | os.PathLike[str], keep_original: bool = True
) -> tuple[list[RecoverResult], Optional[Path]]:
    """Recover a file or every ``*.mcap`` of a folder; write the folder's ``metadata.yaml``.

    Returns the results (in name order) and the metadata path (None for a single file whose
    folder holds no ``metadata.yaml`` yet, or if it could not be written).
    Raises FileNotFoundError if ``path`` does not exist.
    """
    path = Path(path)
    if path.is_dir():
        files, folder, bag = sorted(path.glob('*.mcap')), path, True
    elif path.exists():
        files, folder = [path], path.parent
        bag = (folder / bag_metadata.METADATA_NAME).exists()
    else:
        raise FileNotFoundError(f'no such MCAP file or folder: {path}')
    results = [recover_file(f, keep_original) for f in files]
    written = None
    if bag:
        try:
            written = bag_metadata.write_folder_metadata(folder)
        except OSError:
            written = None
    return results, written


def recover_file(path: str | os.PathLike[str], keep_original: bool = True) -> RecoverResult:
    """Finish one unfinished MCAP file in place (see the module docstring). Never raises for
    a bad or unwritable file: the result's ``status`` and ``error`` say what happened."""
    path = Path(path)
    if is_finished(path):
        return RecoverResult(str(path), 'already_finished')
    result = RecoverResult(str(path), 'recovered')
    tmp = path.with_name(f'.{path.name}.recover-tmp')
    try:
        with open(path, 'rb') as src:
            head = src.read(len(MAGIC))
            if head != MAGIC and not (MAGIC.startswith(head)):
                result.status, result.error = 'not_mcap', 'does not start with the MCAP magic'
                return result
            if _locked(src):
                result.status = 'in_use'
                result.error = 'being written by a running logger (locked): left alone'
                return result
            with open(tmp, 'wb') as out:
                _rewrite(src, out, result, path.name)
                out.flush()
                os.fsync(out.fileno())
        _check_written(tmp, result.messages)
        if keep_original:
            backup = path.with_name(path.name + BACKUP_SUFFIX)
            _keep(path, backup)
            result.backup = str(backup)
        os.replace(tmp, path)
        bag_metadata.fsync_dir(path.parent)
    except Exception as exc:  # noqa: BLE001 - reported per file, never a traceback
        result.status, result.error = 'failed', f'{type(exc).__name__}: {exc}'
        try:
            tmp.unlink()
        except OSError:
            pass
    return result


def _locked(src: IO[bytes]) -> bool:
    """True if a running logger holds the file's lock (:mod:`catenary_monitor.io.mcap_log`)."""
    try:
        import fcntl
    except ImportError:
        return False
    try:
        fcntl.flock(src.fileno(), fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    except OSError:
        return False
    return False


def _keep(path: Path, backup: Path) -> None:
    """Keep the original as ``backup`` (hard link, else copy), replacing an older backup."""
    side = backup.with_name(backup.name + '.tmp')
    try:
        side.unlink()
    except FileNotFoundError:
        pass
    try:
        os.link(path, side)
    except OSError:
        shutil.copyfile(path, side)
    os.replace(side, backup)


def _check_written(tmp: Path, messages: int) -> None:
    """Read the new file back: CRC-checked summary and the message count written."""
    from mcap.reader import make_reader

    with open(tmp, 'rb') as f:
        summary = make_reader(f, validate_crcs=True).get_summary()
    if summary is None or summary.statistics is None:
        raise ValueError('the rewritten file has no summary')
    if summary.statistics.message_count != messages:
        raise ValueError(
            f'the rewritten file holds {summary.statistics.message_count} messages, '
            f'{messages} were written'
        )


class _Rewriter:
    """Re-emits records into a Writer; maps the original schema and channel ids to new ones."""

    def __init__(self, out: IO[bytes], result: RecoverResult) -> None:
        self.out = out
        self.result = result
        self.writer: Writer | None = None
        self.profile = ''
        self.library = ''
        self.compression = 'zstd'
        self.attachments = False
        self.schemas: dict[int, tuple[str, str, bytes]] = {}
        self.schema_ids: dict[int, int] = {}
        self.channels: dict[int, int] = {}
        self.unknown = 0

    def start(self) -> Writer:
        if self.writer is None:
            self.writer = Writer(
                self.out,
                chunk_size=_CHUNK_SIZE,
                compression=_COMPRESSION.get(self.compression, CompressionType.ZSTD),
                # No empty Attachment Index group: pymcap-cli's doctor reports its Summary
                # Offset as pointing to a missing group (docs/mcap_log.md).
                index_types=IndexType.ALL if self.attachments else _NO_ATTACHMENT_INDEX,
            )
            library = self.library + '; finished by catenary_monitor.mcap_recover'
            self.writer.start(profile=self.profile, library=library.lstrip('; '))
        return self.writer

    def schema(self, buf: bytes, pos: int, end: int) -> None:
        (sid,) = struct.unpack_from('<H', buf, pos)
        name, p = _string(buf, pos + 2, end)
        encoding, p = _string(buf, p, end)
        data = _bytes(buf, p, end)
        if sid and sid not in self.schemas:
            self.schemas[sid] = (name, encoding, data)

    def _schema_id(self, sid: int) -> int:
        if sid == 0 or sid not in self.schemas:
            return 0
        if sid not in self.schema_ids:
            name, encoding, data = self.schemas[sid]
            self.schema_ids[sid] = self.start().register_schema(name, encoding, data)
        return self.schema_ids[sid]

    def channel(self, buf: bytes, pos: int, end: int) -> None:
        cid, sid = struct.unpack_from('<HH', buf, pos)
        topic, p = _string(buf, pos + 4, end)
        encoding, p = _string(buf, p, end)
        metadata = _string_map(buf, p, end)
        if cid not in self.channels:
            self.channels[cid] = self.start().register_channel(
                topic, encoding, self._schema_id(sid), metadata
            )

    def message(self, buf: bytes, pos: int, end: int) -> bool:
        if end - pos < 22:
            raise _Bad('Message record too short')
        cid, seq, log_time, publish_time = struct.unpack_from('<HIQQ', buf, pos)
        new = self.channels.get(cid)
        if new is None:
            self.unknown += 1
            return False
        self.start().add_message(new, log_time, bytes(buf[pos + 22 : end]), publish_time, seq)
        self.result.messages += 1
        return True

    def metadata(self, buf: bytes, pos: int, end: int) -> None:
        name, p = _string(buf, pos, end)
        self.start().add_metadata(name, _string_map(buf, p, end))

    def attachment(self, buf: bytes, pos: int, end: int) -> None:
        log_time, create_time = struct.unpack_from('<QQ', buf, pos)
        name, p = _string(buf, pos + 16, end)
        media, p = _string(buf, p, end)
        (size,) = struct.unpack_from('<Q', buf, p)
        if p + 8 + size > end:
            raise _Bad('attachment data runs past its record')
        data = bytes(buf[p + 8 : p + 8 + size])
        self.start().add_attachment(create_time, log_time, name, media, data)

    def records(self, buf: bytes, start: int, end: int) -> tuple[int, int]:
        """Re-emit the records of a chunk's content; return (messages, where it stopped)."""
        pos, count = start, 0
        while pos + 9 <= end:
            op, length = _HEAD.unpack_from(buf, pos)
            stop = pos + 9 + length
            if stop > end or op not in _KNOWN:
                break
            try:
                if op == _OP_MESSAGE:
                    count += self.message(buf, pos + 9, stop)
                elif op == _OP_SCHEMA:
                    self.schema(buf, pos + 9, stop)
                elif op == _OP_CHANNEL:
                    self.channel(buf, pos + 9, stop)
            except (_Bad, struct.error):
                break
            pos = stop
        return count, pos


def _rewrite(src: IO[bytes], out: IO[bytes], result: RecoverResult, name: str) -> None:
    """Walk the original's records (bounded memory) and write the finished file."""
    src.seek(0, os.SEEK_END)
    size = src.tell()
    rw = _Rewriter(out, result)
    rw.compression, rw.attachments = _prescan(src, size)
    for op, at, body, cut in _records(src, size, result):
        if op == _OP_HEADER:
            try:
                rw.profile, p = _string(body, 0, len(body))
                rw.library, _ = _string(body, p, len(body))
            except _Bad:
                pass
            continue
        try:
            if op == _OP_CHUNK:
                _chunk(rw, body, at, cut, result)
            elif op == _OP_SCHEMA:
                rw.schema(body, 0, len(body))
            elif op == _OP_CHANNEL:
                rw.channel(body, 0, len(body))
            elif op == _OP_MESSAGE:
                rw.message(body, 0, len(body))
            elif op == _OP_METADATA:
                rw.metadata(body, 0, len(body))
            elif op == _OP_ATTACHMENT:
                rw.attachment(body, 0, len(body))
        except (_Bad, struct.error) as exc:
            result.damaged.append(f'@{at}: unreadable record (opcode 0x{op:02x}): {exc}')
    if rw.unknown:
        result.damaged.append(f'{rw.unknown} message(s) on channels whose Channel record was lost')
        result.lost += rw.unknown
    writer = rw.start()
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime('%Y-%m-%dT%H:%M:%SZ')
    writer.add_metadata(
        'recovery',
        {
            'original': name,
            'finished_by': 'catenary_monitor.mcap_recover',
            'finished_at': stamp,
            'messages': str(result.messages),
            'damaged_parts': str(len(result.damaged)),
        },
    )
    writer.finish()


def _prescan(src: IO[bytes], size: int) -> tuple[str, bool]:
    """(compression of the first Chunk ('zstd' if none), whether Attachment records exist),
    reading record heads only."""
    pos, compression, attachments = len(MAGIC), '', False
    while pos + 9 <= size:
        src.seek(pos)
        op, length = _HEAD.unpack(src.read(9))
        if op == _OP_CHUNK and not compression:
            head = src.read(min(length, 64))
            header = _chunk_header(head, 0, len(head), partial=True)
            if header is not None and header[2] in _COMPRESSION:
                compression = header[2] or 'none'
        attachments |= op == _OP_ATTACHMENT
        if op not in _KNOWN or op in (_OP_DATA_END, _OP_FOOTER):
            break
        pos += 9 + length
    return ('' if compression == 'none' else compression or 'zstd'), attachments


def _records(
    src: IO[bytes], size: int, result: RecoverResult
) -> Iterator[tuple[int, int, bytes, bool]]:
    """Top-level records ``(opcode, offset, body, cut)`` up to the Data End / Footer or the
    end of the file; ``cut`` marks the last record if the file ends inside it. A damaged
    region is skipped to the next plausible Chunk (reported in ``result.damaged``)."""
    pos = len(MAGIC)
    while pos + 9 <= size:
        src.seek(pos)
        op, length = _HEAD.unpack(src.read(9))
        end = pos + 9 + length
        if op not in _KNOWN and op < 0x80:
            pos = _resync(src, pos, size, f'invalid opcode 0x{op:02x}', result)
            continue
        if op in (_OP_DATA_END, _OP_FOOTER):
            return
        if end > size:
            # Cut by the end of the file (the writer died in it), or a damaged length: then a
            # valid chunk follows somewhere (the reader's rule, io/mcap_read.py).
            found = _next_chunk(src, pos, size)
            if found >= 0:
                reason = f'record (opcode 0x{op:02x}) runs past the end'
                pos = _resync(src, pos, size, reason, result)
                continue
            if op != _OP_CHUNK:
                what = 'a Message Index (no message lost)' if op == 0x07 else 'a record'
                result.damaged.append(
                    f'@{pos}: file ends inside {what} (opcode 0x{op:02x}, {length} B)'
                )
                return
            if size - pos - 9 > MAX_CHUNK_BYTES + 4096:
                pos = _resync(src, pos, size, 'chunk length past the end of the file', result)
                continue
            yield op, pos, src.read(size - pos - 9), True
            return
        if length > MAX_CHUNK_BYTES + 4096:
            pos = _resync(src, pos, size, f'record of {length} B (implausible)', result)
            continue
        if op >= 0x80:
            pos = end  # a private record: not kept
            continue
        yield op, pos, src.read(length), False
        pos = end
    if pos < size:
        result.damaged.append(f'@{pos}: file ends inside a record header ({size - pos} B)')


def _next_chunk(src: IO[bytes], pos: int, size: int) -> int:
    """Offset of the next plausible Chunk record after ``pos``, or -1. The file is searched
    through a read-only memory map (page cache, not a copy)."""
    import mmap

    with mmap.mmap(src.fileno(), size, access=mmap.ACCESS_READ) as data:
        return _find_chunk(data, pos + 1)  # type: ignore[arg-type]


def _resync(src: IO[bytes], pos: int, size: int, reason: str, result: RecoverResult) -> int:
    """Offset of the next plausible Chunk record after ``pos`` (or ``size``); reported."""
    found = _next_chunk(src, pos, size)
    if found < 0:
        result.damaged.append(f'@{pos}: {reason}; nothing readable after it')
        return size
    result.damaged.append(f'@{pos}: {reason}; skipped {found - pos} B to the next chunk')
    return found


def _chunk(rw: _Rewriter, body: bytes, at: int, cut: bool, result: RecoverResult) -> None:
    """Re-emit a chunk's records: whole if it checks out, as far as it decodes if ``cut``."""
    header = _chunk_header(body, 0, len(body), partial=cut)
    if header is None:
        result.damaged.append(f'@{at}: chunk header inconsistent with its length')
        return
    usize, crc, compression, start, end = header
    problem = chunk_size_problem(usize, end - start, compression)
    if problem is not None:
        result.damaged.append(f'@{at}: chunk {problem}')
        return
    if cut:
        try:
            records = _decompress_partial(body, start, min(end, len(body)), compression, usize)
        except Exception:  # noqa: BLE001 - nothing of the cut chunk decodes
            records = b''
        count, _ = rw.records(bytes(records), 0, min(len(records), usize))
        result.salvaged_from_cut_chunk = count
        result.chunks += 1 if count else 0
        result.damaged.append(
            f'@{at}: file ends inside a chunk; {count} complete message(s) salvaged from it'
        )
        return
    try:
        records = bytes(_decompress(body, start, end, compression, usize))
    except Exception as exc:  # noqa: BLE001 - any decoder error: a damaged chunk
        result.damaged.append(f'@{at}: {compression} chunk cannot be decompressed: {exc}')
        return
    if len(records) != usize:
        result.damaged.append(f'@{at}: chunk decompresses to {len(records)} B, not {usize} B')
        return
    if crc and zlib.crc32(records) != crc:
        result.damaged.append(f'@{at}: chunk CRC mismatch')
        return
    result.chunks += 1
    _, stop = rw.records(records, 0, len(records))
    if stop != len(records):
        result.damaged.append(f'@{at}: chunk records unreadable from byte {stop} of {usize}')


def _string(buf: bytes, pos: int, end: int) -> tuple[str, int]:
    if pos + 4 > end:
        raise _Bad('string length runs past its record')
    (n,) = struct.unpack_from('<I', buf, pos)
    if pos + 4 + n > end:
        raise _Bad(f'string of {n} B runs past its record')
    return bytes(buf[pos + 4 : pos + 4 + n]).decode('utf-8', 'replace'), pos + 4 + n


def _bytes(buf: bytes, pos: int, end: int) -> bytes:
    if pos + 4 > end:
        raise _Bad('byte array length runs past its record')
    (n,) = struct.unpack_from('<I', buf, pos)
    if pos + 4 + n > end:
        raise _Bad(f'byte array of {n} B runs past its record')
    return bytes(buf[pos + 4 : pos + 4 + n])


def _string_map(buf: bytes, pos: int, end: int) -> dict[str, str]:
    if pos + 4 > end:
        raise _Bad('map length runs past its record')
    (n,) = struct.unpack_from('<I', buf, pos)
    p, stop = pos + 4, pos + 4 + n
    if stop > end:
        raise _Bad(f'map of {n} B runs past its record')
    out: dict[str, str] = {}
    while p < stop:
        key, p = _string(buf, p, stop)
        value, p = _string(buf, p, stop)
        out[key] = value
    return out


def _main(argv: list[str]) -> int:
    """``python -m catenary_monitor.io.mcap_recover FILE``: one JSON line per file (the node's
    child process; people use ``catenary-monitor log recover``)."""
    import json

    for arg in argv:
        print(json.dumps(recover_file(arg).to_dict()), flush=True)
    return 0


if __name__ == '__main__':
    import sys

    sys.exit(_main(sys.argv[1:]))
