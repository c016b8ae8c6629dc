"""The reader's C loops (catenary_monitor/io/_scan.c) against its numpy passes.

Both paths must give the same columns, the same report and the same errors, on good files
and on damaged ones (bit flips anywhere, Message Index entries pointing elsewhere, duplicated,
out of range or out of order, chunks without index). The reader's damage tests also run here
on the numpy path (they run on the C path in their own files).
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader

import catenary_monitor.io.mcap_read as mcap_read
import catenary_monitor.io.mcap_scan as mcap_scan
from catenary_monitor.io.mcap_read import iter_windows, read_float64_topics
from catenary_monitor.io.mcap_scan import ReadReport

from test_mcap_hostile import KINDS, hostile  # noqa: F401 - the fixture, for the tests below
from test_mcap_hostile import (  # noqa: F401 - rerun on the numpy path
    test_hostile_chunk_is_skipped_in_bounded_memory_and_the_rest_read,
)
from test_mcap_read import (  # noqa: F401 - rerun on the numpy path
    TOPICS,
    chunk_layout,
    sample_messages,
    test_big_endian_and_bad_payloads,
    test_corrupt_chunk_is_skipped_and_counted,
    test_corrupt_message_index_falls_back_to_walking,
    test_damaged_chunk_length_resyncs_to_the_next_chunk,
    test_lost_channel_definitions_come_from_the_summary,
    test_random_damage_never_raises_or_invents_data,
    test_rosbag2_layouts_match_oracle,
    test_truncated_file_gives_the_readable_prefix,
    write_own_log,
    write_rosbag2_style,
)

SCAN = mcap_scan._scan


@pytest.fixture(autouse=True)
def numpy_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every test of this file starts on the numpy path (the imported ones stay there)."""
    monkeypatch.setattr(mcap_scan, '_scan', None)


@pytest.mark.c_extension
def test_the_c_loops_are_built() -> None:
    assert SCAN is not None, 'io/_scan.c is not built: python setup.py build_ext --inplace'


def _bits(v: np.ndarray) -> list[int]:
    return v.view(np.int64).tolist()  # NaN payloads compare too


def _read(path: Path, windows: bool) -> Any:
    """Everything the reader says about a file: columns or windows, report, or the error."""
    report = ReadReport()
    try:
        if windows:
            got: Any = [
                (w.hi, w.messages, {k: (t.tolist(), _bits(v)) for k, (t, v) in w.columns.items()})
                for w in iter_windows([path], TOPICS, window_messages=50, report=report)
            ]
        else:
            columns, report = read_float64_topics(path, TOPICS)
            got = {k: (t.tolist(), _bits(v)) for k, (t, v) in columns.items()}
            for t, v in columns.values():
                assert t.dtype == np.int64 and v.dtype == np.float64
    except Exception as exc:  # noqa: BLE001 - the same error on both paths
        return ('error', type(exc).__name__, str(exc))
    return got, report


def _both(path: Path, windows: bool = False) -> Any:
    mcap_scan._scan = None
    expected = _read(path, windows)
    mcap_scan._scan = SCAN
    try:
        got = _read(path, windows)
    finally:
        mcap_scan._scan = None
    assert got == expected
    return got


@pytest.mark.c_extension
def test_same_results_on_good_files(tmp_path: Path) -> None:
    files = write_own_log(tmp_path / 'own', 700, chunk_size=2500, compression='zstd')
    bag = write_rosbag2_style(tmp_path / 'bag.mcap', sample_messages(700), compression='zstd')
    for path in [*files, bag]:
        for windows in (False, True):
            got = _both(path, windows)
            assert got[0], path


