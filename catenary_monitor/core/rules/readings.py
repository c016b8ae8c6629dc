"""Sensor readings in SI: what each input message type says, with its scale and datum.

Pure (no rclpy, no clock): the node hands a decoded message's fields here, and replay the same
fields read from a log as columns, so live and replay take the same readings. Fields by type
(scalars or arrays; :data:`TENSION_FIELDS`, :data:`DEPTH_FIELDS`):

* ``std_msgs/msg/Float64``: ``value``. Tension = ``value * NAME.tension_scale`` [N]; depth =
  ``value + depth_offset`` [m]. Taken at arrival (the message has no stamp).
* ``geometry_msgs/msg/WrenchStamped`` (ros2_control's force/torque broadcaster): its force
  ``x``, ``y``, ``z``; tension = ``NAME.tension_axis`` (one component, or ``norm``, the force
  vector's length) ``* NAME.tension_scale``.
* ``sensor_msgs/msg/FluidPressure`` (a pressure tide gauge, Pa): ``fluid_pressure``; depth =
  ``gauge_height + (fluid_pressure - atmospheric_pressure) / (water_density * g) +
  depth_offset`` with ``g`` = :data:`G` (standard gravity).
* ``sensor_msgs/msg/Range`` (a radar or sonar gauge looking down): ``range``, ``min_range``,
  ``max_range``; depth = ``gauge_height - range + depth_offset``; a range outside its own
  limits (REP 117: -inf too close, +inf no return) or not finite gives NaN, an impossible
  depth the tide status reports.

The stamped types are taken at their header stamp (:func:`stamp_fault` refuses a stamp too far
ahead of the monitor's clock, a year or more behind it, or going backwards).

A recorded log's own stamps (the log time each message was received at) can be wrong too: a
recorder that booted with its clock in 1970, or one that jumped to 2100 and back.
:func:`far_stamps` finds the samples far from every other (:data:`STAMP_FAR`): bad stamps,
left out and counted by the replay, never a span of time to step through.
"""

from __future__ import annotations

from typing import Any, Mapping, Optional

import numpy as np

from catenary_monitor.core.config.parameters import FLOAT64, LineConfig, MonitorConfig

__all__ = [
    'G',
    'WRENCH',
    'FLUID_PRESSURE',
    'RANGE',
    'TENSION_FIELDS',
    'DEPTH_FIELDS',
    'STAMPED',
    'FAULT_AHEAD',
    'FAULT_BACKWARDS',
    'FAULT_FAR',
    'tension_si',
    'depth_si',
    'stamp_fault',
    'stamp_faults',
    'STAMP_FAR',
    'far_stamps',
]

#: Standard gravity [m/s^2] (the pressure-to-depth conversion).
G = 9.80665
WRENCH = 'geometry_msgs/msg/WrenchStamped'
FLUID_PRESSURE = 'sensor_msgs/msg/FluidPressure'
RANGE = 'sensor_msgs/msg/Range'
#: The fields each tension message type gives (in this order).
TENSION_FIELDS = {FLOAT64: ('value',), WRENCH: ('x', 'y', 'z')}
#: The fields each depth message type gives (in this order).
DEPTH_FIELDS = {
    FLOAT64: ('value',),
    FLUID_PRESSURE: ('fluid_pressure',),
    RANGE: ('range', 'min_range', 'max_range'),
}
#: The types taken at their header stamp (the others at arrival).
STAMPED = frozenset({WRENCH, FLUID_PRESSURE, RANGE})
#: :func:`stamp_fault` codes: a header stamp ahead of the clock, before the one before, or
#: more than :data:`STAMP_FAR` before its arrival (a sensor's clock in 1970).
FAULT_AHEAD, FAULT_BACKWARDS, FAULT_FAR = 1, 2, 3
#: A recorded sample more than this far [s] from every other sample of the log is a bad stamp
#: (:func:`far_stamps`): a year, longer than any gap between a dock's recordings.
STAMP_FAR = 365.0 * 86_400.0


