"""A console's requests resent until the monitor's answer shows (live console and harbour).

The monitor's request queue is shared by every publisher on the topic: a flood of requests
from another node may push the console's out of it before it is read. So each request carries
an id (`` #ID``, new per click; the monitor applies a publisher's id once) and is resent with
it: an acknowledgement while the alarms it names still wait for one, as raised when it was sent
(never once they are acknowledged or raised again since: the operator has not seen that one),
for :data:`ANSWER_WAIT` s at most. Pure: times passed in (s, monotonic), no rclpy.
"""

from __future__ import annotations

import secrets
from typing import Any, Mapping, Sequence

__all__ = ['ANSWER_WAIT', 'RESEND_EVERY', 'AckResends', 'request_id', 'waiting_ack']

#: Seconds a request is resent for (a shelving request waits as long for its answer).
ANSWER_WAIT = 8.0
#: Seconds between the sends of a request not answered yet: the first resend after the first,
#: then the second (a console's own requests stay within the monitor's limit per publisher).
RESEND_EVERY = (0.5, 1.0)
#: Acknowledgements being resent at once at most (more are sent once).
ACKS_MAX = 64


def request_id() -> str:
    """A new request id (12 hex digits)."""
    return secrets.token_hex(6)


def waiting_ack(statuses: Mapping[str, Any], names: Sequence[str]) -> dict[str, str]:
    """The alarms among ``names`` that wait for an acknowledgement: {alarm: when it was raised,
    as the monitor says} (``statuses``: component -> Status with ``values``)."""
    out = {}
    for name in names:
        st = statuses.get(name)
        if st is not None and st.values.get('acknowledged') == 'false':
            out[name] = st.values.get('alarm_raised', '')
    return out


class AckResends:
    """The acknowledgements a console resends: :meth:`add` one as it is sent, :meth:`due`
    the texts to send again now."""

    def __init__(self) -> None:
        # text -> (the alarms it names, until when [s], next send [s], {alarm: raised})
        self._acks: dict[str, tuple[tuple[str, ...], float, float, dict[str, str]]] = {}

    def __len__(self) -> int:
        return len(self._acks)

    def add(
        self, text: str, names: Sequence[str], statuses: Mapping[str, Any], now: float
    ) -> None:
        """Follow ``text``, an acknowledgement of ``names`` sent at ``now`` (nothing when none
        of them waits for one)."""
        waiting = waiting_ack(statuses, names)
        if waiting and len(self._acks) < ACKS_MAX:
            self._acks[text] = (tuple(names), now + ANSWER_WAIT, now + RESEND_EVERY[-1], waiting)

    def due(self, statuses: Mapping[str, Any], now: float) -> list[str]:
        """The acknowledgements to send again at ``now``: their alarms still wait for one,
        raised as when they were sent; the others are dropped."""
        again = []
        for text, (names, until, at, raised) in list(self._acks.items()):
            waiting = waiting_ack(statuses, names)
            changed = any(waiting.get(k, v) != v for k, v in raised.items())
            if now > until or not waiting or changed or not set(waiting) <= set(raised):
                del self._acks[text]
            elif now >= at:
                self._acks[text] = (names, until, now + RESEND_EVERY[-1], raised)
                again.append(text)
        return again
