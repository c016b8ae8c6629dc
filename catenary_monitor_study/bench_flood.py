"""``catenary-monitor bench-flood``: the node under a flood of tension samples.

Starts the monitor on the paper's dock (config/floating_dock.yaml, 12 lines with their chain
lengths, so every sample runs the whole decision path: solve, bounds, holding, alarms; MCAP
logging on, in a temporary directory), and a publisher process that sends every line's hook
tension at ``--rate`` Hz (the lines spread evenly over the period; ``--burst N`` sends N
samples of every line at once every N periods instead) and the depth at 10 Hz for
``--duration`` s. Each tension carries its own index (``BASE + STEP * i``), so the node's log
says which samples it logged and its outputs which ones it stepped. This process receives
``/diagnostics`` and afterwards reads the node's log. It reports:

* ``/diagnostics`` on time: the longest gap between two arrays received while the flood ran
  (and after it), in seconds and in diagnostic periods (``1 / diagnostic_rate``);
* the intake alarm: from the send time of the first sample the node did not step (coalesced,
  or lost before the node) to the first ``catenary_monitor: intake`` status not OK received;
* the counts: samples sent, logged (every one?), stepped, coalesced (logged, not stepped) and
  lost (never logged) against what the node counted in its intake records, and the share the
  last intake status reports against the share not stepped in its 60 s window;
* CPU of the node (user + system over the flood's wall time) and its RSS at the end;
* live = replay: ``replay_log`` of the node's log (the coalescing records followed) against the
  outputs the node logged, line by line (stamps, values to 1e-12).

Exit 0 when every check held, 1 otherwise. ``python -m catenary_monitor_study.bench_flood
publish ...`` is the publisher alone.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Optional

import numpy as np

from catenary_monitor.cli.demo import child_env
from catenary_monitor.core.config.parameters import ConfigError

__all__ = [
    'run_flood',
    'flood',
    'publish_main',
    'register',
    'flood_params',
    'analyse',
    'logged_outputs',
]

#: Tension of sample i: BASE + STEP * i (N): the paper's pretension, each sample its own value;
#: the priming samples before the flood are i - PRIMING (negative indexes).
BASE, STEP, PRIMING = 372e3, 1e-3, 1_000_000
#: Depth published during the flood [m] (the paper's mean tide) and its rate [Hz].
DEPTH, DEPTH_RATE = 20.85, 10.0
INTAKE, SENSORS = 'catenary_monitor: intake', 'catenary_monitor: sensors'


def flood_params(
    path: Path, params_file: Optional[str] = None, extra: Optional[dict[str, Any]] = None
) -> Any:
    """The paper's dock (or ``params_file``) with the bench's topics and the ``extra``
    parameters, written to ``path``; returns the configuration."""
    import dataclasses

    from catenary_monitor.core.config.parameters import (
        config_from_params,
        config_to_params,
        load_params_file,
        params_file_text,
    )
    from catenary_monitor.sim.scenario import default_config_path

    config = config_from_params(load_params_file(params_file or default_config_path()))
    lines = tuple(
        dataclasses.replace(line, tension_topic=f'/bench/{line.name}/tension')
        for line in config.lines
    )
    config = dataclasses.replace(config, lines=lines, depth_topic='/bench/depth')
    if extra:
        config = config_from_params({**config_to_params(config), **extra})
    path.write_text(params_file_text(config_to_params(config)))
    return config


def parse_setting(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` (a number, true/false, or a string) for ``--set``."""
    name, sep, value = text.partition('=')
    if not sep or not name:
        raise argparse.ArgumentTypeError(f'--set {text!r}: expected NAME=VALUE')
    if value.lower() in ('true', 'false'):
        return name, value.lower() == 'true'
    try:
        return name, float(value)
    except ValueError:
        return name, value


