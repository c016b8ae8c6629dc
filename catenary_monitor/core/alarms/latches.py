"""Per-line alarm logic: a pure state machine that is handed the time, and its vectorized replay.

No clocks and no rclpy: the node passes its clock (``use_sim_time`` honoured), replay passes log
times, and both get the same transitions. Times are seconds on one clock, forces N, lengths m.

Conditions, each with its own latch:

``uplift`` (ERROR)
    raised when ``uplift_force > allowed_uplift`` has lasted ``on_delay`` (0: at the first such
    update); cleared when ``uplift_force <= max(allowed_uplift - uplift_clear_hysteresis, 0)``
    (and, when that level is 0 N, ``anchor_margin`` at or above the larger of
    ``uplift_clear_margin`` and the anchor-margin warning's clear level, ``anchor_margin_warn +
    anchor_margin_deadband``: the deadband of the ERROR is at least the warning's, so the ERROR
    never steps down into that warning and back up with the next wave group) has held for
    ``clear_hold``.
``input`` (ERROR)
    raised at once by an impossible input (solver ``status != 0``: NaN, negative tension,
    tension <= weight * depth, ...); cleared after ``clear_hold`` of valid input.
``anchor_margin``, ``tide_margin``, ``load_margin``, ``safety_factor`` (WARN)
    raised when the value ``< *_warn`` has lasted ``on_delay``; cleared when ``>= *_warn +
    *_deadband`` has held for ``margin_clear_hold`` (600 s): the values swing with the waves
    (metres of anchor margin at wave frequency in a storm), so a threshold's edge is reached
    by the rare wave group or gust, minutes apart, and a clear after a lull of 30 s raised the
    same warning again with the next one (three times in 20 min on a storm's neighbour line).
``time_to_uplift`` (WARN)
    the same with ``uplift_time_warn`` and ``uplift_time_deadband`` (s): the anchor lifts within
    that time if the tide keeps its trend (:mod:`catenary_monitor.core.rules.tide_trend`); inf
    (no uplift coming) clears (after ``margin_clear_hold``), NaN holds.
``inconsistent`` (WARN; the dock model only, :mod:`catenary_monitor.core.rules.dock_watch`)
    raised when the dock estimate flags the line's tension as irreconcilable with the other
    lines (its smoothed normalized residual beyond ``dock_residual_limit``) for ``on_delay``;
    cleared after ``warn_clear_hold`` of consistency; held while the line is not tested.
``uplift_possible`` (WARN; with ``tension_accuracy`` or ``depth_accuracy``,
:mod:`catenary_monitor.core.rules.uncertainty`)
    raised when ``uplift_force_upper > allowed_uplift`` while the nominal ``uplift_force`` is
    not (uplift possible within sensor accuracy) for ``on_delay``; cleared when the bound is
    back at or below ``allowed_uplift``, or when the nominal value itself is above it (the
    ``uplift`` ERROR then says so), held for ``warn_clear_hold``; NaN holds.
``drag_margin`` (WARN; with ``anchor_holding``, :mod:`catenary_monitor.core.rules.holding`)
    as the margins above with ``drag_margin_warn`` and ``drag_margin_deadband`` (N), cleared
    after ``margin_clear_hold``.
``dragging`` (ERROR; with ``anchor_holding``, :mod:`catenary_monitor.core.rules.holding`)
    raised when the line's ``drag_state`` is ``dragging`` (the load beyond the holding and the
    implied anchor distance beyond the installed one by ``drag_tolerance``) for ``on_delay``;
    cleared after ``clear_hold`` of ``holding`` or ``overloaded``; NaN holds.
``fatigue`` (WARN; :mod:`catenary_monitor.core.rules.fatigue`)
    raised when the line's cumulative Miner damage reaches ``fatigue_damage_warn`` for
    ``on_delay``; cleared below it (the damage only grows: a new chain, a new store).
``channel`` (WARN; a line measured by several channels,
:mod:`catenary_monitor.core.rules.channels`)
    raised when a channel is silent, stuck or out of line while enough others are healthy (the
    tension then comes from them); cleared once every channel is healthy again for
    ``warn_clear_hold``. Fewer healthy channels than ``NAME.min_channels``: the line is blind
    (STALE, the message naming the channels and why), and its NaN tension is not an impossible
    input.
``sensor_error`` (ERROR), ``sensor_warn`` (WARN; :mod:`catenary_monitor.core.rules.sensor_state`)
    raised when the line's ``sensor_state`` (decided at ticks) is an ERROR state (``over_mbl``,
    ``slack``, ``suspected_parted``), resp. a WARN state (``stuck``, ``spike``), for
    ``on_delay``; cleared after ``clear_hold`` (resp. ``warn_clear_hold``) of any other state.
    They are conditions of the line beside the load alarms: the line's level is the worst of
    all, by the rule below.
stale (STALE, no latch)
    no tension or no depth received yet (the line is blind: its results cannot be computed), the
    newest tension older than ``tension_timeout`` (and, unless the line fell silent with
    other inputs, older than ``tension_timeout + common_cause_window``: the common cause is
    found before a lone line's own STALE), or the depth stale (older than
    ``depth_timeout``; the monitor decides this once for every line, see
    :attr:`AlarmInputs.depth_stale`).

A latch only moves on evidence: an update whose value is NaN (not applicable) keeps the latch and
restarts its pending timer. **While any input is stale nothing clears** (clearing on old data would
hide a lifted anchor); raising still works. Wave-frequency oscillation therefore keeps an alarm
up, as long as ``clear_hold`` exceeds the wave period: one transition, not one per wave.

A line starts blind: :meth:`LineAlarm.initial` is STALE ("no tension received yet; no depth
received yet"), never OK before its inputs are known.

**Suppressed by design.** A line that is STALE only because of a common cause (no tension
received since the start, no depth / the depth stale: every line shares the depth, or its
tension silent together with other inputs: :attr:`AlarmInputs.silent_group`), not because its
own tension alone went stale after it reported, is ``suppressed``: its message says so
(``blind: no depth received yet (suppressed by design: alarm on sensors)``), its alarm is not
active (:mod:`catenary_monitor.core.alarms.acknowledge`) and its changes into and out of that
STALE are not announced (:attr:`Transition.suppressed`): the one ``sensors`` alarm reports the
cause (:func:`catenary_monitor.core.rules.health.sensors_status`). Likewise a line at WARN
whose warnings are all of :data:`CONSEQUENT` (the margins a shifted load brings about) while
another line is suspected parted (:attr:`AlarmInputs.parted_other`), having left OK within
``parted_consequence_window`` after that line became so (:attr:`AlarmState.parted_since`): the
parted line's ERROR reports the cause, the message begins with it
(:func:`consequence_text`). An ERROR is never suppressed.

Level: ERROR if an ERROR latch is up, else STALE if stale, else WARN if a warning latch is up,
else OK. **ERROR outranks STALE** (a sensor dropout must not hide a lifted anchor) although
``Level.STALE`` is numerically larger; STALE outranks WARN (a warning from old data is not
news). The message joins every applicable condition with ``'; '``, ERRORs first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Mapping, NamedTuple, Sequence

import numpy as np

from catenary_monitor.core.config.parameters import ALARM_CONDITIONS, AlarmConfig, LineConfig
from catenary_monitor.core.physics.result import Status
from catenary_monitor.core.rules.level import RANK, Level
from catenary_monitor.core.rules import sensor_state
from catenary_monitor.core.rules.plausible import units_text
from catenary_monitor.core.rules.channels import describe

__all__ = [
    'AlarmInputs',
    'Latch',
    'AlarmState',
    'Transition',
    'LineAlarm',
    'LevelSeries',
    'CONDITIONS',
    'ERROR_CONDITIONS',
    'DIAGNOSTIC_KEYS',
    'replay_levels',
    'diagnostic_values',
    'quiet_change',
    'blind_quiet',
    'SUPPRESSED_NOTE',
    'CONSEQUENT',
    'consequence_text',
    'VIEW_TEXT',
    'uplift_seen',
]


#: Latched conditions, in message order: ERRORs, then WARNs (every alarm condition but
#: ``stale``, which has no latch).
CONDITIONS = tuple(c for c in ALARM_CONDITIONS if c != 'stale')
#: The conditions that raise an ERROR (the others a WARN).
ERROR_CONDITIONS = _ERRORS = ('uplift', 'input', 'sensor_error', 'dragging')
_WARNS = tuple(c for c in CONDITIONS if c not in _ERRORS)
_ERROR_AT = tuple(CONDITIONS.index(c) for c in _ERRORS)
# The warnings with a threshold and a deadband.
_MARGINS = (
    'anchor_margin',
    'tide_margin',
    'load_margin',
    'safety_factor',
    'time_to_uplift',
    'drag_margin',
)
_LIMITS = {'time_to_uplift': 'uplift_time'}  # parameter prefix where it is not the name
#: The warnings a parted chain elsewhere on the dock brings about (the load shifted onto the
#: lines left): raised within ``parted_consequence_window`` of the part, its consequence.
CONSEQUENT = _MARGINS + ('uplift_possible',)
_NOT_CONSEQUENT_AT = tuple(
    i for i, c in enumerate(CONDITIONS) if c in _WARNS and c not in CONSEQUENT
)
_WARN_RANK = RANK[Level.WARN]  # entered[_WARN_RANK]: when the line last left OK
_HOLD, _BREACH, _CLEAR = 0, 1, 2  # classification of one update for one condition


@dataclass(slots=True)
class AlarmInputs:
    """One update of one line: solved quantities (SI) and the stamps of the newest samples
    (built afresh for every update and never changed: slots, not frozen, whose ``__init__``
    costs five times as much).

    NaN marks a quantity that does not apply. ``status`` is the solver's code (0 = ok) and
    ``status_message`` its sentence. Stamps are the receive times (s, same clock as ``now``)
    of the newest tension and depth samples; NaN means none received yet. ``depth_stale`` is
    the monitor's decision that the depth is older than ``depth_timeout`` (taken once for all
    lines, so they agree); None lets the alarm decide from ``depth_stamp`` itself.
    """

    uplift_force: float = math.nan  # N, vertical force on the anchor
    anchor_margin: float = math.nan  # m, installed minus minimum anchor distance
    tide_margin: float = math.nan  # m, depth rise the chain takes before uplift
    load_margin: float = math.nan  # N, as reported by the solver
    safety_factor: float = math.nan  # -, MBL / top tension
    time_to_uplift: float = math.nan  # s, until uplift at the tide's trend (inf: not coming)
    tide_rate: float = math.nan  # m/s, the tide's trend (for the message)
    tide_forecast: float = 0.0  # 1: time_to_uplift is the tide table's forecast (the message)
    status: int = 0
    status_message: str = ''
    tension_stamp: float = math.nan  # s
    depth_stamp: float = math.nan  # s
    depth_stale: bool | None = None
    inconsistent: float = math.nan  # 1 flagged by the dock estimate, 0 consistent, NaN untested
    dock_residual: float = math.nan  # N, measured - expected tension
    dock_expected: float = math.nan  # N, the tension the dock estimate expects
    dock_sigma: float = math.nan  # normalized residual
    uplift_force_upper: float = math.nan  # N, the uplift force's bound within sensor accuracy
    drag_margin: float = math.nan  # N, holding capacity minus horizontal load
    holding_capacity: float = math.nan  # N, anchor and grounded chain (for the message)
    sensor_state: float = 0.0  # core.rules.sensor_state line state code (0 ok)
    sensor_tension: float = math.nan  # N, the newest tension the state was decided on
    mbl: float = math.nan  # N, the line's MBL (for the message)
    drag_state: float = math.nan  # core.rules.holding code (2 dragging), NaN unknown
    implied_anchor_distance: float = math.nan  # m (for the message)
    fatigue_damage: float = math.nan  # Miner's damage so far
    fatigue_life_left: float = math.nan  # s at the last day's rate (for the message)
    dynamic_uplift: float = math.nan  # N, the uplift at the wave window's peak (wave_window)
    uplift_view: float = math.nan  # 1: time_to_uplift is the chain length's, 0: R held's
    channels_healthy: float = math.nan  # a line of several channels: how many are healthy
    channel_states: float = math.nan  # their states (core.rules.channels code; NaN: one channel)
    span: float = math.nan  # m, the span the line was solved at (for the dragging message)
    silent_group: float = 0.0  # 1: silent with other inputs (core.rules.health.common_cause)
    parted_other: float = math.nan  # another line suspected parted: its index; NaN none


class Latch(NamedTuple):
    """One condition's latch: up or not, and when the pending raise or clear started (s)."""

    active: bool = False
    since: float | None = None


