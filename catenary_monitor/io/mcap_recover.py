"""Finish MCAP files left unfinished (writer killed): summary, indexes, statistics, CRCs.

A file whose writer was SIGKILLed has no summary and no footer and may end inside a chunk.
:func:`recover_file` walks it with the log reader (:class:`catenary_monitor.io.mcap_scan.Scanner`:
its damage rules and its bounds -- a chunk checked before use, one too large to hold decoded in
pieces, a damaged region skipped to the next chunk, the complete records of a chunk cut by the
end of the file), and writes every Message record it finds, as it is (sequence numbers, stamps
and bytes kept), into new chunks of about 1 MiB with the :class:`ColumnWriter` (same profile,
same chunk compression, channel and schema ids kept): chunk and message indexes, statistics,
summary and CRCs are the writer's. The first definition of every schema and channel id, and
the top-level Metadata and Attachment records, are kept; a message on a ``cdr`` channel too
short to hold a CDR encapsulation header (4 B) is dropped and counted. A ``recovery`` Metadata
record says what was done. Memory is bounded by a reader batch and the definitions kept; time
by the work of reading the file.

Steps, so that a crash at any point leaves a readable state and a rerun finishes the job:
the new file is written to ``.NAME.recover-tmp`` in the same folder and fsynced; it is read
back (CRC-validated summary, message count checked); the original is kept as
``NAME.unfinished`` (a hard link; copied where links are not supported); the new file replaces
``NAME`` atomically (``os.replace``) and the folder is fsynced. A finished file (valid footer
and magic at its end) is left alone (``already_finished``), so recovering twice changes
nothing.

For a folder, :func:`recover_path` also writes the folder's rosbag2 ``metadata.yaml``
(:mod:`catenary_monitor.io.bag_metadata`).
"""

from __future__ import annotations

import datetime as _dt
import errno
import os
import shutil
import struct
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import IO, Optional

import numpy as np

from catenary_monitor.io import bag_metadata
from catenary_monitor.io.mcap_column_writer import ColumnWriter
from catenary_monitor.io.mcap_finish import finish_in_place
from catenary_monitor.io.mcap_records import (
    MAGIC,
    BadRecord,
    chunk_header,
    read_bytes,
    read_string,
    read_string_map,
)
from catenary_monitor.io.mcap_scan import McapReadError, ReadReport, Scanner, gather

__all__ = [
    'RECOVERED',
    'RecoverResult',
    'is_finished',
    'recover_file',
    'recover_in_child',
    'recover_path',
    'unfinished_files',
    'BACKUP_SUFFIX',
]

#: The statuses of a file that is finished now (a copy, or in place for lack of room).
RECOVERED = ('recovered', 'finished_in_place')

#: Suffix of the kept original of a recovered file (not ``*.mcap``: no reader picks it up).
BACKUP_SUFFIX = '.unfinished'

_HEAD = struct.Struct('<BQ')
_FOOTER_LEN = 9 + 20
_OP_HEADER, _OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL = 0x01, 0x02, 0x03, 0x04
_OP_CHUNK, _OP_METADATA, _OP_DATA_END = 0x06, 0x0C, 0x0F
_KNOWN = frozenset(range(0x01, 0x10))
_COMPRESSION = ('zstd', 'lz4', '')
_CHUNK_SIZE = 1 << 20  # B, chunks of the recovered file (uncompressed)
_NO_ROOM = (errno.ENOSPC, errno.EDQUOT)  # a copy that does not fit
#: Bytes of Schema and Channel record bodies a recovery keeps (100 000 channels of rosbag2's
#: kind take about 60 MB): a file's definitions can come 1000-fold from compressed chunks.
_DEFINITIONS_BYTES = 64 << 20
_KEPT_RECORD_BYTES = 64 << 20  # B, the largest Metadata or Attachment record copied
_HEADS = 1 << 20  # top-level record heads read looking for the first chunk
_BATCH_BYTES = 2 << 20  # B of decompressed chunks the reader hands on at a time


