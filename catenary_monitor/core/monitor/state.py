"""What the monitor core remembers between events, and the layout of a line's values.

:data:`OUTPUT_FIELDS` (each line's outputs) and :data:`VALUE_FIELDS` (its solved and derived
values); :class:`LineState` (one line) and :class:`CoreState` (the core, its lines' too). The
vectorized twin (:mod:`catenary_monitor.core.twin`) writes them only through their typed door,
``state.take(part)``, and reads them as typed fields or as parts, ``state.read(kind)``: a part
is a NamedTuple of the state's own fields (test/test_batch.py checks their names and types),
one per decision the twin takes over a window (:class:`TidePart`, :class:`SensorPart`,
:class:`BlindPart`, :class:`DockPart`, :class:`FloodPart`, :class:`ComponentAckPart`,
:class:`StampPart`; of a line
:class:`LineInputPart`, :class:`LineSolvePart`, :class:`LineRulesPart`, :class:`LineAlarmPart`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple, Optional, Sequence, TypeVar

import numpy as np

from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.alarms import flood as alarm_flood
from catenary_monitor.core.alarms.latches import AlarmInputs, AlarmState, LineAlarm
from catenary_monitor.core.config.parameters import LineConfig
from catenary_monitor.core.monitor.events import Intake
from catenary_monitor.core.physics import elastic
from catenary_monitor.core.rules import channels
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules import fatigue as fatigue_rule
from catenary_monitor.core.rules import holding as holding_rule
from catenary_monitor.core.rules import sensor_state, tide_trend, uncertainty, wave_window
from catenary_monitor.core.rules.health import clock_status
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.rules.plausible import UnitsMemory, status_messages

__all__ = [
    'OUTPUT_FIELDS',
    'VALUE_FIELDS',
    'VALUE_INDEX',
    'NAN_VALUES',
    'NO_DEPTH',
    'NO_MODEL',
    'LineState',
    'CoreState',
    'TidePart',
    'SensorPart',
    'BlindPart',
    'DockPart',
    'FloodPart',
    'ComponentAckPart',
    'StampPart',
    'LineInputPart',
    'LineSolvePart',
    'LineRulesPart',
    'LineAlarmPart',
    'with_sensor',
    'with_span',
    'with_fatigue',
    'set_channels',
    'set_implausible',
    'output_values',
]

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

_NAN = math.nan
#: A line's values before its first solve.
NAN_VALUES = (_NAN,) * len(VALUE_FIELDS)
#: Each of :data:`VALUE_FIELDS` -> its index in a line's values.
VALUE_INDEX = {key: i for i, key in enumerate(VALUE_FIELDS)}
_SENSOR_AT = VALUE_FIELDS.index('sensor_state')  # not a solved value: kept by set_implausible


# --- a line's parts: what the twin's decisions over a window write of a line

class LineInputPart(NamedTuple):
    """The newest accepted tension sample [N], its stamps, and when a sample was last refused."""

    tension: float
    tension_s: float
    sample_ns: int
    stamp_refused: float


class LineSolvePart(NamedTuple):
    """The newest solve: :data:`VALUE_FIELDS` values, solver status, its sentence, model."""

    values: tuple[float, ...]
    status: int
    status_message: str
    model: str


class LineRulesPart(NamedTuple):
    """What the per-line rules carry: the sensor memory and state, the wave window, the fatigue
    count, the channels and the dock estimate's view of the line."""

    sensor_memory: sensor_state.Memory
    sensor_code: int
    parted_seen: float
    firm_seen: float
    units: UnitsMemory
    wave: wave_window.WaveState
    peak_tension: float
    wave_tension: float
    fatigue: fatigue_rule.FatigueState
    fatigue_values: tuple[float, ...]
    channels: Optional[channels.ChannelState]
    channel_values: tuple[float, ...]
    dock: tuple[float, ...]
    dock_span: float


class LineAlarmPart(NamedTuple):
    """The line's alarm: its latches, level and message, and its acknowledgement state."""

    state: AlarmState
    ack: alarm_ack.AckState


LinePart = TypeVar('LinePart', LineInputPart, LineSolvePart, LineRulesPart, LineAlarmPart)