def _index_entries(path: Path) -> list[tuple[int, int]]:
    """(file offset of a Message Index record's first entry, entries) for every chunk."""
    with open(path, 'rb') as handle:
        summary = make_reader(handle).get_summary()
    out = []
    for ci in summary.chunk_indexes:
        for offset in ci.message_index_offsets.values():
            nbytes = struct.unpack_from('<I', path.read_bytes(), offset + 11)[0]
            out.append((offset + 15, nbytes // 16))
    return out


@pytest.mark.c_extension
def test_same_results_on_damaged_message_indexes(tmp_path: Path) -> None:
    """Index entries moved (inside a record, onto another channel's record, onto another
    entry's record, out of the chunk, out of order); the checks must agree entry by entry."""
    src = write_rosbag2_style(
        tmp_path / 'bag.mcap', sample_messages(600), compression='zstd', chunk_size=4096
    )
    data = src.read_bytes()
    indexes = [(at, n) for at, n in _index_entries(src) if n >= 3]
    assert len(indexes) >= 6
    rng = np.random.default_rng(13)
    damaged = tmp_path / 'damaged.mcap'
    kinds = ['shift', 'next', 'same', 'far', 'swap', 'zero']
    for trial in range(120):
        blob = bytearray(data)
        for _ in range(int(rng.integers(1, 4))):
            at, n = indexes[int(rng.integers(len(indexes)))]
            i = int(rng.integers(n - 1))
            entry = at + 16 * i + 8  # the offset field
            offset = struct.unpack_from('<Q', blob, entry)[0]
            kind = kinds[trial % len(kinds)]
            if kind == 'shift':
                new = offset + int(rng.integers(1, 43))
            elif kind == 'next':
                new = offset + 43
            elif kind == 'same':
                new = struct.unpack_from('<Q', blob, entry + 16)[0]
            elif kind == 'far':
                new = [1 << 20, 2**63 + 5, 2**64 - 1][int(rng.integers(3))]
            elif kind == 'swap':
                new = struct.unpack_from('<Q', blob, entry + 16)[0]
                struct.pack_into('<Q', blob, entry + 16, offset)
            else:
                new = 0
            struct.pack_into('<Q', blob, entry, new)
        damaged.write_bytes(blob)
        _both(damaged)
        if trial % 10 == 0:
            _both(damaged, windows=True)


@pytest.mark.c_extension
def test_same_results_on_random_damage(tmp_path: Path) -> None:
    """Bit flips anywhere (mostly in the index, which has no CRC), in two kinds of file."""
    own = write_own_log(tmp_path / 'own', 600, chunk_size=2500, compression='zstd')[0]
    bag = write_rosbag2_style(
        tmp_path / 'bag.mcap', sample_messages(600), compression='none', chunk_size=3000
    )
    rng = np.random.default_rng(17)
    damaged = tmp_path / 'damaged.mcap'
    outcomes = set()
    for src in (own, bag):
        data = src.read_bytes()
        for _ in range(120):
            blob = bytearray(data)
            for at in rng.integers(0, len(blob), rng.integers(1, 6)).tolist():
                blob[at] ^= 1 << int(rng.integers(8))
            damaged.write_bytes(blob)
            got = _both(damaged)
            outcomes.add('error' if got[0] == 'error' else len(got[1].skips) > 0)
    assert outcomes >= {True, False}


@pytest.mark.c_extension
def test_gather_and_columns_match_numpy() -> None:
    """The C gather and the Float64 columns, record by record (big and little endian, bad
    encapsulation, records too short or running past the buffer)."""
    rng = np.random.default_rng(5)
    records = []
    for i in range(300):
        value = float(rng.normal())
        big = i % 7 == 3
        encaps = b'\x00\x00' if big else b'\x00\x01'
        if i % 11 == 5:
            encaps = b'\x00\x02'
        payload = encaps + b'\x00\x00' + struct.pack('>d' if big else '<d', value)
        channel = 1 + i % 3
        records.append(
            struct.pack('<BQHIQQ', 5, 22 + 12, channel, i, 1000 + i, 1000 + i) + payload
        )
    buf = b''.join(records)
    offsets = np.arange(0, len(buf), 43, dtype=np.int64)
    offsets[17] = len(buf) - 20  # runs past the end
    lengths = np.full(len(offsets), 34, np.int64)
    lengths[23] = 30  # too short
    channels = (1 + np.arange(len(offsets)) % 3).astype(np.uint16)
    lut = np.full(1 << 16, -1, np.int64)
    lut[1:4] = [2, 0, 1]
    arr = np.frombuffer(buf, np.uint8)
    for width in (2, 8, 11, 43):
        mcap_scan._scan = SCAN
        fast = mcap_scan.gather(arr, offsets[offsets + width <= len(buf)], width)
        mcap_scan._scan = None
        slow = mcap_scan.gather(arr, offsets[offsets + width <= len(buf)], width)
        assert np.array_equal(fast, slow)
    with pytest.raises(IndexError):
        SCAN.gather(arr, np.array([len(buf) - 1], np.int64), 2, np.empty(2, np.uint8))

    class Scanner:
        topic_lut = lut
        topic_names = ['a', 'b', 'c']

        def __init__(self) -> None:
            self.file_report = mcap_scan.FileReport('x', 0)
            self.skips: list[tuple[Any, ...]] = []

        def skip(self, *args: Any) -> None:
            self.skips.append(args)

        def bad_payload(self, offset: int, bad: int) -> None:
            self.skips.append(('bad_payload', offset, bad))

    block = mcap_scan.Block(buf, offsets, lengths, channels, 0)
    results = []
    for scan in (SCAN, None):
        mcap_scan._scan = scan
        scanner = Scanner()
        columns = mcap_scan.block_columns(scanner, block)  # type: ignore[arg-type]
        results.append(
            (
                {k: (t.tolist(), v.tolist()) for k, (t, v) in columns.items()},
                scanner.skips,
                scanner.file_report.messages,
            )
        )
    assert results[0] == results[1]
    assert results[0][1] and results[0][2] == 300 - len(range(5, 300, 11)) - 2


def test_read_ahead_gives_the_same_windows_and_stops_with_its_caller(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The reader thread of iter_windows (one batch ahead) changes nothing handed out or
    reported; a caller that stops early leaves no thread behind."""
    import threading

    files = write_own_log(tmp_path / 'own', 900, chunk_size=2500, compression='zstd')
    blob = bytearray(files[0].read_bytes())
    start, end, _ = chunk_layout(files[0])[2]
    blob[(start + end) // 2] ^= 0x10  # a corrupt chunk: reported on the way
    files[0].write_bytes(blob)
    got = []
    for ahead in (0, 1, 2):
        monkeypatch.setattr(mcap_read, 'READ_AHEAD', ahead)
        got.append(_both(files[0], windows=True))
    assert got[0] == got[1] == got[2]
    assert got[0][1].skips, 'the damage is reported'
    monkeypatch.setattr(mcap_read, 'READ_AHEAD', 1)
    big = write_own_log(tmp_path / 'big', 30000, chunk_size=4096, compression='zstd')
    windows = iter_windows(big, TOPICS, window_messages=20)  # batches of 64 KiB: about 20
    next(windows)
    assert any(t.name == 'mcap-read-ahead' for t in threading.enumerate())
    windows.close()
    assert not any(t.name == 'mcap-read-ahead' for t in threading.enumerate())


@pytest.mark.c_extension
def test_walk_matches_the_python_walk() -> None:
    """The C walk and the Python one (with its runs of equal records) give the same Message
    starts and stop at the same byte: runs, definitions in between, private records, a record
    that is not one, a record cut by the end, a full output array."""
    h = __import__('hostile_mcap')
    msg = [h.message(float(i), 100 + i, seq=i) for i in range(50)]
    private = h.record(0x80, b'xyz')
    empty = h.record(0x05, struct.pack('<HIQQ', 1, 0, 5, 5))
    bufs = {
        'run': b''.join(msg),
        'mixed': b''.join(msg[:10]) + h.schema() + h.channel() + private * 7 + b''.join(msg),
        'empty_run': empty * 300 + private * 300 + empty,
        'alternating': (empty + private) * 40,
        'bad_op': b''.join(msg[:5]) + h.record(0x33, b'') + b''.join(msg[:5]),
        'short_message': b''.join(msg[:3]) + h.record(0x05, b'\x01' * 10),
        'cut': b''.join(msg[:8])[:-5],
        'bad_channel': b''.join(msg[:4]) + h.record(0x04, b'\x01\x00') + b''.join(msg[:4]),
    }
    for name, buf in bufs.items():
        got = []
        for scan in (SCAN, None):
            mcap_scan._scan = scan
            scanner = mcap_scan.Scanner.__new__(mcap_scan.Scanner)
            scanner.schemas, scanner.summary_schemas, scanner.channels = {}, {}, {}
            scanner.known_lut = np.zeros(1 << 16, bool)
            scanner.topic_lut = np.full(1 << 16, -1, np.int64)
            scanner.accepted, scanner.topic_names, scanner.topic_index = set(), [], {}
            scanner.accept = lambda channel: True
            scanner.on_definition = None
            offsets, stop = scanner._walk(buf, 0, len(buf))
            got.append((offsets.tolist(), stop, sorted(scanner.channels)))
        assert got[0] == got[1], name
    out = np.empty(3, np.int64)
    assert SCAN.walk(bufs['run'], 0, len(bufs['run']), out) == (3, 3 * 43, 3)
