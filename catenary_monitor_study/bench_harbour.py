"""``catenary-monitor bench-harbour``: what the harbour process costs per dock.

First a real monitor (config/floating_dock.yaml, 12 lines) runs the demo's storm in the first
domain for ``--capture`` s and this process keeps the largest ``/diagnostics`` array it published
(raw CDR: every line's status in alarm, the fullest array a dock sends). Then, for each dock
count of ``--docks`` (default 1 and 20; the first is the baseline of the same run), the harbour
runs as its own process (``catenary-monitor harbour --dock dNN=DOMAIN ...``) while this process
publishes that array in every dock's domain at ``--rate`` (the monitor's default 1 Hz) and reads
the page's event stream (``/api/stream``, as an open harbour page does). Over ``--duration`` s,
once every dock is alive: the harbour's CPU (utime + stime from /proc, % of one core), its RSS
(VmRSS at the end, VmHWM), the ``/diagnostics`` bytes it received (CDR payload, its own count:
DDS headers and discovery come on top) and the stream's frames. Per dock: the difference to the
baseline over the added docks.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path
from typing import Any, Optional

__all__ = ['run_bench', 'register', 'capture_array']

_TICK = os.sysconf('SC_CLK_TCK')


def _env(domain: int) -> dict[str, str]:
    env = dict(os.environ)
    env['ROS_DOMAIN_ID'] = str(domain)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env['PYTHONUNBUFFERED'] = '1'
    return env


def _context(domain: int) -> Any:
    import rclpy
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context, domain_id=domain)
    return context


def capture_array(domain: int, seconds: float, tmp: str) -> bytes:
    """The largest ``/diagnostics`` array (CDR) a real monitor on the demo's dock published
    during ``seconds`` of the demo's storm, in ``domain``."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor

    from catenary_monitor.sim.scenario import default_config_path

    context = _context(domain)
    node = rclpy.create_node('bench_harbour_capture', context=context)
    largest = [b'']

    def keep(data: bytes) -> None:
        if len(data) > len(largest[0]):
            largest[0] = data

    node.create_subscription(DiagnosticArray, '/diagnostics', keep, 10, raw=True)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    monitor = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.ros.node', '--ros-args', '--params-file']
        + [str(default_config_path()), '-p', f'log_dir:={tmp}/log'],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=_env(domain),
    )
    sim = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.ros.simulator', '--duration', str(seconds + 30)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=_env(domain),
    )
    try:
        end = time.monotonic() + seconds + 30.0  # the processes' start-up besides
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.2)
    finally:
        for proc in (sim, monitor):
            proc.send_signal(signal.SIGINT)
        for proc in (sim, monitor):
            try:
                proc.wait(15)
            except subprocess.TimeoutExpired:
                proc.kill()
        executor.shutdown(1.0)
        node.destroy_node()
        context.try_shutdown()
    if not largest[0]:
        raise RuntimeError('the monitor published no /diagnostics during the capture')
    return largest[0]


class _Publishers:
    """The captured array published in every dock's domain at ``rate`` Hz, from one thread."""

    def __init__(self, domains: list[int], array: bytes, rate: float) -> None:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray

        self.contexts = [_context(d) for d in domains]
        self.nodes = [
            rclpy.create_node(f'bench_harbour_dock_{k}', context=c, enable_rosout=False)
            for k, c in enumerate(self.contexts)
        ]
        self.pubs = [n.create_publisher(DiagnosticArray, '/diagnostics', 10) for n in self.nodes]
        self.array, self.period = array, 1.0 / rate
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        tick = time.monotonic()
        while not self.stop.is_set():
            for pub in self.pubs:
                pub.publish(self.array)
            tick += self.period
            self.stop.wait(max(tick - time.monotonic(), 0.0))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)
        for node, context in zip(self.nodes, self.contexts):
            node.destroy_node()
            context.try_shutdown()