# --------------------------------------------------------------------------- the publisher
def publish_main(argv: list[str]) -> int:
    """``publish TOPICS RATE DURATION BURST``: prime every topic at 10 Hz (values below
    :data:`BASE`: not part of the flood) until a line comes on stdin, then flood; print one
    JSON line at the start (``{"t0": wall s}``) and one at the end (``{"sent": [...],
    "primed": [...]}``)."""
    import select

    import rclpy
    from rclpy.qos import qos_profile_sensor_data
    from std_msgs.msg import Float64

    topics, burst = argv[0].split(','), int(argv[3])
    rate, duration = float(argv[1]), float(argv[2])
    rclpy.init()
    node = rclpy.create_node('bench_flood_publisher')
    pubs = [node.create_publisher(Float64, t, qos_profile_sensor_data) for t in topics]
    depth = node.create_publisher(Float64, '/bench/depth', qos_profile_sensor_data)
    n = len(pubs)
    msg, level = Float64(), Float64(data=DEPTH)
    primed = [0] * n
    deadline = time.monotonic() + 90.0
    # Until the driver says every line reached the node (its readers matched these writers
    # too: samples sent before are lost to DDS, not to the node), one sample a line at 10 Hz.
    while not select.select([sys.stdin], [], [], 0.1)[0]:
        if time.monotonic() > deadline:
            print(json.dumps({'error': 'no go from the driver'}), flush=True)
            return 1
        depth.publish(level)
        for k, pub in enumerate(pubs):
            msg.data = BASE + STEP * (primed[k] - PRIMING)
            pub.publish(msg)
            primed[k] += 1
    sys.stdin.readline()
    step = burst / (rate * n)  # between one line's send and the next line's
    sent, d = [0] * n, 0
    depth.publish(level)
    t0_wall, t0 = time.time(), time.monotonic()
    print(json.dumps({'t0': t0_wall}), flush=True)
    j = 0  # send slot: line j % n, round j // n
    while True:
        due = j * step
        if due >= duration:
            break
        now = time.monotonic() - t0
        if due > now:
            time.sleep(min(due - now, 0.01))
            continue
        k = j % n
        for _ in range(burst):
            msg.data = BASE + STEP * sent[k]
            pubs[k].publish(msg)
            sent[k] += 1
        j += 1
        while d < int(now * DEPTH_RATE):
            depth.publish(level)
            d += 1
    print(json.dumps({'sent': sent, 'primed': primed, 'depth': d + 1}), flush=True)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


