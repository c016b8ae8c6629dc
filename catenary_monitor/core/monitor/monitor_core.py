"""The monitor core: one object that owns every decision of the live monitor (no rclpy, no clock).

:class:`MonitorCore` holds the per-line state (newest inputs and results, alarm states), the
tide and logger statuses, and turns each event into one :class:`Step`:

* :class:`Tension` (a hook tension sample of one line), :class:`Depth` (a tide depth sample),
  :class:`Tick` (the periodic step, at ``diagnostic_rate``), :class:`LoggerHealth` (the MCAP
  logger's state changed), :class:`Reconfigure` (accepted parameter change) and
  :class:`Acknowledge` (an operator acknowledged a line's alarm, or all:
  :mod:`catenary_monitor.core.alarms.acknowledge`) and :class:`Shelve` (an operator shelved or
  unshelved an alarm: :mod:`catenary_monitor.core.alarms.shelving`), each with its time
  ``stamp_ns`` (ns on the monitor's clock; events come in time order).

What an event does, in this order (the one schedule the node, replay and the tests share):

1. its input is taken: the line's newest tension, or the depth, stamped ``stamp_ns``;
2. at a depth event or a tick the tide is decided: its level and message, and whether the depth
   is stale (older than ``depth_timeout``), one decision that every line then takes;
3. lines are solved (``solve(..., ea=line.ea)``): a tension event solves its line at the newest
   depth (``depth + hook_height``); a depth event solves every line that has a tension;
4. alarms are stepped (:class:`~catenary_monitor.core.alarms.latches.LineAlarm`): the solved
   line at a tension event, every line at a depth event or a tick; each stepped line's
   acknowledgement state follows its level
   (:func:`catenary_monitor.core.alarms.acknowledge.step`);
5. the alarm flood is decided when the event raised an alarm and at a tick
   (:mod:`catenary_monitor.core.alarms.flood`);
6. a diagnostic snapshot is taken when the event is a tick or when any level changed: never two
   per event, so the statuses of one snapshot always agree.

The :class:`Step` carries the outputs of the lines solved (:data:`OUTPUT_FIELDS`), the snapshot
(or None), the level transitions and the alarm journal's records
(:mod:`catenary_monitor.core.alarms.journal`). A line is never OK while blind: before
its first tension and before the first depth it is STALE and says what is missing. Times in the
alarm logic are seconds (``stamp_ns * 1e-9``); forces N, lengths m.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple, Optional, Sequence, Union

import numpy as np

from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.config.parameters import (
    LineConfig,
    MonitorConfig,
    config_from_params,
    config_to_params,
    resolve_topic,
    runtime_change_messages,
)
from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.rules import channels
from catenary_monitor.core.alarms import flood as alarm_flood, shelving
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules import fatigue as fatigue_rule
from catenary_monitor.core.rules import holding as holding_rule
from catenary_monitor.core.rules import (
    readings,
    sensor_state,
    tide_table,
    tide_trend,
    uncertainty,
    wave_window,
)
from catenary_monitor.core.alarms.journal import AlarmEvent, entries
from catenary_monitor.core.alarms.latches import (
    CONDITIONS,
    AlarmInputs,
    AlarmState,
    LineAlarm,
    Transition,
    diagnostic_values,
    quiet_change,
)
from catenary_monitor.core.rules.level import RANK, Level
from catenary_monitor.core.alarms.latches import VIEW_TEXT
from catenary_monitor.core.rules.health import (
    BUSY_WINDOW,
    INTAKE_WINDOW,
    clock_status,
    intake_status,
    logger_status,
    missing_samples,
    parameters_status,
    sensors_status,
    tide_status,
)
from catenary_monitor.core.rules.plausible import (
    reading_status,
    reading_status_array,
    status_messages,
)
from catenary_monitor.core.physics import elastic
from catenary_monitor.core.physics.point_loads import PointLoads
from catenary_monitor.core.physics.solve import solve

__all__ = [
    'NODE_NAME',
    'OUTPUT_FIELDS',
    'VALUE_FIELDS',
    'NO_DEPTH',
    'NO_MODEL',
    'EVENTS_TOPIC',
    'Tension',
    'Depth',
    'Tick',
    'LoggerHealth',
    'Reconfigure',
    'Start',
    'Acknowledge',
    'Shelve',
    'ClockHealth',
    'Intake',
    'Coalesced',
    'FatigueStore',
    'Event',
    'LineOutput',
    'ComponentStatus',
    'Snapshot',
    'Change',
    'Step',
    'LineState',
    'MonitorCore',
    'line_status',
    'bound_values',
    'holding_values',
    'HOLDING_FIELDS',
    'holding_one',
    'derived_values',
    'view_word',
    'output_values',
    'tide_component',
    'sensors_component',
    'depth_word',
    'dock_component',
    'event_record',
    'parse_event_record',
]

#: Node name: the ``/diagnostics`` status names start with it; params files use it as top key.
NODE_NAME = 'catenary_monitor'
#: Element order of each line's outputs (``/catenary_monitor/NAME/outputs``), SI units;
#: ``status`` is the solver code (:data:`NO_DEPTH` before the first depth), ``level`` 0-3;
#: ``time_to_uplift`` [s] (:mod:`~catenary_monitor.core.rules.tide_trend`) was appended after
#: them so the older indexes stay, then the bounds
#: (:mod:`~catenary_monitor.core.rules.uncertainty`), the holding values
#: (:mod:`~catenary_monitor.core.rules.holding`) and ``sensor_state``, the line's sensor state
#: code as of the newest tick (:data:`catenary_monitor.core.rules.sensor_state.LINE_STATES`: 0
#: ok, 1 stuck, 2 spike, 3 over_mbl, 4 slack, 5 suspected_parted), then ``tide_margin_at_length``
#: [m] (:data:`catenary_monitor.core.rules.holding.LENGTH_FIELDS`), then ``wave_tension``,
#: ``peak_tension`` and ``dynamic_uplift`` [N] and ``time_to_uplift_view`` (1 chain length held,
#: 0 horizontal tension held), then ``span`` [m], the hook-anchor distance the line was solved
#: at, and ``span_source`` (0 the installed ``anchor_distance``, 1 the dock estimate:
#: :mod:`~catenary_monitor.core.rules.dock_watch`).
OUTPUT_FIELDS = (
    'top_tension',
    'depth',
    'horizontal_tension',
    'min_anchor_distance',
    'anchor_margin',
    'uplift_force',
    'tide_margin',
    'load_margin',
    'safety_factor',
    'anchor_angle_deg',
    'suspended_length',
    'status',
    'level',
    'time_to_uplift',
    # Margins with the sensors' accuracy: core/rules/uncertainty.py.
    *uncertainty.FIELDS,
    # Holding and the anchor distance the chain implies: core/rules/holding.py.
    *holding_rule.FIELDS,
    # Sensor sanity: core/rules/sensor_state.py.
    'sensor_state',
    # The tide margin of a chain of fixed length, its hook held: core/rules/holding.py.
    *holding_rule.LENGTH_FIELDS,
    # The anchor's drag state (0 holding, 1 overloaded, 2 dragging): core/rules/holding.py.
    *holding_rule.DRAG_FIELDS,
    # Chain fatigue (Miner's damage, its rate over the last day, the life left): fatigue.py.
    *fatigue_rule.FIELDS,
    # Wave-frequency tension and the dynamic uplift (core/rules/wave_window.py,
    # core/rules/uncertainty.py), then which view the time to uplift counts down (1 the chain
    # length held, 0 the horizontal tension held: core/rules/tide_trend.py).
    *wave_window.FIELDS,
    'dynamic_uplift',
    'time_to_uplift_view',
    # A line measured by several channels: the healthy count and their states, channels.py.
    *channels.FIELDS,
    # The span the line was solved at, and where it came from (core/rules/dock_watch.py).
    'span',
    'span_source',
)
#: The solved quantities among them (every field but ``status`` and ``level``).
VALUE_FIELDS = OUTPUT_FIELDS[:11] + OUTPUT_FIELDS[13:]
#: Solver status of an update made before any depth sample arrived.
NO_DEPTH = -1
#: ``model`` of a line that has not been solved yet.
NO_MODEL = 'none'
#: MCAP-only channel where the node records the events that are not input messages (ticks,
#: logger changes, reconfigurations), so that replay redoes every step exactly.
EVENTS_TOPIC = f'/{NODE_NAME}/events'

_NAN = math.nan
_INCONSISTENT = CONDITIONS.index('inconsistent')
_SOLVED = VALUE_FIELDS[2:11]  # taken from the solve result (the first two are the inputs)
#: The components whose STALE is a consequence of blind inputs, announced by the sensors alarm.
_CONSEQUENCES = ('tide', 'dock')
_NAN_VALUES = (_NAN,) * len(VALUE_FIELDS)
_AT = {key: i for i, key in enumerate(VALUE_FIELDS)}
_SENSOR_AT = VALUE_FIELDS.index('sensor_state')  # not a solved value: kept by _implausible


class Tension(NamedTuple):
    """A hook tension sample [N] of line number ``line`` (config order), received at
    ``stamp_ns``; ``sample_ns`` the sensor's header stamp (None: a message without one, taken
    at its arrival)."""

    stamp_ns: int
    line: int
    value: float
    sample_ns: Optional[int] = None
    channel: int = 0  # a line of several channels (NAME.tension_topics): which one


class Depth(NamedTuple):
    """A tide depth sample [m] at the hooks, received at ``stamp_ns``; ``sample_ns`` as for
    :class:`Tension`."""

    stamp_ns: int
    value: float
    sample_ns: Optional[int] = None


class Tick(NamedTuple):
    """The periodic step at ``stamp_ns`` (staleness and hold-time clears are decided here)."""

    stamp_ns: int


class LoggerHealth(NamedTuple):
    """The MCAP logger's state at ``stamp_ns``: ``error`` (None while it writes), its file and
    a ``warning`` (low disk space; None: none)."""

    stamp_ns: int
    error: Optional[str]
    path: Optional[str]
    warning: Optional[str] = None


class Start(NamedTuple):
    """Not an event but a record: the monitor started (blind) at ``stamp_ns``."""

    stamp_ns: int


class Reconfigure(NamedTuple):
    """Accepted parameter change at ``stamp_ns``: the new configuration (same lines)."""

    stamp_ns: int
    config: MonitorConfig


class Acknowledge(NamedTuple):
    """An operator acknowledged line ``line``'s alarm (None: every line) from ``origin`` (as
    the message claims), published by ``publisher`` (the middleware's identity of the sender:
    node and GID; empty when unknown)."""

    stamp_ns: int
    line: Optional[str]
    origin: str
    publisher: str = ''


class Shelve(NamedTuple):
    """An operator shelved ``alarm`` (a line, or ``sensors``) or one ``condition`` of it
    (:data:`~catenary_monitor.core.alarms.acknowledge.WHOLE`: the whole alarm) for
    ``seconds`` (0: unshelve it), from ``origin`` (as claimed), published by ``publisher``
    (the middleware's identity of the sender; '' from the console's page)."""

    stamp_ns: int
    alarm: str
    condition: str
    seconds: float
    origin: str
    publisher: str = ''


class ClockHealth(NamedTuple):
    """The ROS clock (``use_sim_time``) at ``stamp_ns``: ``stopped_for`` [s] of wall time
    without advancing (None: it advances)."""

    stamp_ns: int
    stopped_for: Optional[float]


class Intake(NamedTuple):
    """Samples since the previous Intake event: per line, then the depth, ``received``
    (handled: stepped), ``dropped`` (lost before the node took them) and ``coalesced`` (taken
    and logged, not stepped: a newer sample of the same input was handled instead; empty:
    none, as in logs from before coalescing); ``busy`` [s] of wall time spent in callbacks
    over ``period`` [s] of wall time."""

    stamp_ns: int
    received: tuple[int, ...]
    dropped: tuple[int, ...]
    busy: float
    period: float
    coalesced: tuple[int, ...] = ()


class Coalesced(NamedTuple):
    """The node took ``samples`` samples of line ``line`` (a name; None: the depth) faster than
    it could handle them: they are logged, stamped after ``stamp_ns`` and at most ``last_ns``,
    and not stepped (the newer sample that follows them is). Recorded before them, so replay
    leaves out exactly the samples the node left out."""

    stamp_ns: int
    line: Optional[str]
    last_ns: int
    samples: int


class FatigueStore(NamedTuple):
    """The fatigue store at ``stamp_ns`` (core/rules/fatigue.py; the node keeps it beside
    its log): its ``state`` (:data:`FATIGUE_STORE_STATES`), one-line ``message``, and, when it
    was read at start, each line's stored state (``(name, record or None)``: None, from
    ``NAME.fatigue_damage_initial``); ``lines`` None only changes the status (a write that
    failed or worked again)."""

    stamp_ns: int
    state: str
    message: str
    lines: Optional[tuple[tuple[str, Any], ...]] = None


#: The fatigue store's states and their levels: read at start (``loaded``), none yet in a new
#: log folder (``new``), none where logs are (``missing``), unreadable (``damaged``), a save that
#: failed (``write_failed``).
FATIGUE_STORE_STATES = {
    'loaded': Level.OK,
    'new': Level.OK,
    'saved': Level.OK,
    'missing': Level.WARN,
    'damaged': Level.WARN,
    'write_failed': Level.WARN,
}


Event = Union[
    Tension,
    Depth,
    Tick,
    LoggerHealth,
    Reconfigure,
    Acknowledge,
    Shelve,
    ClockHealth,
    Intake,
    FatigueStore,
    Coalesced,
]


class LineOutput(NamedTuple):
    """The outputs of line number ``line`` after a solve: :data:`OUTPUT_FIELDS` as floats."""

    line: int
    values: tuple[float, ...]


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


class Step(NamedTuple):
    """What one event did: the outputs of the lines solved, the snapshot (or None), the
    transitions, the alarm journal's records and, for a shelving request, the monitor's answer
    (``note``); ``kind`` is ``tension``, ``depth``, ``tick``, ``logger``, ``configure``,
    ``acknowledge``, ``shelve``, ``clock`` or ``intake``."""

    stamp_ns: int
    kind: str
    outputs: tuple[LineOutput, ...]
    snapshot: Optional[Snapshot]
    transitions: tuple[Change, ...]
    alarm_events: tuple[AlarmEvent, ...] = ()
    note: str = ''


@dataclass
class LineState:
    """Everything the core remembers of one line between events."""

    config: LineConfig
    alarm: LineAlarm
    hardware_id: str
    state: AlarmState
    tension: float = _NAN  # N, newest sample
    tension_s: float = _NAN  # s, its stamp (NaN: none yet)
    values: tuple[float, ...] = _NAN_VALUES  # VALUE_FIELDS of the newest solve
    status: int = NO_DEPTH  # solver status of the newest solve
    status_message: str = ''
    model: str = NO_MODEL  # model of the newest solve
    ack: alarm_ack.AckState = alarm_ack.AckState()  # the line's alarm in ISA-18.2 states
    dock: tuple[float, ...] = (_NAN,) * 4  # dock_live.LINE_INPUTS of the newest dock estimate
    sensor_memory: sensor_state.Memory = (
        sensor_state.Memory()
    )  # the tension sensor's per-sample memory
    sensor_code: int = sensor_state.OK  # sensor state decided at the newest tick
    parted_seen: float = -math.inf  # s, when the suspected_parted pattern was last seen
    coalesced_until: int = -1  # ns: this line's samples stamped up to it were not stepped
    fatigue: fatigue_rule.FatigueState = fatigue_rule.FatigueState()  # the streamed count
    fatigue_values: tuple[float, ...] = (0.0, _NAN, _NAN)  # fatigue_rule.FIELDS now
    channels: Optional[channels.ChannelState] = None  # a line of several channels
    channel_values: tuple[float, ...] = (_NAN, _NAN)  # channels.FIELDS now
    sample_ns: int = -1  # ns, the newest accepted sample's stamp (header or arrival; -1: none)
    stamp_refused: float = -math.inf  # s, when a sample's stamp was last refused (arrival)
    # The wave window of its readings (core.rules.wave_window) and its values at the newest.
    wave: wave_window.WaveState = field(default_factory=wave_window.WaveState.empty)
    peak_tension: float = _NAN  # N
    wave_tension: float = _NAN  # N
    # m, the span the newest dock estimate gives the line's solves (NaN: the installed one).
    dock_span: float = _NAN

    def span(self) -> tuple[float, float]:
        """The span [m] the line's next solve takes and its ``span_source`` code."""
        if self.dock_span == self.dock_span:
            return self.dock_span, float(dock_live.DOCK_ESTIMATE)
        return self.config.anchor_distance, float(dock_live.INSTALLED)

    def inputs(
        self, depth_s: float, depth_stale: bool, rate: float = _NAN, table: bool = False
    ) -> AlarmInputs:
        """The alarm inputs of this line now (newest results, stamps, the tide's decision and
        its trend ``rate`` [m/s]; ``table``: the time to uplift is the tide table's)."""
        v, d = self.values, self.dock
        return AlarmInputs(
            uplift_force=v[5],
            anchor_margin=v[4],
            tide_margin=v[6],
            load_margin=v[7],
            safety_factor=v[8],
            time_to_uplift=v[11],
            uplift_force_upper=v[_AT['uplift_force_upper']],
            drag_margin=v[_AT['drag_margin']],
            holding_capacity=v[_AT['holding_capacity']],
            tide_rate=rate,
            tide_forecast=1.0 if table else 0.0,
            status=max(self.status, 0),
            status_message=self.status_message,
            tension_stamp=self.tension_s,
            depth_stamp=depth_s,
            depth_stale=depth_stale,
            inconsistent=d[0],
            dock_residual=d[1],
            dock_expected=d[2],
            dock_sigma=d[3],
            sensor_state=float(self.sensor_code),
            sensor_tension=self.tension,
            mbl=self.config.mbl,
            drag_state=v[_AT['drag_state']],
            implied_anchor_distance=v[_AT['implied_anchor_distance']],
            fatigue_damage=self.fatigue_values[0],
            fatigue_life_left=self.fatigue_values[2],
            dynamic_uplift=v[_AT['dynamic_uplift']],
            uplift_view=v[_AT['time_to_uplift_view']],
            channels_healthy=self.channel_values[0],
            channel_states=self.channel_values[1],
            span=v[_AT['span']],
        )


