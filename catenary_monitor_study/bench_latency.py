"""``catenary-monitor bench-latency``: what the monitor adds to a tension message's trip.

Starts two processes: a bare rclpy echo node (Float64 in, the same Float64 out, per line) and
the monitor (``python -m catenary_monitor.ros.node`` on the paper's dock,
config/floating_dock.yaml: 12 lines with their chain lengths, so every sample runs the whole
decision path; MCAP logging on, in a temporary directory). The driver (this process) publishes
each line's hook tension at ``rate`` Hz, the lines spread evenly over the period, with
sensor-data QoS, and takes the time from publishing a tension to receiving the result that
carries it: the echo's Float64, or the monitor's ``~/NAME/outputs`` array (whose first element
is the measured tension). The same driver, the same QoS and the same load measure both, one
after the other, in one run; the monitor's added latency is the difference. CPU use is the
process's user + system time over the wall time of its phase, read from /proc. Afterwards the
monitor's log is read: every tension sent in the measured phase must be in it (``logged``), and
the node's own intake records say how many it stepped and how many it coalesced (logged, not
stepped: it was behind).

``python -m catenary_monitor_study.bench_latency echo N`` runs the echo node alone.
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
from typing import Any, Callable, Optional

import numpy as np

from catenary_monitor.cli.demo import child_env

__all__ = ['run_bench', 'echo_main', 'dock_params']


def echo_main(lines: int) -> int:
    """The baseline: a bare rclpy node that republishes each line's Float64 unchanged, on the
    executor the monitor runs."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.qos import QoSProfile, qos_profile_sensor_data
    from rclpy.signals import SignalHandlerOptions
    from std_msgs.msg import Float64

    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('bench_echo')
    for k in range(lines):
        pub = node.create_publisher(Float64, f'/bench_echo/l{k:02d}/out', QoSProfile(depth=10))
        node.create_subscription(
            Float64,
            f'/bench_echo/l{k:02d}/in',
            _republish(pub),
            qos_profile_sensor_data,
        )
    executor = _executor()
    executor.add_node(node)
    try:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.2)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def _executor() -> Any:
    """The executor the monitor runs (ros.node): rclpy's EventsExecutor where available and
    not ``CATENARY_MONITOR_EXECUTOR=single``, else the SingleThreadedExecutor."""
    from rclpy.executors import SingleThreadedExecutor

    if os.environ.get('CATENARY_MONITOR_EXECUTOR', 'events') != 'single':
        try:
            from rclpy.experimental import EventsExecutor

            return EventsExecutor()
        except ImportError:
            pass
    return SingleThreadedExecutor()


