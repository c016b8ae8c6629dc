"""Seeded generated recordings for the replay tests (the oracle is the monitor core itself)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from catenary_monitor.core.config.parameters import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.monitor.events import Depth, Tension, Tick
from catenary_monitor.core.monitor.monitor_core import MonitorCore

T0_NS = 1_763_900_000_000_000_000  # 2025-11-23, an epoch-like receive time


def dock_config(n_lines: int = 3, **alarm: Any) -> MonitorConfig:
    """The paper dock's chain, ``n_lines`` lines, line_02 with an uplift allowance."""
    lines = []
    for k in range(n_lines):
        name = f'line_{k + 1:02d}'
        lines.append(
            LineConfig(
                name=name,
                weight=1300.0,
                anchor_distance=121.06 if k == 1 else 120.0,
                mbl=4827000.0,
                allowed_uplift=50e3 if k == 1 else 0.0,
                hook_height=0.5 if k == 2 else 0.0,
            )
        )
    settings = dict(
        clear_hold=3.0, warn_clear_hold=2.0, margin_clear_hold=2.0, tension_timeout=1.5,
        depth_timeout=4.0,
    )  # fmt: skip
    settings.update(alarm)
    return MonitorConfig(lines=tuple(lines), alarm=AlarmConfig(**settings))


def params_yaml(config: MonitorConfig, path: Path) -> Path:
    """Write ``config`` as a ROS params file (the ``catenary_monitor`` section)."""
    from catenary_monitor.core.config.parameters import config_to_params, params_file_text

    path.write_text(params_file_text(config_to_params(config)))
    return path