def _stamp_s(stamp_ns: int) -> float:
    return stamp_ns * 1e-9


def _jitter(alarm: Any, sample_ns: Optional[int]) -> float:
    """How far off a reading's stamp may be [s]: ``stamp_jitter`` for a reading stamped at its
    arrival (delivery bunches samples), 0 for one at the sensor's own header stamp."""
    return alarm.stamp_jitter if sample_ns is None else 0.0


@dataclass
class CoreState:
    """Everything the core's decisions carry from one event to the next (its lines' too).

    The vectorized twin (:mod:`catenary_monitor.core.monitor.twin`) reads and writes the core
    only through this object, and test/test_batch.py compares every field (dataclass fields,
    each line's included) after the same events: state added here and not carried by the twin
    fails there. Times in s (Unix, the monitor's clock) unless named ``_ns``.
    """

    lines: list[LineState]
    sensor_rows: np.ndarray  # N, each line's tension at the sensor_times
    tide: tuple[Level, str]
    tide_entered: float
    start_s: float  # when the monitor started (blind)
    sensors_waiting: int  # lines without a tension at the sensors' decision
    sensors_entered: float
    logger_entered: float
    last_ns: int  # the newest event's stamp
    dock_entered: float
    dock_smoothing: dock_live.Smoothing
    parameters: tuple[Level, str]
    parameters_entered: float
    clock_entered: float
    intake_entered: float
    depth: float = _NAN  # m, newest sample
    depth_s: float = _NAN  # s, its stamp
    depth_stale: bool = False
    trend: tide_trend.TrendState = field(default_factory=tide_trend.TrendState)  # tide rate
    depth_memory: sensor_state.Memory = field(default_factory=sensor_state.Memory)
    depth_code: int = sensor_state.OK  # the depth sensor's state at the newest tick
    depth_sample_ns: int = -1  # ns, the newest accepted depth sample's stamp (-1: none)
    depth_refused: float = -math.inf  # s, when a depth sample's stamp was last refused
    sensor_times: np.ndarray = field(default_factory=lambda: np.zeros(0))  # s, the ticks the
    # suspected_parted test still needs
    # The sensors' common-cause alarm (blind start, silent depth sensor): one, not per line.
    sensors: tuple[Level, str] = (Level.STALE, '')
    sensors_ack: alarm_ack.AckState = field(default_factory=alarm_ack.AckState)
    logger: tuple[Level, str] = (Level.OK, 'logging')
    dock: tuple[Level, str] = (Level.STALE, 'no dock estimate yet')
    dock_values: tuple[tuple[str, str], ...] = ()
    # Accepted runtime changes: their lines, flagged (WARN) until changes_until [s].
    changes: tuple[str, ...] = ()
    changes_until: float = -math.inf
    clock: tuple[Level, str] = field(default_factory=lambda: clock_status(None))
    clock_seen: bool = False
    intake: tuple[Level, str] = (Level.OK, 'no sample counts yet')
    intake_counts: list[Intake] = field(default_factory=list)  # the last INTAKE_WINDOW's events
    # Per Intake event of the window and input: its period is checked against the input's
    # sample rate (the input was heard in an earlier event, and in this one).
    intake_checked: list[tuple[bool, ...]] = field(default_factory=list)
    intake_heard: list[bool] = field(default_factory=list)
    intake_seen: bool = False
    depth_coalesced_until: int = -1  # ns: depth samples stamped up to it were not stepped
    # The alarm system (core.alarm_flood): the flood status, the raises it counts.
    alarms: tuple[Level, str] = (Level.OK, '')
    alarms_entered: float = _NAN
    flood: alarm_flood.Flood = field(default_factory=alarm_flood.initial)
    # The answer to the newest shelving request, and how many were answered.
    shelve_answer: str = ''
    shelve_requests: int = 0
    # The fatigue store's status (a FatigueStore event seen: the node keeps one).
    fatigue: tuple[Level, str] = (Level.OK, '')
    fatigue_word: str = ''
    fatigue_entered: float = 0.0
    fatigue_seen: bool = False