@dataclass
class LineState:
    """Everything the core remembers of one line between events."""

    config: LineConfig
    alarm: LineAlarm
    hardware_id: str
    state: AlarmState
    tension: float = _NAN  # N, newest sample
    tension_s: float = _NAN  # s, its stamp (NaN: none yet)
    values: tuple[float, ...] = NAN_VALUES  # VALUE_FIELDS of the newest solve
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
    firm_seen: float = -math.inf  # s, the newest tick with the tension above w*h
    units: UnitsMemory = UnitsMemory()  # the wrong-units latch (core.rules.plausible)
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
        self,
        depth_s: float,
        depth_stale: bool,
        rate: float = _NAN,
        table: bool = False,
        silent_group: bool = False,
        blind: bool = False,
        parted_other: float = _NAN,
    ) -> AlarmInputs:
        """The alarm inputs of this line now (newest results, stamps, the tide's decision and
        its trend ``rate`` [m/s]; ``table``: the time to uplift is the tide table's;
        ``silent_group``: silent under a common cause at the newest tick; ``blind``: the
        ``sensors`` alarm stands, so the dock estimate's disagreement is its consequence,
        shown and not this line's alarm: ``inconsistent`` untested); ``parted_other``: the
        index of another line suspected parted at the newest tick (NaN none)."""
        v, d = self.values, self.dock
        return AlarmInputs(
            uplift_force=v[5],
            anchor_margin=v[4],
            tide_margin=v[6],
            load_margin=v[7],
            safety_factor=v[8],
            time_to_uplift=v[11],
            uplift_force_upper=v[VALUE_INDEX['uplift_force_upper']],
            drag_margin=v[VALUE_INDEX['drag_margin']],
            holding_capacity=v[VALUE_INDEX['holding_capacity']],
            tide_rate=rate,
            tide_forecast=1.0 if table else 0.0,
            status=max(self.status, 0),
            status_message=self.status_message,
            tension_stamp=self.tension_s,
            depth_stamp=depth_s,
            depth_stale=depth_stale,
            inconsistent=_NAN if blind else d[0],
            dock_residual=d[1],
            dock_expected=d[2],
            dock_sigma=d[3],
            sensor_state=float(self.sensor_code),
            sensor_tension=self.tension,
            mbl=self.config.mbl,
            drag_state=v[VALUE_INDEX['drag_state']],
            implied_anchor_distance=v[VALUE_INDEX['implied_anchor_distance']],
            fatigue_damage=self.fatigue_values[0],
            fatigue_life_left=self.fatigue_values[2],
            dynamic_uplift=v[VALUE_INDEX['dynamic_uplift']],
            uplift_view=v[VALUE_INDEX['time_to_uplift_view']],
            channels_healthy=self.channel_values[0],
            channel_states=self.channel_values[1],
            span=v[VALUE_INDEX['span']],
            silent_group=1.0 if silent_group else 0.0,
            parted_other=parted_other,
        )

    def read(self, kind: type[LinePart]) -> LinePart:
        """The line's fields of one part (the twin's door)."""
        return kind(*(getattr(self, name) for name in kind._fields))

    def take(self, part: LinePart) -> None:
        """Write one part's fields (the twin's door)."""
        for name, value in zip(part._fields, part):
            setattr(self, name, value)


# --- the core's parts: what the twin's decisions over a window write of the core


class TidePart(NamedTuple):
    """The newest depth sample (m, its stamps, when one was last refused), the tide's trend
    and decision (level and message, when that level was entered, the depth stale)."""

    depth: float
    depth_s: float
    depth_sample_ns: int
    depth_refused: float
    trend: tide_trend.TrendState
    tide: tuple[Level, str]
    tide_entered: float
    depth_stale: bool


class SensorPart(NamedTuple):
    """The sensor decisions' memory: the depth sensor's and its state, the ticks and
    tensions the suspected_parted test still needs, and the common causes of silence at the
    newest tick (each line's and the depth's flag, the groups)."""

    depth_memory: sensor_state.DepthMemory
    depth_code: int
    sensor_times: np.ndarray
    sensor_rows: np.ndarray
    silent_grouped: tuple[bool, ...]
    common_causes: tuple[tuple[tuple[str, ...], float], ...]


class BlindPart(NamedTuple):
    """The sensors' common-cause alarm: its status, the lines waiting, when its level was
    entered, its acknowledgement state."""

    sensors: tuple[Level, str]
    sensors_waiting: int
    sensors_entered: float
    sensors_ack: alarm_ack.AckState


