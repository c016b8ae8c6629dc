"""Seeded generated recordings for the replay tests, and a pure simulation of the live node.

``simulate_node`` feeds the same messages through the scalar alarm machine exactly as the
node's callbacks do (``catenary_monitor/node.py``: ``_on_tension``, ``_on_depth``,
``_on_period``), with no ROS: the oracle for replay's vectorized schedule.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from catenary_monitor.core.alarms import AlarmInputs, LineAlarm
from catenary_monitor.core.config import AlarmConfig, LineConfig, MonitorConfig
from catenary_monitor.core.solve import solve

T0_NS = 1_763_900_000_000_000_000  # 2025-11-23, an epoch-like receive time


def dock_config(n_lines: int = 3, **alarm: Any) -> MonitorConfig:
    """The paper dock's chain, ``n_lines`` lines, line_02 with an uplift allowance."""
    lines = []
    for k in range(n_lines):
        name = f'line_{k + 1:02d}'
        lines.append(LineConfig(name=name, weight=1300.0,
                                anchor_distance=121.06 if k == 1 else 120.0, mbl=4827000.0,
                                allowed_uplift=50e3 if k == 1 else 0.0,
                                hook_height=0.5 if k == 2 else 0.0))
    settings = dict(clear_hold=3.0, warn_clear_hold=2.0, tension_timeout=1.5, depth_timeout=4.0)
    settings.update(alarm)
    return MonitorConfig(lines=tuple(lines), alarm=AlarmConfig(**settings))


def params_yaml(config: MonitorConfig, path: Path) -> Path:
    """Write ``config`` as a ROS params file (the ``catenary_monitor`` section)."""
    from catenary_monitor.core.config import config_to_params
    flat = config_to_params(config)
    out = ['catenary_monitor:', '  ros__parameters:']
    for key, value in flat.items():
        if isinstance(value, (list, tuple)):
            value = '[' + ', '.join(value) + ']'
        elif isinstance(value, str):
            value = f'"{value}"'
        else:
            value = repr(value)
        out.append(f'    {key}: {value}')
    path.write_text('\n'.join(out) + '\n')
    return path


