"""Operators' requests (acknowledge, shelve) rate-limited per publisher: a token bucket each.

An operator acknowledges or shelves a few alarms a minute, a storm's dozen at once; a node gone
wrong (or hostile) on the ROS graph may send a thousand a second. Each publisher (the node
names it by the GID the middleware gives each message; the console is one publisher) may send
:data:`BURST` requests at once and :data:`RATE` a second after that; the rest are refused
without being read. Those are never silent: a publisher's refused requests are summed into one
record every :data:`REPORT_EVERY` s at most (the first at once), which the node records as one
core event (:class:`~catenary_monitor.core.monitor.events.Refusal`), answers and logs. So a
flood costs the node at most a request a second per publisher and a record per period, and
another publisher (the console) is never locked out.

A request may end in an id, `` #ID`` (1 to 32 letters, digits, ``-`` or ``_``): the console
resends its request with the same id until it sees the answer (behind a flood, a request may be
pushed out of the middleware's queue, which all publishers share, before it is read), and the
node applies each id of a publisher once (:class:`Resends`): a resend of a request taken
changes nothing. Its memory is bounded per publisher (:data:`IDS_KEPT`) and in all
(:data:`IDS_PUBLISHERS`).

Pure: no clock (times are passed in, s on any monotonic clock), no rclpy.
"""

from __future__ import annotations

import math
import re
from collections import OrderedDict
from dataclasses import dataclass

__all__ = [
    'BURST',
    'RATE',
    'REPORT_EVERY',
    'KEYS_MAX',
    'OTHERS',
    'IDS_KEPT',
    'IDS_PUBLISHERS',
    'IDS_FOR',
    'RequestLimit',
    'Resends',
    'limit_text',
    'split_id',
]

#: Requests a publisher may send at once (a storm's alarms acknowledged one by one).
BURST = 20
#: Requests a second a publisher may send after its burst.
RATE = 1.0
#: At most one record of a publisher's refused requests per this many seconds.
REPORT_EVERY = 10.0
#: Publishers followed at once; beyond, idle ones are forgotten, and new ones share a bucket.
KEYS_MAX = 256
#: The bucket the publishers beyond :data:`KEYS_MAX` share.
OTHERS = '(other publishers)'
#: A publisher's newest request ids remembered (a console resends one id for 8 s).
IDS_KEPT = 64
#: Publishers whose ids are remembered at once (beyond, the longest idle is forgotten).
IDS_PUBLISHERS = 1024
#: An id is remembered this long [s] (a console resends its request for 8 s).
IDS_FOR = 120.0
_ID = re.compile(r'#[A-Za-z0-9_-]{1,32}')


@dataclass
class _Bucket:
    tokens: float
    at: float  # s, when ``tokens`` was last brought up to date
    refused: int = 0  # refused and not yet recorded
    reported: float = -math.inf  # s, the last record of its refusals


def _others(key: str) -> str:
    """The shared bucket of a key's group (a key is ``GROUP NAME``: the group kept)."""
    group, _, _ = key.partition(' ')
    return f'{group} {OTHERS}'


def limit_text(burst: int = BURST, rate: float = RATE) -> str:
    """The limit in words (for the refusal's reason)."""
    return f'{burst} at once, {rate:g} a second after that'


