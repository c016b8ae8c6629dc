"""A new dock's set-up: ``catenary-monitor params-template`` and ``disk-estimate``.

``params-template --lines N [--names A,B,...] [--out FILE]`` writes a valid params file for N
lines with the installer's checklist, every value to measure marked ``CHECK``
(config/dock_template.yaml is ``--lines 4``).

``disk-estimate --params-file F [--tension-rate HZ] [--depth-rate HZ] [--seconds S] [--json]``
gives the MCAP log's bytes per day at the sensors' rates (the params file's
``tension_sample_rate`` and ``depth_sample_rate`` unless given): it makes S seconds of inputs at
those rates (a steady pretension with a 10 s wave swing and noise, a slow tide), redoes the
node's steps on them (the replay's twin: every output, ``/diagnostics`` array and event the
node would log), and writes them through the node's own logger with its chunking (flushed at
0.75 s of age, zstd) on a simulated clock. The per-file part (header, metadata, summary) is
counted once per file (a file every ``log_rotate_duration`` s or ``log_rotate_size``).
test/test_dock_setup.py checks it within 10 % of a node's real log.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import json
import math
import sys
import tempfile
from pathlib import Path
from typing import Any, Optional

import numpy as np

__all__ = ['register', 'template_text', 'estimate', 'NODE_FLUSH_PERIOD']

#: The node's logger settings (ros/node.py ``_open_log``): flushed at this age (s), its
#: ``tick`` every 0.25 s.
NODE_FLUSH_PERIOD = 0.75
NODE_TICK = 0.25
DAY = 86400.0

# ------------------------------------------------------------------------- params-template
_HEADER = """\
# A new dock's params file: copy it to /etc/catenary_monitor/dock.yaml, replace every value
# marked CHECK with the dock's own, and go through the checklist (docs/deploy.md). As written
# it is a valid file ({n} lines of the seed paper's 81 mm U3 chain), so `catenary-monitor run
# --params-file` starts on it: a wrong value is not caught by the node, only by this checklist.
# Written by `catenary-monitor params-template --lines {n}`.
#
# Checklist (each item is what the installer measures, and from where):
# [ ] lines: one name per chain, the names your load cells are labelled with (a letter, then
#     letters, digits, _). Each NAME gets NAME.* parameters below.
# [ ] NAME.weight (N/m): the chain's SUBMERGED weight per metre (catalogue mass per metre x g x
#     0.87 for steel in sea water), not its weight in air.
# [ ] NAME.anchor_distance (m): HORIZONTAL distance from the hook point (the fairlead or chain
#     stopper on the dock, where the load cell is) to the anchor, as surveyed after laying.
# [ ] NAME.mbl (N): the chain's minimum breaking load from its certificate (kN x 1000).
# [ ] NAME.hook_height (m): height of the hook point ABOVE the water surface (negative below).
# [ ] Units of each load cell: the tension in N is the reading x NAME.tension_scale (1000 for a
#     cell in kN; 9.80665 for kgf; 4.44822 for lbf). A kN cell left at 1 says "wrong units?".
# [ ] NAME.tension_type: std_msgs/msg/Float64 (the reading alone, taken at arrival) or
#     geometry_msgs/msg/WrenchStamped (ros2_control's force/torque broadcaster: one force axis,
#     NAME.tension_axis x|y|z|norm, taken at its header stamp).
# [ ] The depth (m) is the water depth AT THE HOOKS, measured from the water surface to the
#     seabed below the hooks. depth_type: std_msgs/msg/Float64 (the depth itself),
#     sensor_msgs/msg/FluidPressure (a pressure gauge on the seabed or a pile: gauge_height is
#     its height above the seabed, water_density, atmospheric_pressure: 0 for a gauge reading
#     relative to the air) or sensor_msgs/msg/Range (a radar or sonar looking down: gauge_height
#     is its height above the seabed). depth_offset (m) adds the datum from the gauge's zero to
#     the depth at the hooks (chart datum vs. local seabed): check it against a lead line at
#     low water.
# [ ] Stamped sensors: their computers keep the monitor's time (chrony or PTP); set
#     tension_timeout / depth_timeout above the gateway's delivery delay plus its bunch period.
# [ ] The sensors' rates: tension_sample_rate (each load cell) and depth_sample_rate (Hz), as
#     they publish; the node counts samples that do not arrive.
# [ ] log_dir on a disk with room: `catenary-monitor disk-estimate --params-file THIS_FILE`
#     gives the log's bytes a day at those rates; log_max_total_size bounds it (at least
#     2 x log_rotate_size), log_max_age too.
# [ ] Thresholds: allowed_uplift (N) per line (0: no uplift; else below the sinker's submerged
#     weight / a safety factor), the *_warn margins, safety_factor_warn (MEG4 WLL: 2.0 = 50 % MBL).
# [ ] Replay a first hour of log with this file (catenary-monitor replay LOG --params-file F)
#     and look at the levels before relying on them.
catenary_monitor:
  ros__parameters:
    lines: [{names}]  # CHECK
    depth_topic: /tide/depth  # CHECK: the gauge's topic
    depth_type: std_msgs/msg/Float64  # CHECK
    depth_offset: 0.0  # CHECK (m)
    gauge_height: 0.0  # CHECK (m above the seabed; FluidPressure and Range only)
    tension_sample_rate: 10.0  # CHECK (Hz, each load cell)
    depth_sample_rate: 1.0  # CHECK (Hz)
    log_dir: /var/log/catenary_monitor  # CHECK
    log_rotate_size: 256.0  # MiB
    log_max_total_size: 50.0e9  # B; CHECK: disk-estimate gives the days it keeps
    log_max_age: 0.0  # s (0: keep while log_max_total_size allows)
    tension_timeout: 5.0  # s; CHECK: above the sensors' delivery delay + bunch period
    depth_timeout: 60.0  # s