def tension_si(line: LineConfig, fields: Mapping[str, Any]) -> Any:
    """The hook tension [N] of a reading of ``line``'s type (``fields`` as above)."""
    scale = line.tension_scale
    if line.tension_type == FLOAT64:
        return np.multiply(fields['value'], scale)
    axis = line.tension_axis
    if axis == 'norm':
        x, y, z = (np.asarray(fields[k], np.float64) for k in ('x', 'y', 'z'))
        return np.sqrt(x * x + y * y + z * z) * scale
    return np.multiply(fields[axis], scale)


def depth_si(config: MonitorConfig, fields: Mapping[str, Any]) -> Any:
    """The depth at the hooks [m] of a reading of ``config.depth_type`` (``fields`` as above)."""
    kind, offset = config.depth_type, config.depth_offset
    if kind == FLOAT64:
        return np.add(fields['value'], offset)
    if kind == FLUID_PRESSURE:
        head = (np.asarray(fields['fluid_pressure'], np.float64) - config.atmospheric_pressure) / (
            config.water_density * G
        )
        return config.gauge_height + head + offset
    r = np.asarray(fields['range'], np.float64)
    lo = np.asarray(fields['min_range'], np.float64)
    hi = np.asarray(fields['max_range'], np.float64)
    with np.errstate(invalid='ignore'):
        inside = np.isfinite(r) & (r >= lo) & (r <= hi)
    return np.where(inside, config.gauge_height - r + offset, np.nan)


def stamp_fault(arrival_ns: int, sample_ns: int, last_ns: int, ahead_max: float) -> int:
    """0, or why a stamped sample is refused: :data:`FAULT_AHEAD` (its stamp more than
    ``ahead_max`` [s] after its arrival on the monitor's clock), :data:`FAULT_FAR` (more than
    :data:`STAMP_FAR` before it), :data:`FAULT_BACKWARDS` (before the newest accepted stamp
    ``last_ns``; -1: none yet). Equal stamps are accepted."""
    if sample_ns - arrival_ns > ahead_max * 1e9:
        return FAULT_AHEAD
    if arrival_ns - sample_ns > STAMP_FAR * 1e9:
        return FAULT_FAR
    if sample_ns < last_ns:
        return FAULT_BACKWARDS
    return 0


def stamp_faults(
    arrival_ns: np.ndarray, sample_ns: np.ndarray, last_ns: int, ahead_max: float
) -> np.ndarray:
    """:func:`stamp_fault` over a column of samples in arrival order (int8 codes): a sample is
    refused when ahead, far behind, or before the newest accepted one (the running maximum of
    the samples neither ahead nor far behind: a sample going backwards never raises it)."""
    arrival = np.asarray(arrival_ns, np.int64)
    sample = np.asarray(sample_ns, np.int64)
    ahead = (sample - arrival) > ahead_max * 1e9
    far = ~ahead & ((arrival - sample) > STAMP_FAR * 1e9)
    eligible = np.where(ahead | far, np.iinfo(np.int64).min, sample)
    newest = np.maximum.accumulate(np.concatenate([[last_ns], eligible]))[:-1]
    code = np.zeros(len(sample), np.int8)
    code[(sample < newest) & ~ahead & ~far] = FAULT_BACKWARDS
    code[far] = FAULT_FAR
    code[ahead] = FAULT_AHEAD
    return code


def far_stamps(
    stamps: np.ndarray,
    before_ns: Optional[int] = None,
    after_ns: Optional[int] = None,
    far: float = STAMP_FAR,
) -> np.ndarray:
    """Which samples of a stretch of log are bad stamps (bool): more than ``far`` [s] from
    their nearest neighbour, the samples of every input merged. ``stamps``: the stretch's
    samples (ns, sorted); ``before_ns`` / ``after_ns``: the sample just before / after the
    stretch (None: none). A sample without any neighbour (a log of one sample) is not one;
    samples at one stamp are each other's neighbours."""
    s = np.asarray(stamps, np.int64)
    n = len(s)
    if not n:
        return np.zeros(0, bool)
    limit, inf = far * 1e9, np.inf
    f = s.astype(np.float64)  # no int64 wrap between stamps of any two centuries
    gaps = np.diff(f)
    left = np.concatenate([[inf if before_ns is None else f[0] - float(before_ns)], gaps])
    right = np.concatenate([gaps, [inf if after_ns is None else float(after_ns) - f[-1]]])
    alone = (left == inf) & (right == inf)
    return (left > limit) & (right > limit) & ~alone
