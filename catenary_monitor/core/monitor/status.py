"""The statuses the core publishes on /diagnostics, built from its state.

:class:`ComponentStatus` (one ``DiagnosticStatus``), :class:`Snapshot` (one
``DiagnosticArray``) and :class:`Change` (a level transition of one component); each line's
status (:func:`line_status`) and the components' (:func:`tide_component`,
:func:`sensors_component`, :func:`dock_component`), with the words their values take. The core
and its vectorized twin build them alike.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, Sequence

from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.alarms import components as component_alarm
from catenary_monitor.core.alarms.latches import (
    CONDITIONS,
    VIEW_TEXT,
    Transition,
    diagnostic_values,
)
from catenary_monitor.core.alarms.texts import (
    active_conditions,
    component_condition,
    status_texts,
)
from catenary_monitor.core.config.parameters import LineConfig, MonitorConfig
from catenary_monitor.core.monitor.events import NODE_NAME
from catenary_monitor.core.monitor.state import VALUE_FIELDS, LineState
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules import sensor_state
from catenary_monitor.core.rules.level import RANK, Level

__all__ = [
    'ComponentStatus',
    'Snapshot',
    'Change',
    'line_status',
    'view_word',
    'line_dock_values',
    'line_dock_word',
    'forecast_word',
    'tide_with_sensor',
    'depth_word',
    'sensors_component',
    'dock_component',
    'tide_component',
    'with_texts',
    'consequence_state',
]

_INCONSISTENT = CONDITIONS.index('inconsistent')


class ComponentStatus(NamedTuple):
    """One ``DiagnosticStatus``: name, level, message, hardware id and ``(key, value)`` strings."""

    name: str
    level: Level
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]


class Snapshot(NamedTuple):
    """One ``DiagnosticArray`` at ``stamp_ns``: every line, then the tide, then the logger."""

    stamp_ns: int
    statuses: tuple[ComponentStatus, ...]


class Change(NamedTuple):
    """A level transition of one component (a line name, ``tide`` or ``logger``)."""

    component: str
    transition: Transition


def line_status(
    config: LineConfig,
    hardware_id: str,
    level: Level,
    message: str,
    values: Sequence[float],
    status: int,
    model: str,
    tension_age: float,
    sensor_word: str = 'ok',
    extra: Sequence[tuple[str, str]] = (),
    latches: Sequence[bool] = (),
    responses: Sequence[tuple[str, str]] = (),
) -> ComponentStatus:
    """One line's ``DiagnosticStatus``: the contract keys (SI strings ``float()`` reads back
    exactly), then ``measured_tension``, ``tension_age`` [s], ``anchor_distance``,
    ``allowed_uplift``, ``anchor_angle_deg``, ``solver_status``, ``model``, ``sensor_state``
    (:func:`catenary_monitor.core.rules.sensor_state.line_word`), ``time_to_uplift_view``
    (:func:`view_word`), ``span`` [m] and ``span_source`` (the span the line was solved at and
    its source: :func:`catenary_monitor.core.rules.dock_watch.span_word`), then ``extra``
    (the alarm's acknowledgement keys:
    :func:`~catenary_monitor.core.alarms.acknowledge.diagnostic_values`; with the dock model,
    :func:`line_dock_values`), then ``conditions``, ``detail`` and ``response``
    (:func:`~catenary_monitor.core.alarms.texts.status_texts`: the ``message`` is the
    headline of the alarm's full ``message``; ``latches`` the active flags of its conditions,
    ``responses`` the configured response texts)."""
    named = dict(zip(VALUE_FIELDS, values))
    pairs = diagnostic_values(named) + [
        ('measured_tension', repr(float(values[0]))),
        ('tension_age', repr(float(tension_age))),
        ('anchor_distance', repr(config.anchor_distance)),
        ('allowed_uplift', repr(config.allowed_uplift)),
        ('anchor_angle_deg', repr(float(values[9]))),
        ('solver_status', str(int(status))),
        ('model', model),
        ('sensor_state', sensor_word),
        ('time_to_uplift_view', view_word(named['time_to_uplift_view'])),
        ('span', repr(float(named['span']))),
        ('span_source', dock_live.span_word(named['span_source'])),
        *extra,
    ]
    condition = next((v for k, v in extra if k == 'alarm_condition'), 'none')
    active = active_conditions(latches, level == Level.STALE)
    head, texts = status_texts(message, level == Level.OK, condition, responses, active)
    return ComponentStatus(
        f'{NODE_NAME}: {config.name}', level, head, hardware_id, tuple(pairs) + texts
    )


def with_texts(
    status: ComponentStatus, responses: Sequence[tuple[str, str]] = ()
) -> ComponentStatus:
    """A component's status (not a line's) with its headline as ``message`` and the values
    ``conditions``, ``detail`` and ``response``
    (:func:`~catenary_monitor.core.alarms.texts.status_texts`)."""
    condition = component_condition(status.name)
    head, texts = status_texts(status.message, status.level == Level.OK, condition, responses)
    return status._replace(message=head, values=status.values + texts)


def view_word(view: float) -> str:
    """Which view a time to uplift counts down (``/diagnostics`` ``time_to_uplift_view``):
    ``chain length held``, ``horizontal tension held`` or ``none`` (no solve)."""
    return VIEW_TEXT.get(float(view), 'none')


def line_dock_values(latched: bool, dock: Sequence[float]) -> tuple[tuple[str, str], ...]:
    """A line's dock-model values: ``residual`` (measured - expected, N), ``expected_tension``
    (N) and ``residual_sigma`` (normalized residual); its word for ``sensor_state`` is
    :func:`line_dock_word`."""
    flag, residual, expected, sigma = dock
    return (
        ('residual', repr(float(residual))),
        ('expected_tension', repr(float(expected))),
        ('residual_sigma', repr(float(sigma))),
    )


def line_dock_word(line: LineState) -> str:
    """The dock model's ``sensor_state`` word of a line (:func:`dock_live.sensor_state`)."""
    return dock_live.sensor_state(line.state.latches[_INCONSISTENT].active, line.dock[0])