class MonitorCore:
    """The monitor's one decision path: :meth:`step` an event, get a :class:`Step`.

    What the decisions carry from one event to the next is :attr:`state` (a :class:`CoreState`),
    the one door through which the vectorized twin reads and writes the core; the rest is the
    configuration and what follows from it (``__slots__``: no other attribute can be added).

    Parameters
    ----------
    config : the validated configuration (lines, topics, alarm settings).
    start_ns : time the monitor starts (ns); lines and tide are blind (STALE) from then.
    hardware_ids : line name -> the tension topic as resolved by the node (default: resolved
        in the root namespace); ``depth_id`` the depth topic; ``logger_id`` the log directory.
    """

    __slots__ = ('config', 'index', 'depth_id', 'logger_id', 'dock_model', 'curves', 'state')

    def __init__(
        self,
        config: MonitorConfig,
        start_ns: int,
        hardware_ids: Optional[dict[str, str]] = None,
        depth_id: Optional[str] = None,
        logger_id: str = '',
    ) -> None:
        ids = hardware_ids or {}
        start = _stamp_s(start_ns)
        self.config = config
        lines = [
            LineState(
                lc,
                LineAlarm.for_line(lc, config.alarm),
                ids.get(lc.name, resolve_topic(lc.tension_topic)),
                LineAlarm.for_line(lc, config.alarm).initial(start),
                ack=alarm_ack.initial(start),
                fatigue=fatigue_rule.initial(lc.fatigue_damage_initial),
                fatigue_values=(lc.fatigue_damage_initial, _NAN, _NAN),
                channels=channels.initial(len(lc.channel_topics)) if lc.channel_topics else None,
            )
            for lc in config.lines
        ]
        self.curves = [fatigue_rule.Curve.of(lc) for lc in config.lines]
        self.index = {line.config.name: k for k, line in enumerate(lines)}
        self.depth_id = depth_id or resolve_topic(config.depth_topic)
        self.logger_id = logger_id
        # The dock as one body (configs placing every line on the dock): estimated at ticks.
        self.dock_model = DockModel.from_config(config) if config.has_dock_model else None
        self.state = CoreState(
            lines=lines,
            sensor_rows=np.zeros((0, len(config.lines))),
            tide=tide_status(_NAN, _NAN, start, config.alarm.depth_timeout),
            tide_entered=start,
            start_s=start,
            sensors_waiting=len(lines),
            sensors_entered=start,
            logger_entered=start,
            last_ns=start_ns,
            dock_entered=start,
            dock_smoothing=dock_live.Smoothing.initial(len(lines)),
            parameters=parameters_status((), -math.inf, start),
            parameters_entered=start,
            clock_entered=start,
            intake_entered=start,
            fatigue_entered=start,
        )
        self.state.sensors = self._sensors_now(start)
        self.state.alarms = alarm_flood.status(self.state.flood, config.alarm)
        self.state.alarms_entered = start

    # ------------------------------------------------------------------ events
    def step(self, event: Event) -> Step:
        """Apply one event (see the module docstring for the schedule); return what it did.

        A tension or depth sample that a :class:`Coalesced` record left out is not stepped
        (an empty Step of kind ``coalesced``, the core unchanged)."""
        if isinstance(event, (Tension, Depth)) and self.coalesced(event):
            return Step(event.stamp_ns, 'coalesced', (), None, ())
        self.state.last_ns = event.stamp_ns
        if isinstance(event, Tension):
            return self._on_tension(event)
        if isinstance(event, Depth):
            return self._on_depth(event)
        if isinstance(event, Coalesced):
            return self._on_coalesced(event)
        if isinstance(event, Tick):
            return self._on_tick(event)
        if isinstance(event, LoggerHealth):
            return self._on_logger(event)
        if isinstance(event, Reconfigure):
            return self._on_reconfigure(event)
        if isinstance(event, Acknowledge):
            return self._on_acknowledge(event)
        if isinstance(event, Shelve):
            return self._on_shelve(event)
        if isinstance(event, ClockHealth):
            return self._on_clock(event)
        if isinstance(event, Intake):
            return self._on_intake(event)
        if isinstance(event, FatigueStore):
            return self._on_fatigue_store(event)
        raise TypeError(f'not a monitor event: {event!r}')

    def _on_tension(self, ev: Tension) -> Step:
        line = self.state.lines[ev.line]
        a = self.config.alarm
        sample_ns = ev.stamp_ns if ev.sample_ns is None else int(ev.sample_ns)
        if ev.sample_ns is not None and readings.stamp_fault(
            ev.stamp_ns, sample_ns, line.sample_ns, a.stamp_ahead_max
        ):
            line.stamp_refused = _stamp_s(ev.stamp_ns)  # refused: not a reading (bad_stamp)
            return Step(ev.stamp_ns, 'tension', (), None, ())
        value = float(ev.value)
        if line.channels is not None:  # the tension from the healthy channels
            line.channels, value, healthy, code = channels.step(
                line.channels, ev.channel, _stamp_s(sample_ns), value, channel_limits(self, line)
            )
            line.channel_values = (float(healthy), code)
        line.sample_ns = sample_ns
        line.tension, line.tension_s = value, _stamp_s(sample_ns)
        line.sensor_memory = sensor_state.sample(
            line.sensor_memory,
            line.tension_s,
            line.tension,
            a.tension_resolution,
            a.tension_rate_max * line.config.mbl,
            _jitter(a, ev.sample_ns),
        )
        line.fatigue, line.fatigue_values = fatigue_rule.step(
            line.fatigue, line.tension_s, line.tension, self.curves[ev.line]
        )
        line.peak_tension, line.wave_tension = wave_window.step(
            line.wave, line.tension_s, line.tension, line.config.mbl, a.wave_window
        )
        self._solve_one(line)
        log: list[AlarmEvent] = []
        changes = self._step_lines([ev.line], ev.stamp_ns, log)
        return self._finish(ev.stamp_ns, 'tension', [ev.line], changes, log)

    def _on_depth(self, ev: Depth) -> Step:
        a = self.config.alarm
        sample_ns = ev.stamp_ns if ev.sample_ns is None else int(ev.sample_ns)
        if ev.sample_ns is not None and readings.stamp_fault(
            ev.stamp_ns, sample_ns, self.state.depth_sample_ns, a.stamp_ahead_max
        ):
            self.state.depth_refused = _stamp_s(ev.stamp_ns)
            return Step(ev.stamp_ns, 'depth', (), None, ())
        self.state.depth_sample_ns = sample_ns
        self.state.depth, self.state.depth_s = float(ev.value), _stamp_s(sample_ns)
        window = a.tide_trend_window
        self.state.trend = tide_trend.step(self.state.trend, sample_ns, self.state.depth, window)
        self.state.depth_memory = sensor_state.sample(
            self.state.depth_memory,
            self.state.depth_s,
            self.state.depth,
            a.depth_resolution,
            a.depth_rate_max,
            _jitter(a, ev.sample_ns),
        )
        log: list[AlarmEvent] = []
        changes = self._decide_tide(ev.stamp_ns)
        changes += self._decide_blind(ev.stamp_ns, log)
        solved = [k for k, line in enumerate(self.state.lines) if line.tension_s == line.tension_s]
        self._solve_many(solved)
        changes += self._step_lines(range(len(self.state.lines)), ev.stamp_ns, log)
        return self._finish(ev.stamp_ns, 'depth', solved, changes, log)

    def _on_tick(self, ev: Tick) -> Step:
        log: list[AlarmEvent] = []
        self._decide_sensors(ev.stamp_ns)
        changes = self._decide_tide(ev.stamp_ns)
        changes += self._decide_blind(ev.stamp_ns, log)
        if self.dock_model is not None:
            changes += self._decide_dock(ev.stamp_ns)
        changes += self._step_lines(range(len(self.state.lines)), ev.stamp_ns, log)
        changes += self._decide_flood(ev.stamp_ns, log, tick=True)
        snapshot = self.snapshot(ev.stamp_ns)
        return Step(ev.stamp_ns, 'tick', (), snapshot, tuple(changes), tuple(log))

    def _on_fatigue_store(self, ev: FatigueStore) -> Step:
        """The fatigue store: each line's stored count taken where it was read (a line the
        store lacks, or whose record is damaged, from ``NAME.fatigue_damage_initial``), and
        the store's status, shown at once."""
        if ev.lines is not None:
            stored = dict(ev.lines)
            for line, curve in zip(self.state.lines, self.curves):
                state = fatigue_rule.from_record(stored.get(line.config.name), curve)
                if state is None:
                    state = fatigue_rule.initial(line.config.fatigue_damage_initial)
                line.fatigue = state
                damage = state.damage()
                line.fatigue_values = (damage, _NAN, fatigue_rule.life_left(damage, _NAN))
                line.values = _with_fatigue(line.values, line.fatigue_values)
        self.state.fatigue_seen = True
        self.state.fatigue_word = ev.state
        level = FATIGUE_STORE_STATES.get(ev.state, Level.WARN)
        changes = self._set_component('fatigue', (level, ev.message), ev.stamp_ns)
        return Step(ev.stamp_ns, 'fatigue', (), self.snapshot(ev.stamp_ns), tuple(changes))

    def _on_logger(self, ev: LoggerHealth) -> Step:
        new = logger_status(ev.error, ev.path, ev.warning)
        changes = self._set_component('logger', new, ev.stamp_ns)
        return self._finish(ev.stamp_ns, 'logger', [], changes)

    def _on_acknowledge(self, ev: Acknowledge) -> Step:
        """Acknowledge one line's alarm (or every line's; an unknown name changes nothing);
        the snapshot shows it at once."""
        now = _stamp_s(ev.stamp_ns)
        log: list[AlarmEvent] = []
        for line in self.state.lines:
            if ev.line is None or ev.line == line.config.name:
                old = line.ack
                line.ack = alarm_ack.acknowledge(old, now, ev.origin, ev.publisher)
                log += entries(line.config.name, old, line.ack, now)
        if ev.line is None or ev.line == alarm_ack.SENSORS:
            old = self.state.sensors_ack
            self.state.sensors_ack = alarm_ack.acknowledge(old, now, ev.origin, ev.publisher)
            log += entries(alarm_ack.SENSORS, old, self.state.sensors_ack, now)
        snapshot = self.snapshot(ev.stamp_ns)
        return Step(ev.stamp_ns, 'acknowledge', (), snapshot, (), tuple(log))

    def _on_shelve(self, ev: Shelve) -> Step:
        """Shelve or unshelve an alarm (core.shelving's rules) or refuse to; the answer is the
        step's ``note`` and the ``alarms`` status's ``shelve_answer``, shown at once."""
        now = _stamp_s(ev.stamp_ns)
        a = self.config.alarm
        request = shelving.ShelveRequest(ev.alarm, ev.condition, ev.seconds, ev.origin)
        k = self.index.get(ev.alarm)
        line = None if k is None else self.state.lines[k]
        active = None if line is None else [latch.active for latch in line.state.latches]
        names = [ln.config.name for ln in self.state.lines]
        target = ev.alarm if ev.condition == alarm_ack.WHOLE else f'{ev.alarm}.{ev.condition}'
        refused = shelving.refusal(request, names, a, active)
        log: list[AlarmEvent] = []
        if refused is not None:
            answer = f'{target}: refused: {refused}'
            by = alarm_ack.bounded_text(ev.origin)
            log.append(AlarmEvent(now, ev.alarm, 'refused', condition=refused, by=by))
        else:
            old = self.state.sensors_ack if line is None else line.ack
            new, answer = self._shelf(old, line, ev, now, target)
            if line is None:
                self.state.sensors_ack = new
            else:
                line.ack = new
            log += entries(ev.alarm, old, new, now, self._raised_condition(line, new), ev.origin)
        self.state.shelve_answer = answer
        self.state.shelve_requests += 1
        changes = self._decide_flood(ev.stamp_ns, log)
        snapshot = self.snapshot(ev.stamp_ns)
        return Step(ev.stamp_ns, 'shelve', (), snapshot, tuple(changes), tuple(log), answer)

    def _shelf(
        self,
        old: alarm_ack.AckState,
        line: Optional[LineState],
        ev: Shelve,
        now: float,
        target: str,
    ) -> tuple[alarm_ack.AckState, str]:
        """The alarm after an accepted shelving request, and the answer."""
        level, suppressed = (
            (self.state.sensors[0], False)
            if line is None
            else (line.state.level, line.state.suppressed)
        )
        if ev.seconds == 0.0:
            if not alarm_ack.shelved(old):
                return old, f'{target}: not shelved, nothing to unshelve'
            masked = self._masked(line, old)
            new = alarm_ack.unshelve(old, now, level, masked, suppressed)
            return new, f'{ev.alarm} unshelved by {ev.origin}'
        until = now + ev.seconds
        masked = self._masked(line, replace(old, shelved_condition=ev.condition))
        new = alarm_ack.shelve(
            old, now, until, ev.condition, ev.origin, masked, suppressed, ev.publisher
        )
        return new, f'{target} shelved for {ev.seconds:g} s by {ev.origin}'

    def _masked(self, line: Optional[LineState], ack: alarm_ack.AckState) -> Level:
        """The level ``ack``'s shelf leaves visible of ``line`` (None: the sensors alarm, whose
        one condition a shelf hides)."""
        if line is None:
            return Level.OK
        hidden = shelving.hidden_conditions(
            ack.shelved_condition, self.config.alarm.unshelvable_conditions
        )
        latches = [latch.active for latch in line.state.latches]
        return shelving.masked_level(latches, line.state.stale, hidden)

    def _raised_condition(self, line: Optional[LineState], ack: alarm_ack.AckState) -> str:
        """The condition a raise of ``line``'s alarm names: the visible one under its shelf."""
        if line is None:
            return alarm_ack.condition(ack.level, ())
        hidden = (
            shelving.hidden_conditions(
                ack.shelved_condition, self.config.alarm.unshelvable_conditions
            )
            if alarm_ack.shelved(ack)
            else frozenset()
        )
        latches = [
            latch.active and c not in hidden for c, latch in zip(CONDITIONS, line.state.latches)
        ]
        return alarm_ack.condition(ack.level, latches)

    def _chatter(self) -> tuple[int, float]:
        """The chattering rule: (chatter_count, chatter_window [s])."""
        a = self.config.alarm
        return int(a.chatter_count), a.chatter_window

    def _decide_flood(
        self, stamp_ns: int, log: list[AlarmEvent], tick: bool = False
    ) -> list[Change]:
        """The flood decision (core.alarm_flood) after an event that raised an alarm, or at a
        tick; its start and end go to the journal ``log``."""
        raised = [(e.time, e.alarm) for e in log if e.kind == 'raised']
        if not raised and not tick:
            return []
        now = _stamp_s(stamp_ns)
        old = self.state.flood
        new = alarm_flood.decide(old, raised, now, self.config.alarm)
        self.state.flood = new
        if new.since == new.since and old.since != old.since:
            name, at = new.first_out
            log.append(AlarmEvent(now, alarm_flood.NAME, 'flood', 'WARN', by=name, value=at))
        elif old.since == old.since and new.since != new.since:
            log.append(AlarmEvent(now, alarm_flood.NAME, 'flood_end', value=now - old.since))
        return self._set_component('alarms', alarm_flood.status(new, self.config.alarm), stamp_ns)

    def _on_clock(self, ev: ClockHealth) -> Step:
        """The ROS clock's state; always a snapshot (the node sends these on a wall-clock
        timer while the ROS clock stands still, so /diagnostics keeps coming)."""
        self.state.clock_seen = True
        changes = self._set_component('clock', clock_status(ev.stopped_for), ev.stamp_ns)
        return Step(ev.stamp_ns, 'clock', (), self.snapshot(ev.stamp_ns), tuple(changes))

    def _on_intake(self, ev: Intake) -> Step:
        """Sample counts: the intake status over the last :data:`INTAKE_WINDOW` of them."""
        self.state.intake_seen = True
        n = len(ev.received)
        if len(self.state.intake_heard) != n:
            self.state.intake_heard = [False] * n
        self.state.intake_checked.append(
            tuple(h and r > 0 for h, r in zip(self.state.intake_heard, ev.received))
        )
        self.state.intake_heard = [
            h or r > 0 for h, r in zip(self.state.intake_heard, ev.received)
        ]
        counts = self.state.intake_counts + [ev]
        while counts and ev.stamp_ns - counts[0].stamp_ns >= int(INTAKE_WINDOW * 1e9):
            counts.pop(0)
        self.state.intake_counts = counts
        self.state.intake_checked = self.state.intake_checked[
            len(self.state.intake_checked) - len(counts) :
        ]
        received = sum(sum(c.received) for c in counts)
        dropped = sum(sum(c.dropped) for c in counts)
        coalesced = sum(sum(c.coalesced) for c in counts)
        recent = [c for c in counts if ev.stamp_ns - c.stamp_ns < int(BUSY_WINDOW * 1e9)]
        period = sum(c.period for c in recent)
        busy = sum(c.busy for c in recent) / period if period > 0 else _NAN
        new = intake_status(
            received,
            dropped,
            busy,
            INTAKE_WINDOW,
            self.state.intake[0] == Level.OK,
            sum(self.intake_missing()),
            coalesced,
        )
        changes = self._set_component('intake', new, ev.stamp_ns)
        return self._finish(ev.stamp_ns, 'intake', [], changes)

    def intake_dropped(self) -> list[int]:
        """Samples not handled per line, then the depth, in the last :data:`INTAKE_WINDOW`:
        those counted lost, those coalesced (logged, not stepped) and those missing against
        the sample rates."""
        n = len(self.state.lines) + 1
        counted = [
            sum(c.dropped[k] for c in self.state.intake_counts if len(c.dropped) == n)
            for k in range(n)
        ]
        coalesced = self.intake_coalesced()
        return [c + j + m for c, j, m in zip(counted, coalesced, self.intake_missing())]

    def intake_coalesced(self) -> list[int]:
        """Samples coalesced (taken and logged, a newer one stepped instead) per line, then the
        depth, in the last :data:`INTAKE_WINDOW`."""
        n = len(self.state.lines) + 1
        return [
            sum(c.coalesced[k] for c in self.state.intake_counts if len(c.coalesced) == n)
            for k in range(n)
        ]

    def intake_missing(self) -> list[int]:
        """Samples missing per line, then the depth, in the last :data:`INTAKE_WINDOW`: the
        shortfall against ``tension_sample_rate`` / ``depth_sample_rate`` over the report
        periods in which the input was heard (not the first: it began before the first
        sample), beyond the tolerance of
        :func:`~catenary_monitor.core.rules.health.missing_samples`.
        """
        n = len(self.state.lines) + 1
        a = self.config.alarm
        rates = [a.tension_sample_rate] * (n - 1) + [a.depth_sample_rate]
        out = []
        for k in range(n):
            pairs = [
                (c, ok[k])
                for c, ok in zip(self.state.intake_counts, self.state.intake_checked)
                if len(c.received) == n
            ]
            span = sum(c.period for c, ok in pairs if ok)
            got = sum(
                c.received[k] + c.dropped[k] + (c.coalesced[k] if len(c.coalesced) == n else 0)
                for c, ok in pairs
                if ok
            )
            out.append(missing_samples(rates[k], span, got))
        return out

    def coalesced(self, ev: Union[Tension, Depth]) -> bool:
        """Whether a :class:`Coalesced` record left this sample out (it is not stepped)."""
        if isinstance(ev, Depth):
            return ev.stamp_ns <= self.state.depth_coalesced_until
        return ev.stamp_ns <= self.state.lines[ev.line].coalesced_until

    def _on_coalesced(self, ev: Coalesced) -> Step:
        """Leave out the samples the record names (an unknown line name changes nothing)."""
        if ev.line is None:
            self.state.depth_coalesced_until = max(self.state.depth_coalesced_until, ev.last_ns)
        elif ev.line in self.index:
            line = self.state.lines[self.index[ev.line]]
            line.coalesced_until = max(line.coalesced_until, ev.last_ns)
        return Step(ev.stamp_ns, 'coalesced', (), None, ())

    def _on_reconfigure(self, ev: Reconfigure) -> Step:
        """Take the new configuration; flag what changed (WARN on the ``parameters`` status
        for ``runtime_change_warn_time``), shown at once."""
        now = _stamp_s(ev.stamp_ns)
        messages = runtime_change_messages(self.config, ev.config)
        self.reconfigure(ev.config)
        if not messages:
            return Step(ev.stamp_ns, 'configure', (), None, ())
        held = self.state.changes if now < self.state.changes_until else ()
        if (
            self.state.changes and not held and self.state.parameters[0] != Level.OK
        ):  # the flag expired
            self.state.parameters = parameters_status(
                self.state.changes, self.state.changes_until, now
            )
            self.state.parameters_entered = self.state.changes_until
        self.state.changes = held + tuple(messages)
        self.state.changes_until = now + ev.config.runtime_change_warn_time
        new = parameters_status(self.state.changes, self.state.changes_until, now)
        changes = self._set_component('parameters', new, ev.stamp_ns)
        return Step(ev.stamp_ns, 'configure', (), self.snapshot(ev.stamp_ns), tuple(changes))

    def reconfigure(self, config: MonitorConfig) -> None:
        """Take new line constants and alarm rules (same line names); alarm states are kept."""
        names = [lc.name for lc in config.lines]
        if names != [line.config.name for line in self.state.lines]:
            raise ValueError(f'reconfigure: the lines must stay {list(self.index)}, got {names}')
        if config.alarm.tide_trend_window != self.config.alarm.tide_trend_window:
            self.state.trend = tide_trend.TrendState()  # other bins: the trend starts again
        self.config = config
        self.curves = [fatigue_rule.Curve.of(lc) for lc in config.lines]
        for line, lc in zip(self.state.lines, config.lines):
            line.config, line.alarm = lc, LineAlarm.for_line(lc, config.alarm)
        self.dock_model = DockModel.from_config(config) if config.has_dock_model else None
        if self.dock_model is None:  # no dock estimate: the installed spans
            for line in self.state.lines:
                line.dock_span = _NAN

    # ------------------------------------------------------------------ decisions
    def _decide_tide(self, stamp_ns: int) -> list[Change]:
        """Tide level and message, and the one depth-stale decision every line takes."""
        now = _stamp_s(stamp_ns)
        timeout = self.config.alarm.depth_timeout
        self.state.depth_stale = (
            self.state.depth_s == self.state.depth_s and now - self.state.depth_s > timeout
        )
        status = tide_status(self.state.depth, self.state.depth_s, now, timeout)
        new = tide_with_sensor(status, self.state.depth_code, self.state.depth, self.config.alarm)
        return self._set_component('tide', new, stamp_ns)

    def _sensors_now(self, now: float) -> tuple[Level, str]:
        """The sensors' common-cause alarm at ``now`` [s] (core.rules.health.sensors_status)."""
        a = self.config.alarm
        waiting = [
            line.config.name for line in self.state.lines if line.tension_s != line.tension_s
        ]
        return sensors_status(
            waiting,
            len(self.state.lines),
            self.state.depth_s,
            self.state.depth_stale,
            now,
            self.state.start_s,
            a.tension_timeout,
            a.depth_timeout,
        )

    def _decide_blind(self, stamp_ns: int, log: list[AlarmEvent]) -> list[Change]:
        """The sensors' common-cause alarm, after the tide's decision, and its
        acknowledgement state (its records to the journal ``log``)."""
        now = _stamp_s(stamp_ns)
        self.state.sensors_waiting = sum(
            line.tension_s != line.tension_s for line in self.state.lines
        )
        changes = self._set_component('sensors', self._sensors_now(now), stamp_ns)
        old = self.state.sensors_ack
        masked = Level.OK if alarm_ack.shelved(old) else None
        level = self.state.sensors[0]
        new = alarm_ack.step(old, level, now, False, masked, bool(changes), self._chatter())
        self.state.sensors_ack = new
        log += entries(alarm_ack.SENSORS, old, new, now, alarm_ack.condition(new.level, ()))
        return changes

    def _decide_sensors(self, stamp_ns: int) -> None:
        """Every line's and the depth sensor's state at a tick (core.rules.sensor_state)."""
        a = self.config.alarm
        now = np.array([_stamp_s(stamp_ns)])
        lines = self.state.lines
        tension = np.array([[line.tension for line in lines]])
        changed = np.array([[line.sensor_memory.changed for line in lines]])
        ref, keep = sensor_state.reference(
            self.state.sensor_times, self.state.sensor_rows, now, a.parted_window
        )
        pattern = sensor_state.parted_pattern(tension, ref, a.parted_drop)
        seen = np.array([[line.parted_seen for line in lines]])
        seen = np.where(pattern, now[:, None], seen)
        self.state.sensor_times = np.append(self.state.sensor_times[keep:], now)
        spiked = np.array([[line.sensor_memory.spiked for line in lines]])
        row = sensor_state.history_row(now, tension, spiked, a.sensor_hold)
        self.state.sensor_rows = np.vstack([self.state.sensor_rows[keep:], row])
        codes = sensor_state.decide_lines(
            a,
            sensor_limits(self.config),
            now,
            tension,
            np.array([[line.tension_s for line in lines]]),
            changed,
            spiked,
            seen,
            np.array([self.state.depth]),
            np.array([self.state.depth_memory.changed]),
            np.array([[line.stamp_refused for line in lines]]),
        )
        for k, line in enumerate(lines):
            line.sensor_code, line.parted_seen = int(codes[0, k]), float(seen[0, k])
        dm = self.state.depth_memory
        self.state.depth_code = int(
            sensor_state.decide_depth(
                a,
                now,
                np.array([self.state.depth]),
                np.array([self.state.depth_s]),
                np.array([dm.changed]),
                np.array([dm.spiked]),
                changed,
                np.array([self.state.depth_refused]),
            )[0]
        )

    def _decide_dock(self, stamp_ns: int) -> list[Change]:
        """The dock estimate from every line's newest tension (core.rules.dock_watch): the dock
        status, and what each line's ``inconsistent`` alarm condition sees."""
        assert self.dock_model is not None
        now = _stamp_s(stamp_ns)
        depth_ok = self.state.depth_s == self.state.depth_s and not self.state.depth_stale
        decision, self.state.dock_smoothing = dock_live.decide_dock(
            self.dock_model,
            self.config,
            np.array([now]),
            np.array([self.state.depth]),
            np.array([depth_ok]),
            np.array([[line.tension for line in self.state.lines]]),
            np.array([[line.tension_s for line in self.state.lines]]),
            self.state.dock_smoothing,
        )
        for k, line in enumerate(self.state.lines):
            line.dock = tuple(decision.line_inputs[0, k].tolist())
            line.dock_span = float(decision.span[0, k])
        self.state.dock_values = dock_live.dock_values(decision, 0)
        new = (Level(int(decision.level[0])), dock_live.dock_message(self.dock_model, decision, 0))
        return self._set_component('dock', new, stamp_ns)

    def _set_component(self, name: str, new: tuple[Level, str], stamp_ns: int) -> list[Change]:
        """Set the tide's or the logger's (level, message); a Change if the level moved."""
        old: tuple[Level, str] = getattr(self.state, name)
        setattr(self.state, name, new)
        if new[0] == old[0]:
            return []
        now = _stamp_s(stamp_ns)
        entered = getattr(self.state, f'{name}_entered')
        setattr(self.state, f'{name}_entered', now)
        quiet = name in _CONSEQUENCES and quiet_change(old[0], True, new[0], True)
        return [Change(name, Transition(now, old[0], new[0], new[1], now - entered, quiet))]

    def _solve_one(self, line: LineState) -> None:
        """Solve one line at the newest depth (the scalar fast path)."""
        lc, t = line.config, line.tension
        h = self.state.depth + lc.hook_height
        span = line.span()
        if self.state.depth_s != self.state.depth_s:  # no depth yet: nothing to solve
            line.values, line.status, line.status_message, line.model = (
                _with_span(_with_sensor((t, h) + _NAN_VALUES[2:], line.sensor_code), span),
                NO_DEPTH,
                '',
                NO_MODEL,
            )
            self._add_derived([line])
            return
        loads: dict[str, Any] = {} if lc.point_loads is None else {'point_loads': lc.point_loads}
        r = solve(
            lc.weight,
            h,
            tension=t,
            anchor_distance=span[0],
            mbl=lc.mbl,
            ea=lc.ea,
            **loads,
        )
        line.values = (
            t,
            h,
            r.horizontal_tension,
            r.min_anchor_distance,
            r.anchor_margin,
            r.uplift_force,
            r.tide_margin,
            r.load_margin,
            r.safety_factor,
            r.anchor_angle_deg,
            r.suspended_length,
            _NAN,  # time_to_uplift: _add_derived
        )
        line.values = _with_sensor(line.values + _NAN_VALUES[len(line.values) :], line.sensor_code)
        line.values = _with_span(line.values, span)
        line.status, line.status_message, line.model = int(r.status), r.message, r.model
        code = reading_status(t, h, lc.mbl, lc.weight)
        if code:
            _implausible(line, code)
        self._add_derived([line])

    def _solve_many(self, which: Sequence[int]) -> None:
        """Solve several lines at the newest depth in one vectorized call (a line with point
        loads by itself: the scalar path)."""
        for k in [k for k in which if self.state.lines[k].config.point_loads is not None]:
            self._solve_one(self.state.lines[k])
        which = [k for k in which if self.state.lines[k].config.point_loads is None]
        if not which:
            return
        lines = [self.state.lines[k] for k in which]
        cfgs = [line.config for line in lines]
        tension = np.array([line.tension for line in lines])
        h = self.state.depth + np.array([c.hook_height for c in cfgs])
        spans = [line.span() for line in lines]
        ea = None
        if any(c.ea is not None for c in cfgs):
            ea = np.array([math.inf if c.ea is None else c.ea for c in cfgs])
        r = solve(
            np.array([c.weight for c in cfgs]),
            h,
            tension=tension,
            anchor_distance=np.array([span for span, _ in spans]),
            mbl=np.array([c.mbl for c in cfgs]),
            ea=ea,
        )
        columns = [tension.tolist(), h.tolist()] + [
            np.asarray(getattr(r, k)).tolist() for k in _SOLVED
        ]
        columns.append([_NAN] * len(lines))  # time_to_uplift: _add_derived
        models = np.broadcast_to(np.asarray(r.model, dtype=object), tension.shape)
        messages, status = r.message, np.asarray(r.status).tolist()
        for i, line in enumerate(lines):
            line.values = tuple(col[i] for col in columns) + _NAN_VALUES[len(columns) :]
            line.values = _with_span(_with_sensor(line.values, line.sensor_code), spans[i])
            line.status, line.status_message = int(status[i]), str(messages[i])
            line.model = str(models[i])
        codes = reading_status_array(
            tension, h, [c.mbl for c in cfgs], [c.weight for c in cfgs]
        ).tolist()
        for line, code in zip(lines, codes):
            if code:
                _implausible(line, code)
        self._add_derived(lines)

    def _add_derived(self, lines: Sequence[LineState]) -> None:
        """The fatigue values, the wave values, the dynamic uplift, the bounds, the holding
        values and the time to uplift of freshly solved lines (from their values;
        :func:`derived_values`, the holding of one line in plain floats: :func:`holding_one`)."""
        for line in lines:
            line.values = _with_fatigue(line.values, line.fatigue_values)
            _with_channels(line)
        named = {k: np.array([line.values[i] for line in lines]) for k, i in _AT.items()}
        named['peak_tension'] = np.array([line.peak_tension for line in lines])
        named['wave_tension'] = np.array([line.wave_tension for line in lines])
        cfgs = [line.config for line in lines]
        tolerance = self.config.alarm.drag_tolerance
        derived = derived_values(cfgs, self.config.alarm, named, holding=False)
        some = [k for k, line in enumerate(lines) if _wants_holding(line.config)]
        held: dict[str, Any] = {key: np.full(len(lines), np.nan) for key in HOLDING_FIELDS}
        if len(some) == 1:  # a tension event: plain floats
            one = holding_one(cfgs[some[0]], lines[some[0]].values, tolerance)
            for key in HOLDING_FIELDS:
                held[key][some[0]] = one[key]
        elif some:
            idx = np.array(some)
            part = holding_values(
                [cfgs[k] for k in some], {k: v[idx] for k, v in named.items()}, tolerance
            )
            for key in HOLDING_FIELDS:
                held[key][idx] = part[key]
        derived.update(held)
        margin, view = tide_trend.nearer_margin(
            named['tide_margin'], derived['tide_margin_at_length']
        )
        derived['time_to_uplift'] = np.array(self._uplift_times(margin, named['uplift_force']))
        derived['time_to_uplift_view'] = view
        at = [(_AT[key], np.asarray(column).tolist()) for key, column in derived.items()]
        for j, line in enumerate(lines):
            v = list(line.values)
            for i, column in at:
                v[i] = column[j]
            line.values = tuple(v)

    def _uplift_times(self, margins: Any, forces: Any) -> list[float]:
        """Each line's time to uplift [s]: on the tide table's forecast from the newest depth
        sample where there is a table (core.rules.tide_table), else at the tide's trend."""
        a = self.config.alarm
        if a.constituents:
            times = tide_table.uplift_times(
                a.constituents,
                a.tide_table_epoch,
                a.tide_forecast_horizon,
                np.full(len(margins), self.state.depth_s),
                np.array(margins, np.float64),
                np.array(forces, np.float64),
            )
            return [float(v) for v in times]
        rate, excess = self.state.trend.rate, self.state.trend.excess
        return [tide_trend.time_to_uplift(m, f, rate, excess) for m, f in zip(margins, forces)]

    def _step_lines(self, which: Any, stamp_ns: int, log: list[AlarmEvent]) -> list[Change]:
        """Step the alarms of the given lines at ``stamp_ns``; their transitions (their
        alarms' records to the journal ``log``)."""
        now = _stamp_s(stamp_ns)
        chatter = self._chatter()
        changes = []
        for k in which:
            line = self.state.lines[k]
            line.state, events = line.alarm.update(
                line.state,
                line.inputs(
                    self.state.depth_s,
                    self.state.depth_stale,
                    self.state.trend.rate,
                    bool(self.config.alarm.constituents),
                ),
                now,
            )
            old = line.ack
            flip = any(not ev.suppressed for ev in events)
            masked = self._masked(line, old) if alarm_ack.shelved(old) else None
            level, quiet = line.state.level, line.state.suppressed
            line.ack = alarm_ack.step(old, level, now, quiet, masked, flip, chatter)
            if line.ack is not old:
                condition = self._raised_condition(line, line.ack)
                log += entries(line.config.name, old, line.ack, now, condition)
            changes += [Change(line.config.name, ev) for ev in events]
        return changes

    def _finish(
        self,
        stamp_ns: int,
        kind: str,
        solved: Sequence[int],
        changes: list[Change],
        log: Sequence[AlarmEvent] = (),
    ) -> Step:
        """The Step of an input event: outputs of the solved lines, the flood decision if it
        raised an alarm, a snapshot on a change."""
        log = list(log)
        changes = changes + self._decide_flood(stamp_ns, log)
        outputs = tuple(self.output(k) for k in solved)
        snapshot = self.snapshot(stamp_ns) if changes else None
        return Step(stamp_ns, kind, outputs, snapshot, tuple(changes), tuple(log))

    # ------------------------------------------------------------------ views
    def output(self, k: int) -> LineOutput:
        """Line ``k``'s outputs now (:data:`OUTPUT_FIELDS`)."""
        line = self.state.lines[k]
        return LineOutput(k, output_values(line.values, line.status, line.state.level))

    def snapshot(self, stamp_ns: int) -> Snapshot:
        """The diagnostic snapshot at ``stamp_ns``: every line, the tide, the logger."""
        now = _stamp_s(stamp_ns)
        dock = self.dock_model is not None
        statuses = [
            line_status(
                line.config,
                line.hardware_id,
                line.state.level,
                line.state.message,
                line.values,
                line.status,
                line.model,
                now - line.tension_s,
                sensor_state.line_word(line.sensor_code, line_dock_word(line) if dock else ''),
                tuple(
                    alarm_ack.diagnostic_values(
                        line.ack, line.state.level, [latch.active for latch in line.state.latches]
                    )
                )
                + (
                    line_dock_values(line.state.latches[_INCONSISTENT].active, line.dock)
                    if dock
                    else ()
                ),
            )
            for line in self.state.lines
        ]
        statuses.append(
            tide_component(
                self.state.tide,
                self.depth_id,
                self.state.depth,
                now - self.state.depth_s,
                self.state.trend.rate,
                depth_word(self.state.depth_s, self.state.depth_code),
                forecast_word(self.config, self.state.trend.rate),
            )
        )
        statuses.append(
            sensors_component(
                self.state.sensors, self.state.sensors_ack, self.state.sensors_waiting
            )
        )
        statuses.append(self.alarms_component(self.state.alarms, self.state.flood))
        level, message = self.state.logger
        statuses.append(
            ComponentStatus(f'{NODE_NAME}: logger', level, message, self.logger_id, ())
        )
        if dock:
            statuses.append(dock_component(self.state.dock, self.state.dock_values))
        statuses += self.guard_components(now)
        return Snapshot(stamp_ns, tuple(statuses))

    def alarms_component(
        self, status: tuple[Level, str], flood: alarm_flood.Flood
    ) -> ComponentStatus:
        """The ``catenary_monitor: alarms`` status: the flood decision ``status`` and ``flood``
        (:mod:`catenary_monitor.core.alarms.flood`), the shelving rules and the answer
        to the newest shelving request."""
        values = alarm_flood.values(
            flood, self.config.alarm, self.state.shelve_answer, self.state.shelve_requests
        )
        return ComponentStatus(f'{NODE_NAME}: alarms', status[0], status[1], NODE_NAME, values)

    def guard_components(
        self, now: float, max_damage: Optional[float] = None
    ) -> list[ComponentStatus]:
        """The statuses after the logger and the dock: the runtime-change flag, the ROS clock,
        the fatigue store and the intake, each once it applies (events only change them; the
        twin gives the worst line's damage at the snapshot, ``max_damage``)."""
        out = []
        flag = self.parameters_component(now)
        if flag is not None:
            out.append(flag)
        if self.state.clock_seen:
            out.append(ComponentStatus(f'{NODE_NAME}: clock', *self.state.clock, NODE_NAME, ()))
        if self.state.fatigue_seen:
            out.append(self.fatigue_component(max_damage))
        if self.state.intake_seen:
            dropped = self.intake_dropped()
            names = [line.config.name for line in self.state.lines] + ['depth']
            values = (('messages_dropped', str(sum(dropped))),) + tuple(
                (f'{name}.messages_dropped', str(d)) for name, d in zip(names, dropped)
            )
            a = self.config.alarm
            if a.tension_sample_rate > 0.0 or a.depth_sample_rate > 0.0:
                missing = self.intake_missing()
                values += (('messages_missing', str(sum(missing))),) + tuple(
                    (f'{name}.messages_missing', str(m)) for name, m in zip(names, missing)
                )
            handled = sum(sum(c.received) for c in self.state.intake_counts)
            values += (
                ('messages_coalesced', str(sum(self.intake_coalesced()))),
                ('messages_handled', str(handled)),
            )
            out.append(
                ComponentStatus(f'{NODE_NAME}: intake', *self.state.intake, NODE_NAME, values)
            )
        return out

    def fatigue_component(self, max_damage: Optional[float] = None) -> ComponentStatus:
        """The ``catenary_monitor: fatigue`` status: the fatigue store's level and message,
        ``store_state`` (:data:`FATIGUE_STORE_STATES`) and the worst line's ``fatigue_damage``
        (``max_damage``: the twin gives it as it was at the snapshot)."""
        if max_damage is None:
            max_damage = max(line.fatigue_values[0] for line in self.state.lines)
        values = (('store_state', self.state.fatigue_word), ('max_damage', repr(max_damage)))
        return ComponentStatus(f'{NODE_NAME}: fatigue', *self.state.fatigue, NODE_NAME, values)

    def parameters_component(self, now: float) -> Optional[ComponentStatus]:
        """The runtime-change status at ``now`` [s] (None when runtime changes are not
        allowed and none was made): WARN naming the changes until their flag expires."""
        if not (self.config.allow_runtime_changes or self.state.changes):
            return None
        level, message = parameters_status(self.state.changes, self.state.changes_until, now)
        until = repr(float(self.state.changes_until)) if self.state.changes else 'nan'
        values = (('changes', str(len(self.state.changes))), ('flagged_until', until))
        return ComponentStatus(f'{NODE_NAME}: parameters', level, message, NODE_NAME, values)


