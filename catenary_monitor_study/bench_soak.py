"""``catenary-monitor bench-soak``: the node for a long run with rotating logs.

Starts the monitor (a child process, MCAP logging on, ``log_rotate_duration`` =
``--rotate-duration``), publishes every line's tension at ``--rate`` and the depth at 1 Hz
from this process for ``--duration`` s, samples the node's RSS every ``--sample`` s, then stops
the node (SIGINT) and checks, with the ``mcap`` package's reader (CRCs validated):

* RSS flat: start (after the warm-up), end, max, and end - start;
* nothing lost: tension and depth messages published vs logged (every file of the folder);
* every file finished: each one has a summary (written by the node on rotation or close);
* the intake status's ``messages_dropped`` (the newest seen on /diagnostics).
"""

from __future__ import annotations

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
from typing import Any

from catenary_monitor.cli.demo import child_env

__all__ = ['run_soak', 'register']

_W = 1300.0


def _rss_bytes(pid: int) -> int:
    """Resident set size of ``pid`` [bytes] (0 once it is gone)."""
    try:
        for line in Path(f'/proc/{pid}/status').read_text().splitlines():
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _params(path: Path, names: list[str], rotate: float) -> None:
    text = [
        'catenary_monitor:',
        '  ros__parameters:',
        f'    lines: [{", ".join(names)}]',
        f'    log_rotate_duration: {float(rotate)!r}',
        '    depth_topic: /soak/depth',
    ]
    for n in names:
        text += [
            f'    {n}:',
            f'      weight: {_W}',
            '      anchor_distance: 120.0',
            '      mbl: 4827000.0',
            f'      tension_topic: /soak/{n}/tension',
        ]
    path.write_text('\n'.join(text) + '\n')


def check_files(log_dir: Path, topics: list[str]) -> dict[str, Any]:
    """Open every MCAP file of ``log_dir`` with the ``mcap`` reader: files, the unfinished
    ones (no summary), messages per topic of ``topics``, and reader errors."""
    from mcap.reader import make_reader

    files = sorted(log_dir.glob('*.mcap'))
    counts = dict.fromkeys(topics, 0)
    unfinished, errors = [], []
    for f in files:
        try:
            with open(f, 'rb') as fh:
                reader = make_reader(fh, validate_crcs=True)
                if reader.get_summary() is None:
                    unfinished.append(f.name)
                for _, channel, _ in reader.iter_messages(topics=topics):
                    counts[channel.topic] += 1
        except Exception as exc:  # noqa: BLE001 - reported, not raised
            errors.append(f'{f.name}: {exc}')
    return {'files': len(files), 'unfinished': unfinished, 'errors': errors, 'logged': counts}