@dataclass
class RecoverResult:
    """What :func:`recover_file` did with one file.

    status: ``recovered``, ``finished_in_place`` (no room for a copy: the summary appended to
    the file itself), ``already_finished``, ``in_use`` (a running logger holds its lock: left
    alone), ``not_mcap`` or ``failed`` (``error`` says why).
    messages: messages in the finished file; chunks: chunks read from the original;
    damaged: one sentence per damaged part skipped (a cut tail included); lost: messages
    known lost in them (a lower bound: a cut tail's count is unknown); backup: the kept
    original; output: where the finished file was written when not in place (``--out``).
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
    output: Optional[str] = None

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
    path: str | os.PathLike[str],
    keep_original: bool = True,
    out_dir: Optional[str | os.PathLike[str]] = None,
) -> tuple[list[RecoverResult], Optional[Path]]:
    """Recover a file or every ``*.mcap`` of a folder; write the folder's ``metadata.yaml``
    (with ``out_dir``: the finished files go there, the originals are left as they are, and
    ``out_dir`` gets the ``metadata.yaml``).

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
    if out_dir is not None:
        folder, bag = Path(out_dir), True
    results = [recover_file(f, keep_original, out_dir) for f in files]
    written = None
    if bag:
        try:
            written = bag_metadata.write_folder_metadata(folder)
        except OSError:
            written = None
    return results, written


def recover_file(
    path: str | os.PathLike[str],
    keep_original: bool = True,
    out_dir: Optional[str | os.PathLike[str]] = None,
) -> RecoverResult:
    """Finish one unfinished MCAP file (see the module docstring); with ``out_dir``, the
    finished copy is written there under the same name and the original is left as it is. When
    the copy does not fit on the disk (``ENOSPC``, ``EDQUOT``) and no ``out_dir`` is given, the
    file is finished where it lies instead (:func:`catenary_monitor.io.mcap_finish.
    finish_in_place`: a summary's room; the chunk cut by the end of the file is dropped, no
    original is kept). Never raises for a bad or unwritable file: the result's ``status`` and
    ``error`` say what happened."""
    path = Path(path)
    if is_finished(path):
        return RecoverResult(str(path), 'already_finished')
    result = RecoverResult(str(path), 'recovered')
    where = path.parent if out_dir is None else Path(out_dir)
    elsewhere = out_dir is not None and not _same_dir(where, path.parent)
    final = where / path.name if elsewhere else path
    tmp = where / f'.{path.name}.recover-tmp'
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
            if elsewhere and final.exists():
                raise FileExistsError(f'{final} exists: not overwritten')
            with open(tmp, 'wb') as out:
                _rewrite(path, out, result, path.name)
                out.flush()
                os.fsync(out.fileno())
        _check_written(tmp, result.messages)
        if keep_original and not elsewhere:
            backup = path.with_name(path.name + BACKUP_SUFFIX)
            _keep(path, backup)
            result.backup = str(backup)
        os.replace(tmp, final)
        bag_metadata.fsync_dir(final.parent)
        result.output = str(final) if elsewhere else None
    except Exception as exc:  # noqa: BLE001 - reported per file, never a traceback
        try:
            tmp.unlink()
        except OSError:
            pass
        if isinstance(exc, OSError) and exc.errno in _NO_ROOM and not elsewhere:
            return _in_place(path, exc)
        result.status, result.error = 'failed', f'{type(exc).__name__}: {exc}'
        if isinstance(exc, OSError) and exc.errno in _NO_ROOM:
            result.error += f' (no room in {where})'
    return result


