"""One line of progress on stderr for the long commands (the benchmarks).

On a terminal the line is rewritten in place (``\\r``); anywhere else (a pipe, a file, a CI
log) each message is its own line, at most one every ``every`` seconds, so a captured log
stays readable instead of one line of carriage returns.
"""

from __future__ import annotations

import sys
import time
from typing import Optional, TextIO


class StatusLine:
    """``status(msg)`` shows ``[prefix] msg``; ``status.done(msg)`` ends the line."""

    def __init__(
        self, prefix: str, stream: Optional[TextIO] = None, every: float = 2.0
    ) -> None:
        self.prefix = prefix
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, 'isatty', lambda: False)())
        self.every = every if not self.tty else 0.2  # [s] between lines
        self.start = time.perf_counter()
        self.last = -float('inf')
        self.width = 0  # of the line on the terminal, to blank it

    def elapsed(self) -> float:
        """Seconds since the status line was made."""
        return time.perf_counter() - self.start

    def __call__(self, msg: str) -> None:
        now = time.perf_counter()
        if now - self.last < self.every:
            return
        self.last = now
        self._show(f'[{self.prefix}] {msg}')

    def done(self, msg: str = '') -> None:
        """The last line (``msg``), or, on a terminal with no ``msg``, the line blanked."""
        if msg:
            self._show(f'[{self.prefix}] {msg}')
            if self.tty:
                self.stream.write('\n')
        elif self.tty and self.width:
            self.stream.write('\r' + ' ' * self.width + '\r')
        self.stream.flush()

    def _show(self, text: str) -> None:
        if self.tty:
            self.stream.write('\r' + text.ljust(self.width))
            self.width = max(self.width, len(text))
        else:
            self.stream.write(text + '\n')
        self.stream.flush()
