"""The live monitor: the rclpy node ``catenary_monitor`` (console script ``monitor``).

Wiring only. Subscriptions, timers, parameters, publishers and the MCAP logger around one
:class:`~catenary_monitor.core.monitor.monitor_core.MonitorCore`: every received sample, every
periodic tick, every logger change and every accepted parameter change becomes one core event, and
the node publishes and logs what the core's
:class:`~catenary_monitor.core.monitor.monitor_core.Step` says. No physics, no threshold comparison
and no level decision live here.

Each event gets a distinct, increasing stamp (the node clock, moved on by 1 ns when two events
would share a reading), used as the MCAP log time of everything the event produced; the events
that are not input messages (ticks, logger changes, parameter changes) are recorded on the
MCAP-only channel ``/catenary_monitor/events``, so replay redoes every step exactly.

Intake: a sample callback takes every sample waiting on its input (the one the executor handed
over, then the subscription's queue until it is empty) and logs each one. While the node keeps
up that is one sample per callback, stepped at once; after a hiccup (the oldest waited at most
:data:`COALESCE_AFTER`) each is stepped in turn. When the node is behind, only the newest is
stepped and the older ones are coalesced: logged, counted, and recorded (a :class:`Coalesced`
record before them) so that replay leaves out exactly those; never a queue worked through late.
So the executor's queue never holds more than about one round of callbacks, and the timers (the
periodic tick, ``/diagnostics``) keep their time whatever the input rate.

A wall-clock (steady) watchdog runs once a second whatever the ROS clock does: with
``use_sim_time`` it reports a ROS clock that stopped (ClockHealth events, each with a
``/diagnostics`` array), and it hands the core the intake counts (Intake events: samples
handled, coalesced, and lost before the node took them, time spent in the sample callbacks);
the first sample not handled brings the counts forward (at once, or at the next periodic tick).

Run it as ``monitor --ros-args --params-file FILE`` (``ros2 run catenary_monitor monitor ...``),
``python -m catenary_monitor.ros.node --ros-args --params-file FILE`` or
``catenary-monitor run --params-file FILE [--log-dir DIR]``.
"""

from __future__ import annotations

import json
import os
import queue
import signal
import struct
import sys
import threading
import time
import traceback
from functools import partial, wraps
from pathlib import Path
from typing import Any, Optional, Sequence

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, qos_profile_sensor_data
from rclpy.serialization import deserialize_message, serialize_message
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import FluidPressure, Range
from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension, String

from catenary_monitor import __version__
from catenary_monitor.core.config.parameters import (
    ConfigError,
    MonitorConfig,
    ParamSpec,
    all_parameters,
    change_message,
    config_from_params,
    config_hash,
    config_to_params,
    expand_parameters,
    load_params_file,
    runtime_change_refusal,
)
from catenary_monitor.core.rules import readings
from catenary_monitor.core.alarms.acknowledge import (
    ACKNOWLEDGE_TOPIC,
    CONSOLE_NODE_PREFIX,
    SENSORS,
    bounded_text,
    console_only_refusal,
    parse_request,
    publisher_identity,
)
from catenary_monitor.core.alarms.components import acknowledgeable
from catenary_monitor.core.alarms.journal import COMPONENTS, AlarmEvent
from catenary_monitor.core.alarms.texts import TEXT_KEYS
from catenary_monitor.core.alarms.requests import RequestLimit, Resends, limit_text, split_id
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.alarms.shelving import SHELVE_TOPIC
from catenary_monitor.core.alarms.shelving import parse_request as parse_shelve_request
from catenary_monitor.core.rules.health import clock_stopped
from catenary_monitor.core.monitor.events import (
    EVENTS_TOPIC,
    NODE_NAME,
    Acknowledge,
    ClockHealth,
    Coalesced,
    Depth,
    Event,
    FatigueStore,
    Intake,
    LoggerHealth,
    Reconfigure,
    Refusal,
    Shelve,
    Start,
    Tension,
    Tick,
    event_record,
)
from catenary_monitor.core.monitor.state import OUTPUT_FIELDS
from catenary_monitor.core.monitor.status import Change, Snapshot
from catenary_monitor.core.monitor.monitor_core import MonitorCore, Step
from catenary_monitor.core.rules.fatigue import to_record
from catenary_monitor.core.physics import elastic
from catenary_monitor.io import fatigue_store
from catenary_monitor.io.mcap_log import McapLogger, own_file_name
from catenary_monitor.io.cdr import string_text
from catenary_monitor.io.mcap_recover import (
    RECOVERED,
    RecoverResult,
    recover_in_child,
    unfinished_files,
)
from catenary_monitor.ros.dds_profile import use_announce_profile
from catenary_monitor.ros.request_reader import RequestReader, Taken

__all__ = ['NODE_NAME', 'OUTPUT_FIELDS', 'CatenaryMonitor', 'main']

_PARAM_TYPES = {
    'double': Parameter.Type.DOUBLE,
    'bool': Parameter.Type.BOOL,
    'string': Parameter.Type.STRING,
    'string_array': Parameter.Type.STRING_ARRAY,
    'double_array': Parameter.Type.DOUBLE_ARRAY,
}
_RELIABLE = QoSProfile(depth=10)
#: The message class of each input type (core.config.parameters.TENSION_TYPES, DEPTH_TYPES).
_MESSAGE_CLASSES: dict[str, Any] = {
    'std_msgs/msg/Float64': Float64,
    readings.WRENCH: WrenchStamped,
    readings.FLUID_PRESSURE: FluidPressure,
    readings.RANGE: Range,
}
#: The input subscriptions: sensor-data QoS (best effort) with a deeper queue than its 5, so a
#: node held off the CPU for up to 5 s at 200 Hz loses no sample before it is logged
#: (bench-soak measured 0.7 % lost with depth 5 on a loaded machine; bench-flood, 12 x 200 Hz
#: at a load of 14 on 2 cores, 4 % with 100 and none with 1000, the RSS unchanged).
_SAMPLES = QoSProfile(
    history=qos_profile_sensor_data.history,
    depth=1000,
    reliability=qos_profile_sensor_data.reliability,
    durability=qos_profile_sensor_data.durability,
)
#: Period of the wall-clock watchdog (ROS clock, intake counts) [s].
WATCHDOG_PERIOD = 1.0
#: The longest time without an Intake event [s] (while nothing is lost, only these are sent).
INTAKE_HEARTBEAT = 60.0
#: The same with a sample rate configured: the counts are checked against it this often [s].
INTAKE_RATE_HEARTBEAT = 10.0
#: The most samples one callback takes off an input's queue (the queue holds _SAMPLES.depth).
DRAIN_MAX = 1000
#: Samples that waited longer than this [s] when their callback ran are not stepped but
#: coalesced (logged, counted, left out); a shorter hiccup (a node held off the CPU by other
#: processes) is caught up with, sample by sample, within ``intake_step_budget`` of steps.
COALESCE_AFTER = 1.0
#: The operators' request topics are read this often [s] of wall time.
REQUEST_PERIOD = 0.05
_REQUESTS = {ACKNOWLEDGE_TOPIC: 'acknowledge', SHELVE_TOPIC: 'shelve'}
#: A sample callback runs the periodic tick (the watchdog) itself this many periods after the
#: previous one (its timer waiting in the executor's queue behind a flood's callbacks).
LATE_TIMER = 1.1
#: The log timer's period [s]: flush when due, retention, logger status (a sample callback runs
#: it too when it is late, as the watchdog).
LOG_PERIOD = 0.25