def _republish(pub: Any) -> Callable[[Any], None]:
    """Subscription callback publishing every message it gets on ``pub``."""

    def echo(msg: Any) -> None:
        pub.publish(msg)

    return echo


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time of ``pid`` and its children (s), from /proc."""
    tick = os.sysconf('SC_CLK_TCK')
    total = 0.0
    for entry in Path('/proc').iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / 'stat').read_text().rsplit(')', 1)[1].split()
        except OSError:
            continue
        if int(entry.name) == pid or int(fields[1]) == pid:
            total += (int(fields[11]) + int(fields[12])) / tick
    return total


class _Driver:
    """Publishes tensions on a schedule and times the results that come back."""

    def __init__(
        self, node: Any, in_topics: list[str], out_topics: list[str], out_type: Any
    ) -> None:
        from rclpy.qos import QoSProfile, qos_profile_sensor_data
        from std_msgs.msg import Float64

        self.Float64 = Float64
        self.pubs = [node.create_publisher(Float64, t, qos_profile_sensor_data) for t in in_topics]
        self.sent: dict[float, int] = {}
        self.latencies: list[float] = []
        self.lock = threading.Lock()
        for t in out_topics:
            node.create_subscription(out_type, t, self._on_result, QoSProfile(depth=100))

    def _on_result(self, msg: Any) -> None:
        now = time.perf_counter_ns()
        value = msg.data if isinstance(msg.data, float) else msg.data[0]
        with self.lock:
            t0 = self.sent.pop(value, None)
            if t0 is not None:
                self.latencies.append((now - t0) * 1e-9)

    def matched(self) -> bool:
        return all(p.get_subscription_count() > 0 for p in self.pubs)

    def run(self, rate: float, duration: float, base: float) -> int:
        """Send every line at ``rate`` Hz, spread evenly, for ``duration`` s; return count."""
        n = len(self.pubs)
        step = 1.0 / (rate * n)
        start = time.perf_counter()
        i = 0
        while True:
            due = start + i * step
            if due - start > duration:
                return i
            delay = due - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            value = base + i * 1e-3  # unique, so each result finds its send time
            with self.lock:
                self.sent[value] = time.perf_counter_ns()
            self.pubs[i % n].publish(self.Float64(data=value))
            i += 1


def _stats(lat: list[float], sent: int) -> dict[str, Any]:
    a = np.asarray(lat) * 1e3
    return {
        'sent': sent,
        'received': int(a.size),
        'median_ms': float(np.median(a)) if a.size else float('nan'),
        'p99_ms': float(np.percentile(a, 99)) if a.size else float('nan'),
        'max_ms': float(a.max()) if a.size else float('nan'),
    }


def run_bench(
    lines: int = 12,
    rate: float = 20.0,
    duration: float = 20.0,
    json_out: bool = False,
    warmup: float = 2.0,
    ea: Optional[float] = None,
    params_file: Optional[str] = None,
) -> int:
    """Measure echo and monitor one after the other; print the comparison.

    ``ea`` [N]: axial stiffness on every line (the node's elastic model); None: inextensible.
    ``params_file``: the monitor's lines (default: the paper's dock).
    """
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import Float64, Float64MultiArray

    env = child_env(101)
    os.environ.update({k: env[k] for k in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_DOMAIN_ID')})
    tmp = Path(tempfile.mkdtemp(prefix='catenary_bench_'))
    params = tmp / 'params.yaml'
    config = dock_params(params, lines, ea, params_file)
    names = [line.name for line in config.lines]
    echo = subprocess.Popen(
        [sys.executable, '-m', 'catenary_monitor_study.bench_latency', 'echo', str(lines)], env=env
    )
    monitor = subprocess.Popen(
        [
            sys.executable,
            '-m',
            'catenary_monitor.ros.node',
            '--ros-args',
            '--params-file',
            str(params),
            '-p',
            f'log_dir:={tmp / "log"}',
        ],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    measured: list[float] = []
    rclpy.init()
    node = rclpy.create_node('bench_driver')
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    results: dict[str, Any] = {
        'lines': lines,
        'rate_hz': rate,
        'duration_s': duration,
        'messages_per_s': lines * rate,
        'ea': ea,
        'model': 'inextensible catenary' if ea is None else 'elastic catenary (rule)',
        'params': params_file or 'config/floating_dock.yaml',
    }
    try:
        echo_d = _Driver(
            node,
            [f'/bench_echo/l{k:02d}/in' for k in range(len(names))],
            [f'/bench_echo/l{k:02d}/out' for k in range(len(names))],
            Float64,
        )
        mon_d = _Driver(
            node,
            [line.tension_topic for line in config.lines],
            [f'/catenary_monitor/{n}/outputs' for n in names],
            Float64MultiArray,
        )
        depth_pub = node.create_publisher(Float64, config.depth_topic, 10)
        node.create_timer(1.0, lambda: depth_pub.publish(Float64(data=20.85)))
        spinner.start()
        deadline = time.monotonic() + 60.0
        while not (echo_d.matched() and mon_d.matched()):
            if (
                time.monotonic() > deadline
                or echo.poll() is not None
                or monitor.poll() is not None
            ):
                print('bench-latency: the nodes did not come up', file=sys.stderr)
                return 1
            time.sleep(0.1)
        time.sleep(1.0)  # discovery of the result topics (return path)
        for label, driver, proc, base in (
            ('echo', echo_d, echo, 4.0e5),
            ('monitor', mon_d, monitor, 5.0e5),
        ):
            driver.run(rate, warmup, base - 5e4)  # warm-up, not counted
            time.sleep(0.2)
            with driver.lock:
                driver.latencies.clear()
                driver.sent.clear()
            cpu0, wall0 = _cpu_seconds(proc.pid), time.monotonic()
            sent = driver.run(rate, duration, base)
            cpu = (_cpu_seconds(proc.pid) - cpu0) / (time.monotonic() - wall0)
            if label == 'monitor':
                measured = [base, base + (sent - 1) * 1e-3]
            time.sleep(0.5)  # the last results
            with driver.lock:
                results[label] = {**_stats(driver.latencies, sent), 'cpu_percent': 100 * cpu}
    finally:
        for proc in (echo, monitor):
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for proc in (echo, monitor):
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
        executor.shutdown(timeout_sec=1.0)
        if spinner.is_alive():
            spinner.join(5.0)  # a daemon thread left inside rclpy aborts the interpreter at exit
        node.destroy_node()
        rclpy.try_shutdown()
    e, m = results['echo'], results['monitor']
    results['added_median_ms'] = m['median_ms'] - e['median_ms']
    results['added_p99_ms'] = m['p99_ms'] - e['p99_ms']
    m.update(_logged(tmp / 'log', config, measured))
    shutil.rmtree(tmp, ignore_errors=True)
    results['target_met'] = bool(
        results['added_median_ms'] <= 1.0
        and m['cpu_percent'] <= 50.0
        and m['logged'] == m['sent']
        and m['coalesced'] == 0
    )
    if json_out:
        print(json.dumps(results))
        return 0
    print(
        f'tension -> result across processes, {lines} lines x {rate:g} Hz '
        f'({lines * rate:g} msg/s, evenly spread), {duration:g} s per node, '
        f'{os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}, '
        + ('inextensible lines' if ea is None else f'elastic lines, EA = {ea:g} N')
    )
    print(
        f'{"node":8s} {"sent":>6s} {"recv":>6s} {"median ms":>10s} {"p99 ms":>8s} '
        f'{"max ms":>8s} {"CPU % of 1 core":>16s}'
    )
    for label in ('echo', 'monitor'):
        r = results[label]
        print(
            f'{label:8s} {r["sent"]:6d} {r["received"]:6d} {r["median_ms"]:10.3f} '
            f'{r["p99_ms"]:8.3f} {r["max_ms"]:8.2f} {r["cpu_percent"]:16.1f}'
        )
    print(
        f'monitor log: {m["logged"]} of the {m["sent"]} tensions sent logged; the node stepped '
        f'{m["stepped"]} of them and coalesced {m["coalesced"]}'
    )
    print(
        f'added by the monitor: median {results["added_median_ms"]:+.3f} ms, p99 '
        f'{results["added_p99_ms"]:+.3f} ms; target (<= 1 ms median, <= 50 % of a core, every '
        f'sample logged and stepped) {"met" if results["target_met"] else "NOT met"}'
    )
    return 0


def dock_params(
    path: Path, lines: int = 12, ea: Optional[float] = None, params_file: Optional[str] = None
) -> Any:
    """The paper's dock (or ``params_file``), its first ``lines`` lines, with the bench's
    topics (and ``ea`` on every line), written to ``path``; returns the configuration."""
    from catenary_monitor.core.config.parameters import (
        config_from_params,
        config_to_params,
        params_file_text,
    )
    from catenary_monitor_study.bench_flood import flood_params

    config = flood_params(path, params_file)
    if lines >= len(config.lines) and ea is None:
        return config
    keep = [line.name for line in config.lines[:lines]]
    params = {
        k: v
        for k, v in config_to_params(config).items()
        if '.' not in k or k.split('.', 1)[0] in keep
    }
    params['lines'] = keep
    if ea is not None:
        params.update({f'{name}.ea': float(ea) for name in keep})
    config = config_from_params(params)
    path.write_text(params_file_text(config_to_params(config)))
    return config


def _logged(log_dir: Path, config: Any, measured: list[float]) -> dict[str, int]:
    """Of the tensions sent in the measured phase (values in ``measured``): how many are in
    the monitor's log, how many it stepped (an output carries them) and coalesced (logged, not
    stepped)."""
    from catenary_monitor.io.mcap_read import read_float64_topics
    from catenary_monitor_study.bench_flood import logged_outputs

    files = sorted(log_dir.glob('*.mcap'))
    topics = [line.tension_topic for line in config.lines]
    columns, _ = read_float64_topics(files, topics)
    lo, hi = (measured[0] - 5e-4, measured[-1] + 5e-4) if measured else (np.inf, -np.inf)
    logged = sum(int(((v >= lo) & (v <= hi)).sum()) for _, v in columns.values())
    stepped = 0
    for line in config.lines:
        _, out = logged_outputs(files, f'/catenary_monitor/{line.name}/outputs')
        if len(out):
            mine = out[:, 0]
            stepped += len(np.unique(mine[(mine >= lo) & (mine <= hi)]))
    return {'logged': logged, 'stepped': stepped, 'coalesced': logged - stepped}


def main(argv: Optional[list[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ['echo']:
        return echo_main(int(argv[1]) if len(argv) > 1 else 12)
    return run_bench()


if __name__ == '__main__':
    sys.exit(main())
