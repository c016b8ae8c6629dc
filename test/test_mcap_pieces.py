"""Chunks too large to hold, decoded in pieces (io/mcap_scan.py ``_big_chunk``, ``_cut_chunk``).

A chunk declaring more than ``WHOLE_CHUNK_BYTES`` is checked in a first streaming pass (size,
CRC) and then decoded again and walked piece by piece, a record cut between pieces waiting for
the next. Here every chunk is taken that way (the limit set to 0) with pieces and walks of a
few dozen bytes, so that every record boundary falls inside a piece somewhere: the reader must
give the same columns and the same damage report as when it holds each chunk whole, on the
reader's own good and damaged files, with the C walk and without it.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import hostile_mcap
import numpy as np
import pytest

import catenary_monitor.io.mcap_scan as mcap_scan
from catenary_monitor.io.mcap_read import iter_windows, read_float64_topics
from catenary_monitor.io.mcap_scan import ReadReport

from test_mcap_read import (  # noqa: F401 - rerun with every chunk decoded in pieces
    TOPICS,
    sample_messages,
    test_big_endian_and_bad_payloads,
    test_corrupt_chunk_is_skipped_and_counted,
    test_lost_channel_definitions_come_from_the_summary,
    test_rosbag2_layouts_match_oracle,
    test_truncated_file_gives_the_readable_prefix,
    write_own_log,
    write_rosbag2_style,
)


def _pieces(monkeypatch: pytest.MonkeyPatch, on: bool) -> None:
    """Every chunk decoded in pieces of a few dozen bytes (``on``), or every chunk whole."""
    monkeypatch.setattr(mcap_scan, 'WHOLE_CHUNK_BYTES', 0 if on else 1 << 40)
    monkeypatch.setattr(mcap_scan, '_BATCH_BYTES', 97 if on else 8 << 20)
    monkeypatch.setattr(mcap_scan, '_READ_STEP', 37 if on else 1 << 20)
    monkeypatch.setattr(mcap_scan, '_STREAM_STEP', 53 if on else 8 << 20)


@pytest.fixture(autouse=True)
def in_pieces(monkeypatch: pytest.MonkeyPatch) -> None:
    """The imported reader tests run with every chunk decoded in pieces."""
    _pieces(monkeypatch, True)


def _read(path: Path) -> Any:
    """Columns and the report's facts (kinds, offsets, losses; not the sentences), or the error."""
    try:
        columns, report = read_float64_topics(path, TOPICS)
    except Exception as exc:  # noqa: BLE001 - the same error both ways
        return ('error', type(exc).__name__)
    cols = {k: (t.tolist(), v.view(np.int64).tolist()) for k, (t, v) in columns.items()}
    skips = [(s.kind, s.offset, s.messages_lost) for s in report.skips]
    return cols, skips, [(f.chunks, f.messages, f.finished) for f in report.files]


def _windows(path: Path) -> Any:
    """Every message the windows hand out, in order (the cuts follow the batches, which
    differ), and the report's facts."""
    report = ReadReport()
    try:
        got: dict[str, list[int]] = {}
        for w in iter_windows([path], TOPICS, window_messages=40, report=report):
            for k, (t, _) in w.columns.items():
                got.setdefault(k, []).extend(t.tolist())
    except Exception as exc:  # noqa: BLE001
        return ('error', type(exc).__name__)
    return got, [(s.kind, s.offset) for s in report.skips]


def _same(monkeypatch: pytest.MonkeyPatch, path: Path, windows: bool = False) -> Any:
    """The same outcome both ways. A loss unknown when whole chunks are read may be known in
    pieces: a chunk in pieces is walked before the next is looked at, so the Channel records
    of the chunks before a damaged one are known when its loss is counted (whole chunks wait
    in a batch)."""
    read = _windows if windows else _read
    _pieces(monkeypatch, False)
    whole = read(path)
    _pieces(monkeypatch, True)
    got = read(path)
    if not windows and whole[0] != 'error' and got[0] != 'error':
        assert len(got[1]) == len(whole[1]), (got[1], whole[1])
        pairs = zip(sorted(got[1], key=str), sorted(whole[1], key=str))  # found in any order
        for (kind, at, lost), (kind_w, at_w, lost_w) in pairs:
            assert (kind, at) == (kind_w, at_w) and lost_w in (None, lost), (got[1], whole[1])
        got, whole = (got[0], got[2]), (whole[0], whole[2])
    assert got == whole
    return whole