def _with_sensor(values: tuple[float, ...], code: int) -> tuple[float, ...]:
    """``values`` with the line's sensor state code in its place (``sensor_state``)."""
    return values[:_SENSOR_AT] + (float(code),) + values[_SENSOR_AT + 1 :]


_SPAN_AT = VALUE_FIELDS.index('span')


def _with_span(values: tuple[float, ...], span: tuple[float, float]) -> tuple[float, ...]:
    """``values`` with the span solved at [m] and its ``span_source`` code in their places."""
    return values[:_SPAN_AT] + tuple(span) + values[_SPAN_AT + 2 :]


_FATIGUE_AT = VALUE_FIELDS.index(fatigue_rule.FIELDS[0])


def _with_fatigue(values: tuple[float, ...], fatigue: tuple[float, ...]) -> tuple[float, ...]:
    """``values`` with the line's fatigue values in their places."""
    end = _FATIGUE_AT + len(fatigue)
    return values[:_FATIGUE_AT] + tuple(fatigue) + values[end:]


_CHANNELS_AT = VALUE_FIELDS.index(channels.FIELDS[0])


def _with_channels(line: LineState) -> None:
    """The line's values with its channels' values in their places."""
    v, end = line.values, _CHANNELS_AT + len(channels.FIELDS)
    line.values = v[:_CHANNELS_AT] + tuple(line.channel_values) + v[end:]


