"""Health of the node's shared inputs and of its logger: pure decisions, handed the time.

No rclpy. The node asks these functions which level and message its ``tide`` and ``logger``
diagnostic statuses carry, so that the node itself makes no threshold comparison. Times are
seconds on one clock (the node clock, or log time in replay).
"""

from __future__ import annotations

import math
from typing import Optional

from catenary_monitor.core.alarms import Level
from catenary_monitor.core.plausible import MAX_DEPTH

__all__ = ['tide_status', 'logger_status', 'parameters_status']


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
    :data:`~catenary_monitor.core.plausible.MAX_DEPTH` (12 000 m); else
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


def logger_status(error: Optional[str], path: Optional[str]) -> tuple[Level, str]:
    """Level and message of the MCAP logger: ERROR while it cannot write, else OK."""
    if error:
        return Level.ERROR, f'MCAP log not written: {error}'
    return Level.OK, f'logging to {path}' if path else 'logging'


def parameters_status(
    messages: tuple[str, ...], until: float, now: float
) -> tuple[Level, str]:
    """Level and message of the runtime-change flag: WARN, naming the accepted runtime
    changes, until ``until`` [s] (``runtime_change_warn_time`` after the newest one), else OK.

    ``messages`` are the :func:`~catenary_monitor.core.config.change_message` lines of the
    changes accepted while the flag was up (empty: none yet).
    """
    if messages and now < until:
        return Level.WARN, '; '.join(messages)
    if messages:
        return Level.OK, 'runtime changes allowed; the flag of the last one has expired'
    return Level.OK, 'runtime changes allowed; none made'
