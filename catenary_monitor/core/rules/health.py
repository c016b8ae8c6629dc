"""Health of the node's shared inputs and of its logger: pure decisions, handed the time.

No rclpy. The node asks these functions which level and message its ``tide`` and ``logger``
diagnostic statuses carry, so that the node itself makes no threshold comparison. Times are
seconds on one clock (the node clock, or log time in replay).
"""

from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

from catenary_monitor.core.rules.level import Level
from catenary_monitor.core.rules.plausible import MAX_DEPTH

__all__ = [
    'tide_status',
    'sensors_status',
    'silent_groups',
    'common_cause',
    'common_cause_groups',
    'runs',
    'CommonCause',
    'DEPTH_INPUT',
    'clock_time',
    'logger_status',
    'parameters_status',
    'clock_stopped',
    'clock_status',
    'intake_status',
    'missing_samples',
]


def tide_status(depth: float, stamp: float, now: float, timeout: float) -> tuple[Level, str]:
    """Level and message of the tide (depth) input.

    Parameters
    ----------
    depth : newest depth sample [m]; NaN if none was received.
    stamp : receive time of that sample [s]; NaN if none.
    now : current time [s].
    timeout : depth_timeout [s].

    Returns
    -------
    (Level.STALE, ...) before the first sample and when the newest one is older than
    ``timeout``; (Level.ERROR, ...) when the sample is not a positive finite number or is above
    :data:`~catenary_monitor.core.rules.plausible.MAX_DEPTH` (12 000 m); else
    (Level.OK, ...).
    """
    if math.isnan(stamp):
        return Level.STALE, 'no depth received yet'
    age = now - stamp
    if age > timeout:
        return Level.STALE, f'depth stale: last sample {age:.1f} s ago (timeout {timeout:g} s)'
    if not (math.isfinite(depth) and depth > 0.0):
        return Level.ERROR, f'impossible depth {depth!r} m (must be a positive number)'
    if depth > MAX_DEPTH:
        return Level.ERROR, (
            f'impossible depth {depth:g} m (above {MAX_DEPTH:g} m, deeper than any sea: '
            'a sensor or scaling fault)'
        )
    return Level.OK, f'depth {depth:.3f} m'


def _every(lines: int) -> str:
    """``all 12 lines`` (``the line`` when there is one)."""
    return f'all {lines} lines' if lines > 1 else 'the line'


def _names(names: Sequence[str], lines: int) -> str:
    """``12 lines`` (all), ``line_03, line_07`` (up to three) or ``5 lines (line_01, ...)``."""
    if len(names) == lines:
        return _every(lines)
    if len(names) <= 3:
        return ', '.join(names)
    return f'{len(names)} lines ({", ".join(names[:2])}, ...)'


#: One common cause: the inputs that fell silent together (line names, ``depth`` for the depth
#: gauge) and the first one's last sample [s].
CommonCause = tuple[tuple[str, ...], float]
#: The depth gauge's name among the inputs of a common cause.
DEPTH_INPUT = 'depth'


def silent_groups(last: np.ndarray, silent: np.ndarray, window: float) -> list[list[int]]:
    """The ``silent`` inputs grouped by cause: in the order of their last samples ``last`` [s],
    each joins the group whose first last sample is at most ``window`` [s] before its own (they
    fell silent together: a gateway, a network, a power supply), else starts a group."""
    last = np.asarray(last, np.float64)
    which = np.flatnonzero(np.asarray(silent, bool))
    order = which[np.argsort(last[which], kind='stable')]
    groups: list[list[int]] = []
    for i in order.tolist():
        if groups and last[i] - last[groups[-1][0]] <= window:
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def common_cause(
    last: np.ndarray,
    now: np.ndarray,
    timeout: np.ndarray,
    window: float,
    before: Sequence[bool],
) -> np.ndarray:
    """Per decision at ``now`` [s] (n,) and input (its last samples ``last`` [s], (n, m);
    NaN: none yet, which is no silence but a wait), whether the input is silent under a common
    cause: silent (older than its ``timeout`` [s], (m,)) and in a group of two or more of
    :func:`silent_groups`, or under one at the previous decision and silent since (``before``:
    the flags before the first decision). A lone silent input is its own alarm."""
    last = np.asarray(last, np.float64)
    n, m = last.shape
    with np.errstate(invalid='ignore'):
        silent = np.asarray(now, np.float64)[:, None] - last > np.asarray(timeout, np.float64)
    several = silent.sum(axis=1) >= 2
    grouped = np.zeros((n, m), bool)
    if several.any():
        rows = np.where(silent[several], last[several], -np.inf)
        first, run = runs(rows)
        flags = np.zeros((len(first), m), bool)
        for u, row in enumerate(rows[first]):
            for group in silent_groups(row, row > -np.inf, window):
                if len(group) >= 2:
                    flags[u, group] = True
        grouped[several] = flags[run]
    idx = np.arange(n)[:, None]
    was = np.asarray(before, bool)[None, :]
    found = np.maximum.accumulate(np.where(grouped, idx, np.where(was & (idx == 0), -1, -2)))
    fresh = np.maximum.accumulate(np.where(~silent, idx, -2))
    return silent & (found > fresh)