def _unnamed(node: str) -> bool:
    """True for the name the middleware lists a publisher under before its node is known
    (rmw_dds_common's ``_NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_``: an endpoint discovered
    ahead of its participant's node list, for tens of milliseconds, longer under load)."""
    return '_NODE_NAME_UNKNOWN_' in node or '_NODE_NAMESPACE_UNKNOWN_' in node


def _events_executor_wanted() -> bool:
    """True unless ``CATENARY_MONITOR_EXECUTOR=single`` asks for the SingleThreadedExecutor."""
    return os.environ.get('CATENARY_MONITOR_EXECUTOR', 'events') != 'single'


def _guarded(method: Any) -> Any:
    """Keep monitoring through an unexpected exception in a callback: log it and go on."""

    @wraps(method)
    def wrapper(self: 'CatenaryMonitor', *args: Any) -> Any:
        try:
            return method(self, *args)
        except Exception:  # noqa: BLE001 - one bad sample must not stop the monitor
            self.callback_errors += 1
            if self.callback_errors <= 10:
                self.get_logger().error(
                    f'{method.__name__} failed (monitoring goes on): ' + traceback.format_exc()
                )
            return None

    return wrapper


def _descriptor(spec: ParamSpec, name: str) -> ParameterDescriptor:
    """ParameterDescriptor (description, unit, range, read-only) from one PARAMETERS row."""
    unit = f' [{spec.unit}]' if spec.unit else ''
    constraints = [f'unit: {spec.unit}'] if spec.unit else []
    desc = ParameterDescriptor(
        name=name,
        type=_PARAM_TYPES[spec.type].value,
        description=spec.description + unit,
        read_only=spec.read_only,
    )
    # An optional parameter (default NaN: not set) cannot carry a ROS range; config checks it.
    if spec.type == 'double_array':  # each element's range is config's to check
        constraints.append(f'each element in [{spec.min:g}, {spec.max:g}]')
    elif (spec.min is not None or spec.max is not None) and spec.default == spec.default:
        low = -sys.float_info.max if spec.min is None else float(spec.min)
        high = sys.float_info.max if spec.max is None else float(spec.max)
        if not spec.optional:  # rclpy's range check refuses NaN, an optional's "not given"
            desc.floating_point_range = [
                FloatingPointRange(from_value=low, to_value=high, step=0.0)
            ]
        constraints.append(f'range: [{low:g}, {high:g}]' + (' or NaN (not given)' * spec.optional))
    desc.additional_constraints = '; '.join(constraints)
    return desc