@dataclass(frozen=True)
class AlarmState:
    """Everything a line's alarm remembers between updates (immutable)."""

    level: Level = Level.STALE
    message: str = (
        'blind: no tension received yet; no depth received yet '
        '(suppressed by design: alarm on sensors)'
    )
    latches: tuple[Latch, ...] = (Latch(),) * len(CONDITIONS)
    entered: tuple[float, ...] = (math.nan,) * 4  # s, when each severity rank was last entered
    input_message: str = ''  # last impossible-input sentence, while its alarm holds
    suppressed: bool = True  # STALE by a common cause, WARN by a part (suppressed by design)
    stale: bool = True  # an input stale or never received (the level may still be ERROR)
    parted_since: float = math.nan  # s, since when another line is suspected parted; NaN not


class Transition(NamedTuple):
    """A level change. ``duration`` (s) is set when severity drops: how long the old level or
    worse lasted (for a return to OK, the whole incident); otherwise None. ``suppressed``: not
    announced, the change into or out of a STALE suppressed by design (:func:`quiet_change`)."""

    time: float
    old: Level
    new: Level
    message: str
    duration: float | None
    suppressed: bool = False


#: Appended to the message of a line suppressed by design (after ``blind: ``).
SUPPRESSED_NOTE = ' (suppressed by design: alarm on sensors)'


def consequence_text(message: str, peer: str) -> str:
    """The message of a warning suppressed as ``peer``'s parted chain's consequence: the cause
    first, so that the headline keeps it."""
    return f'consequence of {peer}\'s parted chain (suppressed by design): {message}'


def quiet_change(old: Level, old_suppressed: bool, new: Level, new_suppressed: bool) -> bool:
    """Whether a level change is not announced: into a STALE or WARN suppressed by design
    (blind inputs' common cause, a parted chain's consequence), or out of one back to OK (the
    cause's own alarm announces both)."""
    if new in (Level.STALE, Level.WARN):
        return new_suppressed
    return new == Level.OK and old in (Level.STALE, Level.WARN) and old_suppressed


def blind_quiet(old: Level, new: Level) -> bool:
    """Whether a change of the tide's or the dock's status is not announced: into its STALE
    under blind inputs, or out of it back to OK (the ``sensors`` alarm announces both)."""
    return quiet_change(old, old == Level.STALE, new, new == Level.STALE)