def runs(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The runs of equal consecutive ``rows`` (2-D): each run's first row, and each row's
    run (a silent input's last sample does not change while it is silent: a day of silence is
    one run)."""
    differ = np.ones(len(rows), bool)
    differ[1:] = (rows[1:] != rows[:-1]).any(axis=1)
    return np.flatnonzero(differ), np.cumsum(differ) - 1


def common_cause_groups(
    names: Sequence[str], last: Sequence[float], grouped: Sequence[bool], window: float
) -> tuple[CommonCause, ...]:
    """The common causes of one decision: the inputs under one (``grouped``, from
    :func:`common_cause`) grouped by their last samples [s] (:func:`silent_groups`), each
    with its names and since when."""
    stamps = np.asarray(last, np.float64)
    return tuple(
        (tuple(names[i] for i in sorted(group)), float(stamps[group[0]]))
        for group in silent_groups(stamps, np.asarray(grouped, bool), window)
    )


def clock_time(t: float) -> str:
    """``t`` [s, Unix] as the UTC time of day to a tenth of a second (``08:10:03.2``)."""
    tenths = int(math.floor(t * 10.0)) % 864000
    sec, tenth = divmod(tenths, 10)
    return f'{sec // 3600:02d}:{sec // 60 % 60:02d}:{sec % 60:02d}.{tenth}'


def _span(names: Sequence[str], order: Sequence[str]) -> str:
    """``line_01..line_09`` (consecutive in the configuration), else up to three named."""
    at = [order.index(n) for n in names if n in order]
    if len(names) > 3 and at == list(range(at[0], at[0] + len(at))):
        return f'{names[0]}..{names[-1]}'
    if len(names) > 3:
        return f'{", ".join(names[:2])}, ...'
    return ', '.join(names)


def _cause_text(cause: CommonCause, order: Sequence[str]) -> str:
    """One common cause's sentence."""
    names, since = cause
    lines = [n for n in names if n != DEPTH_INPUT]
    depth = len(lines) < len(names)
    what = 'load cells' if len(lines) > 1 else 'load cell'
    if depth:
        head = f'depth gauge and {len(lines)} {what} silent' if lines else 'depth gauge silent'
    else:
        head = f'{what} silent'
    where = _span(lines, order)
    where = f'{len(lines)} lines ({where})' if len(lines) > 3 else where
    text = f'{head}: {where} since {clock_time(since)}: gateway, network or power'
    return text + ('; every line blind' if depth else '')


def sensors_status(
    waiting: Sequence[str],
    lines: int,
    depth_s: float,
    depth_stale: bool,
    now: float,
    start: float,
    tension_timeout: float,
    depth_timeout: float,
    causes: Sequence[CommonCause] = (),
    order: Sequence[str] = (),
) -> tuple[Level, str]:
    """Level and message of the sensors' common-cause alarm (``catenary_monitor: sensors``).

    ``waiting``: the lines that have received no tension since the monitor started at ``start``
    [s]; ``lines``: how many lines there are; ``depth_s``: the newest depth sample's stamp [s]
    (NaN: none yet) and ``depth_stale`` the tide's decision that it is older than
    ``depth_timeout`` [s]; ``now`` [s].

    STALE (one alarm for many blind lines, their own STALE suppressed by design) when inputs
    fell silent together (``causes``, :func:`common_cause_groups`: "load cells silent: 9 lines
    (line_01..line_09) since 08:10:03.2: gateway, network or power", ``order`` the lines'
    names in the configuration), when lines are still waiting ``tension_timeout`` after the
    start ("waiting for sensors"), or the depth is stale or still missing ``depth_timeout``
    after the start ("depth sensor silent": every line is blind); else OK: every sensor
    reporting, or within those timeouts of the start (the lines and the tide are STALE
    meanwhile, and the message names what has not reported yet).
    """
    since = now - start
    late = list(waiting) if since > tension_timeout else []
    no_depth = depth_s != depth_s
    silent = depth_stale or (no_depth and since > depth_timeout)
    parts = [_cause_text(cause, order) for cause in causes]
    if any(DEPTH_INPUT in cause[0] for cause in causes):
        silent = False  # said with its cause
    if late:
        text = f'waiting for sensors: no tension from {_names(late, lines)} within '
        text += f'{tension_timeout:g} s of start'
        if silent and no_depth:
            text += f', no depth within {depth_timeout:g} s: {_every(lines)} blind'
        parts.append(text)
    if silent and not (late and no_depth):
        detail = (
            f'no depth within {depth_timeout:g} s of start'
            if no_depth
            else f'last depth {now - depth_s:.1f} s ago, timeout {depth_timeout:g} s'
        )
        parts.append(f'depth sensor silent: {_every(lines)} blind ({detail})')
    if parts:
        return Level.STALE, '; '.join(parts)
    if waiting or no_depth:
        what = [f'no tension from {_names(waiting, lines)}'] if waiting else []
        what += ['no depth'] if no_depth else []
        return Level.OK, (
            f'starting: {" and ".join(what)} yet (an alarm if still silent '
            f'{tension_timeout:g} s after start for tensions, {depth_timeout:g} s for the depth)'
        )
    return Level.OK, 'every sensor reporting'


def logger_status(
    error: Optional[str], path: Optional[str], warning: Optional[str] = None
) -> tuple[Level, str]:
    """Level and message of the MCAP logger: ERROR while it cannot write, WARN with a
    ``warning`` (low disk space), else OK."""
    if error:
        return Level.ERROR, f'MCAP log not written: {error}'
    where = f'logging to {path}' if path else 'logging'
    if warning:
        return Level.WARN, f'{warning} ({where})'
    return Level.OK, where


def parameters_status(messages: tuple[str, ...], until: float, now: float) -> tuple[Level, str]:
    """Level and message of the runtime-change flag: WARN, naming the accepted runtime
    changes, until ``until`` [s] (``runtime_change_warn_time`` after the newest one), else OK.

    ``messages`` are the :func:`~catenary_monitor.core.config.parameters.change_message` lines of
    the changes accepted while the flag was up (empty: none yet).
    """
    if messages and now < until:
        return Level.WARN, '; '.join(messages)
    if messages:
        return Level.OK, 'runtime changes allowed; the flag of the last one has expired'
    return Level.OK, 'runtime changes allowed; none made'


#: The ROS clock is reported stopped once it has not advanced for this long of wall time [s].
CLOCK_STOPPED_AFTER = 3.0
#: Intake: the counts are summed over this long [s].
INTAKE_WINDOW = 60.0
#: Intake: dropped share of the samples at or above which the status is ERROR (a WARN needs
#: ``intake_warn_count`` and ``intake_warn_share``).
DROPPED_ERROR_SHARE = 0.05
#: Intake: share of wall time spent in callbacks (over the last BUSY_WINDOW [s]) at or above
#: which the node cannot keep up, and below which that WARN clears (hysteresis: no flicker).
BUSY_WARN_SHARE = 0.6
BUSY_CLEAR_SHARE = 0.35
BUSY_WINDOW = 5.0
#: Intake with a configured sample rate: a shortfall counts as missing only beyond this many
#: seconds of samples, or :data:`MISSING_TOLERANCE_SHARE` of those expected if more (the
#: boundary of a report period and the sensors' clocks are not exact).
MISSING_TOLERANCE_TIME = 0.5
MISSING_TOLERANCE_SHARE = 0.01


def clock_stopped(frozen_for: float) -> bool:
    """True when the ROS clock has not advanced for ``frozen_for`` [s] of wall time, long
    enough (:data:`CLOCK_STOPPED_AFTER`) to say it stopped."""
    return frozen_for >= CLOCK_STOPPED_AFTER


def clock_status(stopped_for: Optional[float]) -> tuple[Level, str]:
    """Level and message of the ROS clock (``use_sim_time``): ERROR while it has not advanced
    for ``stopped_for`` [s] of wall time (None: it advances)."""
    if stopped_for is None:
        return Level.OK, 'ROS clock advancing (use_sim_time)'
    return Level.ERROR, (
        f'ROS clock stopped: /clock not advancing for {stopped_for:.0f} s '
        '(use_sim_time: alarms and staleness are frozen)'
    )


def missing_samples(rate: float, expected_time: float, got: int) -> int:
    """Samples missing from an input that publishes at ``rate`` [Hz] (0: unknown) over
    ``expected_time`` [s] in which ``got`` samples arrived or were counted dropped: the
    shortfall, once it exceeds the tolerance (:data:`MISSING_TOLERANCE_TIME`,
    :data:`MISSING_TOLERANCE_SHARE`), else 0."""
    if rate <= 0.0 or expected_time <= 0.0:
        return 0
    expected = rate * expected_time
    tolerance = max(rate * MISSING_TOLERANCE_TIME, MISSING_TOLERANCE_SHARE * expected)
    short = expected - got
    return int(round(short)) if short > tolerance else 0


def intake_status(
    received: int,
    dropped: int,
    busy: float,
    window: float,
    was_ok: bool = True,
    missing: int = 0,
    coalesced: int = 0,
    warn_count: float = 10.0,
    warn_share: float = 0.01,
) -> tuple[Level, str]:
    """Level and message of the sample intake over the last ``window`` [s].

    ``received``: tension and depth samples handled (stepped); ``dropped``: lost before the
    node took them (publisher sequence gaps, QoS message-lost events); ``missing``: samples not
    seen against the configured sample rates (:func:`missing_samples`), counted with the lost
    ones; ``coalesced``: taken and logged but not stepped, because a newer sample of the same
    input came before the node could (the node handles the newest of each input at once and
    leaves the older ones out: counted, never queued); ``busy``: share of wall time spent in
    callbacks over the last :data:`BUSY_WINDOW` (NaN: unknown). Every sample not handled
    counts as dropped: ERROR when at least :data:`DROPPED_ERROR_SHARE` of the samples were,
    WARN on a loss to act on (at least ``warn_count`` samples AND ``warn_share`` of them: a
    lone lost datagram is counted in the values and said in the OK message, never
    annunciated), or when the node is busy :data:`BUSY_WARN_SHARE` of the time
    (:data:`BUSY_CLEAR_SHARE` while the status is not OK, ``was_ok`` False), else OK.
    """
    counted = dropped
    lost = dropped + missing
    dropped = lost + coalesced
    total = received + dropped
    share = dropped / total if total else 0.0
    busy_text = '' if busy != busy else f'; busy {100.0 * busy:.0f} % of the time'
    idle = busy != busy or busy < BUSY_CLEAR_SHARE
    if missing and not counted and not coalesced and idle and share >= DROPPED_ERROR_SHARE:
        return Level.ERROR, (
            f'{100.0 * share:.0f} % of tension and depth samples missing in the last '
            f'{window:g} s ({missing} of {total} expected at the sample rates): a sensor '
            f'slower than its sample rate, or samples lost before the node{busy_text}'
        )
    # what the loss was made of (coalesced, missing), said with its figures in every message
    detail = f'; {missing} of them missing against the sample rates' if missing else ''
    if coalesced:
        detail = (
            f'; {coalesced} coalesced (logged, the newer sample of their input handled '
            f'instead), {lost} lost before the node{detail}'
        )
    if dropped and share >= DROPPED_ERROR_SHARE:
        return Level.ERROR, (
            f'node cannot keep up: {100.0 * share:.0f} % of tension and depth samples '
            f'dropped in the last {window:g} s ({dropped} of {total}){detail}{busy_text}'
        )
    text = (
        f'{dropped} of {total} tension and depth samples dropped in the last {window:g} s '
        f'({100.0 * share:.1f} %)'
    )
    if dropped and dropped >= warn_count and share >= warn_share:
        return Level.WARN, text + detail + busy_text
    # a smaller loss is never annunciated for itself, but never left out of a message either
    below = (
        f'{text}: below the warning ({warn_count:g} samples and {100.0 * warn_share:g} %)'
        f'{detail}'
    )
    if busy == busy and busy >= (BUSY_WARN_SHARE if was_ok else BUSY_CLEAR_SHARE):
        return Level.WARN, (
            f'node cannot keep up: busy {100.0 * busy:.0f} % of the last {BUSY_WINDOW:g} s in '
            'callbacks (samples may be lost)' + (f'; {below}' if dropped else '')
        )
    if dropped:
        return Level.OK, below + busy_text
    return Level.OK, f'{received} samples counted in the last {window:g} s, none dropped'
