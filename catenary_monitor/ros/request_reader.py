"""The operators' request topics read with each message's publisher GID.

rclpy (Jazzy) hands a subscription callback the message and, at best, a MessageInfo without
the publisher's GID; rcl's ``rcl_take_serialized_message`` fills ``rmw_message_info_t``, whose
``publisher_gid`` names the sender of that very message. So the request subscriptions belong
to a helper node that no executor spins (``NODE_requests``, in the node's namespace, without
the global ROS arguments), and the node takes their messages itself on a timer: through rcl
(``ctypes``, the library rclpy loaded) with the GID, checked against the middleware's name
for it and the graph's publishers; else (another rcl, a check failed) through rclpy without
one, the publisher then named from the graph as before.

Wiring only: no decision here (core/alarms/requests.py rate-limits, the core decides).
"""

from __future__ import annotations

import ctypes
from ctypes import POINTER, Structure, byref, c_bool, c_char_p, c_int, c_int64, c_size_t
from ctypes import c_uint8, c_uint64, c_void_p
from typing import Any, NamedTuple, Optional

__all__ = ['Taken', 'RequestReader', 'GID_SIZE']

#: ``RMW_GID_STORAGE_SIZE`` of Jazzy's rmw (24 before Jazzy): the bytes of a GID.
GID_SIZE = 16
#: Messages taken per topic per call at most (the rest wait in the reader's queue).
TAKE_MAX = 256
_RCL_RET_OK = 0


class Taken(NamedTuple):
    """One request message: its CDR bytes, its publisher's GID (None: unknown) and that
    publisher's sequence number for it (None: unknown)."""

    data: bytes
    gid: Optional[bytes]
    sequence: Optional[int]


class _Allocator(Structure):
    _fields_ = [
        ('allocate', c_void_p),
        ('deallocate', c_void_p),
        ('reallocate', c_void_p),
        ('zero_allocate', c_void_p),
        ('state', c_void_p),
    ]


class _Bytes(Structure):  # rcutils_uint8_array_t (rmw_serialized_message_t)
    _fields_ = [
        ('buffer', POINTER(c_uint8)),
        ('buffer_length', c_size_t),
        ('buffer_capacity', c_size_t),
        ('allocator', _Allocator),
    ]


class _Gid(Structure):
    _fields_ = [('implementation_identifier', c_char_p), ('data', c_uint8 * GID_SIZE)]


class _Info(Structure):  # rmw_message_info_t (Jazzy)
    _fields_ = [
        ('source_timestamp', c_int64),
        ('received_timestamp', c_int64),
        ('publication_sequence_number', c_uint64),
        ('reception_sequence_number', c_uint64),
        ('publisher_gid', _Gid),
        ('from_intra_process', c_bool),
    ]


class _Rcl:
    """``rcl_take_serialized_message`` through ctypes, with one reusable buffer."""

    def __init__(self, rmw: bytes) -> None:
        self.rcl = ctypes.CDLL('librcl.so')
        self.rcutils = ctypes.CDLL('librcutils.so')
        self.rcutils.rcutils_get_default_allocator.restype = _Allocator
        self.rcutils.rcutils_uint8_array_init.argtypes = [
            POINTER(_Bytes),
            c_size_t,
            POINTER(_Allocator),
        ]
        self.rcutils.rcutils_uint8_array_fini.argtypes = [POINTER(_Bytes)]
        take = self.rcl.rcl_take_serialized_message
        take.argtypes = [c_void_p, POINTER(_Bytes), POINTER(_Info), c_void_p]
        take.restype = c_int
        self.take_fn = take
        self.rmw = rmw
        self.bad = ''  # why the GIDs cannot be trusted ('' they can)
        self.allocator = self.rcutils.rcutils_get_default_allocator()
        self.buffer = _Bytes()
        if self.rcutils.rcutils_uint8_array_init(byref(self.buffer), 2048, byref(self.allocator)):
            raise OSError('rcutils_uint8_array_init failed')

    def take(self, subscription: Any) -> Optional[Taken]:
        info = _Info()
        with subscription.handle:
            ret = self.take_fn(subscription.handle.pointer, byref(self.buffer), byref(info), None)
        if ret != _RCL_RET_OK:
            return None
        n = int(self.buffer.buffer_length)
        data = ctypes.string_at(self.buffer.buffer, n) if n else b''
        ident = info.publisher_gid.implementation_identifier
        if ident != self.rmw:  # not the layout this was written for: no GID from here on
            self.bad = f'rmw_message_info_t names {ident!r}, not {self.rmw!r}'
            return Taken(data, None, None)
        seq = int(info.publication_sequence_number)
        return Taken(data, bytes(info.publisher_gid.data), None if seq >= 2**64 - 1 else seq)

    def close(self) -> None:
        self.rcutils.rcutils_uint8_array_fini(byref(self.buffer))


class RequestReader:
    """The request subscriptions of ``node`` (String topics, reliable, ``depth`` deep) on a
    helper node no executor spins; :meth:`take` their waiting messages with their GIDs."""

    def __init__(self, node: Any, topics: list[str], depth: int = 100) -> None:
        import rclpy
        from rclpy.qos import QoSProfile
        from std_msgs.msg import String

        self.helper = rclpy.create_node(
            f'{node.get_name()}_requests',
            namespace=node.get_namespace(),
            context=node.context,
            use_global_arguments=False,
            enable_rosout=False,
            start_parameter_services=False,
        )
        qos = QoSProfile(depth=depth)
        self.subs = {
            topic: self.helper.create_subscription(
                String, node.resolve_topic_name(topic), lambda _: None, qos, raw=True
            )
            for topic in topics
        }
        self.rcl: Optional[_Rcl] = None
        self.why_no_gid = ''
        try:
            self.rcl = _Rcl(rclpy.get_rmw_implementation_identifier().encode())
        except (OSError, AttributeError, TypeError) as err:
            self.why_no_gid = f'no publisher GID per message ({err})'

    def take(self, topic: str) -> list[Taken]:
        """The messages waiting on ``topic`` (up to :data:`TAKE_MAX`)."""
        sub = self.subs[topic]
        out: list[Taken] = []
        while len(out) < TAKE_MAX:
            taken = self._take_one(sub)
            if taken is None:
                break
            out.append(taken)
        return out

    def _take_one(self, sub: Any) -> Optional[Taken]:
        if self.rcl is not None:
            taken = self.rcl.take(sub)
            if self.rcl.bad:
                self.why_no_gid = f'no publisher GID per message ({self.rcl.bad})'
                self.rcl.close()
                self.rcl = None
            return taken
        with sub.handle:
            got = sub.handle.take_message(sub.msg_type, sub.raw)
        if got is None:
            return None
        data, info = got
        seq = info.get('publication_sequence_number')
        return Taken(bytes(data), None, None if seq is None or seq >= 2**64 - 1 else int(seq))

    def close(self) -> None:
        """Destroy the helper node (and its subscriptions)."""
        if self.rcl is not None:
            self.rcl.close()
            self.rcl = None
        self.helper.destroy_node()
