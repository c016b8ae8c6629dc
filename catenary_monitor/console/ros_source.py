"""The live console's data: a ROS client of the monitor (rclpy, in its own thread).

It subscribes to ``/diagnostics`` and to every line's ``/catenary_monitor/NAME/outputs`` and
publishes acknowledgements on ``/catenary_monitor/acknowledge`` and shelving requests on
``/catenary_monitor/shelve``; it never talks to the monitor otherwise, so a console that crashes
or hangs leaves the monitoring untouched. A request carries an id (`` #ID``) and is resent with
it until the monitor's answer shows (a flood of requests from another node may push it out of
the monitor's queue); the monitor applies an id once. Without a params
file the lines are those the monitor names on ``/diagnostics`` (their outputs are subscribed to
as they appear).

Times are the console's wall clock (s, epoch) at reception; the monitor's own stamps (alarm
raised, acknowledged) come in its values.
"""

from __future__ import annotations

import os
import socket
import threading
import time
from collections import deque
from typing import Any, Optional

from catenary_monitor.console.frames import (
    COMPONENT_ALARMS,
    AckError,
    History,
    Status,
    Trend,
    build_frame,
    console_config,
    silence_limit,
    statuses_by_name,
    tide_trend,
)
from catenary_monitor.console.resend import ANSWER_WAIT, RESEND_EVERY, AckResends, request_id
from catenary_monitor.core.alarms.acknowledge import ACKNOWLEDGE_TOPIC, ALL_LINES, SENSORS, WHOLE
from catenary_monitor.core.alarms.shelving import SHELVE_TOPIC
from catenary_monitor.core.config.parameters import COMPONENTS, MonitorConfig
from catenary_monitor.core.monitor.events import NODE_NAME
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS

__all__ = ['LiveSource', 'AckError', 'ANSWER_WAIT']


_T = OUTPUT_FIELDS.index('top_tension')
_F = OUTPUT_FIELDS.index('uplift_force')
_M = OUTPUT_FIELDS.index('anchor_margin')


