"""The live monitor: the rclpy node ``catenary_monitor`` (console script ``monitor``).

Imperative shell only. The node wires topics, parameters, timers and the MCAP logger to the
core: ``config`` validates the parameters, ``solve`` does the physics, ``alarms`` decides levels
and transitions, ``health`` decides the tide and logger statuses. No physics and no threshold
comparison live here.

Run it as ``monitor --ros-args --params-file FILE`` (``ros2 run catenary_monitor monitor ...``),
``python -m catenary_monitor.ros.node --ros-args --params-file FILE`` or
``catenary-monitor run --params-file FILE [--log-dir DIR]``.
"""
from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
import traceback
from functools import partial, wraps
from typing import Any, Optional, Sequence

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, qos_profile_sensor_data
from rclpy.serialization import deserialize_message, serialize_message
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension

from catenary_monitor import __version__
from catenary_monitor.core import elastic
from catenary_monitor.core.alarms import AlarmInputs, Level, LineAlarm, diagnostic_values
from catenary_monitor.core.config import (ConfigError, MonitorConfig, ParamSpec,
                                          config_from_params, config_hash, config_to_params,
                                          expand_parameters)
from catenary_monitor.core.health import logger_status, tide_status
from catenary_monitor.core.solve import SolveResult, solve
from catenary_monitor.io.mcap_log import McapLogger

__all__ = ['NODE_NAME', 'OUTPUT_FIELDS', 'CatenaryMonitor', 'main']

#: Node name (params files use it as their top key; ``/**`` works too).
NODE_NAME = 'catenary_monitor'

#: Element order of each line's ``~/NAME/outputs`` Float64MultiArray (SI; ``status`` is the
#: solver code, -1 while no depth has been received; ``level`` the diagnostic level 0-3).
OUTPUT_FIELDS = ('top_tension', 'depth', 'horizontal_tension', 'min_anchor_distance',
                 'anchor_margin', 'uplift_force', 'tide_margin', 'load_margin', 'safety_factor',
                 'anchor_angle_deg', 'suspended_length', 'status', 'level')

_RESULT_FIELDS = OUTPUT_FIELDS[:-2]
_NAN = math.nan
_PARAM_TYPES = {'double': Parameter.Type.DOUBLE, 'string': Parameter.Type.STRING,
                'string_array': Parameter.Type.STRING_ARRAY}
_RELIABLE = QoSProfile(depth=10)


def _guarded(method: Any) -> Any:
    """Keep monitoring through an unexpected exception in a callback: log it and go on."""
    @wraps(method)
    def wrapper(self: 'CatenaryMonitor', *args: Any) -> Any:
        try:
            return method(self, *args)
        except Exception:  # noqa: BLE001 - one bad sample must not stop the monitor
            self.callback_errors += 1
            if self.callback_errors <= 10:
                self.get_logger().error(f'{method.__name__} failed (monitoring goes on): '
                                        + traceback.format_exc())
            return None
    return wrapper


def _descriptor(spec: ParamSpec, name: str) -> ParameterDescriptor:
    """ParameterDescriptor (description, unit, range, read-only) from one PARAMETERS row."""
    unit = f' [{spec.unit}]' if spec.unit else ''
    constraints = [f'unit: {spec.unit}'] if spec.unit else []
    desc = ParameterDescriptor(name=name, type=_PARAM_TYPES[spec.type].value,
                               description=spec.description + unit, read_only=spec.read_only)
    if spec.min is not None or spec.max is not None:
        low = -sys.float_info.max if spec.min is None else float(spec.min)
        high = sys.float_info.max if spec.max is None else float(spec.max)
        desc.floating_point_range = [FloatingPointRange(from_value=low, to_value=high, step=0.0)]
        constraints.append(f'range: [{low:g}, {high:g}]')
    desc.additional_constraints = '; '.join(constraints)
    return desc