class CatenaryMonitor(Node):
    """Subscribes to every chain's hook tension and the tide depth; publishes results,
    diagnostics and alarms; logs every input and output message to MCAP."""

    def __init__(self, *, log_dir: Optional[str] = None, **kwargs: Any) -> None:
        super().__init__(
            NODE_NAME, automatically_declare_parameters_from_overrides=False, **kwargs
        )
        self.config = self._declare_parameters(log_dir)
        self._node_clock = self.get_clock()  # not _clock: rclpy's Node owns that name
        # use_sim_time cannot change at runtime (refused): without it the node clock is the
        # system clock, read without building an rclpy Time each time.
        self._system_time = not self.get_parameter('use_sim_time').value
        self._last_ns = 0
        self._log_setup_error = ''
        self._logger_known = False
        self._logger_error: Optional[str] = None
        self._logger_warning: Optional[str] = None
        self.callback_errors = 0
        self._recovered: queue.Queue[RecoverResult] = queue.Queue()
        self.recovery: list[RecoverResult] = []
        # The fatigue store, read before this run's first log file exists (a new folder).
        names = [line.name for line in self.config.lines]
        self._fatigue_found = fatigue_store.load(self._log_dir(), names)
        self.log = self._open_log()
        self._init_intake()
        self._create_interfaces()
        start = self._stamp()
        self.core = MonitorCore(
            self.config,
            start,
            hardware_ids=dict(zip(self._names, self._tension_topics)),
            depth_id=self._depth_topic,
            logger_id=self._log_dir(),
        )
        self._write_record(Start(start))
        self._load_fatigue()
        self._check_logger()
        self._clock_ros, self._clock_wall = start, time.monotonic()
        self._clock_state: Optional[bool] = None  # stopped? (None: not reported yet)
        self._check_clock(self._clock_wall)
        self.add_on_set_parameters_callback(self._validate_change)
        self.add_post_set_parameters_callback(self._apply_change)
        self.get_logger().info(
            f'monitoring {len(self._names)} lines ({", ".join(self._names)}), '
            f'depth from {self.config.depth_topic}, log in {self._log_dir()}'
        )

    # ------------------------------------------------------------------ set-up
    def _declare_parameters(self, log_dir: Optional[str]) -> MonitorConfig:
        """Validate the overrides with ``config`` (one-line ConfigError), then declare them all."""
        # rclpy keeps the params-file and -p values here; it has no public getter for them.
        flat = {name: p.value for name, p in self._parameter_overrides.items()}
        if log_dir is not None:
            flat['log_dir'] = log_dir
        config = config_from_params(flat)
        values = all_parameters(config)
        for name, spec in expand_parameters([line.name for line in config.lines]):
            value = values[name]
            if spec.type in ('string_array', 'double_array'):
                value = list(value)
            if spec.type in ('double_array', 'string_array') and not value:
                value = _PARAM_TYPES[spec.type]  # ([] would be typed a byte array)
            self.declare_parameter(name, value, _descriptor(spec, name), ignore_override=True)
        for line in config.lines:
            if line.ea is not None:
                self.get_logger().info(
                    f'{line.name}: EA = {line.ea:g} N, elastic catenary wherever it changes '
                    f'the answer by more than {elastic.ELASTIC_TOL:g} (diagnostics key "model")'
                )
        return config

    def _log_dir(self) -> str:
        return os.path.expanduser(self.config.log_dir)

    # ------------------------------------------------------------------ fatigue store
    def _load_fatigue(self) -> None:
        """Read the fatigue store beside the log: one recorded FatigueStore event (each line's
        stored count, so replay carries the same), one log line unless it was read clean."""
        names = [line.name for line in self.config.lines]
        found = self._fatigue_found
        lines = tuple((name, found.lines.get(name)) for name in names)
        if found.state in ('loaded', 'new'):
            self.get_logger().info(found.message)
        else:
            self.get_logger().warning(f'FATIGUE {found.state}: {found.message}')
        self._record(FatigueStore(self._stamp(), found.state, found.message, lines))
        self._fatigue_saved = time.monotonic()
        self._fatigue_failed: Optional[str] = None

    def _save_fatigue(self, force: bool = False) -> None:
        """Write the store every SAVE_PERIOD (and at the end); a failed write is a recorded
        FatigueStore event (WARN) and one line, a write that works again another."""
        wall = time.monotonic()
        if not force and wall - self._fatigue_saved < fatigue_store.SAVE_PERIOD:
            return
        self._fatigue_saved = wall
        lines = {line.config.name: to_record(line.fatigue) for line in self.core.state.lines}
        extra = {'config_hash': config_hash(self.config), 'saved_ns': self._last_ns}
        try:
            path = fatigue_store.save(self._log_dir(), lines, extra)
        except (OSError, ValueError) as err:
            if self._fatigue_failed is None:
                text = f'fatigue store not written: {_one_line(err)}'
                self.get_logger().error(text)
                self._record(FatigueStore(self._stamp(), 'write_failed', text))
            self._fatigue_failed = str(err)
            return
        if self._fatigue_failed is not None:
            self._fatigue_failed = None
            text = f'fatigue store {path} written again'
            self.get_logger().info(text)
            self._record(FatigueStore(self._stamp(), 'saved', text))

    def _open_log(self) -> Optional[McapLogger]:
        """The MCAP logger (never raises on disk errors: those become its ``error``)."""
        try:
            # Files a crash left unfinished, found before this run's first file exists.
            unfinished: list[Path] = []
            theirs: list[Path] = []
            for path in unfinished_files(self._log_dir()):
                (unfinished if own_file_name(NODE_NAME, path.name) else theirs).append(path)
            for path in theirs:  # a user's file is never rewritten
                self.get_logger().warning(
                    f'unfinished MCAP file {path.name} in the log folder is not the node\'s own: '
                    'left as it is (catenary-monitor recover finishes it)'
                )
            # Flushed at 0.75 s age, checked every 0.25 s: a SIGKILL loses at most the last second.
            # A vanished file or directory is seen at the next 0.25 s tick; retries every 1 s.
            log = McapLogger(
                self._log_dir(),
                prefix=NODE_NAME,
                flush_period=0.75,
                max_bytes=int(self.config.log_rotate_size * 1024 * 1024),
                max_seconds=self.config.log_rotate_duration,
                create_dir=self.config.log_create_dir,
                retry_period=1.0,
                max_total_bytes=int(self.config.log_max_total_size),
                max_age=self.config.log_max_age,
                min_free_bytes=int(self.config.log_min_free_space),
            )
            log.add_metadata(NODE_NAME, self._metadata(self.config))
            if unfinished:
                self._start_recovery(unfinished)
            return log
        except Exception as exc:  # noqa: BLE001 - logging must never stop the monitoring
            self._log_setup_error = f'cannot start the MCAP logger: {exc}'
            self.get_logger().error(self._log_setup_error)
            return None

    def _start_recovery(self, files: list[Any]) -> None:
        """Finish the unfinished files in a niced child process, one at a time, waited for by
        a thread (monitoring starts at once, its interpreter not shared); the log timer reports
        each result (:meth:`_report_recovery`)."""
        self.get_logger().warning(
            f'{len(files)} unfinished MCAP log(s) in {self._log_dir()} (left by a crash): '
            'finishing them in the background'
        )

        def work() -> None:
            for path in files:
                self._recovered.put(recover_in_child(path))

        threading.Thread(target=work, name='mcap-recover', daemon=True).start()

    def _report_recovery(self) -> None:
        """One line and one events-channel record per recovered file; metadata.yaml redone."""
        done = False
        while True:
            try:
                result = self._recovered.get_nowait()
            except queue.Empty:
                break
            done = True
            self.recovery.append(result)
            name = os.path.basename(result.path)
            if result.status in RECOVERED:
                kept = ''
                if result.backup:
                    kept = f'; original kept as {os.path.basename(result.backup)}'
                elif result.status == 'finished_in_place':
                    kept = '; finished in place (no room for a copy)'
                self.get_logger().warning(
                    f'recovered unfinished MCAP log {name}: {result.messages} messages, '
                    f'{len(result.damaged)} damaged part(s) skipped{kept}'
                )
            else:
                self.get_logger().error(
                    f'unfinished MCAP log {name} not recovered ({result.status}): {result.error}'
                )
            record = {'kind': 'log_recovered', **result.to_dict()}
            self._write(
                EVENTS_TOPIC, serialize_message(String(data=json.dumps(record))), self._stamp()
            )
        if done and self.log is not None:
            self.log.refresh_metadata()

    def _recovery_values(self) -> tuple[tuple[str, str], ...]:
        """The logger status's keys about start-up recovery."""
        if not self.recovery:
            return ()
        ok = [r for r in self.recovery if r.status in RECOVERED]
        return (
            ('files_recovered', str(len(ok))),
            ('files_not_recovered', str(len(self.recovery) - len(ok))),
            ('recovered_messages', str(sum(r.messages for r in ok))),
        )

    @staticmethod
    def _metadata(config: MonitorConfig) -> dict[str, str]:
        """MCAP metadata record: version, configuration and its hash, output layout."""
        return {
            'version': __version__,
            'config_hash': config_hash(config),
            'parameters': json.dumps(config_to_params(config), sort_keys=True),
            'output_fields': ','.join(OUTPUT_FIELDS),
            'units': 'SI (N, m, s)',
        }

    def _register(self, topic: str, type_name: str, qos: str) -> None:
        if self.log is None:
            return
        try:
            self.log.register(topic, type_name, qos)
        except Exception as exc:  # noqa: BLE001
            self.get_logger().error(f'cannot log {topic} to MCAP: {exc}')

    def _init_intake(self) -> None:
        """Intake counters (per line, then the depth) since the last Intake event, and each
        subscription's sequence bookkeeping (the lines' first channels, the depth, then a
        load cell's further channels: :meth:`_create_interfaces`)."""
        n = len(self.config.lines) + 1
        s = n + sum(max(len(line.channel_topics) - 1, 0) for line in self.config.lines)
        self._received = [0] * n
        self._dropped = [0] * n
        self._coalesced = [0] * n
        self._last_seq: list[Optional[int]] = [None] * s
        self._unsequenced = [0] * s  # samples taken without a sequence number since _last_seq
        self._lost_unseen = [0] * s  # samples DDS reported lost, their gap not seen yet
        self._gap_unreported = [0] * s  # samples of seen gaps DDS has not reported (yet)
        self._intake_due = False  # a sample was not handled while the intake said OK
        self._step_cost = 1e-4  # s of wall time one sample's step takes (moving average)
        self._busy = 0.0  # s of wall time in the sample callbacks since the last Intake event
        self._busy_tick = 0.0  # the same since the last watchdog period
        self._intake_wall = time.monotonic()
        self._intake_sent = False
        a = self.config.alarm
        rated = a.tension_sample_rate > 0.0 or a.depth_sample_rate > 0.0
        self._intake_heartbeat = INTAKE_RATE_HEARTBEAT if rated else INTAKE_HEARTBEAT
        # rclpy's EventsExecutor (7.1) cannot call a callback taking MessageInfo: the
        # publisher's sequence numbers (gaps = samples lost) only with the other executor.
        self._with_info = not (_events_executor_wanted() and _has_events_executor())

    def _sample_callback(self, k: int) -> Any:
        """The subscription callback for input ``k`` (with the MessageInfo where the executor
        can hand it over)."""
        if self._with_info:
            return partial(self._on_sample_info, k)
        return partial(self._on_sample, k)

    def _sample_events(self, k: int) -> SubscriptionEventCallbacks:
        return SubscriptionEventCallbacks(message_lost=partial(self._on_lost, k))

    def _create_interfaces(self) -> None:
        """Subscriptions (sensor-data QoS, raw CDR), publishers and timers."""
        cfg = self.config
        self._names = [line.name for line in cfg.lines]
        self._tension_topics: list[str] = []
        self._output_topics: list[str] = []
        self._output_pubs: list[Any] = []
        self._subs: list[Any] = []
        for k, line in enumerate(cfg.lines):
            sub = self.create_subscription(
                _MESSAGE_CLASSES[line.tension_type],
                line.topics[0],
                self._sample_callback(k),
                _SAMPLES,
                event_callbacks=self._sample_events(k),
                raw=True,
            )
            self._subs.append(sub)
            self._tension_topics.append(sub.topic_name)
            self._register(sub.topic_name, line.tension_type, 'sensor_data')
            pub = self.create_publisher(Float64MultiArray, f'~/{line.name}/outputs', _RELIABLE)
            self._output_pubs.append(pub)
            self._output_topics.append(pub.topic_name)
            self._register(pub.topic_name, 'std_msgs/msg/Float64MultiArray', 'default')
        n = len(cfg.lines)
        sub = self.create_subscription(
            _MESSAGE_CLASSES[cfg.depth_type],
            cfg.depth_topic,
            self._sample_callback(n),
            _SAMPLES,
            event_callbacks=self._sample_events(n),
            raw=True,
        )
        self._subs.append(sub)
        self._depth_topic = sub.topic_name
        self._register(self._depth_topic, cfg.depth_type, 'sensor_data')
        # input s: line s's first channel (s < n), the depth (n), then further channels
        self._input_line = list(range(n + 1))
        self._input_channel = [0] * (n + 1)
        self._input_topic = [*self._tension_topics, self._depth_topic]
        for k, line in enumerate(cfg.lines):
            for j, topic in enumerate(line.channel_topics[1:], start=1):
                # a load cell's further channels (core.rules.channels), each an input of its own:
                # drained, coalesced and counted (for its line) as the first is
                s = len(self._subs)
                extra = self.create_subscription(
                    Float64,
                    topic,
                    self._sample_callback(s),
                    _SAMPLES,
                    event_callbacks=self._sample_events(s),
                    raw=True,
                )
                self._subs.append(extra)
                self._input_line.append(k)
                self._input_channel.append(j)
                self._input_topic.append(extra.topic_name)
                self._register(extra.topic_name, readings.FLOAT64, 'sensor_data')
        # A new reader of /diagnostics (the harbour, a console joining late) has the current
        # array at once, not one period later.
        self._diag_pub = self.create_publisher(
            DiagnosticArray,
            '/diagnostics',
            _RELIABLE,
            event_callbacks=PublisherEventCallbacks(matched=self._on_diag_matched),
        )
        self._register('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', 'default')
        self._register(EVENTS_TOPIC, 'std_msgs/msg/String', 'default')
        self._output = Float64MultiArray()
        self._output.layout.dim = [
            MultiArrayDimension(
                label=','.join(OUTPUT_FIELDS), size=len(OUTPUT_FIELDS), stride=len(OUTPUT_FIELDS)
            )
        ]
        self._output_cdr = OutputEncoder(self._output)
        # The operators' requests, each with its publisher's GID (ros/request_reader.py),
        # rate-limited per publisher (core/alarms/requests.py).
        self._requests = RequestReader(self, [ACKNOWLEDGE_TOPIC, SHELVE_TOPIC])
        if self._requests.why_no_gid:
            self.get_logger().warning(
                f'operators\' requests: {self._requests.why_no_gid}: rate-limited per set of '
                'publishers on each topic'
            )
        self._limit = RequestLimit()
        self._resends = Resends()  # the ids each publisher's requests carried lately
        self._senders: dict[tuple[str, bytes], str] = {}  # (topic, GID) -> node's full name
        self._sequences: dict[tuple[str, bytes], int] = {}  # (topic, GID) -> newest number
        self._graph_read: dict[str, float] = {}  # topic -> when its publishers were listed
        self._named: dict[str, str] = {}  # a rate-limit key -> its publisher, as last named
        self._diag_timer = self.create_timer(1.0 / cfg.alarm.diagnostic_rate, self._on_period)
        self._period_ns = int(1e9 / cfg.alarm.diagnostic_rate)
        self._tick_ns = self._now_ns()  # the newest tick's stamp
        self._watchdog_wall = time.monotonic()
        # Wall-clock timers: they run while a simulated ROS clock stands still.
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._log_wall = time.monotonic()  # the log timer's last run
        self._log_timer = self.create_timer(LOG_PERIOD, self._on_log_tick, clock=steady)
        self._watchdog = self.create_timer(WATCHDOG_PERIOD, self._on_watchdog_timer, clock=steady)
        self._request_timer = self.create_timer(REQUEST_PERIOD, self._on_requests, clock=steady)

    # ------------------------------------------------------------------ callbacks
    def _now_ns(self) -> int:
        """The node clock [ns] (the system clock read directly unless ``use_sim_time``)."""
        if self._system_time:
            return time.time_ns()
        return self._node_clock.now().nanoseconds

    def _stamp(self) -> int:
        """A distinct, increasing event stamp (ns): the node clock, or 1 ns after the last one."""
        now = self._now_ns()
        self._last_ns = now if now > self._last_ns else self._last_ns + 1
        return self._last_ns

    @_guarded
    def _on_sample(self, k: int, data: bytes) -> None:
        """A sample of input ``k`` (a line, the depth, a load cell's further channel), and
        every one waiting behind it (:meth:`_take`)."""
        self._unsequenced[k] += 1
        self._take(k, data, None)

    @_guarded
    def _on_sample_info(self, k: int, data: bytes, info: Any) -> None:
        """The same with its MessageInfo (the SingleThreadedExecutor)."""
        self._count_sequence(k, info.get('publication_sequence_number'))
        self._take(k, data, info.get('received_timestamp'))

    def _take(self, k: int, data: bytes, received_ns: Optional[int]) -> None:
        """Log ``data`` and the samples waiting behind it on input ``k``, and step what the
        node can handle of them, newest first (:meth:`_to_step`): after a hiccup, all of them.

        The older ones it cannot handle are coalesced: a :class:`Coalesced` record stamped
        before them tells replay to leave them out, as the node does, and they are counted
        (Intake ``coalesced``); the node never works through a backlog it cannot keep up
        with."""
        t0 = time.perf_counter()
        batch = [(data, received_ns)] + self._drain(k)
        n = len(batch)
        keep = self._to_step(batch)
        topic, owner = self._input_topic[k], self._input_line[k]
        step = self._step_depth if owner == len(self._names) else self._step_tension
        if keep < n:
            line = None if owner == len(self._names) else self._names[owner]
            stamps = [self._stamp() for _ in range(n - keep + 1)]
            self._record(Coalesced(stamps[0], line, stamps[-1], n - keep))
            for (raw, _), stamp in zip(batch, stamps[1:]):
                self._write(topic, raw, stamp)
            self._coalesced[owner] += n - keep
            self._intake_due = True
        for raw, _ in batch[n - keep :]:
            t1 = time.perf_counter()
            stamp = self._stamp()
            self._write(topic, raw, stamp)
            step(k, stamp, raw)
            # a moving average; one slow step (the log's chunk written out) counts 4x at most
            spent = min(time.perf_counter() - t1, 4.0 * self._step_cost)
            self._step_cost += 0.1 * (spent - self._step_cost)
        took = time.perf_counter() - t0
        self._busy += took
        self._busy_tick += took
        self._timers_late()

    def _to_step(self, batch: list[tuple[bytes, Optional[int]]]) -> int:
        """How many of the newest samples of ``batch`` to step: those that waited at most
        :data:`COALESCE_AFTER` (the newest always), as many as ``intake_step_budget`` of steps
        takes at the recent cost of one, less as the batch fills the input's queue (none but
        the newest from half of it: the samples behind must be taken and logged in time)."""
        n = len(batch)
        if n == 1:
            return 1
        now, fresh = time.time_ns(), 0
        for _, received in reversed(batch):
            if isinstance(received, int) and now - received > COALESCE_AFTER * 1e9:
                break
            fresh += 1
        room = max(0.0, 1.0 - n / (0.5 * _SAMPLES.depth))
        budget = room * self.config.alarm.intake_step_budget / max(self._step_cost, 1e-6)
        return max(1, min(fresh, int(budget)))

    def _step_tension(self, s: int, stamp: int, raw: bytes) -> None:
        """One core event of a hook tension sample of input ``s`` as it came (the reading in
        N, at its header stamp where it has one; a load cell's channel: which one); publish
        what it says."""
        k, j = self._input_line[s], self._input_channel[s]
        self._received[k] += 1
        lc = self.config.lines[k]
        fields, sample_ns = _fields(raw, lc.tension_type if j == 0 else readings.FLOAT64)
        self._run(Tension(stamp, k, float(readings.tension_si(lc, fields)), sample_ns, j))

    def _step_depth(self, k: int, stamp: int, raw: bytes) -> None:
        """The same for a depth sample (the depth in m)."""
        self._received[k] += 1
        fields, sample_ns = _fields(raw, self.config.depth_type)
        self._run(Depth(stamp, float(readings.depth_si(self.config, fields)), sample_ns))

    def _drain(self, k: int) -> list[tuple[bytes, Optional[int]]]:
        """Every sample waiting on input ``k``'s subscription (up to :data:`DRAIN_MAX`), with
        its reception time [ns] and its publisher's sequence number counted."""
        sub = self._subs[k]
        out: list[tuple[bytes, Optional[int]]] = []
        with sub.handle:
            while len(out) < DRAIN_MAX:
                taken = sub.handle.take_message(sub.msg_type, sub.raw)
                if taken is None:
                    break
                data, info = taken
                out.append((data, info.get('received_timestamp')))
                self._count_sequence(k, info.get('publication_sequence_number'))
        return out

    def _count_sequence(self, k: int, seq: Any) -> None:
        """A gap in the publisher's sequence numbers counts the samples lost before the node
        took them, less those taken without a number in between (the EventsExecutor hands a
        callback its sample without one); a restarted publisher (the numbers start again) is
        not a loss."""
        if not isinstance(seq, int):
            self._unsequenced[k] += 1
            return
        last = self._last_seq[k]
        if last is not None:
            gap = seq - last - 1 - self._unsequenced[k]
            if gap > 0:
                counted = min(gap, self._lost_unseen[k])  # DDS reported these already
                self._lost_unseen[k] -= counted
                self._gap_unreported[k] += gap - counted
                self._dropped[self._input_line[k]] += gap - counted
                self._intake_due = True
        self._last_seq[k], self._unsequenced[k] = seq, 0

    def _on_lost(self, k: int, info: Any) -> None:
        """A QoS message-lost event of input ``k`` (what DDS reports lost): counted now, and
        not again when the gap it leaves in the sequence numbers is seen."""
        lost = int(info.total_count_change)
        seen = min(lost, self._gap_unreported[k])  # their gap was counted already
        self._gap_unreported[k] -= seen
        self._lost_unseen[k] += lost - seen
        self._dropped[self._input_line[k]] += lost - seen
        self._intake_due = True

    @_guarded
    def _on_watchdog_timer(self) -> None:
        """The watchdog's timer (none when a sample callback ran it lately)."""
        if time.monotonic() - self._watchdog_wall >= 0.5 * WATCHDOG_PERIOD:
            self._on_watchdog()

    def _on_watchdog(self) -> None:
        """Wall-clock checks: the ROS clock advances, and the intake counts."""
        wall = time.monotonic()
        self._watchdog_wall = wall
        self._check_clock(wall)
        self._report_intake(wall)

    def _timers_late(self) -> None:
        """Report the intake counts at once when a sample was not handled while the intake
        status said OK; run the periodic tick, the watchdog and the log timer here when their
        timers are late by a tenth of a period (:data:`LATE_TIMER`): a flood's callbacks wait
        ahead of them in the executor's queue, and /diagnostics must keep its time."""
        if self._intake_due and self.core.state.intake[0] == Level.OK:
            self._report_intake(time.monotonic(), force=True)
        if self._now_ns() - self._tick_ns >= LATE_TIMER * self._period_ns:
            self._tick()
        if time.monotonic() - self._watchdog_wall >= LATE_TIMER * WATCHDOG_PERIOD:
            self._on_watchdog()
        if time.monotonic() - self._log_wall >= LATE_TIMER * LOG_PERIOD:
            self._on_log_timer()

    def _check_clock(self, wall: float) -> None:
        """With ``use_sim_time``: a ClockHealth event (and /diagnostics) every watchdog
        period while the ROS clock stands still, one when it moves again (and one at start)."""
        if not self.get_parameter('use_sim_time').value:
            return
        ros = self._node_clock.now().nanoseconds
        if ros != self._clock_ros:
            self._clock_ros, self._clock_wall = ros, wall
        frozen = wall - self._clock_wall
        if clock_stopped(frozen):
            if self._clock_state is not True:
                self.get_logger().error(
                    f'ROS clock stopped: /clock not advancing for {frozen:.0f} s'
                )
            self._clock_state = True
            self._record(ClockHealth(self._stamp(), round(frozen, 3)))
        elif self._clock_state is not False:
            if self._clock_state:
                self.get_logger().info('ROS clock advancing again')
            self._clock_state = False
            self._record(ClockHealth(self._stamp(), None))

    def _report_intake(self, wall: float, force: bool = False) -> None:
        """An Intake event (samples received and dropped, callback time, since the last one)
        when something is to be said: a drop, a busy second, the intake not OK, or
        :data:`INTAKE_HEARTBEAT` (:data:`INTAKE_RATE_HEARTBEAT` with a sample rate to check
        against) without one (few events: replay steps each one)."""
        busy_share = self._busy_tick / WATCHDOG_PERIOD
        self._busy_tick = 0.0
        quiet = (
            not any(self._dropped)
            and not any(self._coalesced)
            and busy_share < 0.5
            and self.core.state.intake[0] == Level.OK
            and wall - self._intake_wall < self._intake_heartbeat
        )
        if quiet and self._intake_sent and not force:
            return
        period = wall - self._intake_wall
        event = Intake(
            self._stamp(),
            tuple(self._received),
            tuple(self._dropped),
            self._busy,
            period,
            tuple(self._coalesced),
        )
        n = len(self._received)
        self._received, self._dropped, self._busy = [0] * n, [0] * n, 0.0
        self._coalesced = [0] * n
        self._intake_wall, self._intake_sent, self._intake_due = wall, True, False
        self._record(event)

    @_guarded
    def _on_period(self) -> None:
        """The periodic tick's timer (none when a sample callback ran it lately)."""
        if self._now_ns() - self._tick_ns >= 0.5 * self._period_ns:
            self._tick()

    @_guarded
    def _on_diag_matched(self, info: Any) -> None:
        """A reader of /diagnostics matched: a tick now, so it hears the monitor at once."""
        if info.current_count_change > 0:
            self._tick()

    def _tick(self) -> None:
        """The periodic tick: staleness and hold-time clears; /diagnostics at a steady rate.
        The intake counts come first when a sample was not handled while the intake status
        said OK, so it says otherwise within one period."""
        if self._intake_due and self.core.state.intake[0] == Level.OK:
            self._report_intake(time.monotonic(), force=True)
        self._tick_ns = self._stamp()
        self._record(Tick(self._tick_ns))

    @_guarded
    def _on_requests(self) -> None:
        """Take the waiting requests of both topics, each as its publisher's (rate-limited);
        record the refused ones due."""
        for topic in (ACKNOWLEDGE_TOPIC, SHELVE_TOPIC):
            for taken in self._requests.take(topic):
                self._request(topic, taken)
        self._report_refused(time.monotonic())

    def _request(self, topic: str, taken: Taken) -> None:
        """One request: over its publisher's rate limit it is counted (and recorded with the
        others, :meth:`_report_refused`); else read, and acknowledged, shelved or refused, each
        one recorded core event."""
        request = _REQUESTS[topic]
        publisher, node = self._sender(topic, taken.gid)
        # A publisher's bucket by its GID: the same before and after the graph names its node.
        key = f'{request} {publisher if taken.gid is None else taken.gid.hex()}'
        if len(self._named) > 4096:  # publishers come and go: forget their names, not limits
            for known in (self._named, self._senders, self._sequences):
                known.clear()
        self._named[key] = publisher
        if taken.gid is not None and taken.sequence is not None:
            last = self._sequences.get((topic, taken.gid))
            self._sequences[(topic, taken.gid)] = taken.sequence
            if last is not None and taken.sequence > last + 1:  # lost behind a flood
                self._limit.refuse(key, taken.sequence - last - 1)
        if not self._limit.admit(key, time.monotonic()):
            self._report_refused(time.monotonic())
            return
        try:
            text = string_text(taken.data)
        except ValueError:
            self._refuse(request, '', 'not a std_msgs/msg/String', '', publisher)
            return
        text, rid = split_id(text)
        if rid and self._resends.seen(key, rid, time.monotonic()):
            return  # a resend of a request taken already: answered then, applied once
        refusal = self._sender_refusal(topic, node)
        if refusal is not None:
            self._refuse(request, text.split(None, 1)[0][:64] if text.strip() else '',
                         refusal, '', publisher)  # fmt: skip
            return
        if request == 'acknowledge':
            self._acknowledge(text, publisher)
        else:
            self._shelve(text, publisher)

    def _sender(self, topic: str, gid: Optional[bytes]) -> tuple[str, Optional[str]]:
        """(the publisher as the middleware names it, its node's full name or None) of a
        message from ``gid`` (None: unknown; named from every publisher on the topic)."""
        if gid is None:
            return publisher_identity(self._publishers_on(topic)), None
        node = self._senders.get((topic, gid))
        if node is None and time.monotonic() - self._graph_read.get(topic, -1.0) >= 0.5:
            self._graph_read[topic] = time.monotonic()  # at most twice a second per topic
            for name, g in self._publishers_on(topic):
                if not _unnamed(name):  # the middleware's placeholder: asked again, not kept
                    self._senders[(topic, g[: len(gid)])] = name
            node = self._senders.get((topic, gid))
        if node is None:
            return f'gid {".".join(f"{b:02x}" for b in gid)} (not on the ROS graph)', None
        return publisher_identity([(node, gid)]), node

    def _sender_refusal(self, topic: str, node: Optional[str]) -> Optional[str]:
        """Why a request from ``node`` (None: unknown) is refused where only a console may
        send one (``acknowledge_from_ros`` false), or None."""
        if self.config.acknowledge_from_ros:
            return None
        if node is None:
            return console_only_refusal(self._publishers_on(topic))
        if node.rsplit('/', 1)[-1].startswith(CONSOLE_NODE_PREFIX):
            return None
        return f'acknowledge_from_ros is false and {node} is not a console'

    def _refuse(
        self, request: str, alarm: str, reason: str, origin: str, publisher: str, n: int = 1
    ) -> None:
        """Record a request refused before the alarm rules (one core event, its answer the
        step's note), and log it."""
        self._record(Refusal(self._stamp(), request, alarm, reason, origin, publisher, n))
        more = f' ({n} requests)' if n > 1 else ''
        named = f' [{alarm}]' if alarm else ''
        self.get_logger().warning(
            f'{request} refused: {bounded_text(reason, 240)}{more}{named} ({publisher})'
        )

    def _report_refused(self, now: float) -> None:
        """Record each publisher's requests refused over its rate limit since its last
        record (one record per publisher and period at most)."""
        for key, n in self._limit.due(now):
            why = f'over the rate limit of its publisher ({limit_text()})'
            self._refuse(key.partition(' ')[0], '', why, '', self._named.get(key, key), n)

    def _acknowledge(self, text: str, publisher: str) -> None:
        """An operator's acknowledgement (``ALARM|all [ORIGIN]``: a line, ``sensors`` or a
        component status such as ``tide``): one recorded core event, or a recorded refusal
        (unreadable, an unknown alarm)."""
        try:
            line, origin = parse_request(text)
        except ValueError as err:
            self._refuse('acknowledge', '', str(err), '', publisher)
            return
        known = line in self.core.index or line == SENSORS or acknowledgeable(line or '')
        if line is not None and not known:
            shown = bounded_text(line, 64)
            why = (
                f'unknown line {shown!r} (lines: {", ".join(self._names)}; {SENSORS}: the '
                f'sensors alarm; components: {", ".join(COMPONENTS)})'
            )
            self._refuse('acknowledge', shown, why, origin, publisher)
            return
        self._record(Acknowledge(self._stamp(), line, origin, publisher))
        self.get_logger().info(f'ACKNOWLEDGED {line or "all"} by {origin} ({publisher})')

    def _publishers_on(self, topic: str) -> list[tuple[str, bytes]]:
        """The publishers on ``topic`` as the ROS graph names them: (node's full name, GID)."""
        return [
            (f'{ns.rstrip("/")}/{name}', bytes(gid))
            for name, ns, gid in (
                (e.node_name, e.node_namespace, e.endpoint_gid)
                for e in self.get_publishers_info_by_topic(topic)
            )
        ]

    def _shelve(self, text: str, publisher: str) -> None:
        """An operator's shelving request (``LINE[.CONDITION] SECONDS [ORIGIN]``): one recorded
        core event, whose answer (shelved, unshelved, or refused by the core's rules: an
        unknown alarm too) is one log line; an unreadable one a recorded refusal."""
        try:
            request = parse_shelve_request(text)
        except ValueError as err:
            first = text.strip().split(None, 1)[0][:64] if text.strip() else ''
            self._refuse('shelve', bounded_text(first, 64), str(err), '', publisher)
            return
        step = self._record(Shelve(self._stamp(), *request, publisher))
        line = f'SHELVE {step.note} ({publisher})'
        if ': refused: ' in step.note:
            self.get_logger().warning(line)
        else:
            self.get_logger().info(line)

    def _on_log_tick(self) -> None:
        """The log timer (none when a sample callback ran it lately)."""
        if time.monotonic() - self._log_wall >= 0.5 * LOG_PERIOD:
            self._on_log_timer()

    @_guarded
    def _on_log_timer(self) -> None:
        """Flush the MCAP chunk when due (bounded loss on SIGKILL); report logger changes."""
        self._log_wall = time.monotonic()
        if self.log is not None:
            self.log.tick()
            self._report_deleted()
            self._report_finished_late()
        self._check_logger()
        self._report_recovery()
        self._save_fatigue()

    def _report_finished_late(self) -> None:
        """One log line and one events-channel record per file a write error (a full disk)
        had left unfinished and the logger finished where it lies once space allowed."""
        assert self.log is not None
        for path in self.log.take_finished_late():
            self.get_logger().warning(
                f'MCAP log {path.name}, left unfinished by a write error, is finished now '
                '(cut after its last whole chunk, summary written)'
            )
            record = {'kind': 'log_finished_late', 'path': str(path)}
            self._write(
                EVENTS_TOPIC, serialize_message(String(data=json.dumps(record))), self._stamp()
            )

    def _report_deleted(self) -> None:
        """One log line and one events-channel record per file the retention deleted."""
        assert self.log is not None
        for path, size, why in self.log.take_deleted():
            rule = f'the folder above log_max_total_size {self.config.log_max_total_size:g} B'
            if why == 'age':
                rule = f'older than log_max_age {self.config.log_max_age:g} s'
            elif why == 'future':
                rule += ', first as dated ahead of the present (written with a wrong clock)'
            shown = f'{size / 2**20:.1f} MiB' if size >= 2**20 else f'{size / 1024:.1f} KiB'
            self.get_logger().warning(f'log retention: deleted {path.name} ({shown}): {rule}')
            record = {'kind': 'log_deleted', 'path': str(path), 'bytes': size, 'reason': why}
            self._write(
                EVENTS_TOPIC, serialize_message(String(data=json.dumps(record))), self._stamp()
            )

    def _check_logger(self) -> None:
        """A LoggerHealth event whenever the logger's error changes (and once at start)."""
        error: Optional[str]
        path: Optional[str]
        warning: Optional[str] = None
        if self.log is None:
            error, path = self._log_setup_error or 'no logger', None
        else:
            current = self.log.current_path
            error, path = self.log.error, str(current) if current else None
            warning = self.log.warning
        if self._logger_known and (error, warning) == (self._logger_error, self._logger_warning):
            return
        self._logger_known, self._logger_error = True, error
        if error:
            self.get_logger().error(f'MCAP log not written: {error}')
        elif warning and warning != self._logger_warning:
            self.get_logger().warning(warning)
        self._logger_warning = warning
        self._record(LoggerHealth(self._stamp(), error, path, warning))

    def _write_record(self, event: Any) -> None:
        """Log a record of a non-input event (or the start) on the events channel."""
        record = event_record(event)
        if record is not None:
            self._write(
                EVENTS_TOPIC, serialize_message(String(data=json.dumps(record))), event.stamp_ns
            )

    def _record(self, event: Event) -> Step:
        """Record a non-input event, then run it through the core."""
        self._write_record(event)
        return self._run(event)

    def _run(self, event: Event) -> Step:
        """One core step; publish and log its outputs and snapshot, report its transitions."""
        step = self.core.step(event)
        for out in step.outputs:
            data = self._output_cdr(out.values)
            self._output_pubs[out.line].publish(data)
            self._write(self._output_topics[out.line], data, step.stamp_ns)
        for change in step.transitions:
            self._report(change)
        for record in step.alarm_events:
            self._report_alarm(record)
        if step.snapshot is not None:
            self._publish_diagnostics(step.snapshot)
        return step

    def _report(self, change: Change) -> None:
        """One console line per level change: ``ALARM NAME: OLD -> NEW: message (after N s)``;
        none for a change the core marks suppressed by design (into or out of a STALE that the
        one ``sensors`` alarm announces, or a WARN a parted chain's ERROR stands for)."""
        ev = change.transition
        if ev.suppressed:
            return
        took = '' if ev.duration is None else f' (after {ev.duration:.1f} s)'
        text = f'ALARM {change.component}: {ev.old.name} -> {ev.new.name}: {ev.message}{took}'
        # rclpy fixes the severity per call site: one call per severity.
        if ev.new == Level.ERROR:
            self.get_logger().error(text)
        elif ev.new == Level.OK:
            self.get_logger().info(text)
        else:
            self.get_logger().warning(text)

    def _report_alarm(self, record: AlarmEvent) -> None:
        """One line per alarm-management record the level changes do not say: a shelf that
        expired, chattering that starts or stops."""
        if record.kind == 'unshelved' and record.by == 'expired':
            self.get_logger().warning(
                f'SHELVE {record.alarm}: shelf expired after {record.time - record.value:.0f} s; '
                'the alarm is shown again'
            )
        elif record.kind == 'chattering':
            a = self.config.alarm
            self.get_logger().warning(
                f'CHATTERING {record.alarm}: {a.chatter_count:g} level changes or more within '
                f'{a.chatter_window:g} s'
            )
        elif record.kind == 'chattering_end':
            self.get_logger().info(f'CHATTERING {record.alarm}: no longer chattering')

    # ------------------------------------------------------------------ output
    def _write(self, topic: str, data: bytes, stamp_ns: int) -> None:
        if self.log is not None:
            self.log.write(topic, data, stamp_ns)

    def _publish_diagnostics(self, snapshot: Snapshot) -> None:
        """The core's snapshot as one DiagnosticArray (the logger's counters filled in here)."""
        array = DiagnosticArray()
        array.header.stamp.sec, array.header.stamp.nanosec = divmod(snapshot.stamp_ns, 10**9)
        statuses = []
        for st in snapshot.statuses:
            values = st.values
            if st.name == f'{NODE_NAME}: logger' and self.log is not None:
                texts = tuple((k, v) for k, v in values if k in TEXT_KEYS)
                values = (
                    tuple(self.log.diagnostic_values().items()) + self._recovery_values() + texts
                )
            statuses.append(
                DiagnosticStatus(
                    level=bytes([int(st.level)]),
                    name=st.name,
                    message=st.message,
                    hardware_id=st.hardware_id,
                    values=[KeyValue(key=k, value=v) for k, v in values],
                )
            )
        array.status = statuses
        data = serialize_message(array)
        self._diag_pub.publish(data)
        self._write('/diagnostics', data, snapshot.stamp_ns)

    # ------------------------------------------------------------------ parameters
    def _current_params(self) -> dict[str, Any]:
        return {name: p.value for name, p in self._parameters.items()}

    def _validate_change(self, params: list[Parameter]) -> SetParametersResult:
        """Reject a change the runtime-change policy or ``config`` rejects, with its one-line
        reason (core.config.runtime_change_refusal); no side effects."""
        refused = runtime_change_refusal(self.config, [p.name for p in params])
        if refused is not None:
            self.get_logger().warning(f'set_parameters refused: {refused}')
            return SetParametersResult(successful=False, reason=refused)
        flat = self._current_params()
        flat.update({p.name: p.value for p in params})
        try:
            config_from_params(flat)
        except ConfigError as err:
            return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _apply_change(self, params: list[Parameter]) -> None:
        """Apply an accepted change: a Reconfigure event (states kept), recorded in the log,
        and one warning line per changed parameter (old -> new, with its unit)."""
        old = all_parameters(self.config)
        for p in params:
            self.get_logger().warning(change_message(p.name, old.get(p.name), p.value))
        config = config_from_params(self._current_params())
        self.config = config
        self._record(Reconfigure(self._stamp(), config))
        self._diag_timer.timer_period_ns = int(1e9 / config.alarm.diagnostic_rate)
        self._period_ns = self._diag_timer.timer_period_ns
        if self.log is not None:
            self.log.add_metadata(NODE_NAME, self._metadata(config))

    def close(self) -> None:
        """Take the requests still waiting, record the last intake counts and refused requests,
        then finish the MCAP file (summary written)."""
        try:
            for topic in (ACKNOWLEDGE_TOPIC, SHELVE_TOPIC):
                for taken in self._requests.take(topic):
                    self._request(topic, taken)
            self._report_intake(time.monotonic(), force=True)
            for key, n in self._limit.due(time.monotonic(), every_one=True):
                why = f'over the rate limit of its publisher ({limit_text()})'
                self._refuse(key.partition(' ')[0], '', why, '', self._named.get(key, key), n)
        except Exception as exc:  # noqa: BLE001 - closing the log matters more
            self.get_logger().error(f'last intake counts not recorded: {exc}')
        try:
            self._save_fatigue(force=True)
        except Exception as exc:  # noqa: BLE001 - closing the log matters more
            self.get_logger().error(f'fatigue store not written at the end: {exc}')
        if self.log is not None:
            self.log.close()

    def destroy_node(self) -> None:
        """Destroy the request topics' helper node, then this one."""
        self._requests.close()
        super().destroy_node()


