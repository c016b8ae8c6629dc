"""Readings no mooring can produce: the plausibility bounds of a tension and a depth sample.

Pure: no rclpy, no clock. A finite reading beyond these bounds is an impossible input (a
sensor, scaling or wiring fault), reported with its own status code and sentence, not handed
to the solver (which would answer "did not converge" for a tension of 1e300 N). NaN and
infinite readings stay :attr:`Status.NON_FINITE`. The scalar core (``MonitorCore``) and its
batch twin both call :func:`reading_status`, so live and replay decide alike.

Bounds
------
* **Tension** above ``MAX_TENSION_PER_MBL`` x the line's MBL (10 x): a chain parts at its MBL,
  so a reading ten times above it is a measurement fault, whatever the safety margin of the
  MBL given; the safety-factor alarm covers every real overload below that.
* **Depth** (with the hook height) above ``MAX_DEPTH`` = 12 000 m: deeper than any sea
  (Challenger Deep, about 10 935 m).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from catenary_monitor.core.physics.result import Status

__all__ = ['MAX_DEPTH', 'MAX_TENSION_PER_MBL', 'reading_status', 'reading_status_array']

MAX_DEPTH = 12_000.0  # m
MAX_TENSION_PER_MBL = 10.0  # -, tension bound as a multiple of the MBL


def reading_status(tension: float, depth: float, mbl: float) -> int:
    """0, or the Status of an implausible finite reading.

    Parameters: hook tension [N], depth at the hook [m], minimum breaking load [N].
    An implausible depth wins over an implausible tension; non-finite readings give 0 (the
    solver reports them).
    """
    if not (math.isfinite(tension) and math.isfinite(depth)):
        return 0
    if depth > MAX_DEPTH:
        return int(Status.IMPLAUSIBLE_DEPTH)
    if tension > MAX_TENSION_PER_MBL * mbl:
        return int(Status.IMPLAUSIBLE_TENSION)
    return 0


def reading_status_array(tension: Any, depth: Any, mbl: Any) -> np.ndarray:
    """:func:`reading_status` element by element (int64 array of the broadcast shape)."""
    t, h = np.asarray(tension, dtype=float), np.asarray(depth, dtype=float)
    if t.shape == h.shape and t.size and np.ndim(mbl) == 0:  # the usual case, in two passes
        limit = MAX_TENSION_PER_MBL * float(mbl)
        if not np.fmax.reduce(h, axis=None) > MAX_DEPTH:  # NaN only if every value is NaN
            if not np.fmax.reduce(t, axis=None) > limit:
                return np.zeros(t.shape, dtype=np.int64)
    with np.errstate(invalid='ignore'):
        finite = np.isfinite(t) & np.isfinite(h)
        deep = finite & (h > MAX_DEPTH)
        strong = finite & ~deep & (t > MAX_TENSION_PER_MBL * np.asarray(mbl, dtype=float))
    out = np.zeros(np.broadcast(t, h).shape, dtype=np.int64)
    out[deep] = Status.IMPLAUSIBLE_DEPTH
    out[strong] = Status.IMPLAUSIBLE_TENSION
    return out
