"""CDR (XCDR1, little endian) encoding of the few ROS 2 messages replay writes, without rclpy.

``std_msgs/msg/Float64`` and ``std_msgs/msg/Float64MultiArray`` with a fixed layout are a
constant byte prefix followed by doubles, so whole columns are encoded with numpy at once
(:func:`float64_payloads`, :func:`multiarray_payloads`). ``diagnostic_msgs/msg/DiagnosticArray``
is encoded field by field (:func:`diagnostic_array`); the tests check every encoding against
``rclpy.serialization``.

Alignment follows the CDR rule: a primitive of size n starts at an offset (counted after the
4-byte encapsulation header) that is a multiple of n.
"""

from __future__ import annotations

import struct
from typing import Any, Callable, Sequence

import numpy as np

__all__ = [
    'ENCAPSULATION',
    'float64_payloads',
    'multiarray_prefix',
    'multiarray_payloads',
    'diagnostic_array',
    'status_header',
    'key_values',
    'diagnostic_array_parts',
    'string_message',
    'string_text',
]

#: CDR little-endian encapsulation header.
ENCAPSULATION = b'\x00\x01\x00\x00'


class _Buffer:
    """Append-only CDR body with alignment relative to the end of the encapsulation header."""

    def __init__(self) -> None:
        self.parts: list[bytes] = []
        self.size = 0

    def align(self, n: int) -> None:
        pad = -self.size % n
        if pad:
            self.parts.append(b'\0' * pad)
            self.size += pad

    def raw(self, data: bytes) -> None:
        self.parts.append(data)
        self.size += len(data)

    def u32(self, value: int) -> None:
        self.align(4)
        self.raw(struct.pack('<I', value))

    def i32(self, value: int) -> None:
        self.align(4)
        self.raw(struct.pack('<i', value))

    def string(self, text: str) -> None:
        data = text.encode('utf-8') + b'\0'
        self.u32(len(data))
        self.raw(data)

    def bytes(self) -> bytes:
        return ENCAPSULATION + b''.join(self.parts)


def float64_payloads(values: np.ndarray) -> np.ndarray:
    """``(n, 12)`` uint8: the CDR of ``std_msgs/msg/Float64`` for each value."""
    values = np.asarray(values, np.float64)
    out = np.empty((len(values), 12), np.uint8)
    out[:, :4] = np.frombuffer(ENCAPSULATION, np.uint8)
    out[:, 4:] = values.astype('<f8').view(np.uint8).reshape(-1, 8)
    return out


def multiarray_prefix(label: str, size: int) -> bytes:
    """CDR bytes of a ``Float64MultiArray`` with one dimension ``(label, size, size)``,
    ``data_offset`` 0 and ``size`` doubles, up to (not including) the first double."""
    b = _Buffer()
    b.u32(1)  # layout.dim: one MultiArrayDimension
    b.string(label)
    b.u32(size)  # size
    b.u32(size)  # stride
    b.u32(0)  # layout.data_offset
    b.u32(size)  # data: sequence length
    b.align(8)
    return b.bytes()


def multiarray_payloads(label: str, data: np.ndarray) -> np.ndarray:
    """``(n, len(prefix) + 8 k)`` uint8: one ``Float64MultiArray`` per row of ``data`` (n, k)."""
    data = np.ascontiguousarray(data, '<f8')
    n, k = data.shape
    prefix = np.frombuffer(multiarray_prefix(label, k), np.uint8)
    out = np.empty((n, len(prefix) + 8 * k), np.uint8)
    out[:, : len(prefix)] = prefix
    out[:, len(prefix) :] = data.view(np.uint8).reshape(n, 8 * k)
    return out


Status = tuple[int, str, str, str, Sequence[tuple[str, str]]]


_U32 = struct.Struct('<I').pack
_PAD = (b'', b'\0', b'\0\0', b'\0\0\0')
_STRINGS: dict[str, bytes] = {}


def _string(buf: bytearray, text: str) -> None:
    """Append a CDR string (aligned uint32 length incl. NUL, UTF-8, NUL) to ``buf``.

    ``buf`` starts with the 4-byte encapsulation header, so alignment is ``len(buf) % 4``.
    """
    cdr = _STRINGS.get(text)
    if cdr is None:
        data = text.encode('utf-8')
        cdr = _U32(len(data) + 1) + data + b'\0'
        if len(_STRINGS) < 4096:
            _STRINGS[text] = cdr
    buf += _PAD[-len(buf) % 4]
    buf += cdr