class DockPart(NamedTuple):
    """The dock estimate's status, when its level was entered, its values and smoothing."""

    dock: tuple[Level, str]
    dock_entered: float
    dock_values: tuple[tuple[str, str], ...]
    dock_smoothing: dock_live.Smoothing


class FloodPart(NamedTuple):
    """The alarm flood: its decision, the ``alarms`` status and when its level was entered."""

    flood: alarm_flood.Flood
    alarms: tuple[Level, str]
    alarms_entered: float


class ComponentAckPart(NamedTuple):
    """The component statuses' alarms (:mod:`~catenary_monitor.core.alarms.components`), in
    :data:`~catenary_monitor.core.alarms.journal.COMPONENTS` order."""

    component_acks: tuple[alarm_ack.AckState, ...]


class StampPart(NamedTuple):
    """The newest event's stamp [ns]."""

    last_ns: int


CorePart = TypeVar(
    'CorePart', TidePart, SensorPart, BlindPart, DockPart, FloodPart, ComponentAckPart, StampPart
)


@dataclass
class CoreState:
    """Everything the core's decisions carry from one event to the next (its lines' too).

    The vectorized twin (:mod:`catenary_monitor.core.twin.engine`) reads and writes the core
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
    depth_memory: sensor_state.DepthMemory = field(default_factory=sensor_state.DepthMemory)
    depth_code: int = sensor_state.OK  # the depth sensor's state at the newest tick
    # Silent under a common cause at the newest tick (core.rules.health.common_cause): each
    # line's flag, then the depth's; the causes (inputs, since when [s]).
    silent_grouped: tuple[bool, ...] = ()
    common_causes: tuple[tuple[tuple[str, ...], float], ...] = ()
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
    # The alarm system (core.alarms.flood): the flood status, the raises it counts.
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
    # The component statuses' alarms (acknowledgeable: core.alarms.components), COMPONENTS order.
    component_acks: tuple[alarm_ack.AckState, ...] = ()

    def read(self, kind: type[CorePart]) -> CorePart:
        """The core's fields of one part (the twin's door)."""
        return kind(*(getattr(self, name) for name in kind._fields))

    def take(self, part: CorePart) -> None:
        """Write one part's fields (the twin's door)."""
        for name, value in zip(part._fields, part):
            setattr(self, name, value)


# --- a line's values


def with_sensor(values: tuple[float, ...], code: int) -> tuple[float, ...]:
    """``values`` with the line's sensor state code in its place (``sensor_state``)."""
    return values[:_SENSOR_AT] + (float(code),) + values[_SENSOR_AT + 1 :]


_SPAN_AT = VALUE_FIELDS.index('span')


def with_span(values: tuple[float, ...], span: tuple[float, float]) -> tuple[float, ...]:
    """``values`` with the span solved at [m] and its ``span_source`` code in their places."""
    return values[:_SPAN_AT] + tuple(span) + values[_SPAN_AT + 2 :]


_FATIGUE_AT = VALUE_FIELDS.index(fatigue_rule.FIELDS[0])


def with_fatigue(values: tuple[float, ...], fatigue: tuple[float, ...]) -> tuple[float, ...]:
    """``values`` with the line's fatigue values in their places."""
    end = _FATIGUE_AT + len(fatigue)
    return values[:_FATIGUE_AT] + tuple(fatigue) + values[end:]


_CHANNELS_AT = VALUE_FIELDS.index(channels.FIELDS[0])


def set_channels(line: LineState) -> None:
    """The line's values with its channels' values in their places."""
    v, end = line.values, _CHANNELS_AT + len(channels.FIELDS)
    line.values = v[:_CHANNELS_AT] + tuple(line.channel_values) + v[end:]


def set_implausible(line: LineState, code: int) -> None:
    """An implausible reading (core.rules.plausible): its status and sentence, no solved values
    (the measured tension and depth kept, as for every impossible input)."""
    line.values = line.values[:2] + NAN_VALUES[2:_SENSOR_AT] + line.values[_SENSOR_AT:]
    line.status, line.status_message = code, status_messages(line.config)[code]
    line.model = elastic.INEXTENSIBLE


def output_values(values: Sequence[float], status: float, level: float) -> tuple[float, ...]:
    """One output message's elements (:data:`OUTPUT_FIELDS` order) from the
    :data:`VALUE_FIELDS` values, the solver status and the level."""
    v = tuple(float(x) for x in values)
    return v[:11] + (float(status), float(int(level))) + v[11:]
