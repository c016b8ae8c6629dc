"""Generated dock folders for the fleet tests: node-shaped rotated logs (the parameters
recorded in a metadata record, a start and 1 Hz ticks on the events channel), or sensor
recordings with the folder's own params file (ticks on a grid)."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import numpy as np
from replay_data import dock_config, generate, params_yaml

from catenary_monitor.core.config.parameters import config_hash, config_to_params
from catenary_monitor.core.monitor.events import (
    EVENTS_TOPIC,
    NODE_NAME,
    Acknowledge,
    Start,
    Tick,
    event_record,
)
from catenary_monitor.io.cdr import string_message
from catenary_monitor.io.mcap_log import McapLogger

DAY_NS = 86_400 * 10**9


def _events(tensions: dict[str, Any], first: int, last: int) -> list[Any]:
    """A node's events: its start, ticks at 1 Hz (some at an input's very stamp), an
    acknowledgement."""
    ticks = np.arange(first + 100_001, last, 1_000_000_000, dtype=np.int64)
    line0 = next(iter(tensions.values()))[0]
    ticks[5::7] = line0[np.searchsorted(line0, ticks[5::7]).clip(0, len(line0) - 1)]
    out = [Start(first - 500_000_000)] + [Tick(int(t)) for t in np.unique(ticks)]
    out.append(Acknowledge((first + last) // 2 + 17, None, 'console'))
    return sorted(out, key=lambda e: e.stamp_ns)


def write_dock(
    folder: Path,
    seconds: float = 60.0,
    files: int = 3,
    seed: int = 1,
    n_lines: int = 3,
    node: bool = True,
    offset_ns: int = 0,
    storm_line: int = 1,
) -> Path:
    """A dock folder of ``files`` rotated MCAP files over ``seconds`` of log starting
    ``offset_ns`` after the generator's epoch (across a UTC midnight when it falls there).
    ``node``: the node's logs (recorded parameters, events); else bare sensor recordings and
    ``catenary_monitor.yaml`` beside them."""
    folder.mkdir(parents=True, exist_ok=True)
    config = dock_config(n_lines)
    tensions, depth = generate(config, seconds=seconds, seed=seed, storm_line=storm_line)
    tensions = {k: (t + offset_ns, v) for k, (t, v) in tensions.items()}
    depth = (depth[0] + offset_ns, depth[1])
    first = min(int(t[0]) for t, _ in tensions.values())
    last = max(int(t[-1]) for t, _ in tensions.values())
    rows = [(int(t), 0, config.depth_topic, v) for t, v in zip(*depth)]
    for line in config.lines:
        rows += [(int(t), 1, line.tension_topic, v) for t, v in zip(*tensions[line.name])]
    if node:
        rows += [(e.stamp_ns, 2, EVENTS_TOPIC, e) for e in _events(tensions, first, last)]
    else:
        params_yaml(config, folder / 'catenary_monitor.yaml')
    rows.sort(key=lambda r: (r[0], r[1]))
    cuts = np.linspace(rows[0][0], rows[-1][0] + 1, files + 1).astype(np.int64)
    for k in range(files):
        log = McapLogger(folder, prefix=f'part{k}', chunk_size=4096, fsync=False,
                         bag_metadata=False)  # fmt: skip
        for line in config.lines:
            log.register(line.tension_topic, 'std_msgs/msg/Float64', 'sensor_data')
        log.register(config.depth_topic, 'std_msgs/msg/Float64', 'sensor_data')
        if node:
            log.register(EVENTS_TOPIC, 'std_msgs/msg/String')
            log.add_metadata(NODE_NAME, {
                'config_hash': config_hash(config),
                'parameters': json.dumps(config_to_params(config), sort_keys=True),
            })  # fmt: skip
        for stamp, kind, topic, value in rows:
            if not cuts[k] <= stamp < cuts[k + 1]:
                continue
            if kind == 2:
                data = string_message(json.dumps(event_record(value)))
            else:
                data = b'\x00\x01\x00\x00' + struct.pack('<d', value)
            log.write(topic, data, stamp)
        log.close()
        log.files[0].rename(folder / f'dock_{k:03d}.mcap')
    return folder


def damage_middle(path: Path) -> None:
    """Overwrite bytes in the middle of a file (a corrupt chunk: the reader skips it)."""
    data = bytearray(path.read_bytes())
    mid = len(data) // 2
    data[mid : mid + 64] = b'\xa5' * 64
    path.write_bytes(bytes(data))