@pytest.mark.parametrize('walk', ['c', 'numpy'])
def test_pieces_give_what_whole_chunks_give(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, walk: str
) -> None:
    if walk == 'numpy':
        monkeypatch.setattr(mcap_scan, '_scan', None)
    elif mcap_scan._scan is None:
        pytest.skip('io/_scan.c is not built')
    own = write_own_log(tmp_path / 'own', 400, chunk_size=2500, compression='zstd')
    bag = write_rosbag2_style(tmp_path / 'bag.mcap', sample_messages(400), compression='lz4')
    raw = write_rosbag2_style(
        tmp_path / 'raw.mcap', sample_messages(400), compression='none', chunk_size=3000
    )
    for path in [*own, bag, raw]:
        assert _same(monkeypatch, path)[0]
        _same(monkeypatch, path, windows=True)
    rng = np.random.default_rng(23)
    damaged = tmp_path / 'damaged.mcap'
    for src in (own[0], bag):
        data = src.read_bytes()
        for trial in range(25):
            blob = bytearray(data)
            if trial % 4 == 0:
                blob = blob[: int(rng.integers(len(blob) // 2, len(blob)))]  # cut
            for at in rng.integers(0, len(blob), rng.integers(1, 4)).tolist():
                blob[at] ^= 1 << int(rng.integers(8))
            damaged.write_bytes(bytes(blob))
            _same(monkeypatch, damaged)


def test_equal_records_in_pieces_without_the_c_walk(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Millions of equal records cost a few numpy passes, not a Python step each."""
    monkeypatch.setattr(mcap_scan, '_scan', None)
    _pieces(monkeypatch, False)
    monkeypatch.setattr(mcap_scan, 'WHOLE_CHUNK_BYTES', 1 << 20)
    path = hostile_mcap.empty_records_file(
        tmp_path / 'empty.mcap', 'lz4', (hostile_mcap.TOPIC,), chunks=1, usize=64 << 20
    )
    columns, report = read_float64_topics(path, [hostile_mcap.TOPIC])
    assert len(columns[hostile_mcap.TOPIC][0]) == 8  # the good chunks' messages
    [skip] = report.skips
    per_piece = (8 << 20) // 31  # empty Message records per 8 MiB piece of the builder
    assert skip.kind == 'bad_payload'
    assert skip.messages_lost == (64 << 20) // (31 * per_piece) * per_piece


def test_a_record_too_long_to_hold_is_dropped_and_reported(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(mcap_scan, 'LONG_RECORD_BYTES', 1000)
    h = hostile_mcap
    records = (
        h.message(1.0, 10)
        + h.record(0x80, bytes(5000))  # a private record: dropped silently
        + h.message(2.0, 11)
        + h.record(0x05, struct.pack('<HIQQ', 1, 0, 12, 12) + bytes(3000))  # a long message
        + h.message(3.0, 13)
    )
    import zstandard

    data = zstandard.ZstdCompressor().compress(records)
    blob = h.MAGIC + h.header() + h.schema() + h.channel()
    blob += h.chunk(records, 'zstd', data, len(records), 10, 13)
    path = tmp_path / 'long.mcap'
    path.write_bytes(blob)
    columns, report = read_float64_topics(path, [h.TOPIC])
    assert columns[h.TOPIC][1].tolist() == [1.0, 2.0, 3.0]
    reasons = [s.reason for s in report.skips if s.kind == 'corrupt_chunk']
    assert len(reasons) == 1 and 'a Message record of 3031 B dropped unread' in reasons[0]