def channel_limits(core: MonitorCore, line: LineState) -> channels.Limits:
    """The channel rules of a line (core.channels.Limits)."""
    a = core.config.alarm
    return channels.Limits(
        a.tension_timeout,
        a.stuck_time,
        a.tension_resolution,
        a.channel_tolerance,
        int(line.config.min_channels),
    )


def _implausible(line: LineState, code: int) -> None:
    """An implausible reading (core.rules.plausible): its status and sentence, no solved values
    (the measured tension and depth kept, as for every impossible input)."""
    line.values = line.values[:2] + _NAN_VALUES[2:_SENSOR_AT] + line.values[_SENSOR_AT:]
    line.status, line.status_message = code, status_messages(line.config)[code]
    line.model = elastic.INEXTENSIBLE


def _column(cfgs: Sequence[LineConfig], key: str) -> np.ndarray:
    """One line constant per config as floats (None: NaN, ``ea`` None: inf)."""
    none = math.inf if key == 'ea' else math.nan
    return np.array([none if getattr(c, key) is None else getattr(c, key) for c in cfgs])


def _span(cfgs: Sequence[LineConfig], named: dict[str, np.ndarray]) -> np.ndarray:
    """Per element, the span [m] the values were solved at (``named['span']``), the line's
    installed ``anchor_distance`` where it is not given (NaN)."""
    installed = _column(cfgs, 'anchor_distance')
    if 'span' not in named:
        return installed
    span = np.asarray(named['span'], dtype=float)
    return np.where(np.isnan(span), installed, span)


