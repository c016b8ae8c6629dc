"""The monitor core: one object that owns every decision of the live monitor (no rclpy, no clock).

:class:`MonitorCore` holds the per-line state (newest inputs and results, alarm states: its
:class:`~catenary_monitor.core.monitor.state.CoreState`), the tide and logger statuses, and
turns each event (:mod:`catenary_monitor.core.monitor.events`) into one :class:`Step`.

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

The :class:`Step` carries the outputs of the lines solved
(:data:`~catenary_monitor.core.monitor.state.OUTPUT_FIELDS`), the snapshot
(or None), the level transitions and the alarm journal's records
(:mod:`catenary_monitor.core.alarms.journal`). A line is never OK while blind: before
its first tension and before the first depth it is STALE and says what is missing. Times in the
alarm logic are seconds (``stamp_ns * 1e-9``); forces N, lengths m.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, NamedTuple, Optional, Sequence, Union

import numpy as np

from catenary_monitor.core.alarms import acknowledge as alarm_ack
from catenary_monitor.core.alarms import components as component_alarm
from catenary_monitor.core.alarms import flood as alarm_flood
from catenary_monitor.core.alarms import shelving
from catenary_monitor.core.alarms.journal import (
    COMPONENTS,
    CONSEQUENCES,
    AlarmEvent,
    component_entries,
    entries,
)
from catenary_monitor.core.alarms.latches import (
    CONDITIONS,
    LineAlarm,
    Transition,
    blind_quiet,
)
from catenary_monitor.core.body.dock_model import DockModel
from catenary_monitor.core.config.parameters import (
    MonitorConfig,
    resolve_topic,
    runtime_change_messages,
)
from catenary_monitor.core.monitor.derived import add_derived
from catenary_monitor.core.monitor.events import (
    NODE_NAME,
    REASON_LIMIT,
    FATIGUE_STORE_STATES,
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
    Tension,
    Tick,
)
from catenary_monitor.core.monitor.state import (
    NAN_VALUES,
    NO_DEPTH,
    NO_MODEL,
    VALUE_FIELDS,
    CoreState,
    LineState,
    output_values,
    set_implausible,
    with_fatigue,
    with_sensor,
    with_span,
)
from catenary_monitor.core.monitor.status import (
    Change,
    ComponentStatus,
    Snapshot,
    depth_word,
    dock_component,
    forecast_word,
    line_dock_values,
    line_dock_word,
    line_status,
    sensors_component,
    tide_component,
    tide_with_sensor,
    with_texts,
)
from catenary_monitor.core.physics.solve import solve
from catenary_monitor.core.rules import channels
from catenary_monitor.core.rules import dock_watch as dock_live
from catenary_monitor.core.rules import fatigue as fatigue_rule
from catenary_monitor.core.rules import readings, sensor_state, tide_trend, wave_window
from catenary_monitor.core.rules.health import (
    BUSY_WINDOW,
    INTAKE_WINDOW,
    clock_status,
    intake_status,
    logger_status,
    missing_samples,
    parameters_status,
    DEPTH_INPUT,
    common_cause,
    common_cause_groups,
    sensors_status,
    tide_status,
)
from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.rules import plausible
from catenary_monitor.core.rules.plausible import reading_status, reading_status_array

__all__ = [
    'LineOutput',
    'Step',
    'MonitorCore',
    'channel_limits',
    'sensor_limits',
    'input_names',
    'silence_timeouts',
    'component_log',
]

_NAN = math.nan
_INCONSISTENT = CONDITIONS.index('inconsistent')
_SOLVED = VALUE_FIELDS[2:11]  # taken from the solve result (the first two are the inputs)
#: The components whose STALE is a consequence of blind inputs, announced by the sensors alarm.
_CONSEQUENCES = CONSEQUENCES


class LineOutput(NamedTuple):
    """The outputs of line number ``line`` after a solve: :data:`OUTPUT_FIELDS` as floats."""

    line: int
    values: tuple[float, ...]


class Step(NamedTuple):
    """What one event did: the outputs of the lines solved, the snapshot (or None), the
    transitions, the alarm journal's records and, for a shelving request or a refused one,
    the monitor's answer (``note``); ``kind`` is ``tension``, ``depth``, ``tick``, ``logger``,
    ``configure``, ``acknowledge``, ``shelve``, ``refused``, ``clock`` or ``intake``."""

    stamp_ns: int
    kind: str
    outputs: tuple[LineOutput, ...]
    snapshot: Optional[Snapshot]
    transitions: tuple[Change, ...]
    alarm_events: tuple[AlarmEvent, ...] = ()
    note: str = ''


def _stamp_s(stamp_ns: int) -> float:
    return stamp_ns * 1e-9


def _active(ack: alarm_ack.AckState) -> bool:
    """Whether the alarm's condition is active (not returned)."""
    return ack.active_since == ack.active_since


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

    __slots__ = (
        'config',
        'index',
        'depth_id',
        'logger_id',
        'dock_model',
        'curves',
        'rest_table',
        'state',
    )

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
        peers = tuple(lc.name for lc in config.lines)
        lines = [
            LineState(
                lc,
                LineAlarm.for_line(lc, config.alarm, peers),
                ids.get(lc.name, resolve_topic(lc.tension_topic)),
                LineAlarm.for_line(lc, config.alarm, peers).initial(start),
                ack=alarm_ack.initial(start),
                fatigue=fatigue_rule.initial(lc.fatigue_damage_initial),
                fatigue_values=(lc.fatigue_damage_initial, _NAN, _NAN),
                channels=channels.initial(len(lc.channel_topics)) if lc.channel_topics else None,
            )
            for lc in config.lines
        ]
        self.curves = [fatigue_rule.Curve.of(lc) for lc in config.lines]
        self.rest_table = plausible.rest_table(config, config.chart)
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
            silent_grouped=(False,) * (len(lines) + 1),
        )
        self.state.sensors = self._sensors_now(start)
        self.state.alarms = alarm_flood.status(self.state.flood, config.alarm)
        self.state.alarms_entered = start
        levels = [self.component_level(name) for name in COMPONENTS]
        self.state.component_acks = component_alarm.initial(levels, start)

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
        if isinstance(event, Refusal):
            return self._on_refusal(event)
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
            a.stamp_jitter,
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
        self.state.depth_memory = sensor_state.sample_depth(
            self.state.depth_memory,
            self.state.depth_s,
            self.state.depth,
            a,
            self.state.trend.rate,
            a.stamp_jitter,
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
        self._decide_units(ev.stamp_ns)
        changes += self._step_lines(range(len(self.state.lines)), ev.stamp_ns, log)
        changes += self._decide_flood(ev.stamp_ns, log, tick=True)
        snapshot = self.snapshot(ev.stamp_ns)
        log = component_log(changes) + log
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
                line.values = with_fatigue(line.values, line.fatigue_values)
        self.state.fatigue_seen = True
        self.state.fatigue_word = ev.state
        level = FATIGUE_STORE_STATES.get(ev.state, Level.WARN)
        changes = self._set_component('fatigue', (level, ev.message), ev.stamp_ns)
        snapshot = self.snapshot(ev.stamp_ns)
        log = tuple(component_log(changes))
        return Step(ev.stamp_ns, 'fatigue', (), snapshot, tuple(changes), log)

    def _on_logger(self, ev: LoggerHealth) -> Step:
        new = logger_status(ev.error, ev.path, ev.warning)
        changes = self._set_component('logger', new, ev.stamp_ns)
        return self._finish(ev.stamp_ns, 'logger', [], changes)

    def _on_acknowledge(self, ev: Acknowledge) -> Step:
        """Acknowledge one line's alarm (or every line's); the snapshot shows it at once. An
        unknown name changes nothing: a refused request in the journal (``level``
        ``acknowledge``), the step's ``note`` its answer."""
        now = _stamp_s(ev.stamp_ns)
        log: list[AlarmEvent] = []
        known = ev.line in self.index or ev.line == alarm_ack.SENSORS
        if ev.line is not None and not known and not component_alarm.acknowledgeable(ev.line):
            names = ', '.join([*self.index, alarm_ack.SENSORS, *COMPONENTS])
            refusal = Refusal(
                ev.stamp_ns, 'acknowledge', ev.line, f'unknown alarm (alarms: {names})', ev.origin
            )
            return self._on_refusal(refusal)
        for line in self.state.lines:
            if ev.line is None or ev.line == line.config.name:
                old = line.ack
                line.ack = alarm_ack.acknowledge(old, now, ev.origin, ev.publisher)
                log += entries(line.config.name, old, line.ack, now)
        if ev.line is None or ev.line == alarm_ack.SENSORS:
            old = self.state.sensors_ack
            self.state.sensors_ack = alarm_ack.acknowledge(old, now, ev.origin, ev.publisher)
            log += entries(alarm_ack.SENSORS, old, self.state.sensors_ack, now)
        acks = list(self.state.component_acks)
        for k, name in enumerate(COMPONENTS):
            if ev.line is None or ev.line == name:
                old = acks[k]
                acks[k] = alarm_ack.acknowledge(old, now, ev.origin, ev.publisher)
                log += entries(name, old, acks[k], now)
        self.state.component_acks = tuple(acks)
        snapshot = self.snapshot(ev.stamp_ns)
        return Step(ev.stamp_ns, 'acknowledge', (), snapshot, (), tuple(log))

    def _on_shelve(self, ev: Shelve) -> Step:
        """Shelve or unshelve an alarm (core.alarms.shelving's rules) or refuse to; the answer is
        the step's ``note`` and the ``alarms`` status's ``shelve_answer``, shown at once."""
        now = _stamp_s(ev.stamp_ns)
        a = self.config.alarm
        request = shelving.ShelveRequest(ev.alarm, ev.condition, ev.seconds, ev.origin)
        k = self.index.get(ev.alarm)
        line = None if k is None else self.state.lines[k]
        active = None if line is None else [latch.active for latch in line.state.latches]
        names = [ln.config.name for ln in self.state.lines]
        target = ev.alarm if ev.condition == alarm_ack.WHOLE else f'{ev.alarm}.{ev.condition}'
        stale = line is not None and line.state.stale
        refused = shelving.refusal(request, names, a, active, stale)
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

    def _on_refusal(self, ev: Refusal) -> Step:
        """A request refused before the alarm rules (its record in the journal: ``refused``,
        the reason, who, ``value`` the requests it stands for; ``level`` ``acknowledge`` for
        an acknowledgement's). A shelving request's is its answer, as the rules' refusals
        are (the ``alarms`` status, shown at once); the answer is the step's ``note``."""
        now = _stamp_s(ev.stamp_ns)
        target = alarm_ack.bounded_text(ev.alarm, 120) or '?'
        reason = alarm_ack.bounded_text(ev.reason, REASON_LIMIT)
        many = f' ({ev.requests} requests)' if ev.requests > 1 else ''
        answer = f'{target}: refused: {reason}{many}'
        record = AlarmEvent(
            now,
            target,
            'refused',
            '' if ev.request == 'shelve' else ev.request,
            reason,
            alarm_ack.bounded_text(ev.origin),
            float(ev.requests),
        )
        if ev.request != 'shelve':
            return Step(ev.stamp_ns, 'refused', (), None, (), (record,), answer)
        self.state.shelve_answer = answer
        self.state.shelve_requests += int(ev.requests)
        snapshot = self.snapshot(ev.stamp_ns)
        return Step(ev.stamp_ns, 'refused', (), snapshot, (), (record,), answer)

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
        condition, covers = ev.condition, ''
        if line is not None and condition == alarm_ack.WHOLE:
            # a line shelf covers the conditions active now, never a later one
            up = [latch.active for latch in line.state.latches]
            unshelvable = self.config.alarm.unshelvable_conditions
            condition = ','.join(shelving.active_conditions(up, line.state.stale, unshelvable))
            covers = f': {condition} (a new condition still annunciates)'
        masked = self._masked(line, replace(old, shelved_condition=condition))
        new = alarm_ack.shelve(
            old, now, until, condition, ev.origin, masked, suppressed, ev.publisher
        )
        return new, f'{target} shelved for {ev.seconds:g} s by {ev.origin}{covers}'

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
        """The flood decision (core.alarms.flood) after an event that raised an alarm, or at a
        tick; its start and end go to the journal ``log``."""
        raised = [(e.time, e.alarm) for e in log if e.kind == 'raised' and self._counted(e.alarm)]
        if not raised and not tick:
            return []
        now = _stamp_s(stamp_ns)
        old = self.state.flood
        active = [ln.config.name for ln in self.state.lines if _active(ln.ack)]
        active += [alarm_ack.SENSORS] if _active(self.state.sensors_ack) else []
        new = alarm_flood.decide(old, raised, now, self.config.alarm, active)
        self.state.flood = new
        if new.since == new.since and old.since != old.since:
            name, at = new.first_out
            log.append(AlarmEvent(now, alarm_flood.NAME, 'flood', 'WARN', by=name, value=at))
        elif old.since == old.since and new.since != new.since:
            log.append(AlarmEvent(now, alarm_flood.NAME, 'flood_end', value=now - old.since))
        return self._set_component('alarms', alarm_flood.status(new, self.config.alarm), stamp_ns)

    def _counted(self, alarm: str) -> bool:
        """Whether a raise of ``alarm`` counts in the flood (a line's, the sensors')."""
        return alarm in self.index or alarm == alarm_ack.SENSORS

    def _on_clock(self, ev: ClockHealth) -> Step:
        """The ROS clock's state; always a snapshot (the node sends these on a wall-clock
        timer while the ROS clock stands still, so /diagnostics keeps coming)."""
        self.state.clock_seen = True
        changes = self._set_component('clock', clock_status(ev.stopped_for), ev.stamp_ns)
        snapshot = self.snapshot(ev.stamp_ns)
        log = tuple(component_log(changes))
        return Step(ev.stamp_ns, 'clock', (), snapshot, tuple(changes), log)

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
            self.config.alarm.intake_warn_count,
            self.config.alarm.intake_warn_share,
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
            self._follow_component('parameters', self.state.changes_until)
        self.state.changes = held + tuple(messages)
        self.state.changes_until = now + ev.config.runtime_change_warn_time
        new = parameters_status(self.state.changes, self.state.changes_until, now)
        changes = self._set_component('parameters', new, ev.stamp_ns)
        snapshot = self.snapshot(ev.stamp_ns)
        log = tuple(component_log(changes))
        return Step(ev.stamp_ns, 'configure', (), snapshot, tuple(changes), log)

    def reconfigure(self, config: MonitorConfig) -> None:
        """Take new line constants and alarm rules (same line names); alarm states are kept."""
        names = [lc.name for lc in config.lines]
        if names != [line.config.name for line in self.state.lines]:
            raise ValueError(f'reconfigure: the lines must stay {list(self.index)}, got {names}')
        if config.alarm.tide_trend_window != self.config.alarm.tide_trend_window:
            self.state.trend = tide_trend.TrendState()  # other bins: the trend starts again
        self.config = config
        self.curves = [fatigue_rule.Curve.of(lc) for lc in config.lines]
        self.rest_table = plausible.rest_table(config, config.chart)
        peers = tuple(lc.name for lc in config.lines)
        for line, lc in zip(self.state.lines, config.lines):
            line.config, line.alarm = lc, LineAlarm.for_line(lc, config.alarm, peers)
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
        new = tide_with_sensor(
            status, self.state.depth_code, self.state.depth, self.config.alarm, self.config.chart
        )
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
            self.state.common_causes,
            [line.config.name for line in self.state.lines],
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
        limits = sensor_limits(self.config)
        depth = np.array([self.state.depth])
        slack = sensor_state.slack_mask(limits, tension, depth)
        pattern = sensor_state.parted_pattern(tension, ref, a.parted_drop, slack)
        seen = np.array([[line.parted_seen for line in lines]])
        seen = np.where(pattern, now[:, None], seen)
        firm = np.array([line.firm_seen for line in lines])
        firm = sensor_state.firm_times(now, slack, firm)
        tension_s = np.array([[line.tension_s for line in lines]])
        self.state.sensor_times = np.append(self.state.sensor_times[keep:], now)
        spiked = np.array([[line.sensor_memory.spiked for line in lines]])
        row = sensor_state.history_row(now, tension, spiked, a.sensor_hold)
        self.state.sensor_rows = np.vstack([self.state.sensor_rows[keep:], row])
        codes = sensor_state.decide_lines(
            a,
            limits,
            now,
            tension,
            tension_s,
            changed,
            spiked,
            seen,
            depth,
            np.array([self.state.depth_memory.changed]),
            np.array([[line.stamp_refused for line in lines]]),
            firm,
        )
        for k, line in enumerate(lines):
            line.sensor_code, line.parted_seen = int(codes[0, k]), float(seen[0, k])
            line.firm_seen = float(firm[0, k])
        last = np.array([[line.tension_s for line in lines] + [self.state.depth_s]])
        grouped = common_cause(
            last, now, silence_timeouts(self.config), a.common_cause_window,
            self.state.silent_grouped,
        )[0]  # fmt: skip
        self.state.silent_grouped = tuple(grouped.tolist())
        self.state.common_causes = common_cause_groups(
            input_names(self.config), last[0], grouped, a.common_cause_window
        )
        d_changed, d_spiked, sea = sensor_state.sea_columns([self.state.depth_memory])
        self.state.depth_code = int(
            sensor_state.decide_depth(
                a,
                now,
                np.array([self.state.depth]),
                np.array([self.state.depth_s]),
                d_changed,
                d_spiked,
                sea,
                np.array([self.state.depth_refused]),
                self.config.chart,
            )[0]
        )

    def _decide_units(self, stamp_ns: int) -> None:
        """The units check at a tick, after the dock estimate (one of its witnesses):
        each line's ``wrong_units`` claim over its sensor state (core.rules.plausible)."""
        a, lines = self.config.alarm, self.state.lines
        now = np.array([_stamp_s(stamp_ns)])
        dock = None
        if self.dock_model is not None:
            dock = np.array([[line.dock for line in lines]])
        units, memories = plausible.units_decide(
            self.rest_table,
            units_rule(self.config),
            [line.units for line in lines],
            now,
            np.array([[line.tension for line in lines]]),
            np.array([[line.tension_s for line in lines]]),
            np.array([self.state.depth]),
            np.array([self.state.depth_s]),
            (a.tension_timeout, a.depth_timeout),
            self.config.chart,
            dock,
        )
        codes = sensor_state.with_units(np.array([[line.sensor_code for line in lines]]), units)
        for k, line in enumerate(lines):
            line.sensor_code, line.units = int(codes[0, k]), memories[k]

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
        self._follow_component(name, now)
        quiet = name in _CONSEQUENCES and blind_quiet(old[0], new[0])
        return [Change(name, Transition(now, old[0], new[0], new[1], now - entered, quiet))]

    def component_level(self, name: str) -> Level:
        """The level of the component status ``name`` (:data:`COMPONENTS`) as shown now (the
        runtime-change flag's as at its newest event)."""
        level: Level = getattr(self.state, name)[0]
        return level

    def component_ack(self, name: str) -> alarm_ack.AckState:
        """The alarm of the component status ``name`` (:data:`COMPONENTS`)."""
        return self.state.component_acks[COMPONENTS.index(name)]

    def _follow_component(self, name: str, now: float) -> None:
        """Step the component ``name``'s alarm to its level, at ``now`` [s]."""
        if name not in COMPONENTS:
            return
        k = COMPONENTS.index(name)
        acks = self.state.component_acks
        new = component_alarm.follow(acks[k], name, self.component_level(name), now)
        if new is not acks[k]:
            self.state.component_acks = acks[:k] + (new,) + acks[k + 1 :]

    def _solve_one(self, line: LineState) -> None:
        """Solve one line at the newest depth (the scalar fast path)."""
        lc, t = line.config, line.tension
        h = self.state.depth + lc.hook_height
        span = line.span()
        if self.state.depth_s != self.state.depth_s:  # no depth yet: nothing to solve
            line.values, line.status, line.status_message, line.model = (
                with_span(with_sensor((t, h) + NAN_VALUES[2:], line.sensor_code), span),
                NO_DEPTH,
                '',
                NO_MODEL,
            )
            add_derived([line], self.config.alarm, self.state.depth_s, self.state.trend)
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
        line.values = with_sensor(line.values + NAN_VALUES[len(line.values) :], line.sensor_code)
        line.values = with_span(line.values, span)
        line.status, line.status_message, line.model = int(r.status), r.message, r.model
        lo, hi = self.config.chart
        code = reading_status(t, h, lc.mbl, lc.weight, lo + lc.hook_height, hi + lc.hook_height)
        if code:
            set_implausible(line, code)
        add_derived([line], self.config.alarm, self.state.depth_s, self.state.trend)

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
            line.values = tuple(col[i] for col in columns) + NAN_VALUES[len(columns) :]
            line.values = with_span(with_sensor(line.values, line.sensor_code), spans[i])
            line.status, line.status_message = int(status[i]), str(messages[i])
            line.model = str(models[i])
        lo, hi = self.config.chart
        hook = np.array([c.hook_height for c in cfgs])
        codes = reading_status_array(
            tension, h, [c.mbl for c in cfgs], [c.weight for c in cfgs], lo + hook, hi + hook
        ).tolist()
        for line, code in zip(lines, codes):
            if code:
                set_implausible(line, code)
        add_derived(lines, self.config.alarm, self.state.depth_s, self.state.trend)

    def _step_lines(self, which: Any, stamp_ns: int, log: list[AlarmEvent]) -> list[Change]:
        """Step the alarms of the given lines at ``stamp_ns``; their transitions (their
        alarms' records to the journal ``log``)."""
        now = _stamp_s(stamp_ns)
        chatter = self._chatter()
        changes = []
        codes = np.array([[line.sensor_code for line in self.state.lines]])
        parted = sensor_state.parted_others(codes)[0].tolist()
        for k in which:
            line = self.state.lines[k]
            line.state, events = line.alarm.update(
                line.state,
                line.inputs(
                    self.state.depth_s,
                    self.state.depth_stale,
                    self.state.trend.rate,
                    bool(self.config.alarm.constituents),
                    self.state.silent_grouped[k],
                    self.state.sensors[0] != Level.OK,
                    parted[k],
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
        log = component_log(changes) + log
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
                [latch.active for latch in line.state.latches],
                self.config.response_texts,
            )
            for line in self.state.lines
        ]
        n_lines = len(statuses)
        statuses.append(
            tide_component(
                self.state.tide,
                self.depth_id,
                self.state.depth,
                now - self.state.depth_s,
                self.state.trend.rate,
                depth_word(self.state.depth_s, self.state.depth_code),
                forecast_word(self.config, self.state.trend.rate),
                self.component_ack('tide'),
            )
        )
        statuses.append(
            sensors_component(
                self.state.sensors, self.state.sensors_ack, self.state.sensors_waiting
            )
        )
        statuses.append(self.alarms_component(self.state.alarms, self.state.flood))
        statuses.append(self.logger_component())
        if dock:
            ack = self.component_ack('dock')
            statuses.append(dock_component(self.state.dock, self.state.dock_values, ack))
        statuses += self.guard_components(now)
        return Snapshot(stamp_ns, tuple(statuses[:n_lines]) + self.texts(statuses[n_lines:]))

    def texts(self, statuses: Sequence[ComponentStatus]) -> tuple[ComponentStatus, ...]:
        """The components' statuses with their headlines, details and response texts
        (:func:`~catenary_monitor.core.monitor.status.with_texts`)."""
        return tuple(with_texts(s, self.config.response_texts) for s in statuses)

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

    def logger_component(self) -> ComponentStatus:
        """The ``catenary_monitor: logger`` status, its alarm's keys as values."""
        level, message = self.state.logger
        values = self.alarm_values('logger', level)
        return ComponentStatus(f'{NODE_NAME}: logger', level, message, self.logger_id, values)

    def alarm_values(self, name: str, level: Level) -> tuple[tuple[str, str], ...]:
        """The ``/diagnostics`` keys of the component ``name``'s alarm at ``level``
        (:func:`~catenary_monitor.core.alarms.components.values`)."""
        return component_alarm.values(self.component_ack(name), name, level)

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
            values = self.alarm_values('clock', self.state.clock[0])
            clock = ComponentStatus(f'{NODE_NAME}: clock', *self.state.clock, NODE_NAME, values)
            out.append(clock)
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
            ) + self.alarm_values('intake', self.state.intake[0])
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
        values: tuple[tuple[str, str], ...] = (
            ('store_state', self.state.fatigue_word),
            ('max_damage', repr(max_damage)),
        )
        values += self.alarm_values('fatigue', self.state.fatigue[0])
        return ComponentStatus(f'{NODE_NAME}: fatigue', *self.state.fatigue, NODE_NAME, values)

    def parameters_component(self, now: float) -> Optional[ComponentStatus]:
        """The runtime-change status at ``now`` [s] (None when runtime changes are not
        allowed and none was made): WARN naming the changes until their flag expires."""
        if not (self.config.allow_runtime_changes or self.state.changes):
            return None
        level, message = parameters_status(self.state.changes, self.state.changes_until, now)
        until = repr(float(self.state.changes_until)) if self.state.changes else 'nan'
        values: tuple[tuple[str, str], ...] = (
            ('changes', str(len(self.state.changes))),
            ('flagged_until', until),
        )
        values += self.alarm_values('parameters', level)
        return ComponentStatus(f'{NODE_NAME}: parameters', level, message, NODE_NAME, values)