def _blind_text(message: str, suppressed: bool) -> str:
    """A line's message, marked when its STALE is suppressed by design."""
    return f'blind: {message}{SUPPRESSED_NOTE}' if suppressed else message


def _fmt(value: float, scale: float = 1.0, digits: int = 1) -> str:
    if math.isnan(value):
        return 'n/a'
    v = value / scale
    return f'{v:.{digits}f}' if v == 0 or abs(v) >= 10.0**-digits else f'{v:.2g}'


@dataclass(frozen=True)
class LineAlarm:
    """The alarm rules for one line: :class:`AlarmConfig` plus the line's allowed uplift (N)."""

    config: AlarmConfig = field(default_factory=AlarmConfig)
    allowed_uplift: float = 0.0
    anchor_distance: float = math.nan  # m, installed (for the dragging message)
    channel_names: tuple[str, ...] = ()  # a line of several channels: their topics
    min_channels: int = 1
    name: str = ''  # the line's (for the wrong-units message)
    tension_scale: float = 1.0  # its tension_scale (the wrong-units message)
    peers: tuple[str, ...] = ()  # the dock's line names, by index (a consequence's message)

    @classmethod
    def for_line(
        cls, line: LineConfig, config: AlarmConfig, peers: tuple[str, ...] = ()
    ) -> LineAlarm:
        """Rules for ``line`` under ``config``; ``peers``: the dock's line names."""
        return cls(
            config,
            line.allowed_uplift,
            line.anchor_distance,
            line.channel_topics,
            int(line.min_channels),
            line.name,
            line.tension_scale,
            peers,
        )

    def peer(self, index: float) -> str:
        """The name of the dock's line ``index`` (``another line`` when unknown)."""
        k = int(index) if index == index else -1
        return self.peers[k] if 0 <= k < len(self.peers) else 'another line'

    def blind(self, healthy: float) -> bool:
        """Fewer healthy channels than ``min_channels`` (a line of several channels)."""
        return bool(self.channel_names) and healthy < self.min_channels

    @property
    def uplift_clear_level(self) -> float:
        """Uplift force (N) at or below which the uplift alarm may clear."""
        return max(self.allowed_uplift - self.config.uplift_clear_hysteresis, 0.0)

    @cached_property
    def uplift_clear_margin(self) -> float:
        """Anchor margin (m) the uplift alarm needs to clear at a 0 N clear level: at least the
        anchor-margin warning's clear level (an ERROR's deadband is never narrower than the
        warning's below it: no ERROR -> WARN -> ERROR with each wave group)."""
        c = self.config
        return max(c.uplift_clear_margin, c.anchor_margin_warn + c.anchor_margin_deadband)

    def _timing(self, cond: str) -> tuple[float, float]:
        """(on_delay, hold) in s for a condition."""
        c = self.config
        if cond == 'input':
            return 0.0, c.clear_hold
        if cond in _MARGINS:
            return c.on_delay, c.margin_clear_hold
        return c.on_delay, (c.clear_hold if cond in _ERRORS else c.warn_clear_hold)

    def _warn_limits(self, cond: str) -> tuple[float, float]:
        """(raise below, clear at or above) for a warning condition."""
        prefix = _LIMITS.get(cond, cond)
        warn = getattr(self.config, f'{prefix}_warn')
        return warn, warn + getattr(self.config, f'{prefix}_deadband')

    def initial(self, now: float) -> AlarmState:
        """State of a line that has received nothing yet, at time ``now`` (s): blind, STALE."""
        return AlarmState(entered=(now, now, now, math.nan))

    def update(
        self, state: AlarmState, inputs: AlarmInputs, now: float
    ) -> tuple[AlarmState, list[Transition]]:
        """Advance ``state`` by one update at time ``now`` (s); return it and any transition.

        Call it on every solved update and also periodically (e.g. at the diagnostic rate) with
        the newest inputs, so that staleness is noticed when samples stop. ``now`` should not
        decrease; if it does, pending timers restart at ``now``.
        """
        if not math.isfinite(now):
            raise ValueError(f'now must be finite, got {now!r}')
        stale_t, stale_d = self._stale(inputs, now)
        # nothing clears on a tension older than its timeout, STALE shown or not yet
        ts = inputs.tension_stamp
        held = stale_t or stale_d or now - ts > self.config.tension_timeout
        stale = stale_t or stale_d
        latches = []
        classify = self._classify
        for (cond, margin, on_delay, hold, low, high), latch in zip(self._plan, state.latches):
            if margin:  # a warning with a threshold and a deadband (_classify's last case)
                value = getattr(inputs, cond)
                clear = value >= high and not held
                code = _BREACH if value < low else (_CLEAR if clear else _HOLD)
            else:
                code = classify(cond, inputs, held)
            latches.append(_step(latch, code, now, on_delay, hold))
        input_message = state.input_message
        if inputs.status != 0:
            input_message = _status_text(inputs.status, inputs.status_message)
        active = [latch.active for latch in latches]
        level = _combine(active, stale)
        own = stale_t and inputs.tension_stamp == inputs.tension_stamp
        own = own and inputs.silent_group != 1.0
        entered, duration = state.entered, None
        if level != state.level:
            entered, duration = _episode(entered, state.level, level, now)
        parted = inputs.parted_other == inputs.parted_other
        since = (state.parted_since if state.parted_since == state.parted_since else now)
        since = since if parted else math.nan
        consequence = (
            parted
            and level == Level.WARN
            and not any(active[i] for i in _NOT_CONSEQUENT_AT)
            and since <= entered[_WARN_RANK] <= since + self.config.parted_consequence_window
        )
        suppressed = (level == Level.STALE and not own) or consequence
        if stale or any(active):
            message = self._message(active, inputs, now, stale_t, stale_d, input_message)
            message = _blind_text(message, level == Level.STALE and suppressed)
            if consequence:
                message = consequence_text(message, self.peer(inputs.parted_other))
        else:  # nothing up, nothing stale (so not blind): what _message says then
            message = 'OK'
        events = []
        if level != state.level:
            quiet = quiet_change(state.level, state.suppressed, level, suppressed)
            events.append(Transition(now, state.level, level, message, duration, quiet))
        new = AlarmState(
            level,
            message,
            tuple(latches),
            entered,
            input_message if active[1] else '',
            suppressed,
            stale,
            since,
        )
        return new, events

    @cached_property
    def _plan(self) -> tuple[tuple[str, bool, float, float, float, float], ...]:
        """Per condition (:data:`CONDITIONS` order): its name, whether it is a warning with a
        threshold and a deadband (:data:`_MARGINS`), its on-delay and hold (s) and, for those,
        the limits it is raised below and cleared at or above (the configuration's, fixed)."""
        nan = math.nan
        return tuple(
            (cond, cond in _MARGINS, *self._timing(cond))
            + (self._warn_limits(cond) if cond in _MARGINS else (nan, nan))
            for cond in CONDITIONS
        )

    def _stale(self, x: AlarmInputs, now: float) -> tuple[bool, bool]:
        """(tension stale, never received or blind, depth stale, never received or impossible:
        outside the chart, the tide's ERROR, the line blind by it)."""
        ts, ds = x.tension_stamp, x.depth_stamp
        timeout = self.config.tension_timeout
        stale_t = ts != ts or (
            now - ts > timeout
            and (x.silent_group == 1.0 or now - ts > timeout + self.config.common_cause_window)
        )
        stale_t = stale_t or self.blind(x.channels_healthy)
        if ds != ds or x.status == Status.IMPLAUSIBLE_DEPTH:
            return stale_t, True
        if x.depth_stale is None:
            return stale_t, now - ds > self.config.depth_timeout
        return stale_t, bool(x.depth_stale)

    def _classify(self, cond: str, x: AlarmInputs, stale: bool) -> int:
        if cond == 'input':
            if self.blind(x.channels_healthy):  # no tension to judge: blind, not impossible
                return _HOLD
            if _impossible(x.status, x.sensor_state):
                return _BREACH
            return _HOLD if stale else _CLEAR
        if cond == 'uplift':
            force = uplift_seen(x.uplift_force, x.dynamic_uplift)
            breach = force > self.allowed_uplift
            level = self.uplift_clear_level
            clear = force <= level and (level > 0.0 or x.anchor_margin >= self.uplift_clear_margin)
        elif cond == 'inconsistent':
            breach, clear = x.inconsistent == 1.0, x.inconsistent == 0.0
        elif cond == 'dragging':
            breach, clear = x.drag_state == 2.0, x.drag_state < 2.0
        elif cond == 'fatigue':
            warn = self.config.fatigue_damage_warn
            breach, clear = x.fatigue_damage >= warn, x.fatigue_damage < warn
        elif cond == 'channel':
            failed = x.channel_states > 0.0 and not self.blind(x.channels_healthy)
            breach, clear = failed, x.channel_states == 0.0
        elif cond in _SENSOR:
            breach, clear = _sensor_code(cond, float(x.sensor_state))
        elif cond == 'uplift_possible':
            nominal = uplift_seen(x.uplift_force, x.dynamic_uplift) > self.allowed_uplift
            upper = x.uplift_force_upper
            breach = upper > self.allowed_uplift and not nominal
            clear = upper <= self.allowed_uplift or nominal
        else:
            low, high = self._warn_limits(cond)
            value = getattr(x, cond)
            breach, clear = value < low, value >= high
        return _BREACH if breach else (_CLEAR if clear and not stale else _HOLD)

    def _message(
        self,
        active: Sequence[bool],
        x: AlarmInputs,
        now: float,
        stale_t: bool,
        stale_d: bool,
        input_message: str,
    ) -> str:
        """Operator message for the conditions that apply, joined with '; '."""
        parts = []
        hold_e, hold_w = self.config.clear_hold, self.config.warn_clear_hold
        hold_m = self.config.margin_clear_hold
        if active[0]:
            f, allowed = uplift_seen(x.uplift_force, x.dynamic_uplift), self.allowed_uplift
            if f > allowed:
                text = f'anchor uplift {_fmt(f, 1e3)} kN > allowed {_fmt(allowed, 1e3)} kN'
                if f - x.uplift_force > max(1.0, 1e-6 * f):  # not a rounding apart
                    text += f' at the wave peak (quasi-static {_fmt(x.uplift_force, 1e3)} kN)'
                parts.append(text)
            else:
                level = self.uplift_clear_level
                text = (
                    f'anchor uplift alarm held: uplift {_fmt(f, 1e3)} kN, anchor margin '
                    f'{_fmt(x.anchor_margin)} m (clears after {hold_e:g} s at uplift <= '
                    f'{_fmt(level, 1e3)} kN'
                )
                if level == 0.0:
                    text += f' and anchor margin >= {_fmt(self.uplift_clear_margin)} m'
                parts.append(text + ')')
        if active[1]:
            if sensor_state.is_units(x.sensor_state):
                index = int(x.sensor_state) - sensor_state.UNITS_BASE
                parts.append(units_text(self.name, self.tension_scale, index, x.sensor_tension))
            elif x.status != 0:
                parts.append(f'impossible input: {input_message}')
            else:
                parts.append(
                    f'impossible input alarm held: last was "{input_message}" '
                    f'(clears after {hold_e:g} s of valid input)'
                )
        if active[CONDITIONS.index('sensor_error')]:
            parts.append(_sensor_text(x, 'sensor_error', hold_e))
        if active[_DRAGGING]:
            parts.append(self._dragging_text(x, hold_e))
        blind = self.blind(x.channels_healthy)
        if blind:
            parts.append(self._channels_text(x, True))
        for name, is_stale, stamp, timeout in (
            ('tension', stale_t and not blind, x.tension_stamp, self.config.tension_timeout),
            ('depth', stale_d, x.depth_stamp, self.config.depth_timeout),
        ):
            if not is_stale:
                continue
            if math.isnan(stamp):
                parts.append(f'no {name} received yet')
            elif name == 'depth' and x.status == Status.IMPLAUSIBLE_DEPTH:
                parts.append('depth outside the chart: not solved (the tide status names it)')
            else:
                parts.append(
                    f'{name} stale: last sample {_fmt(now - stamp)} s ago '
                    f'(timeout {timeout:g} s)'
                )
        for cond, up in zip(CONDITIONS, active):
            if cond in _ERRORS:
                continue
            if up and cond == 'inconsistent':
                parts.append(_inconsistent_text(x, hold_w))
            elif up and cond == 'sensor_warn':
                parts.append(_sensor_text(x, cond, hold_w))
            elif up and cond == 'time_to_uplift':
                if not (active[0] and not x.time_to_uplift > 0.0):  # the ERROR says it
                    parts.append(self._uplift_time_text(x, hold_m))
            elif up and cond == 'uplift_possible':
                parts.append(self._uplift_possible_text(x, hold_w))
            elif up and cond == 'fatigue':
                parts.append(self._fatigue_text(x))
            elif up and cond == 'channel':
                if not blind:
                    parts.append(self._channels_text(x, False, hold_w))
            elif up and cond == 'drag_margin':
                text = self._warn_text(cond, x.drag_margin, hold_m)
                holding = _fmt(x.holding_capacity, 1e3)
                parts.append(f'{text} (holding {holding} kN): anchor may drag')
            elif up:
                parts.append(self._warn_text(cond, getattr(x, cond), hold_m))
        return '; '.join(parts) if parts else 'OK'

    def _warn_text(self, cond: str, value: float, hold: float) -> str:
        label, scale, unit, digits, low, lo, hi = self._warn_formats[cond]
        v = _fmt(value, scale, digits)
        if value < low:
            return f'{label} {v}{unit} < {lo}{unit}'
        return f'{label} {v}{unit}, warning held (clears after {hold:g} s at >= {hi}{unit})'

    @cached_property
    def _warn_formats(self) -> dict[str, tuple[str, float, str, int, float, str, str]]:
        """Per warning with a threshold: its label, scale, unit and digits, the limit it is
        raised below and both limits as printed (the configuration's, formatted once)."""
        out = {}
        for cond in _MARGINS:
            low, high = self._warn_limits(cond)
            scale, unit, digits = {
                'load_margin': (1e3, ' kN', 1),
                'drag_margin': (1e3, ' kN', 1),
                'safety_factor': (1.0, '', 2),
            }.get(cond, (1.0, ' m', 2))
            lo, hi = _fmt(low, scale, digits), _fmt(high, scale, digits)
            out[cond] = (cond.replace('_', ' '), scale, unit, digits, low, lo, hi)
        return out

    def _uplift_time_text(self, x: AlarmInputs, hold: float) -> str:
        """The message of the ``time_to_uplift`` condition (minutes, the tide's rate in m/h,
        which view answered: the chain's length held or the horizontal tension held)."""
        low, high = self._warn_limits('time_to_uplift')
        value = x.time_to_uplift
        if value != value:
            return (
                f'time to uplift unknown (trend not known yet), warning held (clears after '
                f'{hold:g} s at >= {_duration(high)})'
            )
        if value < low:
            if not value > 0.0:
                return (
                    f'anchor off the seabed (uplift {_fmt(x.uplift_force, 1e3)} kN, within the '
                    f'allowed {_fmt(self.allowed_uplift, 1e3)} kN)'
                )
            rate = x.tide_rate * 3600.0
            view = VIEW_TEXT.get(x.uplift_view, '')
            view = f' ({view})' if view else ''
            if x.tide_forecast == 1.0:
                return f'anchor uplift in {_duration(value)} on the tide table\'s forecast{view}'
            return (
                f'anchor uplift in {_duration(value)} if the tide keeps rising {rate:.2f} m/h'
                f'{view}'
            )
        return (
            f'time to uplift {_duration(value)}, warning held (clears after {hold:g} s '
            f'at >= {_duration(high)})'
        )

    def _channels_text(self, x: AlarmInputs, blind: bool, hold: float = 0.0) -> str:
        """The channels' message: blind (fewer healthy than min_channels) or one failed."""
        n, healthy = len(self.channel_names), x.channels_healthy
        failed = describe(x.channel_states, self.channel_names) or 'none failed'
        if blind:
            return (
                f'{_count(healthy)} of {n} load-cell channels healthy (min_channels '
                f'{self.min_channels}): {failed}'
            )
        if x.channel_states > 0.0:
            return (
                f'load-cell channel {failed}: tension from the other {_count(healthy)} '
                '(regression on their shared history)'
            )
        return f'channel warning held (clears after {hold:g} s of every channel healthy)'

    def _fatigue_text(self, x: AlarmInputs) -> str:
        """The message of the ``fatigue`` condition (the damage, the life left in days)."""
        warn, life = self.config.fatigue_damage_warn, x.fatigue_life_left
        left = 'unknown' if life != life else _life(life)
        return (
            f'chain fatigue: Miner damage {x.fatigue_damage:.3g} >= {warn:g} '
            f'(life left {left} at the last day\'s rate)'
        )

    def _dragging_text(self, x: AlarmInputs, hold: float) -> str:
        """The message of the ``dragging`` condition (load and holding in kN, span in m)."""
        if x.drag_state == 2.0:
            load = x.holding_capacity - x.drag_margin
            installed = x.span != x.span or x.span == self.anchor_distance
            span = self.anchor_distance if installed else x.span
            where = (
                f'its installed {_fmt(span)} m'
                if installed
                else f'the {_fmt(span, 1.0, 2)} m the dock estimate gives'
            )
            return (
                f'anchor dragging: horizontal load {_fmt(load, 1e3)} kN > holding '
                f'{_fmt(x.holding_capacity, 1e3)} kN (the chain puts the anchor '
                f'{_fmt(x.implied_anchor_distance - span, 1.0, 2)} m beyond {where}, '
                f'implied {_fmt(x.implied_anchor_distance, 1.0, 2)} m)'
            )
        return f'anchor dragging alarm held (clears after {hold:g} s of the anchor holding)'

    def _uplift_possible_text(self, x: AlarmInputs, hold: float) -> str:
        """The message of the ``uplift_possible`` condition (bound and nominal in kN)."""
        upper, allowed = x.uplift_force_upper, self.allowed_uplift
        if upper > allowed:
            return (
                f'uplift possible within sensor accuracy: up to {_fmt(upper, 1e3)} kN > allowed '
                f'{_fmt(allowed, 1e3)} kN (nominal {_fmt(x.uplift_force, 1e3)} kN)'
            )
        return (
            f'uplift-within-accuracy warning held: bound {_fmt(upper, 1e3)} kN (clears after '
            f'{hold:g} s at <= {_fmt(allowed, 1e3)} kN)'
        )


