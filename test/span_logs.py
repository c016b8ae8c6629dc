"""Logs whose stamps span far more time than their bytes: the files of the span tests.

Each is a small MCAP file of a one-line dock (``replay_data.dock_config(1)``), Float64 tension
and depth topics, no events channel (so replay steps it on a grid of ticks), the parameters
recorded as the node records them (so ``console --log`` and ``alarms`` need no params file):

* ``stamp_1970``: one sample stamped 1970 and 200 from 2026 (about 7 KB);
* ``stamp_2100``: 200 samples from 2026 and one stamped 2100;
* ``daily``: one sample a day (a tension and a depth) for 3,000 days (about 70 KB);
* ``gap_30d`` / ``gap_365d``: two short recordings (5 min each) 30 or 365 days apart (about
  20 KB each recording);
* ``hours_90d``: two hours of recording (one hour, then one hour 90 days later).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import numpy as np
from replay_data import dock_config

from catenary_monitor.core.config.parameters import MonitorConfig, config_hash, config_to_params
from catenary_monitor.core.monitor.events import NODE_NAME
from catenary_monitor.io.cdr import float64_payloads
from catenary_monitor.io.mcap_column_writer import ColumnWriter
from catenary_monitor.io.ros_schemas import message_definition

SECOND = 10**9
DAY = 86_400 * SECOND
T2026 = 1_775_000_000 * SECOND  # 2026-03-31
T1970 = 7 * SECOND  # 1970-01-01 00:00:07
T2100 = 4_102_444_800 * SECOND  # 2100-01-01
Columns = tuple[np.ndarray, np.ndarray, np.ndarray]  # stamps ns, values, topic index (0 tension)


def config() -> MonitorConfig:
    """The one-line dock of the span files."""
    return dock_config(1)


def recording(t0: int, seconds: float, rate: float = 2.0, seed: int = 3) -> Columns:
    """``seconds`` of a quiet dock from ``t0``: tensions at ``rate`` Hz (372 kN and waves),
    the depth at 1 Hz (20.85 m), each stamp jittered."""
    rng = np.random.default_rng(seed)
    n, nd = int(seconds * rate), int(seconds)
    tt = t0 + (np.arange(n) * (SECOND / rate)).astype(np.int64) + rng.integers(0, 10**7, n)
    td = t0 + 350_000_000 + np.arange(nd, dtype=np.int64) * SECOND
    tv = 372e3 + 30e3 * np.sin(2 * np.pi * (tt - t0) * 1e-9 / 10.0)
    dv = 20.85 + rng.normal(0, 0.01, nd)
    return _joined([(tt, tv, 0), (td, dv, 1)])


def _joined(parts: list[tuple[np.ndarray, np.ndarray, int]]) -> Columns:
    t = np.concatenate([p[0] for p in parts]).astype(np.int64)
    v = np.concatenate([p[1] for p in parts]).astype(np.float64)
    k = np.concatenate([np.full(len(p[0]), p[2]) for p in parts])
    order = np.argsort(t, kind='stable')
    return t[order], v[order], k[order]


def _cat(*cols: Columns) -> Columns:
    return _joined([(c[0][c[2] == j], c[1][c[2] == j], j) for c in cols for j in (0, 1)])


def _single(t: int, topic: int = 0) -> Columns:
    value = 372e3 if topic == 0 else 20.85
    return np.array([t], np.int64), np.array([value]), np.array([topic])


def stamp_1970() -> Columns:
    """One tension sample stamped 1970, then 200 samples of 2026 (80 s)."""
    return _cat(_single(T1970), recording(T2026, 200 / 3.0))


def stamp_2100() -> Columns:
    """200 samples of 2026 (80 s), then one tension sample stamped 2100."""
    return _cat(recording(T2026, 200 / 3.0), _single(T2100))


def daily(days: int = 3000) -> Columns:
    """One tension and one depth sample a day (the depth 0.5 s first) for ``days`` days."""
    t = T2026 - days * DAY + np.arange(days, dtype=np.int64) * DAY
    tension = (t + SECOND, np.full(days, 372e3), 0)
    return _joined([tension, (t + SECOND // 2, np.full(days, 20.85), 1)])


def gap(days: int, seconds: float = 300.0) -> Columns:
    """Two recordings of ``seconds``, the second ``days`` days after the first."""
    return _cat(recording(T2026, seconds), recording(T2026 + days * DAY, seconds, seed=4))


def hours(days: int = 90) -> Columns:
    """An hour of recording, then another ``days`` days later."""
    return _cat(recording(T2026, 3600.0, 1.0), recording(T2026 + days * DAY, 3600.0, 1.0, 4))


FILES: dict[str, Callable[[], Columns]] = {
    'stamp_1970': stamp_1970,
    'stamp_2100': stamp_2100,
    'daily': daily,
    'gap_30d': lambda: gap(30),
    'gap_365d': lambda: gap(365),
    'hours_90d': hours,
}


def write(path: Path, columns: Columns, cfg: MonitorConfig | None = None) -> Path:
    """``columns`` as a ROS 2 MCAP file with the parameters recorded (the node's metadata)."""
    cfg = cfg or config()
    t, v, k = columns
    with open(path, 'wb') as f:
        w = ColumnWriter(f, chunk_bytes=16 * 1024)
        sid = w.register_schema(
            'std_msgs/msg/Float64', 'ros2msg', message_definition('std_msgs/msg/Float64').encode()
        )
        topics = (cfg.lines[0].tension_topic, cfg.depth_topic)
        ids = [w.register_channel(topic, 'cdr', sid) for topic in topics]
        w.add_metadata(
            NODE_NAME,
            {
                'config_hash': config_hash(cfg),
                'parameters': json.dumps(config_to_params(cfg), sort_keys=True),
            },
        )
        w.write_columns(np.array(ids)[k], t, float64_payloads(v))
        w.finish()
    return path


def write_all(folder: Path) -> dict[str, Path]:
    """Every span file in ``folder`` (``NAME.mcap``)."""
    folder.mkdir(parents=True, exist_ok=True)
    return {name: write(folder / f'{name}.mcap', make()) for name, make in FILES.items()}