class LiveSource:
    """The newest state of the dock as the monitor publishes it, for the console server."""

    mode = 'live'

    def __init__(self, config: Optional[MonitorConfig], ros_args: Optional[list[str]] = None):
        self.config = config
        self.names: list[str] = [line.name for line in config.lines] if config else []
        self.ros_args = ros_args or []
        self.limit = silence_limit(config.alarm.diagnostic_rate if config else 1.0)
        self.cond = threading.Condition()
        self.version = 0
        self.statuses: dict[str, Status] = {}
        self.snapshot_rx: Optional[float] = None
        self.outputs: dict[str, tuple[float, list[float]]] = {}
        self.sample_t: dict[str, float] = {}
        self.trends: dict[str, Trend] = {}
        self.depth = Trend(('depth_max', 'depth_min'))
        self.history = History()
        self.host = socket.gethostname()
        self._node: Any = None
        self._subscribed: set[str] = set()
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self._answers_seen: deque[tuple[int, str]] = deque(maxlen=256)  # (count, answer)
        self._acks = AckResends()
        self.error: Optional[str] = None
        self.started = time.time()

    # ------------------------------------------------------------------ ROS side
    def start(self) -> None:
        """Start rclpy and spin its node in a daemon thread."""
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import QoSProfile
        from std_msgs.msg import String

        rclpy.init(args=['catenary_console', *self.ros_args])
        node = rclpy.create_node(f'catenary_console_{os.getpid()}')
        self._node = node
        node.create_subscription(
            DiagnosticArray, '/diagnostics', self._on_diag, QoSProfile(depth=50)
        )
        self._ack_pub = node.create_publisher(String, ACKNOWLEDGE_TOPIC, QoSProfile(depth=10))
        self._shelve_pub = node.create_publisher(String, SHELVE_TOPIC, QoSProfile(depth=10))
        self._String = String
        self._ack_timer = node.create_timer(RESEND_EVERY[0], self._resend_acks)
        for name in self.names:
            self._subscribe(name)
        self._thread = threading.Thread(target=self._spin, name='ros', daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor()
        executor.add_node(self._node)
        try:
            while not self._stop.is_set() and rclpy.ok():
                executor.spin_once(timeout_sec=0.2)
        except Exception as exc:  # noqa: BLE001 - shown on the page, the server goes on
            self.error = f'ROS client stopped: {exc}'

    def stop(self) -> None:
        """Stop spinning and shut rclpy down."""
        import rclpy

        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
        if self._node is not None:
            self._node.destroy_node()
        rclpy.try_shutdown()

    def _subscribe(self, name: str) -> None:
        from rclpy.qos import QoSProfile
        from std_msgs.msg import Float64MultiArray

        if name in self._subscribed:
            return
        self._subscribed.add(name)
        self.trends.setdefault(name, Trend(('tension_max', 'uplift_max', 'margin_min')))
        self._node.create_subscription(
            Float64MultiArray,
            f'/{NODE_NAME}/{name}/outputs',
            lambda msg, n=name: self._on_output(n, msg),
            QoSProfile(depth=50),
        )

    def _on_diag(self, msg: Any) -> None:
        rx = time.time()
        items = [
            (st.name, st.level[0], st.message, [(kv.key, kv.value) for kv in st.values])
            for st in msg.status
        ]
        statuses = statuses_by_name(items)
        if not any(name not in COMPONENTS for name in statuses):
            return  # not the monitor's array (another node on /diagnostics)
        new = [n for n in statuses if n not in COMPONENTS and n not in self.names]
        if new and self.config is None:
            self.names.extend(new)
            for name in new:
                self._subscribe(name)
        with self.cond:
            self.statuses = statuses
            self.snapshot_rx = rx
            count, answer = self._answers()
            if not self._answers_seen or self._answers_seen[-1][0] != count:
                self._answers_seen.append((count, answer))
            for name in self.names:
                st = statuses.get(name)
                age = _float(st.values.get('tension_age')) if st else None
                if age is not None:
                    t = rx - age
                    self.sample_t[name] = max(self.sample_t.get(name, t), t)
            tide = statuses.get('tide')
            depth = _float(tide.values.get('depth')) if tide else None
            if depth is not None:
                self.depth.add(rx, {'depth_max': depth, 'depth_min': depth})
            self.history.feed(rx, statuses, self.names)
            self.version += 1
            self.cond.notify_all()

    def _on_output(self, name: str, msg: Any) -> None:
        rx = time.time()
        values = list(msg.data)
        if len(values) != len(OUTPUT_FIELDS):
            return
        with self.cond:
            old = self.outputs.get(name)
            if old is None or old[1][_T] != values[_T]:
                self.sample_t[name] = rx  # a new tension sample (a depth update repeats it)
            self.outputs[name] = (rx, values)
            self.trends[name].add(
                rx, {'tension_max': values[_T], 'uplift_max': values[_F], 'margin_min': values[_M]}
            )
            self.version += 1
            self.cond.notify_all()

    # ------------------------------------------------------------------ server side
    def config_json(self) -> dict[str, Any]:
        with self.cond:
            names = list(self.names)
        return console_config(self.config, names, 'live', host=self.host)

    def wait(self, version: int, timeout: float) -> int:
        """Block until the state is newer than ``version`` or ``timeout`` s passed."""
        with self.cond:
            if self.version == version:
                self.cond.wait(timeout)
            return self.version

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        now = time.time()
        with self.cond:
            trend = tide_trend(self.statuses)
            return build_frame(
                now,
                list(self.names),
                self.snapshot_rx,
                dict(self.statuses),
                dict(self.outputs),
                dict(self.sample_t),
                trend,
                self.history.entries,
                self.limit,
                started=self.started,
                error=self.error,
            )

    def trend(self, line: str, t: Optional[float], span: float) -> dict[str, Any]:
        now = time.time() if t is None else t
        with self.cond:
            trend = self.trends.get(line)
            series = trend.series(now - span, now) if trend else {}
            depth = self.depth.series(now - span, now)
        return {'line': line, 'lo': now - span, 'hi': now, 'series': series, 'depth': depth}

    def acknowledge(self, line: str, origin: str) -> str:
        """Publish one acknowledgement (``LINE|all ORIGIN #ID``; a line, ``sensors`` or a
        component status such as ``tide``); the monitor decides. While the alarms it names
        still wait for it (raised as when it was sent), it is resent
        (:class:`~catenary_monitor.console.resend.AckResends`)."""
        known = line in self.names or line in (ALL_LINES, SENSORS, *COMPONENT_ALARMS)
        if not known:
            raise AckError(f'unknown line {line!r}', 404)
        if self._ack_pub.get_subscription_count() == 0:
            raise AckError(f'no monitor is listening on {ACKNOWLEDGE_TOPIC}', 503)
        text = f'{line} {origin} #{request_id()}'
        names = [*self.names, SENSORS, *COMPONENT_ALARMS] if line == ALL_LINES else [line]
        with self.cond:
            self._acks.add(text, names, self.statuses, time.monotonic())
        self._ack_pub.publish(self._String(data=text))
        return text

    def _resend_acks(self) -> None:
        """Send again the acknowledgements whose alarms still wait for them."""
        with self.cond:
            again = self._acks.due(self.statuses, time.monotonic())
        for text in again:
            self._ack_pub.publish(self._String(data=text))

    def shelve(self, alarm: str, condition: str, seconds: float, origin: str) -> dict[str, Any]:
        """Publish one shelving request (``ALARM[.CONDITION] SECONDS ORIGIN #ID``; 0 s
        unshelves), resent every :data:`RESEND_EVERY` s until the monitor's answer shows on
        ``/diagnostics``, for :data:`ANSWER_WAIT` s at most: ``{"sent": text, "answer": the
        monitor's answer, or None}``; a refusal is an AckError (409) carrying the monitor's
        own words."""
        if alarm not in self.names and alarm != SENSORS:
            raise AckError(f'unknown alarm {alarm!r}', 404)
        if self._shelve_pub.get_subscription_count() == 0:
            raise AckError(f'no monitor is listening on {SHELVE_TOPIC}', 503)
        target = alarm if condition == WHOLE else f'{alarm}.{condition}'
        with self.cond:
            before = self._answers()[0]
        text = f'{target} {seconds:g} {origin} #{request_id()}'
        start = time.monotonic()
        deadline, sends = start + ANSWER_WAIT, 0
        answer: Optional[str] = None
        while answer is None:
            now = time.monotonic()
            if now >= deadline:
                return {'sent': text, 'answer': None}
            self._shelve_pub.publish(self._String(data=text))
            sends += 1
            resend = now + RESEND_EVERY[min(sends, len(RESEND_EVERY)) - 1]
            with self.cond:
                while answer is None:
                    answer = self._answer_to(before, alarm, target, origin)
                    left = min(resend, deadline) - time.monotonic()
                    if answer is not None or left <= 0:
                        break
                    self.cond.wait(left)
        if ': refused: ' in answer:
            raise AckError(answer, 409)
        return {'sent': text, 'answer': answer}

    def _answer_to(self, before: int, alarm: str, target: str, origin: str) -> Optional[str]:
        """The monitor's answer to a shelving request of ``target`` from ``origin``, among
        those it gave after its ``before``-th (None: none yet). Under ``self.cond``."""
        for count, answer in self._answers_seen:
            if count <= before:
                continue
            if answer.startswith(f'{target}: ') or (
                answer.startswith((f'{target} ', f'{alarm} ')) and f' by {origin}' in answer
            ):
                return answer
        return None

    def _answers(self) -> tuple[int, str]:
        """(shelving requests the monitor answered, its newest answer), from ``/diagnostics``."""
        st = self.statuses.get('alarms')
        if st is None:
            return 0, ''
        try:
            count = int(st.values.get('shelve_requests', '0'))
        except ValueError:
            count = 0
        return count, st.values.get('shelve_answer', '')


def _float(text: Optional[str]) -> Optional[float]:
    try:
        value = float(text) if text is not None else None
    except ValueError:
        return None
    return value if value is not None and value == value and abs(value) != float('inf') else None