def _given_span(lc: LineConfig, span: float) -> float:
    """:func:`_span` of one line in plain floats."""
    return lc.anchor_distance if span != span else span


def _wants_holding(c: LineConfig) -> bool:
    """Whether a line has holding values: a chain length or an anchor holding."""
    return c.chain_length is not None or c.anchor_holding is not None


#: The values :func:`holding_values` gives (core/rules/holding.py).
HOLDING_FIELDS = holding_rule.FIELDS + holding_rule.LENGTH_FIELDS + holding_rule.DRAG_FIELDS


def derived_values(
    cfgs: Sequence[LineConfig], alarm: Any, named: dict[str, np.ndarray], holding: bool = True
) -> dict[str, np.ndarray]:
    """What the core adds to a solve (the core and its batch twin both call this), per element
    of the nominal values ``named`` (VALUE_FIELDS -> arrays, with ``peak_tension`` and
    ``wave_tension`` from the wave window; ``span`` the span solved at, else the installed
    one), each element's line in ``cfgs`` (one config for all, or one per element): the wave
    values, ``dynamic_uplift``, the bounds (:mod:`.uncertainty`) and, with ``holding``, the
    holding values (:mod:`.holding`; NaN for lines with neither ``chain_length`` nor
    ``anchor_holding``), all at that span."""
    n = len(named['top_tension'])
    out = {key: np.asarray(named[key], dtype=float) for key in wave_window.FIELDS}
    tension = uncertainty.dynamic_tension(
        named['peak_tension'], named['wave_tension'], alarm.wave_allowance
    )
    out.update(bound_values(cfgs, alarm.depth_accuracy, dict(named, top_tension=tension)))
    out['dynamic_uplift'] = uncertainty.dynamic_uplift(
        _column(cfgs, 'weight'),
        _span(cfgs, named),
        _column(cfgs, 'mbl'),
        _column(cfgs, 'ea'),
        tension,
        named['depth'],
        named['uplift_force'],
    )
    if any(c.point_loads is not None for c in cfgs):  # with its clumps and buoys
        _loaded_bounds(cfgs, alarm.depth_accuracy, dict(named, top_tension=tension), out)
    if not holding:
        return out
    if len(cfgs) == 1 and _wants_holding(cfgs[0]):  # one line for every element (the twin)
        out.update(holding_values(cfgs, named, alarm.drag_tolerance))
    elif len(cfgs) == 1:
        out.update({key: np.full(n, np.nan) for key in HOLDING_FIELDS})
    else:
        raise ValueError('derived_values: the holding of several lines is the core\'s')
    return out