def run_soak(
    lines: int = 12,
    rate: float = 50.0,
    duration: float = 1800.0,
    rotate_duration: float = 180.0,
    sample: float = 5.0,
    warmup: float = 20.0,
    json_out: bool = False,
    keep_logs: bool = False,
) -> int:
    """Run the soak; print the figures (the log folder removed unless ``keep_logs``); 0 when
    RSS stayed flat (end - start < 20 MB), nothing was lost and every file is finished, else
    1."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import Float64

    env = child_env(121)
    os.environ.update({k: env[k] for k in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_DOMAIN_ID')})
    names = [f'l{k:02d}' for k in range(lines)]
    tmp = Path(tempfile.mkdtemp(prefix='catenary_soak_'))
    _params(tmp / 'params.yaml', names, rotate_duration)
    log_dir = tmp / 'log'
    monitor = subprocess.Popen(
        [
            sys.executable, '-m', 'catenary_monitor.ros.node', '--ros-args',
            '--params-file', str(tmp / 'params.yaml'), '-p', f'log_dir:={log_dir}',
        ],
        env=env,
        stdout=open(tmp / 'monitor.out', 'w'),
        stderr=subprocess.STDOUT,
    )
    rclpy.init()
    node = rclpy.create_node('soak_driver')
    topics = [f'/soak/{n}/tension' for n in names]
    pubs = [node.create_publisher(Float64, t, 100) for t in topics]
    depth_pub = node.create_publisher(Float64, '/soak/depth', 100)
    intake: dict[str, Any] = {}

    def on_diag(msg: Any) -> None:
        for st in msg.status:
            if st.name == 'catenary_monitor: intake':
                intake.update({kv.key: kv.value for kv in st.values}, message=st.message)

    node.create_subscription(DiagnosticArray, '/diagnostics', on_diag, 50)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    sent = dict.fromkeys([*topics, '/soak/depth'], 0)
    rss: list[tuple[float, int]] = []
    try:
        deadline = time.monotonic() + 60.0
        while any(p.get_subscription_count() == 0 for p in [*pubs, depth_pub]):
            if time.monotonic() > deadline or monitor.poll() is not None:
                print('bench-soak: the node did not come up', file=sys.stderr)
                return 1
            time.sleep(0.1)
        time.sleep(3.0)  # the node's readers match the publishers too (else the first is lost)
        t0 = time.monotonic()
        k = d = 0
        next_sample = t0
        while (now := time.monotonic() - t0) < duration:
            while k < int(now * rate):
                value = Float64(data=900e3 + 1e3 * (k % 50))
                for t, p in zip(topics, pubs):
                    p.publish(value)
                    sent[t] += 1
                k += 1
            while d < int(now):
                depth_pub.publish(Float64(data=20.85))
                sent['/soak/depth'] += 1
                d += 1
            if time.monotonic() >= next_sample:
                rss.append((now, _rss_bytes(monitor.pid)))
                next_sample += sample
            time.sleep(0.002)
        time.sleep(2.0)  # the last samples and diagnostics
    finally:
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
    files = check_files(log_dir, list(sent))
    after = [r for t, r in rss if t >= warmup] or [r for _, r in rss]
    mb = 1024 * 1024
    result = {
        'lines': lines,
        'rate_hz': rate,
        'duration_s': duration,
        'rotate_duration_s': rotate_duration,
        'rss_start_mb': after[0] / mb,
        'rss_end_mb': after[-1] / mb,
        'rss_max_mb': max(after) / mb,
        'rss_samples': len(rss),
        'sent': sum(sent.values()),
        'logged': sum(files['logged'].values()),
        'lost': sum(max(sent[t] - files['logged'][t], 0) for t in sent),
        'files': files['files'],
        'unfinished': files['unfinished'],
        'reader_errors': files['errors'],
        'intake_messages_dropped': intake.get('messages_dropped'),
        'exit_code': monitor.returncode,
        'log_dir': str(log_dir),
    }
    ok = (
        result['rss_end_mb'] - result['rss_start_mb'] < 20.0
        and result['lost'] == 0
        and not files['unfinished']
        and not files['errors']
        and monitor.returncode == 0
    )
    result['ok'] = ok
    if not keep_logs:
        shutil.rmtree(tmp, ignore_errors=True)
        result['log_dir'] = None
    if json_out:
        print(json.dumps(result))
    else:
        print(
            f'soak: {lines} lines x {rate:g} Hz for {duration:g} s, rotation every '
            f'{rotate_duration:g} s, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}'
        )
        print(
            f'RSS after {warmup:g} s warm-up: start {result["rss_start_mb"]:.1f} MB, end '
            f'{result["rss_end_mb"]:.1f} MB, max {result["rss_max_mb"]:.1f} MB '
            f'({len(rss)} samples)'
        )
        print(
            f'messages: {result["sent"]} published, {result["logged"]} logged, '
            f'{result["lost"]} lost; intake messages_dropped {result["intake_messages_dropped"]}'
        )
        print(
            f'files: {files["files"]}, unfinished {len(files["unfinished"])}, reader errors '
            f'{len(files["errors"])} (mcap reader, CRCs validated); node exit '
            f'{monitor.returncode}; {"OK" if ok else "FAILED"}'
        )
    return 0 if ok else 1


def register(sub: Any) -> None:
    """Add ``bench-soak`` to the ``catenary-monitor`` parser."""
    p = sub.add_parser(
        'bench-soak',
        help='long run of the node with log rotation: RSS, losses, finished files',
        description='Run the node with every line published at --rate and rotation every '
        '--rotate-duration s; sample its RSS; check nothing was lost and every MCAP file is '
        'finished (the mcap reader, CRCs validated).',
    )
    p.add_argument('--lines', type=int, default=12, help='number of lines (default: 12)')
    p.add_argument('--rate', type=float, default=50.0, help='rate per line [Hz] (default: 50)')
    p.add_argument('--duration', type=float, default=1800.0, help='run time [s] (default: 1800)')
    p.add_argument(
        '--rotate-duration', type=float, default=180.0, help='log rotation [s] (default: 180)'
    )
    p.add_argument('--sample', type=float, default=5.0, help='RSS sampling period [s]')
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.add_argument('--keep-logs', action='store_true', help='keep the node\'s log folder')
    p.set_defaults(
        func=lambda a: run_soak(
            a.lines,
            a.rate,
            a.duration,
            a.rotate_duration,
            a.sample,
            json_out=a.json,
            keep_logs=a.keep_logs,
        )
    )
