"""The harbour's data: one rclpy context per dock, each in the dock's own ROS domain.

Each dock's monitor keeps its domain and runs unchanged; the harbour joins every domain from
one process (``rclpy.init(context=..., domain_id=N)``: one DDS participant per domain) with one
node that subscribes to ``/diagnostics`` only (reliable, as the monitor publishes it; raw CDR,
so the bytes received are counted), no parameter services and no ``/rosout``, spun by its own
executor in its own thread. With a token file it also publishes acknowledgements on the
dock's ``/catenary_monitor/acknowledge``; without one it publishes nothing at all. The node is
named ``catenary_console_harbour_PID``: a monitor with ``acknowledge_from_ros: false`` takes
acknowledgements from console nodes only.

Reception times are the harbour's wall clock; :mod:`.harbour_model` builds the views.
"""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from typing import Any, Callable, Iterator, Optional, Sequence

from catenary_monitor.console.frames import COMPONENT_ALARMS, AckError, statuses_by_name
from catenary_monitor.console.harbour_model import (
    DockSpec,
    DockState,
    dock_view,
    harbour_alarms,
    line_names,
    mixed,
    worst_level,
)
from catenary_monitor.console.resend import AckResends, request_id
from catenary_monitor.core.alarms.acknowledge import ACKNOWLEDGE_TOPIC, ALL_LINES, SENSORS
from catenary_monitor.core.config.parameters import COMPONENTS
from catenary_monitor.core.monitor.events import NODE_NAME

__all__ = ['HarbourSource', 'NODE_PREFIX']

#: The harbour's node name in every domain (then its process id).
NODE_PREFIX = 'catenary_console_harbour'
#: One rclpy.init at a time (the docks' threads join their domains together).
_INIT_LOCK = threading.Lock()
#: Seconds between two looks at who publishes /diagnostics in a dock's domain.
PUBLISHERS_CHECK = 2.0


@contextlib.contextmanager
def _discovery_server(servers: Optional[str], apply: bool) -> Iterator[None]:
    """``ROS_DISCOVERY_SERVER`` set to the dock's ``servers`` while its participant is made
    (a dock without: the process's own, if any), when ``apply``; restored after."""
    if not apply or not servers:
        yield
        return
    name = 'ROS_DISCOVERY_SERVER'
    before = os.environ.get(name)
    os.environ[name] = servers
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = before


class _Dock:
    """One dock's ROS side: its context, node, executor and thread."""

    def __init__(self, spec: DockSpec) -> None:
        self.spec = spec
        self.context: Any = None
        self.node: Any = None
        self.ack_pub: Any = None
        self.acks = AckResends()  # its acknowledgements resent until applied
        self.thread: Optional[threading.Thread] = None
        self.ready = threading.Event()
        self.failure: Optional[str] = None