def generate(config: MonitorConfig, seconds: float = 120.0, rate: float = 10.0,
             depth_rate: float = 1.0, seed: int = 7, storm_line: int = 1,
             dropouts: bool = True) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]],
                                             tuple[np.ndarray, np.ndarray]]:
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
        storm = 1.25e6 * np.exp(-((s - seconds / 2) / (seconds / 8)) ** 2) if k == storm_line \
            else 0.0
        v = 372e3 + storm + 60e3 * np.sin(2 * np.pi * s / 10.0) + rng.normal(0, 5e3, n)
        if dropouts and k == 0:
            keep = (s < 0.3 * seconds) | (s > 0.3 * seconds + 4.0)
            t, v = t[keep], v[keep]
            v[len(v) // 5] = math.nan
            v[len(v) // 5 + 3] = -10.0
        tensions[line.name] = (t.astype(np.int64), v)
    nd = int(seconds * depth_rate)
    td = T0_NS + int(0.35e9) + np.cumsum(rng.integers(int(0.8e9 / depth_rate),
                                                      int(1.2e9 / depth_rate), nd))
    sd = (td - T0_NS) * 1e-9
    dv = 20.85 + 1.2 * np.sin(2 * np.pi * sd / 60.0) + rng.normal(0, 0.01, nd)
    if dropouts:
        keep = (sd < 0.7 * seconds) | (sd > 0.7 * seconds + 6.0)
        td, dv = td[keep], dv[keep]
    return tensions, (td.astype(np.int64), dv)


def simulate_node(config: MonitorConfig, tensions: dict[str, tuple[np.ndarray, np.ndarray]],
                  depth: tuple[np.ndarray, np.ndarray], ticks: np.ndarray) -> dict[str, Any]:
    """The node's callbacks, in receive-time order (depth, tension, tick at equal times).

    Returns per line: ``updates`` [(t_ns, kind, level, values dict)], ``transitions``
    [Transition], ``ticks`` [(t_ns, level)].
    """
    events = [(int(t), 0, None, float(v)) for t, v in zip(*depth)]
    for name, (ts, vs) in tensions.items():
        events += [(int(t), 1, name, float(v)) for t, v in zip(ts, vs)]
    events += [(int(t), 2, None, 0.0) for t in ticks]
    events.sort(key=lambda e: (e[0], e[1]))
    lines = {lc.name: dict(cfg=lc, alarm=LineAlarm.for_line(lc, config.alarm), state=None,
                           tension=math.nan, tension_stamp=math.nan, inputs=AlarmInputs(),
                           updates=[], transitions=[], ticks=[]) for lc in config.lines}
    for ln in lines.values():
        ln['state'] = ln['alarm'].initial()
    d_value, d_stamp = math.nan, math.nan

    def update(ln: dict[str, Any], result: Any, status: int, text: str, now_ns: int,
               kind: int) -> None:
        # node._update
        now = now_ns * 1e-9
        values = dict(result)
        values['top_tension'] = ln['tension']  # the measured tension, solved or not
        values['depth'] = d_value + ln['cfg'].hook_height
        ln['inputs'] = AlarmInputs(
            uplift_force=values['uplift_force'], anchor_margin=values['anchor_margin'],
            tide_margin=values['tide_margin'], load_margin=values['load_margin'],
            safety_factor=values['safety_factor'], status=max(status, 0), status_message=text,
            tension_stamp=ln['tension_stamp'], depth_stamp=d_stamp)
        ln['state'], ev = ln['alarm'].update(ln['state'], ln['inputs'], now)
        ln['transitions'] += ev
        ln['updates'].append((now_ns, kind, int(ln['state'].level), values, status))

    keys = ('top_tension', 'horizontal_tension', 'min_anchor_distance', 'anchor_margin',
            'uplift_force', 'tide_margin', 'load_margin', 'safety_factor', 'anchor_angle_deg',
            'suspended_length')
    for now_ns, kind, name, value in events:
        if kind == 1:  # node._on_tension: scalar solve at the newest depth
            ln = lines[name]
            ln['tension'] = value
            ln['tension_stamp'] = now_ns * 1e-9
            if math.isnan(d_stamp):
                update(ln, dict.fromkeys(keys, math.nan), -1, '', now_ns, kind)
            else:
                lc = ln['cfg']
                r = solve(lc.weight, d_value + lc.hook_height, tension=ln['tension'],
                          anchor_distance=lc.anchor_distance, mbl=lc.mbl)
                update(ln, {k: getattr(r, k) for k in keys}, r.status, r.message, now_ns, kind)
        elif kind == 0:  # node._on_depth: one array solve of the lines that have a tension
            d_value, d_stamp = value, now_ns * 1e-9
            have = [ln for ln in lines.values() if not math.isnan(ln['tension_stamp'])]
            if have:
                cfgs = [ln['cfg'] for ln in have]
                r = solve(np.array([c.weight for c in cfgs]),
                          d_value + np.array([c.hook_height for c in cfgs]),
                          tension=np.array([ln['tension'] for ln in have]),
                          anchor_distance=np.array([c.anchor_distance for c in cfgs]),
                          mbl=np.array([c.mbl for c in cfgs]))
                msgs = r.message
                for i, ln in enumerate(have):
                    update(ln, {k: float(np.asarray(getattr(r, k))[i]) for k in keys},
                           int(r.status[i]), str(msgs[i]), now_ns, kind)
        else:  # node._on_period
            for ln in lines.values():
                ln['state'], ev = ln['alarm'].update(ln['state'], ln['inputs'], now_ns * 1e-9)
                ln['transitions'] += ev
                ln['ticks'].append((now_ns, int(ln['state'].level)))
    return lines


def write_log(path: Path, config: MonitorConfig,
              tensions: dict[str, tuple[np.ndarray, np.ndarray]],
              depth: tuple[np.ndarray, np.ndarray], writer: str = 'column',
              chunk_size: int = 16 * 1024) -> Path:
    """Write the inputs as a ROS 2 MCAP log.

    ``writer``: ``'column'`` (catenary_monitor.io.mcap_fast), ``'logger'`` (the node's McapLogger,
    small chunks, no fsync) or ``'ros2'`` (mcap_ros2.writer, as rosbag2-compatible tools do).
    """
    topics = [(line.tension_topic, *tensions[line.name]) for line in config.lines
              if line.name in tensions] + [(config.depth_topic, *depth)]
    t = np.concatenate([tt for _, tt, _ in topics])
    v = np.concatenate([vv for _, _, vv in topics])
    k = np.concatenate([np.full(len(tt), i) for i, (_, tt, _) in enumerate(topics)])
    order = np.argsort(t, kind='stable')
    t, v, k = t[order], v[order], k[order]
    if writer == 'column':
        from catenary_monitor.io.cdr import float64_payloads
        from catenary_monitor.io.mcap_fast import ColumnWriter
        from catenary_monitor.io.ros_schemas import message_definition
        with open(path, 'wb') as f:
            w = ColumnWriter(f, chunk_bytes=chunk_size)
            sid = w.register_schema('std_msgs/msg/Float64', 'ros2msg',
                                    message_definition('std_msgs/msg/Float64').encode())
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
            schema = w.register_msgdef('std_msgs/msg/Float64',
                                       message_definition('std_msgs/msg/Float64'))
            for tt, vv, kk in zip(t.tolist(), v.tolist(), k.tolist()):
                w.write_message(topics[kk][0], schema, {'data': vv}, log_time=tt,
                                publish_time=tt)
            w.finish()
    else:
        raise ValueError(writer)
    return path