def _loaded_bounds(
    cfgs: Sequence[LineConfig],
    depth_accuracy: float,
    named: dict[str, np.ndarray],
    out: dict[str, np.ndarray],
) -> None:
    """The bounds and dynamic uplift in ``out`` of the elements whose line has point loads
    (:func:`catenary_monitor.core.rules.uncertainty.loaded_bounds`, element by element)."""
    span = _span(cfgs, named)
    for k in range(len(named['top_tension'])):
        c = cfgs[k] if len(cfgs) > 1 else cfgs[0]
        if c.point_loads is None:
            continue
        one = uncertainty.loaded_bounds(
            c.weight,
            float(span[k]),
            c.mbl,
            c.point_loads,
            float(named['top_tension'][k]),
            float(named['depth'][k]),
            float(c.sensor_accuracy),
            depth_accuracy,
            float(named['uplift_force'][k]),
        )
        for key, value in one.items():
            out[key] = np.array(out[key], dtype=float)
            out[key][k] = value


def bound_values(
    cfgs: Sequence[LineConfig], depth_accuracy: float, named: dict[str, np.ndarray]
) -> dict[str, np.ndarray]:
    """The bounds (:data:`catenary_monitor.core.rules.uncertainty.FIELDS`) per element of the
    nominal values ``named`` (VALUE_FIELDS -> arrays), each element's line in ``cfgs`` (one
    config, or one per element); the core and its batch twin both call this."""
    return uncertainty.bounds(
        _column(cfgs, 'weight'),
        _span(cfgs, named),
        _column(cfgs, 'mbl'),
        _column(cfgs, 'ea'),
        named['top_tension'],
        named['depth'],
        np.array([c.sensor_accuracy for c in cfgs]),
        depth_accuracy,
        named['uplift_force'],
    )


def holding_values(
    cfgs: Sequence[LineConfig], named: dict[str, np.ndarray], tolerance: float = math.inf
) -> dict[str, np.ndarray]:
    """The holding values (:data:`HOLDING_FIELDS`), as :func:`bound_values`; ``tolerance``
    is ``drag_tolerance`` (m). Lines with point loads element by element (:func:`holding_one`,
    the core's own numbers)."""
    if any(c.point_loads is not None for c in cfgs):
        return _holding_by_element(cfgs, named, tolerance)
    return holding_rule.holding(
        _column(cfgs, 'weight'),
        _column(cfgs, 'ea'),
        _column(cfgs, 'chain_length'),
        _column(cfgs, 'anchor_holding'),
        _column(cfgs, 'anchor_weight'),
        _column(cfgs, 'chain_friction'),
        named['top_tension'],
        named['depth'],
        named['horizontal_tension'],
        named['suspended_length'],
        named['uplift_force'],
        _span(cfgs, named),
        tolerance,
    )


def _holding_by_element(
    cfgs: Sequence[LineConfig], named: dict[str, np.ndarray], tolerance: float
) -> dict[str, np.ndarray]:
    """:func:`holding_values` one element at a time through :func:`holding_one`."""
    n = len(named['top_tension'])
    out = {key: np.full(n, np.nan) for key in HOLDING_FIELDS}
    for k in range(n):
        values = [_NAN] * len(_AT)
        for key, i in _AT.items():
            if key in named:
                values[i] = float(named[key][k])
        one = holding_one(cfgs[k] if len(cfgs) > 1 else cfgs[0], values, tolerance)
        for key in HOLDING_FIELDS:
            out[key][k] = one[key]
    return out