class HarbourSource:
    """The newest state of every dock, for the harbour's server (the console's ``Source``
    protocol where it applies: ``mode``, ``frame``, ``wait``, ``config_json``).

    ``acknowledge``: publish operators' acknowledgements (a token file was given);
    ``kpis``: a callable giving each dock's daily KPIs (:mod:`.harbour_fleet`), or None.
    """

    mode = 'live'

    def __init__(
        self,
        docks: Sequence[DockSpec],
        acknowledge: bool = False,
        kpis: Optional[Callable[[], dict[str, Any]]] = None,
        ros_args: Optional[list[str]] = None,
    ) -> None:
        self.specs = list(docks)
        self.acknowledge_enabled = acknowledge
        self.kpis = kpis
        self.ros_args = ros_args or []
        self.host = socket.gethostname()
        self.started = time.time()
        self.cond = threading.Condition()
        self.version = 0
        self.states = {d.name: DockState(self.started, d.period) for d in self.specs}
        self.errors: dict[str, str] = {}
        self.crowded: dict[str, list[str]] = {}
        self._docks = [_Dock(d) for d in self.specs]
        # With a dock's own discovery server, each participant is made alone, under the
        # environment naming its servers (Fast DDS reads it as the participant is created).
        self._one_at_a_time = any(d.discovery_server for d in self.specs)
        self._stop = threading.Event()

    # ------------------------------------------------------------------ ROS side
    def start(self) -> None:
        """One context, node and spinning thread per dock (its own domain); ``started`` is
        now, once rclpy is loaded (the docks' ages and silences count from here)."""
        from catenary_monitor.ros.dds_profile import use_announce_profile

        if not self._one_at_a_time:  # (a discovery server's clients do not announce so)
            use_announce_profile()  # a monitor restarting meets the harbour within 1 s
        import rclpy  # noqa: F401 - loaded before the clock starts
        import rclpy.executors  # noqa: F401
        from diagnostic_msgs.msg import DiagnosticArray  # noqa: F401

        with self.cond:
            self.started = time.time()
            for state in self.states.values():
                state.started = self.started
        # Every dock joins its domain in its own thread, at once: a harbour of many docks
        # hears the last as soon as the first.
        for dock in self._docks:
            dock.thread = threading.Thread(
                target=self._join_and_spin, args=(dock,), name=f'ros-{dock.spec.name}',
                daemon=True,
            )  # fmt: skip
            dock.thread.start()
        for dock in self._docks:
            dock.ready.wait(60.0)
        failed = [d for d in self._docks if d.failure is not None]
        if failed and len(failed) == len(self._docks):
            raise RuntimeError(f'dock {failed[0].spec.name}: {failed[0].failure}')

    def _join_and_spin(self, dock: _Dock) -> None:
        try:
            self._start_dock(dock)
        except Exception as exc:  # noqa: BLE001 - on the dock's tile; the others go on
            dock.failure = str(exc)
            with self.cond:
                self.errors[dock.spec.name] = f'cannot join domain {dock.spec.domain_id}: {exc}'
            return
        finally:
            dock.ready.set()
        self._spin(dock)

    def _start_dock(self, dock: _Dock) -> None:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.context import Context
        from rclpy.qos import QoSProfile
        from rclpy.signals import SignalHandlerOptions

        context = Context()
        with _INIT_LOCK:  # rcl's logging set-up is process-wide: one init at a time
            with _discovery_server(dock.spec.discovery_server, self._one_at_a_time):
                rclpy.init(
                    args=['catenary_harbour', *self.ros_args],
                    context=context,
                    domain_id=dock.spec.domain_id,
                    signal_handler_options=SignalHandlerOptions.NO,
                )
                dock.context = context
                if self._one_at_a_time:
                    dock.node = self._create_node(context)
        if dock.node is None:
            dock.node = self._create_node(context)
        dock.node.create_subscription(
            DiagnosticArray,
            '/diagnostics',
            lambda data, name=dock.spec.name: self._on_diag(name, data),
            QoSProfile(depth=10),
            raw=True,
        )
        if self.acknowledge_enabled:
            from std_msgs.msg import String

            dock.ack_pub = dock.node.create_publisher(
                String, ACKNOWLEDGE_TOPIC, QoSProfile(depth=10)
            )

    @staticmethod
    def _create_node(context: Any) -> Any:
        import rclpy

        return rclpy.create_node(
            f'{NODE_PREFIX}_{os.getpid()}',
            context=context,
            start_parameter_services=False,
            enable_rosout=False,
        )

    def _spin(self, dock: _Dock) -> None:
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor(context=dock.context)
        executor.add_node(dock.node)
        check = 0.0
        try:
            while not self._stop.is_set() and dock.context.ok():
                executor.spin_once(timeout_sec=0.5)
                if time.monotonic() >= check:
                    check = time.monotonic() + PUBLISHERS_CHECK
                    self.check_publishers(dock.spec.name, dock.node)
        except Exception as exc:  # noqa: BLE001 - shown on the page, the others go on
            with self.cond:
                self.errors[dock.spec.name] = f'ROS client stopped: {exc}'
        finally:
            executor.shutdown(0.5)

    def check_publishers(self, name: str, node: Any) -> None:
        """Note the monitors publishing ``/diagnostics`` in the dock's domain when there are
        several (two docks in one domain, or a discovery server matching across domains):
        their arrays cannot be told apart, so the dock is shown STALE, naming them. Counted by
        publisher, not by name: every dock's monitor has the same name by default."""
        found = {
            bytes(getattr(info, 'endpoint_gid', b'')) or id(info): (
                f'{info.node_namespace.rstrip("/")}/{info.node_name}'
            )
            for info in node.get_publishers_info_by_topic('/diagnostics')
            if info.node_name == NODE_NAME
        }
        monitors = sorted(found.values())
        with self.cond:
            if len(monitors) > 1:
                self.crowded[name] = monitors
            else:
                self.crowded.pop(name, None)

    def stop(self) -> None:
        """Stop every thread, destroy the nodes and shut each context down."""
        self._stop.set()
        for dock in self._docks:
            if dock.thread is not None:
                dock.thread.join(2.0)
        for dock in self._docks:
            if dock.node is not None:
                dock.node.destroy_node()
            if dock.context is not None:
                dock.context.try_shutdown()

    def _on_diag(self, name: str, data: bytes) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.serialization import deserialize_message

        rx = time.time()
        msg = deserialize_message(data, DiagnosticArray)
        items = [
            (
                s.name,
                s.level[0] if isinstance(s.level, bytes) else int(s.level),
                s.message,
                [(kv.key, kv.value) for kv in s.values],
            )
            for s in msg.status
        ]
        statuses = statuses_by_name(items)
        if not any(n not in COMPONENTS for n in statuses):
            return  # not the monitor's array (another node on /diagnostics)
        with self.cond:
            self.states[name].feed(rx, statuses, len(data))
            self.version += 1
            self.cond.notify_all()
        self._resend_acks(name, statuses)

    def _resend_acks(self, name: str, statuses: dict[str, Any]) -> None:
        """Send again the dock's acknowledgements whose alarms still wait for them (checked
        on each of its arrays: at least one a second)."""
        dock = next((d for d in self._docks if d.spec.name == name), None)
        if dock is None or dock.ack_pub is None:
            return
        from std_msgs.msg import String

        with self.cond:
            again = dock.acks.due(statuses, time.monotonic())
        for text in again:
            dock.ack_pub.publish(String(data=text))

    # ------------------------------------------------------------------ server side
    def wait(self, version: int, timeout: float) -> int:
        """Block until the state is newer than ``version`` or ``timeout`` s passed."""
        with self.cond:
            if self.version == version:
                self.cond.wait(timeout)
            return self.version

    def docks(self, now: Optional[float] = None) -> list[dict[str, Any]]:
        """Every dock's view (``GET /api/docks``), in the order given."""
        now = time.time() if now is None else now
        kpis = self.kpis() if self.kpis is not None else {}
        with self.cond:
            views = [dock_view(s, self.states[s.name], now) for s in self.specs]
            errors = dict(self.errors)
            crowded = dict(self.crowded)
        for view in views:
            if view['name'] in errors:
                view['message'] = errors[view['name']]
            if view['name'] in crowded:
                mixed(view, crowded[view['name']])
            if self.kpis is not None:
                view['kpis'] = kpis.get(view['name'], [])
        return views

    def frame(self, t: Optional[float] = None) -> dict[str, Any]:
        """The page's state: every dock, the harbour-wide alarm list and the counts."""
        now = time.time()
        docks = self.docks(now)
        counts = {lv: 0 for lv in ('OK', 'WARN', 'ERROR', 'STALE')}
        for dock in docks:
            counts[dock['level']] = counts.get(dock['level'], 0) + 1
        return {
            'now': now,
            'level': worst_level([d['level'] for d in docks]),
            'counts': counts,
            'docks': docks,
            'alarms': harbour_alarms(docks),
        }

    def config_json(self) -> dict[str, Any]:
        """The page's static facts: the docks (name, domain, position, console), the host."""
        return {
            'mode': 'harbour',
            'host': self.host,
            'started': self.started,
            'acknowledge': self.acknowledge_enabled,
            'fleet': self.kpis is not None,
            'docks': [
                {
                    'name': s.name,
                    'domain_id': s.domain_id,
                    'position': None if s.lat is None else {'lat': s.lat, 'lon': s.lon},
                    'console_url': s.console_url,
                    'lines': s.line_names,
                }
                for s in self.specs
            ],
        }

    def acknowledge(self, dock: str, line: str, origin: str) -> str:
        """Publish one acknowledgement (``LINE|all|sensors|COMPONENT ORIGIN #ID``, a component
        status such as ``tide``) in the dock's domain;
        its monitor decides. Resent while the alarms it names still wait for it
        (:class:`~catenary_monitor.console.resend.AckResends`)."""
        found = next((d for d in self._docks if d.spec.name == dock), None)
        if found is None:
            raise AckError(f'unknown dock {dock!r}', 404)
        if found.ack_pub is None:
            raise AckError('this harbour does not acknowledge (no --token-file)', 403)
        with self.cond:
            names = line_names(found.spec, self.states[dock].statuses)
        if line not in (ALL_LINES, SENSORS, *COMPONENT_ALARMS) and line not in names:
            raise AckError(f'unknown line {line!r} of dock {dock}', 404)
        if found.ack_pub.get_subscription_count() == 0:
            raise AckError(f'no monitor of dock {dock} is listening on {ACKNOWLEDGE_TOPIC}', 503)
        from std_msgs.msg import String

        text = f'{line} {origin} #{request_id()}'
        with self.cond:
            statuses = self.states[dock].statuses
            alarms = [*names, SENSORS, *COMPONENT_ALARMS] if line == ALL_LINES else [line]
            found.acks.add(text, alarms, statuses, time.monotonic())
        found.ack_pub.publish(String(data=text))
        return text