"""

_LINE = """\
    {name}:
      weight: 1300.0  # CHECK N/m submerged
      anchor_distance: 120.0  # CHECK m, horizontal, hook point to anchor
      mbl: 4827000.0  # CHECK N
      hook_height: 0.0  # CHECK m above the water
      tension_topic: /mooring/{name}/tension  # CHECK
      tension_type: std_msgs/msg/Float64  # CHECK
      tension_scale: 1.0  # CHECK: 1000 for a load cell in kN
"""


def template_text(names: list[str]) -> str:
    """The params template for lines ``names``: the checklist, then every line in full."""
    head = _HEADER.format(n=len(names), names=', '.join(names))
    return head + ''.join(_LINE.format(name=name) for name in names)


def cmd_params_template(args: argparse.Namespace) -> int:
    from catenary_monitor.core.config.parameters import ConfigError, config_from_params
    from catenary_monitor.core.config.parameters import load_params_file

    names = args.names.split(',') if args.names else []
    if not names:
        width = len(str(args.lines))
        names = [f'line_{k + 1:0{width}d}' if width > 1 else f'line_{k + 1}'
                 for k in range(args.lines)]  # fmt: skip
    elif args.lines is not None and args.lines != len(names):
        print(f'catenary-monitor params-template: --lines {args.lines} but {len(names)} '
              '--names', file=sys.stderr)  # fmt: skip
        return 2
    text = template_text(names)
    with tempfile.TemporaryDirectory() as tmp:  # what it writes must load as a params file
        check = Path(tmp) / 'dock.yaml'
        check.write_text(text, encoding='utf-8')
        try:
            config_from_params(load_params_file(check))
        except ConfigError as err:
            print(f'catenary-monitor params-template: {err}', file=sys.stderr)
            return 2
    if args.out in (None, '-'):
        sys.stdout.write(text)
        return 0
    try:
        Path(args.out).write_text(text, encoding='utf-8')
    except OSError as err:
        print(f'catenary-monitor params-template: cannot write {args.out}: '
              f'{err.strerror or err}', file=sys.stderr)  # fmt: skip
        return 2
    print(f'params template for {len(names)} lines: {args.out}', file=sys.stderr)
    return 0


# ---------------------------------------------------------------------------- disk-estimate
def _pretension(config: Any, depth: float) -> np.ndarray:
    """Each line's steady hook tension (N): its minimum anchor distance at 80 % of its anchor
    distance at ``depth`` (a calm day, nothing alarmed)."""
    from catenary_monitor import solve

    out = []
    grid = np.logspace(2.0, 9.0, 4000)
    for line in config.lines:
        result = solve(line.weight, depth + line.hook_height, horizontal=grid,
                       anchor_distance=line.anchor_distance)  # fmt: skip
        gap = np.abs(np.nan_to_num(result.min_anchor_distance, nan=np.inf)
                     - 0.8 * line.anchor_distance)  # fmt: skip
        tension = result.top_tension[int(np.argmin(gap))]
        out.append(float(tension) if math.isfinite(tension) else 0.3 * line.mbl)
    return np.array(out)


def _inputs(config: Any, rates: tuple[float, float], seconds: float, depth: float) -> Any:
    """Tension per line and depth as (receive time ns, value), at the given rates."""
    rng = np.random.default_rng(1)
    start = 1_700_000_000 * 10**9
    tension_rate, depth_rate = rates
    t = np.arange(0.0, seconds, 1.0 / tension_rate)
    tensions = {}
    for k, (line, t0) in enumerate(zip(config.lines, _pretension(config, depth))):
        phase = 2 * math.pi * k / max(len(config.lines), 1)
        values = t0 * (1 + 0.05 * np.sin(2 * math.pi * t / 10.0 + phase))
        values += rng.normal(0.0, 1e-3 * t0, len(t))
        stamps = start + np.round((t + rng.uniform(0, 2e-3, len(t))) * 1e9).astype(np.int64)
        tensions[line.name] = (stamps, values)
    td = np.arange(0.0, seconds, 1.0 / depth_rate)
    level = depth + 0.3 * td / 3600.0 + rng.normal(0.0, 0.005, len(td))
    return tensions, (start + np.round(td * 1e9).astype(np.int64) + 1_000_000, level)


def _write_inputs(path: Path, config: Any, tensions: Any, depth: Any) -> None:
    from catenary_monitor.io.cdr import float64_payloads
    from catenary_monitor.io.mcap_column_writer import ColumnWriter
    from catenary_monitor.io.ros_schemas import message_definition

    topics = [(line.tension_topic, *tensions[line.name]) for line in config.lines]
    topics.append((config.depth_topic, *depth))
    t = np.concatenate([tt for _, tt, _ in topics])
    v = np.concatenate([vv for _, _, vv in topics])
    k = np.concatenate([np.full(len(tt), i) for i, (_, tt, _) in enumerate(topics)])
    order = np.argsort(t, kind='stable')
    with open(path, 'wb') as f:
        w = ColumnWriter(f)
        sid = w.register_schema('std_msgs/msg/Float64', 'ros2msg',
                                message_definition('std_msgs/msg/Float64').encode())  # fmt: skip
        ids = np.array([w.register_channel(name, 'cdr', sid) for name, _, _ in topics])
        w.write_columns(ids[k[order]], t[order], float64_payloads(v[order]))
        w.finish()


def _stamped(type_name: str, value: float, stamp: int, frame: str) -> bytes:
    """A sensor's message of ``type_name`` in CDR (what the node logs for that input)."""
    import struct

    name = frame.encode() + b'\0'
    head = struct.pack('<4siiI', b'\x00\x01\x00\x00', stamp // 10**9, stamp % 10**9, len(name))
    body = head + name
    if type_name.endswith('Float64'):
        return b'\x00\x01\x00\x00' + struct.pack('<d', value)
    if type_name.endswith('Range'):
        body += b'\x00' + bytes(-(len(body) - 4 + 1) % 4)
        return body + struct.pack('<5f', 0.1, 0.3, 50.0, value, 0.0)
    body += bytes(-(len(body) - 4) % 8)
    if type_name.endswith('WrenchStamped'):
        return body + struct.pack('<6d', 0.0, 0.0, value, 0.0, 0.0, 0.0)
    return body + struct.pack('<2d', value * 1e4, 0.0)  # FluidPressure


def _input_types(config: Any) -> dict[str, str]:
    types = {line.tension_topic: line.tension_type for line in config.lines}
    types[config.depth_topic] = config.depth_type
    return types


def _rewrite(results: Path, out_dir: Path, config: Any, span: Optional[float]) -> Path:
    """The results log's messages through the node's logger, on a clock that follows the log's
    time (chunks as the node cuts them); ``span`` 0: the header, metadata and summary alone."""
    from mcap.reader import make_reader

    from catenary_monitor.io.mcap_log import McapLogger

    clock = [0.0]
    log = McapLogger(out_dir, prefix='estimate', flush_period=NODE_FLUSH_PERIOD,
                     max_bytes=2**62, max_seconds=1e12, fsync=False, bag_metadata=False,
                     clock=lambda: clock[0], wall_clock=lambda: 0.0)  # fmt: skip
    types = _input_types(config)
    with open(results, 'rb') as f:
        reader = make_reader(f)
        for record in reader.iter_metadata():
            log.add_metadata(record.name, dict(record.metadata))
        registered: set[str] = set()
        next_tick = None
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            if span == 0:
                break
            now = message.log_time / 1e9
            next_tick = now if next_tick is None else next_tick
            while next_tick <= now:
                clock[0] = next_tick
                log.tick()
                next_tick += NODE_TICK
            clock[0] = now
            topic, kind = channel.topic, schema.name if schema else ''
            data = message.data
            if topic in types and types[topic] != kind:
                kind = types[topic]
                value = float(np.frombuffer(message.data[4:12], '<f8')[0])
                data = _stamped(kind, value, message.log_time, 'sensor_frame')
            if topic not in registered:
                log.register(topic, kind, channel.metadata.get('offered_qos_profiles'))
                registered.add(topic)
            log.write(topic, data, message.log_time)
    path = log.current_path
    log.close()
    assert path is not None
    return path


def _replay(argv: list[str]) -> int:
    """``catenary-monitor replay ARGV`` in this process (its parser alone: the command line's
    main imports this module)."""
    from catenary_monitor.cli import replay

    parser = argparse.ArgumentParser(prog='catenary-monitor')
    replay.register(parser.add_subparsers())
    args = parser.parse_args(argv)
    return int(args.func(args) or 0)


def estimate(config: Any, tension_rate: float, depth_rate: float, seconds: float = 120.0,
             depth: float = 20.0) -> dict[str, Any]:  # fmt: skip
    """The node's MCAP log for ``config`` at these rates: bytes per second of logging, the
    bytes of a file's fixed part, files and bytes per day."""
    from catenary_monitor.core.config.parameters import config_to_params, params_file_text
    from catenary_monitor.replay.outputs import si_inputs

    lines = tuple(dataclasses.replace(lc, tension_topics=()) for lc in config.lines)
    config = dataclasses.replace(config, lines=lines)
    with tempfile.TemporaryDirectory(prefix='catenary-estimate-') as tmp:
        base = Path(tmp)
        params = base / 'si.yaml'
        params.write_text(params_file_text(config_to_params(si_inputs(config))))
        tensions, level = _inputs(config, (tension_rate, depth_rate), seconds, depth)
        _write_inputs(base / 'inputs.mcap', config, tensions, level)
        replay = ['replay', str(base / 'inputs.mcap'), '--params-file', str(params), '--out',
                  str(base / 'results.mcap'), '--quiet']  # fmt: skip
        quiet = io.StringIO()
        with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
            status = _replay(replay)
        if status != 0:
            raise RuntimeError(f'the replay of the made-up inputs failed: {quiet.getvalue()}')
        full = _rewrite(base / 'results.mcap', base / 'full', config, None)
        empty = _rewrite(base / 'results.mcap', base / 'empty', config, 0)
        fixed = empty.stat().st_size
        per_second = (full.stat().st_size - fixed) / seconds
    per_day_data = per_second * DAY
    files = max(DAY / config.log_rotate_duration,
                per_day_data / (config.log_rotate_size * 1024 * 1024))  # fmt: skip
    per_day = per_day_data + math.ceil(files) * fixed
    answer = {
        'lines': len(config.lines),
        'tension_rate': tension_rate,
        'depth_rate': depth_rate,
        'bytes_per_second': per_second,
        'file_fixed_bytes': fixed,
        'files_per_day': math.ceil(files),
        'bytes_per_day': per_day,
        'simulated_seconds': seconds,
    }
    if config.log_max_total_size > 0:
        answer['days_in_log_max_total_size'] = config.log_max_total_size / per_day
    return answer


def _rates(args: argparse.Namespace, config: Any) -> tuple[float, float]:
    tension = args.tension_rate or config.alarm.tension_sample_rate
    depth = args.depth_rate or config.alarm.depth_sample_rate
    if not tension > 0:
        raise ValueError('the params file has no tension_sample_rate: give --tension-rate HZ')
    if not depth > 0:
        raise ValueError('the params file has no depth_sample_rate: give --depth-rate HZ')
    return float(tension), float(depth)


def cmd_disk_estimate(args: argparse.Namespace) -> int:
    from catenary_monitor.core.config.parameters import ConfigError, config_from_params
    from catenary_monitor.core.config.parameters import load_params_file

    try:
        config = config_from_params(load_params_file(args.params_file))
        tension_rate, depth_rate = _rates(args, config)
    except (ConfigError, ValueError) as err:
        print(f'catenary-monitor disk-estimate: {err}', file=sys.stderr)
        return 2
    answer = estimate(config, tension_rate, depth_rate, args.seconds, args.depth)
    if args.json:
        print(json.dumps(answer, indent=1))
        return 0
    day = answer['bytes_per_day']
    print(f"{answer['lines']} lines, tensions at {tension_rate:g} Hz each, the depth at "
          f"{depth_rate:g} Hz: {answer['bytes_per_second'] / 1e3:.1f} kB/s, "
          f'{day / 1e9:.2f} GB a day ({day / 2**30:.2f} GiB)')  # fmt: skip
    if 'days_in_log_max_total_size' in answer:
        print(f'log_max_total_size {config.log_max_total_size / 1e9:g} GB keeps about '
              f"{answer['days_in_log_max_total_size']:.1f} days")  # fmt: skip
    return 0


def _rate(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f'expected a rate > 0 Hz, got {text!r}')
    return value


def register(sub: Any) -> None:
    """Add ``params-template`` and ``disk-estimate`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'params-template',
        help="write a new dock's params file: every line, the installer's checklist",
        description='Write a valid params file for N lines, every value to measure marked '
        'CHECK, with the checklist of docs/deploy.md at its top.',
    )
    p.add_argument('--lines', type=int, choices=range(1, 1000), metavar='N',
                   help='how many lines (chains)')  # fmt: skip
    p.add_argument('--names', metavar='A,B,...', help="the lines' names (default line_1 ...)")
    p.add_argument('--out', metavar='FILE', help='write here (default: standard output)')
    p.set_defaults(func=cmd_params_template)
    p = sub.add_parser(
        'disk-estimate',
        help="the MCAP log's bytes per day at the sensors' rates",
        description="Estimate the node's MCAP log bytes per day for a params file at the "
        "sensors' rates: the node's steps and its logger on made-up inputs at those rates.",
    )
    p.add_argument('--params-file', required=True, metavar='FILE', help='the dock\'s params')
    p.add_argument('--tension-rate', type=_rate, metavar='HZ',
                   help='each load cell\'s rate (default: tension_sample_rate)')  # fmt: skip
    p.add_argument('--depth-rate', type=_rate, metavar='HZ',
                   help='the depth gauge\'s rate (default: depth_sample_rate)')  # fmt: skip
    p.add_argument('--seconds', type=_rate, default=120.0, metavar='S',
                   help='simulated seconds (default %(default)s)')  # fmt: skip
    p.add_argument('--depth', type=_rate, default=20.0, metavar='M',
                   help='the water depth of the made-up inputs (default %(default)s m)')
    p.add_argument('--json', action='store_true', help='one JSON object')
    p.set_defaults(func=cmd_disk_estimate)