def forecast_word(config: MonitorConfig, rate: float) -> str:
    """What the times to uplift follow: ``table`` (a tide table is configured), ``trend``
    (the tide's trend is known) or ``unknown``."""
    if config.alarm.constituents:
        return 'table'
    return 'trend' if math.isfinite(rate) else 'unknown'


def tide_with_sensor(
    tide: tuple[Level, str],
    code: int,
    depth: float,
    config: Any,
    chart: tuple[float, float] | None = None,
) -> tuple[Level, str]:
    """The tide's (level, message) with the depth sensor's state: the worse level (stuck and
    spike WARN, out_of_range ERROR), the sensor's message appended."""
    if code == sensor_state.OK:
        return tide
    level = Level.ERROR if code == sensor_state.OUT_OF_RANGE else Level.WARN
    text = sensor_state.depth_message(code, depth, config, chart)
    if tide[0] == Level.OK:
        return level, text
    return (tide[0] if RANK[tide[0]] >= RANK[level] else level), f'{tide[1]}; {text}'


def depth_word(depth_s: float, code: int) -> str:
    """The depth sensor's ``sensor_state`` word: ``no_data`` before the first depth sample
    (``depth_s`` NaN), else its state
    (:data:`catenary_monitor.core.rules.sensor_state.DEPTH_STATES`).
    """
    return sensor_state.NO_DATA if depth_s != depth_s else sensor_state.DEPTH_STATES[code]


def sensors_component(
    state: tuple[Level, str], ack: alarm_ack.AckState, waiting: int
) -> ComponentStatus:
    """The ``catenary_monitor: sensors`` status: the common-cause alarm's level and message
    (:func:`catenary_monitor.core.rules.health.sensors_status`), ``lines_waiting`` (lines with no
    tension since the start) and the alarm's acknowledgement keys
    (:func:`~catenary_monitor.core.alarms.acknowledge.diagnostic_values`)."""
    values = (('lines_waiting', str(waiting)),) + tuple(
        alarm_ack.diagnostic_values(ack, state[0], ())
    )
    return ComponentStatus(f'{NODE_NAME}: sensors', state[0], state[1], NODE_NAME, values)


#: ``alarm_state`` of a component status whose STALE is a consequence of blind inputs (the
#: tide's, the dock's): shown, not annunciated (the ``sensors`` alarm announces the cause).
_CONSEQUENCE_STATES = {Level.OK: alarm_ack.NORMAL, Level.STALE: alarm_ack.SUPPRESSED}


def consequence_state(level: Level) -> str:
    """The ``alarm_state`` of the tide's or the dock's status at ``level``: ``normal`` (OK),
    ``suppressed`` (STALE: blind inputs, announced by the ``sensors`` alarm), else ``active``
    (annunciated when it rose)."""
    return _CONSEQUENCE_STATES.get(level, 'active')


def dock_component(
    dock: tuple[Level, str],
    values: tuple[tuple[str, str], ...],
    ack: alarm_ack.AckState = alarm_ack.AckState(),
) -> ComponentStatus:
    """The ``catenary_monitor: dock`` status: the estimate's level and message, values
    ``offset_x``, ``offset_y`` [m], ``yaw_deg``, ``load_x``, ``load_y`` [N], ``load_mz`` [N m],
    ``readings`` (NaN strings before the first estimate), then its alarm's keys ``alarm_state``,
    ``acknowledged``, ... (:func:`~catenary_monitor.core.alarms.components.values` of ``ack``)."""
    if not values:
        values = tuple((k, 'nan') for k in dock_live.DOCK_KEYS[:-1]) + (('readings', '0'),)
    values = values + component_alarm.values(ack, 'dock', dock[0])
    return ComponentStatus(f'{NODE_NAME}: dock', dock[0], dock[1], 'dock model', values)


def tide_component(
    tide: tuple[Level, str],
    hardware_id: str,
    depth: float,
    depth_age: float,
    rate: float = math.nan,
    sensor_word: str = 'ok',
    forecast: str = 'unknown',
    ack: alarm_ack.AckState = alarm_ack.AckState(),
) -> ComponentStatus:
    """The tide's ``DiagnosticStatus``: values ``depth`` [m], ``depth_age`` [s] and ``rate``
    [m/s], the trend (:mod:`~catenary_monitor.core.rules.tide_trend`; nan while unknown), and the
    depth sensor's ``sensor_state``
    (:data:`catenary_monitor.core.rules.sensor_state.DEPTH_STATES`) and
    ``tide_forecast``, what the times to uplift follow (:func:`forecast_word`), then its
    alarm's keys ``alarm_state``, ``acknowledged``, ...
    (:func:`~catenary_monitor.core.alarms.components.values` of ``ack``)."""
    return ComponentStatus(
        f'{NODE_NAME}: tide',
        tide[0],
        tide[1],
        hardware_id,
        (
            ('depth', repr(float(depth))),
            ('depth_age', repr(float(depth_age))),
            ('rate', repr(float(rate))),
            ('sensor_state', sensor_word),
            ('tide_forecast', forecast),
            *component_alarm.values(ack, 'tide', tide[0]),
        ),
    )