_SENSOR = ('sensor_error', 'sensor_warn')
_DRAGGING = CONDITIONS.index('dragging')

#: Which view answered a time to uplift (``uplift_view``), for messages and /diagnostics.
VIEW_TEXT = {0.0: 'horizontal tension held', 1.0: 'chain length held'}


def uplift_seen(nominal: float, dynamic: float) -> float:
    """The uplift the ERROR takes [N]: the dynamic uplift where known (it is at least the
    nominal, taken at the wave window's peak tension), else the nominal."""
    if dynamic != dynamic:
        return nominal
    return dynamic if nominal != nominal else max(nominal, dynamic)  # as np.fmax


def _impossible(status: int, sensor: float) -> bool:
    """Whether a solve's ``status`` is an impossible input: any but 0, except an impossible
    depth (the tide's ERROR names it; the line is blind by it) and ``T <= w*h`` but on a line
    whose ``sensor_state`` the tick decided ``slack``: a tension falling to ``T <= w*h`` is
    judged at the next tick (``diagnostic_rate``, before the next /diagnostics), where the
    sensor states tell a parted chain (``suspected_parted`` names it, never as an impossible
    input first) from a slack reading."""
    if status == Status.IMPLAUSIBLE_DEPTH:
        return False  # the depth's: the tide's ERROR, the line blind by it
    if sensor_state.is_units(sensor):
        return True  # a reading off by a unit factor
    return status != 0 and not (status == Status.TENSION and sensor != sensor_state.SLACK)


