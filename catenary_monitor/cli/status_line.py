"""One line of progress on stderr for the long commands (replay, the benchmarks).

On a terminal the line is rewritten in place (``\\r``); anywhere else (a pipe, a file, a CI
log) each message is its own line, at most one every ``every`` seconds, so a captured log
stays readable instead of one line of carriage returns.
"""

from __future__ import annotations

import sys
import time
from typing import Optional, TextIO


class StatusLine:
    """``status(msg)`` shows ``prefix + msg`` (throttled); ``status.done(msg)`` ends the line.

    ``every`` [s]: the least time between two throttled messages (default 0.2 s on a terminal,
    2 s elsewhere)."""

    def __init__(
        self, prefix: str, stream: Optional[TextIO] = None, every: Optional[float] = None
    ) -> None:
        self.prefix = prefix
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, 'isatty', lambda: False)())
        self.every = (0.2 if self.tty else 2.0) if every is None else every
        self.start = time.perf_counter()
        self.last = -float('inf')
        self.width = 0  # of the line on the terminal, to blank it

    def elapsed(self) -> float:
        """Seconds since the status line was made."""
        return time.perf_counter() - self.start

    def due(self) -> bool:
        """Whether the last message is at least ``every`` old (a new one would be shown)."""
        return time.perf_counter() - self.last >= self.every

    def __call__(self, msg: str) -> None:
        """Show ``msg`` unless the last message is younger than ``every``."""
        if self.due():
            self.show(msg)

    def show(self, msg: str) -> None:
        """Show ``msg`` now."""
        self.last = time.perf_counter()
        text = self.prefix + msg
        if self.tty:
            self.stream.write('\r' + text.ljust(self.width))
            self.width = max(self.width, len(text))
        else:
            self.stream.write(text + '\n')
        self.stream.flush()

    def end(self) -> None:
        """On a terminal, end the line: what follows starts below it."""
        if self.tty:
            self.stream.write('\n')
            self.stream.flush()
            self.width = 0

    def done(self, msg: str = '') -> None:
        """The last line (``msg``), or, on a terminal with no ``msg``, the line blanked."""
        if msg:
            self.show(msg)
            self.end()
        elif self.tty and self.width:
            self.stream.write('\r' + ' ' * self.width + '\r')
            self.stream.flush()
