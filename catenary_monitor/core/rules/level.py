"""The levels of every status and alarm: :class:`Level` (the numbers of diagnostic_msgs) and
:data:`RANK`, the severity order in which levels combine (ERROR above STALE)."""

from __future__ import annotations

from enum import IntEnum

__all__ = ['Level', 'RANK']


class Level(IntEnum):
    """DiagnosticStatus level (same numbers as diagnostic_msgs)."""

    OK = 0
    WARN = 1
    ERROR = 2
    STALE = 3


#: Severity rank used to combine and order levels (not the level number: ERROR > STALE).
RANK = {Level.OK: 0, Level.WARN: 1, Level.STALE: 2, Level.ERROR: 3}
