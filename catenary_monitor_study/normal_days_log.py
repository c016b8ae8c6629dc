"""A scene's sensors as their drivers publish them, written as the node's MCAP log.

What :mod:`catenary_monitor_study.normal_days` computes as truth, each sensor turns into
messages the way real drivers publish them:

* **load cells** through one gateway at ``Cells.rate`` (10 Hz): each cell read in turn a few ms
  apart, its reading the hook tension plus white noise, quantized to the cell's resolution, in
  the cell's own unit; the first third of the lines as ``geometry_msgs/WrenchStamped`` (the
  ros2_control force-torque broadcaster: force ``x`` in N, a little cross-talk on ``y`` and
  ``z``, the header stamped when read), the next third ``std_msgs/Float64`` in kN, the rest
  ``std_msgs/Float64`` in N (both taken at arrival). Deliveries a few ms after the reading,
  some late in a bunch; a sample now and then lost on the network (the node counts it from the
  sequence gap: an ``intake`` record says so);
* **the tide gauge** at 1 Hz: a radar (``sensor_msgs/Range``, the distance down to the water),
  a vented pressure gauge (``sensor_msgs/FluidPressure``, Pa above the air's) or a plain depth
  (``std_msgs/Float64``), each the mean water level over its averaging time (the waves filtered
  exactly: a moving mean of a wave component is its value half the window earlier times
  ``sinc``), plus noise, quantized to its resolution;
* **the node's own records** on ``/catenary_monitor/events`` (``std_msgs/String``, JSON): its
  start, the logger and fatigue store at start, a tick at ``diagnostic_rate`` and an intake
  record every 60 s or after a loss, and the ``catenary_monitor`` metadata record holding the
  parameters (so ``replay LOG`` runs without ``--params-file``).

Faults (:class:`~catenary_monitor_study.normal_days.Fault`) act on what is published: silence
(the gateway, one cell, the gauge), the wrong unit, the pressure gauge's step; a parted chain
is in the truth itself. Every log time is distinct and increasing, as the node stamps them.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np

from catenary_monitor.core.config.parameters import (
    config_hash,
    config_to_params,
    params_file_text,
)
from catenary_monitor.core.monitor.events import EVENTS_TOPIC, NODE_NAME
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.rules.readings import G
from catenary_monitor.io.cdr import ENCAPSULATION, float64_payloads, string_message
from catenary_monitor.io.mcap_column_writer import ColumnWriter
from catenary_monitor.io.ros_schemas import (
    QOS_DEFAULT,
    QOS_SENSOR_DATA,
    message_definition,
)
from catenary_monitor_study.normal_days import (
    Coarse,
    Scene,
    wave_components,
    coarse,
    hook_tensions,
    still_depth,
)

__all__ = [
    'LogFacts',
    'write_scene',
    'wrench_payloads',
    'fluid_pressure_payloads',
    'range_payloads',
    'CELL_UNITS',
]

FLOAT64 = 'std_msgs/msg/Float64'
WRENCH = 'geometry_msgs/msg/WrenchStamped'
FLUID = 'sensor_msgs/msg/FluidPressure'
RANGE = 'sensor_msgs/msg/Range'
STRING = 'std_msgs/msg/String'
#: N per unit a cell reports in: its configured unit, or the fault's.
CELL_UNITS = {'n': 1.0, 'kn': 1000.0, 'dan': 10.0, 'tf': 9806.65}
#: Seconds of log generated at a time (memory: ~40 MB per 12 lines at 10 Hz).
STRETCH_S = 1800.0
#: The node's intake heartbeat without a sample rate [s] (ros/node.py INTAKE_HEARTBEAT).
INTAKE_HEARTBEAT = 60.0
_HEAD = 31  # MCAP Message record head: opcode, length, channel, sequence, log and publish time


# --- CDR of the stamped messages (vectorized) -----------------------------------------------


def _header(n: int, size: int, stamps_ns: np.ndarray, frame_id: str) -> tuple[np.ndarray, int]:
    """``(n, size)`` payloads with the encapsulation and a header (stamp, ``frame_id``) filled;
    the offset (from the payload's start) after the header."""
    out = np.zeros((n, size), np.uint8)
    out[:, :4] = np.frombuffer(ENCAPSULATION, np.uint8)
    stamps = np.asarray(stamps_ns, np.int64)
    out[:, 4:8] = (stamps // 1_000_000_000).astype('<i4').view(np.uint8).reshape(n, 4)
    out[:, 8:12] = (stamps % 1_000_000_000).astype('<u4').view(np.uint8).reshape(n, 4)
    text = frame_id.encode() + b'\0'
    out[:, 12:16] = np.frombuffer(np.uint32(len(text)).astype('<u4').tobytes(), np.uint8)
    out[:, 16 : 16 + len(text)] = np.frombuffer(text, np.uint8)
    return out, 16 + len(text)


def _aligned(offset: int, to: int) -> int:
    """``offset`` (from the payload's start) aligned to ``to`` counted after the
    encapsulation."""
    body = offset - 4
    return 4 + body + (-body % to)


def _doubles(out: np.ndarray, at: int, columns: list[np.ndarray], dtype: str = '<f8') -> None:
    width = np.dtype(dtype).itemsize
    for j, col in enumerate(columns):
        data = np.asarray(col).astype(dtype).view(np.uint8).reshape(len(out), width)
        out[:, at + j * width : at + (j + 1) * width] = data


def wrench_payloads(
    stamps_ns: np.ndarray, frame_id: str, force: tuple[np.ndarray, np.ndarray, np.ndarray]
) -> np.ndarray:
    """``(n, size)`` CDR of ``geometry_msgs/msg/WrenchStamped`` (force x, y, z; no torque)."""
    n = len(stamps_ns)
    probe = _aligned(16 + len(frame_id) + 1, 8)
    out, _ = _header(n, probe + 48, stamps_ns, frame_id)
    zero = np.zeros(n)
    _doubles(out, probe, [force[0], force[1], force[2], zero, zero, zero])
    return out


def fluid_pressure_payloads(stamps_ns: np.ndarray, frame_id: str, pa: np.ndarray) -> np.ndarray:
    """``(n, size)`` CDR of ``sensor_msgs/msg/FluidPressure`` (variance 0: unknown)."""
    n = len(stamps_ns)
    at = _aligned(16 + len(frame_id) + 1, 8)
    out, _ = _header(n, at + 16, stamps_ns, frame_id)
    _doubles(out, at, [pa, np.zeros(n)])
    return out


def range_payloads(
    stamps_ns: np.ndarray, frame_id: str, rng: np.ndarray, lo: float, hi: float
) -> np.ndarray:
    """``(n, size)`` CDR of ``sensor_msgs/msg/Range`` (radiation type 0, field of view 0.1
    rad, ``min_range`` ``lo``, ``max_range`` ``hi``, ``range``, variance 0)."""
    n = len(stamps_ns)
    kind = 16 + len(frame_id) + 1  # uint8 radiation_type
    at = _aligned(kind + 1, 4)
    out, _ = _header(n, at + 20, stamps_ns, frame_id)
    full = np.full(n, 1.0)
    _doubles(out, at, [0.1 * full, lo * full, hi * full, rng, 0.0 * full], '<f4')
    return out


# --- the sensors ----------------------------------------------------------------------------


@dataclass
class Stream:
    """One channel's messages of a stretch: log times [ns], header stamps [ns] (the log time
    for unstamped types) and payloads (n, size)."""

    topic: str
    type_name: str
    log_ns: np.ndarray
    stamp_ns: np.ndarray
    payload: np.ndarray


def _cell_kind(scene: Scene, name: str) -> tuple[str, str]:
    """(message kind ``wrench``/``float64``, the unit the cell reports in) of line ``name``."""
    flat = scene.flat
    unit = 'kn' if flat.get(f'{name}.tension_scale', 1.0) == 1000.0 else 'n'
    for f in scene.faults:
        if f.line == name and f.kind == 'units_dan':
            unit = 'dan'
        elif f.line == name and f.kind == 'units_tf':
            unit = 'tf'
    kind = 'wrench' if flat.get(f'{name}.tension_type') == WRENCH else 'float64'
    return kind, unit


def _silent(
    scene: Scene, kinds: tuple[str, ...], line: Optional[str], t: np.ndarray
) -> np.ndarray:
    """Which of the times ``t`` [s] fall in a silence fault of ``kinds`` (for ``line``)."""
    out = np.zeros(len(t), bool)
    for f in scene.faults:
        if f.kind in kinds and (f.line is None or f.line == line):
            out |= (t >= f.at) & (t < f.at + f.duration)
    return out


def cell_streams(
    scene: Scene, c: Coarse, lo: float, hi: float, rng: np.random.Generator
) -> tuple[list[Stream], np.ndarray, np.ndarray]:
    """The load cells' messages in ``[lo, hi)`` s; the samples each line lost on the network
    (its log times [ns], its index) for the intake records."""
    cells = scene.cells
    config = scene.config
    period = 1.0 / cells.rate
    k0, k1 = int(math.ceil(lo / period)), int(math.ceil(hi / period))
    poll = np.arange(k0, k1) * period
    truth = hook_tensions(scene, c, poll)
    n = len(poll)
    stall = rng.random(n) < cells.late  # the gateway stalls: this and what follows wait
    streams, lost_t, lost_k = [], [], []
    for k, line in enumerate(config.lines):
        kind, unit = _cell_kind(scene, line.name)
        ts = poll + k * cells.stagger + rng.normal(0.0, cells.jitter, n)
        arrive = ts + cells.delay + np.abs(rng.normal(0.0, cells.jitter, n))
        arrive = _bunched(poll, arrive, stall, cells.late_s)
        value = truth[:, k] + rng.normal(0.0, cells.noise, n)
        value = np.round(value / cells.resolution) * cells.resolution / CELL_UNITS[unit]
        keep = ~_silent(scene, ('gateway_drop', 'silent_cell'), line.name, ts)
        lost = keep & (rng.random(n) < cells.loss)
        lost_t.append(arrive[lost])
        lost_k.append(np.full(int(lost.sum()), k))
        keep &= ~lost
        log_ns = _ns(scene, arrive[keep])
        stamp_ns = _ns(scene, ts[keep])
        if kind == 'wrench':
            v = value[keep]
            cross = 0.002 * np.abs(v)
            payload = wrench_payloads(
                stamp_ns,
                f'{line.name}_pin',
                (v, rng.normal(0.0, 1.0, len(v)) * cross, rng.normal(0.0, 1.0, len(v)) * cross),
            )
            streams.append(Stream(line.tension_topic, WRENCH, log_ns, stamp_ns, payload))
        else:
            payload = float64_payloads(value[keep])
            streams.append(Stream(line.tension_topic, FLOAT64, log_ns, log_ns, payload))
    return streams, np.concatenate(lost_t), np.concatenate(lost_k)


def _bunched(poll: np.ndarray, arrive: np.ndarray, stall: np.ndarray, wait: float) -> np.ndarray:
    """Arrivals after the gateway's stalls: a sample read within ``wait`` s after a stall
    arrives at the stall's end (in its order), the others as they are."""
    out = arrive.copy()
    for i in np.flatnonzero(stall).tolist():
        end = poll[i] + wait
        j = int(np.searchsorted(poll, end))
        out[i:j] = np.maximum(out[i:j], end + 1e-4 * np.arange(j - i))
    return np.maximum.accumulate(out)


def _ns(scene: Scene, s: np.ndarray) -> np.ndarray:
    return scene.start_ns + np.round(np.asarray(s) * 1e9).astype(np.int64)


def gauge_levels(scene: Scene, c: Coarse, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """What the gauge reads [m of depth at the hooks] at ``t`` [s]: the still-water depth, the
    waves as its averaging and the pressure's attenuation leave them, noise, quantized."""
    g = scene.gauge
    depth = still_depth(scene, t)
    if g.kind != 'float64':
        hs = np.interp(t, c.t, c.hs)
        f, phi = wave_components(scene.seed + 1000, scene.weather.tp)
        amp = math.sqrt(2.0 / len(f)) * g.attenuation
        avg = max(g.average, 1e-9)
        gain = np.sinc(f * avg)  # numpy's sinc(x) = sin(pi x) / (pi x)
        arg = 2 * np.pi * (t[:, None] - avg / 2) * f[None, :] + phi[0][None, :]
        wave = (hs / 4.0) * amp * (gain[None, :] * np.cos(arg)).sum(axis=1)
        depth = depth + wave
    depth = depth + rng.normal(0.0, g.noise, len(t)) if g.noise > 0 else depth
    step = scene.fault('pressure_step')
    if step is not None:
        hit = (t >= step.at) & (t < step.at + step.duration)
        depth = np.where(hit, step.value + rng.normal(0.0, g.noise or 0.001, len(t)), depth)
    return np.round(depth / g.resolution) * g.resolution


def gauge_stream(
    scene: Scene, c: Coarse, lo: float, hi: float, rng: np.random.Generator
) -> Stream:
    """The tide gauge's messages in ``[lo, hi)`` s."""
    g = scene.gauge
    config = scene.config
    k0, k1 = int(math.ceil((lo - 0.35) / g.period)), int(math.ceil((hi - 0.35) / g.period))
    ts = 0.35 + np.arange(k0, k1) * g.period + rng.normal(0.0, 0.002, k1 - k0)
    double = rng.random(len(ts)) < g.double_read
    if double.any():
        ts = np.sort(np.concatenate([ts, ts[double] + rng.uniform(0.001, 0.003, double.sum())]))
    ts = ts[(ts >= lo) & (ts < hi) & ~_silent(scene, ('silent_gauge',), None, ts)]
    depth = gauge_levels(scene, c, ts, rng)
    arrive = ts + g.delay + np.abs(rng.normal(0.0, 0.01, len(ts)))
    arrive = np.maximum.accumulate(arrive)
    log_ns, stamp_ns = _ns(scene, arrive), _ns(scene, ts)
    topic = config.depth_topic
    if g.kind == 'radar':
        rng_m = (config.gauge_height - depth).astype(np.float32)
        payload = range_payloads(stamp_ns, 'tide_radar', rng_m, 0.3, 40.0)
        return Stream(topic, RANGE, log_ns, stamp_ns, payload)
    if g.kind == 'pressure':
        pa = config.water_density * G * (depth - config.gauge_height)
        payload = fluid_pressure_payloads(stamp_ns, 'tide_pressure', pa)
        return Stream(topic, FLUID, log_ns, stamp_ns, payload)
    return Stream(topic, FLOAT64, log_ns, log_ns, float64_payloads(depth))


# --- the node's records ---------------------------------------------------------------------


@dataclass
class _Intake:
    """What the node's intake counts since its last record."""

    inputs: int
    received: np.ndarray = field(init=False)
    dropped: np.ndarray = field(init=False)
    last: float = 0.0
    counted: float = 0.0

    def __post_init__(self) -> None:
        self.received = np.zeros(self.inputs, np.int64)
        self.dropped = np.zeros(self.inputs, np.int64)


def _event_texts(
    scene: Scene,
    lo: float,
    hi: float,
    streams: list[Stream],
    lost: tuple[np.ndarray, np.ndarray],
    intake: _Intake,
    log_dir: str,
) -> tuple[np.ndarray, list[str]]:
    """The node's records in ``[lo, hi)`` s: start, logger and fatigue store (at 0), ticks at
    ``diagnostic_rate``, intake counts every :data:`INTAKE_HEARTBEAT` s and 1 s after a loss."""
    times: list[float] = []
    texts: list[str] = []
    if lo == 0.0:
        times += [0.0, 0.0005, 0.001]
        texts += [
            json.dumps({'kind': 'start'}),
            json.dumps({'kind': 'logger', 'error': None, 'path': f'{log_dir}/normal_days.mcap'}),
            json.dumps({'kind': 'fatigue', 'state': 'new', 'message': 'no fatigue store yet: '
                        'counting from fatigue_damage_initial', 'lines': None}),  # fmt: skip
        ]
    period = 1.0 / scene.config.alarm.diagnostic_rate
    k0 = int(math.ceil((lo - 0.5) / period))
    ticks = 0.5 + np.arange(k0, int(math.ceil((hi - 0.5) / period))) * period
    ticks = ticks[ticks >= lo]
    times += ticks.tolist()
    texts += [json.dumps({'kind': 'tick'})] * len(ticks)
    n_lines = len(scene.config.lines)
    arrivals = [(s.log_ns - scene.start_ns) * 1e-9 for s in streams]
    lost_t = np.asarray(lost[0], np.float64)
    due = set(np.floor(lost_t + 1.0).astype(int).tolist())
    beat = INTAKE_HEARTBEAT
    marks = sorted(
        {float(x) + 0.75 for x in due if lo <= x + 0.75 < hi}
        | {float(x) for x in np.arange(math.ceil(lo / beat) * beat, hi, beat) if x > 0}
    )

    def count(until: float) -> None:
        for i, a in enumerate(arrivals):
            intake.received[i] += int(np.count_nonzero((a >= intake.counted) & (a < until)))
        mask = (lost_t >= intake.counted) & (lost_t < until)
        for k in lost[1][mask].tolist():
            intake.dropped[int(k)] += 1
        intake.counted = until

    for at in marks:
        count(at)
        span = at - intake.last
        times.append(at)
        texts.append(json.dumps({
            'kind': 'intake',
            'received': intake.received.tolist(),
            'dropped': intake.dropped.tolist(),
            'coalesced': [0] * (n_lines + 1),
            'busy': round(0.02 * span, 6),
            'period': span,
        }))  # fmt: skip
        intake.received[:] = 0
        intake.dropped[:] = 0
        intake.last = at
    count(math.inf)
    return np.asarray(times), texts


# --- writing --------------------------------------------------------------------------------


@dataclass
class LogFacts:
    """What :func:`write_scene` wrote: the log and params file, message counts per topic, the
    scene's seconds and the fault windows [s from the start]."""

    log: Path
    params: Path
    messages: dict[str, int]
    seconds: float
    start_ns: int
    windows: dict[str, tuple[float, float]]
    bytes: int = 0


class _Writer:
    """The log's channels and the mixed-size Message records, chunk by chunk, in time order."""

    def __init__(self, stream: Any, chunk_bytes: int = 1 << 20) -> None:
        self.w = ColumnWriter(stream, chunk_bytes=chunk_bytes, level=3)
        self.schemas: dict[str, int] = {}
        self.channels: dict[str, int] = {}
        self.sequence: dict[int, int] = {}
        self.counts: dict[str, int] = {}
        self.chunk_bytes = chunk_bytes

    def channel(self, topic: str, type_name: str) -> int:
        if topic not in self.channels:
            if type_name not in self.schemas:
                text = message_definition(type_name).encode()
                self.schemas[type_name] = self.w.register_schema(type_name, 'ros2msg', text)
            qos = QOS_DEFAULT if topic == EVENTS_TOPIC else QOS_SENSOR_DATA
            cid = self.w.register_channel(
                topic, 'cdr', self.schemas[type_name], {'offered_qos_profiles': qos}
            )
            self.channels[topic] = cid
            self.sequence[cid] = 0
            self.counts[topic] = 0
        return self.channels[topic]

    def write(self, streams: list[Stream]) -> None:
        """The streams' messages merged in log-time order (ties: the order given)."""
        streams = [s for s in streams if len(s.log_ns)]
        if not streams:
            return
        ids = [self.channel(s.topic, s.type_name) for s in streams]
        t = np.concatenate([s.log_ns for s in streams])
        group = np.concatenate([np.full(len(s.log_ns), g) for g, s in enumerate(streams)])
        order = np.lexsort((group, t))
        size = np.concatenate([np.full(len(s.log_ns), _HEAD + s.payload.shape[1])
                               for s in streams])[order]  # fmt: skip
        offsets = np.concatenate([[0], np.cumsum(size)[:-1]])
        buf = np.empty(int(size.sum()), np.uint8)
        rank = np.empty(len(t), np.int64)
        rank[order] = np.arange(len(t))
        channel = np.concatenate([np.full(len(s.log_ns), cid, np.uint16)
                                  for s, cid in zip(streams, ids)])[order]  # fmt: skip
        seq = np.empty(len(t), np.int64)
        for cid in np.unique(channel).tolist():
            where = np.flatnonzero(channel == cid)
            seq[where] = self.sequence[cid] + np.arange(len(where))
            self.sequence[cid] += len(where)
        start = 0
        for s, cid in zip(streams, ids):
            n = len(s.log_ns)
            mine = rank[start : start + n]
            start += n
            rec = np.empty(n, _record_dtype(s.payload.shape[1]))
            rec['op'] = 0x05
            rec['length'] = 22 + s.payload.shape[1]
            rec['channel'] = cid
            rec['sequence'] = seq[mine] % (1 << 32)
            rec['log_time'] = s.log_ns
            rec['publish_time'] = s.stamp_ns
            rec['data'] = s.payload
            self.counts[s.topic] += n
            raw = rec.view(np.uint8).reshape(n, -1)
            buf[offsets[mine][:, None] + np.arange(raw.shape[1])[None, :]] = raw
        t_sorted = t[order]
        bounds = np.searchsorted(np.cumsum(size), np.arange(1, 1 + size.sum() // self.chunk_bytes)
                                 * self.chunk_bytes)  # fmt: skip
        edges = np.unique(np.concatenate([[0], bounds + 1, [len(t)]]))
        edges = edges[edges <= len(t)]
        for a, b in zip(edges[:-1].tolist(), edges[1:].tolist()):
            if b <= a:
                continue
            lo, hi = int(offsets[a]), int(offsets[b - 1] + size[b - 1])
            self.w.write_records(buf[lo:hi].tobytes(), channel[a:b], t_sorted[a:b],
                                 offsets[a:b] - offsets[a])  # fmt: skip


def _record_dtype(payload: int) -> np.dtype:
    return np.dtype(
        [('op', 'u1'), ('length', '<u8'), ('channel', '<u2'), ('sequence', '<u4'),
         ('log_time', '<u8'), ('publish_time', '<u8'), ('data', 'u1', (payload,))],
        align=False,
    )  # fmt: skip


def _distinct(streams: list[Stream]) -> None:
    """Make every log time distinct and increasing across the streams (as the node stamps
    each event 1 ns after the previous one when they coincide), in place."""
    t = np.concatenate([s.log_ns for s in streams])
    if not len(t):
        return
    group = np.concatenate([np.full(len(s.log_ns), g) for g, s in enumerate(streams)])
    order = np.lexsort((group, t))
    ts = t[order]
    fixed = np.maximum.accumulate(ts - np.arange(len(ts))) + np.arange(len(ts))
    t[order] = fixed
    start = 0
    for s in streams:
        n = len(s.log_ns)
        same = s.stamp_ns is s.log_ns or s.type_name in (FLOAT64, STRING)
        s.log_ns = t[start : start + n]
        if same:
            s.stamp_ns = s.log_ns
        start += n


def write_params(scene: Scene, path: Path) -> Path:
    """The scene's params file (a ROS 2 params YAML ``catenary-monitor`` reads)."""
    path.write_text(params_file_text(config_to_params(scene.config)))
    return path


def write_scene(
    scene: Scene,
    folder: Path,
    progress: Optional[Callable[[float], None]] = None,
    stretch: float = STRETCH_S,
) -> LogFacts:
    """Write ``folder/<scene>.mcap`` (the sensors' messages and the node's records, as the node
    logs them) and ``folder/<scene>.yaml`` (its params file); ``progress`` gets the share
    done."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f'{scene.name}.mcap'
    params = write_params(scene, folder / f'{scene.name}.yaml')
    c = coarse(scene)
    rng = np.random.default_rng(scene.seed * 65537 + 11)
    n_inputs = len(scene.config.lines) + 1
    intake = _Intake(n_inputs)
    with open(path, 'wb') as f:
        w = _Writer(f)
        config = scene.config
        w.w.add_metadata(NODE_NAME, {
            'version': 'normal_days',
            'config_hash': config_hash(config),
            'parameters': json.dumps(config_to_params(config), sort_keys=True),
            'output_fields': ','.join(OUTPUT_FIELDS),
            'units': 'SI (N, m, s)',
        })  # fmt: skip
        lo = 0.0
        while lo < scene.seconds:
            hi = min(scene.seconds, lo + stretch)
            streams, lost_t, lost_k = cell_streams(scene, c, lo, hi, rng)
            streams.append(gauge_stream(scene, c, lo, hi, rng))
            times, texts = _event_texts(scene, lo, hi, streams, (lost_t, lost_k), intake,
                                        '~/.ros/catenary_monitor')  # fmt: skip
            ev_ns = _ns(scene, times)
            payload = _strings(texts)
            events = [Stream(EVENTS_TOPIC, STRING, ev_ns[idx], ev_ns[idx], p)
                      for idx, p in payload]  # fmt: skip
            everything = events + streams
            _distinct(everything)
            w.write(everything)
            lo = hi
            if progress is not None:
                progress(lo / scene.seconds)
        w.w.finish()
    windows = {f.kind: f.window(scene.seconds) for f in scene.faults}
    return LogFacts(path, params, dict(w.counts), scene.seconds, scene.start_ns, windows,
                    path.stat().st_size)  # fmt: skip


def _strings(texts: list[str]) -> list[tuple[np.ndarray, np.ndarray]]:
    """``std_msgs/String`` payloads grouped by size: (indexes, (n, size) payloads)."""
    raw = [string_message(x) for x in texts]
    sizes = np.array([len(r) for r in raw])
    out = []
    for size in np.unique(sizes).tolist():
        idx = np.flatnonzero(sizes == size)
        block = np.frombuffer(b''.join(raw[i] for i in idx.tolist()), np.uint8)
        out.append((idx, block.reshape(len(idx), size)))
    return out


def main(argv: Optional[list[str]] = None) -> int:
    """``python -m catenary_monitor_study.normal_days_log DIR [...]``: write one scene's log and
    params file (then ``catenary-monitor replay DIR/SCENE.mcap``, ``catenary-monitor alarms``)."""
    import argparse
    import sys

    from catenary_monitor_study.normal_days import (
        FAULT_KINDS,
        GAUGES,
        Fault,
        drawn_scene,
        paper_scene,
        scene_margins,
    )

    p = argparse.ArgumentParser(prog='normal_days_log', description=main.__doc__)
    p.add_argument('folder', help='where the log and its params file go')
    p.add_argument('--dock', default='paper', help='paper or drawn:SEED (default: paper)')
    p.add_argument('--gauge', default='radar_1cm', choices=sorted(GAUGES))
    p.add_argument('--days', type=float, default=2.0, help='length [days] (default: 2)')
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--fault', action='append', default=[], metavar='KIND[:AT[:SECONDS[:LINE]]]',
                   help=f'a fault ({", ".join(FAULT_KINDS)}) from AT s for SECONDS s on LINE '
                   '(repeatable)')  # fmt: skip
    args = p.parse_args(argv)
    faults = []
    for text in args.fault:
        kind, *rest = text.split(':')
        if kind not in FAULT_KINDS:
            print(f'normal_days_log: unknown fault {kind!r}', file=sys.stderr)
            return 2
        at = float(rest[0]) if rest else 0.0
        seconds = float(rest[1]) if len(rest) > 1 else math.inf
        line = rest[2] if len(rest) > 2 else None
        value = {'parted': 12.0, 'pressure_step': 0.3}.get(kind, math.nan)
        faults.append(Fault(kind, at, seconds, line, value))
    if args.dock == 'paper':
        scene = paper_scene(args.gauge, days=args.days, faults=tuple(faults), seed=args.seed)
    else:
        seed = int(args.dock.split(':', 1)[1])
        scene = drawn_scene(seed, args.gauge, days=args.days, faults=tuple(faults))
    facts = write_scene(scene, Path(args.folder))
    print(json.dumps({'log': str(facts.log), 'params': str(facts.params), 'bytes': facts.bytes,
                      'messages': sum(facts.messages.values()), 'mean_depth': scene.mean_depth,
                      'margins': scene_margins(scene)}))  # fmt: skip
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
