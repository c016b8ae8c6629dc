"""Helpers for the node tests: start the monitor as a process, talk to it from a test node.

The test process runs one rclpy node spun in a background thread; assertions wait on what it
received with a bounded deadline (``Client.wait_for``), never on a sleep.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import threading
import time
from collections import defaultdict
from pathlib import Path
from typing import Any, Callable, Optional

import catenary_monitor

PACKAGE_ROOT = str(Path(catenary_monitor.__file__).resolve().parent.parent)
LEVELS = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}


def child_env() -> dict[str, str]:
    """Environment for a child process: this package importable, same DDS domain."""
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(p for p in (PACKAGE_ROOT, env.get('PYTHONPATH')) if p)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env['PYTHONUNBUFFERED'] = '1'
    env['PYTHONFAULTHANDLER'] = '1'  # a crash prints every thread's Python stack to the .out
    env['RCUTILS_LOGGING_BUFFERED_STREAM'] = '0'
    return env


def write_params(
    path: Path,
    lines: dict[str, dict[str, Any]],
    key: str = 'catenary_monitor',
    **global_params: Any,
) -> Path:
    """A ROS 2 params YAML for the monitor (flow style, no yaml dependency needed)."""
    out = [f'{key}:', '  ros__parameters:', f'    lines: [{", ".join(lines)}]']
    for name, value in global_params.items():
        out.append(
            f'    {name}: {value!r}' if not isinstance(value, str) else f'    {name}: "{value}"'
        )
    for line, params in lines.items():
        out.append(f'    {line}:')
        out.extend(f'      {k}: {v!r}' for k, v in params.items())
    path.write_text('\n'.join(out) + '\n')
    return path


def start_monitor(
    params_file: Path,
    log_dir: Path,
    *ros_args: str,
    out_dir: Optional[Path] = None,
    domain_id: Optional[int] = None,
) -> subprocess.Popen:
    """Start ``python -m catenary_monitor.ros.node`` with a params file; stdout/stderr to files
    (``domain_id``: in that ROS domain, else in this process's)."""
    out_dir = out_dir or log_dir.parent
    out = open(out_dir / f'monitor_{os.getpid()}_{time.monotonic_ns()}.out', 'w+')
    cmd = [
        sys.executable,
        '-m',
        'catenary_monitor.ros.node',
        '--ros-args',
        '--params-file',
        str(params_file),
        '-p',
        f'log_dir:={log_dir}',
        *ros_args,
    ]
    env = child_env()
    if domain_id is not None:
        env['ROS_DOMAIN_ID'] = str(domain_id)
    proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, env=env)
    proc.output_file = out  # type: ignore[attr-defined]
    STARTED.append(proc)
    return proc


#: Every monitor started by this test process (checked for callback errors after each test).
STARTED: list = []


def callback_errors() -> list[str]:
    """Lines where a started monitor logged an exception in a callback, then forget them."""
    found = [
        line
        for proc in STARTED
        for line in output_of(proc).splitlines()
        if 'failed (monitoring goes on)' in line
    ]
    STARTED.clear()
    return found


def output_of(proc: subprocess.Popen) -> str:
    """Everything the process printed so far."""
    f = proc.output_file  # type: ignore[attr-defined]
    f.flush()
    return Path(f.name).read_text()


def stop(proc: subprocess.Popen, sig: int = 15, timeout: float = 10.0) -> int:
    """Send ``sig`` and wait (bounded) for the exit status; kill on timeout."""
    if proc.poll() is None:
        proc.send_signal(sig)
    try:
        return proc.wait(timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)
        raise AssertionError(f'process did not exit within {timeout} s of signal {sig}')


def status_dict(status: Any) -> dict[str, Any]:
    """A DiagnosticStatus as a plain dict: level (int), message, values (str -> str)."""
    return {
        'level': status.level[0] if isinstance(status.level, bytes) else int(status.level),
        'name': status.name,
        'message': status.message,
        'hardware_id': status.hardware_id,
        'values': {kv.key: kv.value for kv in status.values},
    }