_FLOAT64_LE = struct.Struct('<d')


def float64_value(raw: bytes) -> float:
    """The value of a serialized ``std_msgs/Float64`` (little-endian CDR read in place)."""
    if len(raw) == 12 and raw[:2] == b'\x00\x01':
        return float(_FLOAT64_LE.unpack_from(raw, 4)[0])
    return float(deserialize_message(raw, Float64).data)


class OutputEncoder:
    """Serialized outputs (``Float64MultiArray``) from their values: the layout, which never
    changes, serialized once; the values packed after it (little-endian CDR; rclpy's
    serializer where it is not)."""

    def __init__(self, template: Float64MultiArray) -> None:
        self.template = template
        n = len(OUTPUT_FIELDS)
        template.data = [0.0] * n
        whole = serialize_message(template)
        self.prefix = whole[: -8 * n] if whole[:2] == b'\x00\x01' else None
        self.pack = struct.Struct(f'<{n}d').pack

    def __call__(self, values: Sequence[float]) -> bytes:
        if self.prefix is None or len(values) != len(OUTPUT_FIELDS):
            self.template.data = list(values)
            return serialize_message(self.template)
        return self.prefix + self.pack(*values)


def _fields(data: bytes, type_name: str) -> tuple[dict[str, float], Optional[int]]:
    """A raw input message's fields (core.rules.readings) and its header stamp in ns (None
    for a type without a header)."""
    if type_name == 'std_msgs/msg/Float64':
        return {'value': float64_value(data)}, None
    msg = deserialize_message(data, _MESSAGE_CLASSES[type_name])
    stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
    if type_name == readings.WRENCH:
        f = msg.wrench.force
        return {'x': f.x, 'y': f.y, 'z': f.z}, stamp
    if type_name == readings.FLUID_PRESSURE:
        return {'fluid_pressure': msg.fluid_pressure}, stamp
    return {'range': msg.range, 'min_range': msg.min_range, 'max_range': msg.max_range}, stamp