def channel_limits(core: MonitorCore, line: LineState) -> channels.Limits:
    """The channel rules of a line (core.rules.channels.Limits)."""
    a = core.config.alarm
    return channels.Limits(
        a.tension_timeout,
        a.stuck_time,
        a.tension_resolution,
        a.channel_tolerance,
        int(line.config.min_channels),
    )


def component_log(changes: Sequence[Change]) -> list[AlarmEvent]:
    """The journal records of the component statuses' level ``changes`` (the tide, the
    intake, ...: :data:`~catenary_monitor.core.alarms.journal.COMPONENTS`), in order."""
    out: list[AlarmEvent] = []
    for change in changes:
        if change.component in COMPONENTS:
            out += component_entries(change.component, change.transition)
    return out


def input_names(config: MonitorConfig) -> list[str]:
    """The inputs a common cause can silence: each line's name, then ``depth``."""
    return [c.name for c in config.lines] + [DEPTH_INPUT]


def silence_timeouts(config: MonitorConfig) -> np.ndarray:
    """Each line's ``tension_timeout``, then ``depth_timeout`` [s]."""
    a = config.alarm
    return np.array([a.tension_timeout] * len(config.lines) + [a.depth_timeout])


def units_rule(config: MonitorConfig) -> plausible.UnitsRule:
    """The units check's rule (core.rules.plausible): ``units_window``, the rest fixed."""
    return plausible.UnitsRule(window=config.alarm.units_window)


def sensor_limits(config: MonitorConfig) -> sensor_state.LineLimits:
    """The per-line constants of the sensor decision (MBL, weight, hook height)."""
    lines = config.lines
    return sensor_state.LineLimits(
        np.array([c.mbl for c in lines]),
        np.array([c.weight for c in lines]),
        np.array([c.hook_height for c in lines]),
    )