class _Line:
    """Runtime state of one chain: its constants, newest inputs, alarm state and publisher."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.tension = _NAN          # N, newest sample
        self.tension_stamp = _NAN    # s, node clock at receipt
        self.inputs = AlarmInputs()  # newest solved update, handed again by the periodic check
        self.values: dict[str, float] = dict.fromkeys(_RESULT_FIELDS, _NAN)
        self.model = 'none'  # model of the newest solved update ('none' before the first one)
        self.state: Any = None
        self.alarm: Any = None
        self.config: Any = None
        self.output_topic = ''
        self.tension_topic = ''
        self.publisher: Any = None
        self.message = Float64MultiArray()
        self.message.layout.dim = [MultiArrayDimension(
            label=','.join(OUTPUT_FIELDS), size=len(OUTPUT_FIELDS), stride=len(OUTPUT_FIELDS))]


class CatenaryMonitor(Node):
    """Subscribes to every chain's hook tension and the tide depth; publishes results,
    diagnostics and alarms; logs every input and output message to MCAP."""

    def __init__(self, *, log_dir: Optional[str] = None, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, automatically_declare_parameters_from_overrides=False,
                         **kwargs)
        self.config = self._declare_parameters(log_dir)
        self._clock = self.get_clock()
        self._started = self._now()
        self._depth = _NAN
        self._depth_stamp = _NAN
        self._tide: tuple[Level, str] = (Level.OK, '')
        self._logger_state: tuple[Level, str] = (Level.OK, '')
        self._log_setup_error = ''
        self.callback_errors = 0
        self.lines = [_Line(line.name) for line in self.config.lines]
        self._apply_config(self.config)
        for line in self.lines:
            line.state = line.alarm.initial()
        self.log = self._open_log()
        self._create_interfaces()
        self.add_on_set_parameters_callback(self._validate_change)
        self.add_post_set_parameters_callback(self._apply_change)
        self.get_logger().info(
            f'monitoring {len(self.lines)} lines ({", ".join(l.name for l in self.lines)}), '
            f'depth from {self.config.depth_topic}, log in {self._log_dir()}')

    # ------------------------------------------------------------------ set-up
    def _declare_parameters(self, log_dir: Optional[str]) -> MonitorConfig:
        """Validate the overrides with ``config`` (one-line ConfigError), then declare them all."""
        # rclpy keeps the params-file and -p values here; it has no public getter for them.
        flat = {name: p.value for name, p in self._parameter_overrides.items()}
        if log_dir is not None:
            flat['log_dir'] = log_dir
        config = config_from_params(flat)
        values = config_to_params(config)
        for name, spec in expand_parameters([line.name for line in config.lines]):
            value = values[name]
            if spec.type == 'string_array':
                value = list(value)
            self.declare_parameter(name, value, _descriptor(spec, name), ignore_override=True)
        for line in config.lines:
            if line.ea is not None:
                self.get_logger().info(
                    f'{line.name}: EA = {line.ea:g} N, elastic catenary wherever it changes the answer by '
                    f'more than {elastic.ELASTIC_TOL:g} (diagnostics key "model")')
        return config

    def _apply_config(self, config: MonitorConfig) -> None:
        """Take line constants and alarm rules from ``config`` (alarm states are kept)."""
        self.config = config
        for line in self.lines:
            lc = config.line(line.name)
            line.config = lc
            line.alarm = LineAlarm.for_line(lc, config.alarm)

    def _log_dir(self) -> str:
        return os.path.expanduser(self.config.log_dir)

    def _open_log(self) -> Optional[McapLogger]:
        """The MCAP logger (never raises on disk errors: those become its ``error``)."""
        try:
            # Flushed at 0.75 s age, checked every 0.25 s: a SIGKILL loses at most the last second.
            log = McapLogger(self._log_dir(), prefix=NODE_NAME, flush_period=0.75)
            log.add_metadata(NODE_NAME, self._metadata(self.config))
            return log
        except Exception as exc:  # noqa: BLE001 - logging must never stop the monitoring
            self._log_setup_error = f'cannot start the MCAP logger: {exc}'
            self.get_logger().error(self._log_setup_error)
            return None

    @staticmethod
    def _metadata(config: MonitorConfig) -> dict[str, str]:
        """MCAP metadata record: version, configuration and its hash, output layout."""
        return {'version': __version__, 'config_hash': config_hash(config),
                'parameters': json.dumps(config_to_params(config), sort_keys=True),
                'output_fields': ','.join(OUTPUT_FIELDS), 'units': 'SI (N, m, s)'}

    def _register(self, topic: str, type_name: str, qos: str) -> None:
        if self.log is None:
            return
        try:
            self.log.register(topic, type_name, qos)
        except Exception as exc:  # noqa: BLE001
            self.get_logger().error(f'cannot log {topic} to MCAP: {exc}')

    def _create_interfaces(self) -> None:
        """Subscriptions (sensor-data QoS, raw CDR), publishers and timers."""
        cfg = self.config
        for line in self.lines:
            sub = self.create_subscription(
                Float64, line.config.tension_topic, partial(self._on_tension, line),
                qos_profile_sensor_data, raw=True)
            line.tension_topic = sub.topic_name
            self._register(sub.topic_name, 'std_msgs/msg/Float64', 'sensor_data')
            line.publisher = self.create_publisher(
                Float64MultiArray, f'~/{line.name}/outputs', _RELIABLE)
            line.output_topic = line.publisher.topic_name
            self._register(line.output_topic, 'std_msgs/msg/Float64MultiArray', 'default')
        sub = self.create_subscription(Float64, cfg.depth_topic, self._on_depth,
                                       qos_profile_sensor_data, raw=True)
        self._depth_topic = sub.topic_name
        self._register(self._depth_topic, 'std_msgs/msg/Float64', 'sensor_data')
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', _RELIABLE)
        self._register('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray', 'default')
        self._diag_timer = self.create_timer(1.0 / cfg.alarm.diagnostic_rate, self._on_period)
        self._log_timer = self.create_timer(0.25, self._on_log_timer)

    # ------------------------------------------------------------------ callbacks
    def _now(self) -> float:
        return self._clock.now().nanoseconds * 1e-9

    @_guarded
    def _on_tension(self, line: _Line, data: bytes) -> None:
        """A hook tension sample (N): log it, solve the line, alarm, publish."""
        now_ns = self._clock.now().nanoseconds
        self._write(line.tension_topic, data, now_ns)
        line.tension = deserialize_message(data, Float64).data
        line.tension_stamp = now_ns * 1e-9
        if math.isnan(self._depth_stamp):
            self._update(line, None, now_ns)
        else:
            self._update(line, self._solve_one(line), now_ns)

    @_guarded
    def _on_depth(self, data: bytes) -> None:
        """A depth sample (m): log it, solve every line that has a tension (one array call)."""
        now_ns = self._clock.now().nanoseconds
        self._write(self._depth_topic, data, now_ns)
        self._depth = deserialize_message(data, Float64).data
        self._depth_stamp = now_ns * 1e-9
        self._check_tide(now_ns * 1e-9)
        lines = [line for line in self.lines if not math.isnan(line.tension_stamp)]
        if lines:
            self._update_many(lines, self._solve_many(lines), now_ns)

    @_guarded
    def _on_period(self) -> None:
        """Steady diagnostics: re-check every line (staleness) and publish /diagnostics."""
        self._tick(self._clock.now().nanoseconds)

    def _tick(self, now_ns: int) -> None:
        """Step every line with its last inputs at ``now_ns`` and publish (logged at ``now_ns``).

        Every /diagnostics message not logged at an input's receive time is such a tick, so
        replay can take the logged /diagnostics times as the node's ticks.
        """
        now = now_ns * 1e-9
        self._check_tide(now)
        self._check_logger()
        for line in self.lines:
            self._step_alarm(line, line.inputs, now)
        self._publish_diagnostics(now_ns)

    @_guarded
    def _on_log_timer(self) -> None:
        """Flush the MCAP chunk when due (bounded loss on SIGKILL); report logger changes."""
        if self.log is not None:
            self.log.tick()
        if self._check_logger():
            self._tick(self._clock.now().nanoseconds)

    # ------------------------------------------------------------------ core calls
    def _solve_one(self, line: _Line) -> SolveResult:
        """Solve one line at the newest depth (the core's scalar fast path; with ``ea``, the
        elastic model's rule)."""
        lc = line.config
        return solve(lc.weight, self._depth + lc.hook_height, tension=line.tension,
                     anchor_distance=lc.anchor_distance, mbl=lc.mbl, ea=lc.ea)

    def _solve_many(self, lines: Sequence[_Line]) -> SolveResult:
        """Solve several lines at the newest depth in one vectorized call (lines without ``ea``
        get EA = inf there, which keeps the inextensible answer bit for bit)."""
        cfgs = [line.config for line in lines]
        args = (np.array([c.weight for c in cfgs]), self._depth + np.array([c.hook_height for c in cfgs]),
                np.array([line.tension for line in lines]))
        kw = dict(anchor_distance=np.array([c.anchor_distance for c in cfgs]), mbl=np.array([c.mbl for c in cfgs]))
        if any(c.ea is not None for c in cfgs):
            ea = np.array([math.inf if c.ea is None else c.ea for c in cfgs])
            return elastic.solve_with_correction(*args, ea=ea, **kw)[0]
        return solve(args[0], args[1], tension=args[2], **kw)

    def _update_many(self, lines: Sequence[_Line], result: SolveResult, now_ns: int) -> None:
        messages = result.message
        models = np.broadcast_to(np.asarray(result.model, dtype=object), np.shape(result.status))
        columns = {k: np.asarray(getattr(result, k)).tolist() for k in _RESULT_FIELDS
                   if k != 'depth'}
        for i, line in enumerate(lines):
            values = {k: v[i] for k, v in columns.items()}
            self._update(line, (values, int(result.status[i]), str(messages[i]), str(models[i])), now_ns)

    def _update(self, line: _Line, result: Any, now_ns: int) -> None:
        """Hand one solved update to the alarm, publish the outputs, report a level change."""
        now = now_ns * 1e-9
        if result is None:  # no depth yet: nothing to solve
            values, status, text, line.model = dict.fromkeys(_RESULT_FIELDS, _NAN), -1, '', 'none'
        elif isinstance(result, SolveResult):  # a scalar solve
            values = {k: getattr(result, k) for k in _RESULT_FIELDS if k != 'depth'}
            status, text, line.model = result.status, result.message, result.model
        else:  # (values, status, message, model) of one element of a vectorized solve
            values, status, text, line.model = result
        values['top_tension'] = line.tension  # the measured tension, solved or not
        values['depth'] = self._depth + line.config.hook_height
        values['status'] = float(status)
        line.values = values
        line.inputs = AlarmInputs(
            uplift_force=values['uplift_force'], anchor_margin=values['anchor_margin'],
            tide_margin=values['tide_margin'], load_margin=values['load_margin'],
            safety_factor=values['safety_factor'], status=max(status, 0), status_message=text,
            tension_stamp=line.tension_stamp, depth_stamp=self._depth_stamp)
        changed = self._step_alarm(line, line.inputs, now)
        msg = line.message
        msg.data = [values[k] for k in _RESULT_FIELDS] + [values['status'],
                                                          float(line.state.level)]
        data = serialize_message(msg)
        line.publisher.publish(data)
        self._write(line.output_topic, data, now_ns)
        if changed:
            self._publish_diagnostics(now_ns)

    def _step_alarm(self, line: _Line, inputs: AlarmInputs, now: float) -> bool:
        """Advance the line's alarm state; log each transition. True if the level changed."""
        line.state, events = line.alarm.update(line.state, inputs, now)
        for ev in events:
            took = '' if ev.duration is None else f' (after {ev.duration:.1f} s)'
            text = f'ALARM {line.name}: {ev.old.name} -> {ev.new.name}: {ev.message}{took}'
            # rclpy fixes the severity per call site: one call per severity.
            if ev.new == Level.ERROR:
                self.get_logger().error(text)
            elif ev.new == Level.OK:
                self.get_logger().info(text)
            else:
                self.get_logger().warning(text)
        return bool(events)

    def _check_tide(self, now: float) -> None:
        self._tide = tide_status(self._depth, self._depth_stamp, now, self._started,
                                 self.config.alarm.depth_timeout)

    def _check_logger(self) -> bool:
        """Refresh the logger status; True if its level changed."""
        if self.log is None:
            state = logger_status(self._log_setup_error or 'no logger', None)
        else:
            path = self.log.current_path
            state = logger_status(self.log.error, str(path) if path else None)
        changed = state[0] != self._logger_state[0]
        if changed and state[0] != Level.OK:
            self.get_logger().error(state[1])
        self._logger_state = state
        return changed

    # ------------------------------------------------------------------ output
    def _write(self, topic: str, data: bytes, now_ns: int) -> None:
        if self.log is not None:
            self.log.write(topic, data, now_ns)

    def _line_status(self, line: _Line, now: float) -> DiagnosticStatus:
        values = diagnostic_values(line.values)
        extra = [('measured_tension', repr(float(line.tension))),
                 ('tension_age', repr(now - line.tension_stamp)),
                 ('anchor_distance', repr(line.config.anchor_distance)),
                 ('allowed_uplift', repr(line.config.allowed_uplift)),
                 ('anchor_angle_deg', repr(float(line.values['anchor_angle_deg']))),
                 ('solver_status', str(int(line.values.get('status', -1)))),
                 ('model', line.model)]
        return DiagnosticStatus(
            level=bytes([int(line.state.level)]), name=f'{NODE_NAME}: {line.name}',
            message=line.state.message, hardware_id=line.tension_topic,
            values=[KeyValue(key=k, value=v) for k, v in values + extra])

    def _publish_diagnostics(self, now_ns: int) -> None:
        """One DiagnosticArray at node time ``now_ns``: every line, then the tide and the logger."""
        now = now_ns * 1e-9
        array = DiagnosticArray()
        array.header.stamp.sec, array.header.stamp.nanosec = divmod(now_ns, 10**9)
        array.status = [self._line_status(line, now) for line in self.lines]
        level, text = self._tide
        array.status.append(DiagnosticStatus(
            level=bytes([int(level)]), name=f'{NODE_NAME}: tide', message=text,
            hardware_id=self._depth_topic,
            values=[KeyValue(key='depth', value=repr(float(self._depth))),
                    KeyValue(key='depth_age', value=repr(now - self._depth_stamp))]))
        level, text = self._logger_state
        log_values = self.log.diagnostic_values() if self.log is not None else {}
        array.status.append(DiagnosticStatus(
            level=bytes([int(level)]), name=f'{NODE_NAME}: logger', message=text,
            hardware_id=self._log_dir(),
            values=[KeyValue(key=k, value=v) for k, v in log_values.items()]))
        data = serialize_message(array)
        self._diag_pub.publish(data)
        self._write('/diagnostics', data, now_ns)

    # ------------------------------------------------------------------ parameters
    def _current_params(self) -> dict[str, Any]:
        return {name: p.value for name, p in self._parameters.items()}

    def _validate_change(self, params: list[Parameter]) -> SetParametersResult:
        """Reject a change that ``config`` rejects, with its one-line reason; no side effects."""
        flat = self._current_params()
        flat.update({p.name: p.value for p in params})
        try:
            config_from_params(flat)
        except ConfigError as err:
            return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _apply_change(self, params: list[Parameter]) -> None:
        """Apply an accepted change: new line constants and alarm rules, states kept."""
        config = config_from_params(self._current_params())
        self._apply_config(config)
        self._diag_timer.timer_period_ns = int(1e9 / config.alarm.diagnostic_rate)
        if self.log is not None:
            self.log.add_metadata(NODE_NAME, self._metadata(config))
        self.get_logger().info('parameters changed: ' + ', '.join(
            f'{p.name}={p.value!r}' for p in params))

    def close(self) -> None:
        """Finish the MCAP file (summary written)."""
        if self.log is not None:
            self.log.close()


def _make_executor() -> Any:
    """rclpy's EventsExecutor where available (several times cheaper per message), else the
    SingleThreadedExecutor; ``CATENARY_MONITOR_EXECUTOR=single`` forces the latter."""
    if os.environ.get('CATENARY_MONITOR_EXECUTOR', 'events') != 'single':
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


def _one_line(text: str) -> str:
    return ' '.join(str(text).split())


def main(args: Optional[Sequence[str]] = None, log_dir: Optional[str] = None) -> int:
    """Run the node until SIGINT/SIGTERM; exit 2 with one line on a bad parameter."""
    argv = list(sys.argv if args is None else args)
    stop = threading.Event()
    _install_signal_handlers(stop)
    try:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # noqa: BLE001 - rcl rejects an unreadable params file here
        print(f'{NODE_NAME}: cannot start: {_one_line(exc)}', file=sys.stderr)
        return 2
    extra = rclpy.utilities.remove_ros_args(argv)[1:]
    node = None
    try:
        if extra:
            print(f'{NODE_NAME}: unexpected argument {extra[0]!r} (use --ros-args --params-file '
                  'FILE)', file=sys.stderr)
            return 2
        try:
            node = CatenaryMonitor(log_dir=log_dir)
        except ConfigError as err:
            print(f'{NODE_NAME}: {err}', file=sys.stderr)
            return 2
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
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
