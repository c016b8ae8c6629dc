"""Logs as a crash leaves them, for the recovery tests (a real McapLogger file, cut)."""

from __future__ import annotations

import struct
from pathlib import Path

from catenary_monitor.io.mcap_log import McapLogger

TOPICS = ('/chain_01/tension', '/tide/depth')


def cdr(value: float) -> bytes:
    return b'\x00\x01\x00\x00' + struct.pack('<d', value)


def write_log(
    folder: Path, compression: str, n: int = 3000, close: bool = False, chunk_size: int = 8192
) -> Path:
    """A logger file with several flushed chunks; unfinished unless ``close``."""
    log = McapLogger(folder, compression=compression, fsync=False, chunk_size=chunk_size)
    for topic in TOPICS:
        log.register(topic, 'std_msgs/msg/Float64', 'sensor_data')
    log.add_metadata('catenary_monitor', {'config_hash': 'abc'})
    for i in range(n):
        log.write(TOPICS[i % 2], cdr(float(i)), 10**18 + 1000 * i)
    log.flush()
    path = log.current_path
    assert path is not None
    if close:
        log.close()
    return path


def cut_inside_last_chunk(path: Path) -> int:
    """Cut the file in the middle of its last Chunk record (as a kill mid-write does)."""
    data = path.read_bytes()
    pos, last = 8, None
    while pos + 9 <= len(data):
        op, length = struct.unpack_from('<BQ', data, pos)
        if op == 0x06:
            last = (pos, length)
        pos += 9 + length
    assert last is not None
    cut = last[0] + 9 + int(last[1] * 0.6)
    path.write_bytes(data[:cut])
    return cut


def cut_log(folder: Path, compression: str = 'zstd') -> Path:
    """A 20 000-message log with 300 kB chunks, cut inside its last chunk."""
    path = write_log(folder, compression, n=20000, chunk_size=300_000)
    cut_inside_last_chunk(path)
    return path
