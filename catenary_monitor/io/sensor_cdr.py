"""The sensors' stamped messages decoded from their CDR bytes, as columns (no rclpy).

``geometry_msgs/msg/WrenchStamped``, ``sensor_msgs/msg/FluidPressure`` and
``sensor_msgs/msg/Range`` as the node logs them and rosbag2 records them: the header stamp (ns)
and the fields :mod:`catenary_monitor.core.rules.readings` turns into a tension or a depth
(``x``, ``y``, ``z`` of the force; ``fluid_pressure``; ``range``, ``min_range``, ``max_range``).
CDR (XCDR1) little or big endian: after the 4-byte encapsulation, the header (``int32 sec``,
``uint32 nanosec``, ``string frame_id``), then the message's own fields, each aligned to its
size counted from the end of the encapsulation. ``test/test_stamped_inputs.py`` checks the
decoding against ``rclpy.serialization``.
"""

from __future__ import annotations

import struct
from typing import NamedTuple, Sequence

import numpy as np

__all__ = ['STAMPED_TYPES', 'StampedColumns', 'decode']

#: The decodable types and the fields each gives, in order.
STAMPED_TYPES = {
    'geometry_msgs/msg/WrenchStamped': ('x', 'y', 'z'),
    'sensor_msgs/msg/FluidPressure': ('fluid_pressure',),
    'sensor_msgs/msg/Range': ('range', 'min_range', 'max_range'),
}


class StampedColumns(NamedTuple):
    """Decoded messages: ``ok`` (bool per payload: decoded), and for the decoded ones their
    header ``stamps`` (ns, int64) and ``fields`` (name -> float64 array)."""

    ok: np.ndarray
    stamps: np.ndarray
    fields: dict[str, np.ndarray]


def _one(type_name: str, data: bytes) -> tuple[int, tuple[float, ...]]:
    """(stamp ns, fields) of one payload; ValueError or struct.error when it is not one."""
    if len(data) < 16 or data[0] != 0 or data[1] not in (0, 1):
        raise ValueError('not CDR')
    e = '<' if data[1] == 1 else '>'
    sec, nanosec, n = struct.unpack_from(e + 'iII', data, 4)
    if nanosec >= 1_000_000_000:
        raise ValueError('nanosec out of range')
    body = 12 + n  # offset after frame_id, from the end of the encapsulation
    if type_name == 'sensor_msgs/msg/Range':
        body += 1  # uint8 radiation_type
        body += -body % 4
        values = struct.unpack_from(e + 'ffff', data, 4 + body)  # fov, min, max, range
        fields: tuple[float, ...] = (values[3], values[1], values[2])
    else:
        body += -body % 8
        count = 3 if type_name == 'geometry_msgs/msg/WrenchStamped' else 1
        fields = struct.unpack_from(e + 'd' * count, data, 4 + body)
    return sec * 1_000_000_000 + nanosec, fields


def decode(type_name: str, payloads: Sequence[bytes]) -> StampedColumns:
    """Every payload of a stamped type (:data:`STAMPED_TYPES`), as columns; a payload that is
    not one (too short, not CDR) is left out (``ok`` False) for the caller to report."""
    names = STAMPED_TYPES[type_name]
    ok = np.zeros(len(payloads), bool)
    stamps = np.zeros(len(payloads), np.int64)
    values = np.zeros((len(payloads), len(names)))
    for i, data in enumerate(payloads):
        try:
            stamps[i], values[i] = _one(type_name, data)
        except (ValueError, struct.error):
            continue
        ok[i] = True
    return StampedColumns(
        ok, stamps[ok], {name: values[ok, j] for j, name in enumerate(names)}
    )