def holding_one(
    lc: LineConfig, values: Sequence[float], tolerance: float = math.inf
) -> dict[str, float]:
    """:func:`holding_values` of one line's :data:`VALUE_FIELDS` values in plain floats
    (:func:`catenary_monitor.core.rules.holding.holding_scalar`: the same numbers to
    rounding, an order of magnitude faster than one-element arrays; a line with point loads:
    :func:`~catenary_monitor.core.rules.holding.holding_loaded`, the twin's too)."""

    def given(v: Optional[float]) -> float:
        return _NAN if v is None else v

    if lc.point_loads is not None:
        return holding_rule.holding_loaded(
            PointLoads.of(*lc.point_loads),
            lc.weight,
            given(lc.chain_length),
            given(lc.anchor_holding),
            given(lc.anchor_weight),
            given(lc.chain_friction),
            values[_AT['top_tension']],
            values[_AT['depth']],
            values[_AT['horizontal_tension']],
            values[_AT['suspended_length']],
            values[_AT['uplift_force']],
            _given_span(lc, values[_AT['span']]),
            tolerance,
        )

    return holding_rule.holding_scalar(
        lc.weight,
        math.inf if lc.ea is None else lc.ea,
        given(lc.chain_length),
        given(lc.anchor_holding),
        given(lc.anchor_weight),
        given(lc.chain_friction),
        values[_AT['top_tension']],
        values[_AT['depth']],
        values[_AT['horizontal_tension']],
        values[_AT['suspended_length']],
        values[_AT['uplift_force']],
        _given_span(lc, values[_AT['span']]),
        tolerance,
    )


def output_values(values: Sequence[float], status: float, level: float) -> tuple[float, ...]:
    """One output message's elements (:data:`OUTPUT_FIELDS` order) from the
    :data:`VALUE_FIELDS` values, the solver status and the level."""
    v = tuple(float(x) for x in values)
    return v[:11] + (float(status), float(int(level))) + v[11:]


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
) -> ComponentStatus:
    """One line's ``DiagnosticStatus``: the contract keys (SI strings ``float()`` reads back
    exactly), then ``measured_tension``, ``tension_age`` [s], ``anchor_distance``,
    ``allowed_uplift``, ``anchor_angle_deg``, ``solver_status``, ``model``, ``sensor_state``
    (:func:`catenary_monitor.core.rules.sensor_state.line_word`), ``time_to_uplift_view``
    (:func:`view_word`), ``span`` [m] and ``span_source`` (the span the line was solved at and
    its source: :func:`catenary_monitor.core.rules.dock_watch.span_word`), then ``extra``
    (the alarm's acknowledgement keys: :func:`.acknowledge.diagnostic_values`; with the dock
    model, :func:`line_dock_values`)."""
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
    return ComponentStatus(
        f'{NODE_NAME}: {config.name}', level, message, hardware_id, tuple(pairs)
    )


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


def sensor_limits(config: MonitorConfig) -> sensor_state.LineLimits:
    """The per-line constants of the sensor decision (MBL, weight, hook height)."""
    lines = config.lines
    return sensor_state.LineLimits(
        np.array([c.mbl for c in lines]),
        np.array([c.weight for c in lines]),
        np.array([c.hook_height for c in lines]),
    )


def forecast_word(config: MonitorConfig, rate: float) -> str:
    """What the times to uplift follow: ``table`` (a tide table is configured), ``trend``
    (the tide's trend is known) or ``unknown``."""
    if config.alarm.constituents:
        return 'table'
    return 'trend' if math.isfinite(rate) else 'unknown'


def tide_with_sensor(
    tide: tuple[Level, str], code: int, depth: float, config: Any
) -> tuple[Level, str]:
    """The tide's (level, message) with the depth sensor's state: the worse level (stuck and
    spike WARN, out_of_range ERROR), the sensor's message appended."""
    if code == sensor_state.OK:
        return tide
    level = Level.ERROR if code == sensor_state.OUT_OF_RANGE else Level.WARN
    text = sensor_state.depth_message(code, depth, config)
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
    (:func:`.acknowledge.diagnostic_values`)."""
    values = (('lines_waiting', str(waiting)),) + tuple(
        alarm_ack.diagnostic_values(ack, state[0], ())
    )
    return ComponentStatus(f'{NODE_NAME}: sensors', state[0], state[1], NODE_NAME, values)


def dock_component(
    dock: tuple[Level, str], values: tuple[tuple[str, str], ...]
) -> ComponentStatus:
    """The ``catenary_monitor: dock`` status: the estimate's level and message, values
    ``offset_x``, ``offset_y`` [m], ``yaw_deg``, ``load_x``, ``load_y`` [N], ``load_mz`` [N m],
    ``readings`` (NaN strings before the first estimate)."""
    if not values:
        values = tuple((k, 'nan') for k in dock_live.DOCK_KEYS[:-1]) + (('readings', '0'),)
    return ComponentStatus(f'{NODE_NAME}: dock', dock[0], dock[1], 'dock model', values)


def tide_component(
    tide: tuple[Level, str],
    hardware_id: str,
    depth: float,
    depth_age: float,
    rate: float = math.nan,
    sensor_word: str = 'ok',
    forecast: str = 'unknown',
) -> ComponentStatus:
    """The tide's ``DiagnosticStatus``: values ``depth`` [m], ``depth_age`` [s] and ``rate``
    [m/s], the trend (:mod:`~catenary_monitor.core.rules.tide_trend`; nan while unknown), and the
    depth sensor's ``sensor_state``
    (:data:`catenary_monitor.core.rules.sensor_state.DEPTH_STATES`) and
    ``tide_forecast``, what the times to uplift follow (:func:`forecast_word`)."""
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
        ),
    )


# --- the events channel
# ---------------------------------------------------------------------------


def event_record(event: Union[Event, Start]) -> Optional[dict[str, Any]]:
    """What the node records on :data:`EVENTS_TOPIC` for an event that is not an input message
    (None for tension and depth: their input messages are the record)."""
    if isinstance(event, Start):
        return {'kind': 'start'}
    if isinstance(event, Tick):
        return {'kind': 'tick'}
    if isinstance(event, LoggerHealth):
        record = {'kind': 'logger', 'error': event.error, 'path': event.path}
        if event.warning is not None:
            record['warning'] = event.warning
        return record
    if isinstance(event, Reconfigure):
        return {'kind': 'configure', 'parameters': config_to_params(event.config)}
    if isinstance(event, Acknowledge):
        line = alarm_ack.ALL_LINES if event.line is None else event.line
        return {
            'kind': 'acknowledge',
            'line': line,
            'origin': alarm_ack.bounded_text(event.origin),
            'publisher': alarm_ack.bounded_text(event.publisher),
        }
    if isinstance(event, Shelve):
        return {
            'kind': 'shelve',
            'alarm': event.alarm,
            'condition': event.condition,
            'seconds': event.seconds,
            'origin': alarm_ack.bounded_text(event.origin),
            'publisher': alarm_ack.bounded_text(event.publisher),
        }
    if isinstance(event, ClockHealth):
        return {'kind': 'clock', 'stopped_for': event.stopped_for}
    if isinstance(event, FatigueStore):
        lines = None if event.lines is None else dict(event.lines)
        return {'kind': 'fatigue', 'state': event.state, 'message': event.message, 'lines': lines}
    if isinstance(event, Intake):
        return {
            'kind': 'intake',
            'received': list(event.received),
            'dropped': list(event.dropped),
            'coalesced': list(event.coalesced),
            'busy': event.busy,
            'period': event.period,
        }
    if isinstance(event, Coalesced):
        where = {'input': 'depth'} if event.line is None else {'line': event.line}
        return {'kind': 'coalesced', **where, 'last_ns': event.last_ns, 'samples': event.samples}
    return None


def parse_event_record(stamp_ns: int, text: str) -> Optional[Union[Event, Start]]:
    """The event (or :class:`Start`) of one :data:`EVENTS_TOPIC` record (None for an unknown
    or damaged one)."""
    try:
        record = json.loads(text)
        kind = record['kind']
        if kind == 'start':
            return Start(stamp_ns)
        if kind == 'tick':
            return Tick(stamp_ns)
        if kind == 'logger':
            return LoggerHealth(
                stamp_ns, record.get('error'), record.get('path'), record.get('warning')
            )
        if kind == 'configure':
            return Reconfigure(stamp_ns, config_from_params(record['parameters']))
        if kind == 'clock':
            stopped = record.get('stopped_for')
            return ClockHealth(stamp_ns, None if stopped is None else float(stopped))
        if kind == 'intake':
            return Intake(
                stamp_ns,
                tuple(int(x) for x in record['received']),
                tuple(int(x) for x in record['dropped']),
                float(record['busy']),
                float(record['period']),
                tuple(int(x) for x in record.get('coalesced', ())),
            )
        if kind == 'coalesced':
            line = None if record.get('input') == 'depth' else str(record['line'])
            return Coalesced(stamp_ns, line, int(record['last_ns']), int(record['samples']))
        if kind == 'shelve':
            seconds = float(record['seconds'])
            if not math.isfinite(seconds) or seconds < 0.0:
                return None
            return Shelve(
                stamp_ns,
                alarm_ack.bounded_text(str(record['alarm'])),
                alarm_ack.bounded_text(str(record.get('condition') or alarm_ack.WHOLE)),
                seconds,
                alarm_ack.bounded_text(str(record.get('origin', ''))),
                alarm_ack.bounded_text(str(record.get('publisher', ''))),
            )
        if kind == 'fatigue':
            lines = record.get('lines')
            return FatigueStore(
                stamp_ns,
                str(record['state']),
                str(record['message']),
                None if lines is None else tuple((str(k), v) for k, v in dict(lines).items()),
            )
        if kind == 'acknowledge':
            line = str(record['line'])
            return Acknowledge(
                stamp_ns,
                None if line == alarm_ack.ALL_LINES else alarm_ack.bounded_text(line),
                alarm_ack.bounded_text(str(record.get('origin', ''))),
                alarm_ack.bounded_text(str(record.get('publisher', ''))),
            )
    except (ValueError, KeyError, TypeError, RecursionError):  # a damaged or crafted record
        return None
    return None