class _StreamReader:
    """Reads the harbour's ``/api/stream`` as its page does: frames and bytes."""

    def __init__(self, url: str) -> None:
        self.frames = self.bytes = 0
        self.response = urllib.request.urlopen(url + 'api/stream', timeout=30)
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            for line in self.response:
                self.bytes += len(line)
                self.frames += line.startswith(b'data: ')
        except (OSError, ValueError, AttributeError):
            pass  # closed by close() (http.client drops its file under the reader)

    def close(self) -> None:
        self.response.close()


def _proc_cpu(pid: int) -> float:
    """CPU seconds (user + system) of process ``pid`` and its threads."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / _TICK


def _proc_mem(pid: int) -> dict[str, float]:
    """VmRSS and VmHWM of ``pid`` (MiB)."""
    text = Path(f'/proc/{pid}/status').read_text()
    out = {}
    for key in ('VmRSS', 'VmHWM', 'Threads'):
        found = re.search(rf'^{key}:\s+(\d+)', text, re.M)
        out[key] = int(found.group(1)) / (1024.0 if key != 'Threads' else 1.0) if found else 0.0
    return out


def _get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=30) as res:
        return json.loads(res.read())


def measure(
    n: int, first_domain: int, array: bytes, rate: float, duration: float, tmp: str
) -> dict[str, Any]:
    """The harbour over ``n`` docks (domains ``first_domain``...): its cost over ``duration``
    s once every dock is alive."""
    domains = [first_domain + k for k in range(n)]
    docks = [f'--dock=d{k + 1:02d}={d}' for k, d in enumerate(domains)]
    out = Path(tmp) / f'harbour_{n}.out'
    harbour = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor.cli.main', 'harbour', *docks, '--port', '0'],
        stdout=open(out, 'w'),
        stderr=subprocess.STDOUT,
        env=_env(first_domain),
    )
    pubs: Optional[_Publishers] = None
    reader: Optional[_StreamReader] = None
    try:
        url = _wait('the harbour URL', lambda: _url(out, harbour), 120.0)
        pubs = _Publishers(domains, array, rate)
        _wait(
            f'{n} docks alive',
            lambda: all(d['monitor_alive'] for d in _get(url + 'api/docks')),
            120.0,
        )
        reader = _StreamReader(url)
        time.sleep(5.0)  # warm-up: every dock's arrays flowing, the stream open
        rx0 = sum(d['received']['bytes'] for d in _get(url + 'api/docks'))
        cpu0, t0, frames0 = _proc_cpu(harbour.pid), time.monotonic(), reader.frames
        time.sleep(duration)
        cpu1, t1, frames1 = _proc_cpu(harbour.pid), time.monotonic(), reader.frames
        views = _get(url + 'api/docks')
        rx1 = sum(d['received']['bytes'] for d in views)
        mem = _proc_mem(harbour.pid)
        alive = sum(d['monitor_alive'] for d in views)
    finally:
        if reader is not None:
            reader.close()
        harbour.send_signal(signal.SIGINT)
        try:
            harbour.wait(30)
        except subprocess.TimeoutExpired:
            harbour.kill()
        if pubs is not None:
            pubs.close()
    span = t1 - t0
    return {
        'docks': n,
        'alive_at_end': alive,
        'cpu_percent': round(100.0 * (cpu1 - cpu0) / span, 2),
        'rss_mib': round(mem['VmRSS'], 1),
        'hwm_mib': round(mem['VmHWM'], 1),
        'threads': int(mem['Threads']),
        'rx_kib_per_s': round((rx1 - rx0) / span / 1024.0, 2),
        'stream_frames_per_s': round((frames1 - frames0) / span, 2),
    }


def _url(out: Path, proc: subprocess.Popen) -> Optional[str]:
    if proc.poll() is not None:
        raise RuntimeError(f'the harbour exited: {out.read_text()[-500:]}')
    found = re.search(r'harbour: (http://\S+)', out.read_text())
    return found.group(1) if found else None


def _wait(what: str, check: Any, timeout: float) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(0.2)
    raise RuntimeError(f'timed out after {timeout:.0f} s waiting for {what}')


def run_bench(
    docks: tuple[int, ...] = (1, 20),
    rate: float = 1.0,
    duration: float = 30.0,
    capture: float = 20.0,
    first_domain: Optional[int] = None,
    json_out: bool = False,
) -> int:
    """Run the benchmark; print a table (or JSON); 0 on success, 2 on a bad argument."""
    first = first_domain if first_domain is not None else int(os.environ.get('ROS_DOMAIN_ID', 80))
    if not docks or min(docks) < 1 or first < 0 or first + max(docks) - 1 > 232:
        print('bench-harbour: the docks\' domains must lie within 0..232', file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix='bench_harbour_') as tmp:
        array = capture_array(first, capture, tmp)
        runs = [measure(n, first, array, rate, duration, tmp) for n in sorted(set(docks))]
    base = runs[0]
    for run in runs[1:]:
        added = run['docks'] - base['docks']
        run['per_dock'] = {
            'cpu_percent': round((run['cpu_percent'] - base['cpu_percent']) / added, 3),
            'rss_mib': round((run['rss_mib'] - base['rss_mib']) / added, 2),
            'rx_kib_per_s': round((run['rx_kib_per_s'] - base['rx_kib_per_s']) / added, 3),
        }
    result = {'array_bytes': len(array), 'rate_hz': rate, 'duration_s': duration, 'runs': runs}
    if json_out:
        print(json.dumps(result))
        return 0
    print(
        f'bench-harbour: a real monitor\'s /diagnostics array of {len(array)} bytes (12 lines, '
        f'the storm) at {rate:g} Hz per dock; {duration:g} s per run; one page stream open'
    )
    print('docks  CPU %core  RSS MiB  HWM MiB  threads  rx KiB/s  frames/s  per dock')
    for run in runs:
        per = run.get('per_dock')
        extra = (
            f'+{per["cpu_percent"]:.3f} %core, +{per["rss_mib"]:.2f} MiB, '
            f'+{per["rx_kib_per_s"]:.2f} KiB/s'
            if per
            else 'baseline'
        )
        print(
            f'{run["docks"]:5d}  {run["cpu_percent"]:9.2f}  {run["rss_mib"]:7.1f}  '
            f'{run["hwm_mib"]:7.1f}  {run["threads"]:7d}  {run["rx_kib_per_s"]:8.2f}  '
            f'{run["stream_frames_per_s"]:8.2f}  {extra}'
        )
    return 0


def register(sub: Any) -> None:
    """Add ``bench-harbour``."""
    p = sub.add_parser(
        'bench-harbour',
        help='what the harbour process costs per dock (CPU, RSS, bytes received)',
        description='A real monitor\'s largest /diagnostics array of the storm, published in '
        'N domains; the harbour over them as a process: its CPU, RSS and bytes received, '
        'against one dock in the same run.',
    )
    p.add_argument(
        '--docks',
        type=int,
        nargs='+',
        default=[1, 20],
        help='dock counts to run (the smallest is the baseline; default 1 20)',
    )
    p.add_argument('--rate', type=float, default=1.0, help='arrays per dock per s (default 1)')
    p.add_argument('--duration', type=float, default=30.0, help='measuring time per run [s]')
    p.add_argument('--capture', type=float, default=20.0, help='storm captured [s] (default 20)')
    p.add_argument(
        '--first-domain',
        type=int,
        default=None,
        help='the first dock\'s ROS domain (default ROS_DOMAIN_ID, else 80); the others follow',
    )
    p.add_argument('--json', action='store_true', help='print one JSON object')
    p.set_defaults(
        func=lambda args: run_bench(
            tuple(args.docks),
            args.rate,
            args.duration,
            args.capture,
            args.first_domain,
            args.json,
        )
    )


if __name__ == '__main__':  # pragma: no cover
    sys.exit(run_bench())