class Client:
    """A test node in this process: publishes inputs, records diagnostics and outputs."""

    def __init__(self, name: str = 'node_test_client', domain_id: Optional[int] = None) -> None:
        """``domain_id``: join that ROS domain with a context of its own (the process's default
        context and ROS_DOMAIN_ID otherwise)."""
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        self.context: Any = None
        if domain_id is not None:
            self.context = Context()
            rclpy.init(context=self.context, domain_id=domain_id)
        elif not rclpy.ok():
            rclpy.init()
        self.rclpy = rclpy
        self.node = rclpy.create_node(name, context=self.context)
        self.lock = threading.RLock()
        self.diagnostics: list[tuple[float, dict[str, dict[str, Any]]]] = []
        self.outputs: dict[str, list[tuple[float, list[float]]]] = defaultdict(list)
        self._publishers: dict[str, Any] = {}
        self.feeds: dict[str, float] = {}
        self.diag_stamps: list[int] = []
        self.sent: dict[str, list[tuple[float, float]]] = defaultdict(list)
        self.node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diag, 50)
        self.node.create_timer(0.1, self._on_feed)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except Exception:  # noqa: BLE001 - shutting down
            pass

    def _on_diag(self, msg: Any) -> None:
        entry = {s.name: status_dict(s) for s in msg.status}
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        with self.lock:
            self.diagnostics.append((time.monotonic(), entry))
            self.diag_stamps.append(stamp)

    def subscribe_outputs(self, topic: str) -> None:
        """Record every Float64MultiArray on ``topic``."""
        from std_msgs.msg import Float64MultiArray

        def cb(msg: Any) -> None:
            with self.lock:
                self.outputs[topic].append((time.monotonic(), list(msg.data)))

        self.node.create_subscription(Float64MultiArray, topic, cb, 100)

    def publisher(self, topic: str) -> Any:
        """The std_msgs/Float64 publisher for ``topic`` (reliable, as many drivers use)."""
        from std_msgs.msg import Float64

        pub = self._publishers.get(topic)
        if pub is None:
            pub = self._publishers[topic] = self.node.create_publisher(Float64, topic, 10)
        return pub

    def wait_matched(self, topics: list[str], timeout: float) -> None:
        """Wait until every publisher in ``topics`` has a subscriber (the monitor)."""
        pubs = [self.publisher(t) for t in topics]
        deadline = time.monotonic() + timeout
        while any(p.get_subscription_count() == 0 for p in pubs):
            if time.monotonic() > deadline:
                raise AssertionError(f'no subscriber on {topics} after {timeout} s')
            time.sleep(0.05)

    def publish(self, topic: str, value: float) -> None:
        """Publish one std_msgs/Float64 and record it in ``sent``."""
        from std_msgs.msg import Float64

        pub = self.publisher(topic)
        with self.lock:
            pub.publish(Float64(data=float(value)))
            self.sent[topic].append((time.monotonic(), float(value)))

    def feed(self, topic: str, value: Optional[float]) -> None:
        """Publish ``value`` on ``topic`` at 10 Hz from now on (None: stop)."""
        self.publisher(topic)
        with self.lock:
            if value is None:
                self.feeds.pop(topic, None)
            else:
                self.feeds[topic] = float(value)

    def _on_feed(self) -> None:
        with self.lock:
            feeds = list(self.feeds.items())
        for topic, value in feeds:
            self.publish(topic, value)

    def wait_for(self, predicate: Callable[[], Any], timeout: float, what: str = '') -> Any:
        """Poll ``predicate`` (called under the lock) until it returns a truthy value."""
        deadline = time.monotonic() + timeout
        while True:
            with self.lock:
                value = predicate()
            if value:
                return value
            if time.monotonic() > deadline:
                raise AssertionError(
                    f'timed out after {timeout} s waiting for {what or predicate}'
                )
            time.sleep(0.02)

    def latest_status(self, name: str, since: float = -math.inf) -> Optional[dict[str, Any]]:
        """Newest status called ``name`` received after ``since`` (monotonic s), or None."""
        for t, entry in reversed(self.diagnostics):
            if t < since:
                return None
            if name in entry:
                return entry[name]
        return None

    def wait_status(
        self,
        name: str,
        timeout: float,
        level: Optional[int] = None,
        since: float = -math.inf,
        check: Callable[[dict[str, Any]], bool] = lambda s: True,
    ) -> dict[str, Any]:
        """Wait for a status ``name`` with ``level`` received after ``since``."""

        def pred() -> Any:
            s = self.latest_status(name, since)
            return (
                s
                if s is not None and (level is None or s['level'] == level) and check(s)
                else None
            )

        try:
            return self.wait_for(pred, timeout, f'{name} at level {LEVELS.get(level, level)}')
        except AssertionError as err:
            with self.lock:
                last = self.latest_status(name)
            raise AssertionError(f'{err}; last status: {last}') from None

    def levels(self, name: str, since: float = -math.inf) -> list[int]:
        """Levels of ``name`` in every array received after ``since``."""
        with self.lock:
            return [e[name]['level'] for t, e in self.diagnostics if t >= since and name in e]

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self._thread.join(2.0)
        if self.context is not None:
            self.context.try_shutdown()
