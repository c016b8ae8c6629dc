"""The benchmarks' progress line: rewritten in place on a terminal, whole lines elsewhere."""

from __future__ import annotations

import io

from catenary_monitor.cli.status_line import StatusLine


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_pipe_gets_whole_lines_at_most_one_per_period():
    out = io.StringIO()
    status = StatusLine('[bench] ', out, every=3600.0)
    status('dock: vectorized, 1000 elements')
    status('dock: crossover')  # within the period: not shown
    status.done('done in 1 s')
    assert out.getvalue() == '[bench] dock: vectorized, 1000 elements\n[bench] done in 1 s\n'
    assert '\r' not in out.getvalue()


def test_a_terminal_gets_one_line_rewritten_then_blanked():
    out = _Tty()
    status = StatusLine('[bench] ', out, every=0.0)
    status('a long first message')
    status('short')
    status.done()
    text = out.getvalue()
    assert text.startswith('\r[bench] a long first message\r[bench] short')
    shown = '[bench] a long first message'
    assert text.endswith('\r' + ' ' * len(shown) + '\r') and '\n' not in text
    # every rewrite covers the longest line shown so far
    assert '\r[bench] short' + ' ' * (len(shown) - len('[bench] short')) + '\r' in text


def test_show_is_not_throttled_and_end_starts_a_new_terminal_line():
    out = _Tty()
    status = StatusLine('replay: ', out, every=3600.0)
    assert status.due()
    status('reading   0%')
    assert not status.due()
    status('reading  50%')  # throttled
    status.show('reading 100%')
    status.end()
    status.show('solving   0%')
    assert out.getvalue() == '\rreplay: reading   0%\rreplay: reading 100%\n\rreplay: solving   0%'
