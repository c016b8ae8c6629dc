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
* **Tension off by orders of magnitude below** (:attr:`Status.WRONG_UNITS`): 100 times or more
  below the hanging chain's own weight ``w * h`` (``UNITS_FACTOR``), or at or below ``w * h``
  where 1000 times the reading (a load cell in kN read as N) would lie between ``w * h`` and
  the MBL. A chain cannot hang with less than its own weight at the hook, so such a reading is
  a scale (or a parted chain); the message names the line's ``tension_scale``. A negative
  reading stays the solver's ``T <= w*h``.
* **Depth** (with the hook height) above ``MAX_DEPTH`` = 12 000 m: deeper than any sea
  (Challenger Deep, about 10 935 m).

Both tension sentences end with "wrong units?" and the parameter to check
(:func:`status_messages`: the status table of one line).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from catenary_monitor.core.config.parameters import LineConfig
from catenary_monitor.core.physics.result import STATUS_MESSAGES, Status

__all__ = [
    'MAX_DEPTH',
    'MAX_TENSION_PER_MBL',
    'UNITS_FACTOR',
    'KN',
    'reading_status',
    'reading_status_array',
    'status_messages',
    'units_hint',
]

MAX_DEPTH = 12_000.0  # m
MAX_TENSION_PER_MBL = 10.0  # -, tension bound as a multiple of the MBL
UNITS_FACTOR = 100.0  # -, a tension this many times below w * h is off by orders of magnitude
KN = 1000.0  # N per kN: the scale a load cell in kN needs


def reading_status(
    tension: float,
    depth: float,
    mbl: float,
    weight: float = math.nan,
    low: float = -math.inf,
    high: float = MAX_DEPTH,
) -> int:
    """0, or the Status of an implausible finite reading.

    Parameters: hook tension [N], depth at the hook [m], minimum breaking load [N], the
    chain's submerged weight [N/m] (NaN: no check below), the chart range at the hook [m]
    (``depth_min``, ``depth_max`` + the hook height: outside it the depth is impossible). An
    implausible depth wins over an implausible tension; non-finite readings give 0 (the solver
    reports them).
    """
    if not (math.isfinite(tension) and math.isfinite(depth)):
        return 0
    if depth > MAX_DEPTH or depth > high or depth < low:
        return int(Status.IMPLAUSIBLE_DEPTH)
    if tension > MAX_TENSION_PER_MBL * mbl:
        return int(Status.IMPLAUSIBLE_TENSION)
    hanging = weight * depth
    if (
        depth > 0.0
        and tension >= 0.0
        and (tension * UNITS_FACTOR <= hanging or (tension <= hanging < KN * tension <= mbl))
    ):
        return int(Status.WRONG_UNITS)
    return 0


def reading_status_array(
    tension: Any,
    depth: Any,
    mbl: Any,
    weight: Any = math.nan,
    low: Any = -math.inf,
    high: Any = MAX_DEPTH,
) -> np.ndarray:
    """:func:`reading_status` element by element (int64 array of the broadcast shape)."""
    t, h = np.asarray(tension, dtype=float), np.asarray(depth, dtype=float)
    w = np.asarray(weight, dtype=float)
    with np.errstate(invalid='ignore'):
        finite = np.isfinite(t) & np.isfinite(h)
        deep = finite & ((h > MAX_DEPTH) | (h > high) | (h < low))
        strong = finite & ~deep & (t > MAX_TENSION_PER_MBL * np.asarray(mbl, dtype=float))
        hanging = w * h
        weak = (
            finite
            & ~deep
            & ~strong
            & (h > 0.0)
            & (t >= 0.0)
            & (
                (t * UNITS_FACTOR <= hanging)
                | ((t <= hanging) & (hanging < KN * t) & (KN * t <= np.asarray(mbl, float)))
            )
        )
    out = np.zeros(np.broadcast(t, h, w, deep).shape, dtype=np.int64)
    out[deep] = Status.IMPLAUSIBLE_DEPTH
    out[strong] = Status.IMPLAUSIBLE_TENSION
    out[weak] = Status.WRONG_UNITS
    return out


def units_hint(line: LineConfig, low: bool) -> str:
    """ "wrong units?" and the parameter to check, for a reading too low (``low``) or too high."""
    name, scale = f'{line.name}.tension_scale', line.tension_scale
    if low:
        return (
            f'wrong units? a load cell in kN needs {name}: {KN:g} (it is {scale:g}; the '
            'tension is the reading x the scale, in N)'
        )
    return (
        f'wrong units? check {name} (it is {scale:g}; the tension is the reading x the scale, '
        'in N)'
    )


def status_messages(line: LineConfig) -> dict[int, str]:
    """The status sentences of ``line``: :data:`STATUS_MESSAGES` with the implausible tension's
    and the wrong units' naming the line's scale parameter."""
    out = dict(STATUS_MESSAGES)
    out[Status.IMPLAUSIBLE_TENSION] = (
        f'{STATUS_MESSAGES[Status.IMPLAUSIBLE_TENSION]}: {units_hint(line, False)}'
    )
    out[Status.IMPLAUSIBLE_DEPTH] = (
        'depth outside the chart (depth_min, depth_max) or deeper than any sea (above '
        f'{MAX_DEPTH:g} m): the tide gauge\'s datum, scale or the sensor; not solved (the tide '
        'status names it)'
    )
    out[Status.WRONG_UNITS] = (
        'hook tension 100 times or more below the hanging chain\'s own weight w*h, or below it '
        f'where 1000 times the reading would fit the chain (or a parted chain): '
        f'{units_hint(line, True)}'
    )
    return out