def _has_events_executor() -> bool:
    try:
        from rclpy.experimental import EventsExecutor  # noqa: F401
    except ImportError:
        return False
    return True


def _make_executor() -> Any:
    """rclpy's EventsExecutor where available (several times cheaper per message), else the
    SingleThreadedExecutor; ``CATENARY_MONITOR_EXECUTOR=single`` forces the latter."""
    if _events_executor_wanted():
        try:
            from rclpy.experimental import EventsExecutor

            return EventsExecutor()
        except ImportError:
            pass
    return SingleThreadedExecutor()


def _install_signal_handlers(stop: threading.Event) -> None:
    """SIGINT/SIGTERM end the spin loop between callbacks (never inside a publish)."""

    def handler(signum: int, frame: Any) -> None:
        stop.set()

    signal.signal(signal.SIGINT, handler)
    signal.signal(signal.SIGTERM, handler)


def _one_line(text: object) -> str:
    return ' '.join(str(text).split())


def _params_files(argv: Sequence[str]) -> list[str]:
    """The ``--params-file FILE`` values among the ``--ros-args`` of ``argv``."""
    files, in_ros = [], False
    for k, arg in enumerate(argv):
        if arg == '--ros-args':
            in_ros = True
        elif arg == '--':
            in_ros = False
        elif in_ros and arg == '--params-file' and k + 1 < len(argv):
            files.append(argv[k + 1])
    return files