def _same_dir(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:
        return False


def _in_place(path: Path, why: OSError) -> RecoverResult:
    """:func:`recover_file`'s answer to a disk too full for a copy: finished where it lies."""
    result = RecoverResult(str(path), 'finished_in_place')
    try:
        result.messages, damaged = finish_in_place(path)
    except Exception as exc:  # noqa: BLE001
        result.status = 'failed'
        result.error = (
            f'no room for a copy ({why.strerror}) nor for a summary in place: '
            f'{type(exc).__name__}: {exc}; free space, or write the copy elsewhere with --out DIR'
        )
        return result
    result.damaged = [
        f'no room for a copy ({why.strerror}): finished in place, the file cut after its last '
        'whole chunk (a chunk the end of the file cut is dropped; no original kept)',
        *damaged,
    ]
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


class _Copy:
    """What a recovery carries from the original into the new file (a :class:`ColumnWriter`):
    the first definition of every schema and channel id (at most :data:`_DEFINITIONS_BYTES`
    of them), top-level Metadata and Attachment records, and the Message records of the
    blocks the reader hands on, copied as they are into chunks of about 1 MiB."""

    def __init__(self, writer: ColumnWriter, result: RecoverResult) -> None:
        self.writer = writer
        self.result = result
        self.schemas: dict[int, tuple[str, str, bytes]] = {}
        self.channels: dict[int, tuple[str, str, int, dict[str, str]]] = {}
        self.registered: set[int] = set()
        self.budget = _DEFINITIONS_BYTES
        self.refused = 0  # definitions past the budget
        self.undefined = 0  # messages on them
        self.short = 0  # messages on cdr channels too short for a CDR encapsulation header

    def definition(self, op: int, buf: bytes | memoryview, pos: int, end: int) -> None:
        """A Schema or Channel record body (the reader parsed it already)."""
        (key,) = struct.unpack_from('<H', buf, pos)
        known = self.schemas if op == _OP_SCHEMA else self.channels
        if key in known or (op == _OP_SCHEMA and key == 0):
            return
        if end - pos > self.budget:
            self.refused += 1
            return
        self.budget -= end - pos
        try:
            if op == _OP_SCHEMA:
                name, p = read_string(buf, pos + 2, end)
                encoding, p = read_string(buf, p, end)
                self.schemas[key] = (name, encoding, read_bytes(buf, p, end))
            else:
                (sid,) = struct.unpack_from('<H', buf, pos + 2)
                topic, p = read_string(buf, pos + 4, end)
                encoding, p = read_string(buf, p, end)
                self.channels[key] = (topic, encoding, sid, read_string_map(buf, p, end))
        except (BadRecord, struct.error):
            self.refused += 1

    def record(self, op: int, data: bytes, pos: int, end: int) -> None:
        """A top-level Metadata or Attachment record body."""
        try:
            if end - pos > _KEPT_RECORD_BYTES:
                raise BadRecord(f'{end - pos} B, more than the {_KEPT_RECORD_BYTES} B kept')
            if op == _OP_METADATA:
                name, p = read_string(data, pos, end)
                self.writer.add_metadata(name, read_string_map(data, p, end))
                return
            log_time, create_time = struct.unpack_from('<QQ', data, pos)
            name, p = read_string(data, pos + 16, end)
            media, p = read_string(data, p, end)
            (size,) = struct.unpack_from('<Q', data, p)
            if p + 8 + size > end:
                raise BadRecord('attachment data runs past its record')
            body = bytes(data[p + 8 : p + 8 + size])
            self.writer.add_attachment(name, media, body, log_time, create_time)
        except (BadRecord, struct.error) as exc:
            self.result.damaged.append(f'@{pos - 9}: record (opcode 0x{op:02x}) not kept: {exc}')

    def _register(self, cid: int) -> bool:
        """Define channel ``cid`` (and its schema) in the new file; False if it is unknown."""
        if cid in self.registered:
            return True
        if cid not in self.channels:
            return False
        topic, encoding, sid, metadata = self.channels[cid]
        if sid in self.schemas:
            name, schema_encoding, data = self.schemas[sid]
            self.writer.register_schema(name, schema_encoding, data, schema_id=sid)
        else:
            sid = 0  # lost, or none: a channel without schema
        self.writer.register_channel(topic, encoding, sid, metadata, channel_id=cid)
        self.registered.add(cid)
        return True

    def block(
        self,
        buf: bytes | memoryview,
        offsets: np.ndarray,
        lengths: np.ndarray,
        channels: np.ndarray,
    ) -> None:
        """Copy a block's Message records (file order) into chunks of about 1 MiB."""
        ok = np.zeros(1 << 16, bool)
        cdr = np.zeros(1 << 16, bool)
        for cid in np.unique(channels).tolist():
            ok[cid] = self._register(cid)
            cdr[cid] = ok[cid] and self.channels[cid][1] == 'cdr'
        keep = ok[channels]
        self.undefined += int(np.count_nonzero(~keep))
        short = keep & cdr[channels] & (lengths < 22 + 4)
        self.short += int(np.count_nonzero(short))
        keep &= ~short
        if not keep.all():
            offsets, lengths, channels = offsets[keep], lengths[keep], channels[keep]
        if not len(offsets):
            return
        arr = np.frombuffer(buf, np.uint8)
        times = gather(arr, offsets + 15, 8).view('<u8').ravel().astype(np.int64)
        data, placed = _records(buf, arr, offsets, 9 + lengths)
        group = placed // _CHUNK_SIZE
        cuts = [0, *(np.flatnonzero(np.diff(group)) + 1).tolist(), len(placed)]
        for a, b in zip(cuts[:-1], cuts[1:]):
            lo = int(placed[a])
            hi = int(placed[b]) if b < len(placed) else len(data)
            self.writer.write_records(data[lo:hi], channels[a:b], times[a:b], placed[a:b] - lo)

    def finish(self) -> None:
        """Define the channels no message used (their records are kept too)."""
        for cid in sorted(self.channels):
            self._register(cid)
        if self.refused:
            self.result.damaged.append(
                f'{self.refused} Schema or Channel record(s) not kept (damaged, or past the '
                f'{_DEFINITIONS_BYTES} B of definitions kept)'
            )
        if self.undefined:
            self.result.damaged.append(
                f'{self.undefined} message(s) on channels without a kept Channel record'
            )
            self.result.lost += self.undefined
        if self.short:
            self.result.damaged.append(
                f'{self.short} message(s) too short to be CDR (no encapsulation header) '
                'dropped'
            )
            self.result.lost += self.short


def _records(
    buf: bytes | memoryview, arr: np.ndarray, offsets: np.ndarray, sizes: np.ndarray
) -> tuple[bytes | memoryview, np.ndarray]:
    """The records at ``offsets`` (``sizes`` B each, in order) back to back, and where each
    starts there: a view when they are already back to back, else a copy."""
    ends = offsets + sizes
    placed = np.zeros(len(offsets), np.int64)
    np.cumsum(sizes[:-1], out=placed[1:])
    first, last = int(offsets[0]), int(ends[-1])
    if np.array_equal(offsets[1:], ends[:-1]):
        return memoryview(buf)[first:last], placed
    if last - first <= 4 * int(placed[-1] + sizes[-1]):
        mark = np.zeros(last - first + 1, np.int8)
        mark[offsets - first] += 1
        mark[ends - first] -= 1
        return arr[first:last][np.cumsum(mark[:-1]) > 0].tobytes(), placed
    view = memoryview(buf)
    return b''.join(view[a:b] for a, b in zip(offsets.tolist(), ends.tolist())), placed


def _rewrite(path: Path, out: IO[bytes], result: RecoverResult, name: str) -> None:
    """Walk the original with the reader (its damage rules and bounds) and write the finished
    file with the records copied as they are."""
    report = ReadReport()
    scanner = Scanner(path, lambda channel: True, report)
    scanner.batch_bytes = _BATCH_BYTES
    profile, library = _header(scanner.data)
    writer = ColumnWriter(
        out,
        compression=_first_compression(scanner.data) or 'none',
        chunk_bytes=_CHUNK_SIZE,
        profile=profile,
        library=(library + '; finished by catenary_monitor.io.mcap_recover').lstrip('; '),
    )
    copy = _Copy(writer, result)
    scanner.on_definition = copy.definition
    scanner.on_record = copy.record
    try:
        for block in scanner.blocks():
            copy.block(block.buf, block.offsets, block.lengths, block.channels)
    except McapReadError as exc:
        result.damaged.append(f'@0: {exc}')
    scanner.finish()
    copy.finish()
    result.chunks = scanner.file_report.chunks
    for skip in report.skips:
        if skip.kind == 'truncated' and skip.offset == scanner.cut_chunk_at:
            result.salvaged_from_cut_chunk = scanner.recovered
            text = (
                f'@{skip.offset}: file ends inside a chunk; {scanner.recovered} complete '
                'message(s) salvaged from it'
            )
        else:
            text = f'@{skip.offset}: {skip.reason}'
        if skip.messages_lost:
            text += f' ({skip.messages_lost} message(s) lost)'
            result.lost += skip.messages_lost
        result.damaged.append(text)
    result.messages = writer.messages
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime('%Y-%m-%dT%H:%M:%SZ')
    writer.add_metadata(
        'recovery',
        {
            'original': name,
            'finished_by': 'catenary_monitor.io.mcap_recover',
            'finished_at': stamp,
            'messages': str(result.messages),
            'damaged_parts': str(len(result.damaged)),
        },
    )
    writer.finish()


def _header(data: bytes) -> tuple[str, str]:
    """(profile, library) of the file's Header record ('' where it has none)."""
    if len(data) < len(MAGIC) + 9:
        return '', ''
    op, length = _HEAD.unpack_from(data, len(MAGIC))
    end = len(MAGIC) + 9 + length
    if op != _OP_HEADER or end > len(data) or length > 1 << 20:
        return '', ''
    try:
        profile, p = read_string(data, len(MAGIC) + 9, end)
        library, _ = read_string(data, p, end)
    except (BadRecord, struct.error):
        return '', ''
    return profile, library


def _first_compression(data: bytes) -> str:
    """The compression of the file's first Chunk record ('' if none is found among the first
    :data:`_HEADS` top-level records): the new file's chunks are compressed alike."""
    pos = len(MAGIC)
    for _ in range(_HEADS):
        if pos + 9 > len(data):
            break
        op, length = _HEAD.unpack_from(data, pos)
        if op == _OP_CHUNK:
            header = chunk_header(data, pos + 9, min(len(data), pos + 9 + length), partial=True)
            if header is not None and header[2] in _COMPRESSION:
                return header[2] or 'none'
            break
        if op not in _KNOWN or op in (_OP_DATA_END, _OP_FOOTER):
            break
        pos += 9 + length
    return ''


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