def diagnostic_array(stamp_ns: int, statuses: Sequence[Status], frame_id: str = '') -> bytes:
    """CDR of a ``diagnostic_msgs/msg/DiagnosticArray``.

    ``statuses``: ``(level, name, message, hardware_id, [(key, value), ...])`` each;
    ``stamp_ns`` fills ``header.stamp``.
    """
    buf = bytearray(ENCAPSULATION)
    buf += struct.pack('<iI', stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000)
    _string(buf, frame_id)
    buf += _PAD[-len(buf) % 4]
    buf += _U32(len(statuses))
    for level, name, message, hardware_id, values in statuses:
        buf.append(level)
        _string(buf, name)
        _string(buf, message)
        _string(buf, hardware_id)
        buf += _PAD[-len(buf) % 4]
        buf += _U32(len(values))
        for key, value in values:
            _string(buf, key)
            _string(buf, value)
    return bytes(buf)


# --- DiagnosticArray from pre-encoded pieces (replay writes one per line per tick) ----------
# A status is ``header(level, name, message, hardware_id, count)`` + ``key/value pairs``. The
# header ends on a 4-byte boundary (the count), so the pairs' bytes never depend on where the
# status starts; the header depends on it only through ``offset % 4``.


def status_header(
    level: int, name: str, message: str, hardware_id: str, n_values: int, align: int
) -> bytes:
    """Bytes of a DiagnosticStatus up to its ``values`` count, starting at ``offset % 4 ==
    align`` (the padding before each field included)."""
    buf = bytearray(b'\0' * (4 + align))  # a stand-in prefix with the same alignment
    start = len(buf)
    buf.append(level)
    _string(buf, name)
    _string(buf, message)
    _string(buf, hardware_id)
    buf += _PAD[-len(buf) % 4]
    buf += _U32(n_values)
    return bytes(buf[start:])


def key_values(pairs: Sequence[tuple[str, str]]) -> bytes:
    """Bytes of a KeyValue sequence's elements, starting on a 4-byte boundary."""
    out = []
    pos = 0
    for key, value in pairs:
        k = _STRINGS.get(key)
        if k is None:
            data = key.encode('utf-8')
            k = _U32(len(data) + 1) + data + b'\0'
        pad = -pos & 3
        out.append(_PAD[pad])
        out.append(k)
        pos += pad + len(k)
        v = value.encode('utf-8')
        pad = -pos & 3
        out.append(_PAD[pad] + _U32(len(v) + 1) + v + b'\0')
        pos += pad + 5 + len(v)
    return b''.join(out)


def diagnostic_array_parts(
    stamp_ns: int, statuses: Sequence[tuple[Callable[[int], bytes], bytes]]
) -> bytes:
    """CDR of a DiagnosticArray (empty ``frame_id``) from, per status, a function giving its
    header for an alignment (see :func:`status_header`) and its :func:`key_values` bytes."""
    parts = [
        ENCAPSULATION,
        struct.pack('<iI', stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000),
        b'\x01\x00\x00\x00\x00\x00\x00\x00',
        _U32(len(statuses)),
    ]
    align = 0  # offset 20 after the encapsulation
    for header, pairs in statuses:
        parts.append(header(align))
        parts.append(pairs)
        align = len(pairs) % 4
    return b''.join(parts)


# --- std_msgs/msg/String ------------------------------------------------------------------------


def string_message(text: str) -> bytes:
    """CDR of a ``std_msgs/msg/String``."""
    buf = bytearray(ENCAPSULATION)
    _string(buf, text)
    return bytes(buf)


def string_text(data: bytes) -> str:
    """The text of a ``std_msgs/msg/String`` in CDR (ValueError if it is not one)."""
    if len(data) < 9 or data[1] not in (0, 1):
        raise ValueError('not a CDR std_msgs/String')
    order = '<' if data[1] == 1 else '>'
    (n,) = struct.unpack(order + 'I', data[4:8])
    if n < 1 or 8 + n > len(data) or data[8 + n - 1] != 0:
        raise ValueError('not a CDR std_msgs/String')
    return data[8 : 8 + n - 1].decode('utf-8')


# --- DiagnosticArrays of many snapshots, a status shape at a time (replay's --out) ------------
# A status after its level byte is its "body": name, message, hardware_id, the values count
# and the key/value strings, all 4-byte aligned from the body's start (which is aligned: the
# level byte and the padding after it come before). :func:`status_bodies` encodes the bodies
# of n statuses of one shape (the same keys) at once with numpy; :func:`diagnostic_array_bodies`
# puts one array together from its statuses' levels and bodies. Both give the bytes
# :func:`diagnostic_array` gives (the tests compare them).

Field = str | Sequence[str]