def _check_params_files(argv: Sequence[str]) -> tuple[Optional[str], list[str]]:
    """One line naming the problem of the first bad params file (before rcl sees it), or None;
    and the files that hold no section for this node (empty, or not a params mapping).

    The project's loader follows rcl's YAML rules, so a file refused here is one rcl refuses
    (with a two-line log and a vaguer reason); any bytes, a directory or an unreadable path
    give a :class:`ConfigError` line, never a traceback.
    """
    empty = []
    for path in _params_files(argv):
        try:
            if not load_params_file(path):
                empty.append(path)
        except ConfigError as err:
            return str(err), empty
    return None, empty


def _hint(err: ConfigError, empty: list[str]) -> str:
    """The start error, naming the params files that gave this node nothing."""
    if err.parameter != 'lines' or not empty:
        return str(err)
    files = ', '.join(repr(f) for f in empty)
    return f'{err} ({files}: no {NODE_NAME} or /** section with ros__parameters)'


def main(
    args: Optional[Sequence[str]] = None,
    log_dir: Optional[str] = None,
    start_note: Optional[str] = None,
) -> int:
    """Run the node until SIGINT/SIGTERM; exit 2 with one line on a bad parameter or a bad
    params file. ``start_note`` is logged once the node has started (``run``'s discovery
    line)."""
    argv = list(sys.argv if args is None else args)
    problem, empty = _check_params_files(argv)
    if problem is not None:
        print(f'{NODE_NAME}: {problem}', file=sys.stderr)
        return 2
    stop = threading.Event()
    _install_signal_handlers(stop)
    use_announce_profile()  # met within 1 s by a harbour or console joining later
    try:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # noqa: BLE001 - rcl rejects an unreadable params file here
        print(f'{NODE_NAME}: cannot start: {_one_line(exc)}', file=sys.stderr)
        return 2
    extra = rclpy.utilities.remove_ros_args(argv)[1:]
    node = None
    executor: Any = None
    try:
        if extra:
            print(
                f'{NODE_NAME}: unexpected argument {extra[0]!r} (use --ros-args --params-file '
                'FILE)',
                file=sys.stderr,
            )
            return 2
        try:
            node = CatenaryMonitor(log_dir=log_dir)
        except ConfigError as err:
            print(f'{NODE_NAME}: {_hint(err, empty)}', file=sys.stderr)
            return 2
        if start_note:
            node.get_logger().info(start_note)
        executor = _make_executor()
        executor.add_node(node)
        # The signal handler only sets ``stop``, seen within 0.2 s, so a signal never lands
        # inside a publish. (The EventsExecutor's spin_once() without a timeout busy-waits.)
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.2)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.close()
            node.get_logger().info('stopped; MCAP log closed')
            if executor is not None:  # its event queue ends before the node it calls into
                executor.shutdown()
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