def generate(
    config: MonitorConfig,
    seconds: float = 120.0,
    rate: float = 10.0,
    depth_rate: float = 1.0,
    seed: int = 7,
    storm_line: int = 1,
    dropouts: bool = True,
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], tuple[np.ndarray, np.ndarray]]:
    """Tension per line and depth as (receive time ns, value) columns.

    Tension: pretension ~370 kN, wave-frequency swing (10 s), a storm on ``storm_line`` building
    to uplift around the middle of the record; jittered receive times. Depth: a compressed tide
    around 20.85 m at ``depth_rate``. With ``dropouts``: a 4 s tension gap on line_01 (stale), a
    6 s depth gap, a NaN and a negative tension sample, and the first depth sample after the
    first tensions.
    """
    rng = np.random.default_rng(seed)
    tensions = {}
    n = int(seconds * rate)
    for k, line in enumerate(config.lines):
        t = T0_NS + np.cumsum(rng.integers(int(0.6e9 / rate), int(1.4e9 / rate), n))
        s = (t - T0_NS) * 1e-9
        storm = (
            1.25e6 * np.exp(-(((s - seconds / 2) / (seconds / 8)) ** 2))
            if k == storm_line
            else 0.0
        )
        v = 372e3 + storm + 60e3 * np.sin(2 * np.pi * s / 10.0) + rng.normal(0, 5e3, n)
        if dropouts and k == 0:
            keep = (s < 0.3 * seconds) | (s > 0.3 * seconds + 4.0)
            t, v = t[keep], v[keep]
            v[len(v) // 5] = math.nan
            v[len(v) // 5 + 3] = -10.0
        tensions[line.name] = (t.astype(np.int64), v)
    nd = int(seconds * depth_rate)
    td = (
        T0_NS
        + int(0.35e9)
        + np.cumsum(rng.integers(int(0.8e9 / depth_rate), int(1.2e9 / depth_rate), nd))
    )
    sd = (td - T0_NS) * 1e-9
    dv = 20.85 + 1.2 * np.sin(2 * np.pi * sd / 60.0) + rng.normal(0, 0.01, nd)
    if dropouts:
        keep = (sd < 0.7 * seconds) | (sd > 0.7 * seconds + 6.0)
        td, dv = td[keep], dv[keep]
    return tensions, (td.astype(np.int64), dv)


def events_of(
    config: MonitorConfig,
    tensions: dict[str, tuple[np.ndarray, np.ndarray]],
    depth: tuple[np.ndarray, np.ndarray],
    ticks: np.ndarray,
) -> list[Any]:
    """All events in time order (depth, tensions in config order, tick at equal times)."""
    events = [(int(t), 0, 0, Depth(int(t), float(v))) for t, v in zip(*depth)]
    for k, line in enumerate(config.lines):
        ts, vs = tensions.get(line.name, (np.zeros(0, np.int64), np.zeros(0)))
        events += [(int(t), 1, k, Tension(int(t), k, float(v))) for t, v in zip(ts, vs)]
    events += [(int(t), 2, 0, Tick(int(t))) for t in ticks]
    events.sort(key=lambda e: e[:3])
    return [e[3] for e in events]


def core_steps(
    config: MonitorConfig,
    tensions: dict[str, tuple[np.ndarray, np.ndarray]],
    depth: tuple[np.ndarray, np.ndarray],
    ticks: np.ndarray,
    start_ns: int,
) -> tuple[MonitorCore, list[Any]]:
    """The oracle: every event stepped through a MonitorCore, one at a time."""
    core = MonitorCore(config, start_ns)
    return core, [core.step(ev) for ev in events_of(config, tensions, depth, ticks)]


def write_log(
    path: Path,
    config: MonitorConfig,
    tensions: dict[str, tuple[np.ndarray, np.ndarray]],
    depth: tuple[np.ndarray, np.ndarray],
    writer: str = 'column',
    chunk_size: int = 16 * 1024,
) -> Path:
    """Write the inputs as a ROS 2 MCAP log.

    ``writer``: ``'column'`` (catenary_monitor.io.mcap_column_writer), ``'logger'`` (the node's
    McapLogger, small chunks, no fsync) or ``'ros2'`` (mcap_ros2.writer, as rosbag2-compatible
    tools do).
    """
    topics = [
        (line.tension_topic, *tensions[line.name])
        for line in config.lines
        if line.name in tensions
    ] + [(config.depth_topic, *depth)]
    t = np.concatenate([tt for _, tt, _ in topics])
    v = np.concatenate([vv for _, _, vv in topics])
    k = np.concatenate([np.full(len(tt), i) for i, (_, tt, _) in enumerate(topics)])
    order = np.argsort(t, kind='stable')
    t, v, k = t[order], v[order], k[order]
    if writer == 'column':
        from catenary_monitor.io.cdr import float64_payloads
        from catenary_monitor.io.mcap_column_writer import ColumnWriter
        from catenary_monitor.io.ros_schemas import message_definition

        with open(path, 'wb') as f:
            w = ColumnWriter(f, chunk_bytes=chunk_size)
            sid = w.register_schema(
                'std_msgs/msg/Float64',
                'ros2msg',
                message_definition('std_msgs/msg/Float64').encode(),
            )
            ids = [w.register_channel(name, 'cdr', sid) for name, _, _ in topics]
            w.write_columns(np.array(ids)[k], t, float64_payloads(v))
            w.finish()
    elif writer == 'logger':
        import struct

        from catenary_monitor.io.mcap_log import McapLogger

        log = McapLogger(path.parent, prefix=path.stem, chunk_size=chunk_size, fsync=False)
        for name, _, _ in topics:
            log.register(name, 'std_msgs/msg/Float64', 'sensor_data')
        for tt, vv, kk in zip(t.tolist(), v.tolist(), k.tolist()):
            log.write(topics[kk][0], b'\x00\x01\x00\x00' + struct.pack('<d', vv), tt)
        log.close()
        written = log.files[0]
        written.rename(path)
    elif writer == 'ros2':
        from mcap_ros2.writer import Writer

        from catenary_monitor.io.ros_schemas import message_definition

        with open(path, 'wb') as f:
            w = Writer(f, chunk_size=chunk_size)
            schema = w.register_msgdef(
                'std_msgs/msg/Float64', message_definition('std_msgs/msg/Float64')
            )
            for tt, vv, kk in zip(t.tolist(), v.tolist(), k.tolist()):
                w.write_message(topics[kk][0], schema, {'data': vv}, log_time=tt, publish_time=tt)
            w.finish()
    else:
        raise ValueError(writer)
    return path