def status_body(
    name: str, message: str, hardware_id: str, values: Sequence[tuple[str, str]]
) -> bytes:
    """The body of one DiagnosticStatus (everything after its level byte and padding)."""
    buf = bytearray(ENCAPSULATION)  # a stand-in prefix: the body starts aligned
    _string(buf, name)
    _string(buf, message)
    _string(buf, hardware_id)
    buf += _PAD[-len(buf) % 4]
    buf += _U32(len(values))
    buf += key_values(values)
    return bytes(buf[4:])


def _padded(text: str) -> bytes:
    """A CDR string padded with zeros to a multiple of 4 bytes."""
    data = text.encode('utf-8')
    cdr = _U32(len(data) + 1) + data + b'\0'
    return cdr + b'\0' * (-len(cdr) % 4)


def _utf8(texts: Sequence[str], n: int) -> tuple[bytes, np.ndarray]:
    """The UTF-8 texts one after the other, and their lengths in bytes."""
    if len(texts) != n:
        raise ValueError(f'{len(texts)} values for {n} statuses')
    joined = ''.join(texts)
    if joined.isascii():
        return joined.encode('ascii'), np.fromiter(map(len, texts), np.int64, n)
    data = [t.encode('utf-8') for t in texts]
    return b''.join(data), np.fromiter(map(len, data), np.int64, n)


def status_bodies(
    n: int,
    name: Field,
    message: Field,
    hardware_id: Field,
    keys: Sequence[str],
    values: Sequence[Field],
) -> tuple[bytes, np.ndarray, np.ndarray]:
    """The bodies (see :func:`status_body`) of ``n`` statuses with the same ``keys``: each of
    ``name``, ``message``, ``hardware_id`` and ``values`` (one per key) is a str (the same in
    every status) or a sequence of ``n`` str. Returns (buffer, starts, ends): body ``i`` is
    ``buffer[starts[i]:ends[i]]``."""
    if len(values) != len(keys):
        raise ValueError(f'{len(values)} value columns for {len(keys)} keys')
    fields: list[Any] = [name, message, hardware_id, None]
    for key, value in zip(keys, values):
        fields += [key, value]
    # Where each field starts in its body: an int while every body has the same lengths.
    rel: Any = 0
    constants: list[tuple[Any, np.ndarray]] = []
    texts: list[tuple[Any, bytes, np.ndarray]] = []
    last_end: Any = 0
    for f in fields:
        if f is None or isinstance(f, str):
            data = _U32(len(keys)) if f is None else _padded(f)
            constants.append((rel, np.frombuffer(data, '<u4')))
            last_end = rel + (4 if f is None else 5 + len(f.encode('utf-8')))
            rel = rel + len(data)
        else:
            joined, lens = _utf8(f, n)
            texts.append((rel, joined, lens))
            last_end = rel + 5 + lens
            rel = rel + 4 + ((lens + 4) & ~3)
    sizes = np.broadcast_to(np.asarray(rel, np.int64), (n,))
    starts = np.zeros(n, np.int64)
    np.cumsum(sizes[:-1], out=starts[1:])
    buf = np.zeros(int(sizes.sum()) if n else 0, np.uint8)
    words = buf.view('<u4')
    for offset, padded in constants:  # a constant's padded words, in every body
        words[((starts + offset) >> 2)[:, None] + np.arange(len(padded))] = padded
    for offset, joined, lens in texts:  # a text's length word, then its bytes
        at = starts + offset
        words[at >> 2] = lens + 1
        total = len(joined)
        if total:
            before = np.zeros(n, np.int64)
            np.cumsum(lens[:-1], out=before[1:])
            where = np.repeat(at + 4 - before, lens) + np.arange(total)
            buf[where] = np.frombuffer(joined, np.uint8)
    return buf.tobytes(), starts, starts + last_end


_LEVEL_GAPS: dict[tuple[int, int], bytes] = {}


def diagnostic_array_bodies(
    stamp_ns: int, levels: Sequence[int], bodies: Sequence[bytes]
) -> bytes:
    """CDR of a DiagnosticArray (empty ``frame_id``) from its statuses' levels and bodies."""
    parts = [
        ENCAPSULATION,
        struct.pack('<iI', stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000),
        b'\x01\x00\x00\x00\x00\x00\x00\x00',
        _U32(len(bodies)),
    ]
    end = 0  # offset 20 after the encapsulation: aligned
    for level, body in zip(levels, bodies):
        gap = _LEVEL_GAPS.get((level, end))
        if gap is None:
            gap = _LEVEL_GAPS[(level, end)] = bytes((level,)) + b'\0' * (3 - end)
        parts.append(gap)
        parts.append(body)
        end = len(body) & 3
    return b''.join(parts)