def _impossible_column(status: np.ndarray, sensor: np.ndarray) -> np.ndarray:
    """:func:`_impossible` per update."""
    pending = (status == Status.TENSION) & (sensor != sensor_state.SLACK)
    units = sensor >= sensor_state.UNITS_BASE
    return ((status != 0) & (status != Status.IMPLAUSIBLE_DEPTH) & ~pending) | units


def _sensor_codes(cond: str, code: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(breach, clear) of a sensor condition from line state codes (NaN: hold)."""
    errors = code == sensor_state.ERROR_STATES[0]  # np.isin's machinery cost 4 ns per code
    for state in sensor_state.ERROR_STATES[1:]:
        errors = errors | (code == state)
    breach = errors if cond == 'sensor_error' else ~errors & (code > 0)
    if cond != 'sensor_error':
        breach &= code < sensor_state.UNITS_BASE  # wrong units: the input condition's
    return breach, ~breach & np.isfinite(code)


def _sensor_code(cond: str, code: float) -> tuple[bool, bool]:
    """:func:`_sensor_codes` of one code (the per-sample path: no arrays)."""
    errors = code in _ERROR_CODES
    breach = errors if cond == 'sensor_error' else not errors and 0 < code < _UNITS
    return breach, not breach and math.isfinite(code)


_ERROR_CODES = frozenset(float(c) for c in sensor_state.ERROR_STATES)
_UNITS = float(sensor_state.UNITS_BASE)


def _sensor_text(x: AlarmInputs, cond: str, hold: float) -> str:
    """The message of a sensor condition (what to check), or that it is held."""
    code = x.sensor_state
    breach, _ = _sensor_codes(cond, np.asarray(code))
    if bool(breach):
        return sensor_state.line_message(int(code), x.sensor_tension, x.mbl)
    return f'sensor alarm held (clears after {hold:g} s of sane readings)'


def _count(value: float) -> str:
    return 'no' if value != value else str(int(value))


def _life(seconds: float) -> str:
    """A fatigue life for the operator: days, years beyond two years."""
    if seconds == math.inf:
        return 'unlimited'
    days = seconds / 86400.0
    return f'{days / 365.25:.1f} years' if days > 730.0 else f'{days:.1f} days'


def _duration(seconds: float) -> str:
    """A time to uplift for the operator: whole minutes, seconds below 2 min."""
    if seconds < 120.0:
        return f'{_fmt(seconds, 1.0, 0)} s'
    return f'{_fmt(seconds, 60.0, 0)} min'


def _inconsistent_text(x: AlarmInputs, hold: float) -> str:
    """The message of the ``inconsistent`` condition (what to check)."""
    expected, residual = x.dock_expected, x.dock_residual
    if math.isinf(expected):
        gap = 'the other lines put the hook beyond its chain\'s reach'
    else:
        gap = (
            f'{_fmt(expected + residual, 1e3)} kN, expected {_fmt(expected, 1e3)} kN (from the '
            f'dock position the other lines agree on; {residual / 1e3:+.1f} kN, '
            f'{x.dock_sigma:+.1f} sigma)'
        )
    check = (
        'check the tension sensor (calibration, drift, cable), the chain (slipped stopper, '
        'broken link) and the anchor (dragging)'
    )
    if x.inconsistent == 1.0:
        return f'tension inconsistent with the other lines: {gap}: {check}'
    return f'tension inconsistency held (clears after {hold:g} s consistent): {check}'


def _status_text(status: int, message: str) -> str:
    return message or f'solver status {status}'


def _step(latch: Latch, code: int, now: float, on_delay: float, hold: float) -> Latch:
    """One latch update: raise after ``on_delay`` of breaches, clear after ``hold`` of clears."""
    active, since = latch
    if code != (_CLEAR if active else _BREACH):
        return latch if since is None else Latch(active, None)
    since = now if since is None or since > now else since
    if now - since >= (hold if active else on_delay):
        return Latch(not active, None)
    return latch if since == latch.since else Latch(active, since)


def _combine(active: Sequence[bool], stale: bool) -> Level:
    """Explicit precedence ERROR > STALE > WARN > OK (not a max over level numbers)."""
    if any(active[i] for i in _ERROR_AT):
        return Level.ERROR
    if stale:
        return Level.STALE
    return Level.WARN if any(a for i, a in enumerate(active) if i not in _ERROR_AT) else Level.OK


def _episode(
    entered: tuple[float, ...], old: Level, new: Level, now: float
) -> tuple[tuple[float, ...], float | None]:
    """Update the time each severity rank was entered; return the ending episode's length."""
    r_old, r_new = RANK[old], RANK[new]
    if r_new > r_old:
        return tuple(now if r_old < r <= r_new else t for r, t in enumerate(entered)), None
    return entered, now - entered[r_old]


# --- vectorized replay --------------------------------------------------------------------------

_INPUT_FIELDS = (
    'uplift_force',
    'anchor_margin',
    'tide_margin',
    'load_margin',
    'safety_factor',
    'time_to_uplift',
    'tide_rate',
    'tide_forecast',
    'tension_stamp',
    'depth_stamp',
    'inconsistent',
    'dock_residual',
    'dock_expected',
    'dock_sigma',
    'uplift_force_upper',
    'drag_margin',
    'holding_capacity',
    'sensor_state',
    'sensor_tension',
    'mbl',
    'drag_state',
    'implied_anchor_distance',
    'fatigue_damage',
    'fatigue_life_left',
    'dynamic_uplift',
    'uplift_view',
    'channels_healthy',
    'channel_states',
    'span',
    'silent_group',
    'parted_other',
)


def _latch_series(
    codes: np.ndarray, t: np.ndarray, on_delay: float, hold: float, start: Latch = Latch()
) -> tuple[np.ndarray, Latch]:
    """Latch state after each update, exactly as repeated :func:`_step` from ``start``.

    A raise or clear is decided inside one run of equal codes, timed from the run's first
    update (or from ``start.since`` when the first run continues a pending one), and never
    depends on the latch state at the run's start (a breach run cannot clear, a clear run cannot
    raise). So every "set" and "reset" candidate is found independently and the latch is the
    most recent candidate, forward-filled from ``start.active``. Also returns the final latch.

    The latch's one column loop (:func:`_step` is its reference), numpy and no C: on the
    million-message replay (12 lines, 2.7 M latch updates in windows with a breach; 1.3 s in
    all) these passes take 47 ms, a C loop of ``_step`` took 3.6 ms, and without a compiler its
    fallback, ``_step`` in a Python loop, would take 2.1 s.
    """
    n = codes.size
    if n == 0:
        return np.zeros(0, dtype=bool), start
    if not start.active and not (codes == _BREACH).any():
        return np.zeros(n, dtype=bool), Latch()  # only a breach run can raise the latch
    idx = np.arange(n)
    starts = np.empty(n, dtype=bool)
    starts[0] = True
    np.not_equal(codes[1:], codes[:-1], out=starts[1:])
    run_start = np.maximum.accumulate(np.where(starts, idx, 0))
    began = t[run_start]
    pending = _CLEAR if start.active else _BREACH
    if start.since is not None and codes[0] == pending:
        first = np.flatnonzero(starts[1:])
        began[: first[0] + 1 if first.size else n] = start.since
    elapsed = t - began
    event = np.full(n, -1, dtype=np.int8)
    event[(codes == _CLEAR) & (elapsed >= hold)] = 0
    event[(codes == _BREACH) & (elapsed >= on_delay)] = 1
    last = np.maximum.accumulate(np.where(event >= 0, idx, -1))
    active = np.where(last >= 0, event[np.maximum(last, 0)] == 1, start.active)
    final_active = bool(active[-1])
    want = _CLEAR if final_active else _BREACH
    since = float(began[-1]) if codes[-1] == want else None
    return active, Latch(final_active, since)


class LevelSeries:
    """Levels of a whole sequence of updates of one line, and what the scalar machine says.

    ``levels`` (int8, one per update) and ``transitions`` equal those of feeding
    ``alarm.update`` one update at a time from ``initial``; :meth:`message_at` gives the
    message after update ``i`` and :meth:`final_state` the state after the last one.
    """

    def __init__(
        self,
        alarm: LineAlarm,
        times: np.ndarray,
        x: dict[str, np.ndarray],
        status: np.ndarray,
        texts: Any,
        stale_t: np.ndarray,
        stale_d: np.ndarray,
        active: dict[str, np.ndarray],
        latches: tuple[Latch, ...],
        initial: AlarmState,
        status_messages: Mapping[int, str] | None,
    ) -> None:
        self.alarm, self.times, self._status = alarm, times, status
        self._x: dict[str, np.ndarray] | None = x
        self._last = ''  # the last update's message once the inputs are forgotten
        self._texts, self._table = texts, status_messages or {}
        self._stale_t, self._stale_d, self._active = stale_t, stale_d, active
        self._latches, self._initial = latches, initial
        n = times.size
        err = active['uplift'] | active['input'] | active['sensor_error'] | active['dragging']
        warn = np.zeros(n, dtype=bool)
        for cond in _WARNS:
            warn |= active[cond]
        levels = np.where(warn, np.int8(Level.WARN), np.int8(Level.OK))
        np.copyto(levels, np.int8(Level.STALE), where=stale_t | stale_d)
        np.copyto(levels, np.int8(Level.ERROR), where=err)
        self.levels = levels
        own = stale_t & ~np.isnan(x['tension_stamp']) & (x['silent_group'] != 1.0)
        self._since = _parted_since(times, x['parted_other'], initial.parted_since)
        #: Per update: a warning suppressed as another line's parted chain's consequence.
        self.consequence = self._consequences(alarm, levels, active)
        #: Per update: STALE only by a common cause, or a parted chain's consequence
        #: (suppressed by design).
        self.suppressed = ((levels == Level.STALE) & ~own) | self.consequence
        #: Per update: an input stale or never received.
        self.stale = stale_t | stale_d
        self._bad: np.ndarray | None = None  # updates with a solver status, when first asked
        #: The updates at which the level changed (one per transition, in order).
        self.changed_at = np.zeros(0, np.int64)
        self.transitions, self._entered = self._walk()

    def _consequences(
        self, alarm: LineAlarm, levels: np.ndarray, active: dict[str, np.ndarray]
    ) -> np.ndarray:
        """Per update: the line's warning is a parted chain's consequence (as
        :meth:`LineAlarm.update` decides it)."""
        n, since = levels.size, self._since
        warn = (levels == Level.WARN) & ~np.isnan(since)
        if not warn.any():
            return warn
        for i in _NOT_CONSEQUENT_AT:
            warn &= ~active[CONDITIONS[i]]
        before = np.empty(n, levels.dtype)
        before[0] = self._initial.level
        before[1:] = levels[:-1]
        left = (before == Level.OK) & (levels != Level.OK)
        idx = np.maximum.accumulate(np.where(left, np.arange(n), -1))
        began = np.where(idx >= 0, self.times[np.maximum(idx, 0)], self._initial.entered[1])
        window = alarm.config.parted_consequence_window
        return warn & (since <= began) & (began <= since + window)

    def _held(self, i: int) -> str:
        """The impossible-input sentence the input alarm holds after update ``i``."""
        if self._bad is None:
            self._bad = np.flatnonzero(self._status != 0)
        at = int(np.searchsorted(self._bad, i, 'right')) - 1
        j = int(self._bad[at]) if at >= 0 else -1
        if j < 0:
            return self._initial.input_message
        code = int(self._status[j])
        text = str(self._texts[j]) if self._texts is not None else self._table.get(code, '')
        return _status_text(code, text)

    def forget_inputs(self) -> None:
        """Let the inputs go (a window's worth of columns per line): :meth:`message_at` is then
        only the last update's (its transitions' messages are taken already)."""
        last = self.times.size - 1
        if last >= 0 and self._x is not None:
            self._last = self.message_at(last)
        self._x = None

    def active(self, cond: str) -> np.ndarray:
        """Per update: whether condition ``cond``'s latch is up after it."""
        return self._active[cond]

    def active_at(self, i: int) -> list[bool]:
        """The latches' active flags (:data:`CONDITIONS` order) after update ``i``."""
        return [bool(self._active[cond][i]) for cond in CONDITIONS]

    def message_at(self, i: int) -> str:
        """The line's message after update ``i`` (as ``AlarmState.message``)."""
        if self.levels[i] == Level.OK:
            return 'OK'
        if self._x is None:  # forget_inputs: the last update's only
            if i != self.times.size - 1:
                raise ValueError('LevelSeries.message_at: the inputs were forgotten')
            return self._last
        floats: dict[str, Any] = {k: float(self._x[k][i]) for k in _INPUT_FIELDS}
        sample = AlarmInputs(**floats, status=int(self._status[i]))
        flags = [bool(self._active[cond][i]) for cond in CONDITIONS]
        text = self.alarm._message(
            flags,
            sample,
            float(self.times[i]),
            bool(self._stale_t[i]),
            bool(self._stale_d[i]),
            self._held(i),
        )
        if self.consequence[i]:
            return consequence_text(text, self.alarm.peer(floats['parted_other']))
        return _blind_text(text, bool(self.suppressed[i]) and self.levels[i] == Level.STALE)

    def _walk(self) -> tuple[list[Transition], tuple[float, ...]]:
        """Transitions (with messages and episode durations) from the initial state."""
        changed = np.flatnonzero(np.diff(self.levels, prepend=np.int8(self._initial.level)))
        self.changed_at = changed
        transitions: list[Transition] = []
        entered, old = self._initial.entered, self._initial.level
        for i in changed.tolist():
            new = Level(int(self.levels[i]))
            now = float(self.times[i])
            entered, duration = _episode(entered, old, new, now)
            was = bool(self.suppressed[i - 1]) if i > 0 else self._initial.suppressed
            quiet = quiet_change(old, was, new, bool(self.suppressed[i]))
            transitions.append(Transition(now, old, new, self.message_at(i), duration, quiet))
            old = new
        return transitions, entered

    def final_state(self) -> AlarmState:
        """The :class:`AlarmState` after the last update (the initial state if there is none)."""
        n = self.times.size
        if n == 0:
            return self._initial
        held = self._held(n - 1) if self._active['input'][-1] else ''
        return AlarmState(
            level=Level(int(self.levels[-1])),
            message=self.message_at(n - 1),
            latches=self._latches,
            entered=self._entered,
            input_message=held,
            suppressed=bool(self.suppressed[-1]),
            stale=bool(self.stale[-1]),
            parted_since=_nan_or(float(self._since[-1])),
        )


def _nan_or(value: float) -> float:
    """``value``, or :data:`math.nan` itself for a NaN (states compare equal field by field)."""
    return value if value == value else math.nan


def _parted_since(times: np.ndarray, other: np.ndarray, before: float) -> np.ndarray:
    """Per update: since when another line is suspected parted [s] (the start of the run of
    updates with ``other`` known, ``before`` when the first run continues one); NaN none."""
    n = times.size
    parted = ~np.isnan(other)
    if not parted.any():
        return np.full(n, math.nan)
    was = np.empty(n, bool)
    was[0] = before == before
    was[1:] = parted[:-1]
    start = parted & ~was
    idx = np.maximum.accumulate(np.where(start, np.arange(n), -1))
    since = np.where(idx >= 0, times[np.maximum(idx, 0)], before)
    return np.where(parted, since, math.nan)


def replay_levels(
    times: Any,
    inputs: Mapping[str, Any],
    alarm: LineAlarm,
    status_messages: Mapping[int, str] | None = None,
    initial: AlarmState | None = None,
) -> LevelSeries:
    """Levels and transitions for a whole sequence of updates of one line, vectorized.

    Gives exactly the levels, transitions (times, levels, messages, durations) and final state
    of feeding ``alarm.update`` one update at a time from ``initial`` (default: a blind line,
    ``alarm.initial(times[0])``).

    Parameters
    ----------
    times : array (n,), s, non-decreasing
        Update times (the ``now`` of each update).
    inputs : mapping of field name to array or scalar broadcastable to (n,)
        The :class:`AlarmInputs` fields; a missing field takes its default (``depth_stale``
        missing: decided from ``depth_stamp``). ``status_message`` may be an array of str;
        otherwise ``status_messages`` maps codes to sentences.
    alarm : LineAlarm
    status_messages : mapping int -> str, optional
    initial : AlarmState, optional

    Notes
    -----
    Cost is a few dozen numpy passes over the arrays plus Python work per transition only.
    """
    t = np.asarray(times, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f'times must be one-dimensional, got shape {t.shape}')
    n = t.size
    if n and (not np.all(np.isfinite(t)) or np.any(t[1:] < t[:-1])):
        raise ValueError('times must be finite and non-decreasing')
    unknown = set(inputs) - set(_INPUT_FIELDS) - {'status', 'status_message', 'depth_stale'}
    if unknown:
        raise ValueError(f'unknown input fields {sorted(unknown)}')
    if initial is None:
        initial = alarm.initial(float(t[0]) if n else 0.0)
    default = AlarmInputs()
    x = {k: _column(inputs.get(k, getattr(default, k)), np.float64, n) for k in _INPUT_FIELDS}
    status = _column(inputs.get('status', 0), np.int64, n)
    stale_t, stale_d = _stale_columns(alarm, t, x, inputs.get('depth_stale'))
    stale_d = stale_d | (status == Status.IMPLAUSIBLE_DEPTH)
    with np.errstate(invalid='ignore'):
        late = t - x['tension_stamp'] > alarm.config.tension_timeout
    held = stale_t | stale_d | late  # nothing clears on a tension older than its timeout
    classified = _classify_columns(alarm, x, status, held, initial.latches)
    active, latches = {}, []
    quiet = np.zeros(n, dtype=bool)
    quiet.flags.writeable = False
    for cond, latch in zip(CONDITIONS, initial.latches):
        code = classified[cond]
        if code is None:  # down before the window and no breach in it: down throughout
            active[cond], end = quiet, Latch()
        else:
            active[cond], end = _latch_series(code, t, *alarm._timing(cond), latch)
        latches.append(end)
    texts = inputs.get('status_message')
    if texts is not None:
        texts = np.broadcast_to(np.asarray(texts, dtype=object), (n,))
    return LevelSeries(
        alarm,
        t,
        x,
        status,
        texts,
        stale_t,
        stale_d,
        active,
        tuple(latches),
        initial,
        status_messages,
    )


def _column(value: Any, dtype: Any, n: int) -> np.ndarray:
    """``value`` as an array of ``dtype`` broadcast to (n,) (a column of that shape as is)."""
    column = np.asarray(value, dtype=dtype)
    return column if column.shape == (n,) else np.broadcast_to(column, (n,))


def _stale_columns(
    alarm: LineAlarm, t: np.ndarray, x: dict[str, np.ndarray], depth_stale: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Per update: (tension stale or never received, depth stale or never received)."""
    cfg = alarm.config
    ts, ds = x['tension_stamp'], x['depth_stamp']
    with np.errstate(invalid='ignore'):
        grouped = x['silent_group'] == 1.0
        age = t - ts
        late = (age > cfg.tension_timeout) & (
            grouped | (age > cfg.tension_timeout + cfg.common_cause_window)
        )
        stale_t = np.isnan(ts) | late
        if alarm.channel_names:  # a blind line of several channels
            stale_t = stale_t | _blind_column(alarm, x)
        if depth_stale is None:
            stale_d = np.isnan(ds) | (t - ds > cfg.depth_timeout)
        else:
            stale_d = np.isnan(ds) | np.broadcast_to(np.asarray(depth_stale, bool), t.shape)
    return stale_t, stale_d


def _classify_columns(
    alarm: LineAlarm,
    x: dict[str, np.ndarray],
    status: np.ndarray,
    stale: np.ndarray,
    latches: Sequence[Latch] | None = None,
) -> dict[str, np.ndarray | None]:
    """Each condition's code (breach, clear, hold) per update, as :meth:`LineAlarm._classify`.

    Given the latches before the updates (:data:`CONDITIONS` order), a condition whose latch is
    down and that no update breaches is None instead: it stays down (most conditions of most
    windows).
    """

    fresh = ~stale
    down = {} if latches is None else {c: not l.active for c, l in zip(CONDITIONS, latches)}

    def codes(cond: str, breach: np.ndarray, clear: np.ndarray) -> np.ndarray | None:
        # _HOLD 0, _BREACH 1, _CLEAR 2: breach wins, a clear counts only on fresh inputs
        if down.get(cond, False) and not breach.any():
            return None
        out = np.bitwise_and(clear, fresh, dtype=bool)
        out &= ~breach
        code = out.view(np.int8)
        code <<= 1
        code |= breach.view(np.int8) if breach.dtype == bool else breach.astype(np.int8)
        return code

    cfg = alarm.config
    level_up = alarm.uplift_clear_level
    f = np.fmax(x['uplift_force'], x['dynamic_uplift'])
    up_clear = f <= level_up
    if not level_up > 0.0:
        up_clear &= x['anchor_margin'] >= alarm.uplift_clear_margin
    out = {
        'uplift': codes('uplift', f > alarm.allowed_uplift, up_clear),
        'input': codes(
            'input',
            _impossible_column(status, x['sensor_state']) & ~_blind_column(alarm, x),
            ~_impossible_column(status, x['sensor_state']),
        ),
    }
    for cond in _MARGINS:
        low, high = alarm._warn_limits(cond)
        out[cond] = codes(cond, x[cond] < low, x[cond] >= high)
    flag = x['inconsistent']
    out['inconsistent'] = codes('inconsistent', flag == 1.0, flag == 0.0)
    nominal = f > alarm.allowed_uplift
    upper = x['uplift_force_upper']
    out['uplift_possible'] = codes(
        'uplift_possible',
        (upper > alarm.allowed_uplift) & ~nominal,
        (upper <= alarm.allowed_uplift) | nominal,
    )
    for cond in _SENSOR:
        out[cond] = codes(cond, *_sensor_codes(cond, x['sensor_state']))
    drag = x['drag_state']
    out['dragging'] = codes('dragging', drag == 2.0, drag < 2.0)
    damage, warn = x['fatigue_damage'], cfg.fatigue_damage_warn
    out['fatigue'] = codes('fatigue', damage >= warn, damage < warn)
    states = x['channel_states']
    blind = _blind_column(alarm, x)
    out['channel'] = codes('channel', (states > 0.0) & ~blind, states == 0.0)
    return out


def _blind_column(alarm: LineAlarm, x: dict[str, np.ndarray]) -> np.ndarray:
    """Per update: the line is blind (fewer healthy channels than min_channels)."""
    if not alarm.channel_names:
        return np.zeros(x['channels_healthy'].shape, bool)
    return x['channels_healthy'] < alarm.min_channels


# --- diagnostics values -------------------------------------------------------------------------

#: KeyValue keys of each line's DiagnosticStatus (contract, SI units).
DIAGNOSTIC_KEYS = (
    'top_tension',
    'depth',
    'horizontal_tension',
    'min_anchor_distance',
    'anchor_margin',
    'uplift_force',
    'tide_margin',
    'load_margin',
    'safety_factor',
    'time_to_uplift',
    # Margins with uncertainty (core/rules/uncertainty.py) and holding (core/rules/holding.py).
    'uplift_force_upper',
    'anchor_margin_lower',
    'tide_margin_lower',
    'grounded_length',
    'holding_capacity',
    'drag_margin',
    'implied_anchor_distance',
    # The tide margin at fixed chain length (core/rules/holding.py).
    'tide_margin_at_length',
    # The anchor's drag state code (core/rules/holding.py).
    'drag_state',
    # Chain fatigue (core/rules/fatigue.py): Miner's damage, its rate (1/s), life left (s).
    'fatigue_damage',
    'fatigue_damage_rate',
    'fatigue_life_left',
    # Wave-frequency tension and the dynamic uplift (core/rules/wave_window.py).
    'wave_tension',
    'peak_tension',
    'dynamic_uplift',
    # A line of several channels (core/rules/channels.py): healthy count, states code.
    'channels_healthy',
    'channel_states',
)


def diagnostic_values(result_fields: Any) -> list[tuple[str, str]]:
    """``[(key, value)]`` for :data:`DIAGNOSTIC_KEYS`, values as ``repr(float(x))``.

    ``result_fields`` is a mapping or an object with those attributes (e.g. a scalar solve
    result); a missing field gives ``'nan'``. ``float()`` parses every value back exactly.
    """

    def get(key: str) -> Any:
        if isinstance(result_fields, Mapping):
            return result_fields.get(key, math.nan)
        return getattr(result_fields, key, math.nan)

    return [(key, repr(float(get(key)))) for key in DIAGNOSTIC_KEYS]