def send_times(t0: float, rate: float, n: int, burst: int, k: int, i: np.ndarray) -> np.ndarray:
    """Wall time [s] at which sample ``i`` of line ``k`` (of ``n``) was due."""
    return t0 + ((i // burst) * n + k) * burst / (rate * n)


# --------------------------------------------------------------------------- the analysis
def _cpu_seconds(pid: int) -> float:
    """User + system CPU time of ``pid`` [s] (0 once it is gone)."""
    try:
        fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _rss_mb(pid: int) -> float:
    try:
        for line in Path(f'/proc/{pid}/status').read_text().splitlines():
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float('nan')


def _node_records(files: list[Path]) -> list[dict[str, Any]]:
    from catenary_monitor.core.monitor.events import EVENTS_TOPIC
    from catenary_monitor.io.cdr import string_text
    from catenary_monitor.io.mcap_read import iter_messages

    out = []
    for m in iter_messages(files, [EVENTS_TOPIC]):
        record = json.loads(string_text(m.data))
        record['stamp_ns'] = m.log_time_ns
        out.append(record)
    return out


def logged_outputs(files: list[Path], topic: str) -> tuple[np.ndarray, np.ndarray]:
    """(log time ns, the output arrays) of one line's outputs topic."""
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64MultiArray

    from catenary_monitor.io.mcap_read import iter_messages

    stamps, rows = [], []
    for m in iter_messages(files, [topic]):
        stamps.append(m.log_time_ns)
        rows.append(deserialize_message(m.data, Float64MultiArray).data)
    return np.array(stamps, np.int64), np.array(rows, float).reshape(len(rows), -1)


def analyse(
    config: Any,
    log_dir: Path,
    sent: list[int],
    t0: float,
    rate: float,
    burst: int,
    diagnostics: list[tuple[float, int, str, dict[str, str]]],
    flood_end: float,
    primed: Optional[list[int]] = None,
) -> dict[str, Any]:
    """The figures and checks of one flood (see the module docstring); ``primed``: the
    samples sent before it (negative indexes: in the node's counts, those that reached it,
    but not in the flood's figures)."""
    from catenary_monitor.core.monitor.state import OUTPUT_FIELDS, VALUE_FIELDS
    from catenary_monitor.io.mcap_read import iter_messages, read_float64_topics
    from catenary_monitor.replay.driver import replay_log

    files = sorted(log_dir.glob('*.mcap'))
    names = [line.name for line in config.lines]
    topics = [f'/bench/{name}/tension' for name in names]
    columns, _ = read_float64_topics(files, topics)
    n = len(names)
    logged = logged_all = stepped = stepped_all = 0
    first_missed = np.inf
    outputs = {}
    for k, (name, topic) in enumerate(zip(names, topics)):
        index = np.rint((columns[topic][1] - BASE) / STEP).astype(np.int64)
        logged += int((index >= 0).sum())
        logged_all += len(index)
        out_t, out = logged_outputs(files, f'/catenary_monitor/{name}/outputs')
        outputs[name] = (out_t, out)
        handled = np.rint((out[:, 0] - BASE) / STEP).astype(np.int64) if len(out) else index[:0]
        handled = np.unique(handled)  # a depth event's output repeats the line's tension
        stepped += int((handled >= 0).sum())
        stepped_all += len(handled)
        missed = np.setdiff1d(np.arange(sent[k]), handled)
        if missed.size:
            first_missed = min(first_missed, float(send_times(t0, rate, n, burst, k, missed)[0]))
    total = sum(sent)
    # /diagnostics: gaps while the flood ran (from its start to 2 s after its end).
    period = 1.0 / config.alarm.diagnostic_rate
    times = np.array([d[0] for d in diagnostics if t0 <= d[0] <= flood_end + 2.0])
    gaps = np.diff(np.concatenate([[t0], times])) if times.size else np.array([np.inf])
    alarm_at = next(
        (d[0] for d in diagnostics if d[1] != 0 and d[0] >= first_missed - period), np.inf
    )
    last = next((d for d in reversed(diagnostics) if d[0] <= flood_end + 2.0), None)
    logged_at = np.array(
        [m.log_time_ns * 1e-9 for m in iter_messages(files, ['/diagnostics'])], float
    )
    logged_at = logged_at[(logged_at >= t0) & (logged_at <= flood_end + 2.0)]
    log_gap = float(np.diff(np.concatenate([[t0], logged_at])).max()) if logged_at.size else np.inf
    # What the node counted (its intake records) and what its last status said.
    records = _node_records(files)
    intake = [r for r in records if r['kind'] == 'intake']
    counted = {
        key: int(sum(sum(r.get(key, [])[:n]) for r in intake))
        for key in ('received', 'coalesced', 'dropped')
    }
    coalesced_records = [r for r in records if r['kind'] == 'coalesced' and 'line' in r]
    # live = replay
    result = replay_log(files, config, ticks='log').result
    worst, mismatched = 0.0, []
    for r in result.lines:
        out_t, out = outputs[r.name]
        if out_t.tolist() != r.t_ns.tolist():
            mismatched.append(r.name)
            continue
        for key in VALUE_FIELDS:
            a, b = out[:, OUTPUT_FIELDS.index(key)], r.values[key]
            both = np.isfinite(a) & np.isfinite(b)
            if not np.array_equal(np.isnan(a), np.isnan(b)):
                mismatched.append(f'{r.name} {key}')
            elif both.any():
                rel = np.abs(a[both] - b[both]) / np.maximum(np.abs(b[both]), 1e-6)
                worst = max(worst, float(rel.max()))
    values = last[3] if last is not None else {}
    shown = int(values.get('messages_dropped', -1))
    shown_of = shown + int(values.get('messages_handled', 0))
    return {
        'sent': total,
        'primed': sum(primed or []),
        'logged_with_priming': logged_all,
        'stepped_with_priming': stepped_all,
        'logged': logged,
        'stepped': stepped,
        'not_stepped': total - stepped,
        'share_not_stepped': (total - stepped) / total if total else 0.0,
        'node_counted': counted,
        'coalescing_records': len(coalesced_records),
        'last_intake_level': last[1] if last is not None else None,
        'last_intake_message': last[2] if last is not None else None,
        'last_intake_share': shown / shown_of if shown_of > 0 else None,
        'diagnostics_received': int(times.size),
        'diagnostic_period_s': period,
        'max_gap_s': float(gaps.max()),
        'max_gap_periods': float(gaps.max() / period),
        'max_gap_in_log_s': log_gap,
        'first_not_stepped_s': None if first_missed == np.inf else first_missed - t0,
        'intake_alarm_after_s': (
            None if first_missed == np.inf or alarm_at == np.inf else alarm_at - first_missed
        ),
        'replay_mismatches': mismatched,
        'replay_max_rel_diff': worst,
    }


def _checks(r: dict[str, Any]) -> dict[str, bool]:
    """The bench's pass/fail lines."""
    period = r['diagnostic_period_s']
    counted = r['node_counted']
    missed = r['not_stepped'] > 0
    alarm = r['intake_alarm_after_s']
    return {
        'diagnostics within 2 periods': r['max_gap_periods'] <= 2.0,
        'intake alarm within 2 periods of the first sample not stepped': (
            not missed or (alarm is not None and alarm <= 2.0 * period)
        ),
        'no "none dropped" while dropping': not (
            missed and 'none dropped' in (r['last_intake_message'] or '')
        ),
        'node counted what it stepped': counted['received'] == r['stepped_with_priming'],
        'node counted what it coalesced': (
            counted['coalesced'] == r['logged_with_priming'] - r['stepped_with_priming']
        ),
        'node counted what it lost': counted['dropped'] == r['sent'] - r['logged'],
        'live = replay': not r['replay_mismatches'] and r['replay_max_rel_diff'] <= 1e-12,
    }


# --------------------------------------------------------------------------- the run
def run_flood(
    rate: float = 200.0,
    duration: float = 60.0,
    burst: int = 1,
    params_file: Optional[str] = None,
    json_out: bool = False,
    log_dir: Optional[str] = None,
    extra: Optional[dict[str, Any]] = None,
) -> int:
    """Run one flood and print its figures; 0 when every check held (1 otherwise, 2 when it
    could not run)."""
    try:
        result = flood(rate, duration, burst, params_file, log_dir, extra=extra)
    except ConfigError as err:
        print(f'bench-flood: {err}', file=sys.stderr)
        return 2
    if 'error' in result:
        print(f'bench-flood: {result["error"]}', file=sys.stderr)
        return 2
    print(json.dumps(result) if json_out else report(result))
    return 0 if result['ok'] else 1


def flood(
    rate: float = 200.0,
    duration: float = 60.0,
    burst: int = 1,
    params_file: Optional[str] = None,
    log_dir: Optional[str] = None,
    domain: int = 131,
    extra: Optional[dict[str, Any]] = None,
) -> dict[str, Any]:
    """One flood: its figures and checks (``error`` when it could not run). The node's log
    goes to ``log_dir`` (kept) or a temporary directory (removed)."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile

    env = child_env(domain)
    os.environ.update({k: env[k] for k in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_DOMAIN_ID')})
    tmp = Path(tempfile.mkdtemp(prefix='catenary_flood_'))
    config = flood_params(tmp / 'params.yaml', params_file, extra)
    logs = Path(log_dir) if log_dir else tmp / 'log'
    monitor = subprocess.Popen(
        [
            sys.executable, '-m', 'catenary_monitor.ros.node', '--ros-args',
            '--params-file', str(tmp / 'params.yaml'), '-p', f'log_dir:={logs}',
        ],
        env=env,
        stdout=open(tmp / 'monitor.out', 'w'),
        stderr=subprocess.STDOUT,
    )  # fmt: skip
    rclpy.init()
    node = rclpy.create_node('bench_flood_driver')
    diagnostics: list[tuple[float, int, str, dict[str, str]]] = []
    lock = threading.Lock()

    reporting = threading.Event()  # every line's tension reached the node

    def on_diag(msg: Any) -> None:
        now = time.time()
        for st in msg.status:
            if st.name == SENSORS and any(
                kv.key == 'lines_waiting' and kv.value == '0' for kv in st.values
            ):
                reporting.set()
            if st.name == INTAKE:
                values = {kv.key: kv.value for kv in st.values}
                with lock:
                    # the full text (the message is its headline)
                    text = values.get('detail', st.message)
                    diagnostics.append((now, st.level[0], text, values))
                return
        with lock:
            diagnostics.append((now, 0, '', {}))

    node.create_subscription(DiagnosticArray, '/diagnostics', on_diag, QoSProfile(depth=100))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    topics = ','.join(line.tension_topic for line in config.lines)
    publisher = subprocess.Popen(
        [
            sys.executable, '-m', 'catenary_monitor_study.bench_flood', 'publish', topics,
            repr(rate), repr(duration), str(burst),
        ],
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )  # fmt: skip
    try:
        if not reporting.wait(90.0):
            publisher.kill()
            return {'error': 'the node never had every line reporting'}
        time.sleep(1.0)  # a quiet second: no status left over from the start
        publisher.stdin.write('go\n')  # type: ignore[union-attr]
        publisher.stdin.flush()  # type: ignore[union-attr]
        start = json.loads(publisher.stdout.readline() or '{}')  # type: ignore[union-attr]
        if 't0' not in start:
            return {'error': f'the publisher did not start ({start})'}
        t0 = float(start['t0'])
        cpu0, wall0 = _cpu_seconds(monitor.pid), time.monotonic()
        rss, flooding = [_rss_mb(monitor.pid)], threading.Event()

        def sample_rss() -> None:
            while not flooding.wait(1.0):
                rss.append(_rss_mb(monitor.pid))

        sampler = threading.Thread(target=sample_rss, daemon=True)
        sampler.start()
        end = json.loads(publisher.stdout.readline() or '{}')  # type: ignore[union-attr]
        cpu = (_cpu_seconds(monitor.pid) - cpu0) / (time.monotonic() - wall0)
        flood_end = time.time()
        flooding.set()
        sampler.join(5.0)
        rss.append(_rss_mb(monitor.pid))
        time.sleep(3.0)  # the last intake counts and diagnostics
    finally:
        try:
            publisher.wait(30)
        except subprocess.TimeoutExpired:
            publisher.kill()
            publisher.wait(5)
        if monitor.poll() is None:
            monitor.send_signal(signal.SIGINT)
        try:
            monitor.wait(30)
        except subprocess.TimeoutExpired:
            monitor.kill()
        executor.shutdown(timeout_sec=1.0)
        spinner.join(5.0)
        node.destroy_node()
        rclpy.try_shutdown()
    if 'sent' not in end:
        return {'error': f'the publisher failed ({end})'}
    with lock:
        seen = list(diagnostics)
    result = {
        'lines': len(config.lines),
        'rate_hz': rate,
        'duration_s': duration,
        'burst': burst,
        'cpus': os.cpu_count(),
        'load': os.getloadavg()[0],
        'node_cpu_share': cpu,
        'node_rss_mb': rss[-1],
        'node_rss_start_mb': rss[0],
        'node_rss_max_mb': max(rss),
        'node_exit': monitor.returncode,
        **analyse(
            config, logs, end['sent'], t0, rate, burst, seen, flood_end, end.get('primed')
        ),
    }
    checks = _checks(result)
    result['checks'] = checks
    result['ok'] = all(checks.values()) and monitor.returncode == 0
    result['log_dir'] = str(logs) if log_dir else None
    shutil.rmtree(tmp, ignore_errors=True)
    return result


def report(r: dict[str, Any]) -> str:
    """The figures as text."""
    pct = 100.0
    counted = r['node_counted']
    alarm = r['intake_alarm_after_s']
    first = r['first_not_stepped_s']
    burst = f', bursts of {r["burst"]}' if r['burst'] > 1 else ''
    lines = [
        f'flood: {r["lines"]} lines x {r["rate_hz"]:g} Hz for {r["duration_s"]:g} s{burst} '
        f'({r["lines"] * r["rate_hz"]:g} samples/s), {r["cpus"]} CPUs, load {r["load"]:.2f}',
        f'node: {pct * r["node_cpu_share"]:.0f} % of one core; RSS {r["node_rss_start_mb"]:.0f} '
        f'MB at the start, {r["node_rss_max_mb"]:.0f} MB at most, {r["node_rss_mb"]:.0f} MB at '
        'the end',
        f'samples: {r["sent"]} sent, {r["logged"]} logged, {r["stepped"]} stepped, '
        f'{r["not_stepped"]} not stepped ({pct * r["share_not_stepped"]:.1f} %)',
        f'node counted: {counted["received"]} stepped, {counted["coalesced"]} coalesced, '
        f'{counted["dropped"]} lost; {r["coalescing_records"]} coalescing records',
        f'/diagnostics: {r["diagnostics_received"]} received, longest gap '
        f'{r["max_gap_s"]:.2f} s ({r["max_gap_periods"]:.2f} periods of '
        f'{r["diagnostic_period_s"]:g} s; {r["max_gap_in_log_s"]:.2f} s between two the node '
        'logged)',
        (
            'every sample stepped'
            if first is None
            else f'first sample not stepped at {first:.2f} s; intake alarm '
            + (
                'never'
                if alarm is None
                else (
                    f'{alarm:.2f} s later'
                    if alarm >= 0
                    else f'already up ({-alarm:.2f} s before: the node was busy)'
                )
            )
        ),
        f'last intake status: {r["last_intake_message"]}',
        f'live = replay: {"yes" if not r["replay_mismatches"] else r["replay_mismatches"]} '
        f'(largest relative difference {r["replay_max_rel_diff"]:.1e})',
    ]
    lines += [f'  {"ok  " if ok else "FAIL"} {name}' for name, ok in r['checks'].items()]
    lines.append('OK' if r['ok'] else 'FAILED')
    return '\n'.join(lines)


def register(sub: Any) -> None:
    """Add ``bench-flood`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-flood',
        help='the node under a flood of samples: diagnostics on time, coalescing counted',
        description='Flood the node (the paper\'s dock, 12 lines) with tension samples at '
        '--rate for --duration s; check /diagnostics stays on time, the intake alarm comes '
        'within two diagnostic periods of the first sample not stepped, the counts are right, '
        'every sample is logged and replay of the log redoes the node\'s steps.',
    )
    p.add_argument('--rate', type=float, default=200.0, help='per line [Hz] (default: 200)')
    p.add_argument('--duration', type=float, default=60.0, help='flood time [s] (default: 60)')
    p.add_argument(
        '--burst',
        type=int,
        default=1,
        help='send N samples of a line at once every N periods (default: 1, evenly spread)',
    )
    p.add_argument('--params-file', metavar='F', help='default: config/floating_dock.yaml')
    p.add_argument(
        '--set',
        type=parse_setting,
        action='append',
        default=[],
        metavar='NAME=VALUE',
        help="a parameter of the node's (e.g. intake_step_budget=0); repeatable",
    )
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.add_argument(
        '--log-dir', metavar='DIR', help="the node's log folder, kept (default: a temporary one)"
    )
    p.set_defaults(func=_command)


def _command(args: argparse.Namespace) -> int:
    return run_flood(
        args.rate,
        args.duration,
        max(1, args.burst),
        args.params_file,
        json_out=args.json,
        log_dir=args.log_dir,
        extra=dict(args.set),
    )


if __name__ == '__main__':
    if sys.argv[1:2] == ['publish']:
        sys.exit(publish_main(sys.argv[2:]))
    sys.exit(run_flood())