class RequestLimit:
    """Token buckets per publisher (``key``: ``GROUP NAME``, e.g. the request and the
    publisher's GID): :meth:`admit` a request, :meth:`due` the records of the refused ones.
    Beyond ``keys`` publishers, a new one shares its group's bucket (``GROUP`` +
    :data:`OTHERS`)."""

    def __init__(
        self,
        burst: int = BURST,
        rate: float = RATE,
        every: float = REPORT_EVERY,
        keys: int = KEYS_MAX,
    ) -> None:
        self.burst, self.rate, self.every, self.keys = int(burst), float(rate), every, keys
        self._buckets: dict[str, _Bucket] = {}
        self._pending: set[str] = set()

    def _bucket(self, key: str, now: float) -> tuple[str, _Bucket]:
        bucket = self._buckets.get(key)
        if bucket is None:
            if len(self._buckets) >= self.keys:
                self._forget_idle(now)
            if len(self._buckets) >= self.keys:
                key = _others(key)
                bucket = self._buckets.get(key)
        if bucket is None:
            bucket = self._buckets[key] = _Bucket(float(self.burst), now)
        if now > bucket.at:
            bucket.tokens = min(float(self.burst), bucket.tokens + (now - bucket.at) * self.rate)
            bucket.at = now
        return key, bucket

    def _forget_idle(self, now: float) -> None:
        """Drop the buckets that are full again and owe no record."""
        for key in [k for k, b in self._buckets.items() if not b.refused]:
            b = self._buckets[key]
            if b.tokens + (now - b.at) * self.rate >= self.burst:
                del self._buckets[key]

    def admit(self, key: str, now: float) -> bool:
        """Whether ``key``'s request at ``now`` [s] is within its rate (a token taken); a
        refused one is counted for :meth:`due`."""
        key, bucket = self._bucket(key, now)
        if bucket.tokens >= 1.0:
            bucket.tokens -= 1.0
            return True
        self.refuse(key, 1)
        return False

    def refuse(self, key: str, n: int) -> None:
        """Count ``n`` more refused requests of ``key`` (e.g. lost before they were read,
        behind a flood)."""
        if n <= 0:
            return
        if key not in self._buckets:
            key, _ = self._bucket(key, -math.inf)
        self._buckets[key].refused += n
        self._pending.add(key)

    def due(self, now: float, every_one: bool = False) -> list[tuple[str, int]]:
        """The records to make at ``now`` [s]: (key, refused requests since its last record)
        for each publisher whose last record is at least :attr:`every` s old (``every_one``:
        all of them, e.g. at shutdown)."""
        out = []
        for key in sorted(self._pending):
            bucket = self._buckets[key]
            if bucket.refused and (every_one or now - bucket.reported >= self.every):
                out.append((key, bucket.refused))
                bucket.refused, bucket.reported = 0, now
        self._pending = {k for k in self._pending if self._buckets[k].refused}
        return out


def split_id(text: str) -> tuple[str, str]:
    """(the request's text without its id, the id or '') of a request's ``text``: its last
    word when that is ``#ID`` and other words come before it."""
    body = text.rstrip()
    head, _, last = body.rpartition(' ')
    if not head.strip() or len(last) > 33 or _ID.fullmatch(last) is None:
        return text, ''
    return head.rstrip(), last[1:]


class Resends:
    """The request ids each publisher (``key``) sent lately: :meth:`seen` says whether a
    request is a resend of one already taken. Bounded: :data:`IDS_KEPT` ids per publisher,
    :data:`IDS_PUBLISHERS` publishers, each id for :data:`IDS_FOR` s."""

    def __init__(
        self, kept: int = IDS_KEPT, publishers: int = IDS_PUBLISHERS, keep_for: float = IDS_FOR
    ) -> None:
        self.kept, self.publishers, self.keep_for = kept, publishers, keep_for
        self._ids: OrderedDict[str, OrderedDict[str, float]] = OrderedDict()

    def seen(self, key: str, rid: str, now: float) -> bool:
        """Whether ``key`` sent ``rid`` within :attr:`keep_for` s before ``now`` [s]; else it
        is remembered from now on (False)."""
        ids = self._ids.get(key)
        if ids is None:
            while len(self._ids) >= self.publishers:
                self._ids.popitem(last=False)
            ids = self._ids[key] = OrderedDict()
        self._ids.move_to_end(key)
        at = ids.get(rid)
        if at is not None and now - at <= self.keep_for:
            return True
        ids[rid] = now
        ids.move_to_end(rid)
        while len(ids) > self.kept:
            ids.popitem(last=False)
        return False
